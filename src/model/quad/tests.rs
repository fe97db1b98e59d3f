//! The quadrotor against closed-form answers: hover, free fall, terminal climb, descent and fall speeds, energy
//! lost to the air, resting and lifting off, touchdown, the moments' first response, torque-free rotation, the
//! accelerometer, the barometer.

use super::outputs::{OUTPUTS, isa_altitude_m, isa_pressure_pa, output_index, quad_outputs};
use super::params::{GRAVITY_MPS2, QuadParams};
use super::*;

const DT_S: f64 = 0.001;

fn fly(v: &mut QuadVehicle, seconds: f64) {
    for _ in 0..(seconds / DT_S).round() as usize {
        v.step(DT_S);
    }
}

fn output(v: &QuadVehicle, name: &str) -> f64 {
    quad_outputs(v)[output_index(name).unwrap()]
}

#[test]
fn hover_commands_hold_a_hover() {
    let mut v = QuadVehicle::hovering(QuadParams::default(), 10.0, 0.3).unwrap();
    fly(&mut v, 5.0);
    assert!((output(&v, "alt_m") - 10.0).abs() < 1e-9, "{}", output(&v, "alt_m"));
    assert!(output(&v, "phi_deg").abs() < 1e-9 && output(&v, "theta_deg").abs() < 1e-9);
    assert!((output(&v, "psi_deg") - 0.3f64.to_degrees()).abs() < 1e-9);
    // The accelerometer of a hovering vehicle reads one g upwards along body z.
    let f = v.specific_force_b_mps2();
    assert!(f.x.abs() < 1e-9 && f.y.abs() < 1e-9 && (f.z + GRAVITY_MPS2).abs() < 1e-9, "{f:?}");
}

#[test]
fn with_the_rotors_stopped_it_falls_as_a_stone() {
    let p = QuadParams::default();
    let p = QuadParams { body_drag_x_kgpm: 0.0, body_drag_y_kgpm: 0.0, body_drag_z_kgpm: 0.0, ..p };
    let mut v = QuadVehicle::hovering(p, 100.0, 0.0).unwrap();
    v.state = QuadState::at_rest([0.0, 0.0, -100.0], 0.0, 0.0);
    v.command([0.0; 4]);
    fly(&mut v, 2.0);
    // down = g t^2 / 2 (no rotor turns, so no rotor drag or inflow either, and the frame's drag is taken away);
    // RK4 is exact for this polynomial.
    assert!((output(&v, "alt_m") - (100.0 - 0.5 * GRAVITY_MPS2 * 4.0)).abs() < 1e-9);
    assert!((output(&v, "vd_mps") - 2.0 * GRAVITY_MPS2).abs() < 1e-9);
    assert!(v.specific_force_b_mps2().norm() < 1e-12, "free fall reads zero");
}

/// The steady vertical speed (up positive) of a level vehicle with every rotor at `omega`: the rotors' thrust less
/// the inflow's share, the frame's drag and the weight in balance, 4 (k_T w^2 - k_z w v) - m g - c_z |v| v = 0, a
/// quadratic in v on each side of 0.
fn terminal_speed_up_mps(p: &QuadParams, omega: f64) -> f64 {
    let excess_n = 4.0 * p.thrust_coeff_npradps2 * omega * omega - p.mass_kg * GRAVITY_MPS2;
    let (b, c) = (4.0 * p.rotor_inflow_coeff * omega, p.body_drag_z_kgpm);
    let sign = excess_n.signum();
    sign * (-b + (b * b + 4.0 * c * excess_n.abs()).sqrt()) / (2.0 * c)
}

/// Flies a level vehicle from a hover at 1000 m with every motor held at `command` for `seconds`; its climb rate,
/// m/s.
fn steady_climb_mps(p: QuadParams, command: f64, seconds: f64) -> f64 {
    let mut v = QuadVehicle::hovering(p, 1000.0, 0.0).unwrap();
    v.command([command; 4]);
    fly(&mut v, seconds);
    assert!(output(&v, "phi_deg").abs() < 1e-9 && output(&v, "theta_deg").abs() < 1e-9, "it stays level");
    -output(&v, "vd_mps")
}

