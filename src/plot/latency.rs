//! Latency percentile distributions, drawn as HdrHistogram's plotter draws them (the tail spread out on the
//! number-of-nines scale), and latency histograms with a logarithmic count axis, as cyclictest's are plotted.

use std::path::{Path, PathBuf};

use super::PlotError;
use super::axis::nines;
use super::figure::{Figure, Panel, Series, XScale};
use super::render::write_figure;

/// Draw latency percentile distributions, as HdrHistogram's plotter does, into `<stem>.{png,svg}` in `out_dir`.
/// Each series is (name, points) with points (percentile in 0..100, latency in µs). The x axis is the "number of
/// nines", log10(1 / (1 - p/100)), labelled 0%, 90%, 99%, 99.9%, 99.99% (and further if the data go further); the
/// y axis is linear from 0. Points at or above the 100th percentile, below the 0th, or not finite are skipped.
pub fn plot_percentile_distributions(
    series: &[(String, Vec<(f64, f64)>)],
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    if series.is_empty() {
        return Err(PlotError::NoData { file, problem: "no latency series".into() });
    }
    let lines = series
        .iter()
        .enumerate()
        .map(|(k, (name, points))| {
            let pts = points
                .iter()
                .filter(|(p, v)| (0.0..100.0).contains(p) && v.is_finite())
                .map(|&(p, v)| (nines(p), v))
                .collect();
            Series::cycled(name, pts, k)
        })
        .collect();
    let mut panel = Panel::new("", "latency (µs)", lines);
    panel.x_scale = XScale::Nines;
    panel.x_desc = "percentile".into();
    panel.y_from_zero = true;
    let fig = Figure::stacked(title, (1200, 700), vec![panel]);
    write_figure(&fig, out_dir, stem)
}

/// Draw latency histograms into `<stem>.{png,svg}` in `out_dir`, as cyclictest histograms are plotted: latency on
/// x, the count of each bucket on a logarithmic y axis (log10 of the count), so the rare late wake-ups stay visible
/// beside the thousands of ordinary ones. Each series is (name, values in µs), bucketed `bucket_us` wide; empty
/// buckets are left out.
pub fn plot_latency_histograms(
    series: &[(String, Vec<f64>)],
    bucket_us: f64,
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    if series.iter().all(|(_, v)| v.is_empty()) || !(bucket_us > 0.0) {
        return Err(PlotError::NoData { file, problem: "no latency values".into() });
    }
    let lines = series
        .iter()
        .enumerate()
        .map(|(k, (name, values))| {
            let mut counts = std::collections::BTreeMap::<i64, u64>::new();
            for v in values.iter().filter(|v| v.is_finite()) {
                *counts.entry((v / bucket_us).floor() as i64).or_insert(0) += 1;
            }
            // A step at each bucket's edges, so a bucket reads as a bar top.
            let pts = counts
                .into_iter()
                .flat_map(|(b, n)| {
                    let y = (n as f64).log10();
                    [(b as f64 * bucket_us, y), ((b + 1) as f64 * bucket_us, y), ((b + 1) as f64 * bucket_us, f64::NAN)]
                })
                .collect();
            Series::cycled(name, pts, k)
        })
        .collect();
    let mut panel = Panel::new("", "count (log10: 0 = 1, 1 = 10, 2 = 100)", lines);
    panel.x_desc = format!("latency (µs, {bucket_us} µs buckets)");
    panel.y_from_zero = true;
    let fig = Figure::stacked(title, (1200, 700), vec![panel]);
    write_figure(&fig, out_dir, stem)
}
