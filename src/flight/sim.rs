//! The closed loop in one process: plant, actuators and controller stepped in lockstep with no clock, so two runs
//! of one scenario give bit-identical traces. The multi-process rig reuses [`PlantRunner`], [`measurement`] and
//! [`trace_row`], so both produce the same trace.
//!
//! A run of duration T at period dt has N = T / dt steps and N + 1 samples, t_k = k dt for k = 0..N (a 10 s run at
//! 0.01 s: 1001 samples, t = 0.00 to 10.00 s). Tick k: the plant's snapshot at t_k (state and load factors, with
//! the surfaces where the actuators left them) goes to the controller; its command acts from tick k (`same-tick`)
//! or from tick k+1 (`next-tick`); the actuators then take their position for [t_k, t_k+1) under the applied
//! command and hold it (zero-order hold), and RK4 integrates the plant over that step. At the last sample the
//! actuators still take their position under its command, but nothing is integrated past the end.
//!
//! Row k of the trace shows the state at t_k and the deflections held over [t_k, t_k+1): what acted on the
//! aircraft from that sample on, never a position the surface left at t_k.
//!
//! Every integrated state is checked against the model's envelope ([`silrig_model::plant::envelope`]): a flight that
//! leaves it ends there ([`LeftEnvelope`]), with its trace up to the last state inside.
//!
//! Plant-model faults of the scenario's plan act here, so `silrig sim` and the rig apply them identically: actuator
//! faults in [`PlantRunner::step`] (over the step that starts at a tick inside the fault's window), sensor faults on
//! what [`PlantRunner::snapshot`] reports (never on the integrated state). Windows are judged on simulated time
//! `tick * dt`, never on a clock.

use crate::fault::{Fault, FaultAction, SENSOR_CHANNELS, SURFACES};
use crate::scenario::Scenario;
use crate::setpoints::SetpointTrack;
use crate::trace::{self, Trace};
use silrig_model::actuator::ActuatorFault;
use silrig_model::control::{AttitudeController, ControllerDiagnostics, Measurement, SurfaceCommand};
use silrig_model::plant::envelope::EnvelopeError;
use silrig_model::plant::tables::F16Tables;
use silrig_model::plant::{ExternalForcing, F16State, STATE_NAMES};
use silrig_model::rng::SplitMix64;
use silrig_model::units::deg_to_rad;
use silrig_model::vehicle::{F16Vehicle, InitialError};

/// Why a scenario cannot start.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// The trim requested by the initial condition does not exist.
    #[error("initial condition: {0}")]
    Trim(#[from] silrig_model::plant::trim::TrimError),
    /// No throttle in 0..1 holds the initial airspeed.
    #[error(
        "initial condition: no throttle in 0..1 holds the airspeed (VT_dot is {at_idle:.2} ft/s^2 at throttle 0 and {at_full:.2} at 1); give initial.throttle explicitly"
    )]
    NoThrottle {
        /// VT_dot at throttle 0, ft/s^2.
        at_idle: f64,
        /// VT_dot at throttle 1, ft/s^2.
        at_full: f64,
    },
    /// The initial state is outside the model's envelope (a scenario built in code rather than through
    /// [`Scenario::validate`]).
    #[error("initial condition: outside the model's envelope: {0}")]
    OutsideEnvelope(#[from] EnvelopeError),
    /// A plant-model fault of the plan is malformed (a scenario built in code rather than through
    /// [`Scenario::validate`]).
    #[error("faults[{index}].{key}: {problem}")]
    Fault {
        /// Position in the plan.
        index: usize,
        /// The key at fault.
        key: String,
        /// What is wrong.
        problem: String,
    },
    /// The scenario names what the F-16 does not have (an input, a sensor channel, a parameter of a plant of
    /// your own).
    #[error("`{key}`: {problem}")]
    NotForF16 {
        /// The dotted key at fault.
        key: String,
        /// What is wrong.
        problem: String,
    },
}

impl From<InitialError> for SetupError {
    fn from(e: InitialError) -> Self {
        match e {
            InitialError::Trim(e) => Self::Trim(e),
            InitialError::NoThrottle { at_idle, at_full } => Self::NoThrottle { at_idle, at_full },
            InitialError::OutsideEnvelope(e) => Self::OutsideEnvelope(e),
        }
    }
}

