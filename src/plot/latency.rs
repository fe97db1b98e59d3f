//! Latency percentile distributions, drawn as HdrHistogram's plotter draws them: the tail spread out on the
//! number-of-nines scale.

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
