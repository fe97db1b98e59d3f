//! The Stevens & Lewis nonlinear 6-DOF F-16 (Appendix A): 13-state equations of motion in the book's units, with
//! the CG position as a parameter. Pure math: no I/O, no clock, no allocation per call.
//!
//! Module map: [`tables`] (data and lookup rule), [`atmosphere`], [`aero`] (coefficient build-up), [`engine`]
//! (gearing, power lag, thrust), [`envelope`] (the states the equations are defined at), [`trim`] (steady
//! wings-level flight). The equations themselves are in [`F16Model::derivative`], with the load factors Nz, Ny
//! beside them ([`F16Model::derivative_with_outputs`]). The CSV cross-check tool built on them is
//! `silrig_tools::derivative_csv`.

pub mod aero;
pub mod atmosphere;
pub mod engine;
pub mod envelope;
pub mod tables;
pub mod trim;

use crate::units::DEG_PER_RAD_BOOK;
use serde::{Deserialize, Serialize};
use tables::{F16_TABLES, F16Tables};

/// Number of states.
pub const STATE_LEN: usize = 13;

/// Aircraft mass properties and constants of the book's model (rounded values of the reference implementation).
pub mod constants {
    /// 1 / mass, 1/slug (the book's rounded value; m = 636.94 slug).
    pub const INV_MASS_PER_SLUG: f64 = 1.57e-3;
    /// Gravity, ft/s^2.
    pub const GRAVITY_FPS2: f64 = 32.17;
    /// Roll inertia Jx, slug ft^2.
    pub const JX_SLUGFT2: f64 = 9_496.0;
    /// Pitch inertia Jy, slug ft^2.
    pub const JY_SLUGFT2: f64 = 55_814.0;
    /// Yaw inertia Jz, slug ft^2.
    pub const JZ_SLUGFT2: f64 = 63_100.0;
    /// Product of inertia Jxz, slug ft^2.
    pub const JXZ_SLUGFT2: f64 = 982.0;
    /// Engine angular momentum along body x, slug ft^2/s.
    pub const ENGINE_MOMENTUM_SLUGFT2PS: f64 = 160.0;
    /// Station of the accelerometer whose readings are the load factors Nz, Ny: this far ahead of the CG on the body
    /// x axis, ft (the book's and AeroBench's 15 ft).
    pub const ACCELEROMETER_AHEAD_OF_CG_FT: f64 = 15.0;
    /// Inertia coefficients c1..c9 as rounded in the reference implementation.
    pub const C: [f64; 9] = [-0.770, 0.02755, 1.055e-4, 1.642e-6, 0.9604, 1.759e-2, 1.792e-5, -0.7336, 1.587e-5];
}

/// The 13 states, in the book's units. Body axes x forward, y right, z down; Euler angles 3-2-1 from north-east-down.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct F16State {
    /// True airspeed, ft/s.
    pub vt_fps: f64,
    /// Angle of attack, rad.
    pub alpha_rad: f64,
    /// Sideslip, rad (positive: wind from the right).
    pub beta_rad: f64,
    /// Roll angle, rad.
    pub phi_rad: f64,
    /// Pitch angle, rad.
    pub theta_rad: f64,
    /// Heading, rad.
    pub psi_rad: f64,
    /// Body roll rate, rad/s.
    pub p_radps: f64,
    /// Body pitch rate, rad/s.
    pub q_radps: f64,
    /// Body yaw rate, rad/s.
    pub r_radps: f64,
    /// North position, ft.
    pub north_ft: f64,
    /// East position, ft.
    pub east_ft: f64,
    /// Altitude, ft.
    pub alt_ft: f64,
    /// Engine power level, percent (0..100).
    pub power_pct: f64,
}

/// Names of the states, in vector order, as used in CSV headers.
pub const STATE_NAMES: [&str; STATE_LEN] = [
    "vt_fps",
    "alpha_rad",
    "beta_rad",
    "phi_rad",
    "theta_rad",
    "psi_rad",
    "p_radps",
    "q_radps",
    "r_radps",
    "north_ft",
    "east_ft",
    "alt_ft",
    "power_pct",
];

