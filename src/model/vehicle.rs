//! The F-16 as a vehicle stepped tick by tick, with nothing of a scenario file, fault plan or process around it: the
//! initial condition and its trim ([`InitialCondition`], [`initial_state`]), the four actuators, one RK4 step with
//! their positions held, the envelope check, and the snapshot of a tick ([`F16Vehicle`]). `silrig_flight`'s
//! `PlantRunner` (so `silrig sim` and the rig's plant) flies it with the scenario's faults and disturbance around
//! it; the FMU of `silrig-fmu-f16` flies it alone, so both step the same code.

use crate::actuator::{Actuator, ActuatorFault, ActuatorSetLimits, LimitHits};
use crate::control::SurfaceCommand;
use crate::f16_outputs::PlantSnapshot;
use crate::integrator::rk4_step;
use crate::plant::trim::{TrimError, trim_level_flight};
use crate::plant::{ControlInputs, ExternalForcing, F16Model, F16State, engine, envelope, envelope::EnvelopeError};
use crate::units::{deg_to_rad, m_to_ft};
use serde::{Deserialize, Serialize};

/// How the run starts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialCondition {
    /// `explicit`: every angle below is used as given; `trim`: alpha, theta, throttle and elevator come from the
    /// level-flight trim at this airspeed and altitude (phi, psi and the rates still from below).
    #[serde(default)]
    pub mode: InitialMode,
    /// True airspeed, m/s.
    pub airspeed_mps: f64,
    /// Altitude, ft.
    pub altitude_ft: f64,
    /// Angle of attack, deg (explicit mode).
    #[serde(default)]
    pub alpha_deg: f64,
    /// Sideslip, deg.
    #[serde(default)]
    pub beta_deg: f64,
    /// Roll angle, deg.
    #[serde(default)]
    pub phi_deg: f64,
    /// Pitch angle, deg (explicit mode).
    #[serde(default)]
    pub theta_deg: f64,
    /// Heading, deg.
    #[serde(default)]
    pub psi_deg: f64,
    /// Body roll rate, deg/s.
    #[serde(default)]
    pub p_dps: f64,
    /// Body pitch rate, deg/s.
    #[serde(default)]
    pub q_dps: f64,
    /// Body yaw rate, deg/s.
    #[serde(default)]
    pub r_dps: f64,
    /// Throttle 0..1; omitted: the value that gives VT_dot = 0 at the initial state with the engine at its
    /// equilibrium power (explicit mode), or the trim throttle.
    #[serde(default)]
    pub throttle: Option<f64>,
}

impl Default for InitialCondition {
    /// The embedded default scenario's: explicit, 150 m/s at 25,000 ft, alpha, phi, theta and psi 5 deg.
    fn default() -> Self {
        Self {
            mode: InitialMode::Explicit,
            airspeed_mps: 150.0,
            altitude_ft: 25_000.0,
            alpha_deg: 5.0,
            beta_deg: 0.0,
            phi_deg: 5.0,
            theta_deg: 5.0,
            psi_deg: 5.0,
            p_dps: 0.0,
            q_dps: 0.0,
            r_dps: 0.0,
            throttle: None,
        }
    }
}

/// Initial-condition mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InitialMode {
    /// Angles and rates as given.
    #[default]
    Explicit,
    /// Level-flight trim.
    Trim,
}

/// Why an initial condition gives no state to fly from.
#[derive(Debug, Clone, thiserror::Error)]
pub enum InitialError {
    /// The trim requested by the initial condition does not exist.
    #[error(transparent)]
    Trim(#[from] TrimError),
    /// No throttle in 0..1 holds the initial airspeed.
    #[error(
        "no throttle in 0..1 holds the airspeed (VT_dot is {at_idle:.2} ft/s^2 at throttle 0 and {at_full:.2} at 1); give initial.throttle explicitly"
    )]
    NoThrottle {
        /// VT_dot at throttle 0, ft/s^2.
        at_idle: f64,
        /// VT_dot at throttle 1, ft/s^2.
        at_full: f64,
    },
    /// The initial state is outside the model's envelope.
    #[error("outside the model's envelope: {0}")]
    OutsideEnvelope(#[from] EnvelopeError),
}

