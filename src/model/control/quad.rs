//! Our reference controller for the X quadrotor, as the sliding-mode law is ours for the F-16: cascaded loops,
//! outer to inner, each the plain textbook form (Mahony, Kumar, Corke, "Multirotor Aerial Vehicles", IEEE Robotics
//! & Automation Magazine 19(3), 2012, section "Control"). Pure math: no I/O, no clock.
//!
//! - Altitude: the height error asks a climb rate (P, limited), the climb-rate error a vertical acceleration (PI);
//!   collective thrust `m (g + a) / (cos phi cos theta)` keeps the vertical component when tilted.
//! - Attitude: each Euler-angle error (yaw wrapped to +-180 deg) asks a body rate (P, limited).
//! - Rate: each body-rate error asks an angular acceleration (PI); the moment is `J alpha + omega x J omega`.
//! - Mixer: the thrust and three moments into four rotor thrusts by the X's inverse allocation (its columns are
//!   orthogonal), yaw given up first when a rotor would leave 0..full thrust, then rotor speeds and commands
//!   0..1 as [`crate::quad::rotors`] maps them.
//!
//! The integrators stop while a rotor is saturated (anti-windup).

use crate::quad::params::{GRAVITY_MPS2, QuadParams};
use crate::quad::rotors::ROTORS;
use serde::{Deserialize, Serialize};

/// Gains and limits of the cascade.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct QuadGains {
    /// Climb rate asked per metre of height error, 1/s.
    pub alt_p_per_s: f64,
    /// Largest climb or sink rate asked, m/s.
    pub max_climb_mps: f64,
    /// Vertical acceleration asked per m/s of climb-rate error, 1/s.
    pub climb_p_per_s: f64,
    /// Integral gain of the climb-rate loop, 1/s^2.
    pub climb_i_per_s2: f64,
    /// Body rate asked per radian of angle error (roll, pitch, yaw), 1/s.
    pub angle_p_per_s: [f64; 3],
    /// Largest body rate asked (roll, pitch, yaw), deg/s.
    pub max_rate_dps: [f64; 3],
    /// Angular acceleration asked per rad/s of rate error (p, q, r), 1/s.
    pub rate_p_per_s: [f64; 3],
    /// Integral gain of the rate loops, 1/s^2.
    pub rate_i_per_s2: [f64; 3],
    /// Largest roll or pitch set point flown, deg.
    pub max_tilt_deg: f64,
}

impl Default for QuadGains {
    /// A cascade whose loops are each several times faster than the one outside it, for the Hummingbird's motors
    /// (12.5 ms up): rate about 25 rad/s, attitude 6 rad/s, climb 4 rad/s, altitude 1.2 rad/s.
    fn default() -> Self {
        Self {
            alt_p_per_s: 1.2,
            max_climb_mps: 2.0,
            climb_p_per_s: 4.0,
            climb_i_per_s2: 2.0,
            angle_p_per_s: [6.0, 6.0, 3.0],
            max_rate_dps: [200.0, 200.0, 90.0],
            rate_p_per_s: [25.0, 25.0, 12.0],
            rate_i_per_s2: [20.0, 20.0, 5.0],
            max_tilt_deg: 35.0,
        }
    }
}

/// What the controller measures.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct QuadMeasurement {
    /// Euler angles phi, theta, psi, rad.
    pub euler_rad: [f64; 3],
    /// Body rates p, q, r, rad/s.
    pub body_rates_radps: [f64; 3],
    /// Height above the ground, m.
    pub alt_m: f64,
    /// Vertical speed, down positive, m/s.
    pub vd_mps: f64,
}

/// What it is asked to hold.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct QuadSetpoint {
    /// Roll, pitch and heading, rad.
    pub euler_rad: [f64; 3],
    /// Height above the ground, m.
    pub alt_m: f64,
}

/// The cascade's state: its integrators and the vehicle it was tuned for.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadController {
    /// Gains.
    pub gains: QuadGains,
    /// The vehicle's nominal parameters (mass, inertia, rotors) the thrust and moments are computed with.
    pub vehicle: QuadParams,
    climb_integral_mps2: f64,
    rate_integral_radps2: [f64; 3],
}

