//! A quadrotor in X configuration, the second built-in vehicle: a 6-DOF rigid body under four rotors with
//! first-order speed dynamics, thrust and reaction torque proportional to speed squared, thrust reduced by the air
//! climbing through the discs (axial inflow), rotor drag, the frame's quadratic drag, gravity and a flat ground it
//! rests on before take-off and never falls through. Pure math: no I/O, no clock, no allocation.
//!
//! Module map: [`params`] (parameters by name, the published defaults), [`rotors`] (geometry, motor dynamics, the
//! rotors' force and moments), [`drag`] (the frame's drag), [`outputs`] (what it reports and takes, by name),
//! [`QuadVehicle`] (stepped tick by tick: RK4 over [`derivative`], then the ground contact). Frames: position and velocity in north-east-down (NED)
//! about a point on the ground; body axes forward-right-down (FRD); the attitude a unit quaternion (w, x, y, z)
//! rotating body vectors into NED. Left out: the rotors' gyroscopic moments, blade flapping, the inflow's effect on
//! the reaction torque, the vortex ring state of a fast descent, wind, ground effect, and tipping over on the
//! ground.

pub mod drag;
pub mod outputs;
pub mod params;
pub mod rotors;

use crate::integrator::rk4_step;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use params::{GRAVITY_MPS2, QuadParams};
use rotors::{ROTORS, commanded_speed_radps, rotor_acceleration_radps2, rotor_wrench};

/// Number of integrated states: position (3), velocity (3), attitude quaternion (4), body rates (3), rotor speeds
/// (4).
pub const QUAD_STATE_LEN: usize = 17;

/// Offsets of each part of the state vector.
mod ix {
    pub const POS: usize = 0;
    pub const VEL: usize = 3;
    pub const QUAT: usize = 6;
    pub const RATE: usize = 10;
    pub const ROTOR: usize = 13;
}

/// The integrated state, with named views.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadState {
    /// Position NED (m), velocity NED (m/s), quaternion (w, x, y, z), body rates p, q, r (rad/s), rotor speeds
    /// (rad/s, motor order).
    pub x: [f64; QUAD_STATE_LEN],
}

impl QuadState {
    /// At rest at `position_ned_m`, heading `psi_rad`, level, rotors at `rotor_speed_radps`.
    pub fn at_rest(position_ned_m: [f64; 3], psi_rad: f64, rotor_speed_radps: f64) -> Self {
        let q = UnitQuaternion::from_euler_angles(0.0, 0.0, psi_rad);
        let mut x = [0.0; QUAD_STATE_LEN];
        x[ix::POS..ix::POS + 3].copy_from_slice(&position_ned_m);
        x[ix::QUAT..ix::QUAT + 4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
        x[ix::ROTOR..].fill(rotor_speed_radps);
        Self { x }
    }
    /// Position north, east, down, m.
    pub fn position_ned_m(&self) -> [f64; 3] {
        [self.x[ix::POS], self.x[ix::POS + 1], self.x[ix::POS + 2]]
    }
    /// Velocity north, east, down, m/s.
    pub fn velocity_ned_mps(&self) -> [f64; 3] {
        [self.x[ix::VEL], self.x[ix::VEL + 1], self.x[ix::VEL + 2]]
    }
    /// Attitude: the rotation of body vectors into NED.
    pub fn attitude(&self) -> UnitQuaternion<f64> {
        let q = &self.x[ix::QUAT..ix::QUAT + 4];
        UnitQuaternion::new_normalize(Quaternion::new(q[0], q[1], q[2], q[3]))
    }
    /// Body rates p, q, r, rad/s.
    pub fn rates_radps(&self) -> [f64; 3] {
        [self.x[ix::RATE], self.x[ix::RATE + 1], self.x[ix::RATE + 2]]
    }
    /// Rotor speeds in motor order, rad/s.
    pub fn rotor_speeds_radps(&self) -> [f64; ROTORS] {
        std::array::from_fn(|i| self.x[ix::ROTOR + i])
    }
}

/// The right-hand side `x_dot = f(x, u)`, with the ground holding the vehicle when `on_ground` and the rotors do not
/// lift it. Returns the derivative and the acceleration NED (m/s^2) it implies, from which the accelerometer reads
/// its specific force.
pub fn derivative(
    p: &QuadParams,
    x: &[f64; QUAD_STATE_LEN],
    motor_commands: &[f64; ROTORS],
    on_ground: bool,
) -> ([f64; QUAD_STATE_LEN], Vector3<f64>) {
    let s = QuadState { x: *x };
    let att = s.attitude();
    let v_ned = Vector3::from(s.velocity_ned_mps());
    let v_b = att.inverse_transform_vector(&v_ned);
    let speeds = s.rotor_speeds_radps();
    let v_b = [v_b.x, v_b.y, v_b.z];
    let w = rotor_wrench(p, &speeds, &v_b, &s.rates_radps());
    let force_b_n = Vector3::from(w.force_b_n) + Vector3::from(drag::body_drag_n(p, &v_b));
    let mut accel_ned = att.transform_vector(&force_b_n) / p.mass_kg;
    accel_ned.z += GRAVITY_MPS2;
    let omega = Vector3::from(s.rates_radps());
    let inertia = Vector3::new(p.ixx_kgm2, p.iyy_kgm2, p.izz_kgm2);
    // Euler's equations for a body with principal axes along x, y, z: J omega_dot = M - omega x (J omega).
    let h = omega.component_mul(&inertia);
    let mut omega_dot = (Vector3::from(w.moment_b_nm) - omega.cross(&h)).component_div(&inertia);
    // Resting contact: the ground pushes back as hard as the vehicle pushes down, and holds it still.
    let resting = on_ground && accel_ned.z >= 0.0;
    if resting {
        accel_ned = Vector3::zeros();
        omega_dot = Vector3::zeros();
    }
    let mut dx = [0.0; QUAD_STATE_LEN];
    dx[ix::POS..ix::POS + 3].copy_from_slice(&s.velocity_ned_mps());
    dx[ix::VEL..ix::VEL + 3].copy_from_slice(accel_ned.as_slice());
    // q_dot = q (x) (0, omega) / 2.
    let q = att.into_inner();
    let q_dot = q * Quaternion::new(0.0, omega.x, omega.y, omega.z) * 0.5;
    dx[ix::QUAT..ix::QUAT + 4].copy_from_slice(&[q_dot.w, q_dot.i, q_dot.j, q_dot.k]);
    dx[ix::RATE..ix::RATE + 3].copy_from_slice(omega_dot.as_slice());
    for i in 0..ROTORS {
        let commanded = commanded_speed_radps(p, motor_commands[i]);
        dx[ix::ROTOR + i] = rotor_acceleration_radps2(p, speeds[i], commanded);
    }
    (dx, accel_ned)
}

/// The quadrotor stepped tick by tick: its parameters, state, whether it rests on the ground, and the motor
/// commands it flies.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadVehicle {
    /// Parameters (validated at construction).
    pub params: QuadParams,
    /// The integrated state.
    pub state: QuadState,
    /// Resting on the ground: held there until the rotors lift it.
    pub on_ground: bool,
    /// Motor commands held over the current step, 0..1, motor order.
    pub motor_commands: [f64; ROTORS],
    /// Vertical speed at the last touchdown, m/s (down positive; 0 before any).
    pub touchdown_speed_mps: f64,
}

