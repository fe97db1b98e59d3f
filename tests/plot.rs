//! Plots: every figure is written as a real PNG and SVG, with its legends, from a synthetic trace that has sines,
//! constant and all-zero columns and a NaN; a missing column is an error naming it; a trace without our controller's
//! columns still gets its states figure; a plant that is not the F-16 gets its faults and signals figures, commands
//! beside positions, set points drawn, dimensionless units blank and held rows shaded.
//!
//! Set `SILRIG_PLOT_DIR=/some/dir` to keep the figures there for a look instead of a removed temp dir.

use std::path::{Path, PathBuf};
use std::time::Instant;

use silrig::f16_signals::f16_signals;
use silrig::plot::{
    Envelope, FigureAxes, Histogram, PlotError, TimelineEvent, plot_closed_loop, plot_envelope, plot_histograms,
    plot_latency_histograms, plot_overlay, plot_percentile_distributions, plot_response, plot_signals, plot_timeline,
};
use silrig::signals::{InputSignal, OutputSignal, PlantSignals};
use silrig::trace::{OUTPUTS_HELD_COLUMN, Trace, columns};

/// An output directory unique to the test; removed when dropped unless `SILRIG_PLOT_DIR` is set.
struct OutDir {
    path: PathBuf,
    keep: bool,
}

