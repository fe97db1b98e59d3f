//! The quadrotor against closed-form answers: hover, free fall, resting and lifting off, touchdown, the moments'
//! first response, torque-free rotation, the accelerometer, the barometer.

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
    let mut v = QuadVehicle::hovering(p, 100.0, 0.0).unwrap();
    v.state = QuadState::at_rest([0.0, 0.0, -100.0], 0.0, 0.0);
    v.command([0.0; 4]);
    fly(&mut v, 2.0);
    // down = g t^2 / 2 (no rotor turns, so no rotor drag either); RK4 is exact for this polynomial.
    assert!((output(&v, "alt_m") - (100.0 - 0.5 * GRAVITY_MPS2 * 4.0)).abs() < 1e-9);
    assert!((output(&v, "vd_mps") - 2.0 * GRAVITY_MPS2).abs() < 1e-9);
    assert!(v.specific_force_b_mps2().norm() < 1e-12, "free fall reads zero");
}

#[test]
fn on_the_ground_it_rests_until_the_rotors_lift_it() {
    let p = QuadParams::default();
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
    let mut v = QuadVehicle::hovering(QuadParams::default(), 1.0, 0.7).unwrap();
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
