//! Plant-model faults (sensor noise and bias, actuator stuck, hard-over, rate-frozen) as `silrig sim` and the rig's
//! plant apply them through `PlantRunner`: actuator faults hold or drive the surface within its limits, sensor
//! faults change what the plant reports and never the true state, noise is reproducible from the seed, windows
//! end, and malformed plans are refused naming the entry.

use silrig::control::SurfaceCommand;
use silrig::fault::{Fault, FaultAction, FaultTarget};
use silrig::plant::F16Model;
use silrig::scenario::{Scenario, ScenarioError};
use silrig::sim::{self, ActuatorCommand, PlantRunner, SetupError, measurement};
use silrig::trace::Trace;
use silrig::units::rad_to_deg;
use std::path::PathBuf;

fn config_text(name: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("configs").join(format!("{name}.toml"));
    std::fs::read_to_string(path).unwrap()
}

/// The default scenario (book rate limits and lag, next-tick) with `faults` as its plan.
fn robust_with(faults: Vec<Fault>) -> Scenario {
    let mut s = Scenario::from_toml(&config_text("robust"), "robust.toml").unwrap();
    s.faults = faults;
    s.validate().unwrap();
    s
}

fn plant_fault(action: FaultAction, at_s: f64, duration_s: Option<f64>) -> Fault {
    Fault { at_s, duration_s, target: Some(FaultTarget::Plant), action: Some(action), ..Fault::default() }
}

fn surface_fault(action: FaultAction, surface: &str, at_s: f64, duration_s: Option<f64>) -> Fault {
    Fault { surface: Some(surface.into()), ..plant_fault(action, at_s, duration_s) }
}

fn sensor_bias(channel: &str, bias: f64, at_s: f64, duration_s: Option<f64>) -> Fault {
    Fault { channel: Some(channel.into()), bias: Some(bias), ..plant_fault(FaultAction::SensorBias, at_s, duration_s) }
}

fn sensor_noise(channel: &str, std: f64, at_s: f64) -> Fault {
    Fault { channel: Some(channel.into()), std: Some(std), ..plant_fault(FaultAction::SensorNoise, at_s, None) }
}

fn column(trace: &Trace, name: &str) -> Vec<f64> {
    trace.column(name).unwrap()
}

fn bits(trace: &Trace) -> Vec<Vec<u64>> {
    trace.rows.iter().map(|r| r.iter().map(|v| v.to_bits()).collect()).collect()
}

/// A command with the given elevator and the runner's initial aileron, rudder and throttle.
fn elevator_command(runner: &PlantRunner, elevator_deg: f64) -> ActuatorCommand {
    let c = runner.initial_command();
    ActuatorCommand { surfaces: SurfaceCommand { elevator_deg, ..c.surfaces }, ..c }
}

#[test]
fn a_stuck_elevator_holds_its_position_exactly_while_commands_change() {
    let s = robust_with(vec![surface_fault(FaultAction::ActuatorStuck, "elevator", 2.0, None)]);
    let trace = sim::run(&s).unwrap();
    let clean = sim::run(&robust_with(vec![])).unwrap();
    let (elevator, command) = (column(&trace, "elevator_deg"), column(&trace, "elevator_cmd_deg"));
    // Row k holds the deflection over [t_k, t_k+1); from tick 200 (t = 2 s) on the elevator stays where the update
    // of tick 199 left it.
    assert!(bits(&trace)[..200] == bits(&clean)[..200], "nothing differs before the fault acts");
    let held = elevator[199];
    assert!(elevator[199..].iter().all(|e| *e == held), "the stuck elevator moved");
    let (lo, hi) = command[200..].iter().fold((f64::MAX, f64::MIN), |(lo, hi), c| (lo.min(*c), hi.max(*c)));
    assert!(hi - lo > 1.0, "the commands should change while it is stuck: {lo}..{hi}");
    assert!(elevator[198] != held, "it was moving before the fault");

    // By hand: whatever the commands, the position stays put.
    let mut runner = PlantRunner::new(&s).unwrap();
    for k in 0..400 {
        let before = runner.snapshot().surfaces_deg[1];
        runner.step(&elevator_command(&runner, if k % 2 == 0 { 20.0 } else { -20.0 })).unwrap();
        if k >= 200 {
            assert_eq!(runner.snapshot().surfaces_deg[1], before, "tick {k}");
        }
    }
}

