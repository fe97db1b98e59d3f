//! silrig-plot: every figure the rig draws (closed-loop states, sliding surfaces, RBF weights, run overlays, fault
//! timelines, latency percentile distributions, sweep histograms, scatter plots and envelopes), each written as PNG
//! and SVG.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (`src/plot/fonts/`, Bitstream Vera licence), so plotting
//! needs no system font libraries. Every figure is first described as plain data (a figure: a grid of panels, each
//! with its series), then laid out once and drawn twice, by the same code, on the bitmap and the SVG backend.
//!
//! Data rules shared by all figures: NaN and infinite samples are skipped (the line breaks there); y ranges are the
//! data range padded by 5 %, and a constant or all-zero series gets a small symmetric range around its value. A
//! series marked to stay within the others' range (fig1's commands) does not widen it and is cut at its edges.
//!
//! The engine: `figure.rs` (the data), `axis.rs`, `layout.rs` (pixel sizes) and `render.rs` (both backends, the font,
//! the files). Each figure family is one file that turns trace columns (`columns.rs`) into figures: `closed_loop.rs`,
//! `smc_rbf.rs`, `overlay.rs`, `latency.rs`, `timeline.rs` (faults over any plant's signals), `sweep.rs`, and
//! `signals.rs` (any plant's outputs and commands by name); `plant_series.rs` is what the last two read from a
//! plant's announcement (units, commands beside positions, held rows).

use silrig_flight::scenario::Scenario;
use std::path::PathBuf;

mod axis;
mod closed_loop;
mod columns;
mod drawn;
mod figure;
mod latency;
mod layout;
mod overlay;
mod plant_series;
mod render;
mod response;
mod signals;
mod smc_rbf;
mod sweep;
mod timeline;

pub use closed_loop::plot_closed_loop;
pub use drawn::{AxisRange, Drawn, FigureAxes, PanelAxes};
pub use latency::{plot_latency_histograms, plot_percentile_distributions};
pub use overlay::plot_overlay;
pub use response::plot_response;
pub use signals::plot_signals;
pub use sweep::{Envelope, Histogram, Scatter, plot_envelope, plot_histograms, plot_scatter};
pub use timeline::plot_timeline;

/// Title of a scenario's figures: its name and what it shows.
pub fn plot_title(scenario: &Scenario) -> String {
    if scenario.description.is_empty() {
        scenario.name.clone()
    } else {
        format!("{}: {}", scenario.name, scenario.description)
    }
}

/// A figure that could not be drawn. Each variant names the file it was drawing (or the directory it wanted).
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A column the figure needs is not in the trace.
    #[error("cannot draw {file}: {trace} has no column `{column}`")]
    MissingColumn {
        /// The figure's first output file.
        file: PathBuf,
        /// Which trace: "the trace", or "run `name`" in an overlay.
        trace: String,
        /// The missing column.
        column: String,
    },
    /// There is nothing to draw (no rows, no runs, no series).
    #[error("cannot draw {file}: {problem}")]
    NoData {
        /// The figure's first output file.
        file: PathBuf,
        /// What is missing.
        problem: String,
    },
    /// The output directory cannot be created.
    #[error("cannot create the output directory {dir}: {cause}")]
    CreateDir {
        /// The directory.
        dir: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
    /// Writing a file failed.
    #[error("cannot write {file}: {cause}")]
    Write {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
    /// The plotting backend failed (drawing or PNG encoding).
    #[error("cannot draw {file}: {message}")]
    Draw {
        /// The file.
        file: PathBuf,
        /// The backend's message.
        message: String,
    },
    /// The embedded font is not a font (a build problem, not a data problem).
    #[error("cannot draw {file}: the embedded font src/plot/fonts/DejaVuSans.ttf does not load")]
    Font {
        /// The file.
        file: PathBuf,
    },
}

/// A marked instant on a timeline (an injected fault, a mode change), or the start of a window (a fault from its
/// injection to its end).
#[derive(Debug, Clone)]
pub struct TimelineEvent {
    /// When, in the trace's time `t_s` (seconds).
    pub t_s: f64,
    /// The text written at the top of the figure next to the marker.
    pub label: String,
    /// Where the window this event opens ends (a fault's recovery, or the trace's end for one that never
    /// recovered), in `t_s`: the timeline shades the window from `t_s` to here. None: an instant.
    pub end_s: Option<f64>,
}
