//! Latency percentile distributions, drawn as HdrHistogram's plotter draws them (the tail spread out on the
//! number-of-nines scale), and latency histograms with a logarithmic count axis, as cyclictest's are plotted.

use std::path::Path;

use super::PlotError;
use super::axis::nines;
use super::drawn::Drawn;
use super::figure::{Figure, Panel, Series, XScale};
use super::render::write_figure;

/// Draw latency percentile distributions, as HdrHistogram's plotter does, into `<stem>.{png,svg}` in `out_dir`.
/// Each series is (name, points) with points (percentile in 0..100, latency in µs). The x axis is the "number of
/// nines", log10(1 / (1 - p/100)), labelled 0%, 90%, 99%, 99.9%, ..., and ends at the highest percentile the data
/// reach; the y axis is logarithmic, so the bulk of tens of µs and a logger's rare 50 ms wake-up are both read
/// (a linear axis to the worst outlier lays every other curve flat on zero). Points at or above the 100th
/// percentile, below the 0th, or not finite are skipped.
pub fn plot_percentile_distributions(
    series: &[(String, Vec<(f64, f64)>)],
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Drawn, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    if series.is_empty() {
        return Err(PlotError::NoData { file, problem: "no latency series".into() });
    }
    let kept: Vec<(&str, Vec<(f64, f64)>)> = series
        .iter()
        .map(|(name, points)| {
            let pts = points
                .iter()
                .filter(|(p, v)| (0.0..100.0).contains(p) && v.is_finite())
                .map(|&(p, v)| (nines(p), v))
                .collect();
            (name.as_str(), pts)
        })
        .collect();
    let worst = kept
        .iter()
        .flat_map(|(name, pts)| pts.iter().map(move |(_, v)| (*v, *name)))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    let lines = kept.into_iter().enumerate().map(|(k, (name, pts))| Series::cycled(name, pts, k)).collect();
    let caption = match worst {
        Some((v, name)) => format!("log scale: the bulk and the worst tick both in view (highest {v:.0} µs, {name})"),
        None => String::new(),
    };
    let mut panel = Panel::new(&caption, "latency (µs)", lines);
    panel.x_scale = XScale::Nines;
    panel.x_desc = "percentile".into();
    panel.y_log = true;
    let fig = Figure::stacked(title, (1200, 700), vec![panel]);
    write_figure(&fig, out_dir, stem)
}

/// The `p`th percentile of `values`, ranked down (the value of rank floor(p % of the count)), for the histogram's
/// cut: of 301 ticks, the 99.9th is the 300th, so one far outlier is cut off rather than setting the axis (ranked
/// up, it would be the outlier itself).
fn percentile(values: &mut [f64], p: f64) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    let last = values.len().checked_sub(1)?;
    Some(values[((p / 100.0 * values.len() as f64).floor() as usize).saturating_sub(1).min(last)])
}

/// Draw latency histograms into `<stem>.{png,svg}` in `out_dir`, as cyclictest histograms are plotted: latency on
/// x, the count of ticks in each bucket as bars on a logarithmic count axis labelled in counts (1, 10, 100), so the
/// rare late wake-ups stay visible beside the thousands of ordinary ones. Each series is (name, values in µs),
/// bucketed `bucket_us` wide; empty buckets are left out. The x axis ends at the bucket holding the 99.9th
/// percentile of all values, so that the bulk fills the plot; the caption counts the ticks beyond it and gives the
/// highest value.
pub fn plot_latency_histograms(
    series: &[(String, Vec<f64>)],
    bucket_us: f64,
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Drawn, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    let mut all: Vec<f64> = series.iter().flat_map(|(_, v)| v.iter().copied()).filter(|v| v.is_finite()).collect();
    let (Some(cut), true) = (percentile(&mut all, 99.9), bucket_us > 0.0) else {
        return Err(PlotError::NoData { file, problem: "no latency values".into() });
    };
    let max = all.last().copied().unwrap_or(cut);
    let last_bucket = (cut / bucket_us).floor() as i64;
    let bars = series
        .iter()
        .enumerate()
        .map(|(k, (name, values))| {
            let mut counts = std::collections::BTreeMap::<i64, u64>::new();
            for v in values.iter().filter(|v| v.is_finite()) {
                *counts.entry((v / bucket_us).floor() as i64).or_insert(0) += 1;
            }
            let pts = counts.range(..=last_bucket).map(|(b, n)| (*b as f64 * bucket_us, *n as f64)).collect();
            Series::bars(name, pts, bucket_us, k)
        })
        .collect();
    let end_us = (last_bucket + 1) as f64 * bucket_us;
    let beyond = all.iter().filter(|v| **v >= end_us).count();
    let caption = match beyond {
        0 => format!("every tick shown (highest {max:.0} µs)"),
        n => format!("{n} tick{} beyond {end_us:.0} µs not shown (highest {max:.0} µs)", if n == 1 { "" } else { "s" }),
    };
    let mut panel = Panel::new(&caption, "ticks per bucket", bars);
    panel.x_desc = format!("latency (µs, {bucket_us} µs buckets)");
    panel.x_span = Some((0.0_f64.min(all[0]), end_us));
    panel.y_log = true;
    let fig = Figure::stacked(title, (1200, 700), vec![panel]);
    write_figure(&fig, out_dir, stem)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cut_is_ranked_down_so_one_outlier_of_a_few_hundred_ticks_is_left_out() {
        let mut values: Vec<f64> = (1..=301).map(f64::from).collect();
        assert_eq!(percentile(&mut values, 99.9), Some(300.0));
        let mut values: Vec<f64> = (1..=1000).map(f64::from).rev().collect();
        assert_eq!(percentile(&mut values, 99.9), Some(999.0));
        assert_eq!(percentile(&mut [5.0], 99.9), Some(5.0));
        assert_eq!(percentile(&mut [], 99.9), None);
    }
}
