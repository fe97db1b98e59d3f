//! The figures of one `silrig run`, each drawn from the plant's announced signals (which the recording keeps): the
//! paper's fig1 to fig3 where the trace has their columns, `response` (the outputs with a set point), `signals` and,
//! with faults, `faults` for any plant, and the timing distributions. A figure the run's data cannot give is left out with its reason, said once in
//! `report.json` and `report.html` ([`FigureLeftOut`]): it never fails the flight. Only a file that cannot be
//! written (a full disk) is an error.

use super::fault_report::FaultRecord;
use super::run_report::{FigureLeftOut, RigReport, per_tick_values_us};
use silrig_flight::fault::Fault;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace::Trace;
use silrig_plot::PlotError;
use std::path::Path;

/// The error of a figure the data cannot give as its entry in the left-out list, with `context` after the
/// reason; any other error (a file that cannot be written) as it is.
fn left_out(error: PlotError, context: &str) -> Result<FigureLeftOut, PlotError> {
    let (file, reason) = match error {
        PlotError::MissingColumn { file, trace, column } => (file, format!("{trace} has no column `{column}`")),
        PlotError::NoData { file, problem } => (file, problem),
        other => return Err(other),
    };
    let figure = file.file_name().map_or_else(|| file.display().to_string(), |f| f.to_string_lossy().into_owned());
    Ok(FigureLeftOut { figure, reason: format!("{reason}{context}") })
}

/// Why the paper's figures may not fit a plant: they show the F-16's states and our controller's diagnostics.
const PAPER_FIGURES: &str =
    " (fig1 to fig3 are the paper's figures of the F-16's states; signals.png shows every signal of this plant)";

type Drawing<'a> = Box<dyn FnOnce() -> Result<Option<FigureLeftOut>, PlotError> + Send + 'a>;

/// The figures that need the trace: the paper's, `signals` and `faults`.
fn trace_figures<'a>(
    report: &'a RigReport,
    out: &'a Path,
    scenario: &'a Scenario,
    trace: &'a Trace,
    plant: Option<&'a PlantSignals>,
) -> Vec<Drawing<'a>> {
    let setpoint = |name: &str| scenario.setpoint_track(name);
    let mut figures: Vec<Drawing> = vec![
        Box::new(move || {
            // Rows without a command (a lost controller) have NaN command columns, which the plots skip.
            let f_true = silrig_flight::f_true::from_trace(trace, scenario);
            let title = silrig_plot::plot_title(scenario);
            match silrig_plot::plot_closed_loop(trace, f_true.as_ref(), &setpoint, out, &title) {
                Ok(_) => Ok(None),
                Err(e) => left_out(e, PAPER_FIGURES).map(Some),
            }
        }),
        Box::new(move || {
            let plant_name = plant.map_or(String::new(), |p| format!(", plant {}", p.plant));
            let title = format!("{}{plant_name}: the response to the set points", scenario.name);
            match silrig_plot::plot_response(trace, plant, &setpoint, out, "response", &title) {
                Ok(_) => Ok(None),
                Err(e) => left_out(e, "").map(Some),
            }
        }),
        Box::new(move || {
            let plant_name = plant.map_or(String::new(), |p| format!(", plant {}", p.plant));
            let title = format!("{}{plant_name}: every signal, commands in orange", scenario.name);
            match silrig_plot::plot_signals(trace, plant, &setpoint, out, "signals", &title) {
                Ok(_) => Ok(None),
                Err(e) => left_out(e, "").map(Some),
            }
        }),
    ];
    if !(report.faults.is_empty() && report.discontinuities.is_empty()) {
        figures.push(Box::new(move || {
            let Some(plant) = plant else {
                let reason = "the run's recording does not hold the plant's announcement, which names its signals";
                return Ok(Some(FigureLeftOut { figure: "faults.png".into(), reason: reason.into() }));
            };
            let title = format!("{} ({}, run {}): faults", report.scenario, report.mode, report.run_id);
            let marks = fault_marks(report, &scenario.faults);
            match silrig_plot::plot_timeline(trace, plant, &setpoint, &marks, out, "faults", &title) {
                Ok(_) => Ok(None),
                Err(e) => left_out(e, "").map(Some),
            }
        }));
    }
    figures
}

