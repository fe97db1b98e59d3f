//! The quadrotor's parameters by name: what a scenario's `[plant.parameters]` and a dispersion address, each with
//! its unit, its range and its published default.
//!
//! Defaults: the AscTec Hummingbird as RotorS models it (Furrer, Burri, Achtelik, Siegwart, "RotorS — A Modular
//! Gazebo MAV Simulator Framework", in *Robot Operating System (ROS): The Complete Reference, Vol. 1*, Springer
//! 2016, pp. 595-625; the numbers are those of `rotors_description/urdf/hummingbird.xacro` and
//! `rotors_gazebo/resource/hummingbird.yaml`, which credit Wang et al., "Novel Dynamic Inversion Architecture Design
//! for Quadrocopter Control"). RotorS mounts the Hummingbird's rotors in "+"; ours sit in "X" at the same distance
//! from the centre, which changes the allocation, not the vehicle's mass, inertia or rotors.
//!
//! RotorS has no force along the rotors' axis but their thrust, so a quadrotor above hover thrust climbs ever
//! faster. The axial inflow coefficient and the frame's drag come from RotorPy's model of the same vehicle (Folk,
//! Paulos, Kumar, "RotorPy: A Python-based Multirotor Simulator with Aerodynamics for Education and Research", 2023,
//! arXiv:2306.04485; the numbers are `k_z`, `c_Dx`, `c_Dy` and `c_Dz` of `rotorpy/vehicles/hummingbird_params.py`,
//! whose model follows Svacha, Mohta, Kumar, "Improving Quadrotor Trajectory Tracking by Compensating for
//! Aerodynamic Effects", ICUAS 2017). RotorPy notes that it took its `k_z` an order of magnitude below the value it
//! first tried, which flew badly: a tuned number, not a measured one, and named so here.

use serde::{Deserialize, Serialize};

/// Standard gravity, m/s^2 (ISO 80000-3).
pub const GRAVITY_MPS2: f64 = 9.806_65;

/// Mass, geometry, inertia and rotors of an X quadrotor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct QuadParams {
    /// Take-off mass, kg.
    pub mass_kg: f64,
    /// Distance from the centre of mass to each rotor's axis, m (the rotors sit on the diagonals of the X).
    pub arm_m: f64,
    /// Roll inertia about body x (forward), kg m^2.
    pub ixx_kgm2: f64,
    /// Pitch inertia about body y (right), kg m^2.
    pub iyy_kgm2: f64,
    /// Yaw inertia about body z (down), kg m^2.
    pub izz_kgm2: f64,
    /// Thrust of one rotor per (rotor speed)^2, N/(rad/s)^2: T = k_T omega^2.
    pub thrust_coeff_npradps2: f64,
    /// Reaction torque of one rotor per unit of its thrust, m: Q = k_Q T (RotorS's moment constant).
    pub torque_per_thrust_m: f64,
    /// Time constant of a rotor speeding up, s.
    pub motor_tau_up_s: f64,
    /// Time constant of a rotor slowing down, s.
    pub motor_tau_down_s: f64,
    /// Rotor speed at a motor command of 1, rad/s (command 0..1 maps linearly to 0..this).
    pub max_rotor_speed_radps: f64,
    /// Rotor drag: each spinning rotor pushes back on the velocity in its disc's plane with a force of this times
    /// its speed times that velocity, N/((rad/s)(m/s)) (RotorS's rotor drag coefficient).
    pub rotor_drag_coeff: f64,
    /// Axial inflow: air through a rotor's disc along its axis (climbing) takes this times the rotor's speed times
    /// that air speed off its thrust (and descending adds it), N/((rad/s)(m/s)): T = k_T omega^2 - k_z omega v
    /// (blade-element theory to first order; RotorPy's induced inflow coefficient `k_z`).
    pub rotor_inflow_coeff: f64,
    /// The frame's own drag along body x: a force of this times the air speed times its x component, against it,
    /// N/(m/s)^2 (0.5 rho Cd A at sea level; RotorPy's parasitic drag `c_Dx`).
    pub body_drag_x_kgpm: f64,
    /// The same along body y, N/(m/s)^2 (RotorPy's `c_Dy`).
    pub body_drag_y_kgpm: f64,
    /// The same along body z, the rotors' axis, N/(m/s)^2 (RotorPy's `c_Dz`).
    pub body_drag_z_kgpm: f64,
    /// Altitude of the ground above mean sea level, m: where the barometer reads when the vehicle sits on it.
    pub ground_altitude_m: f64,
}

