//! The four rotors of an X quadrotor: where they sit, which way they spin, how fast they follow their commands, and
//! the force and moments they put on the body: thrust less what the air flowing through the discs takes off it
//! (axial inflow), reaction torque, and rotor drag in the discs' plane.
//!
//! Motor order and spin are Betaflight's Quad X (its `mixerQuadX`, "props in"): 1 rear right (clockwise seen from
//! above), 2 front right (counter-clockwise), 3 rear left (counter-clockwise), 4 front left (clockwise), so a
//! flight controller's motor outputs map one to one. Body axes FRD: x forward, y right, z down.

use super::params::QuadParams;

/// Number of rotors.
pub const ROTORS: usize = 4;

/// Where each rotor sits, as (x forward, y right) in units of arm / sqrt(2), in motor order.
pub const ROTOR_POSITION: [[f64; 2]; ROTORS] = [[-1.0, 1.0], [1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]];

/// Yaw moment of each rotor per unit of its reaction torque, in motor order: +1 for the counter-clockwise rotors
/// (seen from above), whose drag turns the body clockwise, nose right, positive about z down.
pub const ROTOR_YAW_SIGN: [f64; ROTORS] = [-1.0, 1.0, 1.0, -1.0];

/// Total force and moments of the rotors on the body, body axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RotorWrench {
    /// Force along body x, y, z, N (thrust along -z, less the axial inflow's share; rotor drag in the x-y plane).
    pub force_b_n: [f64; 3],
    /// Moments about body x, y, z (roll, pitch, yaw), N m.
    pub moment_b_nm: [f64; 3],
}

/// Thrust of one rotor at a speed, N.
#[inline]
pub fn rotor_thrust_n(p: &QuadParams, speed_radps: f64) -> f64 {
    p.thrust_coeff_npradps2 * speed_radps * speed_radps
}

/// Rotor speed a motor command asks for: the command clamped to 0..1 (a NaN is 0), times the top speed, rad/s.
#[inline]
pub fn commanded_speed_radps(p: &QuadParams, command: f64) -> f64 {
    let command = if command.is_nan() { 0.0 } else { command.clamp(0.0, 1.0) };
    command * p.max_rotor_speed_radps
}

/// Rate of change of a rotor's speed: first order towards the commanded speed, faster up than down (RotorS's two
/// time constants), rad/s^2.
#[inline]
pub fn rotor_acceleration_radps2(p: &QuadParams, speed_radps: f64, commanded_radps: f64) -> f64 {
    let tau_s = if commanded_radps > speed_radps { p.motor_tau_up_s } else { p.motor_tau_down_s };
    (commanded_radps - speed_radps) / tau_s
}