/// A flight that left the envelope, the actuator positions and commands of a step: the vehicle's own
/// ([`silrig_model::vehicle`]), kept here under their old names.
pub use silrig_model::vehicle::{ActuatorCommand, HeldActuators, LeftEnvelope, StepHits};

/// Why a closed-loop run did not fly its whole scenario.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// It could not start.
    #[error(transparent)]
    Setup(#[from] SetupError),
    /// It left the model's envelope; `trace` holds the flight up to the last sample inside.
    #[error("{exit} (the trace ends at the sample before)")]
    LeftEnvelope {
        /// When and why.
        exit: LeftEnvelope,
        /// The flight so far.
        trace: Box<Trace>,
    },
}

pub use crate::f16_signals::{PlantSnapshot, measured_columns};

/// Mixed into `scenario.seed` for the sensor-noise stream, so another random source seeded from the same scenario
/// seed never draws the same sequence as the noise.
const SENSOR_NOISE_STREAM: u64 = 0x5E45_0A15_E000_0001;

/// A sensor fault of the plan, resolved to a state index.
#[derive(Debug, Clone)]
struct SensorFault {
    /// The plan entry (for its window).
    fault: Fault,
    /// Index of the channel in [`F16State::to_array`].
    index: usize,
    /// Constant offset, or the standard deviation of Gaussian noise, in the channel's unit.
    kind: SensorFaultKind,
}

/// What a sensor fault adds to its channel.
#[derive(Debug, Clone, Copy)]
enum SensorFaultKind {
    /// A constant offset.
    Bias(f64),
    /// Gaussian noise of this standard deviation, one draw per tick.
    Noise { std: f64 },
}

/// An actuator fault of the plan, resolved to a surface index and mode.
#[derive(Debug, Clone)]
struct SurfaceFault {
    /// The plan entry (for its window).
    fault: Fault,
    /// 0 aileron, 1 elevator, 2 rudder (the order of [`PlantRunner`]'s actuators).
    surface: usize,
    /// The failure mode while the window is open.
    mode: ActuatorFault,
}

/// The plant side of the loop: the vehicle (model, actuators and state, [`F16Vehicle`]) with the scenario's
/// disturbance and plant-model faults around it.
///
/// It carries the scenario's plant-model faults. Sensor noise comes from one SplitMix64 stream seeded from
/// `scenario.seed`, drawn once per tick per active noise fault (in plan order) when that tick's state becomes
/// current, not when it is read: the reported sample is a function of the tick alone, however often
/// [`PlantRunner::snapshot`] is called, so `silrig sim` and the rig's plant report the same bits.
#[derive(Debug, Clone)]
pub struct PlantRunner {
    /// Model, holds, actuators, the true state and the tick.
    vehicle: F16Vehicle,
    disturbance: crate::scenario::Disturbance,
    disturbance_mask: [bool; 3],
    /// The vehicle's state as the sensors report it at its tick (equal to it while no sensor fault is active).
    measured: F16State,
    sensor_faults: Vec<SensorFault>,
    surface_faults: Vec<SurfaceFault>,
    noise: SplitMix64,
}

/// What the built-in vehicle the scenario names can check before it flies: [`check_for_f16`], or the quadrotor's
/// [`crate::quad::check_for_quad`]. On error (dotted key, problem).
pub fn check_builtin(s: &Scenario) -> Result<(), (String, String)> {
    if crate::quad::is_quad(s) { crate::quad::check_for_quad(s) } else { check_for_f16(s) }
}

