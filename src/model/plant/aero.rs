//! Aerodynamic coefficient build-up of the F-16 (Stevens & Lewis Appendix A): table coefficients, the side-force
//! and normal-force formulas, rate damping, and the transfer of moments from the reference CG (0.35 c-bar) to the
//! actual one. Angles in degrees, rates in rad/s, airspeed in ft/s.

use super::tables::F16Tables;

/// Wing area, ft^2.
pub const WING_AREA_FT2: f64 = 300.0;
/// Wing span, ft.
pub const WING_SPAN_FT: f64 = 30.0;
/// Mean aerodynamic chord, ft.
pub const MEAN_CHORD_FT: f64 = 11.32;
/// CG position (fraction of the chord) at which the tables' moments are taken.
pub const XCG_REF: f64 = 0.35;
/// The angle of attack the aerodynamic tables cover, deg (outside it they extrapolate linearly: no data).
pub const ALPHA_DATA_DEG: (f64, f64) = (-10.0, 45.0);
/// The largest |sideslip| the tables cover, deg.
pub const BETA_DATA_MAX_DEG: f64 = 30.0;

/// What the coefficients depend on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AeroInput {
    /// Angle of attack, deg.
    pub alpha_deg: f64,
    /// Sideslip, deg.
    pub beta_deg: f64,
    /// Elevator, deg (positive trailing edge down).
    pub elevator_deg: f64,
    /// Aileron, deg.
    pub aileron_deg: f64,
    /// Rudder, deg.
    pub rudder_deg: f64,
    /// True airspeed, ft/s.
    pub vt_fps: f64,
    /// Body roll rate, rad/s.
    pub p_radps: f64,
    /// Body pitch rate, rad/s.
    pub q_radps: f64,
    /// Body yaw rate, rad/s.
    pub r_radps: f64,
    /// CG position, fraction of the mean chord.
    pub xcg: f64,
}

/// Total body-axis force and moment coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AeroCoefficients {
    /// Axial force (x forward).
    pub cx: f64,
    /// Side force (y right).
    pub cy: f64,
    /// Normal force (z down; lift is negative).
    pub cz: f64,
    /// Rolling moment.
    pub cl: f64,
    /// Pitching moment, about the actual CG.
    pub cm: f64,
    /// Yawing moment, about the actual CG.
    pub cn: f64,
}

#[inline]
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// The coefficient build-up, including damping and the CG transfer terms.
#[inline]
pub fn coefficients(t: &F16Tables, a: &AeroInput) -> AeroCoefficients {
    let (alpha, beta) = (a.alpha_deg, a.beta_deg);
    let dail = a.aileron_deg / 20.0;
    let drdr = a.rudder_deg / 30.0;

    let cx = t.cx.lookup(alpha, a.elevator_deg);
    let cy = -0.02 * beta + 0.021 * dail + 0.086 * drdr;
    // The sideslip factor divides degrees by 57.3, as printed; it is not a radian conversion.
    let cz = t.cz.lookup(alpha, 0) * (1.0 - (beta / 57.3).powi(2)) - 0.19 * (a.elevator_deg / 25.0);
    let cl = sign(beta) * t.cl.lookup(alpha, beta.abs())
        + t.dlda.lookup(alpha, beta) * dail
        + t.dldr.lookup(alpha, beta) * drdr;
    let cm = t.cm.lookup(alpha, a.elevator_deg);
    let cn = sign(beta) * t.cn.lookup(alpha, beta.abs())
        + t.dnda.lookup(alpha, beta) * dail
        + t.dndr.lookup(alpha, beta) * drdr;

    let [cxq, cyr, cyp, czq, clr, clp, cmq, cnr, cnp] = t.damping.lookup_all::<9>(alpha);
    let tvt = 0.5 / a.vt_fps;
    let b2v = WING_SPAN_FT * tvt;
    let cq = MEAN_CHORD_FT * a.q_radps * tvt;
    let (p, r) = (a.p_radps, a.r_radps);

    let cx_t = cx + cq * cxq;
    let cy_t = cy + b2v * (cyr * r + cyp * p);
    let cz_t = cz + cq * czq;
    let cl_t = cl + b2v * (clr * r + clp * p);
    let cm_t = cm + cq * cmq + cz_t * (XCG_REF - a.xcg);
    let cn_t = cn + b2v * (cnr * r + cnp * p) - cy_t * (XCG_REF - a.xcg) * (MEAN_CHORD_FT / WING_SPAN_FT);
    AeroCoefficients { cx: cx_t, cy: cy_t, cz: cz_t, cl: cl_t, cm: cm_t, cn: cn_t }
}