/// The rotors' force and moments at these speeds, with the body moving at `velocity_b_mps` and turning at
/// `rates_b_radps` (body axes) through still air.
pub fn rotor_wrench(
    p: &QuadParams,
    speeds_radps: &[f64; ROTORS],
    velocity_b_mps: &[f64; 3],
    rates_b_radps: &[f64; 3],
) -> RotorWrench {
    let d = p.arm_m / std::f64::consts::SQRT_2;
    let [rate_p, rate_q, _] = *rates_b_radps;
    let mut w = RotorWrench::default();
    let mut speed_sum = 0.0;
    for i in 0..ROTORS {
        let [x, y] = ROTOR_POSITION[i].map(|c| c * d);
        // Air through the disc along the axis, upwards (the disc climbing into it): the body's velocity at the
        // rotor's hub, v + omega x r, along -z; a rolling or pitching body meets it at the rising rotors, which is
        // the inflow's damping of those rates.
        let climb_mps = -(velocity_b_mps[2] + rate_p * y - rate_q * x);
        let thrust = rotor_thrust_n(p, speeds_radps[i]) - p.rotor_inflow_coeff * speeds_radps[i].abs() * climb_mps;
        // r x F for F = (0, 0, -T) at r = (x, y, 0): (-y T, x T, 0).
        w.force_b_n[2] -= thrust;
        w.moment_b_nm[0] -= y * thrust;
        w.moment_b_nm[1] += x * thrust;
        // The reaction torque stays that of the static thrust (RotorPy's yaw moment is k_m omega^2 alone).
        w.moment_b_nm[2] += ROTOR_YAW_SIGN[i] * p.torque_per_thrust_m * rotor_thrust_n(p, speeds_radps[i]);
        speed_sum += speeds_radps[i].abs();
    }
    // Rotor drag (RotorS): each disc opposes the velocity in its plane in proportion to its speed; applied at the
    // centre of mass (the moment of its small offset above it is left out).
    w.force_b_n[0] -= p.rotor_drag_coeff * speed_sum * velocity_b_mps[0];
    w.force_b_n[1] -= p.rotor_drag_coeff * speed_sum * velocity_b_mps[1];
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn speeds(base: f64, delta: [f64; ROTORS]) -> [f64; ROTORS] {
        std::array::from_fn(|i| base + delta[i])
    }

    #[test]
    fn equal_rotors_push_straight_up_with_no_moment() {
        let p = QuadParams::default();
        let w = rotor_wrench(&p, &[p.hover_rotor_speed_radps(); 4], &[0.0; 3], &[0.0; 3]);
        assert!((w.force_b_n[2] + p.mass_kg * super::super::params::GRAVITY_MPS2).abs() < 1e-9);
        assert!(w.moment_b_nm.iter().all(|m| m.abs() < 1e-12), "{:?}", w.moment_b_nm);
    }

    #[test]
    fn the_mixer_signs_are_betaflights() {
        let p = QuadParams::default();
        let h = p.hover_rotor_speed_radps();
        // Betaflight's mixerQuadX: roll right = left motors (3, 4) up; pitch up = front motors (2, 4) up;
        // yaw right = the counter-clockwise motors (2, 3) up.
        let roll = rotor_wrench(&p, &speeds(h, [0.0, 0.0, 10.0, 10.0]), &[0.0; 3], &[0.0; 3]).moment_b_nm;
        assert!(roll[0] > 0.0 && roll[1].abs() < 1e-12 && roll[2].abs() < 1e-12, "{roll:?}");
        let pitch = rotor_wrench(&p, &speeds(h, [0.0, 10.0, 0.0, 10.0]), &[0.0; 3], &[0.0; 3]).moment_b_nm;
        assert!(pitch[1] > 0.0 && pitch[0].abs() < 1e-12 && pitch[2].abs() < 1e-12, "{pitch:?}");
        let yaw = rotor_wrench(&p, &speeds(h, [0.0, 10.0, 10.0, 0.0]), &[0.0; 3], &[0.0; 3]).moment_b_nm;
        assert!(yaw[2] > 0.0 && yaw[0].abs() < 1e-12 && yaw[1].abs() < 1e-12, "{yaw:?}");
    }

    #[test]
    fn roll_moment_is_thrust_difference_times_lever() {
        let p = QuadParams::default();
        let w = rotor_wrench(&p, &[0.0, 0.0, 400.0, 400.0], &[0.0; 3], &[0.0; 3]);
        let lever = p.arm_m / std::f64::consts::SQRT_2;
        assert!((w.moment_b_nm[0] - 2.0 * rotor_thrust_n(&p, 400.0) * lever).abs() < 1e-12);
        assert!((w.moment_b_nm[2]).abs() < 1e-12, "rotors 3 and 4 spin opposite ways");
    }

    #[test]
    fn rotor_drag_opposes_motion_in_the_disc_plane_only() {
        let p = QuadParams::default();
        let w = rotor_wrench(&p, &[400.0; 4], &[2.0, -1.0, 0.0], &[0.0; 3]);
        assert!((w.force_b_n[0] + p.rotor_drag_coeff * 1600.0 * 2.0).abs() < 1e-12);
        assert!((w.force_b_n[1] - p.rotor_drag_coeff * 1600.0).abs() < 1e-12);
        assert!((w.force_b_n[2] + 4.0 * rotor_thrust_n(&p, 400.0)).abs() < 1e-12, "no force along the axis");
    }

    #[test]
    fn thrust_falls_as_the_air_climbs_through_the_discs_and_rises_as_it_descends() {
        let p = QuadParams::default();
        let h = p.hover_rotor_speed_radps();
        let lift = |w_mps: f64| -rotor_wrench(&p, &[h; 4], &[0.0, 0.0, w_mps], &[0.0; 3]).force_b_n[2];
        let weight_n = p.mass_kg * super::super::params::GRAVITY_MPS2;
        assert!((lift(0.0) - weight_n).abs() < 1e-12, "hover thrust unchanged at rest");
        // Climbing at 2 m/s (body z down, so w = -2): 4 k_z omega v = 4 * 2.32e-4 * 441.61 * 2 = 0.8196 N less.
        assert!((weight_n - lift(-2.0) - 4.0 * 2.32e-4 * h * 2.0).abs() < 1e-12, "{}", lift(-2.0));
        assert!((weight_n - lift(-2.0) - 0.8196).abs() < 1e-4, "{}", lift(-2.0));
        assert!((lift(2.0) - weight_n - (weight_n - lift(-2.0))).abs() < 1e-12, "descending adds as much");
        // Thrust falls to nothing at the climb speed k_T omega / k_z: 16.27 m/s at the hover speed.
        let zero_mps = p.thrust_coeff_npradps2 * h / p.rotor_inflow_coeff;
        assert!((zero_mps - 16.27).abs() < 0.01, "{zero_mps}");
        assert!(lift(-zero_mps).abs() < 1e-12, "{}", lift(-zero_mps));
        let yaw = rotor_wrench(&p, &speeds(h, [0.0, 10.0, 10.0, 0.0]), &[0.0, 0.0, -3.0], &[0.0; 3]).moment_b_nm[2];
        let still = rotor_wrench(&p, &speeds(h, [0.0, 10.0, 10.0, 0.0]), &[0.0; 3], &[0.0; 3]).moment_b_nm[2];
        assert_eq!(yaw, still, "the reaction torque is the static thrust's");
    }

    #[test]
    fn the_inflow_damps_roll_and_pitch_rates_and_never_does_work() {
        let p = QuadParams::default();
        let h = p.hover_rotor_speed_radps();
        let roll = rotor_wrench(&p, &[h; 4], &[0.0; 3], &[1.0, 0.0, 0.0]).moment_b_nm;
        let pitch = rotor_wrench(&p, &[h; 4], &[0.0; 3], &[0.0, -1.0, 0.0]).moment_b_nm;
        // Each rotor at d = arm / sqrt(2) from both axes: -4 k_z omega d^2 per rad/s.
        let d = p.arm_m / std::f64::consts::SQRT_2;
        let damping = 4.0 * p.rotor_inflow_coeff * h * d * d;
        assert!((roll[0] + damping).abs() < 1e-12 && roll[1].abs() < 1e-12, "{roll:?}");
        assert!((pitch[1] - damping).abs() < 1e-12 && pitch[0].abs() < 1e-12, "{pitch:?}");
        // What the inflow adds to the wrench takes power out at any motion: F.v + M.omega <= 0.
        let no_inflow = QuadParams { rotor_inflow_coeff: 0.0, ..p };
        let mut rng = crate::rng::SplitMix64::new(7);
        for _ in 0..200 {
            let mut draw = |scale: f64| rng.range(-scale, scale);
            let speeds: [f64; ROTORS] = std::array::from_fn(|_| 838.0 * (draw(0.5) + 0.5));
            let v = [draw(10.0), draw(10.0), draw(10.0)];
            let rates = [draw(5.0), draw(5.0), draw(5.0)];
            let (with, without) =
                (rotor_wrench(&p, &speeds, &v, &rates), rotor_wrench(&no_inflow, &speeds, &v, &rates));
            let power_w: f64 = (0..3)
                .map(|k| {
                    (with.force_b_n[k] - without.force_b_n[k]) * v[k]
                        + (with.moment_b_nm[k] - without.moment_b_nm[k]) * rates[k]
                })
                .sum();
            assert!(power_w <= 1e-12, "{power_w} W at {v:?}, {rates:?}");
        }
    }

    #[test]
    fn motors_follow_with_their_published_time_constants() {
        let p = QuadParams::default();
        assert!((rotor_acceleration_radps2(&p, 0.0, 100.0) - 100.0 / 0.0125).abs() < 1e-9);
        assert!((rotor_acceleration_radps2(&p, 100.0, 0.0) + 100.0 / 0.025).abs() < 1e-9);
        assert_eq!(commanded_speed_radps(&p, 1.5), 838.0);
        assert_eq!(commanded_speed_radps(&p, -0.1), 0.0);
        assert_eq!(commanded_speed_radps(&p, f64::NAN), 0.0);
    }
}