/// What only the built-in F-16 can check: `[actuators]` names its inputs within their travel, sensor and
/// actuator faults name its channels and surfaces, and `[plant.parameters]` (a plant of your own's) is empty.
/// On error (dotted key, problem).
pub fn check_for_f16(s: &Scenario) -> Result<(), (String, String)> {
    if crate::quad::is_quad(s) {
        return Err((
            "plant.model".into(),
            "is \"quad\": this flies the built-in F-16 only; the quadrotor flies in `silrig sim`, `run`, `sweep` \
             and `check`"
                .into(),
        ));
    }
    if let Some(fmu) = &s.plant.fmu {
        return Err((
            "plant.fmu".into(),
            format!(
                "{} is a plant of your own: it flies in the rig (`silrig run`, `silrig check`), not in place of \
                 the built-in F-16 in one process",
                fmu.display()
            ),
        ));
    }
    for (name, a) in &s.actuators {
        let Some((input, key, travel)) = crate::scenario::F16_ACTUATORS.iter().find(|(i, k, _)| i == name || k == name)
        else {
            let names: Vec<&str> = crate::scenario::F16_ACTUATORS.iter().map(|(i, _, _)| *i).collect();
            return Err((
                format!("actuators.{name}"),
                format!("the F-16 has no input `{name}`; its inputs: {}", names.join(", ")),
            ));
        };
        if input != key && s.actuators.contains_key(*input) && s.actuators.contains_key(*key) {
            return Err((format!("actuators.{key}"), format!("is `actuators.{input}` again: give one of the two")));
        }
        a.validate(*travel).map_err(|e| (format!("actuators.{name}"), e))?;
    }
    let outputs: Vec<String> = crate::f16_signals::f16_signals([0.0; 4]).outputs.into_iter().map(|o| o.name).collect();
    if let Some(name) = s.setpoint.outputs.keys().find(|n| !outputs.contains(n)) {
        return Err((
            format!("setpoint.{name}"),
            format!("the F-16 has no output `{name}`; its outputs: {}", outputs.join(", ")),
        ));
    }
    if let Some(name) = s.plant.parameters.keys().next() {
        return Err((
            format!("plant.parameters.{name}"),
            "is for a plant of your own (--plant-cmd, --plant external); the F-16's parameters are plant.xcg, \
             plant.mass_scale and plant.aero_scale"
                .into(),
        ));
    }
    for (i, f) in s.faults.iter().enumerate() {
        f.check_names("the F-16", &crate::fault::SENSOR_CHANNELS, &crate::fault::SURFACES)
            .map_err(|(key, problem)| (format!("faults[{i}].{key}"), problem))?;
    }
    Ok(())
}

impl PlantRunner {
    /// The plant at the scenario's initial condition.
    pub fn new(s: &Scenario) -> Result<Self, SetupError> {
        let forcing = ExternalForcing {
            speed_hold: s.plant.speed_hold,
            sideslip_hold: s.plant.sideslip_hold,
            ..Default::default()
        };
        let vehicle = F16Vehicle::new(s.plant.model(), &s.initial, &s.f16_actuators(), forcing, s.timing.dt_s)?;
        for (index, f) in s.faults.iter().enumerate() {
            if f.action.is_some_and(FaultAction::is_plant_model_fault) {
                f.validate(s.timing.duration_s).map_err(|(key, problem)| SetupError::Fault { index, key, problem })?;
            }
        }
        check_for_f16(s).map_err(|(key, problem)| SetupError::NotForF16 { key, problem })?;
        let (sensor_faults, surface_faults) = plant_model_faults(&s.faults);
        let mut runner = Self {
            measured: vehicle.state(),
            vehicle,
            disturbance: s.disturbance.clone(),
            disturbance_mask: s.disturbance.channel_mask(),
            sensor_faults,
            surface_faults,
            noise: SplitMix64::new(s.seed ^ SENSOR_NOISE_STREAM),
        };
        runner.measure();
        Ok(runner)
    }

    /// Simulated time of the current tick, s (what fault windows are judged on).
    fn t_s(&self) -> f64 {
        self.vehicle.t_s()
    }

    /// Set `measured` for the current tick: the true state plus every active sensor fault. Called exactly once per
    /// tick, so each active noise fault draws exactly one sample per tick.
    fn measure(&mut self) {
        if self.sensor_faults.is_empty() {
            self.measured = self.vehicle.state();
            return;
        }
        let t = self.t_s();
        let mut x = self.vehicle.state().to_array();
        for f in &self.sensor_faults {
            if f.fault.active_at(t) {
                x[f.index] += match f.kind {
                    SensorFaultKind::Bias(b) => b,
                    SensorFaultKind::Noise { std } => std * self.noise.normal(),
                };
            }
        }
        self.measured = F16State::from_array(&x);
    }