#[test]
fn at_a_fixed_throttle_it_climbs_and_descends_at_the_closed_form_terminal_speed() {
    let p = QuadParams::default();
    // 0.6 of full speed: 502.8 rad/s, 1.977 N more thrust than the weight; terminal climb 3.908 m/s.
    let (climb, want) = (steady_climb_mps(p, 0.6, 30.0), terminal_speed_up_mps(&p, 0.6 * p.max_rotor_speed_radps));
    assert!((want - 3.908).abs() < 1e-3, "{want}");
    assert!((climb - want).abs() < 1e-6, "{climb} against {want}");
    // Full throttle: 18.09 m/s, where RotorS's model alone would accelerate at 2.6 g for ever.
    let full = terminal_speed_up_mps(&p, p.max_rotor_speed_radps);
    assert!((full - 18.093).abs() < 1e-3, "{full}");
    assert!((steady_climb_mps(p, 1.0, 30.0) - full).abs() < 1e-6);
    // 0.45: 1.806 N short of the weight; it sinks at 4.57 m/s.
    let (sink, want) = (steady_climb_mps(p, 0.45, 30.0), terminal_speed_up_mps(&p, 0.45 * p.max_rotor_speed_radps));
    assert!((want + 4.565).abs() < 1e-3, "{want}");
    assert!((sink - want).abs() < 1e-6, "{sink} against {want}");
    // Each part alone bounds the climb too: the inflow alone (linear), the frame alone (quadratic).
    let inflow_only = QuadParams { body_drag_z_kgpm: 0.0, ..p };
    let excess_n = 4.0 * p.thrust_coeff_npradps2 * (0.6f64 * 838.0).powi(2) - p.mass_kg * GRAVITY_MPS2;
    let linear = excess_n / (4.0 * p.rotor_inflow_coeff * 0.6 * 838.0);
    assert!((steady_climb_mps(inflow_only, 0.6, 30.0) - linear).abs() < 1e-6, "{linear}");
    let frame_only = QuadParams { rotor_inflow_coeff: 0.0, ..p };
    let quadratic = (excess_n / p.body_drag_z_kgpm).sqrt();
    // Quadratic drag alone nears its terminal speed as e^(-2 a t / v): a minute to come within 1e-6.
    let got = steady_climb_mps(frame_only, 0.6, 60.0);
    assert!((got - quadratic).abs() < 1e-6, "{got} against {quadratic}");
}

#[test]
fn thrown_with_the_rotors_stopped_it_only_loses_energy() {
    let p = QuadParams::default();
    let mut v = QuadVehicle::hovering(p, 2000.0, 0.0).unwrap();
    v.state = QuadState::at_rest([0.0, 0.0, -2000.0], 0.0, 0.0);
    // Thrown up, forwards and sideways, turning.
    v.state.x[3..6].copy_from_slice(&[6.0, -3.0, -15.0]);
    v.state.x[10..13].copy_from_slice(&[0.3, -0.2, 0.5]);
    v.command([0.0; 4]);
    let energy_j = |v: &QuadVehicle| {
        let speed2 = v.state.velocity_ned_mps().iter().map(|c| c * c).sum::<f64>();
        let w = Vector3::from(v.state.rates_radps());
        let spin = p.ixx_kgm2 * w.x * w.x + p.iyy_kgm2 * w.y * w.y + p.izz_kgm2 * w.z * w.z;
        0.5 * p.mass_kg * speed2 + 0.5 * spin + p.mass_kg * GRAVITY_MPS2 * output(v, "alt_m")
    };
    let mut last = energy_j(&v);
    for _ in 0..40_000 {
        v.step(DT_S);
        let now = energy_j(&v);
        assert!(now <= last + 1e-9, "energy rose from {last} to {now} J at alt {}", output(&v, "alt_m"));
        last = now;
    }
    // Tumbling, it falls no faster than along its least draggy axes: sqrt(m g / c_Dx) = 36.52 m/s.
    let speed = v.state.velocity_ned_mps().iter().map(|c| c * c).sum::<f64>().sqrt();
    assert!(speed < (p.mass_kg * GRAVITY_MPS2 / p.body_drag_x_kgpm).sqrt(), "{speed}");
}

