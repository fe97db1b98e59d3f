//! The figure of any plant: every traced output and every commanded input against time, one small panel each,
//! in the order the plant announced them, with the set point dashed where the scenario gives one. The closed-loop
//! figures show the F-16's states; this one shows whatever a plant of your own calls its signals.

use std::path::{Path, PathBuf};

use super::PlotError;
use super::columns::{Columns, zip};
use super::figure::{Figure, FigureLegend, Panel, Series, palette};
use super::render::write_figure;
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace::Trace;

/// Panels side by side: three, four past 24 panels, so up to 48 stay readable on one page.
fn columns_for(panels: usize) -> usize {
    if panels > 24 { 4 } else { 3 }.min(panels.max(1))
}

/// Height of one row of panels, px.
const ROW_HEIGHT_PX: u32 = 230;

/// One panel: a trace column, its caption and unit, its set point.
struct Signal {
    column: String,
    caption: String,
    unit: String,
    setpoint: Option<f64>,
    command: bool,
}

/// What to draw: with the plant's announcement, its traced outputs (with units) then its traced commands; without
/// it (a run with no recording), every trace column but time and the flight segment.
fn signals(trace: &Trace, plant: Option<&PlantSignals>, setpoint: &dyn Fn(&str) -> Option<f64>) -> Vec<Signal> {
    match plant {
        Some(p) => {
            let outputs = p.outputs.iter().filter(|o| o.in_trace).map(|o| Signal {
                column: o.name.clone(),
                caption: o.name.clone(),
                unit: o.unit.clone(),
                setpoint: setpoint(&o.name),
                command: false,
            });
            let commands = (0..p.inputs.len()).filter(|k| p.inputs[*k].command_in_trace).map(|k| {
                let input = &p.inputs[k];
                Signal {
                    column: p.command_column(k),
                    caption: format!("{} command", input.name),
                    unit: input.unit.clone(),
                    setpoint: None,
                    command: true,
                }
            });
            outputs.chain(commands).collect()
        }
        None => trace
            .columns
            .iter()
            .filter(|c| !["t_s", "flight_segment"].contains(&c.as_str()))
            .map(|c| Signal {
                column: c.clone(),
                caption: c.clone(),
                unit: String::new(),
                setpoint: setpoint(c),
                command: false,
            })
            .collect(),
    }
}

/// Draw `<stem>.{png,svg}` in `out_dir`: a grid of panels, one per signal (see [`signals`]), time on every x axis.
/// `setpoint` gives an output's set point by name. Returns the files written.
pub fn plot_signals(
    trace: &Trace,
    plant: Option<&PlantSignals>,
    setpoint: &dyn Fn(&str) -> Option<f64>,
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let wanted = signals(trace, plant, setpoint);
    if wanted.is_empty() {
        return Err(PlotError::NoData { file, problem: "the trace has no signal columns".into() });
    }
    let mut cells = Vec::with_capacity(wanted.len());
    for s in &wanted {
        let values = data.get(&s.column)?;
        let colour = palette(if s.command { 1 } else { 0 });
        let mut series = vec![Series::solid(&s.caption, zip(&t, &values), colour)];
        if let Some(sp) = s.setpoint {
            let span = [t.first().copied().unwrap_or(0.0), t.last().copied().unwrap_or(0.0)];
            series.push(Series::command("set point", span.iter().map(|ti| (*ti, sp)).collect(), palette(3)));
        }
        let caption = match s.setpoint {
            Some(sp) => format!("{} (set point {sp}, dashed)", s.caption),
            None => s.caption.clone(),
        };
        let mut panel = Panel::new(&caption, &s.unit, series);
        panel.legend = false;
        cells.push(Some(panel));
    }
    let cols = columns_for(cells.len());
    let rows = cells.len().div_ceil(cols);
    cells.resize_with(rows * cols, || None);
    let size = (1500, 90 + ROW_HEIGHT_PX * rows as u32);
    let mut fig = Figure::grid(title, size, rows, cols, cells, FigureLegend::None);
    // Every panel keeps its own time labels: a grid this dense is read panel by panel.
    fig.shared_x = false;
    write_figure(&fig, out_dir, stem)
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_flight::signals::{InputSignal, OutputSignal};

    fn plant() -> PlantSignals {
        let output = |name: &str, in_trace| OutputSignal { name: name.into(), unit: "ft".into(), in_trace };
        PlantSignals {
            plant: "toy".into(),
            outputs: vec![output("alt_ft", true), output("hidden", false), output("x", true)],
            inputs: vec![InputSignal {
                name: "elevator".into(),
                unit: "1".into(),
                min: -1.0,
                max: 1.0,
                hold: 0.0,
                held_output: None,
                command_in_trace: true,
            }],
        }
    }

    #[test]
    fn one_panel_per_traced_output_and_command_with_set_points_and_units() {
        let p = plant();
        let setpoint = |name: &str| (name == "alt_ft").then_some(4000.0);
        let trace = Trace::new(["t_s", "alt_ft", "x", "elevator_cmd", "flight_segment"].map(String::from).to_vec());
        let s = signals(&trace, Some(&p), &setpoint);
        let columns: Vec<&str> = s.iter().map(|s| s.column.as_str()).collect();
        assert_eq!(columns, ["alt_ft", "x", p.command_column(0).as_str()]);
        assert_eq!((s[0].setpoint, s[0].unit.as_str(), s[1].setpoint), (Some(4000.0), "ft", None));
        assert!(s[2].command && s[2].caption == "elevator command");
        // Without the announcement: every column but time and the segment.
        let bare: Vec<String> = signals(&trace, None, &setpoint).into_iter().map(|s| s.column).collect();
        assert_eq!(bare, ["alt_ft", "x", "elevator_cmd"]);
    }

    #[test]
    fn the_figure_is_drawn_with_nan_rows_as_breaks() {
        let p = plant();
        let mut trace = Trace::new(
            ["t_s", "alt_ft", "x", p.command_column(0).as_str(), "flight_segment"].map(String::from).to_vec(),
        );
        trace.rows = (0..200)
            .map(|k| {
                let t = k as f64 * 0.01;
                let cmd = if (50..60).contains(&k) { f64::NAN } else { (t * 3.0).sin() };
                vec![t, 4000.0 + 10.0 * t, t.cos(), cmd, 0.0]
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("silrig-plot-signals-{}", std::process::id()));
        let files =
            plot_signals(&trace, Some(&p), &|n: &str| (n == "alt_ft").then_some(4010.0), &dir, "signals", "t").unwrap();
        assert_eq!(files.len(), 2);
        let png = std::fs::read(&files[0]).unwrap();
        assert!(png.starts_with(b"\x89PNG") && png.len() > 10_000, "{} bytes", png.len());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