    /// The failure mode of each surface (aileron, elevator, rudder) over the step starting at the current tick.
    /// Where windows overlap on one surface, the fault that started last wins (the later plan entry on a tie).
    fn surface_modes(&self) -> [ActuatorFault; 3] {
        let t = self.t_s();
        let mut modes = [ActuatorFault::None; 3];
        let mut since = [f64::NEG_INFINITY; 3];
        for f in &self.surface_faults {
            if f.fault.active_at(t) && f.fault.at_s >= since[f.surface] {
                modes[f.surface] = f.mode;
                since[f.surface] = f.fault.at_s;
            }
        }
        modes
    }

    /// The true, integrated state now, as no sensor fault distorts it (what [`PlantRunner::snapshot`] reports
    /// while no sensor fault is active).
    pub fn true_state(&self) -> F16State {
        self.vehicle.state()
    }

    /// The command that holds the initial surfaces and throttle (used before any controller command exists).
    pub fn initial_command(&self) -> ActuatorCommand {
        self.vehicle.initial_command()
    }

    /// The state as measured (with any active sensor fault), the surface positions now, and the load factors of
    /// the true state with them (one evaluation of the equations of motion). The same however often it is called
    /// within a tick: the sensor noise of a tick is drawn when the tick begins.
    pub fn snapshot(&self) -> PlantSnapshot {
        self.vehicle.snapshot(self.measured, self.disturbance.at(self.t_s(), &self.disturbance_mask))
    }

    /// The actuator positions now.
    pub fn held(&self) -> HeldActuators {
        self.vehicle.held()
    }

    /// Move the actuators under `command` (each surface in the failure mode its active fault gives, if any) to the
    /// positions they hold over the step that starts at the current tick. [`PlantRunner::step`] does this first; on
    /// its own it serves the last sample of a run, whose deflections are logged but not flown.
    pub fn actuate(&mut self, command: &ActuatorCommand) -> StepHits {
        let modes = if self.surface_faults.is_empty() { [ActuatorFault::None; 3] } else { self.surface_modes() };
        self.vehicle.actuate(command, modes)
    }

    /// Move the actuators under `command` ([`PlantRunner::actuate`]) and integrate one step with their positions
    /// held; then take the next tick's measurement. A new state outside the model's envelope is not taken: the
    /// plant stays at the current tick (with the actuators moved) and the flight is over.
    pub fn step(&mut self, command: &ActuatorCommand) -> Result<StepHits, LeftEnvelope> {
        let hits = self.actuate(command);
        let (dist, mask) = (&self.disturbance, &self.disturbance_mask);
        self.vehicle.integrate(|t| dist.at(t, mask))?;
        self.measure();
        Ok(hits)
    }
}

/// What a plant process saves so that a restarted plant continues the same flight.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlantCheckpoint {
    /// The next tick to run.
    pub tick: u64,
    /// The true state at that tick (not the measured one).
    pub state: F16State,
    /// Actuator positions: aileron, elevator, rudder (deg), throttle.
    pub actuator_positions: [f64; 4],
}

impl PlantRunner {
    /// The state to save now.
    pub fn checkpoint(&self) -> PlantCheckpoint {
        let held = self.vehicle.held();
        PlantCheckpoint {
            tick: self.vehicle.tick(),
            state: self.vehicle.state(),
            actuator_positions: [held.surfaces_deg[0], held.surfaces_deg[1], held.surfaces_deg[2], held.throttle],
        }
    }

