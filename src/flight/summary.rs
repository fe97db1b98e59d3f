//! Control-quality figures of a closed-loop trace: settling times, final values, alpha, surface peaks, time at the
//! rate and position limits, RMS surface rate (the chattering figure), a limit-cycle detector, final |S|, max |W| and
//! the RMS error of the RBF estimate f_hat against the true f ([`crate::f_true`]).
//! Computed from the trace alone (plus the scenario's set points and limits), so the single-process and the
//! multi-process runs are judged by the same code.

use crate::scenario::Scenario;
use crate::trace::{CHANNELS, Trace};
use serde::{Deserialize, Serialize};

/// Window at the end of the run searched for sustained oscillations, s.
pub const LIMIT_CYCLE_WINDOW_S: f64 = 3.0;
/// RMS surface rates are also given from this time on, s (after the initial transient).
pub const RMS_RATE_FROM_S: f64 = 5.0;
/// Body rates are judged from this time on, s.
pub const RATES_FROM_S: f64 = 6.0;

/// One Euler angle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AngleFigures {
    /// phi, theta or psi.
    pub name: String,
    /// Set point, deg.
    pub setpoint_deg: f64,
    /// Value at t = 0, deg.
    pub initial_deg: f64,
    /// Value at the end, deg.
    pub final_deg: f64,
    /// Time after which the angle stays within 0.5 deg of its set point, s; `None` if it never does.
    pub settle_within_0p5deg_s: Option<f64>,
    /// Time after which it stays within 2 % of the step (|set point - initial|), s.
    pub settle_within_2pct_s: Option<f64>,
}

/// One output with a set point of its own (`[setpoint] alt_ft = 4000.0`; the F-16's angles are [`AngleFigures`]),
/// in that output's unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutputFigures {
    /// The output's name (a trace column).
    pub name: String,
    /// Set point.
    pub setpoint: f64,
    /// Value at t = 0 (NaN: the trace has no such column).
    pub initial: f64,
    /// Value at the end.
    pub final_value: f64,
    /// Time after which it stays within 2 % of the step (|set point - initial|), s; `None` if it never does.
    pub settle_within_2pct_s: Option<f64>,
    /// Largest excursion past the set point in the direction of the step (0 without a step).
    pub overshoot: f64,
}

/// One control surface.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfaceFigures {
    /// aileron, elevator or rudder.
    pub name: String,
    /// Largest |deflection|, deg.
    pub peak_deg: f64,
    /// Ticks at which the rate limit cut the motion: rows whose deflection moved a whole rate limit's worth from
    /// the row before.
    pub ticks_at_rate_limit: u64,
    /// Ticks at a position limit: rows whose deflection sits on a stop (counted as the rate-limit hits are, from
    /// the deflection alone, so a delayed command column does not shift it).
    pub ticks_at_position_limit: u64,
    /// RMS of the actual surface rate over the run, deg/s.
    pub rms_rate_dps: f64,
    /// RMS of the actual surface rate from `RMS_RATE_FROM_S` on, deg/s.
    pub rms_rate_late_dps: f64,
    /// RMS of the commanded rate over the run, deg/s.
    pub rms_command_rate_dps: f64,
}

/// An oscillation found at the end of the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Oscillation {
    /// Signal (trace column).
    pub signal: String,
    /// Half the peak-to-peak swing in the window, in the signal's unit.
    pub amplitude: f64,
    /// Mean period from zero crossings of the de-meaned signal, s.
    pub period_s: f64,
    /// Whether it counts as a sustained oscillation (see [`limit_cycle_threshold`]).
    pub sustained: bool,
}

/// One controller channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelFigures {
    /// phi, theta or psi.
    pub name: String,
    /// |S| at the end (the last logged value), rad/s.
    pub final_abs_s: f64,
    /// Largest |W| entry over the run.
    pub max_abs_w: f64,
    /// RMS of f_hat - f_true over the run, rad/s^2: how far the RBF estimate is from the lumped function it
    /// estimates ([`crate::f_true`]); NaN without an `fhat_<channel>` column.
    pub rms_f_error_radps2: f64,
}

