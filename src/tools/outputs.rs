//! Files a run leaves behind: `trace.csv`, `summary.json`, the effective `scenario.toml`, the figures; and the two
//! single-process workflows built on them, `silrig sim` ([`simulate`]) and `silrig compare` ([`compare`], with its
//! side-by-side table).

use anyhow::Context;
use silrig_adapters::in_process::Models;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_flight::sim::LeftEnvelope;
use silrig_flight::summary::{Response, Summary};
use silrig_flight::trace::Trace;
use silrig_plot::plot_title;
use std::path::{Path, PathBuf};

/// Write trace, summary, scenario and figures into `out_dir` (created if needed); returns the paths written. The
/// closed-loop figures need the F-16's trace columns; a plant of the user's own (`plant`) gets the figure of every
/// one of its signals instead.
pub fn write_run(
    out_dir: &Path,
    scenario: &Scenario,
    trace: &Trace,
    summary: &Summary,
    plant: Option<&PlantSignals>,
) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let trace_path = out_dir.join("trace.csv");
    trace.save(&trace_path).with_context(|| format!("writing {}", trace_path.display()))?;
    let summary_path = out_dir.join("summary.json");
    std::fs::write(&summary_path, serde_json::to_string_pretty(summary)? + "\n")
        .with_context(|| format!("writing {}", summary_path.display()))?;
    let scenario_path = out_dir.join("scenario.toml");
    std::fs::write(&scenario_path, scenario.to_toml())
        .with_context(|| format!("writing {}", scenario_path.display()))?;
    let mut files = vec![trace_path, summary_path, scenario_path];
    let setpoint = |name: &str| scenario.setpoint.get(name);
    if silrig_flight::trace::LOOP_COLUMNS.iter().all(|c| trace.index(c).is_some()) {
        let f_true = silrig_flight::f_true::from_trace(trace, scenario);
        let title = plot_title(scenario);
        files.extend(silrig_plot::plot_closed_loop(trace, f_true.as_ref(), &setpoint, out_dir, &title)?);
    } else if let Some(plant) = plant {
        let title = format!("{}, plant {}: every signal, commands in orange", scenario.name, plant.plant);
        files.extend(silrig_plot::plot_signals(trace, Some(plant), &setpoint, out_dir, "signals", &title)?);
    }
    Ok(files)
}

/// A scenario flown, in one process ([`fly_one_process`]) or through the three-process rig (a sweep's case with
/// `--controller-cmd`): what a case is judged on.
#[derive(Debug)]
pub struct FlownScenario {
    /// Its trace, as `silrig run --mode lockstep` writes it.
    pub trace: Trace,
    /// The plant's signals when it is not the built-in F-16 (its figures and its summary's rows come from them).
    pub plant: Option<PlantSignals>,
    /// When (s) and why it ended before the scenario's end; the trace holds it up to there.
    pub ended_early: Option<(f64, String)>,
    /// What the rig refused or reported as failed on the way (commands, plant outputs, a process that died), as
    /// sentences.
    pub refusals: Vec<String>,
}

/// Fly `scenario` in one process: the built-in F-16 against our controller by the reference loop
/// ([`silrig_flight::sim`]), a scenario with an FMU by the rig's generic loop ([`silrig_adapters::in_process`]) with
/// `models` (opened from this scenario, or from the one it was sampled from: the same FMU files). An error says
/// why it could not start.
pub fn fly_one_process(models: &Models, scenario: &Scenario) -> Result<FlownScenario, String> {
    if models.flies_reference_loop(scenario) {
        let (trace, left) = silrig_flight::sim::fly(scenario).map_err(|e| e.to_string())?;
        let ended_early = left.map(|exit| (exit.t_s, exit.to_string()));
        return Ok(FlownScenario { trace, plant: None, ended_early, refusals: Vec::new() });
    }
    let flown = models.fly(scenario).map_err(|e| e.to_string())?;
    let refusals = flown.refusals();
    let ended_early = flown.ended_early.map(|e| (e.t_s, e.to_string()));
    Ok(FlownScenario { trace: flown.trace, plant: models.own_plant(flown.plant), ended_early, refusals })
}

/// What [`simulate`] flew and wrote.
#[derive(Debug)]
pub struct Simulated {
    /// The control-quality figures.
    pub summary: Summary,
    /// The files written.
    pub files: Vec<PathBuf>,
    /// Set when the flight ended before the scenario's end (the F-16 left its envelope, an FMU failed): why; the
    /// files hold it up to there.
    pub ended_early: Option<String>,
    /// What the rig refused or reported as failed on the way (commands, plant outputs, a process that died), as
    /// sentences.
    pub refusals: Vec<String>,
}

/// `silrig sim`: fly the scenario's closed loop in one process (its FMUs too) and write its run into `out_dir` (as
/// far as it flew, if it ended early).
pub fn simulate(scenario: &Scenario, out_dir: &Path) -> anyhow::Result<Simulated> {
    let models = Models::open(scenario)?;
    let flight = fly_one_process(&models, scenario).map_err(anyhow::Error::msg)?;
    let summary = silrig_flight::summary::summarize(&flight.trace, scenario, flight.plant.as_ref());
    let files = write_run(out_dir, scenario, &flight.trace, &summary, flight.plant.as_ref())?;
    Ok(Simulated { summary, files, ended_early: flight.ended_early.map(|(_, why)| why), refusals: flight.refusals })
}

/// What [`compare`] produced.
#[derive(Debug)]
pub struct Comparison {
    /// One summary per scenario, in order.
    pub summaries: Vec<Summary>,
    /// The overlay figure's files.
    pub overlay: Vec<PathBuf>,
    /// The runs that left the model's envelope (scenario name, when and why); each is compared as far as it flew.
    pub left_envelope: Vec<(String, LeftEnvelope)>,
}

