//! What the plant process flies: [`PlantModel`], a vehicle behind named signals, stepped by the plant loop
//! ([`super::plant::PlantLoop`]); the models themselves (the built-in F-16, an FMU) are adapters, in
//! `silrig-adapters`; a model of the user's own in another process is driven through [`super::plant_session`].

use silrig_flight::signals::PlantSignals;

/// What the plant process flies: a vehicle model behind named signals. The loop around it
/// ([`super::plant::PlantLoop`]) keeps the clock, the commands, the watchdog and failsafe, the checkpoints and the
/// report.
pub trait PlantModel {
    /// Its announcement: name, outputs, inputs with their ranges and the values its failsafe holds.
    fn signals(&self) -> &PlantSignals;
    /// The tick its state belongs to (a restored model: its checkpoint's).
    fn tick(&self) -> u64;
    /// Simulated time of its state, s.
    fn t_s(&self) -> f64;
    /// Its outputs now, in the announced order: what this tick's sample carries.
    fn outputs(&self) -> Vec<f64>;
    /// The inputs its actuators hold before any command.
    fn initial_inputs(&self) -> Vec<f64>;
    /// Move the actuators under `inputs` (checked against the announced ranges) and integrate one step to the
    /// next tick; `last`: only move the actuators (the scenario's last tick). An error says why the flight cannot
    /// go on (the state left where the model is defined): the flight ends there.
    fn step(&mut self, inputs: &[f64], last: bool) -> Result<ActuatorFlags, String>;
    /// What a restarted plant resumes from, as text (`None`: nothing to save).
    fn checkpoint(&self) -> Option<String>;
    /// Resume from what [`PlantModel::checkpoint`] saved in a run of `ticks` ticks; the tick it resumes at.
    fn restore(&mut self, saved: &str, ticks: u64) -> Result<u64, String>;
}

/// What the actuators did in one step, for the next sample's flags.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ActuatorFlags {
    /// An actuator sits on its position limit.
    pub saturated: bool,
    /// An actuator moved at its rate limit.
    pub rate_limited: bool,
}
