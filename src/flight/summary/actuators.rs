//! The summary's row per actuator: every input the loop flies through an actuator model (the F-16's surfaces, the
//! book's where the scenario names none; a plant of your own's inputs under `[actuators.<input>]`) whose command is
//! in the trace, judged against that actuator's limits: peak, time at its rate and position limits, RMS rates.

use super::measures::rms;
use crate::signals::PlantSignals;
use crate::trace::Trace;
use serde::{Deserialize, Serialize};
use silrig_model::actuator::ActuatorLimits;

/// One actuator, in its input's unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ActuatorFigures {
    /// The input it drives (`elevator`).
    pub name: String,
    /// The input's unit (`deg`; `1` for a ratio).
    pub unit: String,
    /// The trace column of its position (`elevator_deg`); absent when the plant reports none, and then every
    /// figure below is the command's, against the actuator's limits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<String>,
    /// The trace column of its command (`elevator_cmd_deg`).
    pub command: String,
    /// Largest |position| (|command| without a position).
    pub peak: f64,
    /// Ticks at which the rate limit cut the motion: rows whose position moved a whole rate limit's worth from the
    /// row before (without a position: rows whose command moved more than that).
    pub ticks_at_rate_limit: u64,
    /// Ticks at a position limit: rows whose position sits on a stop (counted from the position alone, so a delayed
    /// command column does not shift it; without a position: rows whose command is on or beyond a stop).
    pub ticks_at_position_limit: u64,
    /// `ticks_at_rate_limit` as a fraction of the trace's rows.
    pub rate_limit_fraction: f64,
    /// `ticks_at_position_limit` as a fraction of the trace's rows.
    pub position_limit_fraction: f64,
    /// Time at the rate limit or a position limit (either), s.
    pub saturated_s: f64,
    /// RMS of the actual rate over the run, unit/s (absent without a position).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_rate_per_s: Option<f64>,
    /// RMS of the actual rate over the late window, unit/s: the chattering figure (absent without a position).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_rate_late_per_s: Option<f64>,
    /// RMS of the commanded rate over the run, unit/s (absent when no two commands in a row came).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_command_rate_per_s: Option<f64>,
}

impl ActuatorFigures {
    /// The trace column its limit cycle is looked for in: its position, or its command.
    pub fn signal(&self) -> &str {
        self.position.as_deref().unwrap_or(&self.command)
    }
}

/// The rows of every input of `plant` whose command is in `trace` and which `limits_of` gives an actuator; `late`
/// is the first row of the late window.
pub(super) fn actuator_rows(
    trace: &Trace,
    plant: &PlantSignals,
    limits_of: &dyn Fn(&str) -> Option<ActuatorLimits>,
    dt_s: f64,
    late: usize,
) -> Vec<ActuatorFigures> {
    let rows = trace.rows.len();
    (0..plant.inputs.len())
        .filter_map(|k| {
            let input = &plant.inputs[k];
            let limits = limits_of(&input.name)?;
            let command_column = plant.command_column(k);
            let command = trace.column(&command_column).filter(|_| input.command_in_trace)?;
            let position_column = input
                .held_output
                .map(|o| &plant.outputs[o])
                .filter(|o| o.in_trace && trace.index(&o.name).is_some())
                .map(|o| o.name.clone());
            let position = position_column.as_deref().and_then(|c| trace.column(c));
            let hits = limit_hits(position.as_deref(), &command, &limits, dt_s);
            let count = |f: &dyn Fn(&(bool, bool)) -> bool| hits.iter().filter(|h| f(h)).count() as u64;
            let (at_rate, at_position) = (count(&|h| h.0), count(&|h| h.1));
            let rates = |x: &[f64]| -> Vec<f64> { x.windows(2).map(|w| (w[1] - w[0]) / dt_s).collect() };
            let moved = position.as_deref().map(rates);
            let series = position.as_deref().unwrap_or(&command);
            Some(ActuatorFigures {
                name: input.name.clone(),
                unit: input.unit.clone(),
                position: position_column,
                command: command_column,
                peak: series.iter().filter(|v| v.is_finite()).fold(0.0, |m, v| m.max(v.abs())),
                ticks_at_rate_limit: at_rate,
                ticks_at_position_limit: at_position,
                rate_limit_fraction: at_rate as f64 / rows.max(1) as f64,
                position_limit_fraction: at_position as f64 / rows.max(1) as f64,
                saturated_s: count(&|h| h.0 || h.1) as f64 * dt_s,
                rms_rate_per_s: moved.as_ref().and_then(|r| rms(r.iter().copied())),
                // The rate from row i to i + 1 belongs to row i, as the late window's rows do.
                rms_rate_late_per_s: moved.as_ref().and_then(|r| rms(r.iter().skip(late).copied())),
                rms_command_rate_per_s: rms(rates(&command).into_iter()),
            })
        })
        .collect()
}

/// Per row: (at the rate limit, at a position limit), from the position when there is one, else from the command
/// (a command that moved more than the actuator can in a tick, or that asks for a stop or beyond it).
fn limit_hits(position: Option<&[f64]>, command: &[f64], limits: &ActuatorLimits, dt_s: f64) -> Vec<(bool, bool)> {
    let max_step = limits.rate_limit_per_s.map(|r| r * dt_s);
    let stop_tolerance = |stop: f64| 1e-9 * stop.abs().max(1.0);
    match position {
        Some(p) => {
            let on_stop = |v: f64, stop: f64| (v - stop).abs() <= stop_tolerance(stop);
            (0..p.len())
                .map(|i| {
                    let rate = i > 0 && max_step.is_some_and(|m| (p[i] - p[i - 1]).abs() >= m * (1.0 - 1e-9));
                    (rate, on_stop(p[i], limits.max) || on_stop(p[i], limits.min))
                })
                .collect()
        }
        None => (0..command.len())
            .map(|i| {
                let c = command[i];
                // NaN (no command that tick) is neither: the actuator holds the last one.
                let rate = i > 0 && max_step.is_some_and(|m| (c - command[i - 1]).abs() > m * (1.0 + 1e-9));
                let stop = c >= limits.max - stop_tolerance(limits.max) || c <= limits.min + stop_tolerance(limits.min);
                (rate, stop)
            })
            .collect(),
    }
}
