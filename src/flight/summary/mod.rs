//! Control-quality figures of a closed-loop trace, for any plant: a row per output with a set point (held or
//! stepped, judged accordingly), the F-16's flight figures where the plant announces the signals they need (alpha,
//! body rates, flight path), a row per actuator ([`actuators`]), a limit-cycle detector over the late window, and the
//! channels of a sliding-mode controller (final |S|, max |W|, the RMS error of f_hat against the true f of
//! [`crate::f_true`]). Computed from the trace alone (with the scenario's set points, actuators and late window, and
//! the plant's announcement), so the single-process and the multi-process runs are judged by the same code; the
//! measures on one signal are [`measures`], the printed form `text.rs`.

pub mod actuators;
pub mod measures;
mod text;

pub use actuators::ActuatorFigures;
pub use measures::{Oscillation, oscillation_above, overshoot, settle_time};
pub use text::seconds;

use crate::scenario::Scenario;
use crate::signals::PlantSignals;
use crate::trace::{CHANNELS, Trace};
use measures::late_start;
use serde::{Deserialize, Serialize};

/// Amplitude from which an angle's oscillation counts (an output in deg with a set point), deg.
pub const ANGLE_OSCILLATION_DEG: f64 = 0.1;
/// Amplitude from which an actuator's oscillation counts when it moves in deg, deg.
pub const SURFACE_OSCILLATION_DEG: f64 = 0.5;
/// Amplitude from which any other signal's oscillation counts, as a fraction of its scale: an output's largest
/// error over the flight, an actuator's travel.
pub const OSCILLATION_FRACTION: f64 = 0.01;

/// How an output with a set point is judged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "response", rename_all = "lowercase")]
pub enum Response {
    /// The set point is where the output started: judged by how far it strays (`max_error`) and where it ends.
    Held,
    /// A step from where it started: judged by how it gets there.
    Stepped {
        /// Time after which it stays within 2 % of the step (|set point - initial|), s; `None` if it never does.
        settle_within_2pct_s: Option<f64>,
        /// Largest excursion past the set point in the direction of the step.
        overshoot: f64,
    },
}

/// When an output in deg stays within 0.5 deg of its set point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settled {
    /// From this time on, s; `None` if it is outside at the end.
    pub at_s: Option<f64>,
}

/// One output with a set point, in that output's unit. A set point that `[[setpoint_steps]]` change is described
/// by its last step: the set point then, the value at the step, the response from there; `max_error` against the
/// value in force at each row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetpointFigures {
    /// The output's name (a trace column).
    pub name: String,
    /// Its unit, as the plant announces it.
    pub unit: String,
    /// Set point (the last step's, for one that steps).
    pub setpoint: f64,
    /// Value at t = 0 (at the last step, for a set point that steps).
    pub initial: f64,
    /// Value at the end.
    pub final_value: f64,
    /// Largest |value - set point| over the run (infinite once a value is NaN).
    pub max_error: f64,
    /// Held or stepped, with the figures of each.
    #[serde(flatten)]
    pub response: Response,
    /// An output in deg: when it settles within 0.5 deg of its set point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settle_within_0p5deg: Option<Settled>,
}

/// Angle of attack.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlphaFigures {
    /// At the end, deg.
    pub final_deg: f64,
    /// Largest, deg.
    pub peak_deg: f64,
}

/// The flight path, end minus start.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlightPath {
    /// Altitude, ft.
    pub altitude_change_ft: f64,
    /// Airspeed, m/s (0 under the speed hold).
    pub airspeed_change_mps: f64,
    /// Energy height (h + VT^2 / 2g), ft: the mechanical energy per unit weight the flight gained. Under the speed
    /// hold it is all altitude, supplied by the hold where the engine falls short.
    pub energy_height_change_ft: f64,
    /// The airspeed was held (VT_dot = 0) by the scenario's speed hold.
    pub speed_hold: bool,
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
    /// estimates ([`crate::f_true`]); absent without an `fhat_<channel>` column or the F-16's states.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_f_error_radps2: Option<f64>,
}