impl Default for QuadParams {
    /// RotorS's Hummingbird, with RotorPy's axial inflow and frame drag (see the module documentation).
    fn default() -> Self {
        Self {
            mass_kg: 0.68,
            arm_m: 0.17,
            ixx_kgm2: 0.007,
            iyy_kgm2: 0.007,
            izz_kgm2: 0.012,
            thrust_coeff_npradps2: 8.548_58e-6,
            torque_per_thrust_m: 0.016,
            motor_tau_up_s: 0.0125,
            motor_tau_down_s: 0.025,
            max_rotor_speed_radps: 838.0,
            rotor_drag_coeff: 8.064_28e-5,
            rotor_inflow_coeff: 2.32e-4,
            body_drag_x_kgpm: 0.5e-2,
            body_drag_y_kgpm: 0.5e-2,
            body_drag_z_kgpm: 1e-2,
            ground_altitude_m: 0.0,
        }
    }
}

/// One parameter as a scenario names it: its unit, its accepted range and what it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamInfo {
    /// Name in `[plant.parameters]`.
    pub name: &'static str,
    /// Unit, as printed.
    pub unit: &'static str,
    /// Smallest accepted value.
    pub min: f64,
    /// Largest accepted value.
    pub max: f64,
    /// What it is, in a few words.
    pub description: &'static str,
}

/// Every parameter, in the order `QuadParams` declares them. Ranges keep the equations meaningful (positive mass,
/// inertia, coefficients and time constants) and refuse unit slips by orders of magnitude.
pub const PARAMS: [ParamInfo; 16] = [
    ParamInfo { name: "mass_kg", unit: "kg", min: 0.01, max: 100.0, description: "take-off mass" },
    ParamInfo { name: "arm_m", unit: "m", min: 0.01, max: 5.0, description: "centre to rotor axis" },
    ParamInfo { name: "ixx_kgm2", unit: "kg m^2", min: 1e-7, max: 100.0, description: "roll inertia" },
    ParamInfo { name: "iyy_kgm2", unit: "kg m^2", min: 1e-7, max: 100.0, description: "pitch inertia" },
    ParamInfo { name: "izz_kgm2", unit: "kg m^2", min: 1e-7, max: 100.0, description: "yaw inertia" },
    ParamInfo { name: "thrust_coeff_npradps2", unit: "N/(rad/s)^2", min: 1e-12, max: 1.0, description: "k_T" },
    ParamInfo { name: "torque_per_thrust_m", unit: "m", min: 0.0, max: 1.0, description: "k_Q" },
    ParamInfo { name: "motor_tau_up_s", unit: "s", min: 1e-4, max: 1.0, description: "spin-up time constant" },
    ParamInfo { name: "motor_tau_down_s", unit: "s", min: 1e-4, max: 1.0, description: "spin-down time constant" },
    ParamInfo { name: "max_rotor_speed_radps", unit: "rad/s", min: 1.0, max: 1e5, description: "speed at command 1" },
    ParamInfo { name: "rotor_drag_coeff", unit: "N s^2/(rad m)", min: 0.0, max: 1.0, description: "rotor drag" },
    ParamInfo { name: "rotor_inflow_coeff", unit: "N s^2/(rad m)", min: 0.0, max: 1.0, description: "axial inflow" },
    ParamInfo { name: "body_drag_x_kgpm", unit: "N/(m/s)^2", min: 0.0, max: 10.0, description: "frame drag, x" },
    ParamInfo { name: "body_drag_y_kgpm", unit: "N/(m/s)^2", min: 0.0, max: 10.0, description: "frame drag, y" },
    ParamInfo { name: "body_drag_z_kgpm", unit: "N/(m/s)^2", min: 0.0, max: 10.0, description: "frame drag, z" },
    ParamInfo { name: "ground_altitude_m", unit: "m", min: -500.0, max: 9000.0, description: "ground above MSL" },
];

