//! The paper's attitude controller: adaptive sliding-mode control with one RBF network per Euler-angle channel
//! (roll phi, pitch theta, yaw psi), as `shared/docs/controller.md` states it. Pure math: no I/O, no clock.
//!
//! Per channel i: x1 = Euler angle, x2 = Euler-angle rate (kinematics, eq. 1), e = x1 - x1d, S = K e + x2,
//! v = -K x2 - f_hat - rho * sw(S) with sw(S) = S / (|S| + eps) (or sign(S)), and the surface command
//! u = g^-1 v, where g = T(phi, theta) J^-1 qbar S_w diag(b, c, b) D_nom maps deflections (deg) to Euler-angle
//! accelerations. The weights adapt by W_dot = Gamma S h(x).
//!
//! [`quad`] is our reference controller for the second vehicle, the X quadrotor (a cascade with a mixer).

/// The largest |RBF weight| a checkpoint may hand a restarted controller: adaptation in every scenario we fly keeps
/// them below 1 (the paper's are about 1e-3), so anything near this is a damaged checkpoint, not a learnt state.
pub const MAX_RESTORED_WEIGHT: f64 = 1e3;

pub mod quad;
pub mod rbf;

use crate::plant::aero::{MEAN_CHORD_FT, WING_AREA_FT2, WING_SPAN_FT};
use crate::plant::atmosphere::air_data;
use crate::plant::constants::{JX_SLUGFT2, JXZ_SLUGFT2, JY_SLUGFT2, JZ_SLUGFT2};
use crate::plant::tables::F16Tables;
use nalgebra::{Matrix3, Vector3};
use rbf::{RbfLayout, RbfNetwork};
use serde::{Deserialize, Serialize};

/// The switching term of the control law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Switching {
    /// S / (|S| + eps): the paper's smooth ("sigmoid") boundary layer.
    #[default]
    Sigmoid,
    /// sign(S): classic sliding mode, for comparison (chatters).
    Sign,
}

/// Gains and structure of the controller; each array is per channel (phi, theta, psi).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerGains {
    /// Switching term.
    #[serde(default)]
    pub switching: Switching,
    /// Sliding-surface slope K, 1/s.
    pub surface_slope_per_s: [f64; 3],
    /// Switching gain rho, rad/s^2.
    pub switching_gain_radps2: [f64; 3],
    /// Boundary-layer width eps of S / (|S| + eps), rad/s.
    pub boundary_layer_radps: [f64; 3],
    /// Adaptation gain Gamma of W_dot = Gamma S h.
    pub adaptation_gain: [f64; 3],
    /// Angle of attack at which the nominal control derivatives are read from the tables, deg.
    #[serde(default = "default_nominal_alpha_deg")]
    pub nominal_alpha_deg: f64,
    /// RBF network layout, shared by the three channels.
    #[serde(default)]
    pub rbf: RbfLayout,
    /// Pause the adaptation of every channel while a surface demand is past its travel (an anti-windup the paper
    /// does not have): then S grows because the actuator cannot deliver, not because f_hat is wrong, and learning
    /// from it winds the weights up into a growing oscillation (the soak's elevator hard-over).
    #[serde(default)]
    pub freeze_adaptation_when_saturated: bool,
}

fn default_nominal_alpha_deg() -> f64 {
    6.0
}

impl Default for ControllerGains {
    /// The paper's values (K = 0.75, 1.5, 0.75; rho = 2; eps = 0.01) with Gamma = 0.1 (controller.md).
    fn default() -> Self {
        Self {
            switching: Switching::Sigmoid,
            surface_slope_per_s: [0.75, 1.5, 0.75],
            switching_gain_radps2: [2.0; 3],
            boundary_layer_radps: [0.01; 3],
            adaptation_gain: [0.1; 3],
            nominal_alpha_deg: default_nominal_alpha_deg(),
            rbf: RbfLayout::default(),
            freeze_adaptation_when_saturated: false,
        }
    }
}

/// Channel names, for messages.
pub const CHANNEL_NAMES: [&str; 3] = ["phi", "theta", "psi"];

