//! The overlay figure: several runs compared, panel by panel, one colour per run.

use std::path::Path;

use super::PlotError;
use super::columns::{Columns, zip};
use super::drawn::Drawn;
use super::figure::{Figure, FigureLegend, LegendEntry, Panel, Series};
use super::render::write_figure;
use silrig_flight::trace::Trace;

/// Draw one figure `<stem>.{png,svg}` in `out_dir` comparing several runs (name, trace): panels for theta, phi,
/// psi, alpha, elevator, aileron and rudder (deg) against `t_s`, in a 4x2 grid, one colour per run, the legend of run
/// names in the eighth cell. Returns the files written.
pub fn plot_overlay(runs: &[(String, Trace)], out_dir: &Path, stem: &str) -> Result<Drawn, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    if runs.is_empty() {
        return Err(PlotError::NoData { file, problem: "no runs to compare".into() });
    }
    let specs = [
        ("theta_deg", "pitch angle θ"),
        ("phi_deg", "roll angle φ"),
        ("psi_deg", "yaw angle ψ"),
        ("alpha_deg", "angle of attack α"),
        ("elevator_deg", "elevator"),
        ("aileron_deg", "aileron"),
        ("rudder_deg", "rudder"),
    ];
    let mut panels: Vec<Panel> = specs
        .iter()
        .map(|(_, caption)| {
            let mut panel = Panel::new(caption, "deg", Vec::new());
            panel.legend = false; // one legend for all panels, in the empty cell
            panel
        })
        .collect();
    for (r, (name, trace)) in runs.iter().enumerate() {
        let data = Columns::new(trace, &file, &format!("run `{name}`"))?;
        let t = data.get("t_s")?;
        for (panel, (column, _)) in panels.iter_mut().zip(specs) {
            panel.series.push(Series::cycled(name, zip(&t, &data.get(column)?), r));
        }
    }
    let entries = runs.iter().enumerate().map(|(r, (name, _))| LegendEntry::cycled(name, r)).collect();
    let mut cells: Vec<Option<Panel>> = panels.into_iter().map(Some).collect();
    cells.push(None);
    let fig = Figure::grid(stem, (1400, 1050), 4, 2, cells, FigureLegend::Cell(7, entries));
    write_figure(&fig, out_dir, stem)
}