#[test]
fn dropped_level_it_falls_at_the_frames_terminal_speed() {
    let p = QuadParams::default();
    let mut v = QuadVehicle::hovering(p, 2000.0, 0.0).unwrap();
    v.state = QuadState::at_rest([0.0, 0.0, -2000.0], 0.0, 0.0);
    v.command([0.0; 4]);
    fly(&mut v, 40.0);
    // Along its axis with the rotors stopped: sqrt(m g / c_Dz) = 25.82 m/s.
    let terminal = (p.mass_kg * GRAVITY_MPS2 / p.body_drag_z_kgpm).sqrt();
    assert!((terminal - 25.823).abs() < 1e-3, "{terminal}");
    assert!((output(&v, "vd_mps") - terminal).abs() < 1e-6, "{}", output(&v, "vd_mps"));
}

#[test]
fn on_the_ground_it_rests_until_the_rotors_lift_it() {
    // Without the air's share (inflow, frame drag), so the lift-off's acceleration has its closed form.
    let p = QuadParams { rotor_inflow_coeff: 0.0, body_drag_z_kgpm: 0.0, ..QuadParams::default() };
    let mut v = QuadVehicle::on_ground(p, 0.0).unwrap();
    v.command([0.99 * p.hover_command(); 4]);
    fly(&mut v, 2.0);
    assert!(v.on_ground && output(&v, "alt_m") == 0.0 && output(&v, "vd_mps") == 0.0);
    let f = v.specific_force_b_mps2();
    assert!((f.z + GRAVITY_MPS2).abs() < 1e-12, "resting reads one g: {f:?}");
    assert_eq!(output(&v, "on_ground"), 1.0);
    v.command([1.01 * p.hover_command(); 4]);
    fly(&mut v, 2.0);
    assert!(!v.on_ground && output(&v, "alt_m") > 0.05, "{}", output(&v, "alt_m"));
    // 2 % more speed is 4 % more thrust: about 0.04 g upwards once the rotors have spun up.
    let a = -v.acceleration_ned_mps2().z / GRAVITY_MPS2;
    assert!((a - (1.01f64.powi(2) - 1.0)).abs() < 2e-3, "{a}");
}

#[test]
fn it_lands_and_never_falls_through_the_ground() {
    // Without the frame's drag, so the touchdown speed has its closed form.
    let p = QuadParams { body_drag_x_kgpm: 0.0, body_drag_y_kgpm: 0.0, body_drag_z_kgpm: 0.0, ..QuadParams::default() };
    let mut v = QuadVehicle::hovering(p, 1.0, 0.7).unwrap();
    v.state = QuadState::at_rest([3.0, 4.0, -1.0], 0.7, 0.0);
    v.state.x[10] = 0.5; // rolling as it falls
    v.command([0.0; 4]);
    let mut lowest: f64 = 1.0;
    for _ in 0..2000 {
        v.step(DT_S);
        lowest = lowest.min(output(&v, "alt_m"));
    }
    assert_eq!(lowest, 0.0);
    assert!(v.on_ground);
    // Touchdown at sqrt(2 g h) within one step's fall.
    assert!((v.touchdown_speed_mps - (2.0 * GRAVITY_MPS2).sqrt()).abs() < 0.02, "{}", v.touchdown_speed_mps);
    assert_eq!(v.state.position_ned_m(), [3.0, 4.0, 0.0]);
    assert!(output(&v, "phi_deg").abs() < 1e-9 && (output(&v, "psi_deg") - 0.7f64.to_degrees()).abs() < 1e-9);
}

