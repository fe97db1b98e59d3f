//! Trim: steady, wings-level, constant-altitude flight at a given airspeed, altitude and CG. Solves throttle,
//! elevator and alpha (with theta = alpha, engine power at its equilibrium for the throttle) so that VT_dot,
//! alpha_dot and q_dot vanish, by Newton's method with a finite-difference Jacobian.

use super::{ControlInputs, ExternalForcing, F16Model, F16State, engine};
use crate::units::rad_to_deg;
use serde::Serialize;

/// Range of alpha covered by the aerodynamic data, deg.
pub const ALPHA_DATA_RANGE_DEG: (f64, f64) = (-10.0, 45.0);
/// Elevator travel used to judge a trim feasible, deg (the book's position limit).
pub const ELEVATOR_LIMIT_DEG: f64 = 25.0;

/// A solved trim.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Trim {
    /// Airspeed, ft/s.
    pub vt_fps: f64,
    /// Altitude, ft.
    pub alt_ft: f64,
    /// CG position, fraction of the mean chord.
    pub xcg: f64,
    /// Throttle, 0..1.
    pub throttle: f64,
    /// Elevator, deg.
    pub elevator_deg: f64,
    /// Angle of attack (= pitch angle), deg.
    pub alpha_deg: f64,
    /// Engine power at equilibrium, percent.
    pub power_pct: f64,
    /// The trimmed state.
    pub state: F16State,
    /// The trimmed controls.
    pub controls: ControlInputs,
    /// Largest |derivative| left, excluding north_dot (which is the airspeed), in the book's units.
    pub max_residual: f64,
    /// Newton iterations used.
    pub iterations: usize,
}

/// Why no trim was returned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrimError {
    /// The request itself is not a flight condition.
    #[error("invalid trim request: {0}")]
    InvalidRequest(String),
    /// The solver found a solution, but it needs a value the aircraft cannot have.
    #[error(
        "no trim at {vt_mps:.1} m/s and {alt_ft:.0} ft: level flight needs {what} = {value:.3}, outside {range} ({hint})"
    )]
    Infeasible {
        /// Airspeed, m/s.
        vt_mps: f64,
        /// Altitude, ft.
        alt_ft: f64,
        /// The quantity that is out of range.
        what: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range.
        range: &'static str,
        /// What that usually means.
        hint: &'static str,
    },
    /// Newton's method did not converge from any starting point.
    #[error(
        "no trim at {vt_mps:.1} m/s and {alt_ft:.0} ft: the solver did not converge (residual {residual:.3e}); the airspeed is probably too low or too high for level flight"
    )]
    NoConvergence {
        /// Airspeed, m/s.
        vt_mps: f64,
        /// Altitude, ft.
        alt_ft: f64,
        /// Smallest residual norm reached.
        residual: f64,
    },
}

/// The state and controls for unknowns z = [throttle, elevator_deg, alpha_rad].
fn trimmed_point(vt_fps: f64, alt_ft: f64, z: &[f64; 3]) -> (F16State, ControlInputs) {
    let state = F16State {
        vt_fps,
        alpha_rad: z[2],
        theta_rad: z[2],
        alt_ft,
        power_pct: engine::commanded_power_pct(z[0]),
        ..F16State::default()
    };
    (state, ControlInputs { throttle: z[0], elevator_deg: z[1], aileron_deg: 0.0, rudder_deg: 0.0 })
}

fn residual(model: &F16Model, vt_fps: f64, alt_ft: f64, z: &[f64; 3]) -> [f64; 3] {
    let (x, u) = trimmed_point(vt_fps, alt_ft, z);
    let d = model.derivative(&x, &u, &ExternalForcing::default());
    // Scale so the three equations weigh alike: VT_dot in ft/s^2 is about VT times larger than the angular terms.
    [d[0] / vt_fps, d[1], d[7]]
}

fn norm(r: &[f64; 3]) -> f64 {
    r.iter().map(|v| v * v).sum::<f64>().sqrt()
}

fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let m = nalgebra::Matrix3::from_fn(|i, j| a[i][j]);
    let x = m.lu().solve(&nalgebra::Vector3::from_column_slice(&b))?;
    x.iter().all(|v| v.is_finite()).then(|| [x[0], x[1], x[2]])
}

