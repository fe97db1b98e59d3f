//! The true lumped function f of each controller channel, recovered from a flown trace, to set beside the RBF
//! network's estimate f_hat (the paper's Fig. 2 plots "the estimated and true RBFNN functions"). Pure: no I/O.
//!
//! The controller's model of each Euler-angle channel is x2_dot = f + g u + d (controller.md): g is its nominal
//! control effectiveness, d the scenario's known disturbance, and f everything else. Over the step [t_k, t_k+1),
//! with the deflections u_k held (row k of the trace):
//!
//! ```text
//! f_true_k = (x2_{k+1} - x2_k) / dt  -  g(x_k) u_k  -  d_k
//! ```
//!
//! x2 = T(phi, theta) (p, q, r): the Euler-angle rates from the measured rows, as the controller computes them;
//! (x2_{k+1} - x2_k) / dt the mean angular acceleration of the channel over the step; g(x_k) the controller's own g
//! at row k's measurement; u_k the actual deflections held over the step (after the actuators, not the commands);
//! d_k the disturbance's mean over the step (Simpson's rule, which is how RK4 integrates a forcing of time alone).
//! The last row has no step after it, so its f_true is NaN; so is a step whose rows are incomplete.

use crate::scenario::Scenario;
use crate::trace::Trace;
use nalgebra::Vector3;
use silrig_model::control::{AttitudeController, Measurement, euler_rate_matrix};
use silrig_model::units::{M_PER_FT, deg_to_rad};

/// Trace columns f_true is computed from.
const COLUMNS: [&str; 12] = [
    "t_s",
    "phi_deg",
    "theta_deg",
    "psi_deg",
    "p_dps",
    "q_dps",
    "r_dps",
    "vt_mps",
    "alt_ft",
    "aileron_deg",
    "elevator_deg",
    "rudder_deg",
];

/// f_true of the phi, theta and psi channels, one value per row of `trace` (rad/s^2), for the controller and
/// disturbance of `scenario`; `None` if the trace lacks one of the loop columns it needs.
pub fn from_trace(trace: &Trace, scenario: &Scenario) -> Option<[Vec<f64>; 3]> {
    let index: Vec<usize> = COLUMNS.iter().map(|c| trace.index(c)).collect::<Option<_>>()?;
    let controller = AttitudeController::new(scenario.controller.gains.clone(), scenario.plant.model().tables());
    let dt = scenario.timing.dt_s;
    let mask = scenario.disturbance.channel_mask();
    let row = |k: usize| -> [f64; 12] { std::array::from_fn(|i| trace.rows[k][index[i]]) };
    let measure = |r: &[f64; 12]| Measurement {
        euler_rad: [deg_to_rad(r[1]), deg_to_rad(r[2]), deg_to_rad(r[3])],
        body_rates_radps: [deg_to_rad(r[4]), deg_to_rad(r[5]), deg_to_rad(r[6])],
        vt_fps: r[7] / M_PER_FT,
        alt_ft: r[8],
    };
    let euler_rates =
        |m: &Measurement| euler_rate_matrix(m.euler_rad[0], m.euler_rad[1]) * Vector3::from(m.body_rates_radps);
    let rows = trace.rows.len();
    // Per row once: the measurement, its Euler-angle rates and the disturbance at its time (the next step's start).
    let measurements: Vec<Measurement> = (0..rows).map(|k| measure(&row(k))).collect();
    let rates: Vec<Vector3<f64>> = measurements.iter().map(euler_rates).collect();
    let disturbance = |t: f64| Vector3::from(scenario.disturbance.at(t, &mask));
    let mut f = [vec![f64::NAN; rows], vec![f64::NAN; rows], vec![f64::NAN; rows]];
    let mut d_start = disturbance(trace.rows.first().map_or(0.0, |r| r[index[0]]));
    for k in 0..rows.saturating_sub(1) {
        let now = row(k);
        let t = now[0];
        let d_end = disturbance(t + dt);
        let d_mean = (d_start + 4.0 * disturbance(t + 0.5 * dt) + d_end) / 6.0;
        d_start = d_end;
        let held = Vector3::new(now[9], now[10], now[11]);
        let accel = (rates[k + 1] - rates[k]) / dt;
        let value = accel - controller.control_effectiveness(&measurements[k]) * held - d_mean;
        for (channel, v) in f.iter_mut().zip(value.iter()) {
            channel[k] = *v;
        }
    }
    Some(f)
}