/// All figures of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Samples in the trace (N + 1 for N steps: t = 0 to the duration).
    pub ticks: u64,
    /// Loop period, s.
    pub dt_s: f64,
    /// phi, theta, psi.
    pub angles: Vec<AngleFigures>,
    /// Angle of attack at the end, deg.
    pub alpha_final_deg: f64,
    /// Largest angle of attack, deg.
    pub alpha_peak_deg: f64,
    /// Largest |p|, |q|, |r| from `RATES_FROM_S` on, deg/s.
    pub body_rate_max_late_dps: [f64; 3],
    /// Altitude at the end minus at the start, ft.
    pub altitude_change_ft: f64,
    /// Airspeed at the end minus at the start, m/s (0 under the speed hold).
    pub airspeed_change_mps: f64,
    /// Energy height (h + VT^2 / 2g) at the end minus at the start, ft: the mechanical energy per unit weight the
    /// flight gained. Under the speed hold it is all altitude, supplied by the hold where the engine falls short.
    pub energy_height_change_ft: f64,
    /// The airspeed was held (VT_dot = 0) by the scenario's speed hold.
    pub speed_hold: bool,
    /// aileron, elevator, rudder.
    pub surfaces: Vec<SurfaceFigures>,
    /// Oscillations in the last `LIMIT_CYCLE_WINDOW_S`, per signal examined.
    pub oscillations: Vec<Oscillation>,
    /// True if any examined signal oscillates in a sustained way.
    pub limit_cycle: bool,
    /// phi, theta, psi channels of a sliding-mode controller (empty for a controller without S diagnostics).
    pub channels: Vec<ChannelFigures>,
    /// Outputs with set points of their own, in name order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outputs: Vec<OutputFigures>,
}

/// Amplitude above which an oscillation of `signal` counts: 0.1 deg for angles, 0.5 deg for surfaces.
pub fn limit_cycle_threshold(signal: &str) -> f64 {
    if signal.ends_with("_deg") && ["phi", "theta", "psi"].iter().any(|a| signal.starts_with(a)) { 0.1 } else { 0.5 }
}

fn col(trace: &Trace, name: &str) -> Vec<f64> {
    trace.column(name).unwrap_or_else(|| vec![f64::NAN; trace.rows.len()])
}

/// The time after which `x` stays within `band` of `target`; `None` if it is outside at the end.
pub fn settle_time(t: &[f64], x: &[f64], target: f64, band: f64) -> Option<f64> {
    let last_outside = x.iter().rposition(|v| !((v - target).abs() <= band));
    match last_outside {
        None => t.first().copied(),
        Some(i) if i + 1 < x.len() => Some(t[i + 1]),
        Some(_) => None,
    }
}

fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    // Rows without a command (a lost controller) carry NaN; they are gaps, not data.
    for v in values.filter(|v| v.is_finite()) {
        sum += v * v;
        n += 1;
    }
    if n == 0 { f64::NAN } else { (sum / n as f64).sqrt() }
}

fn oscillation(signal: &str, t: &[f64], x: &[f64]) -> Oscillation {
    oscillation_above(signal, t, x, limit_cycle_threshold(signal))
}

/// Largest excursion of `x` past `setpoint` in the direction of the step from its first value (0 without a step;
/// infinite once a value is NaN, a flight that is no longer a number).
pub fn overshoot(x: &[f64], setpoint: f64) -> f64 {
    let Some(first) = x.first() else { return 0.0 };
    let step = setpoint - first;
    if step == 0.0 {
        return 0.0;
    }
    // f64::signum gives 1 for 0: the step's direction is taken explicitly.
    let direction = if step > 0.0 { 1.0 } else { -1.0 };
    x.iter().map(|v| (v - setpoint) * direction).fold(0.0_f64, |m, v| if v.is_nan() { f64::INFINITY } else { m.max(v) })
}