/// Mixer sign of each moment per rotor (motor order; see [`crate::quad::rotors`]): roll, pitch, yaw.
const MIX: [[f64; ROTORS]; 3] = [[-1.0, -1.0, 1.0, 1.0], [-1.0, 1.0, -1.0, 1.0], [-1.0, 1.0, 1.0, -1.0]];

impl QuadController {
    /// A controller with empty integrators.
    pub fn new(gains: QuadGains, vehicle: QuadParams) -> Self {
        Self { gains, vehicle, climb_integral_mps2: 0.0, rate_integral_radps2: [0.0; 3] }
    }

    /// The integrators (climb, then roll, pitch and yaw rate), rad/s^2 and m/s^2: what a restarted controller
    /// resumes from so the vehicle does not sag or twitch while they build up again.
    pub fn integrators(&self) -> [f64; 4] {
        let [p, q, r] = self.rate_integral_radps2;
        [self.climb_integral_mps2, p, q, r]
    }

    /// Resume the integrators [`QuadController::integrators`] saved; refused unless every one is finite.
    pub fn set_integrators(&mut self, saved: [f64; 4]) -> Result<(), String> {
        if let Some(v) = saved.iter().find(|v| !v.is_finite()) {
            return Err(format!("an integrator of the saved state is {v}, not a finite number"));
        }
        self.climb_integral_mps2 = saved[0];
        self.rate_integral_radps2 = [saved[1], saved[2], saved[3]];
        Ok(())
    }

    /// One step over `dt_s`: the motor commands (0..1, motor order) for this measurement and set point.
    pub fn step(&mut self, m: &QuadMeasurement, sp: &QuadSetpoint, dt_s: f64) -> [f64; ROTORS] {
        let g = self.gains;
        let climb_sp = (g.alt_p_per_s * (sp.alt_m - m.alt_m)).clamp(-g.max_climb_mps, g.max_climb_mps);
        let climb_error = climb_sp + m.vd_mps;
        let accel_up = g.climb_p_per_s * climb_error + self.climb_integral_mps2;
        let [phi, theta, _] = m.euler_rad;
        let tilt = (phi.cos() * theta.cos()).max(0.5);
        let thrust_n = (self.vehicle.mass_kg * (GRAVITY_MPS2 + accel_up) / tilt).max(0.0);
        let rate_sp = self.rate_setpoint(m, sp);
        let rate_error: [f64; 3] = std::array::from_fn(|k| rate_sp[k] - m.body_rates_radps[k]);
        let alpha = std::array::from_fn(|k| g.rate_p_per_s[k] * rate_error[k] + self.rate_integral_radps2[k]);
        let (commands, saturated) = self.mix(thrust_n, self.moments_nm(m, alpha));
        if !saturated {
            self.climb_integral_mps2 += g.climb_i_per_s2 * climb_error * dt_s;
            for (integral, (gain, error)) in
                self.rate_integral_radps2.iter_mut().zip(g.rate_i_per_s2.iter().zip(rate_error))
            {
                *integral += gain * error * dt_s;
            }
        }
        commands
    }

