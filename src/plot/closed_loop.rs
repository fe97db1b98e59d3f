//! The closed-loop figures of a trace: the states figure (fig1: angle of attack, Euler angles, body rates, control
//! surfaces with their commands), whatever controller flew, and the figures of our adaptive SMC/RBF controller where
//! the trace has their columns.

use std::path::Path;

use super::PlotError;
use super::columns::{Columns, zip};
use super::drawn::Drawn;
use super::figure::{Figure, Panel, Series, palette};
use super::plant_series::time_span;
use super::render::write_figure;
use super::smc_rbf;
use silrig_flight::trace::Trace;

const STATES: &str = "fig1_states";

/// Draw the closed-loop figures of `trace` into `out_dir` (created if missing), each as PNG and SVG:
/// `fig1_states` (alpha; Euler angles; body rates; surfaces and their commands; each state over its set point,
/// dashed in its colour, where `setpoint` gives one by column name) always, its columns required;
/// `fig2_sliding` (sliding surfaces `s_<channel>` and RBF estimates `fhat_<channel>`, each over `f_true` of its
/// channel when given, 3x2) if the trace has any of those columns, and `fig3_weights` (the RBF weights
/// `w_<channel>_<k>` of each channel) if it has any weight column;
/// such a figure with only some of its columns is an error naming a missing one. `title` goes on top of every figure.
/// Every column is checked before any file is written. Returns the files written, PNG before SVG, figure by figure.
pub fn plot_closed_loop(
    trace: &Trace,
    f_true: Option<&[Vec<f64>; 3]>,
    setpoint: &dyn Fn(&str) -> Option<f64>,
    out_dir: &Path,
    title: &str,
) -> Result<Drawn, PlotError> {
    let mut figures = vec![(states(trace, setpoint, out_dir, title)?, STATES)];
    figures.extend(smc_rbf::figures(trace, f_true, out_dir, title)?);
    // All figures are built, and so all columns checked, before the first file is written: a trace that fails leaves
    // no partial set of figures behind.
    let mut written = Drawn::default();
    for (fig, stem) in &figures {
        written.extend(write_figure(fig, out_dir, stem)?);
    }
    Ok(written)
}

fn states(
    trace: &Trace,
    setpoint: &dyn Fn(&str) -> Option<f64>,
    out_dir: &Path,
    title: &str,
) -> Result<Figure, PlotError> {
    let file = out_dir.join(format!("{STATES}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let span = time_span(&t).unwrap_or((0.0, 0.0));
    let panel = |caption: &str, y_desc: &str, specs: &[(&str, &str)]| -> Result<Panel, PlotError> {
        let mut series = Vec::new();
        for (k, (column, label)) in specs.iter().enumerate() {
            series.push(Series::solid(label, zip(&t, &data.get(column)?), palette(k)));
            if let Some(sp) = setpoint(column) {
                series.push(Series::level(&format!("{label} set point"), sp, span, palette(k)));
            }
        }
        let with_setpoints = specs.iter().any(|(column, _)| setpoint(column).is_some());
        let caption = if with_setpoints { format!("{caption} (set points dashed)") } else { caption.to_string() };
        Ok(Panel::new(&caption, y_desc, series))
    };
    let mut surfaces = Vec::new();
    for (k, name) in ["aileron", "elevator", "rudder"].into_iter().enumerate() {
        let actual = data.get(&format!("{name}_deg"))?;
        let command = data.get(&format!("{name}_cmd_deg"))?;
        surfaces.push(Series::solid(name, zip(&t, &actual), palette(k)));
        // Scaled to the deflections: a command far beyond the stops (62.8 deg of rudder) would squash them flat.
        surfaces.push(Series::command(&format!("{name} cmd"), zip(&t, &command), palette(k)).within_others_range());
    }
    Ok(Figure::stacked(
        title,
        (1200, 900),
        vec![
            panel("(a) angle of attack", "deg", &[("alpha_deg", "α")])?,
            panel("(b) Euler angles", "deg", &[("phi_deg", "φ roll"), ("theta_deg", "θ pitch"), ("psi_deg", "ψ yaw")])?,
            panel("(c) body rates", "deg/s", &[("p_dps", "p roll"), ("q_dps", "q pitch"), ("r_dps", "r yaw")])?,
            Panel::new(
                "(d) control surfaces: deflection held over each step (solid), command (dashed, cut at the edges)",
                "deg",
                surfaces,
            ),
        ],
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_surface_panel_is_scaled_to_the_deflections_not_to_a_command_beyond_the_stops() {
        // paper-ideal asks for a 62.8 deg rudder the 30 deg stop cuts: the deflections must keep the panel's scale.
        let columns: Vec<String> = silrig_flight::trace::LOOP_COLUMNS.iter().map(|c| c.to_string()).collect();
        let mut trace = Trace::new(columns.clone());
        for k in 0..100 {
            let t = k as f64 * 0.01;
            let rudder_cmd = if k < 10 { 62.8 } else { 10.0 * (3.0 * t).sin() };
            trace.rows.push(
                columns
                    .iter()
                    .map(|c| match c.as_str() {
                        "t_s" => t,
                        "rudder_cmd_deg" => rudder_cmd,
                        "rudder_deg" => rudder_cmd.clamp(-30.0, 30.0),
                        _ => 1.0,
                    })
                    .collect(),
            );
        }
        let fig = states(&trace, &|_: &str| None, Path::new("/nonexistent"), "t").unwrap();
        let surfaces = fig.cells[3].as_ref().unwrap();
        let (lo, hi) = surfaces.y_range();
        assert!(hi < 35.0 && lo > -35.0, "the surface panel spans {lo}..{hi}");
        assert!(surfaces.series.iter().any(|s| s.label == "rudder cmd" && !s.sets_y_range));
    }
}
