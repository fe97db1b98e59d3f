//! Unit conversions and the few physical constants shared across the crate.
//!
//! The plant works in the book's English units (ft, slug, lbf, deg for table lookups); the CLI and scenarios
//! speak SI where engineers expect it (airspeed in m/s). Every conversion between the two happens here.

/// Metres per foot (exact, international foot).
pub const M_PER_FT: f64 = 0.3048;

/// The book's degrees-per-radian factor. The F-16 reference implementation converts alpha and beta with this
/// rounded value, not 180/pi; using it keeps the derivatives within 2e-7 of the published check case.
pub const DEG_PER_RAD_BOOK: f64 = 57.29578;

/// Feet to metres.
#[inline]
pub fn ft_to_m(ft: f64) -> f64 {
    ft * M_PER_FT
}

/// Metres to feet.
#[inline]
pub fn m_to_ft(m: f64) -> f64 {
    m / M_PER_FT
}

/// Degrees to radians (exact factor).
#[inline]
pub fn deg_to_rad(deg: f64) -> f64 {
    deg.to_radians()
}

/// Radians to degrees (exact factor).
#[inline]
pub fn rad_to_deg(rad: f64) -> f64 {
    rad.to_degrees()
}

/// A number for a message: plain when it reads well, in exponent form when it is huge or tiny (`1e300`, not three
/// hundred digits).
pub fn readable(value: f64) -> String {
    if value != 0.0 && !(1e-4..1e6).contains(&value.abs()) { format!("{value:e}") } else { format!("{value}") }
}