impl ControllerGains {
    /// Check every gain; the error names the key (as in the scenario file) and the problem.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |key: &str, v: &[f64; 3], allow_zero: bool| -> Result<(), String> {
            for (i, x) in v.iter().enumerate() {
                let ok = if allow_zero { *x >= 0.0 } else { *x > 0.0 };
                if !(ok && x.is_finite()) {
                    let want = if allow_zero { ">= 0" } else { "> 0" };
                    return Err(format!("{key}[{i}] ({}) must be {want}, got {x}", CHANNEL_NAMES[i]));
                }
            }
            Ok(())
        };
        positive("surface_slope_per_s", &self.surface_slope_per_s, false)?;
        positive("switching_gain_radps2", &self.switching_gain_radps2, true)?;
        positive("boundary_layer_radps", &self.boundary_layer_radps, false)?;
        positive("adaptation_gain", &self.adaptation_gain, true)?;
        if !(-10.0..=45.0).contains(&self.nominal_alpha_deg) {
            return Err(format!(
                "nominal_alpha_deg must be within the aero data's -10..45, got {}",
                self.nominal_alpha_deg
            ));
        }
        self.rbf.validate().map_err(|e| format!("rbf: {e}"))
    }
}

/// What the controller measures: attitude, body rates and the air data it needs for qbar.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measurement {
    /// Euler angles phi, theta, psi, rad.
    pub euler_rad: [f64; 3],
    /// Body rates p, q, r, rad/s.
    pub body_rates_radps: [f64; 3],
    /// True airspeed, ft/s.
    pub vt_fps: f64,
    /// Altitude, ft.
    pub alt_ft: f64,
}

/// The surface commands, deg.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceCommand {
    /// Aileron, deg.
    pub aileron_deg: f64,
    /// Elevator, deg.
    pub elevator_deg: f64,
    /// Rudder, deg.
    pub rudder_deg: f64,
}

impl SurfaceCommand {
    /// Aileron, elevator and rudder each limited to its (min, max) range, deg, as a flight computer limits what it
    /// commands (a NaN stays NaN, to be refused): a surface stuck hard-over drives the sliding surface, and the
    /// demand, past any travel.
    pub fn limited(self, ranges_deg: [(f64, f64); 3]) -> Self {
        let limit = |v: f64, (min, max): (f64, f64)| if v.is_nan() { v } else { v.clamp(min, max) };
        Self {
            aileron_deg: limit(self.aileron_deg, ranges_deg[0]),
            elevator_deg: limit(self.elevator_deg, ranges_deg[1]),
            rudder_deg: limit(self.rudder_deg, ranges_deg[2]),
        }
    }
}

/// Per-step values engineers plot (paper Fig. 2 and 3).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ControllerDiagnostics {
    /// Sliding surface S per channel, rad/s.
    pub sliding_surface: [f64; 3],
    /// RBF estimate f_hat per channel (before this step's adaptation), rad/s^2.
    pub f_hat: [f64; 3],
}

/// Nominal control-moment derivatives per degree, rows (roll, pitch, yaw), columns (aileron, elevator, rudder),
/// read once from the tables at `alpha_deg` and beta = 0 (controller.md: "partial information from the
/// aerodynamic model"). The pitch entry is the secant of C_m over elevator -12..+12 deg.
pub fn nominal_control_derivatives(tables: &F16Tables, alpha_deg: f64) -> Matrix3<f64> {
    let cl_da = tables.dlda.lookup(alpha_deg, 0.0) / 20.0;
    let cl_dr = tables.dldr.lookup(alpha_deg, 0.0) / 30.0;
    let cm_de = (tables.cm.lookup(alpha_deg, 12.0) - tables.cm.lookup(alpha_deg, -12.0)) / 24.0;
    let cn_da = tables.dnda.lookup(alpha_deg, 0.0) / 20.0;
    let cn_dr = tables.dndr.lookup(alpha_deg, 0.0) / 30.0;
    Matrix3::new(cl_da, 0.0, cl_dr, 0.0, cm_de, 0.0, cn_da, 0.0, cn_dr)
}