/// Newton's method on the trim residual from `start` (throttle, elevator_deg, alpha_rad), with a central-difference
/// Jacobian and a backtracking line search, for at most 100 steps: the point reached, its residual and the steps.
fn newton(model: &F16Model, vt_fps: f64, alt_ft: f64, start: [f64; 3]) -> ([f64; 3], [f64; 3], usize) {
    let mut z = start;
    let mut r = residual(model, vt_fps, alt_ft, &z);
    let mut iterations = 0;
    for _ in 0..100 {
        if norm(&r) < 1e-14 {
            break;
        }
        iterations += 1;
        let h = [1e-6, 1e-5, 1e-7];
        let mut jac = [[0.0; 3]; 3];
        for j in 0..3 {
            let (mut zp, mut zm) = (z, z);
            zp[j] += h[j];
            zm[j] -= h[j];
            let (rp, rm) = (residual(model, vt_fps, alt_ft, &zp), residual(model, vt_fps, alt_ft, &zm));
            for i in 0..3 {
                jac[i][j] = (rp[i] - rm[i]) / (2.0 * h[j]);
            }
        }
        let Some(step) = solve3(jac, [-r[0], -r[1], -r[2]]) else { break };
        // Backtracking: halve the step until the residual falls (tables are only piecewise smooth).
        let mut lambda = 1.0;
        let improved = loop {
            let cand: [f64; 3] = std::array::from_fn(|i| z[i] + lambda * step[i]);
            let rc = residual(model, vt_fps, alt_ft, &cand);
            if norm(&rc) < norm(&r) {
                break Some((cand, rc));
            }
            lambda *= 0.5;
            if lambda < 1e-6 {
                break None;
            }
        };
        match improved {
            Some((cand, rc)) => (z, r) = (cand, rc),
            None => break,
        }
    }
    (z, r, iterations)
}

/// Trim for steady wings-level flight at `vt_fps` and `alt_ft` with the model's CG.
pub fn trim_level_flight(model: &F16Model, vt_fps: f64, alt_ft: f64) -> Result<Trim, TrimError> {
    if !(vt_fps.is_finite() && vt_fps > 0.0) {
        return Err(TrimError::InvalidRequest(format!("airspeed must be positive, got {vt_fps} ft/s")));
    }
    if !(alt_ft.is_finite() && (0.0..=60_000.0).contains(&alt_ft)) {
        return Err(TrimError::InvalidRequest(format!("altitude must be within 0..60000 ft, got {alt_ft}")));
    }
    let vt_mps = crate::units::ft_to_m(vt_fps);
    let mut best: Option<([f64; 3], f64, usize)> = None;
    // Starting points from low to high alpha; the first converged solution inside the data wins.
    for start in [[0.2, -1.0, 3f64.to_radians()], [0.5, -3.0, 10f64.to_radians()], [0.8, -5.0, 25f64.to_radians()]] {
        let (z, r, iterations) = newton(model, vt_fps, alt_ft, start);
        let n = norm(&r);
        if best.as_ref().is_none_or(|b| n < b.1) {
            best = Some((z, n, iterations));
        }
        if n < 1e-10 && (ALPHA_DATA_RANGE_DEG.0..=ALPHA_DATA_RANGE_DEG.1).contains(&rad_to_deg(z[2])) {
            break;
        }
    }
    let (z, n, iterations) = best.expect("at least one start");
    if !(n < 1e-10) {
        return Err(TrimError::NoConvergence { vt_mps, alt_ft, residual: n });
    }
    let infeasible = |what, value, range, hint| TrimError::Infeasible { vt_mps, alt_ft, what, value, range, hint };
    let alpha_deg = rad_to_deg(z[2]);
    if !(ALPHA_DATA_RANGE_DEG.0..=ALPHA_DATA_RANGE_DEG.1).contains(&alpha_deg) {
        return Err(infeasible("alpha_deg", alpha_deg, "the aero data's -10..45 deg", "the airspeed is too low"));
    }
    if !(0.0..=1.0).contains(&z[0]) {
        let hint = if z[0] > 1.0 {
            "not enough thrust at this speed and altitude"
        } else {
            "the airspeed is too high to hold level with idle thrust"
        };
        return Err(infeasible("throttle", z[0], "0..1", hint));
    }
    if z[1].abs() > ELEVATOR_LIMIT_DEG {
        return Err(infeasible(
            "elevator_deg",
            z[1],
            "the elevator's -25..25 deg",
            "the CG or speed is outside the pitch control authority",
        ));
    }
    let (state, controls) = trimmed_point(vt_fps, alt_ft, &z);
    let d = model.derivative(&state, &controls, &ExternalForcing::default());
    let max_residual = d.iter().enumerate().filter(|(i, _)| *i != 9).map(|(_, v)| v.abs()).fold(0.0, f64::max);
    Ok(Trim {
        vt_fps,
        alt_ft,
        xcg: model.xcg,
        throttle: z[0],
        elevator_deg: z[1],
        alpha_deg,
        power_pct: state.power_pct,
        state,
        controls,
        max_residual,
        iterations,
    })
}

impl Trim {
    /// A short human-readable report.
    pub fn to_text(&self) -> String {
        format!(
            "trim: steady wings-level flight\n  airspeed   {:.3} m/s ({:.3} ft/s)\n  altitude   {:.1} ft\n  xcg        {:.3} c-bar\n  throttle   {:.5}\n  elevator   {:.5} deg\n  alpha      {:.5} deg (= theta)\n  power      {:.4} %\n  max |xdot| {:.2e} (all derivatives but north_dot)\n",
            crate::units::ft_to_m(self.vt_fps),
            self.vt_fps,
            self.alt_ft,
            self.xcg,
            self.throttle,
            self.elevator_deg,
            self.alpha_deg,
            self.power_pct,
            self.max_residual
        )
    }
}