impl OutDir {
    fn new(test: &str) -> Self {
        match std::env::var_os("SILRIG_PLOT_DIR") {
            Some(dir) => {
                let path = PathBuf::from(dir).join(test);
                let _ = std::fs::remove_dir_all(&path);
                Self { path, keep: true }
            }
            None => {
                let path = std::env::temp_dir().join(format!("silrig-plot-{}-{test}", std::process::id()));
                let _ = std::fs::remove_dir_all(&path);
                Self { path, keep: false }
            }
        }
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if !self.keep {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

const NODES: usize = 5;

/// `rows` rows at 100 Hz: sines and decays, `psi_deg`, `s_psi` and the `w_psi_*` all zero, `rudder_cmd_deg` and
/// `fhat_psi` constant, one NaN in `theta_deg`. `phase` shifts the sines so that runs differ.
fn synthetic(rows: usize, phase: f64) -> Trace {
    let names = columns(NODES);
    let mut trace = Trace::new(names.clone());
    for k in 0..rows {
        let t = k as f64 * 0.01;
        let row = names
            .iter()
            .map(|name| {
                let s = |a: f64, w: f64| a * (w * t + phase).sin();
                match name.as_str() {
                    "t_s" => t,
                    "phi_deg" => s(20.0, 0.8),
                    "theta_deg" if k == rows / 2 => f64::NAN,
                    "theta_deg" => 5.0 + s(8.0, 0.5),
                    "psi_deg" => 0.0,
                    "alpha_deg" => 6.8 + s(2.0, 0.5),
                    "beta_deg" => s(0.5, 1.1),
                    "p_dps" => s(16.0, 0.8 + 1.0) * (-0.1 * t).exp(),
                    "q_dps" => s(4.0, 0.5 + 1.0),
                    "r_dps" => s(1.0, 0.3),
                    "vt_mps" => 150.0,
                    "alt_ft" => 25_000.0 + 10.0 * t,
                    "nz_g" => 1.0 + s(0.3, 0.9),
                    "ny_g" => s(0.05, 1.1),
                    "aileron_cmd_deg" => s(-10.0, 1.3),
                    "aileron_deg" => s(-10.0, 1.3) * 0.95,
                    "elevator_cmd_deg" => -0.56 + s(3.0, 0.7),
                    "elevator_deg" => -0.56 + s(3.0, 0.7) * 0.9,
                    "rudder_cmd_deg" => 2.0,
                    "rudder_deg" => 2.0 * (1.0 - (-5.0 * t).exp()),
                    "throttle" => 0.2586,
                    "flight_segment" => 0.0,
                    "s_phi" => s(1.0, 2.0) * (-0.3 * t).exp(),
                    "s_theta" => s(0.3, 1.5) * (-0.2 * t).exp(),
                    "s_psi" => 0.0,
                    "fhat_phi" => s(50.0, 0.8),
                    "fhat_theta" => -3.0 + s(1.0, 0.4),
                    "fhat_psi" => 0.5,
                    w if w.starts_with("w_psi_") => 0.0,
                    w if w.starts_with("w_") => {
                        let node: f64 = w.rsplit('_').next().unwrap().parse().unwrap();
                        (node - 3.0) * 0.01 * (1.0 - (-t / node).exp())
                    }
                    other => panic!("no synthetic data for {other}"),
                }
            })
            .collect();
        trace.rows.push(row);
    }
    trace
}

/// The F-16's announcement (the synthetic trace's columns are its trace's).
fn f16() -> PlantSignals {
    f16_signals([0.0; 4])
}

/// The F-16 scenario's set points: the attitude, wings level at 5 deg of pitch.
fn f16_setpoint(name: &str) -> Option<f64> {
    [("phi_deg", 0.0), ("theta_deg", 5.0), ("psi_deg", 0.0)].iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
}

/// A foreign three-axis vehicle as tests/fmu/attitude announces itself: inputs named with their unit, no output
/// reporting a surface's position, a dimensionless throttle.
fn attitude() -> PlantSignals {
    let output = |name: &str, unit: &str| OutputSignal { name: name.into(), unit: unit.into(), in_trace: true };
    let input = |name: &str, unit: &str, hold| InputSignal {
        name: name.into(),
        unit: unit.into(),
        min: -25.0,
        max: 25.0,
        hold,
        held_output: None,
        command_in_trace: true,
    };
    PlantSignals {
        plant: "attitude".into(),
        outputs: ["phi_deg", "theta_deg", "psi_deg"]
            .map(|n| output(n, "deg"))
            .into_iter()
            .chain(["p_dps", "q_dps", "r_dps"].map(|n| output(n, "deg/s")))
            .collect(),
        inputs: vec![
            input("aileron_deg", "deg", 0.0),
            input("elevator_deg", "deg", 0.0),
            input("rudder_deg", "deg", 0.0),
            input("throttle", "", 0.5),
        ],
    }
}

/// 10 s of the attitude vehicle rolling to 10 deg: the controller killed at 3 s (no command after it, NaN), the
/// outputs held from 6 to 7 s (flagged in `outputs_held`).
fn attitude_trace(plant: &PlantSignals) -> Trace {
    let mut names = plant.trace_columns(&[]);
    names.push(OUTPUTS_HELD_COLUMN.into());
    let mut trace = Trace::new(names.clone());
    for k in 0..=1000 {
        let t = k as f64 * 0.01;
        let roll = 10.0 * (1.0 - (-t).exp());
        let commanded = |v: f64| if t < 3.0 { v } else { f64::NAN };
        let held = (600..700).contains(&k);
        let row = names
            .iter()
            .map(|c| match c.as_str() {
                "t_s" => t,
                "phi_deg" if held => 10.0 * (1.0 - (-6.0f64).exp()),
                "phi_deg" => roll,
                "theta_deg" => 5.0 * (1.0 - (-2.0 * t).exp()),
                "p_dps" => 10.0 * (-t).exp(),
                "aileron_deg_cmd_deg" => commanded(-5.0 * (-t).exp()),
                "throttle_cmd" => commanded(0.5),
                c if c.ends_with("_cmd_deg") => commanded(0.0),
                OUTPUTS_HELD_COLUMN => f64::from(u8::from(held)),
                _ => 0.0,
            })
            .collect();
        trace.rows.push(row);
    }
    trace
}

#[test]
fn faults_and_signals_of_a_plant_that_is_not_the_f16() {
    let dir = OutDir::new("foreign");
    let plant = attitude();
    let trace = attitude_trace(&plant);
    let setpoint = |name: &str| [("phi_deg", 10.0), ("theta_deg", 5.0)].iter().find(|(n, _)| *n == name).map(|p| p.1);
    let events = [TimelineEvent { t_s: 3.0, label: "controller kill at 3 s".into(), end_s: Some(3.5) }];
    let faults = plot_timeline(&trace, &plant, &setpoint, &events, &dir.path, "faults", "attitude: faults").unwrap();
    let signals =
        plot_signals(&trace, Some(&plant), &setpoint, &dir.path, "signals", "attitude: every signal").unwrap();
    check_files(
        &[faults.files, signals.files].concat(),
        &["faults", "signals"],
        &[
            &["controller kill at 3 s", "phi_deg set point", "theta_deg set point", "aileron_deg cmd", "throttle cmd"],
            &["phi_deg (set point 10, dashed)", "aileron_deg command", "throttle command", "p_dps"],
        ],
    );
    for stem in ["faults", "signals"] {
        let svg = std::fs::read_to_string(dir.path.join(format!("{stem}.svg"))).unwrap();
        assert!(svg.contains("shaded: outputs held"), "{stem}.svg does not say what is shaded");
        // Only the output with no set point (psi) is left without a dashed set point line.
        assert!(
            !svg.contains("psi_deg set point") && !svg.contains("psi_deg (set point"),
            "{stem}: a set point for psi"
        );
    }
    // The paper's states figure needs the F-16's columns: the run leaves it out with this reason.
    let missing = plot_closed_loop(&trace, None, &f16_setpoint, &dir.path, "x").unwrap_err();
    assert!(matches!(missing, PlotError::MissingColumn { .. }), "{missing}");
}

/// Every file exists; PNGs are real, non-trivial PNGs; SVGs are SVG and contain `needles` (legend text).
fn check_files(paths: &[PathBuf], stems: &[&str], needles: &[&[&str]]) {
    assert_eq!(paths.len(), 2 * stems.len(), "{paths:?}");
    for (k, stem) in stems.iter().enumerate() {
        let png = &paths[2 * k];
        let svg = &paths[2 * k + 1];
        assert_eq!(png.file_name().unwrap().to_str().unwrap(), format!("{stem}.png"));
        assert_eq!(svg.file_name().unwrap().to_str().unwrap(), format!("{stem}.svg"));
        let bytes = std::fs::read(png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{} is not a PNG", png.display());
        assert!(bytes.len() > 10_000, "{} is only {} bytes", png.display(), bytes.len());
        let text = std::fs::read_to_string(svg).unwrap_or_else(|e| panic!("{}: {e}", svg.display()));
        assert!(text.contains("<svg"), "{} is not an SVG", svg.display());
        for needle in needles[k] {
            assert!(text.contains(needle), "{} lacks {needle:?}", svg.display());
        }
    }
}

fn timed<T>(what: &str, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let out = f();
    eprintln!("{what}: {:.0} ms", start.elapsed().as_secs_f64() * 1e3);
    out
}

#[test]
fn closed_loop_figures_are_written_with_their_legends() {
    let dir = OutDir::new("closed_loop");
    let trace = synthetic(1000, 0.0);
    // The true f the figure sets beside each RBF estimate (crate::f_true computes it from a flight).
    let t = trace.column("t_s").unwrap();
    let f_true = [0.3, -1.0, 2.0].map(|a| t.iter().map(|t| a * (2.0 * t).cos()).collect::<Vec<f64>>());
    let paths = timed("closed loop, 3 figures", || {
        plot_closed_loop(&trace, Some(&f_true), &f16_setpoint, &dir.path, "synthetic 10 s run")
    })
    .expect("closed-loop figures");
    check_files(
        &paths,
        &["fig1_states", "fig2_sliding", "fig3_weights"],
        &[
            &["synthetic 10 s run", "α", "φ roll", "θ pitch", "ψ yaw", "p roll", "aileron", "rudder cmd", "t (s)"],
            &["S (rad/s)", "f_hat", "f true", "true f = d²φ/dt² − g·δ − d", "θ channel", "ψ channel"],
            &["W1", "W5", "RBF weights"],
        ],
    );
}

#[test]
fn weight_legend_follows_the_number_of_weight_columns() {
    let dir = OutDir::new("weights_12");
    let names = columns(12);
    let mut trace = Trace::new(names.clone());
    for k in 0..300 {
        let t = k as f64 * 0.01;
        trace
            .rows
            .push(names.iter().enumerate().map(|(i, _)| if i == 0 { t } else { (t * i as f64 * 0.1).sin() }).collect());
    }
    let paths = plot_closed_loop(&trace, None, &f16_setpoint, &dir.path, "12 nodes").expect("figures");
    let svg = std::fs::read_to_string(&paths[5]).unwrap();
    assert!(svg.contains("\nW12\n"), "no W12 in the legend");
    assert!(!svg.contains("\nW13\n"));
}

#[test]
fn overlay_has_one_legend_entry_per_run() {
    let dir = OutDir::new("overlay");
    let runs = vec![
        ("baseline".to_string(), synthetic(1000, 0.0)),
        ("fault & gust".to_string(), synthetic(800, 0.7)),
        ("no adaptation".to_string(), synthetic(1000, 1.9)),
    ];
    let paths = timed("overlay", || plot_overlay(&runs, &dir.path, "compare")).expect("overlay");
    check_files(&paths, &["compare"], &[&["baseline", "fault &amp; gust", "no adaptation", "elevator", "rudder"]]);
}

#[test]
fn percentile_distribution_on_the_nines_scale() {
    let dir = OutDir::new("percentiles");
    let curve = |base: f64, tail: f64| -> Vec<(f64, f64)> {
        let mut points = Vec::new();
        let mut p: f64 = 0.0;
        while p < 99.999 {
            let nines = (1.0 / (1.0 - p / 100.0)).log10();
            points.push((p, base + tail * nines.powi(3)));
            p += (100.0 - p) * 0.1; // HdrHistogram-like: denser towards the tail
        }
        points.push((100.0, 1e9)); // the 100th percentile is off the scale: skipped
        points.push((50.0, f64::NAN)); // skipped
        points
    };
    let series = vec![
        ("tick period jitter".to_string(), curve(3.0, 2.0)),
        ("plant step".to_string(), curve(1.1, 0.4)),
        ("round trip".to_string(), curve(12.0, 8.0)),
    ];
    let paths = timed("percentiles", || plot_percentile_distributions(&series, &dir.path, "latency", "Loop latency"))
        .expect("percentiles");
    check_files(
        &paths,
        &["latency"],
        &[&["tick period jitter", "plant step", "round trip", "99.9%", "99.99%", "90%", "µs", "Loop latency"]],
    );
}

#[test]
fn timeline_marks_events() {
    let dir = OutDir::new("timeline");
    let trace = synthetic(1000, 0.0);
    let events = vec![
        TimelineEvent { t_s: 2.0, label: "aileron stuck".into(), end_s: Some(f64::INFINITY) },
        TimelineEvent { t_s: 2.2, label: "sensor dropout".into(), end_s: None },
        TimelineEvent { t_s: 7.5, label: "elevator 50 % effective".into(), end_s: None },
        TimelineEvent { t_s: 9.8, label: "controller restarted".into(), end_s: None },
        TimelineEvent { t_s: 42.0, label: "after the end".into(), end_s: None },
    ];
    let paths = timed("timeline", || {
        plot_timeline(&trace, &f16(), &f16_setpoint, &events, &dir.path, "faults", "Fault injection")
    })
    .expect("timeline");
    check_files(
        &paths,
        &["faults"],
        &[&[
            "aileron stuck",
            "sensor dropout",
            "elevator 50 % effective",
            "outputs (solid) and their set points (dashed)",
            "phi_deg set point",
            "rudder cmd",
            "throttle",
        ]],
    );
    let svg = std::fs::read_to_string(&paths[1]).unwrap();
    assert!(!svg.contains("after the end"), "an event outside the trace was drawn");
}

fn expect_missing(result: Result<silrig::plot::Drawn, PlotError>, column: &str, file: &str) -> String {
    let err = result.expect_err("a missing column must be an error");
    let message = err.to_string();
    assert!(matches!(&err, PlotError::MissingColumn { column: c, .. } if c == column), "{message}");
    assert!(message.contains(&format!("`{column}`")) && message.contains(file), "{message}");
    message
}

#[test]
fn a_missing_column_is_an_error_naming_it() {
    let dir = OutDir::new("missing");
    let full = synthetic(50, 0.0);
    let without = |column: &str| {
        let i = full.index(column).unwrap();
        let mut t = Trace::new(full.columns.clone());
        t.columns.remove(i);
        t.rows = full.rows.iter().map(|r| [&r[..i], &r[i + 1..]].concat()).collect();
        t
    };
    expect_missing(
        plot_closed_loop(&without("alpha_deg"), None, &f16_setpoint, &dir.path, "x"),
        "alpha_deg",
        "fig1_states.png",
    );
    expect_missing(
        plot_closed_loop(&without("fhat_theta"), None, &f16_setpoint, &dir.path, "x"),
        "fhat_theta",
        "fig2_sliding.png",
    );
    assert!(!dir.path.join("fig1_states.png").exists(), "a figure was written before the missing column was found");
    // Without any weight column there is no weights figure to draw, and nothing is missing.
    let mut no_weights = full.clone();
    let first_weight = no_weights.index("w_phi_1").unwrap();
    no_weights.columns.truncate(first_weight);
    no_weights.rows.iter_mut().for_each(|r| r.truncate(first_weight));
    let no_weights_dir = dir.path.join("no_weights");
    let paths =
        plot_closed_loop(&no_weights, None, &f16_setpoint, &no_weights_dir, "x").expect("a trace without weights");
    check_files(&paths, &["fig1_states", "fig2_sliding"], &[&["α"], &["S (rad/s)", "RBF estimate f_hat, ψ channel"]]);
    assert!(!no_weights_dir.join("fig3_weights.png").exists() && !no_weights_dir.join("fig3_weights.svg").exists());
    let message = expect_missing(
        plot_overlay(&[("good".into(), full.clone()), ("bad run".into(), without("rudder_deg"))], &dir.path, "cmp"),
        "rudder_deg",
        "cmp.png",
    );
    assert!(message.contains("run `bad run`"), "{message}");
    expect_missing(plot_timeline(&without("t_s"), &f16(), &f16_setpoint, &[], &dir.path, "tl", "x"), "t_s", "tl.png");

    // Nothing to draw is an error too, not a panic or an empty picture.
    assert!(matches!(plot_overlay(&[], &dir.path, "none"), Err(PlotError::NoData { .. })));
    assert!(matches!(
        plot_closed_loop(&Trace::new(columns(2)), None, &f16_setpoint, &dir.path, "x"),
        Err(PlotError::NoData { .. })
    ));
}

/// `trace` with only the columns `keep` accepts.
fn only(trace: &Trace, keep: impl Fn(&str) -> bool) -> Trace {
    let kept: Vec<usize> = (0..trace.columns.len()).filter(|&i| keep(&trace.columns[i])).collect();
    let mut t = Trace::new(kept.iter().map(|&i| trace.columns[i].clone()).collect());
    t.rows = trace.rows.iter().map(|r| kept.iter().map(|&i| r[i]).collect()).collect();
    t
}

fn is_controller_column(column: &str) -> bool {
    ["s_", "fhat_", "w_"].iter().any(|prefix| column.starts_with(prefix))
}

#[test]
fn a_trace_of_another_controller_gets_the_states_figure_only() {
    let dir = OutDir::new("states_only");
    let full = synthetic(300, 0.0);
    let states = only(&full, |c| !is_controller_column(c));
    let paths =
        plot_closed_loop(&states, None, &f16_setpoint, &dir.path, "another controller").expect("the states figure");
    check_files(&paths, &["fig1_states"], &[&["another controller", "α", "φ roll", "rudder cmd", "t (s)"]]);
    let mut written: Vec<_> = std::fs::read_dir(&dir.path).unwrap().map(|e| e.unwrap().file_name()).collect();
    written.sort();
    assert_eq!(written, ["fig1_states.png", "fig1_states.svg"]);

    // The states figure does not depend on the controller's columns.
    let with_controller = dir.path.join("with_controller");
    let all =
        plot_closed_loop(&full, None, &f16_setpoint, &with_controller, "another controller").expect("all figures");
    assert_eq!(all.len(), 6);
    for (a, b) in paths.iter().zip(&all) {
        assert!(std::fs::read(a).unwrap() == std::fs::read(b).unwrap(), "{} and {} differ", a.display(), b.display());
    }
}

#[test]
fn a_partly_present_controller_figure_is_an_error_naming_the_missing_column() {
    let dir = OutDir::new("partly");
    let full = synthetic(50, 0.0);
    let no_psi_weights = only(&full, |c| !c.starts_with("w_psi_"));
    expect_missing(
        plot_closed_loop(&no_psi_weights, None, &f16_setpoint, &dir.path, "x"),
        "w_psi_1",
        "fig3_weights.png",
    );
    let one_surface = only(&full, |c| !is_controller_column(c) || c == "s_phi");
    expect_missing(plot_closed_loop(&one_surface, None, &f16_setpoint, &dir.path, "x"), "fhat_phi", "fig2_sliding.png");
    let no_fhat_theta = only(&full, |c| !c.starts_with("w_") && c != "fhat_theta");
    expect_missing(
        plot_closed_loop(&no_fhat_theta, None, &f16_setpoint, &dir.path, "x"),
        "fhat_theta",
        "fig2_sliding.png",
    );
    assert!(!dir.path.exists(), "a figure was written before the missing column was found");
}

#[test]
fn extreme_and_non_finite_values_do_not_panic() {
    let dir = OutDir::new("extreme");
    let mut trace = synthetic(200, 0.0);
    let (alpha, theta, p) =
        (trace.index("alpha_deg").unwrap(), trace.index("theta_deg").unwrap(), trace.index("p_dps").unwrap());
    for (k, row) in trace.rows.iter_mut().enumerate() {
        row[alpha] = if k % 2 == 0 { f64::MAX } else { -f64::MAX };
        row[theta] = f64::NAN;
        row[p] = if k == 3 { f64::INFINITY } else { 1e-300 * k as f64 };
    }
    let paths = plot_closed_loop(&trace, None, &f16_setpoint, &dir.path, "extreme").expect("figures");
    assert!(paths.iter().all(|p| p.exists()));
    let one_row = synthetic(1, 0.0);
    let start = [TimelineEvent { t_s: 0.0, label: "start".into(), end_s: None }];
    plot_timeline(&one_row, &f16(), &f16_setpoint, &start, &dir.path, "one", "one row").expect("a one-row trace");
    plot_percentile_distributions(&[("empty".into(), Vec::new())], &dir.path, "empty", "no points").expect("empty");
}

#[test]
fn an_unwritable_output_directory_is_an_error_naming_it() {
    let dir = OutDir::new("unwritable");
    std::fs::create_dir_all(&dir.path).unwrap();
    let file = dir.path.join("a-file");
    std::fs::write(&file, "not a directory").unwrap();
    let err = plot_timeline(&synthetic(50, 0.0), &f16(), &f16_setpoint, &[], &file.join("sub"), "tl", "x").unwrap_err();
    assert!(matches!(err, PlotError::CreateDir { .. }), "{err}");
    assert!(err.to_string().contains(&file.join("sub").display().to_string()), "{err}");
}

#[test]
fn a_60_s_trace_plots_in_well_under_a_second_per_figure() {
    let dir = OutDir::new("long");
    let trace = synthetic(6000, 0.3);
    let start = Instant::now();
    let paths = plot_closed_loop(&trace, None, &f16_setpoint, &dir.path, "60 s").unwrap();
    let per_figure = start.elapsed().as_secs_f64() / 3.0;
    eprintln!("60 s trace: {:.0} ms per figure (PNG + SVG)", per_figure * 1e3);
    assert!(Path::new(&paths[0]).exists());
    // Generous for a loaded 2-core CI machine; the measured figure is printed above.
    assert!(per_figure < 3.0, "{per_figure} s per figure");
}

/// A figure's axes against its data, as the layout decided them: the title fits the width; some panel names the x
/// axis; every panel has tick labels on both axes, a y label that is never "1" (a dimensionless unit is blank),
/// an x axis that covers its data and ends where the data end, and a y axis that covers the data setting it.
fn axes_fit_their_data(fig: &FigureAxes) {
    let name = &fig.stem;
    assert!(
        fig.title_width_px <= fig.width_px,
        "{name}: the title is {} px in {} px",
        fig.title_width_px,
        fig.width_px
    );
    assert!(fig.panels.iter().any(|p| p.x_label.as_deref().is_some_and(|l| !l.is_empty())), "{name}: no x label");
    for p in &fig.panels {
        let what = format!("{name}, panel {:?}", p.caption);
        assert!(p.x.ticks.len() >= 2 && !p.y.ticks.is_empty(), "{what}: ticks {:?} {:?}", p.x.ticks, p.y.ticks);
        assert!(p.x.ticks.iter().chain(&p.y.ticks).all(|t| !t.is_empty()), "{what}: an empty tick label");
        assert_ne!(p.y_label, "1", "{what}: a dimensionless unit is left blank");
        if let Some((lo, hi)) = p.x_data {
            let tol = 1e-9 * (hi - lo).abs().max(1.0);
            assert!(
                p.x.lo <= lo + tol && (p.x.hi - hi).abs() <= tol,
                "{what}: x {}..{} for data {lo}..{hi}",
                p.x.lo,
                p.x.hi
            );
        }
        if let Some((lo, hi)) = p.y_data {
            let tol = 1e-9 * hi.abs().max(lo.abs()).max(1e-12);
            assert!(p.y.lo <= lo + tol && p.y.hi >= hi - tol, "{what}: y {}..{} for data {lo}..{hi}", p.y.lo, p.y.hi);
        }
    }
}

/// A trace of `plant`'s columns over 10 s at 100 Hz: each output with a set point rising to it, every other column
/// a sine of its own amplitude (a command leads its position by a little).
fn signal_trace(plant: &PlantSignals, setpoint: &dyn Fn(&str) -> Option<f64>) -> Trace {
    let names = plant.trace_columns(&[]);
    let mut trace = Trace::new(names.clone());
    trace.rows = (0..=1000)
        .map(|k| {
            let t = k as f64 * 0.01;
            names
                .iter()
                .enumerate()
                .map(|(c, name)| match (name.as_str(), setpoint(name)) {
                    ("t_s", _) => t,
                    (_, Some(sp)) => sp * (1.0 - (-2.0 * t).exp()),
                    (n, None) if n.ends_with("_cmd_deg") || n.ends_with("_cmd") => (c as f64) * (t + 0.1).sin(),
                    _ => (c as f64) * t.sin(),
                })
                .collect()
        })
        .collect();
    trace
}

/// The plant's figures drawn, each held to its data; every output with a set point has its panel in the response
/// figure with the set point over it and its unit as the y label; the fault window is drawn from start to end.
fn check_plant_figures(plant: &PlantSignals, setpoint: &dyn Fn(&str) -> Option<f64>, dir: &Path) {
    let trace = signal_trace(plant, setpoint);
    let response = plot_response(&trace, Some(plant), setpoint, dir, "response", &plant.plant).unwrap();
    let events = [TimelineEvent { t_s: 3.0, label: "controller kill at 3 s".into(), end_s: Some(3.5) }];
    let faults = plot_timeline(&trace, plant, setpoint, &events, dir, "faults", &plant.plant).unwrap();
    let signals = plot_signals(&trace, Some(plant), setpoint, dir, "signals", &plant.plant).unwrap();
    for drawn in [&response, &faults, &signals] {
        drawn.figures.iter().for_each(axes_fit_their_data);
    }
    let with_setpoint: Vec<&OutputSignal> = plant.outputs.iter().filter(|o| setpoint(&o.name).is_some()).collect();
    let panels = &response.figure("response").unwrap().panels;
    assert_eq!(panels.len(), with_setpoint.len(), "{}: one response panel per set point", plant.plant);
    for (panel, output) in panels.iter().zip(&with_setpoint) {
        assert_eq!(panel.series, [output.name.as_str(), "set point"], "{}", plant.plant);
        let unit = if output.unit == "1" { "" } else { output.unit.as_str() };
        assert_eq!(panel.y_label, unit, "{}: {}'s unit", plant.plant, output.name);
    }
    for panel in &faults.figure("faults").unwrap().panels {
        assert_eq!(panel.windows, [(3.0, 3.5)], "{}: the fault's window, start to end", plant.plant);
    }
}

#[test]
fn every_figure_s_axes_fit_its_data_for_the_f16_a_plant_of_your_own_and_the_quadrotor() {
    let dir = OutDir::new("axes");
    check_plant_figures(&f16(), &f16_setpoint, &dir.path.join("f16"));
    let attitude_setpoint = |n: &str| (n == "phi_deg").then_some(10.0);
    check_plant_figures(&attitude(), &attitude_setpoint, &dir.path.join("attitude"));
    // The quadrotor as configs/quad-steps.toml flies it: its announcement and its set points.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/quad-steps.toml");
    let scenario = silrig::scenario::Scenario::load(&path).unwrap();
    let quad = silrig_flight::quad::builtin_signals(&scenario).unwrap();
    let quad_setpoint = |n: &str| scenario.setpoint.get(n);
    check_plant_figures(&quad, &quad_setpoint, &dir.path.join("quad"));

    // The F-16's states: set points on the attitude panel, every panel fitting its data.
    let states =
        plot_closed_loop(&synthetic(1000, 0.0), None, &f16_setpoint, &dir.path, "long title ".repeat(20).trim())
            .unwrap();
    states.figures.iter().for_each(axes_fit_their_data);
    let fig1 = states.figure("fig1_states").unwrap();
    assert_eq!(
        fig1.panels[1].series,
        ["φ roll", "φ roll set point", "θ pitch", "θ pitch set point", "ψ yaw", "ψ yaw set point"]
    );
}

#[test]
fn latency_figures_show_the_bulk_and_the_worst_tick() {
    let dir = OutDir::new("latency-axes");
    // 301 samples: the bulk at tens of µs, one logger wake-up at 47 ms.
    let mut values: Vec<f64> = (0..300).map(|k| 20.0 + (k % 40) as f64).collect();
    values.push(47_000.0);
    values.sort_by(f64::total_cmp);
    let points = |v: &[f64]| -> Vec<(f64, f64)> {
        v.iter().enumerate().map(|(k, x)| (100.0 * k as f64 / v.len() as f64, *x)).collect()
    };
    let series = vec![
        ("logger.ipc_plant_to_logger".to_string(), points(&values)),
        ("plant".to_string(), points(&values[..300])),
    ];
    let drawn = plot_percentile_distributions(&series, &dir.path, "latency", "latency").unwrap();
    let fig = drawn.figure("latency").unwrap();
    axes_fit_their_data(fig);
    let p = &fig.panels[0];
    assert!(p.y_log && p.y.hi >= 47_000.0 && p.y.lo <= 20.0, "log y {}..{}", p.y.lo, p.y.hi);
    assert!(p.y.ticks.contains(&"10,000".to_string()) && p.y.ticks.contains(&"100".to_string()), "{:?}", p.y.ticks);
    let highest = (1.0f64 / (1.0 - 300.0 / 301.0)).log10();
    assert!((p.x.hi - highest).abs() < 1e-9, "the percentile axis ends at the data: {} vs {highest}", p.x.hi);
    assert!(p.caption.contains("47000 µs, logger.ipc_plant_to_logger"), "{}", p.caption);

    let per_tick = vec![("plant.wake_lateness".to_string(), values.clone())];
    let drawn = plot_latency_histograms(&per_tick, 5.0, &dir.path, "latency_histogram", "histogram").unwrap();
    let fig = drawn.figure("latency_histogram").unwrap();
    axes_fit_their_data(fig);
    let p = &fig.panels[0];
    assert!(p.x.hi <= 100.0, "the x axis ends at the 99.9th percentile's bucket, not at 47,000 µs: {}", p.x.hi);
    assert!(p.caption.starts_with("1 tick beyond") && p.caption.contains("highest 47000 µs"), "{}", p.caption);
    assert_eq!(p.y_label, "ticks per bucket");
    assert!(p.y_log && p.y.ticks.iter().all(|t| ["1", "10", "100"].contains(&t.as_str())), "{:?}", p.y.ticks);
}

#[test]
fn sweep_figures_name_every_panel_s_unit_and_fit_their_titles() {
    let dir = OutDir::new("sweep-axes");
    let histogram = |caption: &str, unit: &str| Histogram {
        caption: caption.into(),
        unit: unit.into(),
        values: (0..50).map(|k| k as f64 * 0.1).collect(),
        limit: Some(4.0),
    };
    let panels: Vec<Histogram> =
        [("alpha", "deg"), ("settle", "s"), ("rate", "deg/s"), ("overshoot", "deg"), ("error", "m")]
            .iter()
            .map(|(c, u)| histogram(c, u))
            .collect();
    let drawn = plot_histograms(&panels, &dir.path, "histograms", "histograms").unwrap();
    let fig = drawn.figure("histograms").unwrap();
    axes_fit_their_data(fig);
    let labels: Vec<Option<&str>> = fig.panels.iter().map(|p| p.x_label.as_deref()).collect();
    assert_eq!(labels, [Some("deg"), Some("s"), Some("deg/s"), Some("deg"), Some("m")], "every histogram's unit");
    let envelope = Envelope {
        caption: "phi_deg".into(),
        unit: "deg".into(),
        band: (0..100).map(|k| (k as f64 * 0.1, -1.0, 1.0)).collect(),
        failed: vec![],
        setpoint: 0.0,
    };
    let title = "sweep-robust: 1000 cases, the default scenario with sensor errors and 21 dispersions: envelope";
    let drawn = plot_envelope(&[envelope], &dir.path, "envelope", title).unwrap();
    axes_fit_their_data(drawn.figure("envelope").unwrap());
}