    /// Continue from a saved checkpoint of a run of `ticks` ticks. A checkpoint that could not have come from this
    /// run (a tick beyond it, a state outside the model's envelope, a surface beyond its travel) is refused with
    /// the field and the range, and the runner is left as it was.
    pub fn restore(&mut self, c: &PlantCheckpoint, ticks: u64) -> Result<(), String> {
        if c.tick >= ticks {
            return Err(format!("tick {} is beyond the run's {ticks} ticks", c.tick));
        }
        let x = &c.state;
        use silrig_model::units::readable;
        let deg = f64::to_radians;
        let envelope = [
            ("vt_fps", x.vt_fps, 1.0, 5_000.0),
            // The model flies any alpha (only |beta| is bounded): a tumbling aircraft passes 90 deg, and its
            // checkpoint must resume (the soak's plant, restarted at alpha -139 deg, could not).
            ("alpha_rad", x.alpha_rad, -1e3, 1e3),
            ("beta_rad", x.beta_rad, -deg(90.0), deg(90.0)),
            ("phi_rad", x.phi_rad, -1e3, 1e3),
            ("theta_rad", x.theta_rad, -deg(90.0), deg(90.0)),
            ("psi_rad", x.psi_rad, -1e3, 1e3),
            ("p_radps", x.p_radps, -100.0, 100.0),
            ("q_radps", x.q_radps, -100.0, 100.0),
            ("r_radps", x.r_radps, -100.0, 100.0),
            ("north_ft", x.north_ft, -1e9, 1e9),
            ("east_ft", x.east_ft, -1e9, 1e9),
            ("alt_ft", x.alt_ft, -1e4, 1e6),
            ("power_pct", x.power_pct, 0.0, 100.0),
        ];
        for (field, value, lo, hi) in envelope {
            if !(lo..=hi).contains(&value) {
                let (value, lo, hi) = (readable(value), readable(lo), readable(hi));
                return Err(format!("state.{field} = {value} is outside {lo}..{hi}"));
            }
        }
        for ((a, p), name) in
            self.vehicle.actuators().iter().zip(c.actuator_positions).zip(["aileron", "elevator", "rudder", "throttle"])
        {
            if !(a.limits.min..=a.limits.max).contains(&p) {
                return Err(format!(
                    "{name} position {} is outside its travel {}..{}",
                    readable(p),
                    a.limits.min,
                    a.limits.max
                ));
            }
        }
        self.vehicle.restore(c.tick, c.state, c.actuator_positions);
        // The noise sequence of a restarted plant is not the one the killed plant would have drawn.
        self.measure();
        Ok(())
    }
}

/// The plant-model faults of a plan, resolved once so the loop does no string lookups. Other faults (process and
/// loop faults) are left to the launcher and the processes. Expects validated entries (channel and surface names
/// known, `std`, `bias` and `limit` given where required); [`PlantRunner::new`] checks that first.
fn plant_model_faults(plan: &[Fault]) -> (Vec<SensorFault>, Vec<SurfaceFault>) {
    let (mut sensors, mut surfaces) = (Vec::new(), Vec::new());
    for f in plan.iter().filter(|f| f.action.is_some_and(FaultAction::is_plant_model_fault)) {
        let channel = f.channel.as_deref().filter(|c| SENSOR_CHANNELS.contains(c));
        let index = channel.and_then(|c| STATE_NAMES.iter().position(|n| *n == c));
        // SURFACES lists aileron, elevator, rudder: the order of the runner's actuators.
        let surface = f.surface.as_deref().and_then(|s| SURFACES.iter().position(|n| *n == s));
        let sensor = |kind| index.map(|index| SensorFault { fault: f.clone(), index, kind });
        let actuator = |mode| surface.map(|surface| SurfaceFault { fault: f.clone(), surface, mode });
        match f.action() {
            FaultAction::SensorBias => sensors.extend(f.bias.and_then(|b| sensor(SensorFaultKind::Bias(b)))),
            FaultAction::SensorNoise => sensors.extend(f.std.and_then(|std| sensor(SensorFaultKind::Noise { std }))),
            FaultAction::ActuatorStuck => surfaces.extend(actuator(ActuatorFault::Stuck)),
            FaultAction::ActuatorRateFrozen => surfaces.extend(actuator(ActuatorFault::RateFrozen)),
            FaultAction::ActuatorHardOver => {
                let to_max = match f.limit.as_deref() {
                    Some("max") => Some(true),
                    Some("min") => Some(false),
                    _ => None,
                };
                surfaces.extend(to_max.and_then(|to_max| actuator(ActuatorFault::HardOver { to_max })));
            }
            _ => {}
        }
    }
    (sensors, surfaces)
}