/// All figures of one run. What the plant does not announce is left out, not given as NaN or 0.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// The plant's name (`f16` for the built-in F-16).
    pub plant: String,
    /// Samples in the trace (N + 1 for N steps: t = 0 to the duration).
    pub ticks: u64,
    /// Loop period, s.
    pub dt_s: f64,
    /// The late window: the last this many seconds of the trace are judged at rest (late body rates, late RMS
    /// actuator rates, limit cycles), s.
    pub late_window_s: f64,
    /// The outputs with a set point that the trace has: the F-16's attitude first, then the others in name order.
    pub setpoints: Vec<SetpointFigures>,
    /// Angle of attack, when the plant announces `alpha_deg`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<AlphaFigures>,
    /// Largest |p|, |q|, |r| in the late window, deg/s, when the plant announces `p_dps`, `q_dps` and `r_dps`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body_rate_max_late_dps: Option<[f64; 3]>,
    /// The flight path, when the plant announces `alt_ft` and `vt_mps`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flight_path: Option<FlightPath>,
    /// One per input flown through an actuator model whose command is in the trace.
    pub actuators: Vec<ActuatorFigures>,
    /// Oscillations in the late window, per signal examined: each set point's output and each actuator.
    pub oscillations: Vec<Oscillation>,
    /// True if any examined signal oscillates in a sustained way.
    pub limit_cycle: bool,
    /// phi, theta, psi channels of a sliding-mode controller (empty for a controller without S diagnostics).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<ChannelFigures>,
}

/// The built-in F-16's announcement, which the summary reads its units and actuator positions from.
fn builtin_f16() -> PlantSignals {
    crate::f16_signals::f16_signals([0.0; 4])
}

/// Figures of `trace` as a run of `scenario` with `plant`: the announcement of a plant of your own (an FMU,
/// `--plant-cmd`, `--plant external`), whose actuators are the rig's on the inputs `[actuators]` names; `None` for
/// the built-in F-16, whose surfaces always fly through actuators (the book's where the scenario names none).
pub fn summarize(trace: &Trace, scenario: &Scenario, plant: Option<&PlantSignals>) -> Summary {
    let builtin;
    let signals = match plant {
        Some(p) => p,
        None => {
            builtin = builtin_f16();
            &builtin
        }
    };
    let col = |name: &str| trace.column(name);
    let t = col("t_s").unwrap_or_default();
    let dt = scenario.timing.dt_s;
    let late_window_s = scenario.timing.late_window_s();
    let late = late_start(&t, late_window_s);
    let setpoints = setpoint_rows(trace, scenario, signals, &t);
    let alpha = col("alpha_deg").map(|a| AlphaFigures {
        final_deg: a.last().copied().unwrap_or(f64::NAN),
        peak_deg: a.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    });
    let late_peak = |x: Vec<f64>| x.iter().skip(late).fold(0.0, |m: f64, v| m.max(v.abs()));
    let body_rate_max_late_dps = match (col("p_dps"), col("q_dps"), col("r_dps")) {
        (Some(p), Some(q), Some(r)) => Some([late_peak(p), late_peak(q), late_peak(r)]),
        _ => None,
    };
    let flight_path = col("alt_ft").zip(col("vt_mps")).map(|(alt, vt)| flight_path(&alt, &vt, scenario));
    let f16 = scenario.f16_actuators();
    let limits_of = |input: &str| match plant {
        Some(_) => scenario.actuators.get(input).copied(),
        None => match input {
            "aileron" => Some(f16.aileron_deg),
            "elevator" => Some(f16.elevator_deg),
            "rudder" => Some(f16.rudder_deg),
            "throttle" => Some(f16.throttle),
            _ => None,
        },
    };
    let actuators = actuators::actuator_rows(trace, signals, &limits_of, dt, late);
    let oscillations = oscillations(trace, &t, &setpoints, &actuators, scenario, late_window_s);
    Summary {
        scenario: scenario.name.clone(),
        plant: signals.plant.clone(),
        ticks: trace.rows.len() as u64,
        dt_s: dt,
        late_window_s,
        setpoints,
        alpha,
        body_rate_max_late_dps,
        flight_path,
        actuators,
        limit_cycle: oscillations.iter().any(|o| o.sustained),
        oscillations,
        channels: channels(trace, scenario),
    }
}

