//! The figures of the paper's adaptive SMC/RBF controller: fig2 (the sliding surface `s_<ch>` of each channel, and
//! its RBF estimate `fhat_<ch>` beside the true lumped function f of [`silrig_flight::f_true`], as the paper's Fig. 2
//! sets "the estimated and true RBFNN functions" side by side) and fig3 (the RBF weights `w_<ch>_<k>` of each channel).

use std::path::Path;

use super::PlotError;
use super::columns::{Columns, zip};
use super::figure::{Figure, FigureLegend, LegendEntry, Panel, Series, palette};
use plotters::style::RGBColor;
use silrig_flight::trace::{CHANNELS, Trace};

const SLIDING: &str = "fig2_sliding";
const WEIGHTS: &str = "fig3_weights";

/// The controller's figures that `trace` has columns for, each with its file stem: fig2 if it has any `s_<ch>` or
/// `fhat_<ch>` column, fig3 if it has any `w_<ch>_<k>` column. A trace of another controller has none and gets none;
/// a figure with only some of its columns is an error naming a missing one, as that trace is ours but damaged.
/// `f_true` (per channel, one value per row), when given, is drawn beside each `fhat_<ch>`.
pub(super) fn figures(
    trace: &Trace,
    f_true: Option<&[Vec<f64>; 3]>,
    out_dir: &Path,
    title: &str,
) -> Result<Vec<(Figure, &'static str)>, PlotError> {
    let mut figures = Vec::new();
    let sliding_column = |ch: &&str| [format!("s_{ch}"), format!("fhat_{ch}")].iter().any(|c| trace.index(c).is_some());
    if CHANNELS.iter().any(sliding_column) {
        figures.push((sliding(trace, f_true, out_dir, title)?, SLIDING));
    }
    if CHANNELS.iter().any(|ch| !weight_nodes(trace, ch).is_empty()) {
        figures.push((weights(trace, out_dir, title)?, WEIGHTS));
    }
    Ok(figures)
}

/// Colour of the true f, under every channel's estimate.
const F_TRUE_COLOUR: RGBColor = RGBColor(90, 90, 90);

/// Sliding surfaces (left) and RBF estimates with the true f (right), a row per channel.
fn sliding(trace: &Trace, f_true: Option<&[Vec<f64>; 3]>, out_dir: &Path, title: &str) -> Result<Figure, PlotError> {
    let file = out_dir.join(format!("{SLIDING}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let mut cells = Vec::new();
    for (k, ch) in CHANNELS.iter().enumerate() {
        let greek = greek(ch);
        let s_col = format!("s_{ch}");
        let f_col = format!("fhat_{ch}");
        let s = Series::solid(&s_col, zip(&t, &data.get(&s_col)?), palette(k));
        let mut left = Panel::new(&format!("sliding surface S, {greek} channel"), "S (rad/s)", vec![s]);
        left.legend = false;
        // The true f first, so the estimate is drawn over it.
        let mut estimates = Vec::new();
        let caption = match f_true {
            Some(f) => {
                estimates.push(Series::thin("f true", zip(&t, &f[k]), F_TRUE_COLOUR));
                format!("RBF estimate f_hat and true f = d²{greek}/dt² − g·δ − d, {greek} channel")
            }
            None => format!("RBF estimate f_hat, {greek} channel"),
        };
        estimates.push(Series::solid("f_hat", zip(&t, &data.get(&f_col)?), palette(k)));
        let mut right = Panel::new(&caption, "rad/s²", estimates);
        right.legend = f_true.is_some();
        cells.push(Some(left));
        cells.push(Some(right));
    }
    Ok(Figure::grid(title, (1200, 850), 3, 2, cells, FigureLegend::None))
}

/// The RBF weights, a panel per channel, one legend for all.
fn weights(trace: &Trace, out_dir: &Path, title: &str) -> Result<Figure, PlotError> {
    let file = out_dir.join(format!("{WEIGHTS}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    // One colour per node number, the same in every channel and in the shared legend.
    let mut all_nodes: Vec<usize> = CHANNELS.iter().flat_map(|ch| weight_nodes(trace, ch)).collect();
    all_nodes.sort_unstable();
    all_nodes.dedup();
    let colour_of = |k: usize| all_nodes.iter().position(|&n| n == k).unwrap_or(0);
    let mut panels = Vec::new();
    for ch in CHANNELS {
        let nodes = weight_nodes(trace, ch);
        if nodes.is_empty() {
            return Err(PlotError::MissingColumn { file, trace: "the trace".into(), column: format!("w_{ch}_1") });
        }
        let mut series = Vec::new();
        for &k in &nodes {
            series.push(Series::cycled(&format!("W{k}"), zip(&t, &data.get(&format!("w_{ch}_{k}"))?), colour_of(k)));
        }
        let mut panel = Panel::new(&format!("RBF weights, {} channel", greek(ch)), "weight", series);
        panel.legend = false;
        panels.push(panel);
    }
    let entries = all_nodes.iter().enumerate().map(|(i, k)| LegendEntry::cycled(&format!("W{k}"), i)).collect();
    let mut fig = Figure::stacked(title, (1200, 900), panels);
    fig.legend = FigureLegend::Top(entries);
    Ok(fig)
}

/// Node numbers k of the columns `w_<ch>_<k>`, ascending.
fn weight_nodes(trace: &Trace, ch: &str) -> Vec<usize> {
    let prefix = format!("w_{ch}_");
    let mut nodes: Vec<usize> =
        trace.columns.iter().filter_map(|c| c.strip_prefix(&prefix).and_then(|k| k.parse().ok())).collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

fn greek(ch: &str) -> &'static str {
    match ch {
        "phi" => "φ",
        "theta" => "θ",
        "psi" => "ψ",
        _ => "?",
    }
}