#[test]
fn hard_over_reaches_its_limit_at_the_rate_limit_and_stays() {
    let s = robust_with(vec![Fault {
        limit: Some("max".into()),
        ..surface_fault(FaultAction::ActuatorHardOver, "elevator", 2.0, None)
    }]);
    let mut runner = PlantRunner::new(&s).unwrap();
    let step_deg = 60.0 * s.timing.dt_s;
    let (mut reached_at, mut start_deg) = (None, None);
    for k in 0..300u64 {
        let before = runner.snapshot().surfaces_deg[1];
        if k == 200 {
            start_deg = Some(before);
        }
        // The command pulls the other way; the runaway ignores it.
        let hits = runner.step(&elevator_command(&runner, -10.0)).unwrap();
        let after = runner.snapshot().surfaces_deg[1];
        if k < 200 {
            continue;
        }
        if before < 25.0 {
            // Full rate until the last step, which lands on the stop.
            assert!(after == 25.0 || (after - before - step_deg).abs() < 1e-9, "tick {k}: {before} -> {after}");
            assert!(after - before <= step_deg + 1e-9);
            if after == 25.0 {
                reached_at = Some(k);
            } else {
                assert!(hits[1].rate, "tick {k}: the rate limit should bind");
            }
        } else {
            assert_eq!(after, 25.0, "tick {k}: left the stop");
            assert!(hits[1].position, "tick {k}: the stop should be reported");
        }
    }
    // Before the fault the -10 deg command took the elevator there (within the lag's last hair); 35 deg of travel
    // at 0.6 deg a step is 59 steps.
    let start_deg = start_deg.unwrap();
    assert!((start_deg + 10.0).abs() < 1e-9, "{start_deg}");
    assert_eq!(reached_at, Some(200 + ((25.0 - start_deg) / step_deg).ceil() as u64 - 1));
}

#[test]
fn the_anti_windup_keeps_the_soaks_elevator_hard_over_from_departing() {
    // The chaos soak's fault (seed 1): the elevator driven to its lower stop for 0.232 s at 113.301 s. Learning
    // from the sliding surface while the elevator cannot deliver winds the pitch weights up into a growing
    // oscillation that leaves the model's envelope within 10 s; with the adaptation paused while a demand is past
    // travel (robust.toml's `freeze_adaptation_when_saturated`), the flight stays in the envelope with alpha below
    // 20 deg. Over 120 random elevator hard-overs (12..112 s, either stop, 0.2..0.4 s) the same tuning departed 67
    // times without the pause and never with it (docs/src/guides/soak.md).
    let mut s = robust_with(vec![]);
    s.timing.duration_s = 133.3;
    s.faults = vec![Fault {
        limit: Some("min".into()),
        ..surface_fault(FaultAction::ActuatorHardOver, "elevator", 113.301, Some(0.232))
    }];
    s.validate().unwrap();
    assert!(s.controller.gains.freeze_adaptation_when_saturated, "robust.toml pauses its adaptation");
    let trace = sim::run(&s).unwrap();
    let alpha = column(&trace, "alpha_deg");
    assert_eq!(alpha.len(), 13_331);
    let peak = alpha.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    assert!(peak < 20.0, "alpha peaked at {peak} deg");

    s.controller.gains.freeze_adaptation_when_saturated = false;
    let departed = sim::run(&s).unwrap_err().to_string();
    assert!(departed.contains("left the model's envelope"), "{departed}");
}

