//! What the quadrotor reports each tick and what it takes, as plain tables: its outputs in announced order with
//! names and units ([`OUTPUTS`], [`quad_outputs`]) and its inputs ([`INPUTS`]). The rig's announcement, the trace
//! and an FMU of the vehicle are built from these, so they all name the same signals.

use super::QuadVehicle;
use super::rotors::ROTORS;
use crate::units::rad_to_deg;

/// The quadrotor's plant name.
pub const PLANT_NAME: &str = "quad";

/// Outputs in announced order: (name, unit). A unit of "1" is dimensionless.
pub const OUTPUTS: [(&str, &str); 27] = [
    ("phi_deg", "deg"),
    ("theta_deg", "deg"),
    ("psi_deg", "deg"),
    ("p_dps", "deg/s"),
    ("q_dps", "deg/s"),
    ("r_dps", "deg/s"),
    ("alt_m", "m"),
    ("vd_mps", "m/s"),
    ("north_m", "m"),
    ("east_m", "m"),
    ("down_m", "m"),
    ("vn_mps", "m/s"),
    ("ve_mps", "m/s"),
    ("qw", "1"),
    ("qx", "1"),
    ("qy", "1"),
    ("qz", "1"),
    ("fx_mps2", "m/s^2"),
    ("fy_mps2", "m/s^2"),
    ("fz_mps2", "m/s^2"),
    ("pressure_pa", "Pa"),
    ("baro_alt_m", "m"),
    ("omega1_radps", "rad/s"),
    ("omega2_radps", "rad/s"),
    ("omega3_radps", "rad/s"),
    ("omega4_radps", "rad/s"),
    ("on_ground", "1"),
];

/// The inputs: one command per motor, 0..1 of its top speed, in Betaflight's Quad X order
/// ([`super::rotors`]).
pub const INPUTS: [(&str, &str); ROTORS] = [("motor1", "1"), ("motor2", "1"), ("motor3", "1"), ("motor4", "1")];

/// The range every input may take.
pub const INPUT_RANGE: (f64, f64) = (0.0, 1.0);

/// ISA sea-level pressure, Pa.
const SEA_LEVEL_PA: f64 = 101_325.0;

/// Static pressure at a geopotential altitude in the ISA troposphere (ICAO Doc 7488: 288.15 K, -6.5 K/km), Pa.
pub fn isa_pressure_pa(altitude_m: f64) -> f64 {
    SEA_LEVEL_PA * (1.0 - 2.255_77e-5 * altitude_m).powf(5.255_88)
}

/// Altitude of an ISA static pressure, m (the barometer's reading).
pub fn isa_altitude_m(pressure_pa: f64) -> f64 {
    (1.0 - (pressure_pa / SEA_LEVEL_PA).powf(1.0 / 5.255_88)) / 2.255_77e-5
}

/// The vehicle's outputs in the order of [`OUTPUTS`].
pub fn quad_outputs(v: &QuadVehicle) -> [f64; OUTPUTS.len()] {
    let s = &v.state;
    let att = s.attitude();
    let (phi, theta, psi) = att.euler_angles();
    let [p, q, r] = s.rates_radps();
    let [north, east, down] = s.position_ned_m();
    let [vn, ve, vd] = s.velocity_ned_mps();
    let f = v.specific_force_b_mps2();
    let pressure = isa_pressure_pa(v.params.ground_altitude_m - down);
    let w = s.rotor_speeds_radps();
    // `+ 0.0` turns a negative zero into zero, so a level vehicle on the ground prints 0.000, not -0.000.
    [
        rad_to_deg(phi) + 0.0,
        rad_to_deg(theta) + 0.0,
        rad_to_deg(psi) + 0.0,
        rad_to_deg(p),
        rad_to_deg(q),
        rad_to_deg(r),
        0.0 - down,
        vd,
        north,
        east,
        down,
        vn,
        ve,
        att.w,
        att.i,
        att.j,
        att.k,
        f.x,
        f.y,
        f.z,
        pressure,
        isa_altitude_m(pressure),
        w[0],
        w[1],
        w[2],
        w[3],
        if v.on_ground { 1.0 } else { 0.0 },
    ]
}

/// Index of an output by name.
pub fn output_index(name: &str) -> Option<usize> {
    OUTPUTS.iter().position(|(n, _)| *n == name)
}
