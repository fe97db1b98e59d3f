//! The closed loop in one process: plant, actuators and controller stepped in lockstep with no clock, so two runs
//! of one scenario give bit-identical traces. The multi-process rig reuses [`PlantRunner`], [`measurement`] and
//! [`trace_row`], so both produce the same trace.
//!
//! Tick k: the plant's snapshot at t_k (state and the surface positions the actuators hold at t_k) goes to the
//! controller; its command acts from tick k (`same-tick`) or from tick k+1 (`next-tick`); the actuators then move
//! over [t_k, t_k+1) under the applied command, and RK4 integrates the plant over that step with the new surface
//! positions and the throttle held.

use crate::actuator::{Actuator, LimitHits};
use crate::control::{AttitudeController, ControllerDiagnostics, Measurement, SurfaceCommand};
use crate::integrator::rk4_step;
use crate::plant::trim::trim_level_flight;
use crate::plant::{ControlInputs, ExternalForcing, F16Model, F16State, engine};
use crate::scenario::{CommandTiming, InitialMode, Scenario};
use crate::trace::{self, Trace};
use crate::units::{M_PER_FT, deg_to_rad, m_to_ft, rad_to_deg};

/// Why a scenario cannot start.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// The trim requested by the initial condition does not exist.
    #[error("initial condition: {0}")]
    Trim(#[from] crate::plant::trim::TrimError),
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
}

/// What the plant reports each tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantSnapshot {
    /// Tick index.
    pub tick: u64,
    /// Simulated time, s.
    pub t_s: f64,
    /// The 13 states.
    pub state: F16State,
    /// Surface positions held by the actuators at t_s: aileron, elevator, rudder, deg.
    pub surfaces_deg: [f64; 3],
    /// Throttle position, 0..1.
    pub throttle: f64,
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

/// The plant side of the loop: model, actuators and state.
#[derive(Debug, Clone)]
pub struct PlantRunner {
    model: F16Model,
    forcing: ExternalForcing,
    disturbance: crate::scenario::Disturbance,
    disturbance_mask: [bool; 3],
    /// Aileron, elevator, rudder, throttle.
    actuators: [Actuator; 4],
    state: F16State,
    tick: u64,
    dt_s: f64,
    initial_command: ActuatorCommand,
}

/// Throttle that gives VT_dot = 0 at `state` with the engine at its equilibrium power, by bisection.
fn holding_throttle(model: &F16Model, state: &F16State, surfaces: &ControlInputs) -> Result<f64, SetupError> {
    let vt_dot = |throttle: f64| {
        let x = F16State { power_pct: engine::commanded_power_pct(throttle), ..*state };
        model.derivative(&x, &ControlInputs { throttle, ..*surfaces }, &ExternalForcing::default())[0]
    };
    let (at_idle, at_full) = (vt_dot(0.0), vt_dot(1.0));
    if !(at_idle <= 0.0 && at_full >= 0.0) {
        return Err(SetupError::NoThrottle { at_idle, at_full });
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if vt_dot(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    Ok(0.5 * (lo + hi))
}

impl PlantRunner {
    /// The plant at the scenario's initial condition.
    pub fn new(s: &Scenario) -> Result<Self, SetupError> {
        let model = F16Model::new(s.plant.xcg);
        let i = &s.initial;
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
                None => holding_throttle(&model, &state, &surfaces)?,
            },
            InitialMode::Trim => {
                let trim = trim_level_flight(&model, vt_fps, i.altitude_ft)?;
                state.alpha_rad = trim.state.alpha_rad;
                state.theta_rad = trim.state.theta_rad;
                surfaces.elevator_deg = trim.elevator_deg;
                i.throttle.unwrap_or(trim.throttle)
            }
        };
        state.power_pct = engine::commanded_power_pct(throttle);
        let a = &s.actuators;
        let actuators = [
            Actuator::new(a.aileron_deg, surfaces.aileron_deg),
            Actuator::new(a.elevator_deg, surfaces.elevator_deg),
            Actuator::new(a.rudder_deg, surfaces.rudder_deg),
            Actuator::new(a.throttle, throttle),
        ];
        let initial_command = ActuatorCommand {
            surfaces: SurfaceCommand {
                aileron_deg: actuators[0].position,
                elevator_deg: actuators[1].position,
                rudder_deg: actuators[2].position,
            },
            throttle: actuators[3].position,
        };
        Ok(Self {
            model,
            forcing: ExternalForcing { speed_hold: s.plant.speed_hold, ..Default::default() },
            disturbance: s.disturbance.clone(),
            disturbance_mask: s.disturbance.channel_mask(),
            actuators,
            state,
            tick: 0,
            dt_s: s.timing.dt_s,
            initial_command,
        })
    }

    /// The command that holds the initial surfaces and throttle (used before any controller command exists).
    pub fn initial_command(&self) -> ActuatorCommand {
        self.initial_command
    }

    /// The state and surface positions now.
    pub fn snapshot(&self) -> PlantSnapshot {
        PlantSnapshot {
            tick: self.tick,
            t_s: self.tick as f64 * self.dt_s,
            state: self.state,
            surfaces_deg: [self.actuators[0].position, self.actuators[1].position, self.actuators[2].position],
            throttle: self.actuators[3].position,
        }
    }

    /// Move the actuators under `command` and integrate one step.
    pub fn step(&mut self, command: &ActuatorCommand) -> StepHits {
        let dt = self.dt_s;
        let c = &command.surfaces;
        let hits = [
            self.actuators[0].update(c.aileron_deg, dt),
            self.actuators[1].update(c.elevator_deg, dt),
            self.actuators[2].update(c.rudder_deg, dt),
            self.actuators[3].update(command.throttle, dt),
        ];
        let inputs = ControlInputs {
            aileron_deg: self.actuators[0].position,
            elevator_deg: self.actuators[1].position,
            rudder_deg: self.actuators[2].position,
            throttle: self.actuators[3].position,
        };
        let t0 = self.tick as f64 * dt;
        let (model, base, dist, mask) = (&self.model, self.forcing, &self.disturbance, &self.disturbance_mask);
        let x = rk4_step(
            |t, x| {
                let forcing = ExternalForcing { euler_accel_disturbance_radps2: dist.at(t, mask), ..base };
                model.derivative(&F16State::from_array(x), &inputs, &forcing)
            },
            t0,
            &self.state.to_array(),
            dt,
        );
        self.state = F16State::from_array(&x);
        self.tick += 1;
        hits
    }
}