#[test]
fn a_rate_frozen_surface_does_not_move() {
    let s = robust_with(vec![surface_fault(FaultAction::ActuatorRateFrozen, "aileron", 2.0, None)]);
    let trace = sim::run(&s).unwrap();
    let (aileron, command) = (column(&trace, "aileron_deg"), column(&trace, "aileron_cmd_deg"));
    assert!(aileron[200..].iter().all(|a| *a == aileron[200]), "the frozen aileron moved");
    assert!(command[200..].iter().any(|c| (c - aileron[200]).abs() > 0.5), "the commands should ask for motion");
    let mut runner = PlantRunner::new(&s).unwrap();
    for _ in 0..200 {
        runner.step(&runner.initial_command()).unwrap();
    }
    let c = runner.initial_command();
    let hits =
        runner.step(&ActuatorCommand { surfaces: SurfaceCommand { aileron_deg: 15.0, ..c.surfaces }, ..c }).unwrap();
    assert!(hits[0].rate && !hits[0].position, "a frozen rate is reported as the rate limit: {:?}", hits[0]);
    assert_eq!(runner.snapshot().surfaces_deg[0], c.surfaces.aileron_deg);
}

#[test]
fn a_sensor_bias_shifts_the_reported_roll_and_the_loop_holds_the_measured_roll() {
    let bias_rad = 0.1;
    let s = robust_with(vec![sensor_bias("phi_rad", bias_rad, 2.0, None)]);
    let trace = sim::run(&s).unwrap();
    let clean = sim::run(&robust_with(vec![])).unwrap();
    let (phi, phi_clean) = (column(&trace, "phi_deg"), column(&clean, "phi_deg"));
    assert!(bits(&trace)[..200] == bits(&clean)[..200]);
    // At the first tick of the fault the true states are still equal: the offset is the bias, 5.73 deg.
    assert!((phi[200] - phi_clean[200] - rad_to_deg(bias_rad)).abs() < 1e-9, "{} {}", phi[200], phi_clean[200]);
    assert!((rad_to_deg(bias_rad) - 5.7296).abs() < 1e-4);

    // By hand, as `sim::run` does it (the same rows, bit for bit): the controller drives the MEASURED roll to 0, so
    // the true roll settles near -5.73 deg. Averaged over the last 3 s, as the sinusoidal disturbance keeps it moving.
    let mut runner = PlantRunner::new(&s).unwrap();
    let model = F16Model::new(s.plant.xcg);
    let mut controller = sim::attitude_controller(&s, model.tables());
    let attitude = s.attitude_setpoints();
    let mut previous = runner.initial_command();
    let (mut measured_sum, mut true_sum, mut n) = (0.0, 0.0, 0.0);
    assert_eq!(phi.len() as u64, s.timing.ticks() + 1);
    for (k, &phi_k) in phi.iter().enumerate().take(phi.len() - 1) {
        let snap = runner.snapshot();
        assert_eq!(rad_to_deg(snap.state.phi_rad).to_bits(), phi_k.to_bits(), "tick {k}: the hand loop left sim::run");
        let truth = rad_to_deg(runner.true_state().phi_rad);
        if k >= 200 {
            assert!((phi_k - truth - rad_to_deg(bias_rad)).abs() < 1e-9, "tick {k}");
        }
        if k >= 700 {
            (measured_sum, true_sum, n) = (measured_sum + phi_k, true_sum + truth, n + 1.0);
        }
        let (surfaces, _) =
            controller.step(&measurement(&snap), &sim::setpoint_rad(&attitude, snap.t_s), s.timing.dt_s);
        let command = ActuatorCommand { surfaces, throttle: previous.throttle };
        runner.step(&previous).unwrap(); // robust.toml is next-tick
        previous = command;
    }
    let (measured, truth) = (measured_sum / n, true_sum / n);
    assert!(measured.abs() < 0.5, "measured roll over 7..10 s: {measured} deg");
    assert!((truth + 5.73).abs() < 0.5, "true roll over 7..10 s: {truth} deg");
}