/// Where a fault's window ends: at its recovery; without one, where its planned window ends (a sensor bias for
/// 1 s); a process left down (a kill without a restart) at the trace's end (infinity); a one-off (a single
/// delay) has no window.
fn window_end(f: &FaultRecord, injected_s: f64, plan: &[Fault]) -> Option<f64> {
    if let Some(t) = f.recovered_at_s {
        return Some(t);
    }
    let planned = plan.iter().find(|p| p.describe() == f.fault)?;
    match planned.duration_s {
        Some(d) => Some(injected_s + d),
        None => planned.action().is_process_fault().then_some(f64::INFINITY),
    }
}

/// Every fault's injection, failsafe and recovery, and every flight discontinuity, as marks on the timeline; a
/// fault's injection opens its window ([`window_end`]).
fn fault_marks(report: &RigReport, plan: &[Fault]) -> Vec<silrig_plot::TimelineEvent> {
    use silrig_plot::TimelineEvent;
    let mut marks = Vec::new();
    for f in &report.faults {
        let short = f.fault.split(',').next().unwrap_or(&f.fault).to_string();
        if let Some(t_s) = f.injected_at_s {
            marks.push(TimelineEvent { t_s, label: short, end_s: window_end(f, t_s, plan) });
        }
        for (t, label) in [(f.failsafe_at_s, "failsafe"), (f.recovered_at_s, "recovered")] {
            if let Some(t_s) = t {
                marks.push(TimelineEvent { t_s, label: label.to_string(), end_s: None });
            }
        }
    }
    for d in &report.discontinuities {
        marks.push(TimelineEvent { t_s: d.at_s, label: "discontinuity".into(), end_s: None });
    }
    marks
}

/// The timing figures: every process's latency distributions and the plant's per-tick histograms.
fn timing_figures<'a>(report: &'a RigReport, out: &'a Path) -> Vec<Drawing<'a>> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = report
        .processes
        .iter()
        .flat_map(|p| &p.latencies)
        .filter(|l| {
            l.summary.count > 0
                && !["step_exec", "compute", "checkpoint_write", "_steady"].iter().any(|work| l.name.ends_with(work))
        })
        .map(|l| (l.name.clone(), l.percentile_points.clone()))
        .collect();
    if let Some(b) = &report.timer_baseline {
        series.push(("os-floor.wake_lateness".into(), b.percentile_points.clone()));
    }
    let mut figures: Vec<Drawing> = Vec::new();
    if !series.is_empty() {
        figures.push(Box::new(move || {
            let title = format!("{} ({}, run {}): latency distributions", report.scenario, report.mode, report.run_id);
            match silrig_plot::plot_percentile_distributions(&series, out, "latency", &title) {
                Ok(_) => Ok(None),
                Err(e) => left_out(e, "").map(Some),
            }
        }));
    }
    figures.push(Box::new(move || {
        let per_tick = per_tick_values_us(out, report.mode == "realtime");
        if per_tick.iter().any(|(_, v)| !v.is_empty()) {
            let title = format!("{} ({}, run {}): per-tick histograms", report.scenario, report.mode, report.run_id);
            if let Err(e) = silrig_plot::plot_latency_histograms(&per_tick, 5.0, out, "latency_histogram", &title) {
                return left_out(e, "").map(Some);
            }
        }
        Ok(None)
    }));
    figures
}