impl QuadVehicle {
    /// At rest on the ground at the origin, heading `psi_rad`, rotors stopped.
    pub fn on_ground(params: QuadParams, psi_rad: f64) -> Result<Self, params::ParamError> {
        params.validate()?;
        let state = QuadState::at_rest([0.0; 3], psi_rad, 0.0);
        Ok(Self { params, state, on_ground: true, motor_commands: [0.0; ROTORS], touchdown_speed_mps: 0.0 })
    }

    /// Hovering at `altitude_m` above the ground, heading `psi_rad`, rotors at the hover speed and commanded to it.
    pub fn hovering(params: QuadParams, altitude_m: f64, psi_rad: f64) -> Result<Self, params::ParamError> {
        params.validate()?;
        let hover = params.hover_rotor_speed_radps();
        let state = QuadState::at_rest([0.0, 0.0, -altitude_m], psi_rad, hover);
        let motor_commands = [params.hover_command(); ROTORS];
        Ok(Self { params, state, on_ground: altitude_m <= 0.0, motor_commands, touchdown_speed_mps: 0.0 })
    }

    /// Where a scenario starts it: hovering at `altitude_m` above 0, else at rest on the ground with the rotors
    /// stopped; heading `psi_rad`.
    pub fn at_start(params: QuadParams, altitude_m: f64, psi_rad: f64) -> Result<Self, params::ParamError> {
        if altitude_m > 0.0 { Self::hovering(params, altitude_m, psi_rad) } else { Self::on_ground(params, psi_rad) }
    }

    /// Sets the motor commands held over the next steps (0..1; beyond is clamped, NaN is 0, as an ESC would).
    pub fn command(&mut self, motor_commands: [f64; ROTORS]) {
        self.motor_commands = motor_commands;
    }

    /// One RK4 step of `dt_s` with the held commands, then the ground contact.
    pub fn step(&mut self, dt_s: f64) {
        let (p, u, on_ground) = (self.params, self.motor_commands, self.on_ground);
        let mut x =
            rk4_step(|_, x: &[f64; QUAD_STATE_LEN]| derivative(&p, x, &u, on_ground).0, 0.0, &self.state.x, dt_s);
        let q = UnitQuaternion::new_normalize(Quaternion::new(x[6], x[7], x[8], x[9]));
        x[ix::QUAT..ix::QUAT + 4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
        self.state.x = x;
        self.contact();
    }

    /// The ground at down = 0: a vehicle resting there leaves it only upwards; one that reaches it moving down stops
    /// there, level, with its heading kept (no bounce, no tipping).
    fn contact(&mut self) {
        let [north, east, down] = self.state.position_ned_m();
        if self.on_ground {
            if down < 0.0 {
                self.on_ground = false;
            } else {
                self.state.x[ix::POS + 2] = 0.0;
            }
            return;
        }
        let vd = self.state.x[ix::VEL + 2];
        if down >= 0.0 && vd >= 0.0 {
            self.touchdown_speed_mps = vd;
            let psi = self.state.attitude().euler_angles().2;
            let level = QuadState::at_rest([north, east, 0.0], psi, 0.0);
            self.state.x[..ix::ROTOR].copy_from_slice(&level.x[..ix::ROTOR]);
            self.on_ground = true;
        }
    }

    /// Acceleration NED at the current state and commands, m/s^2.
    pub fn acceleration_ned_mps2(&self) -> Vector3<f64> {
        derivative(&self.params, &self.state.x, &self.motor_commands, self.on_ground).1
    }

    /// What an accelerometer at the centre of mass reads, body axes, m/s^2: the acceleration less gravity (at rest
    /// on level ground, (0, 0, -g)).
    pub fn specific_force_b_mps2(&self) -> Vector3<f64> {
        let gravity = Vector3::new(0.0, 0.0, GRAVITY_MPS2);
        self.state.attitude().inverse_transform_vector(&(self.acceleration_ned_mps2() - gravity))
    }
}

#[cfg(test)]
mod tests;