/// What the controller sees of a plant snapshot.
#[inline]
pub fn measurement(s: &PlantSnapshot) -> Measurement {
    Measurement {
        euler_rad: [s.state.phi_rad, s.state.theta_rad, s.state.psi_rad],
        body_rates_radps: [s.state.p_radps, s.state.q_radps, s.state.r_radps],
        vt_fps: s.state.vt_fps,
        alt_ft: s.state.alt_ft,
    }
}

/// The loop part of a `trace.csv` row ([`crate::trace::LOOP_COLUMNS`]): the snapshot at t_k, the controller's
/// command computed from it, and the actuator positions held over [t_k, t_k+1) (the positions the plant reports
/// with its next sample, or after the last tick's [`PlantRunner::actuate`]); the controller's diagnostics follow.
pub fn trace_row(
    snap: &PlantSnapshot,
    held: &HeldActuators,
    command: &SurfaceCommand,
    flight_segment: u32,
    diagnostics: &[f64],
) -> Vec<f64> {
    let mut row = Vec::with_capacity(trace::LOOP_COLUMNS.len() + diagnostics.len());
    row.push(snap.t_s);
    row.extend_from_slice(&measured_columns(snap));
    row.extend_from_slice(&[
        command.aileron_deg,
        command.elevator_deg,
        command.rudder_deg,
        held.surfaces_deg[0],
        held.surfaces_deg[1],
        held.surfaces_deg[2],
        held.throttle,
        f64::from(flight_segment),
    ]);
    row.extend_from_slice(diagnostics);
    row
}

/// Write the paper's controller's diagnostics of one step into `out`, in the order of
/// [`crate::trace::attitude_diagnostic_names`]: S and f_hat per channel, then the weights after this step's
/// adaptation, channel by channel. Returns how many were written; `out` must hold as many as there are names.
pub fn write_attitude_diagnostics(
    out: &mut [f64],
    diag: &ControllerDiagnostics,
    controller: &AttitudeController,
) -> usize {
    out[..3].copy_from_slice(&diag.sliding_surface);
    out[3..6].copy_from_slice(&diag.f_hat);
    let mut n = 6;
    for net in controller.networks() {
        out[n..n + net.weights.len()].copy_from_slice(&net.weights);
        n += net.weights.len();
    }
    n
}

/// Our controller for `s`: its gains, the nominal control derivatives from `tables`, and the travel of the
/// scenario's surfaces, which its anti-windup compares each demand with.
pub fn attitude_controller(s: &Scenario, tables: &F16Tables) -> AttitudeController {
    let a = s.f16_actuators();
    let travel_deg = [a.aileron_deg, a.elevator_deg, a.rudder_deg].map(|l| (l.min, l.max));
    AttitudeController::new(s.controller.gains.clone(), tables).with_travel(travel_deg)
}

/// The attitude set points in force at `t_s`, rad. Without steps, the same numbers at every tick.
pub fn setpoint_rad(attitude: &[SetpointTrack; 3], t_s: f64) -> [f64; 3] {
    [0, 1, 2].map(|c| deg_to_rad(attitude[c].at(t_s)))
}

/// Run a scenario's closed loop as far as it flies: its trace, and how it left the model's envelope if it did
/// (the trace then ends at the last sample inside).
pub fn fly(s: &Scenario) -> Result<(Trace, Option<LeftEnvelope>), SetupError> {
    match run(s) {
        Ok(trace) => Ok((trace, None)),
        Err(SimError::Setup(e)) => Err(e),
        Err(SimError::LeftEnvelope { exit, trace }) => Ok((*trace, Some(exit))),
    }
}