/// A row per set point whose output the plant announces and the trace has, in [`crate::scenario::Setpoint::all`]'s
/// order. Held: the set point equals the output's first value (to 1e-9 of it).
fn setpoint_rows(trace: &Trace, scenario: &Scenario, plant: &PlantSignals, t: &[f64]) -> Vec<SetpointFigures> {
    scenario
        .setpoint
        .all()
        .into_iter()
        .filter_map(|(name, _)| {
            let unit = plant.outputs.iter().find(|o| o.name == name)?.unit.clone();
            let all = trace.column(name)?;
            let track = scenario.setpoint_track(name)?;
            let all_t = t;
            // The last step the trace reaches, and the rows from it on (all of them without steps).
            let rows = measures::segment_rows(t, track.segments());
            let last = rows.iter().rposition(|r| !r.is_empty()).unwrap_or(0);
            let (setpoint, from) = (track.segments()[last].value, rows[last].start);
            let (t, x) = (&t[from..], &all[from..]);
            let initial = x.first().copied().unwrap_or(f64::NAN);
            let step = setpoint - initial;
            let response = if step.abs() <= 1e-9 * setpoint.abs().max(1.0) {
                Response::Held
            } else {
                Response::Stepped {
                    settle_within_2pct_s: settle_time(t, x, setpoint, 0.02 * step.abs()),
                    overshoot: overshoot(x, setpoint),
                }
            };
            let in_force = all_t.iter().map(|ti| track.at(*ti));
            let error = |(v, sp): (&f64, f64)| if v.is_nan() { f64::INFINITY } else { (v - sp).abs() };
            Some(SetpointFigures {
                name: name.to_string(),
                settle_within_0p5deg: (unit == "deg").then(|| Settled { at_s: settle_time(t, x, setpoint, 0.5) }),
                unit,
                setpoint,
                initial,
                final_value: x.last().copied().unwrap_or(f64::NAN),
                max_error: all.iter().zip(in_force).map(error).fold(0.0, f64::max),
                response,
            })
        })
        .collect()
}

/// End minus start of altitude, airspeed and energy height.
fn flight_path(alt_ft: &[f64], vt_mps: &[f64], scenario: &Scenario) -> FlightPath {
    let change = |x: &[f64]| x.last().zip(x.first()).map_or(f64::NAN, |(b, a)| b - a);
    let energy_height_ft = |k: usize| {
        let vt_fps = vt_mps[k] / silrig_model::units::M_PER_FT;
        alt_ft[k] + vt_fps * vt_fps / (2.0 * silrig_model::plant::constants::GRAVITY_FPS2)
    };
    let energy_height_change_ft =
        if alt_ft.is_empty() { f64::NAN } else { energy_height_ft(alt_ft.len() - 1) - energy_height_ft(0) };
    FlightPath {
        altitude_change_ft: change(alt_ft),
        airspeed_change_mps: change(vt_mps),
        energy_height_change_ft,
        speed_hold: scenario.plant.speed_hold,
    }
}

/// The late window's oscillation of every set point's output and every actuator (its position, or its command),
/// each against its own threshold: [`ANGLE_OSCILLATION_DEG`] and [`SURFACE_OSCILLATION_DEG`] in deg, else
/// [`OSCILLATION_FRACTION`] of the signal's scale.
fn oscillations(
    trace: &Trace,
    t: &[f64],
    setpoints: &[SetpointFigures],
    actuators: &[ActuatorFigures],
    scenario: &Scenario,
    window_s: f64,
) -> Vec<Oscillation> {
    let outputs = setpoints.iter().map(|s| {
        let threshold = if s.unit == "deg" { ANGLE_OSCILLATION_DEG } else { OSCILLATION_FRACTION * s.max_error };
        (s.name.as_str(), threshold)
    });
    let moved = actuators.iter().map(|a| {
        let travel = scenario.actuators.get(&a.name).map_or(0.0, |l| l.max - l.min);
        let threshold = if a.unit == "deg" { SURFACE_OSCILLATION_DEG } else { OSCILLATION_FRACTION * travel };
        (a.signal(), threshold)
    });
    outputs
        .chain(moved)
        .filter_map(|(signal, threshold)| {
            let x = trace.column(signal)?;
            Some(oscillation_above(signal, t, &x, threshold, window_s))
        })
        .collect()
}