/// The start values a scenario's `[plant.parameters]` (and the quadrotor's FMU) take beside the vehicle's
/// parameters: where the vehicle is at t = 0 ([`super::QuadVehicle::at_start`]).
pub const START_VALUES: [ParamInfo; 2] = [
    ParamInfo {
        name: "start_alt_m",
        unit: "m",
        min: 0.0,
        max: 1000.0,
        description: "height above the ground at t = 0: 0 rests on the ground with the rotors stopped, above it hovers",
    },
    ParamInfo { name: "start_psi_deg", unit: "deg", min: -180.0, max: 180.0, description: "heading at t = 0" },
];

/// A parameter set that cannot fly: which name, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// No parameter of that name.
    #[error("the quadrotor has no parameter `{name}`; its parameters are: {known}")]
    Unknown {
        /// The name given.
        name: String,
        /// Every name, comma-separated.
        known: String,
    },
    /// Outside its range, or not a number.
    #[error("quadrotor parameter `{name}` = {value} is outside {min}..={max} {unit}")]
    OutOfRange {
        /// The parameter.
        name: &'static str,
        /// The value given.
        value: f64,
        /// Smallest accepted.
        min: f64,
        /// Largest accepted.
        max: f64,
        /// Its unit.
        unit: &'static str,
    },
    /// The rotors at full speed cannot lift the vehicle.
    #[error(
        "the quadrotor cannot hover: four rotors at max_rotor_speed_radps give {thrust_n:.3} N against a weight of \
         {weight_n:.3} N; raise max_rotor_speed_radps or thrust_coeff_npradps2, or lower mass_kg"
    )]
    CannotHover {
        /// Full thrust, N.
        thrust_n: f64,
        /// Weight, N.
        weight_n: f64,
    },
}

impl QuadParams {
    /// The value of a parameter by name.
    pub fn get(&self, name: &str) -> Option<f64> {
        let info = PARAMS.iter().find(|p| p.name == name)?;
        let mut copy = *self;
        Some(*copy.field_mut(info.name))
    }

    /// Sets a parameter by name, range-checked; the set as a whole is checked by [`QuadParams::validate`].
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), ParamError> {
        let Some(info) = PARAMS.iter().find(|p| p.name == name) else {
            let known = PARAMS.iter().map(|p| p.name).collect::<Vec<_>>().join(", ");
            return Err(ParamError::Unknown { name: name.to_string(), known });
        };
        check_range(info, value)?;
        *self.field_mut(info.name) = value;
        Ok(())
    }

    /// Every parameter in range, and enough thrust to hover.
    pub fn validate(&self) -> Result<(), ParamError> {
        for info in &PARAMS {
            check_range(info, self.get(info.name).unwrap_or(f64::NAN))?;
        }
        let thrust_n = 4.0 * self.thrust_coeff_npradps2 * self.max_rotor_speed_radps.powi(2);
        let weight_n = self.mass_kg * GRAVITY_MPS2;
        if thrust_n <= weight_n {
            return Err(ParamError::CannotHover { thrust_n, weight_n });
        }
        Ok(())
    }

    /// Rotor speed that holds the vehicle in hover, rad/s: four rotors carrying the weight.
    pub fn hover_rotor_speed_radps(&self) -> f64 {
        (self.mass_kg * GRAVITY_MPS2 / (4.0 * self.thrust_coeff_npradps2)).sqrt()
    }

    /// Motor command (0..1) of the hover rotor speed.
    pub fn hover_command(&self) -> f64 {
        self.hover_rotor_speed_radps() / self.max_rotor_speed_radps
    }

    fn field_mut(&mut self, name: &str) -> &mut f64 {
        match name {
            "mass_kg" => &mut self.mass_kg,
            "arm_m" => &mut self.arm_m,
            "ixx_kgm2" => &mut self.ixx_kgm2,
            "iyy_kgm2" => &mut self.iyy_kgm2,
            "izz_kgm2" => &mut self.izz_kgm2,
            "thrust_coeff_npradps2" => &mut self.thrust_coeff_npradps2,
            "torque_per_thrust_m" => &mut self.torque_per_thrust_m,
            "motor_tau_up_s" => &mut self.motor_tau_up_s,
            "motor_tau_down_s" => &mut self.motor_tau_down_s,
            "max_rotor_speed_radps" => &mut self.max_rotor_speed_radps,
            "rotor_drag_coeff" => &mut self.rotor_drag_coeff,
            "rotor_inflow_coeff" => &mut self.rotor_inflow_coeff,
            "body_drag_x_kgpm" => &mut self.body_drag_x_kgpm,
            "body_drag_y_kgpm" => &mut self.body_drag_y_kgpm,
            "body_drag_z_kgpm" => &mut self.body_drag_z_kgpm,
            "ground_altitude_m" => &mut self.ground_altitude_m,
            other => unreachable!("PARAMS names `{other}`, which QuadParams lacks"),
        }
    }
}

