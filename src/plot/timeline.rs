//! The fault timeline: attitude and surfaces against time, with a marker and a label at every event.

use std::path::{Path, PathBuf};

use super::columns::{Columns, zip};
use super::figure::{Figure, Panel, Series, palette};
use super::render::write_figure;
use super::{PlotError, TimelineEvent};
use silrig_flight::trace::Trace;

/// Draw `<stem>.{png,svg}` in `out_dir`: Euler angles above, actual surface deflections below, against `t_s`, with a
/// dashed vertical line at every event (both panels) and its label above the upper panel. Events outside the trace's
/// time span are left out. Returns the files written.
pub fn plot_timeline(
    trace: &Trace,
    events: &[TimelineEvent],
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let mut euler = Vec::new();
    for (k, (column, label)) in
        [("phi_deg", "φ roll"), ("theta_deg", "θ pitch"), ("psi_deg", "ψ yaw")].iter().enumerate()
    {
        euler.push(Series::solid(label, zip(&t, &data.get(column)?), palette(k)));
    }
    let mut surfaces = Vec::new();
    for (k, (column, label)) in
        [("aileron_deg", "aileron"), ("elevator_deg", "elevator"), ("rudder_deg", "rudder")].iter().enumerate()
    {
        surfaces.push(Series::solid(label, zip(&t, &data.get(column)?), palette(k)));
    }
    let events: Vec<(f64, String)> =
        events.iter().filter(|e| e.t_s.is_finite()).map(|e| (e.t_s, e.label.clone())).collect();
    let mut upper = Panel::new("Euler angles", "deg", euler);
    upper.events = events.clone();
    upper.event_labels = true;
    let mut lower = Panel::new("control surfaces", "deg", surfaces);
    lower.events = events;
    let fig = Figure::stacked(title, (1200, 800), vec![upper, lower]);
    write_figure(&fig, out_dir, stem)
}
