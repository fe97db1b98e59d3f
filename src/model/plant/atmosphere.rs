//! The book's standard atmosphere (air-data computer, Stevens & Lewis `ADC`): density, speed of sound, Mach and
//! dynamic pressure from altitude and true airspeed, in English units.

/// Sea-level air density, slug/ft^3.
pub const SEA_LEVEL_DENSITY_SLUGFT3: f64 = 2.377e-3;
/// Altitude above which the temperature is constant, ft.
pub const STRATOSPHERE_ALT_FT: f64 = 35_000.0;
/// Fall of the temperature ratio per foot of altitude (the book's 0.703e-5 1/ft).
pub const TEMPERATURE_RATIO_LAPSE_PER_FT: f64 = 0.703e-5;
/// Top of the model's atmosphere, ft (about 142,248 ft): there the temperature ratio, and with it the density,
/// reaches 0; above it the density formula raises a negative number to a fractional power (NaN).
pub const ATMOSPHERE_CEILING_FT: f64 = 1.0 / TEMPERATURE_RATIO_LAPSE_PER_FT;

/// Air data at one flight condition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirData {
    /// Air density, slug/ft^3.
    pub density_slugft3: f64,
    /// Static temperature, degrees Rankine.
    pub temperature_degr: f64,
    /// Speed of sound, ft/s.
    pub speed_of_sound_fps: f64,
    /// Mach number.
    pub mach: f64,
    /// Dynamic pressure, lbf/ft^2.
    pub qbar_psf: f64,
}

/// Density, temperature and speed of sound at `alt_ft`; Mach and dynamic pressure at `vt_fps`.
#[inline]
pub fn air_data(vt_fps: f64, alt_ft: f64) -> AirData {
    let tfac = 1.0 - TEMPERATURE_RATIO_LAPSE_PER_FT * alt_ft;
    // The temperature breaks at 35,000 ft; the density formula deliberately does not (book, Appendix A).
    let temperature_degr = if alt_ft >= STRATOSPHERE_ALT_FT { 390.0 } else { 519.0 * tfac };
    let density_slugft3 = SEA_LEVEL_DENSITY_SLUGFT3 * tfac.powf(4.14);
    let speed_of_sound_fps = (1.4 * 1716.3 * temperature_degr).sqrt();
    AirData {
        density_slugft3,
        temperature_degr,
        speed_of_sound_fps,
        mach: vt_fps / speed_of_sound_fps,
        qbar_psf: 0.5 * density_slugft3 * vt_fps * vt_fps,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sea_level_is_the_book_standard_day() {
        let a = air_data(0.0, 0.0);
        assert_eq!(a.density_slugft3, 2.377e-3);
        assert_eq!(a.temperature_degr, 519.0);
        // a = sqrt(1.4 * 1716.3 * 519) = 1116.7 ft/s (the 1976 standard atmosphere gives 1116.45 ft/s).
        assert!((a.speed_of_sound_fps - 1116.72).abs() < 0.01, "{}", a.speed_of_sound_fps);
    }

    #[test]
    fn temperature_breaks_at_35000_ft_and_density_does_not() {
        let below = air_data(500.0, 34_999.999);
        let above = air_data(500.0, 35_000.0);
        assert!((below.temperature_degr - 391.3).abs() < 0.1);
        assert_eq!(above.temperature_degr, 390.0);
        assert!((below.density_slugft3 - above.density_slugft3).abs() < 1e-9);
        // 25,000 ft: the standard atmosphere gives about 1.07e-3 slug/ft^3 (1976 table: 1.0663e-3).
        let a = air_data(492.0, 25_000.0);
        assert!((a.density_slugft3 - 1.066e-3).abs() < 0.01e-3, "{}", a.density_slugft3);
        assert!((a.qbar_psf - 0.5 * a.density_slugft3 * 492.0 * 492.0).abs() < 1e-12);
    }
}
