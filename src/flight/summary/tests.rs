use super::*;
use crate::signals::{InputSignal, OutputSignal};

/// A plant that is not the F-16: a rover with a position in m, a heading in deg, a speed, and two inputs, the
/// steering reporting its position (`steer_deg`), the throttle (a ratio) not.
fn rover() -> PlantSignals {
    let output = |name: &str, unit: &str| OutputSignal { name: name.into(), unit: unit.into(), in_trace: true };
    let input = |name: &str, unit: &str, min: f64, max: f64, held_output: Option<usize>| InputSignal {
        name: name.into(),
        unit: unit.into(),
        min,
        max,
        hold: 0.0,
        held_output,
        command_in_trace: true,
    };
    PlantSignals {
        plant: "rover".into(),
        outputs: vec![
            output("x_m", "m"),
            output("heading_deg", "deg"),
            output("v_mps", "m/s"),
            output("steer_deg", "deg"),
        ],
        inputs: vec![input("steer", "deg", -30.0, 30.0, Some(3)), input("throttle", "1", 0.0, 1.0, None)],
    }
}

fn scenario(extra: &str) -> Scenario {
    let text = format!(
        "name = \"rover\"\n[timing]\ndt_s = 0.01\nduration_s = 2.0\ncommand_timing = \"next-tick\"\n{extra}\n\
         [setpoint]\nx_m = 10.0\nheading_deg = 0.0\n\
         [actuators.steer]\nmin = -20.0\nmax = 20.0\nrate_limit_per_s = 50.0\n\
         [actuators.throttle]\nmin = 0.0\nmax = 1.0\nrate_limit_per_s = 0.5\n"
    );
    Scenario::from_toml(&text, "test").unwrap()
}

/// 2 s of the rover at 0.01 s: x steps from 0 towards 10 (settling within 2 % at 1.31 s), the heading strays from
/// its held 0 by up to 0.8 deg and comes back (within 0.5 deg from 0.79 s on); the steering is commanded to 30 deg
/// at 0.51 s and moves at its 50 deg/s to its stop at 20 deg (rows 51..=90 at the rate limit, 90..=200 on the
/// stop); the throttle is commanded from 0.4 to 1.2 at row 100 (one step beyond its rate, 101 rows beyond its stop).
fn flown() -> Trace {
    let mut trace = Trace::new(rover().trace_columns(&[]));
    assert_eq!(
        trace.columns,
        ["t_s", "x_m", "heading_deg", "v_mps", "steer_cmd_deg", "throttle_cmd", "steer_deg", "flight_segment"]
    );
    for k in 0..=200 {
        let t = k as f64 * 0.01;
        let x = 10.0 * (1.0 - (-3.0 * t).exp());
        let heading = if t <= 1.0 { 0.8 * (std::f64::consts::PI * t).sin() } else { 0.0 };
        let steer_cmd = if k > 50 { 30.0 } else { 0.0 };
        let steer = if k > 50 { (0.5 * (k - 50) as f64).min(20.0) } else { 0.0 };
        let throttle_cmd = if k >= 100 { 1.2 } else { 0.4 };
        trace.rows.push(vec![t, x, heading, 1.0, steer_cmd, throttle_cmd, steer, 0.0]);
    }
    trace
}

#[test]
fn a_plant_of_your_own_gets_rows_for_its_own_signals_only() {
    let plant = rover();
    let s = summarize(&flown(), &scenario(""), Some(&plant));
    assert_eq!(s.plant, "rover");
    // The attitude's set points (0 when not given) are not this plant's: no rows for them, no NaN rows.
    let names: Vec<&str> = s.setpoints.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["heading_deg", "x_m"], "the attitude first, then the others in name order");
    assert!(s.alpha.is_none() && s.body_rate_max_late_dps.is_none() && s.flight_path.is_none());
    assert!(s.channels.is_empty());
    let text = s.to_text();
    let json = serde_json::to_string(&s).unwrap();
    for absent in ["NaN", "phi", "theta", "psi", "alpha", "aileron", "elevator", "rudder", "surface"] {
        assert!(!text.contains(absent), "{absent} in\n{text}");
        assert!(!json.contains(absent), "{absent} in {json}");
    }
    assert!(!json.contains("null"), "{json}");
    assert_eq!(serde_json::from_str::<Summary>(&json).unwrap(), s, "summary.json reads back");
}