/// `silrig compare`: fly each scenario in one process, write each run under `out_dir/<scenario name>`, and draw
/// the runs over each other in `out_dir/overlay.{png,svg}`.
pub fn compare(scenarios: &[Scenario], out_dir: &Path) -> anyhow::Result<Comparison> {
    let mut summaries = Vec::new();
    let mut traces = Vec::new();
    let mut left_envelope = Vec::new();
    for scenario in scenarios {
        let (trace, left) = silrig_flight::sim::fly(scenario)?;
        left_envelope.extend(left.map(|exit| (scenario.name.clone(), exit)));
        let summary = silrig_flight::summary::summarize(&trace, scenario, None);
        write_run(&out_dir.join(&scenario.name), scenario, &trace, &summary, None)?;
        summaries.push(summary);
        traces.push((scenario.name.clone(), trace));
    }
    let overlay = silrig_plot::plot_overlay(&traces, out_dir, "overlay")?.files;
    Ok(Comparison { summaries, overlay, left_envelope })
}

/// Summaries side by side, one column per run, with the RMS-rate ratio of each run against the first.
pub fn compare_table(summaries: &[Summary]) -> String {
    let width = summaries.iter().map(|s| s.scenario.len()).max().unwrap_or(8).max(12) + 2;
    let mut out = format!("{:<34}", "");
    for s in summaries {
        out += &format!("{:>width$}", s.scenario);
    }
    out.push('\n');
    let mut line = |label: &str, f: &dyn Fn(&Summary) -> String| {
        out += &format!("{label:<34}");
        for s in summaries {
            out += &format!("{:>width$}", f(s));
        }
        out.push('\n');
    };
    let opt = |v: Option<f64>| v.map_or("never".into(), |x| format!("{x:.2}"));
    // `silrig compare` flies the built-in F-16: its attitude and its surfaces, looked up by name.
    let angle = |s: &'_ Summary, name: &str| s.setpoints.iter().find(|r| r.name == format!("{name}_deg")).cloned();
    let surface = |s: &'_ Summary, name: &str| s.actuators.iter().find(|a| a.name == name).cloned();
    let figure = |v: Option<f64>, decimals: usize| v.map_or("-".to_string(), |v| format!("{v:.decimals$}"));
    for name in ["phi", "theta", "psi"] {
        line(&format!("{name} settle 0.5 deg (s)"), &|s| {
            angle(s, name).and_then(|a| a.settle_within_0p5deg).map_or("-".into(), |d| opt(d.at_s))
        });
        line(&format!("{name} settle 2 % (s)"), &|s| match angle(s, name).map(|a| a.response) {
            Some(Response::Stepped { settle_within_2pct_s, .. }) => opt(settle_within_2pct_s),
            Some(Response::Held) => "held".into(),
            None => "-".into(),
        });
        line(&format!("{name} final (deg)"), &|s| figure(angle(s, name).map(|a| a.final_value), 3));
    }
    line("alpha final / peak (deg)", &|s| {
        s.alpha.as_ref().map_or("-".into(), |a| format!("{:.2}/{:.2}", a.final_deg, a.peak_deg))
    });
    for name in ["aileron", "elevator", "rudder"] {
        line(&format!("{name} peak (deg)"), &|s| figure(surface(s, name).map(|a| a.peak), 2));
        line(&format!("{name} ticks rate/pos limit"), &|s| {
            surface(s, name).map_or("-".into(), |a| format!("{}/{}", a.ticks_at_rate_limit, a.ticks_at_position_limit))
        });
        line(&format!("{name} rms rate (dps)"), &|s| figure(surface(s, name).and_then(|a| a.rms_rate_per_s), 3));
        line(&format!("{name} rms rate, late (dps)"), &|s| {
            figure(surface(s, name).and_then(|a| a.rms_rate_late_per_s), 3)
        });
    }
    let total = |s: &Summary, of: &dyn Fn(&silrig_flight::summary::ActuatorFigures) -> Option<f64>| {
        s.actuators.iter().map(|a| of(a).unwrap_or(f64::NAN).powi(2)).sum::<f64>().sqrt()
    };
    let total_rms =
        |s: &Summary, late: bool| total(s, &|a| if late { a.rms_rate_late_per_s } else { a.rms_rate_per_s });
    let total_cmd = |s: &Summary| total(s, &|a| a.rms_command_rate_per_s);
    let first = summaries.first().cloned();
    line("all surfaces rms rate (dps)", &|s| format!("{:.3}", total_rms(s, false)));
    if let Some(first) = first {
        line("  ratio to first run", &|s| format!("{:.2}x", total_rms(s, false) / total_rms(&first, false)));
        line("  late window, ratio to first run", &|s| format!("{:.2}x", total_rms(s, true) / total_rms(&first, true)));
        line("  commanded, ratio to first run", &|s| format!("{:.2}x", total_cmd(s) / total_cmd(&first)));
    }
    line("limit cycle", &|s| {
        let found: Vec<&str> = s.oscillations.iter().filter(|o| o.sustained).map(|o| o.signal.as_str()).collect();
        if found.is_empty() { "none".into() } else { format!("YES({})", found.len()) }
    });
    line("final |S| phi/theta/psi", &|s| {
        let finals: Vec<String> = s.channels.iter().map(|c| format!("{:.0e}", c.final_abs_s)).collect();
        if finals.is_empty() { "-".into() } else { finals.join("/") }
    });
    out
}