/// The oscillation of `x` in the last [`LIMIT_CYCLE_WINDOW_S`], sustained when it swings at least `threshold` (in
/// the signal's unit) either way, at least two whole periods, without decaying.
pub fn oscillation_above(signal: &str, t: &[f64], x: &[f64], threshold: f64) -> Oscillation {
    let t_end = t.last().copied().unwrap_or(0.0);
    let start = t.iter().position(|v| *v >= t_end - LIMIT_CYCLE_WINDOW_S).unwrap_or(0);
    let (tw, xw) = (&t[start..], &x[start..]);
    let mean = xw.iter().sum::<f64>() / xw.len().max(1) as f64;
    let (lo, hi) = xw.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    let amplitude = if xw.is_empty() { 0.0 } else { (hi - lo) / 2.0 };
    // Zero crossings of the de-meaned signal with a 10 % hysteresis, so noise around the mean is not counted.
    let hysteresis = 0.1 * amplitude;
    let (mut side, mut crossings) = (0i8, Vec::new());
    for (ti, xi) in tw.iter().zip(xw) {
        let d = xi - mean;
        let s = if d > hysteresis {
            1
        } else if d < -hysteresis {
            -1
        } else {
            0
        };
        if s != 0 {
            if side != 0 && s != side {
                crossings.push(*ti);
            }
            side = s;
        }
    }
    let period_s = if crossings.len() >= 2 {
        2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
    } else {
        f64::NAN
    };
    // Sustained: at least two full periods in the window and not decaying (the second half swings at least half
    // as much as the first).
    let half = xw.len() / 2;
    let swing =
        |s: &[f64]| s.iter().fold(f64::NEG_INFINITY, |a, v| a.max(*v)) - s.iter().fold(f64::INFINITY, |a, v| a.min(*v));
    let not_decaying = half > 0 && swing(&xw[half..]) >= 0.5 * swing(&xw[..half]);
    let sustained = crossings.len() >= 4 && amplitude >= threshold && not_decaying;
    Oscillation { signal: signal.into(), amplitude, period_s, sustained }
}