#[test]
fn a_stepped_set_point_is_judged_by_its_settling_and_a_held_one_by_its_largest_error() {
    let s = summarize(&flown(), &scenario(""), Some(&rover()));
    let (heading, x) = (&s.setpoints[0], &s.setpoints[1]);
    assert_eq!((x.unit.as_str(), x.setpoint, x.initial), ("m", 10.0, 0.0));
    let Response::Stepped { settle_within_2pct_s: Some(settled), overshoot } = x.response else { panic!("{x:?}") };
    assert!((settled - 1.31).abs() < 1e-9 && overshoot == 0.0, "{x:?}");
    assert_eq!(x.max_error, 10.0);
    assert!(x.settle_within_0p5deg.is_none(), "x is not in deg");
    assert_eq!(heading.response, Response::Held);
    assert!((heading.max_error - 0.8).abs() < 1e-12, "{heading:?}");
    let at = heading.settle_within_0p5deg.as_ref().unwrap().at_s.unwrap();
    assert!((at - 0.79).abs() < 1e-9, "{heading:?}");
    let text = s.to_text();
    assert!(text.contains("step: settle(2%) 1.31 s, overshoot 0.000"), "{text}");
    assert!(text.contains("held: largest error 0.800"), "{text}");
    assert!(!text.contains("never"), "a held set point is not a step that never settled:\n{text}");
}

#[test]
fn a_set_point_that_steps_is_described_by_its_last_step_and_its_error_against_the_value_in_force() {
    // x_m's set point steps from 10 to 12 at 1.5 s; the rover (x towards 10) never gets there.
    let s = summarize(&flown(), &scenario("[[setpoint_steps]]\nat_s = 1.5\nx_m = 12.0"), Some(&rover()));
    let x = &s.setpoints[1];
    let at_step = 10.0 * (1.0 - (-3.0 * 150.0 * 0.01_f64).exp());
    assert_eq!((x.name.as_str(), x.setpoint, x.initial), ("x_m", 12.0, at_step));
    assert_eq!(x.response, Response::Stepped { settle_within_2pct_s: None, overshoot: 0.0 });
    // 10 m at t = 0 against 10; after the step about 2.1 m against 12.
    assert_eq!(x.max_error, 10.0);
    let late = 12.0 - 10.0 * (1.0 - (-3.0 * 2.0_f64).exp());
    assert!((x.final_value - (12.0 - late)).abs() < 1e-12, "{x:?}");
}

#[test]
fn every_input_under_its_actuator_gets_rate_and_position_limit_fractions_and_saturated_time() {
    let s = summarize(&flown(), &scenario(""), Some(&rover()));
    assert_eq!(s.actuators.len(), 2);
    let steer = &s.actuators[0];
    assert_eq!((steer.name.as_str(), steer.unit.as_str()), ("steer", "deg"));
    assert_eq!((steer.position.as_deref(), steer.command.as_str()), (Some("steer_deg"), "steer_cmd_deg"));
    assert_eq!((steer.ticks_at_rate_limit, steer.ticks_at_position_limit), (40, 111));
    assert_eq!(steer.rate_limit_fraction, 40.0 / 201.0);
    assert_eq!(steer.position_limit_fraction, 111.0 / 201.0);
    assert!((steer.saturated_s - 1.5).abs() < 1e-12, "rows 51..=200: {steer:?}");
    assert_eq!(steer.peak, 20.0);
    // On the stop for the whole late window (the last 0.6 s): no motion to speak of.
    assert_eq!(steer.rms_rate_late_per_s, Some(0.0));
    assert!(steer.rms_rate_per_s.unwrap() > 0.0);
    // The throttle reports no position: its figures are its command's against the actuator.
    let throttle = &s.actuators[1];
    assert_eq!((throttle.position.as_deref(), throttle.command.as_str()), (None, "throttle_cmd"));
    assert_eq!((throttle.ticks_at_rate_limit, throttle.ticks_at_position_limit), (1, 101));
    assert!((throttle.saturated_s - 1.01).abs() < 1e-12, "{throttle:?}");
    assert_eq!((throttle.rms_rate_per_s, throttle.rms_rate_late_per_s), (None, None));
    assert!((throttle.rms_command_rate_per_s.unwrap() - 80.0 / 200f64.sqrt()).abs() < 1e-9, "{throttle:?}");
    let text = s.to_text();
    assert!(text.contains("\n  throttle: the plant reports no position; the figures are the commands'"), "{text}");
    assert!(text.contains("19.9 %") && text.contains("55.2 %") && text.contains("1.50 s"), "{text}");
    // An input the scenario puts under no actuator gets no row.
    let mut bare = scenario("");
    bare.actuators.remove("throttle");
    assert_eq!(summarize(&flown(), &bare, Some(&rover())).actuators.len(), 1);
}