/// The channels of a sliding-mode controller (ours), from its `s_<channel>`, `w_<channel>_<i>` and `fhat_<channel>`
/// diagnostics; a controller of your own has other diagnostics, and no channels.
fn channels(trace: &Trace, scenario: &Scenario) -> Vec<ChannelFigures> {
    if !CHANNELS.iter().any(|ch| trace.index(&format!("s_{ch}")).is_some()) {
        return Vec::new();
    }
    let f_true = crate::f_true::from_trace(trace, scenario);
    CHANNELS
        .iter()
        .enumerate()
        .filter_map(|(c, ch)| {
            let s = trace.column(&format!("s_{ch}"))?;
            let w_cols: Vec<usize> = trace
                .columns
                .iter()
                .enumerate()
                .filter(|(_, name)| name.starts_with(&format!("w_{ch}_")))
                .map(|(i, _)| i)
                .collect();
            let max_abs_w = trace.rows.iter().flat_map(|r| w_cols.iter().map(move |i| r[*i].abs())).fold(0.0, f64::max);
            // Rows without a command (a lost controller) carry NaN: report the last known |S|.
            let final_abs_s = s.iter().rev().find(|v| v.is_finite()).map_or(f64::NAN, |v| v.abs());
            let rms_f_error_radps2 = match (&f_true, trace.column(&format!("fhat_{ch}"))) {
                (Some(f), Some(fhat)) => Some(crate::f_true::rms_error(&fhat, &f[c])).filter(|v| !v.is_nan()),
                _ => None,
            };
            Some(ChannelFigures { name: ch.to_string(), final_abs_s, max_abs_w, rms_f_error_radps2 })
        })
        .collect()
}

/// `name` split into its stem and its unit suffix (`phi_deg` in deg: `phi`, `_deg`; `p_dps` in deg/s: `p`, `_dps`),
/// so a figure's column carries the unit once (`phi_final_error_deg`); a name without its unit's suffix is its own
/// stem.
fn split_unit<'a>(name: &'a str, unit: &str) -> (&'a str, &'a str) {
    let abbreviation = match unit {
        "deg/s" => "dps",
        "m/s" => "mps",
        "ft/s" => "fps",
        "rad/s" => "radps",
        other => other,
    };
    match name.rsplit_once('_') {
        Some((stem, suffix)) if !stem.is_empty() && !suffix.is_empty() && suffix == abbreviation => {
            (stem, &name[stem.len()..])
        }
        _ => (name, ""),
    }
}

impl Summary {
    /// The figures a sweep's `cases.csv` carries for this flight, by column, each named by the plant's signals and
    /// in their units: per set point the settling time (within 0.5 deg for an output in deg, else within 2 % of a
    /// step), the final and the largest error; the peak alpha and the late body rates where the plant has them;
    /// the worst actuator's rate- and position-limit fractions where there are actuators. `None`: no such number
    /// (never settled, not a number).
    pub fn case_figures(&self) -> Vec<(String, Option<f64>)> {
        let finite = |v: f64| v.is_finite().then_some(v);
        let mut out = Vec::new();
        for s in &self.setpoints {
            let settle = match (&s.settle_within_0p5deg, &s.response) {
                (Some(deg), _) => deg.at_s,
                (None, Response::Stepped { settle_within_2pct_s, .. }) => *settle_within_2pct_s,
                (None, Response::Held) => None,
            };
            out.push((format!("{}_settle_s", split_unit(&s.name, &s.unit).0), settle));
        }
        for (figure, value) in [("final_error", 0), ("max_error", 1)] {
            for s in &self.setpoints {
                let (stem, suffix) = split_unit(&s.name, &s.unit);
                let v = if value == 0 { s.final_value - s.setpoint } else { s.max_error };
                out.push((format!("{stem}_{figure}{suffix}"), finite(v)));
            }
        }
        if let Some(a) = &self.alpha {
            out.push(("alpha_peak_deg".into(), finite(a.peak_deg)));
        }
        if let Some(rates) = self.body_rate_max_late_dps {
            for (name, v) in ["p", "q", "r"].iter().zip(rates) {
                out.push((format!("{name}_max_late_dps"), finite(v)));
            }
        }
        if !self.actuators.is_empty() {
            let worst = |f: &dyn Fn(&ActuatorFigures) -> f64| self.actuators.iter().map(f).fold(0.0, f64::max);
            out.push(("rate_limit_fraction".into(), Some(worst(&|a| a.rate_limit_fraction))));
            out.push(("position_limit_fraction".into(), Some(worst(&|a| a.position_limit_fraction))));
        }
        out
    }
}

/// The names of [`Summary::case_figures`] for any flight of `scenario` with `plant` (as [`summarize`] takes it): the
/// figures of a trace with the plant's columns and no rows, so they are the very names a flown case gives.
pub fn case_columns(scenario: &Scenario, plant: Option<&PlantSignals>) -> Vec<String> {
    let columns = match plant {
        Some(p) => p.trace_columns(&[]),
        None => crate::trace::LOOP_COLUMNS.map(String::from).to_vec(),
    };
    summarize(&Trace::new(columns), scenario, plant).case_figures().into_iter().map(|(name, _)| name).collect()
}

#[cfg(test)]
mod tests;
