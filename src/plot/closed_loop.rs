//! The closed-loop figures of a trace: the states figure (fig1: angle of attack, Euler angles, body rates, control
//! surfaces with their commands), whatever controller flew, and the figures of our adaptive SMC/RBF controller where
//! the trace has their columns.

use std::path::{Path, PathBuf};

use super::PlotError;
use super::columns::{Columns, zip};
use super::figure::{Figure, Panel, Series, palette};
use super::render::write_figure;
use super::smc_rbf;
use crate::trace::Trace;

const STATES: &str = "fig1_states";

/// Draw the closed-loop figures of `trace` into `out_dir` (created if missing), each as PNG and SVG:
/// `fig1_states` (alpha; Euler angles; body rates; surfaces and their commands) always, its columns required;
/// `fig2_sliding` (sliding surfaces `s_<channel>` and RBF estimates `fhat_<channel>`, 3x2) if the trace has any of
/// those columns, and `fig3_weights` (the RBF weights `w_<channel>_<k>` of each channel) if it has any weight column;
/// such a figure with only some of its columns is an error naming a missing one. `title` goes on top of every figure.
/// Every column is checked before any file is written. Returns the files written, PNG before SVG, figure by figure.
pub fn plot_closed_loop(trace: &Trace, out_dir: &Path, title: &str) -> Result<Vec<PathBuf>, PlotError> {
    let mut figures = vec![(states(trace, out_dir, title)?, STATES)];
    figures.extend(smc_rbf::figures(trace, out_dir, title)?);
    // All figures are built, and so all columns checked, before the first file is written: a trace that fails leaves
    // no partial set of figures behind.
    let mut written = Vec::new();
    for (fig, stem) in &figures {
        written.extend(write_figure(fig, out_dir, stem)?);
    }
    Ok(written)
}

fn states(trace: &Trace, out_dir: &Path, title: &str) -> Result<Figure, PlotError> {
    let file = out_dir.join(format!("{STATES}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let panel = |caption: &str, y_desc: &str, specs: &[(&str, &str)]| -> Result<Panel, PlotError> {
        let mut series = Vec::new();
        for (k, (column, label)) in specs.iter().enumerate() {
            series.push(Series::solid(label, zip(&t, &data.get(column)?), palette(k)));
        }
        Ok(Panel::new(caption, y_desc, series))
    };
    let mut surfaces = Vec::new();
    for (k, name) in ["aileron", "elevator", "rudder"].into_iter().enumerate() {
        let actual = data.get(&format!("{name}_deg"))?;
        let command = data.get(&format!("{name}_cmd_deg"))?;
        surfaces.push(Series::solid(name, zip(&t, &actual), palette(k)));
        surfaces.push(Series::command(&format!("{name} cmd"), zip(&t, &command), palette(k)));
    }
    Ok(Figure::stacked(
        title,
        (1200, 900),
        vec![
            panel("(a) angle of attack", "deg", &[("alpha_deg", "α")])?,
            panel("(b) Euler angles", "deg", &[("phi_deg", "φ roll"), ("theta_deg", "θ pitch"), ("psi_deg", "ψ yaw")])?,
            panel("(c) body rates", "deg/s", &[("p_dps", "p roll"), ("q_dps", "q pitch"), ("r_dps", "r yaw")])?,
            Panel::new("(d) control surfaces: actual (solid) and command (dashed)", "deg", surfaces),
        ],
    ))
}
