//! A scenario's `[timing]`: the loop period, the run's length, when a command acts, and the late window (the end of
//! the flight where the summary and the criteria judge the loop at rest), with their checks.

use serde::{Deserialize, Serialize};

/// Most ticks in one run: a trace row of 39 numbers per tick stays in memory (about 300 MB at this many).
pub const MAX_TICKS: u64 = 1_000_000;

/// Largest extra transport delay, ticks (the rig's plant keeps the last 8 commands).
pub const MAX_TRANSPORT_DELAY_TICKS: u64 = 5;

/// The late window when the scenario gives none, as a fraction of the run: the last 3 s of the 10 s flights the
/// summary's limit-cycle detector has always searched (and the check suites' verdicts rest on).
pub const LATE_WINDOW_FRACTION: f64 = 0.3;

/// When a command computed from the sample of tick k acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum CommandTiming {
    /// From tick k: no transport delay (the paper's simulation).
    SameTick,
    /// From tick k+1: one sample of transport delay, as in a multi-process loop.
    NextTick,
}

/// Step, duration and command timing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Timing {
    /// Loop period, s.
    pub dt_s: f64,
    /// Run length, s.
    pub duration_s: f64,
    /// Command timing.
    pub command_timing: CommandTiming,
    /// Extra transport delay, whole ticks on top of `command_timing` (0..=5): the command computed from the sample
    /// of tick k acts from tick k + d (same-tick) or k + 1 + d (next-tick).
    #[serde(default)]
    pub transport_delay_ticks: u64,
    /// The end of the flight judged at rest, s: the summary's late body rates, late RMS actuator rates and
    /// limit-cycle detector look at the last this many seconds of the trace (default: [`LATE_WINDOW_FRACTION`] of
    /// the run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub late_window_s: Option<f64>,
    /// The controller computes every this many plant ticks (1..=1000, from tick 0): a controller at a divisor of
    /// the plant's rate (4 at a 1 kHz plant is 250 Hz). Between its ticks its last answer is repeated, so the plant
    /// and the trace keep the plant's rate; the controller's step is this many periods.
    #[serde(default = "every_tick", skip_serializing_if = "is_every_tick")]
    pub controller_every_ticks: u64,
}

/// Most plant ticks between two controller ticks.
pub const MAX_CONTROLLER_EVERY_TICKS: u64 = 1000;

fn every_tick() -> u64 {
    1
}

fn is_every_tick(n: &u64) -> bool {
    *n == 1
}

impl Timing {
    /// Ticks between the sample a command answers and the first tick it acts on.
    pub fn command_delay_ticks(&self) -> u64 {
        let offset = match self.command_timing {
            CommandTiming::SameTick => 0,
            CommandTiming::NextTick => 1,
        };
        offset + self.transport_delay_ticks
    }

    /// Whether the controller computes at plant tick `tick` (else its last answer is repeated).
    pub fn is_controller_tick(&self, tick: u64) -> bool {
        tick.is_multiple_of(self.controller_every_ticks.max(1))
    }

    /// The controller's step, s: `controller_every_ticks` plant periods.
    pub fn controller_dt_s(&self) -> f64 {
        self.dt_s * self.controller_every_ticks.max(1) as f64
    }

    /// Number of ticks in the run.
    pub fn ticks(&self) -> u64 {
        (self.duration_s / self.dt_s).round() as u64
    }

    /// The loop period, ns: the one figure every clock of the rig (the plant's ticks, the consumers' staleness
    /// deadlines, the OS-floor baseline beside a run) takes its period from.
    pub fn period_ns(&self) -> u64 {
        (self.dt_s * 1e9).round() as u64
    }

    /// The late window, s: the scenario's `late_window_s`, or [`LATE_WINDOW_FRACTION`] of the run.
    pub fn late_window_s(&self) -> f64 {
        self.late_window_s.unwrap_or(LATE_WINDOW_FRACTION * self.duration_s)
    }

    /// Check every value; on error return (dotted key, problem).
    pub fn validate(&self) -> Result<(), (String, String)> {
        let err = |key: &str, problem: String| Err((key.to_string(), problem));
        if !(self.dt_s >= 1e-4 && self.dt_s <= 0.1) {
            return err("timing.dt_s", format!("must be within 0.0001..0.1 s (10 kHz to 10 Hz), got {}", self.dt_s));
        }
        if !(self.duration_s > 0.0 && self.duration_s <= 3600.0) {
            return err("timing.duration_s", format!("must be within (0, 3600] s, got {}", self.duration_s));
        }
        if self.duration_s < self.dt_s {
            return err("timing.duration_s", format!("is shorter than one step ({} s)", self.dt_s));
        }
        if self.ticks() > MAX_TICKS {
            return err(
                "timing.duration_s",
                format!(
                    "is {} ticks of {} s; a run has at most {MAX_TICKS} (its trace is kept in memory)",
                    self.ticks(),
                    self.dt_s
                ),
            );
        }
        if self.transport_delay_ticks > MAX_TRANSPORT_DELAY_TICKS {
            return err(
                "timing.transport_delay_ticks",
                format!("must be within 0..={MAX_TRANSPORT_DELAY_TICKS}, got {}", self.transport_delay_ticks),
            );
        }
        let every = self.controller_every_ticks;
        if !(1..=MAX_CONTROLLER_EVERY_TICKS).contains(&every) || every > self.ticks().max(1) {
            return err(
                "timing.controller_every_ticks",
                format!(
                    "must be within 1..={} plant ticks and at most the run's {} ticks, got {every}: the controller \
                     computes every this many plant ticks",
                    MAX_CONTROLLER_EVERY_TICKS,
                    self.ticks()
                ),
            );
        }
        if let Some(w) = self.late_window_s
            && !(w > 0.0 && w <= self.duration_s)
        {
            return err(
                "timing.late_window_s",
                format!(
                    "must be within (0, {}] s (the run's duration), got {w}: the last part of the flight the summary \
                     judges at rest",
                    self.duration_s
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timing(late_window_s: Option<f64>) -> Timing {
        Timing {
            dt_s: 0.01,
            duration_s: 10.0,
            command_timing: CommandTiming::NextTick,
            transport_delay_ticks: 0,
            late_window_s,
            controller_every_ticks: 1,
        }
    }

    #[test]
    fn the_late_window_is_a_fraction_of_the_run_unless_given() {
        assert_eq!(timing(None).late_window_s(), 3.0);
        assert_eq!(Timing { duration_s: 30.0, ..timing(None) }.late_window_s(), 9.0);
        assert_eq!(timing(Some(4.5)).late_window_s(), 4.5);
        assert_eq!(timing(Some(10.0)).validate(), Ok(()));
        for bad in [0.0, -1.0, 10.5, f64::NAN] {
            let (key, problem) = timing(Some(bad)).validate().unwrap_err();
            assert_eq!(key, "timing.late_window_s");
            assert!(problem.contains("must be within (0, 10] s"), "{problem}");
        }
    }
}