#[test]
fn moments_accelerate_the_body_as_euler_says() {
    let p = QuadParams::default();
    let h = p.hover_rotor_speed_radps();
    let mut v = QuadVehicle::hovering(p, 10.0, 0.0).unwrap();
    // Left rotors (3, 4) faster: a roll-right moment 2 (T+ - T) d over Ixx.
    let fast = h + 20.0;
    v.state.x[13 + 2] = fast;
    v.state.x[13 + 3] = fast;
    let (dx, _) = derivative(&p, &v.state.x, &v.motor_commands, false);
    let d = p.arm_m / std::f64::consts::SQRT_2;
    let dt = p.thrust_coeff_npradps2 * (fast * fast - h * h);
    assert!((dx[10] - 2.0 * dt * d / p.ixx_kgm2).abs() < 1e-9, "{}", dx[10]);
    assert!(dx[11].abs() < 1e-12 && dx[12].abs() < 1e-12);
    // The counter-clockwise rotors (2, 3) faster: yaw right at k_Q (T+ - T) 2 / Izz.
    let mut v = QuadVehicle::hovering(p, 10.0, 0.0).unwrap();
    v.state.x[13 + 1] = fast;
    v.state.x[13 + 2] = fast;
    let (dx, _) = derivative(&p, &v.state.x, &v.motor_commands, false);
    assert!((dx[12] - 2.0 * p.torque_per_thrust_m * dt / p.izz_kgm2).abs() < 1e-9, "{}", dx[12]);
}

#[test]
fn a_spinning_body_keeps_its_energy_and_momentum() {
    let p = QuadParams::default();
    let mut v = QuadVehicle::hovering(p, 50.0, 0.0).unwrap();
    v.state = QuadState::at_rest([0.0, 0.0, -50.0], 0.0, 0.0);
    v.state.x[10..13].copy_from_slice(&[1.0, 0.1, 2.0]);
    v.command([0.0; 4]);
    let energy = |v: &QuadVehicle| {
        let w = Vector3::from(v.state.rates_radps());
        0.5 * (p.ixx_kgm2 * w.x * w.x + p.iyy_kgm2 * w.y * w.y + p.izz_kgm2 * w.z * w.z)
    };
    let momentum_ned = |v: &QuadVehicle| {
        let w = Vector3::from(v.state.rates_radps());
        v.state.attitude().transform_vector(&w.component_mul(&Vector3::new(p.ixx_kgm2, p.iyy_kgm2, p.izz_kgm2)))
    };
    let (e0, h0) = (energy(&v), momentum_ned(&v));
    fly(&mut v, 1.0);
    assert!((energy(&v) - e0).abs() < 1e-9 * e0, "{} against {e0}", energy(&v));
    assert!((momentum_ned(&v) - h0).norm() < 1e-9, "{:?} against {h0:?}", momentum_ned(&v));
    assert!((v.state.attitude().into_inner().norm() - 1.0).abs() < 1e-12);
}

#[test]
fn the_barometer_reads_the_isa() {
    // ICAO standard atmosphere: 101325 Pa at sea level, 89874.6 Pa at 1000 m, 79495.2 Pa at 2000 m.
    assert!((isa_pressure_pa(0.0) - 101_325.0).abs() < 1e-9);
    assert!((isa_pressure_pa(1000.0) - 89_874.6).abs() < 0.5, "{}", isa_pressure_pa(1000.0));
    assert!((isa_pressure_pa(2000.0) - 79_495.2).abs() < 0.5, "{}", isa_pressure_pa(2000.0));
    assert!((isa_altitude_m(isa_pressure_pa(1234.5)) - 1234.5).abs() < 1e-6);
    let p = QuadParams { ground_altitude_m: 500.0, ..QuadParams::default() };
    let v = QuadVehicle::hovering(p, 20.0, 0.0).unwrap();
    assert!((output(&v, "baro_alt_m") - 520.0).abs() < 1e-6);
    assert!((output(&v, "pressure_pa") - isa_pressure_pa(520.0)).abs() < 1e-9);
}

#[test]
fn outputs_are_named_once_with_units() {
    let mut names: Vec<_> = OUTPUTS.iter().map(|(n, _)| *n).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), OUTPUTS.len());
    assert!(OUTPUTS.iter().all(|(_, unit)| !unit.is_empty()));
    let v = QuadVehicle::hovering(QuadParams::default(), 5.0, 0.0).unwrap();
    assert!(quad_outputs(&v).iter().all(|x| x.is_finite()));
    assert_eq!(output(&v, "qw"), 1.0);
}