fn check_range(info: &ParamInfo, value: f64) -> Result<(), ParamError> {
    if !(value >= info.min && value <= info.max) {
        return Err(ParamError::OutOfRange { name: info.name, value, min: info.min, max: info.max, unit: info.unit });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hummingbird_hovers_at_rotors_published_point() {
        let p = QuadParams::default();
        p.validate().unwrap();
        // RotorS's Hummingbird: 0.68 kg on four rotors of k_T = 8.54858e-6 N/(rad/s)^2, omega_max 838 rad/s.
        let omega = p.hover_rotor_speed_radps();
        assert!((omega - 441.61).abs() < 0.01, "{omega}");
        assert!((p.hover_command() - 0.52698).abs() < 1e-4, "{}", p.hover_command());
        // Thrust-to-weight at full speed: 24.0 N against 6.67 N.
        let full = 4.0 * p.thrust_coeff_npradps2 * p.max_rotor_speed_radps.powi(2);
        assert!((full / (p.mass_kg * GRAVITY_MPS2) - 3.600).abs() < 1e-3);
        // RotorPy's Hummingbird: k_z 2.32e-4 N/((rad/s)(m/s)); c_Dx, c_Dy 0.5e-2 and c_Dz 1e-2 N/(m/s)^2.
        assert_eq!(
            [p.rotor_inflow_coeff, p.body_drag_x_kgpm, p.body_drag_y_kgpm, p.body_drag_z_kgpm],
            [2.32e-4, 0.5e-2, 0.5e-2, 1e-2]
        );
    }

    #[test]
    fn every_parameter_is_reachable_by_name() {
        let mut p = QuadParams::default();
        for (k, info) in PARAMS.iter().enumerate() {
            let value = info.min + (info.max - info.min) * 0.25 + k as f64 * 1e-9;
            p.set(info.name, value).unwrap();
            assert_eq!(p.get(info.name), Some(value), "{}", info.name);
        }
    }

    #[test]
    fn refusals_name_the_parameter() {
        let mut p = QuadParams::default();
        let e = p.set("mass", 1.0).unwrap_err().to_string();
        assert!(e.contains("no parameter `mass`") && e.contains("mass_kg"), "{e}");
        let e = p.set("arm_m", f64::NAN).unwrap_err().to_string();
        assert!(e.contains("`arm_m` = NaN is outside 0.01..=5 m"), "{e}");
        p.set("mass_kg", 10.0).unwrap();
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("cannot hover") && e.contains("98.066 N"), "{e}");
    }
}