/// Names of the state derivatives, in vector order, as used in CSV headers.
pub const STATE_DOT_NAMES: [&str; STATE_LEN] = [
    "vt_dot",
    "alpha_dot",
    "beta_dot",
    "phi_dot",
    "theta_dot",
    "psi_dot",
    "p_dot",
    "q_dot",
    "r_dot",
    "north_dot",
    "east_dot",
    "alt_dot",
    "power_dot",
];

impl F16State {
    /// The state as a vector in the book's order.
    #[inline]
    pub fn to_array(&self) -> [f64; STATE_LEN] {
        [
            self.vt_fps,
            self.alpha_rad,
            self.beta_rad,
            self.phi_rad,
            self.theta_rad,
            self.psi_rad,
            self.p_radps,
            self.q_radps,
            self.r_radps,
            self.north_ft,
            self.east_ft,
            self.alt_ft,
            self.power_pct,
        ]
    }

    /// The state from a vector in the book's order.
    #[inline]
    pub fn from_array(x: &[f64; STATE_LEN]) -> Self {
        Self {
            vt_fps: x[0],
            alpha_rad: x[1],
            beta_rad: x[2],
            phi_rad: x[3],
            theta_rad: x[4],
            psi_rad: x[5],
            p_radps: x[6],
            q_radps: x[7],
            r_radps: x[8],
            north_ft: x[9],
            east_ft: x[10],
            alt_ft: x[11],
            power_pct: x[12],
        }
    }
}

/// The inputs the equations of motion take directly (the book models no actuators inside the derivative).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ControlInputs {
    /// Throttle, 0..1.
    pub throttle: f64,
    /// Elevator, deg (positive trailing edge down, nose-down moment).
    pub elevator_deg: f64,
    /// Aileron, deg (positive gives a negative rolling moment).
    pub aileron_deg: f64,
    /// Rudder, deg (positive gives a nose-left yawing moment).
    pub rudder_deg: f64,
}

/// Things added to the book's equations by a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ExternalForcing {
    /// Freeze the airspeed (VT_dot = 0), as the paper's scenario assumes. The other derivatives are unchanged: a
    /// force along the velocity that cancels VT_dot leaves alpha_dot and beta_dot as they are.
    pub speed_hold: bool,
    /// Freeze the sideslip (beta_dot = 0), as the paper's derivation assumes ("the sideslip is assumed to be
    /// zero"): a side force outside the book's model. For reproducing the paper's figures, not for flying.
    pub sideslip_hold: bool,
    /// Disturbance added to the Euler-angle accelerations (phi, theta, psi), rad/s^2; mapped to the body rates
    /// through T(phi, theta)^-1.
    pub euler_accel_disturbance_radps2: [f64; 3],
}

/// Multipliers on the book's F-16 for uncertainty studies (Monte Carlo): all 1 is the book's aircraft.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelScales {
    /// On the total body-axis coefficients Cx, Cy, Cz, Cl, Cm, Cn (after the build-up, damping and CG terms).
    pub aero: [f64; 6],
    /// On the mass and the inertias together (the radii of gyration kept).
    pub mass: f64,
}

impl Default for ModelScales {
    fn default() -> Self {
        Self { aero: [1.0; 6], mass: 1.0 }
    }
}

/// The F-16 model: the tables plus the CG position (and uncertainty scales, 1 by default).
#[derive(Debug, Clone, Copy)]
pub struct F16Model {
    tables: &'static F16Tables,
    /// CG position, fraction of the mean aerodynamic chord (book default 0.35; the check case uses 0.4).
    pub xcg: f64,
    /// Uncertainty multipliers (1: the book's aircraft; multiplying by 1 changes no bit).
    pub scales: ModelScales,
}

impl Default for F16Model {
    fn default() -> Self {
        Self::new(aero::XCG_REF)
    }
}

/// Outputs computed alongside the derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelOutputs {
    /// Dynamic pressure, lbf/ft^2.
    pub qbar_psf: f64,
    /// Mach number.
    pub mach: f64,
    /// Thrust, lbf.
    pub thrust_lbf: f64,
    /// Normal load factor, g: what an accelerometer at [`constants::ACCELEROMETER_AHEAD_OF_CG_FT`] reads along
    /// body -z (specific force, so gravity is not in it), divided by g. In trimmed wings-level flight it is
    /// cos(theta), close to 1 (thrust along body x carries the rest of the weight). AeroBench's `Nz` is this minus 1.
    pub nz_g: f64,
    /// Lateral load factor, g: the same accelerometer along body +y (out the right wing), divided by g.
    pub ny_g: f64,
}