/// Root mean square of `estimate - truth` over the rows where both are numbers; NaN if there are none.
pub fn rms_error(estimate: &[f64], truth: &[f64]) -> f64 {
    let (sum, n) = estimate
        .iter()
        .zip(truth)
        .map(|(e, t)| e - t)
        .filter(|d| d.is_finite())
        .fold((0.0, 0usize), |(s, n), d| (s + d * d, n + 1));
    if n == 0 { f64::NAN } else { (sum / n as f64).sqrt() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_model::control::ControllerGains;
    use silrig_model::plant::tables::F16_TABLES;

    #[test]
    fn rms_error_skips_rows_without_a_number() {
        assert_eq!(rms_error(&[1.0, f64::NAN, 3.0], &[0.0, 1.0, 0.0]), 5f64.sqrt());
        assert!(rms_error(&[f64::NAN], &[1.0]).is_nan());
    }

    #[test]
    fn f_true_of_a_plant_that_is_exactly_the_controllers_model_is_its_f() {
        // Rows made up from x2_dot = f + g u + d with a known f, the Euler rates advanced each step by its exact
        // mean: the recovered f_true must be that f. The attitude and air data held fixed keep T(phi, theta) and g
        // constant, so the rows' body rates are T^-1 x2.
        let mut scenario = Scenario::embedded_default();
        scenario.controller.gains = ControllerGains::default();
        scenario.disturbance.amplitude_radps2 = 0.3;
        let dt = scenario.timing.dt_s;
        let controller = AttitudeController::new(scenario.controller.gains.clone(), &F16_TABLES);
        let m0 =
            Measurement { euler_rad: [0.0, 0.1, 0.0], body_rates_radps: [0.0; 3], vt_fps: 500.0, alt_ft: 20_000.0 };
        let g = controller.control_effectiveness(&m0);
        let f = Vector3::new(-0.7, 0.2, 0.05);
        let u = |k: usize| Vector3::new(1.0 + 0.1 * k as f64, -2.0, 0.5 * (k as f64).sin());
        let mask = scenario.disturbance.channel_mask();
        let d = |t: f64| Vector3::from(scenario.disturbance.at(t, &mask));
        let mut trace = Trace::new(crate::trace::columns(5));
        let mut rates = Vector3::zeros();
        let t_inverse = euler_rate_matrix(0.0, 0.1).try_inverse().unwrap();
        for k in 0..6 {
            let t = k as f64 * dt;
            let body = t_inverse * rates;
            let mut r = vec![0.0; trace.columns.len()];
            let set = |r: &mut Vec<f64>, c: &str, v: f64| r[trace.index(c).unwrap()] = v;
            set(&mut r, "t_s", t);
            set(&mut r, "theta_deg", 0.1f64.to_degrees());
            for (c, v) in ["p_dps", "q_dps", "r_dps"].iter().zip(body.iter()) {
                set(&mut r, c, v.to_degrees());
            }
            set(&mut r, "vt_mps", 500.0 * M_PER_FT);
            set(&mut r, "alt_ft", 20_000.0);
            for (c, v) in ["aileron_deg", "elevator_deg", "rudder_deg"].iter().zip(u(k).iter()) {
                set(&mut r, c, *v);
            }
            trace.rows.push(r);
            // Exact mean acceleration over the step: f + g u_k + the Simpson mean of d (exact for this sine to 1e-9).
            let d_mean = (d(t) + 4.0 * d(t + 0.5 * dt) + d(t + dt)) / 6.0;
            rates += (f + g * u(k) + d_mean) * dt;
        }
        let got = from_trace(&trace, &scenario).unwrap();
        for (c, channel) in got.iter().enumerate() {
            for (k, v) in channel[..5].iter().enumerate() {
                assert!((v - f[c]).abs() < 1e-9, "row {k}, channel {c}: {v} vs {}", f[c]);
            }
        }
        assert!(got.iter().all(|ch| ch[5].is_nan()), "the last row has no step after it");
    }
}