/// T(phi, theta): body rates to Euler-angle rates (paper eq. 1).
#[inline]
pub fn euler_rate_matrix(phi_rad: f64, theta_rad: f64) -> Matrix3<f64> {
    let (sph, cph) = phi_rad.sin_cos();
    let (sth, cth) = theta_rad.sin_cos();
    let tth = sth / cth;
    Matrix3::new(1.0, sph * tth, cph * tth, 0.0, cph, -sph, 0.0, sph / cth, cph / cth)
}

/// The controller with its adaptive state.
#[derive(Debug, Clone)]
pub struct AttitudeController {
    gains: ControllerGains,
    networks: [RbfNetwork; 3],
    /// J^-1 diag(b, c, b) D_nom: angular acceleration per (qbar S_w) per degree.
    moment_map: Matrix3<f64>,
    /// The (min, max) travel of aileron, elevator and rudder the controller believes its surfaces have, deg.
    travel_deg: [(f64, f64); 3],
}

impl AttitudeController {
    /// A controller with zero weights; `tables` supplies the nominal control derivatives once.
    pub fn new(gains: ControllerGains, tables: &F16Tables) -> Self {
        let inertia = Matrix3::new(JX_SLUGFT2, 0.0, -JXZ_SLUGFT2, 0.0, JY_SLUGFT2, 0.0, -JXZ_SLUGFT2, 0.0, JZ_SLUGFT2);
        let inertia_inv = inertia.try_inverse().expect("the F-16 inertia matrix is invertible");
        let lever = Matrix3::from_diagonal(&Vector3::new(WING_SPAN_FT, MEAN_CHORD_FT, WING_SPAN_FT));
        let moment_map = inertia_inv * lever * nominal_control_derivatives(tables, gains.nominal_alpha_deg);
        let networks = std::array::from_fn(|_| RbfNetwork::new(&gains.rbf));
        Self { gains, networks, moment_map, travel_deg: [(f64::NEG_INFINITY, f64::INFINITY); 3] }
    }

    /// The travel of aileron, elevator and rudder, (min, max) deg, past which a demand counts as saturated
    /// ([`ControllerGains::freeze_adaptation_when_saturated`]); unlimited until set.
    pub fn with_travel(mut self, travel_deg: [(f64, f64); 3]) -> Self {
        self.travel_deg = travel_deg;
        self
    }

    /// The gains in use.
    pub fn gains(&self) -> &ControllerGains {
        &self.gains
    }

    /// The three networks (phi, theta, psi).
    pub fn networks(&self) -> &[RbfNetwork; 3] {
        &self.networks
    }

    /// Replace the RBF weights (a restarted controller resuming from a checkpoint); `weights[c]` must have one
    /// finite entry per node, each within ±[`MAX_RESTORED_WEIGHT`]. Refused, changing nothing, with the reason.
    pub fn set_weights(&mut self, weights: &[Vec<f64>; 3]) -> Result<(), String> {
        for (c, (w, n)) in weights.iter().zip(&self.networks).enumerate() {
            if w.len() != n.weights.len() {
                return Err(format!(
                    "channel {c} has {} weights; this controller's network has {}",
                    w.len(),
                    n.weights.len()
                ));
            }
            if let Some(x) = w.iter().find(|x| !(x.abs() <= MAX_RESTORED_WEIGHT)) {
                let x = crate::units::readable(*x);
                return Err(format!("channel {c} has a weight of {x}, outside ±{MAX_RESTORED_WEIGHT}"));
            }
        }
        for (n, w) in self.networks.iter_mut().zip(weights) {
            n.weights.copy_from_slice(w);
        }
        Ok(())
    }

    /// g(x): Euler-angle acceleration per degree of (aileron, elevator, rudder) at this measurement.
    pub fn control_effectiveness(&self, m: &Measurement) -> Matrix3<f64> {
        let qbar_psf = air_data(m.vt_fps, m.alt_ft).qbar_psf;
        euler_rate_matrix(m.euler_rad[0], m.euler_rad[1]) * self.moment_map * (qbar_psf * WING_AREA_FT2)
    }