/// Draw every figure of the run in `out`, each on a thread of its own (drawing is most of the time from a run's
/// end, or a Ctrl-C, to its report): the figures left out, with their reasons, in the figures' order; the first
/// file that could not be written is the error.
pub(crate) fn write_plots(report: &RigReport, out: &Path, scenario: &Scenario) -> anyhow::Result<Vec<FigureLeftOut>> {
    let trace = match report.control {
        Some(_) => Some(Trace::load(&out.join("trace.csv"))?),
        None => None,
    };
    // The units and which output is which input's position are in the plant's announcement, which the recording
    // keeps (a run without one draws bare names, and no fault timeline).
    let plant = silrig_recording::reader::RecordedRun::read(out).ok().and_then(|r| r.plant_signals().ok());
    let mut figures = match &trace {
        Some(trace) => trace_figures(report, out, scenario, trace, plant.as_ref()),
        None => Vec::new(),
    };
    figures.extend(timing_figures(report, out));
    let drawn = std::thread::scope(|scope| {
        let drawing: Vec<_> = figures.into_iter().map(|f| scope.spawn(f)).collect();
        drawing.into_iter().map(|d| d.join().expect("drawing a figure does not panic")).collect::<Vec<_>>()
    });
    let mut left = Vec::new();
    for figure in drawn {
        left.extend(figure?);
    }
    Ok(left)
}

/// A figure the disk could not take is left empty by the plotting library: remove it rather than leave a file
/// that is not a figure.
pub(crate) fn remove_empty_figures(out: &Path) {
    for entry in std::fs::read_dir(out).into_iter().flatten().flatten() {
        let path = entry.path();
        let figure = path.extension().is_some_and(|e| e == "png" || e == "svg");
        if figure && entry.metadata().is_ok_and(|m| m.len() == 0) {
            let _ = std::fs::remove_file(path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn a_figure_the_data_cannot_give_is_left_out_in_words_and_a_write_error_stays_an_error() {
        let file = PathBuf::from("/run/out/fig1_states.png");
        let missing =
            PlotError::MissingColumn { file: file.clone(), trace: "the trace".into(), column: "alpha_deg".into() };
        let entry = left_out(missing, PAPER_FIGURES).unwrap();
        assert_eq!(entry.figure, "fig1_states.png");
        assert!(entry.reason.starts_with("the trace has no column `alpha_deg` (fig1 to fig3"), "{}", entry.reason);
        let empty = PlotError::NoData { file: file.clone(), problem: "the trace has no rows".into() };
        assert_eq!(left_out(empty, "").unwrap().reason, "the trace has no rows");
        let full = PlotError::Write { file, cause: std::io::Error::other("No space left on device") };
        assert!(left_out(full, "").is_err());
    }

    #[test]
    fn a_fault_window_ends_at_its_recovery_else_at_its_planned_end_and_a_one_off_has_none() {
        let plan: Vec<Fault> = [
            "plant:sensor-bias@8s,for=1s,channel=phi_rad,bias=0.02",
            "controller:kill@3s",
            "plant:delay@5s,delay=15ms",
        ]
        .iter()
        .map(|text| silrig_flight::fault::parse_fault_flag(text).unwrap())
        .collect();
        let record = |k: usize, recovered_at_s| FaultRecord {
            fault: plan[k].describe(),
            injected_at_s: Some(plan[k].at_s),
            injected_at_wall_s: None,
            detected_at_s: None,
            detected_by: None,
            failsafe_at_s: None,
            recovered_at_s,
            plant_samples_lost: 0,
            command_samples_lost: 0,
            discontinuity: None,
            plant_resume: None,
            rejoin: None,
        };
        assert_eq!(window_end(&record(0, None), 8.0, &plan), Some(9.0), "the planned window");
        assert_eq!(window_end(&record(1, Some(3.6)), 3.0, &plan), Some(3.6), "its recovery");
        assert_eq!(window_end(&record(1, None), 3.0, &plan), Some(f64::INFINITY), "down to the end");
        assert_eq!(window_end(&record(2, None), 5.0, &plan), None, "a one-off");
    }
}