#[test]
fn the_late_window_is_the_scenarios_key() {
    let plant = rover();
    let default = summarize(&flown(), &scenario(""), Some(&plant));
    assert_eq!(default.late_window_s, 0.6, "0.3 of the 2 s run");
    assert!(default.to_text().contains("limit cycle (last 0.6 s): none"), "{}", default.to_text());
    // Over the whole run the steering's motion is in the window.
    let whole = summarize(&flown(), &scenario("late_window_s = 2.0"), Some(&plant));
    assert_eq!(whole.late_window_s, 2.0);
    assert_eq!(whole.actuators[0].rms_rate_late_per_s, whole.actuators[0].rms_rate_per_s);
    assert!(whole.to_text().contains("limit cycle (last 2 s): none"));
}

#[test]
fn a_sustained_swing_of_any_output_is_a_limit_cycle_against_its_own_scale() {
    let mut trace = flown();
    // x swings +-0.5 m (5 % of its largest error, 10 m) at 5 Hz in the late window.
    for row in trace.rows.iter_mut().filter(|r| r[0] >= 1.4) {
        row[1] += 0.5 * (std::f64::consts::TAU * 5.0 * row[0]).sin();
    }
    let s = summarize(&trace, &scenario(""), Some(&rover()));
    let x = s.oscillations.iter().find(|o| o.signal == "x_m").unwrap();
    assert!(x.sustained && (x.threshold - 0.1).abs() < 1e-9, "{x:?}");
    assert!(s.limit_cycle && s.to_text().contains("limit cycle (last 0.6 s): YES: x_m +-0.5"), "{}", s.to_text());
}

#[test]
fn case_figures_name_the_plants_signals_with_their_units_once() {
    let plant = rover();
    let s = summarize(&flown(), &scenario(""), Some(&plant));
    let figures = s.case_figures();
    let names: Vec<&str> = figures.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "heading_settle_s",
            "x_settle_s",
            "heading_final_error_deg",
            "x_final_error_m",
            "heading_max_error_deg",
            "x_max_error_m",
            "rate_limit_fraction",
            "position_limit_fraction"
        ]
    );
    assert_eq!(case_columns(&scenario(""), Some(&plant)), names, "the header a sweep writes before any case flies");
    assert_eq!(figures[6].1, Some(40.0 / 201.0));
    assert_eq!(figures[7].1, Some(111.0 / 201.0));
    // The built-in F-16: its attitude, alpha, body rates and surfaces, as a sweep's cases.csv has always named them.
    let f16 = case_columns(&Scenario::embedded_default(), None);
    assert_eq!(&f16[..3], ["phi_settle_s", "theta_settle_s", "psi_settle_s"]);
    assert_eq!(&f16[3..6], ["phi_final_error_deg", "theta_final_error_deg", "psi_final_error_deg"]);
    assert_eq!(
        &f16[9..],
        [
            "alpha_peak_deg",
            "p_max_late_dps",
            "q_max_late_dps",
            "r_max_late_dps",
            "rate_limit_fraction",
            "position_limit_fraction"
        ]
    );
}

#[test]
fn the_f16_keeps_its_surfaces_under_the_books_actuators() {
    let scenario = Scenario::embedded_default();
    let (trace, _) = crate::sim::fly(&scenario).unwrap();
    let s = summarize(&trace, &scenario, None);
    let names: Vec<(&str, Option<&str>)> =
        s.actuators.iter().map(|a| (a.name.as_str(), a.position.as_deref())).collect();
    assert_eq!(
        names,
        [("aileron", Some("aileron_deg")), ("elevator", Some("elevator_deg")), ("rudder", Some("rudder_deg"))]
    );
    let angles: Vec<&str> = s.setpoints.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(angles, ["phi_deg", "theta_deg", "psi_deg"]);
    assert!(s.alpha.is_some() && s.body_rate_max_late_dps.is_some() && s.flight_path.is_some());
    assert_eq!(s.channels.len(), 3);
    assert!(s.channels.iter().all(|c| c.rms_f_error_radps2.is_some()));
    // The F-16's limit-cycle detector still searches the last 3 s of a 10 s flight.
    assert_eq!(s.late_window_s, 3.0);
    assert!(s.to_text().contains("limit cycle (last 3 s)"));
}