    /// One control step: the command for this measurement and set point, then the weight update over `dt_s`.
    #[inline]
    pub fn step(
        &mut self,
        m: &Measurement,
        setpoint_rad: &[f64; 3],
        dt_s: f64,
    ) -> (SurfaceCommand, ControllerDiagnostics) {
        let g = &self.gains;
        let t = euler_rate_matrix(m.euler_rad[0], m.euler_rad[1]);
        let euler_rates = t * Vector3::from(m.body_rates_radps);
        let mut v = Vector3::zeros();
        let mut diag = ControllerDiagnostics::default();
        for i in 0..3 {
            let (x1, x2) = (m.euler_rad[i], euler_rates[i]);
            let s = g.surface_slope_per_s[i] * (x1 - setpoint_rad[i]) + x2;
            let f_hat = self.networks[i].evaluate([x1, x2]);
            let switch = match g.switching {
                Switching::Sigmoid => s / (s.abs() + g.boundary_layer_radps[i]),
                Switching::Sign => {
                    if s > 0.0 {
                        1.0
                    } else if s < 0.0 {
                        -1.0
                    } else {
                        0.0
                    }
                }
            };
            v[i] = -g.surface_slope_per_s[i] * x2 - f_hat - g.switching_gain_radps2[i] * switch;
            diag.sliding_surface[i] = s;
            diag.f_hat[i] = f_hat;
        }
        let effectiveness = self.control_effectiveness(m);
        // g is well conditioned in the flight envelope; a singular g (qbar = 0) commands neutral surfaces.
        let u = effectiveness.lu().solve(&v).filter(|u| u.iter().all(|x| x.is_finite())).unwrap_or_else(Vector3::zeros);
        let saturated = u.iter().zip(&self.travel_deg).any(|(u, (min, max))| *u < *min || *u > *max);
        if !(g.freeze_adaptation_when_saturated && saturated) {
            for i in 0..3 {
                self.networks[i].adapt(g.adaptation_gain[i], diag.sliding_surface[i], dt_s);
            }
        }
        (SurfaceCommand { aileron_deg: u[0], elevator_deg: u[1], rudder_deg: u[2] }, diag)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::tables::F16_TABLES;

    #[test]
    fn restored_weights_must_fit_the_network_and_stay_finite_and_bounded() {
        let mut c = AttitudeController::new(ControllerGains::default(), &F16_TABLES);
        let n = c.networks()[0].weights.len();
        let good: [Vec<f64>; 3] = std::array::from_fn(|_| vec![1e-3; n]);
        assert_eq!(c.set_weights(&good), Ok(()));
        let mut huge = good.clone();
        huge[1][0] = 1e300;
        assert_eq!(c.set_weights(&huge), Err("channel 1 has a weight of 1e300, outside ±1000".into()));
        let mut nan = good.clone();
        nan[2][1] = f64::NAN;
        assert!(c.set_weights(&nan).unwrap_err().contains("weight of NaN"));
        let short: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; n - 1]);
        assert!(c.set_weights(&short).unwrap_err().contains("weights; this controller's network has"));
        // A refusal changes nothing.
        assert!(c.networks().iter().all(|net| net.weights.iter().all(|w| *w == 1e-3)));
    }

    #[test]
    fn nominal_derivatives_match_controller_md_near_six_degrees_alpha() {
        let d = nominal_control_derivatives(&F16_TABLES, 6.0);
        let close = |got: f64, want: f64, tol: f64| assert!((got - want).abs() <= tol * want.abs(), "{got} vs {want}");
        close(d[(0, 0)], -0.00256, 0.03);
        close(d[(0, 2)], 0.000467, 0.03);
        close(d[(1, 1)], -0.00989, 0.03);
        close(d[(2, 0)], -0.00044, 0.05);
        close(d[(2, 2)], -0.00149, 0.03);
        assert_eq!(d[(1, 0)], 0.0);
        assert_eq!(d[(0, 1)], 0.0);
    }

    #[test]
    fn command_produces_the_euler_acceleration_the_law_asks_for() {
        // Through g, the command must reproduce v = -K x2 - f_hat - rho sw(S) exactly (f_hat = 0 at first).
        let mut c = AttitudeController::new(ControllerGains::default(), &F16_TABLES);
        let m = Measurement {
            euler_rad: [0.05, 0.08, -0.02],
            body_rates_radps: [0.01, -0.02, 0.005],
            vt_fps: 492.0,
            alt_ft: 25_000.0,
        };
        let g = c.control_effectiveness(&m);
        let (u, d) = c.step(&m, &[0.0, 10f64.to_radians(), 0.0], 0.01);
        let accel = g * Vector3::new(u.aileron_deg, u.elevator_deg, u.rudder_deg);
        let rates = euler_rate_matrix(m.euler_rad[0], m.euler_rad[1]) * Vector3::from(m.body_rates_radps);
        let gains = ControllerGains::default();
        for i in 0..3 {
            let s = d.sliding_surface[i];
            let want = -gains.surface_slope_per_s[i] * rates[i] - 2.0 * s / (s.abs() + 0.01);
            assert!((accel[i] - want).abs() < 1e-9, "channel {i}: {} vs {want}", accel[i]);
        }
        // Pitch error is negative (theta below its set point), so the elevator goes trailing edge up.
        assert!(u.elevator_deg < 0.0);
        // The weights moved by Gamma S h dt.
        assert!(c.networks()[1].weight_norm() > 0.0);
    }

    #[test]
    fn adaptation_pauses_while_a_demand_is_past_its_travel_only_when_asked() {
        // Far below the set point the demand is past a ±1 deg travel; the weights learn from it only without the
        // anti-windup, and with it as soon as the demand is back within travel.
        let m =
            Measurement { euler_rad: [0.0, -0.3, 0.0], body_rates_radps: [0.0; 3], vt_fps: 492.0, alt_ft: 25_000.0 };
        let setpoint = [0.0, 10f64.to_radians(), 0.0];
        let travel = [(-1.0, 1.0); 3];
        let norm = |c: &AttitudeController| c.networks()[1].weight_norm();
        let mut learning = AttitudeController::new(ControllerGains::default(), &F16_TABLES).with_travel(travel);
        let (u, _) = learning.step(&m, &setpoint, 0.01);
        assert!(u.elevator_deg.abs() > 1.0, "the demand is past travel: {u:?}");
        assert!(norm(&learning) > 0.0);
        let gains = ControllerGains { freeze_adaptation_when_saturated: true, ..ControllerGains::default() };
        let mut frozen = AttitudeController::new(gains.clone(), &F16_TABLES).with_travel(travel);
        frozen.step(&m, &setpoint, 0.01);
        assert_eq!(norm(&frozen), 0.0);
        let mut within = AttitudeController::new(gains, &F16_TABLES).with_travel([(-90.0, 90.0); 3]);
        within.step(&m, &setpoint, 0.01);
        assert!(norm(&within) > 0.0);
    }

    #[test]
    fn a_limited_command_keeps_what_is_within_and_a_nan() {
        let demand = SurfaceCommand { aileron_deg: 12.5, elevator_deg: -91.8, rudder_deg: f64::NAN };
        let limited = demand.limited([(-90.0, 90.0); 3]);
        assert_eq!((limited.aileron_deg, limited.elevator_deg), (12.5, -90.0));
        assert!(limited.rudder_deg.is_nan(), "a NaN is a bug to be refused, not a command to limit");
        assert_eq!(SurfaceCommand { rudder_deg: 95.0, ..demand }.limited([(-90.0, 90.0); 3]).rudder_deg, 90.0);
    }

    #[test]
    fn gains_are_validated_by_key() {
        let mut g = ControllerGains::default();
        g.boundary_layer_radps[1] = 0.0;
        assert!(g.validate().unwrap_err().contains("boundary_layer_radps[1] (theta) must be > 0"));
        let mut g = ControllerGains::default();
        g.surface_slope_per_s[0] = -1.0;
        assert!(g.validate().unwrap_err().contains("surface_slope_per_s[0] (phi)"));
    }
}