/// Figures of `trace` as a run of `scenario`.
pub fn summarize(trace: &Trace, scenario: &Scenario) -> Summary {
    let t = col(trace, "t_s");
    let dt = scenario.timing.dt_s;
    let sp = &scenario.setpoint;
    let angles: Vec<AngleFigures> = [("phi", sp.phi_deg), ("theta", sp.theta_deg), ("psi", sp.psi_deg)]
        .iter()
        .map(|(name, setpoint_deg)| {
            let x = col(trace, &format!("{name}_deg"));
            let initial_deg = x.first().copied().unwrap_or(f64::NAN);
            let step = (setpoint_deg - initial_deg).abs();
            AngleFigures {
                name: name.to_string(),
                setpoint_deg: *setpoint_deg,
                initial_deg,
                final_deg: x.last().copied().unwrap_or(f64::NAN),
                settle_within_0p5deg_s: settle_time(&t, &x, *setpoint_deg, 0.5),
                settle_within_2pct_s: settle_time(&t, &x, *setpoint_deg, 0.02 * step),
            }
        })
        .collect();
    let outputs: Vec<OutputFigures> = sp
        .outputs
        .iter()
        .map(|(name, setpoint)| {
            let x = col(trace, name);
            let initial = x.first().copied().unwrap_or(f64::NAN);
            OutputFigures {
                name: name.clone(),
                setpoint: *setpoint,
                initial,
                final_value: x.last().copied().unwrap_or(f64::NAN),
                settle_within_2pct_s: settle_time(&t, &x, *setpoint, 0.02 * (setpoint - initial).abs()),
                overshoot: overshoot(&x, *setpoint),
            }
        })
        .collect();
    let alpha = col(trace, "alpha_deg");
    let (alt, vt) = (col(trace, "alt_ft"), col(trace, "vt_mps"));
    let change = |x: &[f64]| x.last().zip(x.first()).map_or(f64::NAN, |(b, a)| b - a);
    let energy_height_ft = |k: usize| {
        let vt_fps = vt[k] / silrig_model::units::M_PER_FT;
        alt[k] + vt_fps * vt_fps / (2.0 * silrig_model::plant::constants::GRAVITY_FPS2)
    };
    let energy_height_change_ft =
        if alt.is_empty() { f64::NAN } else { energy_height_ft(alt.len() - 1) - energy_height_ft(0) };
    // NaN when the run ends before `from`: there is nothing to judge, which is not the same as zero.
    let late = |name: &str, from: f64| -> f64 {
        let late: Vec<f64> =
            col(trace, name).iter().zip(&t).filter(|(_, ti)| **ti >= from).map(|(v, _)| v.abs()).collect();
        if late.is_empty() { f64::NAN } else { late.iter().fold(0.0, |m, v| m.max(*v)) }
    };
    let actuators = scenario.f16_actuators();
    let limits =
        [("aileron", &actuators.aileron_deg), ("elevator", &actuators.elevator_deg), ("rudder", &actuators.rudder_deg)];
    let surfaces = limits
        .iter()
        .map(|(name, lim)| {
            let pos = col(trace, &format!("{name}_deg"));
            let cmd = col(trace, &format!("{name}_cmd_deg"));
            let rates: Vec<f64> = pos.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
            let max_step = lim.rate_limit_per_s.map(|r| r * dt);
            let ticks_at_rate_limit = match max_step {
                Some(m) => pos.windows(2).filter(|w| (w[1] - w[0]).abs() >= m * (1.0 - 1e-9)).count() as u64,
                None => 0,
            };
            let on_stop = |p: f64, stop: f64| (p - stop).abs() <= 1e-9 * stop.abs().max(1.0);
            let ticks_at_position_limit =
                pos.iter().filter(|p| on_stop(**p, lim.max) || on_stop(**p, lim.min)).count() as u64;
            let late_rates = rates.iter().zip(&t).filter(|(_, ti)| **ti >= RMS_RATE_FROM_S).map(|(r, _)| *r);
            SurfaceFigures {
                name: name.to_string(),
                peak_deg: pos.iter().fold(0.0, |m, v| m.max(v.abs())),
                ticks_at_rate_limit,
                ticks_at_position_limit,
                rms_rate_dps: rms(rates.iter().copied()),
                rms_rate_late_dps: rms(late_rates),
                rms_command_rate_dps: rms(cmd.windows(2).map(|w| (w[1] - w[0]) / dt)),
            }
        })
        .collect();
    let oscillations: Vec<Oscillation> =
        ["phi_deg", "theta_deg", "psi_deg", "aileron_deg", "elevator_deg", "rudder_deg"]
            .iter()
            .map(|s| oscillation(s, &t, &col(trace, s)))
            .collect();
    // Only a sliding-mode controller (ours) reports S and W; a user's controller has other diagnostics.
    let f_true = crate::f_true::from_trace(trace, scenario);
    let channels = CHANNELS
        .iter()
        .enumerate()
        .filter(|(_, ch)| trace.index(&format!("s_{ch}")).is_some())
        .map(|(c, ch)| {
            let s = col(trace, &format!("s_{ch}"));
            let w_cols: Vec<usize> = trace
                .columns
                .iter()
                .enumerate()
                .filter(|(_, c)| c.starts_with(&format!("w_{ch}_")))
                .map(|(i, _)| i)
                .collect();
            let max_abs_w = trace.rows.iter().flat_map(|r| w_cols.iter().map(move |i| r[*i].abs())).fold(0.0, f64::max);
            // Rows without a command (a lost controller) carry NaN: report the last known |S|.
            let final_abs_s = s.iter().rev().find(|v| v.is_finite()).map_or(f64::NAN, |v| v.abs());
            let rms_f_error_radps2 = match (&f_true, trace.column(&format!("fhat_{ch}"))) {
                (Some(f), Some(fhat)) => crate::f_true::rms_error(&fhat, &f[c]),
                _ => f64::NAN,
            };
            ChannelFigures { name: ch.to_string(), final_abs_s, max_abs_w, rms_f_error_radps2 }
        })
        .collect();
    Summary {
        scenario: scenario.name.clone(),
        ticks: trace.rows.len() as u64,
        dt_s: dt,
        angles,
        alpha_final_deg: alpha.last().copied().unwrap_or(f64::NAN),
        alpha_peak_deg: alpha.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        body_rate_max_late_dps: [late("p_dps", RATES_FROM_S), late("q_dps", RATES_FROM_S), late("r_dps", RATES_FROM_S)],
        altitude_change_ft: change(&alt),
        airspeed_change_mps: change(&vt),
        energy_height_change_ft,
        speed_hold: scenario.plant.speed_hold,
        surfaces,
        limit_cycle: oscillations.iter().any(|o| o.sustained),
        oscillations,
        channels,
        outputs,
    }
}

fn opt_s(v: Option<f64>) -> String {
    v.map_or("never".to_string(), |s| format!("{s:.2} s"))
}