impl F16Model {
    /// The model with the embedded tables and the given CG position.
    pub fn new(xcg: f64) -> Self {
        Self { tables: &F16_TABLES, xcg, scales: ModelScales::default() }
    }

    /// The model with uncertainty multipliers.
    pub fn with_scales(self, scales: ModelScales) -> Self {
        Self { scales, ..self }
    }

    /// The tables the model reads.
    pub fn tables(&self) -> &'static F16Tables {
        self.tables
    }

    /// State derivative in the book's units (Stevens & Lewis, Appendix A, subroutine `F`).
    #[inline]
    pub fn derivative(&self, x: &F16State, u: &ControlInputs, forcing: &ExternalForcing) -> [f64; STATE_LEN] {
        self.derivative_with_outputs(x, u, forcing).0
    }

    /// State derivative plus air data, thrust and the load factors.
    #[inline]
    pub fn derivative_with_outputs(
        &self,
        x: &F16State,
        u: &ControlInputs,
        forcing: &ExternalForcing,
    ) -> ([f64; STATE_LEN], ModelOutputs) {
        use constants::*;
        let [c1, c2, c3, c4, c5, c6, c7, c8, c9] = C;
        let he = ENGINE_MOMENTUM_SLUGFT2PS;
        let g = GRAVITY_FPS2;
        let vt = x.vt_fps;
        let (p, q, r) = (x.p_radps, x.q_radps, x.r_radps);

        let air = atmosphere::air_data(vt, x.alt_ft);
        let power_dot = engine::power_rate_pctps(x.power_pct, engine::commanded_power_pct(u.throttle));
        let thrust = engine::thrust_lbf(self.tables, x.power_pct, x.alt_ft, air.mach);
        let k = self.scaled_coefficients(x, u);
        // Mass and inertias scaled together: 1/m and the inverse-inertia terms c3, c4, c7, c9 divide by the
        // scale; the inertia ratios c1, c2, c5, c6, c8 are unchanged.
        let mass = self.scales.mass;
        let inv_mass = INV_MASS_PER_SLUG / mass;
        let (c3, c4, c7, c9) = (c3 / mass, c4 / mass, c7 / mass, c9 / mass);
        let cbta = x.beta_rad.cos();
        let u_fps = vt * x.alpha_rad.cos() * cbta;
        let v_fps = vt * x.beta_rad.sin();
        let w_fps = vt * x.alpha_rad.sin() * cbta;
        let (sth, cth) = x.theta_rad.sin_cos();
        let (sph, cph) = x.phi_rad.sin_cos();
        let (spsi, cpsi) = x.psi_rad.sin_cos();

        let qs = air.qbar_psf * aero::WING_AREA_FT2;
        let qsb = qs * aero::WING_SPAN_FT;
        let rmqs = inv_mass * qs;
        let gcth = g * cth;
        let qsph = q * sph;

        // Force equations in body axes.
        let udot = r * v_fps - q * w_fps - g * sth + inv_mass * (qs * k.cx + thrust);
        let vdot = p * w_fps - r * u_fps + gcth * sph + rmqs * k.cy;
        let wdot = q * u_fps - p * v_fps + gcth * cph + rmqs * k.cz;
        let dum = u_fps * u_fps + w_fps * w_fps;
        let vt_dot_free = (u_fps * udot + v_fps * vdot + w_fps * wdot) / vt;
        let alpha_dot = (u_fps * wdot - w_fps * udot) / dum;
        let beta_dot = if forcing.sideslip_hold { 0.0 } else { (vt * vdot - v_fps * vt_dot_free) * cbta / dum };

        // Kinematics.
        let phi_dot = p + (sth / cth) * (qsph + r * cph);
        let theta_dot = q * cph - r * sph;
        let psi_dot = (qsph + r * cph) / cth;

        // Moment equations.
        let p_dot = (c2 * p + c1 * r + c4 * he) * q + qsb * (c3 * k.cl + c4 * k.cn);
        let q_dot = (c5 * p - c7 * he) * r + c6 * (r * r - p * p) + qs * aero::MEAN_CHORD_FT * c7 * k.cm;
        let r_dot = (c8 * p - c2 * r + c9 * he) * q + qsb * (c4 * k.cl + c9 * k.cn);
        let d = forcing.euler_accel_disturbance_radps2;
        let [p_dot, q_dot, r_dot] = with_euler_disturbance([p_dot, q_dot, r_dot], d, (sph, cph), (sth, cth));

        let [north_dot, east_dot, alt_dot] =
            navigation_rates([u_fps, v_fps, w_fps], (sph, cph), (sth, cth), (spsi, cpsi));

        // Load factors: the specific force of the aerodynamic forces (thrust acts along body x only) at the
        // accelerometer station, whose angular-acceleration terms are q_dot and r_dot times its lever arm (the
        // centripetal terms are neglected, as the book does); in g, z positive up.
        let station = ACCELEROMETER_AHEAD_OF_CG_FT;
        let nz_g = -(rmqs * k.cz - station * q_dot) / g;
        let ny_g = (rmqs * k.cy + station * r_dot) / g;

        let vt_dot = if forcing.speed_hold { 0.0 } else { vt_dot_free };
        (
            [
                vt_dot, alpha_dot, beta_dot, phi_dot, theta_dot, psi_dot, p_dot, q_dot, r_dot, north_dot, east_dot,
                alt_dot, power_dot,
            ],
            ModelOutputs { qbar_psf: air.qbar_psf, mach: air.mach, thrust_lbf: thrust, nz_g, ny_g },
        )
    }

    /// The aerodynamic coefficients at the state and the surfaces, scaled by the plant's `aero_scale`.
    #[inline]
    fn scaled_coefficients(&self, x: &F16State, u: &ControlInputs) -> aero::AeroCoefficients {
        let k = aero::coefficients(
            self.tables,
            &aero::AeroInput {
                alpha_deg: x.alpha_rad * DEG_PER_RAD_BOOK,
                beta_deg: x.beta_rad * DEG_PER_RAD_BOOK,
                elevator_deg: u.elevator_deg,
                aileron_deg: u.aileron_deg,
                rudder_deg: u.rudder_deg,
                vt_fps: x.vt_fps,
                p_radps: x.p_radps,
                q_radps: x.q_radps,
                r_radps: x.r_radps,
                xcg: self.xcg,
            },
        );

        let [sx, sy, sz, sl, sm, sn] = self.scales.aero;
        aero::AeroCoefficients {
            cx: k.cx * sx,
            cy: k.cy * sy,
            cz: k.cz * sz,
            cl: k.cl * sl,
            cm: k.cm * sm,
            cn: k.cn * sn,
        }
    }
}

