//! The model's envelope: the states at which the equations of motion give numbers at all. Outside it the
//! Stevens & Lewis equations divide by zero (VT = 0; |beta| = 90 deg, where u^2 + w^2 = 0) or the atmosphere takes
//! a fractional power of a negative number (above [`ATMOSPHERE_CEILING_FT`]), and the derivatives come out NaN.
//! One check, used by `silrig plant derivative` on every input row and by `silrig_flight::sim::PlantRunner` (so by
//! `silrig sim` and the plant process alike) on every state it integrates. Pure: no I/O.
//!
//! This is not the aerodynamic data's reach (alpha -10..45 deg, |beta| <= 30 deg): the tables extrapolate beyond it
//! and the equations still give numbers there; campaigns call a flight that leaves the data "departed".

pub use super::atmosphere::ATMOSPHERE_CEILING_FT;
use super::{F16State, STATE_NAMES};

/// A state outside the model's envelope, naming the state (as in [`STATE_NAMES`]) and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{state}` = {value}: {problem}")]
pub struct EnvelopeError {
    /// The state at fault, as named in CSV headers (`vt_fps`, `alt_ft`, ...).
    pub state: &'static str,
    /// Its value, in the state's unit.
    pub value: f64,
    /// Why the model cannot take it.
    pub problem: String,
}

/// Check that the equations of motion are defined at `x`: every state a finite number, airspeed above 0, |beta|
/// below 90 deg, altitude at most the atmosphere's ceiling.
pub fn check(x: &F16State) -> Result<(), EnvelopeError> {
    let values = x.to_array();
    let error = |i: usize, problem: String| EnvelopeError { state: STATE_NAMES[i], value: values[i], problem };
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(error(i, "not a finite number".into()));
    }
    if x.vt_fps <= 0.0 {
        return Err(error(0, "the airspeed must be above 0 ft/s (the equations of motion divide by it)".into()));
    }
    if x.beta_rad.abs() >= std::f64::consts::FRAC_PI_2 {
        return Err(error(
            2,
            "|beta| must be below pi/2 rad (90 deg), where the velocity leaves the body's x-z plane and the \
             equations of motion divide by zero"
                .into(),
        ));
    }
    if x.alt_ft > ATMOSPHERE_CEILING_FT {
        return Err(error(
            11,
            format!(
                "above the atmosphere model's ceiling of {ATMOSPHERE_CEILING_FT:.0} ft (where its density reaches 0)"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::{ControlInputs, ExternalForcing, F16Model};

    fn cruise() -> F16State {
        F16State { vt_fps: 500.0, alpha_rad: 0.1, alt_ft: 10_000.0, power_pct: 20.0, ..Default::default() }
    }

    #[test]
    fn states_inside_give_finite_derivatives_and_states_outside_are_named() {
        let model = F16Model::default();
        let derivative = |x: &F16State| model.derivative(x, &ControlInputs::default(), &ExternalForcing::default());
        let inside =
            [cruise(), F16State { alt_ft: ATMOSPHERE_CEILING_FT, ..cruise() }, F16State { vt_fps: 1e-3, ..cruise() }];
        for x in inside {
            assert_eq!(check(&x), Ok(()));
            assert!(derivative(&x).iter().all(|v| v.is_finite()), "{x:?}");
        }
        for (x, state) in [
            (F16State { vt_fps: 0.0, ..cruise() }, "vt_fps"),
            (F16State { vt_fps: -5.0, ..cruise() }, "vt_fps"),
            (F16State { alt_ft: 150_000.0, ..cruise() }, "alt_ft"),
            (F16State { beta_rad: -std::f64::consts::FRAC_PI_2, ..cruise() }, "beta_rad"),
            (F16State { q_radps: f64::NAN, ..cruise() }, "q_radps"),
        ] {
            assert_eq!(check(&x).unwrap_err().state, state, "{x:?}");
        }
        // The two cases the guard exists for do give NaN without it.
        assert!(derivative(&F16State { vt_fps: 0.0, ..cruise() }).iter().any(|v| v.is_nan()));
        assert!(derivative(&F16State { alt_ft: 150_000.0, ..cruise() }).iter().any(|v| v.is_nan()));
        assert!(check(&F16State { alt_ft: 150_000.0, ..cruise() }).unwrap_err().to_string().contains("142248 ft"));
    }
}