impl Summary {
    /// Readable report.
    pub fn to_text(&self) -> String {
        let t_end = self.ticks.saturating_sub(1) as f64 * self.dt_s;
        let mut out = format!(
            "scenario {}: {} samples every {} s, t = 0 to {t_end:.2} s\n",
            self.scenario, self.ticks, self.dt_s
        );
        out += "  angle   set    initial  final     settle(0.5deg)  settle(2%)\n";
        for a in &self.angles {
            out += &format!(
                "  {:<6} {:>6.2} {:>8.3} {:>8.3}   {:>13}  {:>10}\n",
                a.name,
                a.setpoint_deg,
                a.initial_deg,
                a.final_deg,
                opt_s(a.settle_within_0p5deg_s),
                opt_s(a.settle_within_2pct_s)
            );
        }
        if !self.outputs.is_empty() {
            out += "  output        set       initial   final     overshoot  settle(2%)\n";
        }
        for o in &self.outputs {
            out += &format!(
                "  {:<12} {:>9.3} {:>9.3} {:>9.3} {:>9.3}  {:>10}\n",
                o.name,
                o.setpoint,
                o.initial,
                o.final_value,
                o.overshoot,
                opt_s(o.settle_within_2pct_s)
            );
        }
        // A plant of the user's own may have no such column (NaN): its line is left out rather than printed as NaN.
        if !self.alpha_final_deg.is_nan() {
            out += &format!("  alpha: final {:.3} deg, peak {:.3} deg\n", self.alpha_final_deg, self.alpha_peak_deg);
        }
        let [p, q, r] = self.body_rate_max_late_dps;
        if p.is_nan() {
            out += &format!("  max |p|, |q|, |r| after {RATES_FROM_S} s: n/a (the run is shorter)\n");
        } else {
            out += &format!("  max |p|, |q|, |r| after {RATES_FROM_S} s: {p:.3}, {q:.3}, {r:.3} deg/s\n");
        }
        if !self.altitude_change_ft.is_nan() {
            out += &format!(
                "  flight path: altitude {:+.1} ft, airspeed {:+.2} m/s{}, energy height {:+.1} ft\n",
                self.altitude_change_ft,
                self.airspeed_change_mps,
                if self.speed_hold { " (speed hold)" } else { "" },
                self.energy_height_change_ft
            );
        }
        // The limits counted are the scenario's F-16 actuators': a plant whose commands are not the F-16's
        // `<surface>_cmd_deg` columns is not judged against them.
        if self.surfaces.iter().all(|s| s.rms_command_rate_dps.is_nan()) {
            out += "  surfaces: not the F-16's commands; the scenario's actuator limits do not apply\n";
        } else {
            out += "  surface   peak(deg)  rate-limit  pos-limit  rms rate(dps)  after 5 s  rms cmd rate\n";
        }
        for s in self.surfaces.iter().filter(|s| !s.rms_command_rate_dps.is_nan()) {
            // NaN: the run ended before the window began, or had no command to differentiate.
            let figure = |v: f64| if v.is_nan() { "n/a".to_string() } else { format!("{v:.3}") };
            out += &format!(
                "  {:<9} {:>9.2} {:>11} {:>10} {:>14} {:>10} {:>13}\n",
                s.name,
                s.peak_deg,
                s.ticks_at_rate_limit,
                s.ticks_at_position_limit,
                figure(s.rms_rate_dps),
                figure(s.rms_rate_late_dps),
                figure(s.rms_command_rate_dps)
            );
        }
        let found: Vec<String> = self
            .oscillations
            .iter()
            .filter(|o| o.sustained)
            .map(|o| format!("{} +-{:.2} every {:.3} s", o.signal, o.amplitude, o.period_s))
            .collect();
        out += &format!(
            "  limit cycle (last {LIMIT_CYCLE_WINDOW_S} s): {}\n",
            if found.is_empty() { "none".to_string() } else { format!("YES: {}", found.join("; ")) }
        );
        for c in &self.channels {
            out += &format!(
                "  channel {:<6} final |S| {:.2e}  max |W| {:.2e}  rms(f_hat - f) {:.3} rad/s^2\n",
                c.name, c.final_abs_s, c.max_abs_w, c.rms_f_error_radps2
            );
        }
        out
    }
}