/// The body-rate accelerations with the disturbance `d` added to the Euler angles' (phi, theta, psi)'': through the
/// inverse of the Euler-rate matrix T(phi, theta).
#[inline]
fn with_euler_disturbance(
    [mut p_dot, mut q_dot, mut r_dot]: [f64; 3],
    d: [f64; 3],
    (sph, cph): (f64, f64),
    (sth, cth): (f64, f64),
) -> [f64; 3] {
    if d != [0.0; 3] {
        p_dot += d[0] - sth * d[2];
        q_dot += cph * d[1] + sph * cth * d[2];
        r_dot += -sph * d[1] + cph * cth * d[2];
    }
    [p_dot, q_dot, r_dot]
}

/// Navigation: the rates of north, east and altitude from the body-axis velocities through the direction cosines of
/// the Euler angles (each given as its sine and cosine).
#[inline]
fn navigation_rates(
    [u_fps, v_fps, w_fps]: [f64; 3],
    (sph, cph): (f64, f64),
    (sth, cth): (f64, f64),
    (spsi, cpsi): (f64, f64),
) -> [f64; 3] {
    let t1 = sph * cpsi;
    let t2 = cph * sth;
    let t3 = sph * spsi;
    let s1 = cth * cpsi;
    let s2 = cth * spsi;
    let s3 = t1 * sth - cph * spsi;
    let s4 = t3 * sth + cph * cpsi;
    let s5 = sph * cth;
    let s6 = t2 * cpsi + t3;
    let s7 = t2 * spsi - t1;
    let s8 = cph * cth;
    let north_dot = u_fps * s1 + v_fps * s3 + w_fps * s6;
    let east_dot = u_fps * s2 + v_fps * s4 + w_fps * s7;
    let alt_dot = u_fps * sth - v_fps * s5 - w_fps * s8;
    [north_dot, east_dot, alt_dot]
}