/// A flight that left the model's envelope: when, and which state.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the state left the model's envelope at t = {t_s:.2} s: {error}")]
pub struct LeftEnvelope {
    /// Simulated time of the first state outside, s (the flight is kept up to the sample before it).
    pub t_s: f64,
    /// The state at fault and why.
    pub error: EnvelopeError,
}

/// The actuator positions held over one step, as row k of the trace shows them: the deflections and throttle the
/// actuators took at t_k, acting until t_k+1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldActuators {
    /// Aileron, elevator, rudder, deg.
    pub surfaces_deg: [f64; 3],
    /// Throttle, 0..1.
    pub throttle: f64,
}

impl HeldActuators {
    /// Positions not known (the plant sample that carries them never came): NaN.
    pub const UNKNOWN: Self = Self { surfaces_deg: [f64::NAN; 3], throttle: f64::NAN };
}

/// What the actuators are told to do for one tick.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ActuatorCommand {
    /// Surface commands, deg.
    pub surfaces: SurfaceCommand,
    /// Throttle command, 0..1.
    pub throttle: f64,
}

/// Which limits bound each actuator in one step: aileron, elevator, rudder, throttle.
pub type StepHits = [LimitHits; 4];

/// Throttle that gives VT_dot = 0 at `state` with the engine at its equilibrium power, by bisection.
fn holding_throttle(model: &F16Model, state: &F16State, surfaces: &ControlInputs) -> Result<f64, InitialError> {
    let vt_dot = |throttle: f64| {
        let x = F16State { power_pct: engine::commanded_power_pct(throttle), ..*state };
        model.derivative(&x, &ControlInputs { throttle, ..*surfaces }, &ExternalForcing::default())[0]
    };
    let (at_idle, at_full) = (vt_dot(0.0), vt_dot(1.0));
    if !(at_idle <= 0.0 && at_full >= 0.0) {
        return Err(InitialError::NoThrottle { at_idle, at_full });
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if vt_dot(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    Ok(0.5 * (lo + hi))
}

/// The state an initial condition starts from, the surfaces (deg) and the throttle it starts with: as given, or
/// trimmed for level flight (see [`InitialMode`]), with the engine at the throttle's equilibrium power. The state
/// is checked against the model's envelope.
pub fn initial_state(model: &F16Model, i: &InitialCondition) -> Result<(F16State, ControlInputs, f64), InitialError> {
    let vt_fps = m_to_ft(i.airspeed_mps);
    let mut state = F16State {
        vt_fps,
        alpha_rad: deg_to_rad(i.alpha_deg),
        beta_rad: deg_to_rad(i.beta_deg),
        phi_rad: deg_to_rad(i.phi_deg),
        theta_rad: deg_to_rad(i.theta_deg),
        psi_rad: deg_to_rad(i.psi_deg),
        p_radps: deg_to_rad(i.p_dps),
        q_radps: deg_to_rad(i.q_dps),
        r_radps: deg_to_rad(i.r_dps),
        north_ft: 0.0,
        east_ft: 0.0,
        alt_ft: i.altitude_ft,
        power_pct: 0.0,
    };
    let mut surfaces = ControlInputs::default();
    let throttle = match i.mode {
        InitialMode::Explicit => match i.throttle {
            Some(t) => t,
            None => holding_throttle(model, &state, &surfaces)?,
        },
        InitialMode::Trim => {
            let trim = trim_level_flight(model, vt_fps, i.altitude_ft)?;
            state.alpha_rad = trim.state.alpha_rad;
            state.theta_rad = trim.state.theta_rad;
            surfaces.elevator_deg = trim.elevator_deg;
            i.throttle.unwrap_or(trim.throttle)
        }
    };
    state.power_pct = engine::commanded_power_pct(throttle);
    envelope::check(&state)?;
    Ok((state, surfaces, throttle))
}

/// The F-16 with its actuators, stepped one tick at a time: model, forcing (the speed and sideslip holds), the four
/// actuators (aileron, elevator, rudder, throttle), the true state and the tick. Every step is a pure function of
/// these and the command, so a clone (or the fields a checkpoint saves) continues bit for bit.
#[derive(Debug, Clone)]
pub struct F16Vehicle {
    model: F16Model,
    /// The holds; the disturbance of a step comes from the caller, per RK4 stage.
    forcing: ExternalForcing,
    /// Aileron, elevator, rudder, throttle.
    actuators: [Actuator; 4],
    /// The true, integrated state.
    state: F16State,
    tick: u64,
    dt_s: f64,
    initial_command: ActuatorCommand,
}

impl F16Vehicle {
    /// The vehicle at `initial` ([`initial_state`]), its actuators at rest where it starts (clamped into `limits`),
    /// flown with `forcing`'s holds (its disturbance is ignored: [`F16Vehicle::integrate`] takes one) at `dt_s`.
    pub fn new(
        model: F16Model,
        initial: &InitialCondition,
        limits: &ActuatorSetLimits,
        forcing: ExternalForcing,
        dt_s: f64,
    ) -> Result<Self, InitialError> {
        let (state, surfaces, throttle) = initial_state(&model, initial)?;
        let actuators = [
            Actuator::new(limits.aileron_deg, surfaces.aileron_deg),
            Actuator::new(limits.elevator_deg, surfaces.elevator_deg),
            Actuator::new(limits.rudder_deg, surfaces.rudder_deg),
            Actuator::new(limits.throttle, throttle),
        ];
        let initial_command = ActuatorCommand {
            surfaces: SurfaceCommand {
                aileron_deg: actuators[0].position,
                elevator_deg: actuators[1].position,
                rudder_deg: actuators[2].position,
            },
            throttle: actuators[3].position,
        };
        let forcing = ExternalForcing { euler_accel_disturbance_radps2: [0.0; 3], ..forcing };
        Ok(Self { model, forcing, actuators, state, tick: 0, dt_s, initial_command })
    }

    /// Step at `dt_s` from now on (an FMU learns its step from its importer's first step). The tick count stays,
    /// so [`F16Vehicle::t_s`] is `tick * dt_s` with the new step.
    pub fn set_dt_s(&mut self, dt_s: f64) {
        self.dt_s = dt_s;
    }

    /// The model it flies.
    pub fn model(&self) -> &F16Model {
        &self.model
    }

    /// The tick its state belongs to.
    pub fn tick(&self) -> u64 {
        self.tick
    }

    /// The step, s.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// Simulated time of the current tick, s (`tick * dt`: what fault windows and the disturbance are judged on).
    pub fn t_s(&self) -> f64 {
        self.tick as f64 * self.dt_s
    }

    /// The true, integrated state now.
    pub fn state(&self) -> F16State {
        self.state
    }

    /// The four actuators: aileron, elevator, rudder, throttle.
    pub fn actuators(&self) -> &[Actuator; 4] {
        &self.actuators
    }

    /// The command that holds the initial surfaces and throttle (used before any controller command exists).
    pub fn initial_command(&self) -> ActuatorCommand {
        self.initial_command
    }

    /// The actuator positions now.
    pub fn held(&self) -> HeldActuators {
        HeldActuators {
            surfaces_deg: [self.actuators[0].position, self.actuators[1].position, self.actuators[2].position],
            throttle: self.actuators[3].position,
        }
    }

    /// The actuator positions as the equations of motion take them.
    pub fn inputs(&self) -> ControlInputs {
        ControlInputs {
            aileron_deg: self.actuators[0].position,
            elevator_deg: self.actuators[1].position,
            rudder_deg: self.actuators[2].position,
            throttle: self.actuators[3].position,
        }
    }

    /// The snapshot of the current tick: `measured` as the reported state, the actuator positions now, and the load
    /// factors of the true state with them under `disturbance` (rad/s^2 on the Euler-angle accelerations, at
    /// [`F16Vehicle::t_s`]): one evaluation of the equations of motion.
    pub fn snapshot(&self, measured: F16State, disturbance: [f64; 3]) -> PlantSnapshot {
        let held = self.held();
        let forcing = ExternalForcing { euler_accel_disturbance_radps2: disturbance, ..self.forcing };
        let (_, outputs) = self.model.derivative_with_outputs(&self.state, &self.inputs(), &forcing);
        PlantSnapshot {
            tick: self.tick,
            t_s: self.t_s(),
            state: measured,
            surfaces_deg: held.surfaces_deg,
            throttle: held.throttle,
            nz_g: outputs.nz_g,
            ny_g: outputs.ny_g,
        }
    }

    /// Move the actuators under `command` to the positions they hold over the step that starts at the current
    /// tick, each surface (aileron, elevator, rudder) in failure mode `modes[k]`; the throttle never fails.
    pub fn actuate(&mut self, command: &ActuatorCommand, modes: [ActuatorFault; 3]) -> StepHits {
        let dt = self.dt_s;
        let c = &command.surfaces;
        [
            self.actuators[0].update_with_fault(c.aileron_deg, dt, modes[0]),
            self.actuators[1].update_with_fault(c.elevator_deg, dt, modes[1]),
            self.actuators[2].update_with_fault(c.rudder_deg, dt, modes[2]),
            self.actuators[3].update(command.throttle, dt),
        ]
    }

    /// Integrate one step with the actuators' positions held and `disturbance(t)` (rad/s^2 on the Euler-angle
    /// accelerations) at each RK4 stage, and advance the tick. A new state outside the model's envelope is not
    /// taken: the vehicle stays at the current tick and the flight is over.
    pub fn integrate(&mut self, disturbance: impl Fn(f64) -> [f64; 3]) -> Result<(), LeftEnvelope> {
        let dt = self.dt_s;
        let inputs = self.inputs();
        let t0 = self.tick as f64 * dt;
        let (model, base) = (&self.model, self.forcing);
        let x = rk4_step(
            |t, x| {
                let forcing = ExternalForcing { euler_accel_disturbance_radps2: disturbance(t), ..base };
                model.derivative(&F16State::from_array(x), &inputs, &forcing)
            },
            t0,
            &self.state.to_array(),
            dt,
        );
        let next = F16State::from_array(&x);
        envelope::check(&next).map_err(|error| LeftEnvelope { t_s: t0 + dt, error })?;
        self.state = next;
        self.tick += 1;
        Ok(())
    }

    /// One tick with no fault and no disturbance: [`F16Vehicle::actuate`] then [`F16Vehicle::integrate`].
    pub fn step(&mut self, command: &ActuatorCommand) -> Result<StepHits, LeftEnvelope> {
        let hits = self.actuate(command, [ActuatorFault::None; 3]);
        self.integrate(|_| [0.0; 3])?;
        Ok(hits)
    }

    /// Continue from `tick` with `state` and the actuators at `positions` (aileron, elevator, rudder, throttle),
    /// as saved by a checkpoint. The caller checks them first: this only sets them.
    pub fn restore(&mut self, tick: u64, state: F16State, positions: [f64; 4]) {
        self.tick = tick;
        self.state = state;
        for (a, p) in self.actuators.iter_mut().zip(positions) {
            a.position = p;
        }
    }
}

/// What the F-16's failsafe commands, and what it announces as its inputs' hold values: the level-flight trim
/// surfaces (aileron and rudder 0, the trim elevator) of `initial`'s airspeed and altitude with the throttle of
/// `hold`, or `hold` itself (the command that holds the initial surfaces) when level flight has no trim there.
pub fn failsafe_command(model: &F16Model, initial: &InitialCondition, hold: ActuatorCommand) -> ActuatorCommand {
    let vt_fps = m_to_ft(initial.airspeed_mps);
    match trim_level_flight(model, vt_fps, initial.altitude_ft) {
        Ok(trim) => ActuatorCommand {
            surfaces: SurfaceCommand { aileron_deg: 0.0, elevator_deg: trim.elevator_deg, rudder_deg: 0.0 },
            throttle: hold.throttle,
        },
        Err(_) => hold,
    }
}