/// What a plant process saves so that a restarted plant continues the same flight.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlantCheckpoint {
    /// The next tick to run.
    pub tick: u64,
    /// The true state at that tick.
    pub state: F16State,
    /// Actuator positions: aileron, elevator, rudder (deg), throttle.
    pub actuator_positions: [f64; 4],
}

impl PlantRunner {
    /// The state to save now.
    pub fn checkpoint(&self) -> PlantCheckpoint {
        PlantCheckpoint {
            tick: self.tick,
            state: self.state,
            actuator_positions: [
                self.actuators[0].position,
                self.actuators[1].position,
                self.actuators[2].position,
                self.actuators[3].position,
            ],
        }
    }

    /// Continue from a saved checkpoint.
    pub fn restore(&mut self, c: &PlantCheckpoint) {
        self.tick = c.tick;
        self.state = c.state;
        for (a, p) in self.actuators.iter_mut().zip(c.actuator_positions) {
            a.position = p.clamp(a.limits.min, a.limits.max);
        }
    }
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

/// One `trace.csv` row (see [`crate::trace::columns`]): the snapshot at t_k, the controller's command and
/// diagnostics for that tick, and the weights after that tick's adaptation.
pub fn trace_row(
    snap: &PlantSnapshot,
    command: &SurfaceCommand,
    diag: &ControllerDiagnostics,
    weights: [&[f64]; 3],
) -> Vec<f64> {
    let x = &snap.state;
    let mut row = Vec::with_capacity(trace::BASE_COLUMNS.len() + 3 * weights[0].len());
    row.extend_from_slice(&[
        snap.t_s,
        rad_to_deg(x.phi_rad),
        rad_to_deg(x.theta_rad),
        rad_to_deg(x.psi_rad),
        rad_to_deg(x.alpha_rad),
        rad_to_deg(x.beta_rad),
        rad_to_deg(x.p_radps),
        rad_to_deg(x.q_radps),
        rad_to_deg(x.r_radps),
        x.vt_fps * M_PER_FT,
        x.alt_ft,
        command.aileron_deg,
        command.elevator_deg,
        command.rudder_deg,
        snap.surfaces_deg[0],
        snap.surfaces_deg[1],
        snap.surfaces_deg[2],
        snap.throttle,
    ]);
    row.extend_from_slice(&diag.sliding_surface);
    row.extend_from_slice(&diag.f_hat);
    for w in weights {
        row.extend_from_slice(w);
    }
    row
}

/// The set points in rad.
pub fn setpoint_rad(s: &Scenario) -> [f64; 3] {
    [deg_to_rad(s.setpoint.phi_deg), deg_to_rad(s.setpoint.theta_deg), deg_to_rad(s.setpoint.psi_deg)]
}

/// Run a scenario's closed loop to the end and return its trace.
pub fn run(s: &Scenario) -> Result<Trace, SetupError> {
    let mut plant = PlantRunner::new(s)?;
    let mut controller = AttitudeController::new(s.controller.clone(), plant.model.tables());
    let setpoint = setpoint_rad(s);
    let dt = s.timing.dt_s;
    let ticks = s.timing.ticks();
    let mut trace = Trace::new(trace::columns(s.controller.rbf.nodes()));
    trace.rows.reserve(ticks as usize);
    let mut previous = plant.initial_command();
    for _ in 0..ticks {
        let snap = plant.snapshot();
        let (surfaces, diag) = controller.step(&measurement(&snap), &setpoint, dt);
        let n = controller.networks();
        trace.rows.push(trace_row(&snap, &surfaces, &diag, [&n[0].weights, &n[1].weights, &n[2].weights]));
        let command = ActuatorCommand { surfaces, throttle: previous.throttle };
        let applied = match s.timing.command_timing {
            CommandTiming::SameTick => command,
            CommandTiming::NextTick => previous,
        };
        plant.step(&applied);
        previous = command;
    }
    Ok(trace)
}