    /// Body rates asked by the attitude errors, rad/s.
    fn rate_setpoint(&self, m: &QuadMeasurement, sp: &QuadSetpoint) -> [f64; 3] {
        let g = &self.gains;
        let tilt_max = g.max_tilt_deg.to_radians();
        let target =
            [sp.euler_rad[0].clamp(-tilt_max, tilt_max), sp.euler_rad[1].clamp(-tilt_max, tilt_max), sp.euler_rad[2]];
        std::array::from_fn(|k| {
            let mut error = target[k] - m.euler_rad[k];
            if k == 2 {
                error = (error + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
            }
            let limit = g.max_rate_dps[k].to_radians();
            (g.angle_p_per_s[k] * error).clamp(-limit, limit)
        })
    }

    /// `J alpha + omega x J omega`, N m.
    fn moments_nm(&self, m: &QuadMeasurement, alpha: [f64; 3]) -> [f64; 3] {
        let v = &self.vehicle;
        let j = [v.ixx_kgm2, v.iyy_kgm2, v.izz_kgm2];
        let w = m.body_rates_radps;
        let h = [j[0] * w[0], j[1] * w[1], j[2] * w[2]];
        let gyro = [w[1] * h[2] - w[2] * h[1], w[2] * h[0] - w[0] * h[2], w[0] * h[1] - w[1] * h[0]];
        std::array::from_fn(|k| j[k] * alpha[k] + gyro[k])
    }

    /// Rotor thrusts for a collective thrust and three moments, as motor commands, and whether any rotor had to be
    /// held at 0 or full thrust.
    fn mix(&self, thrust_n: f64, moments_nm: [f64; 3]) -> ([f64; ROTORS], bool) {
        let v = &self.vehicle;
        let full_n = v.thrust_coeff_npradps2 * v.max_rotor_speed_radps.powi(2);
        let d = v.arm_m / std::f64::consts::SQRT_2;
        // Per-rotor share of each moment: roll and pitch over the lever, yaw over k_Q.
        let per = [moments_nm[0] / d, moments_nm[1] / d, moments_nm[2] / v.torque_per_thrust_m.max(1e-9)];
        let rotor = |yaw_scale: f64, i: usize| {
            (thrust_n + MIX[0][i] * per[0] + MIX[1][i] * per[1] + yaw_scale * MIX[2][i] * per[2]) / 4.0
        };
        let fits = |yaw_scale: f64| (0..ROTORS).all(|i| (0.0..=full_n).contains(&rotor(yaw_scale, i)));
        // Give up yaw first (halving until it fits, then none), as PX4's and Betaflight's mixers do.
        let mut yaw_scale = 1.0;
        while yaw_scale > 1e-3 && !fits(yaw_scale) {
            yaw_scale *= 0.5;
        }
        if !fits(yaw_scale) {
            yaw_scale = 0.0;
        }
        let saturated = yaw_scale < 1.0 || !fits(yaw_scale);
        let commands = std::array::from_fn(|i| {
            let t = rotor(yaw_scale, i).clamp(0.0, full_n);
            (t / v.thrust_coeff_npradps2).sqrt() / v.max_rotor_speed_radps
        });
        (commands, saturated)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quad::QuadVehicle;
    use crate::quad::outputs::{output_index, quad_outputs};

    const PLANT_DT_S: f64 = 0.001;

    fn measure(v: &QuadVehicle) -> QuadMeasurement {
        let o = quad_outputs(v);
        let at = |name| o[output_index(name).unwrap()];
        QuadMeasurement {
            euler_rad: [at("phi_deg"), at("theta_deg"), at("psi_deg")].map(f64::to_radians),
            body_rates_radps: [at("p_dps"), at("q_dps"), at("r_dps")].map(f64::to_radians),
            alt_m: at("alt_m"),
            vd_mps: at("vd_mps"),
        }
    }

    /// Flies `seconds` with the plant at 1 kHz and the controller at 1 kHz / `divisor`; returns the largest
    /// |error| of each channel (roll, pitch, yaw in deg, height in m) over the last second.
    fn fly(v: &mut QuadVehicle, c: &mut QuadController, sp: &QuadSetpoint, seconds: f64, divisor: usize) -> [f64; 4] {
        let ticks = (seconds / PLANT_DT_S).round() as usize;
        let mut worst = [0.0f64; 4];
        for k in 0..ticks {
            if k % divisor == 0 {
                let m = measure(v);
                v.command(c.step(&m, sp, PLANT_DT_S * divisor as f64));
            }
            v.step(PLANT_DT_S);
            if k + 1000 >= ticks {
                let m = measure(v);
                for (a, worst) in worst.iter_mut().take(3).enumerate() {
                    *worst = worst.max((m.euler_rad[a] - sp.euler_rad[a]).to_degrees().abs());
                }
                worst[3] = worst[3].max((m.alt_m - sp.alt_m).abs());
            }
        }
        worst
    }

    #[test]
    fn it_takes_off_hovers_and_tracks_attitude_steps_at_500_hz() {
        let p = QuadParams::default();
        let mut v = QuadVehicle::on_ground(p, 0.0).unwrap();
        let mut c = QuadController::new(QuadGains::default(), p);
        let mut sp = QuadSetpoint { euler_rad: [0.0; 3], alt_m: 2.0 };
        let hover = fly(&mut v, &mut c, &sp, 6.0, 2);
        assert!(!v.on_ground && hover[3] < 0.02, "hover at 2 m: {hover:?}");
        assert!(hover[..3].iter().all(|e| *e < 0.1), "{hover:?}");
        sp.euler_rad = [10f64.to_radians(), 0.0, 0.0];
        let roll = fly(&mut v, &mut c, &sp, 3.0, 2);
        assert!(roll[0] < 0.2, "roll 10 deg tracked: {roll:?}");
        sp.euler_rad = [0.0, -10f64.to_radians(), 45f64.to_radians()];
        let pitch_yaw = fly(&mut v, &mut c, &sp, 4.0, 2);
        assert!(pitch_yaw[1] < 0.2 && pitch_yaw[2] < 0.5, "pitch and yaw tracked: {pitch_yaw:?}");
        assert!(pitch_yaw[3] < 0.3, "height held while tilted: {pitch_yaw:?}");
    }

    #[test]
    fn a_heavier_vehicle_than_tuned_for_still_hovers_at_250_hz() {
        let mut p = QuadParams::default();
        let nominal = p;
        p.mass_kg *= 1.2;
        let mut v = QuadVehicle::hovering(p, 1.0, 0.0).unwrap();
        let mut c = QuadController::new(QuadGains::default(), nominal);
        let sp = QuadSetpoint { euler_rad: [0.0; 3], alt_m: 1.0 };
        let worst = fly(&mut v, &mut c, &sp, 12.0, 4);
        assert!(worst[3] < 0.02, "the climb integrator takes up 20 % more weight: {worst:?}");
    }

    #[test]
    fn the_integrators_resume_as_saved_and_refuse_nan() {
        let p = QuadParams::default();
        let mut v = QuadVehicle::hovering(p, 1.0, 0.0).unwrap();
        let mut c = QuadController::new(QuadGains::default(), p);
        let sp = QuadSetpoint { euler_rad: [0.1, 0.0, 0.0], alt_m: 1.5 };
        fly(&mut v, &mut c, &sp, 0.5, 1);
        let saved = c.integrators();
        assert!(saved.iter().any(|i| *i != 0.0), "{saved:?}");
        let mut resumed = QuadController::new(QuadGains::default(), p);
        resumed.set_integrators(saved).unwrap();
        assert_eq!(resumed, c);
        let e = resumed.set_integrators([0.0, f64::NAN, 0.0, 0.0]).unwrap_err();
        assert!(e.contains("NaN, not a finite number"), "{e}");
        assert_eq!(resumed, c, "a refused state leaves the controller as it was");
    }

    #[test]
    fn the_mixer_inverts_the_rotors_and_gives_up_yaw_first() {
        let p = QuadParams::default();
        let c = QuadController::new(QuadGains::default(), p);
        let weight = p.mass_kg * GRAVITY_MPS2;
        let (u, saturated) = c.mix(weight, [0.01, -0.02, 0.005]);
        assert!(!saturated);
        let speeds = u.map(|u| u * p.max_rotor_speed_radps);
        let w = crate::quad::rotors::rotor_wrench(&p, &speeds, &[0.0; 3], &[0.0; 3]);
        assert!((w.force_b_n[2] + weight).abs() < 1e-9);
        for (got, want) in w.moment_b_nm.iter().zip([0.01, -0.02, 0.005]) {
            assert!((got - want).abs() < 1e-9, "{:?}", w.moment_b_nm);
        }
        // A yaw demand beyond what the rotors can give is cut; roll is kept.
        let (u, saturated) = c.mix(weight, [0.05, 0.0, 5.0]);
        assert!(saturated);
        let w = crate::quad::rotors::rotor_wrench(&p, &u.map(|u| u * p.max_rotor_speed_radps), &[0.0; 3], &[0.0; 3]);
        assert!((w.moment_b_nm[0] - 0.05).abs() < 1e-9, "{:?}", w.moment_b_nm);
        assert!(w.moment_b_nm[2].abs() < 5.0);
    }
}