/// Run a scenario's closed loop to the end and return its trace: N + 1 rows, t = 0 to the duration.
pub fn run(s: &Scenario) -> Result<Trace, SimError> {
    // This loop flies our controller: a scenario that names another must not quietly fly ours instead.
    if let Some(fmu) = &s.controller.fmu {
        return Err(SimError::Setup(SetupError::NotForF16 {
            key: "controller.fmu".into(),
            problem: format!(
                "{} is a controller of your own: it flies in the rig (`silrig run`, `silrig check`), not in place \
                 of ours in one process",
                fmu.display()
            ),
        }));
    }
    let mut plant = PlantRunner::new(s)?;
    let mut controller = attitude_controller(s, plant.vehicle.model().tables());
    let attitude = s.attitude_setpoints();
    let dt = s.timing.dt_s;
    let steps = s.timing.ticks();
    let mut trace = Trace::new(trace::columns(s.controller.rbf.nodes()));
    trace.rows.reserve(steps as usize + 1);
    // The commands computed but not yet acting, oldest first: the one computed `delay` ticks ago acts now.
    let delay = s.timing.command_delay_ticks() as usize;
    let mut pending = std::collections::VecDeque::with_capacity(delay + 1);
    let mut acting = plant.initial_command();
    let mut diagnostics = vec![0.0; trace.columns.len() - trace::LOOP_COLUMNS.len()];
    for tick in 0..=steps {
        let snap = plant.snapshot();
        let (surfaces, diag) = controller.step(&measurement(&snap), &setpoint_rad(&attitude, snap.t_s), dt);
        // Limited to what the plant accepts, as the rig's controller limits them (`AttitudeLaw`).
        let limit = silrig_model::actuator::SURFACE_CMD_LIMIT_DEG;
        let surfaces = surfaces.limited([(-limit, limit); 3]);
        write_attitude_diagnostics(&mut diagnostics, &diag, &controller);
        // The throttle is held: the controller commands surfaces only.
        pending.push_back(ActuatorCommand { surfaces, throttle: acting.throttle });
        if pending.len() > delay {
            acting = pending.pop_front().expect("not empty");
        }
        // The last sample's deflections are logged, but nothing is flown past the end.
        let stepped = if tick < steps {
            plant.step(&acting).map(drop)
        } else {
            plant.actuate(&acting);
            Ok(())
        };
        // One process, one flight: never a discontinuity.
        trace.rows.push(trace_row(&snap, &plant.held(), &surfaces, 0, &diagnostics));
        if let Err(exit) = stepped {
            return Err(SimError::LeftEnvelope { exit, trace: Box::new(trace) });
        }
    }
    Ok(trace)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_checkpoint_that_cannot_come_from_this_run_is_refused_naming_the_field() {
        let scenario = Scenario::embedded_default();
        let ticks = scenario.timing.ticks();
        let mut runner = PlantRunner::new(&scenario).unwrap();
        let good = runner.checkpoint();
        let refused = |edit: &dyn Fn(&mut PlantCheckpoint)| {
            let mut c = good;
            edit(&mut c);
            let mut r = PlantRunner::new(&scenario).unwrap();
            let before = r.checkpoint();
            let e = r.restore(&c, ticks).unwrap_err();
            assert_eq!(r.checkpoint(), before, "a refused checkpoint changed the runner");
            e
        };
        assert_eq!(
            refused(&|c| c.tick = 1_000_000_000_000),
            format!("tick 1000000000000 is beyond the run's {ticks} ticks")
        );
        assert_eq!(refused(&|c| c.state.vt_fps = 0.0), "state.vt_fps = 0 is outside 1..5000");
        assert_eq!(refused(&|c| c.state.alt_ft = f64::NAN), "state.alt_ft = NaN is outside -10000..1e6");
        assert_eq!(refused(&|c| c.state.q_radps = 1e300), "state.q_radps = 1e300 is outside -100..100");
        assert!(refused(&|c| c.actuator_positions[1] = 90.0).starts_with("elevator position 90 is outside its travel"));
        // A tumbling aircraft the model still flies resumes.
        let mut tumbling = good;
        tumbling.state.alpha_rad = (-139f64).to_radians();
        assert_eq!(PlantRunner::new(&scenario).unwrap().restore(&tumbling, ticks), Ok(()));
        let mut later = good;
        later.tick = 500;
        assert_eq!(runner.restore(&later, ticks), Ok(()));
        assert_eq!(runner.checkpoint().tick, 500);
    }
}