#[test]
fn sensor_noise_is_bit_identical_for_a_seed_and_different_for_another() {
    let noisy = |seed: u64| {
        let mut s = robust_with(vec![sensor_noise("p_radps", 0.01, 1.0), sensor_noise("theta_rad", 0.002, 3.0)]);
        s.seed = seed;
        sim::run(&s).unwrap()
    };
    let (a, b, c) = (noisy(1), noisy(1), noisy(2));
    assert!(bits(&a) == bits(&b), "same seed, different traces");
    assert!(bits(&a)[..100] == bits(&c)[..100], "the noise acts only from its window");
    assert!(bits(&a)[100] != bits(&c)[100], "another seed should give other noise");
    let clean = sim::run(&robust_with(vec![])).unwrap();
    assert!(bits(&a)[..100] == bits(&clean)[..100]);
}

#[test]
fn sensor_noise_has_its_std_and_leaves_the_true_state_alone() {
    let s = robust_with(vec![sensor_noise("q_radps", 0.02, 0.0)]);
    let mut runner = PlantRunner::new(&s).unwrap();
    let mut errors = Vec::new();
    for _ in 0..1000 {
        let snap = runner.snapshot();
        // Reading twice within a tick gives the same sample: the noise is drawn once per tick.
        assert_eq!(runner.snapshot(), snap);
        let truth = runner.true_state();
        errors.push(snap.state.q_radps - truth.q_radps);
        assert_eq!(snap.state.p_radps, truth.p_radps, "only the faulted channel is touched");
        runner.step(&runner.initial_command()).unwrap();
    }
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let std = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n).sqrt();
    // 1000 samples: the standard error of the std is about 2 %, so 15 % is a wide margin for any seed.
    assert!(mean.abs() < 0.003 && (std - 0.02).abs() < 0.003, "mean {mean}, std {std}");

    // The integrated state is the one a run without the fault reaches: sensors never feed back by themselves.
    let mut clean = PlantRunner::new(&robust_with(vec![])).unwrap();
    for _ in 0..1000 {
        clean.step(&clean.initial_command()).unwrap();
    }
    assert_eq!(runner.true_state(), clean.true_state());
}

#[test]
fn faults_whose_window_ended_no_longer_act() {
    let s = robust_with(vec![
        surface_fault(FaultAction::ActuatorStuck, "elevator", 2.0, Some(0.5)),
        sensor_bias("theta_rad", 0.05, 2.0, Some(0.5)),
    ]);
    let mut runner = PlantRunner::new(&s).unwrap();
    let mut bias_seen = 0;
    for k in 0..400 {
        let snap = runner.snapshot();
        let offset = snap.state.theta_rad - runner.true_state().theta_rad;
        if (200..250).contains(&k) {
            assert!((offset - 0.05).abs() < 1e-12, "tick {k}: {offset}");
            bias_seen += 1;
        } else {
            assert_eq!(offset, 0.0, "tick {k}");
        }
        let before = snap.surfaces_deg[1];
        runner.step(&elevator_command(&runner, if k % 20 < 10 { 5.0 } else { -5.0 })).unwrap();
        let moved = runner.snapshot().surfaces_deg[1] != before;
        // Stuck over the steps from 2 s to 2.5 s; before and after, the square-wave command keeps it moving.
        assert_eq!(moved, !(200..250).contains(&k), "tick {k}: {before}");
    }
    assert_eq!(bias_seen, 50);
}

#[test]
fn bad_plans_are_refused_naming_the_entry() {
    let text = format!(
        "{}\n[[faults]]\nat_s = 1.0\ntarget = \"controller\"\naction = \"actuator-stuck\"\nsurface = \"elevator\"\n",
        config_text("robust")
    );
    let e = Scenario::from_toml(&text, "test").unwrap_err();
    assert!(matches!(&e, ScenarioError::Invalid { key, .. } if key == "faults[0].target"), "{e}");
    assert!(e.to_string().contains("faults[0].") && e.to_string().contains("target must be plant"), "{e}");

    // A plan built in code skips `Scenario::validate`; the runner still refuses a malformed plant fault.
    let mut s = robust_with(vec![]);
    s.faults =
        vec![Fault { limit: Some("up".into()), ..surface_fault(FaultAction::ActuatorHardOver, "rudder", 1.0, None) }];
    let e = PlantRunner::new(&s).unwrap_err();
    assert!(matches!(&e, SetupError::Fault { index: 0, key, .. } if key == "limit"), "{e}");
}
