//! The `held` criterion of an output: from a time on, for a while, within a band of its own value at that time. It
//! judges a hold by where it began, for a controller that holds what it found rather than a set point (Betaflight's
//! altitude hold, switched on in flight, holds the altitude it was engaged at).

use super::{Measured, figure};
use crate::criteria::HeldBand;

/// The limit in words: "within 0.5 of its value at 16 s, for 10 s".
pub(super) fn limit_words(h: HeldBand) -> String {
    format!("within {} of its value at {} s, for {} s", h.band, h.from_s, h.for_s)
}

/// Judge `held` on the series `t`, `x` of output `name`: its value at the first sample at or after `from_s` is the
/// reference, and every sample up to `from_s + for_s` must stay within `band` of it. `None` when the trace ends
/// before `from_s + for_s` (a hold not flown to its end is no evidence). The value is the widest departure.
pub(super) fn held(name: &str, t: &[f64], x: &[f64], h: HeldBand) -> Option<Measured> {
    let end_s = h.from_s + h.for_s;
    if t.last().is_none_or(|&last| last < end_s) {
        return None;
    }
    let first = t.iter().position(|&ti| ti >= h.from_s)?;
    let reference = x[first];
    let window = t[first..].iter().zip(&x[first..]).take_while(|(ti, _)| **ti <= end_s);
    // NaN, a flight no longer a number, is the widest departure there is.
    let (low, high, worst, at_s) =
        window.fold((reference, reference, 0.0_f64, h.from_s), |(low, high, worst, at_s), (&ti, &v)| {
            let off = if v.is_nan() { f64::INFINITY } else { (v - reference).abs() };
            let (worst, at_s) = if off > worst { (off, ti) } else { (worst, at_s) };
            (low.min(v), high.max(v), worst, at_s)
        });
    let measured = format!(
        "{} at {} s, then {} to {} (widest {} at {at_s:.2} s)",
        figure(reference),
        h.from_s,
        figure(low),
        figure(high),
        figure(worst)
    );
    let failure = (worst > h.band).then(|| {
        format!(
            "{name} left the band of +-{} around the {} it had at {} s: {} away at {at_s:.2} s, within the {} s it \
             should hold",
            h.band,
            figure(reference),
            h.from_s,
            figure(worst),
            h.for_s
        )
    });
    Some((measured, failure, worst))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::criteria::Criteria;
    use crate::judge::judge_flight;
    use crate::scenario::Scenario;
    use crate::trace::Trace;

    const HOLD: HeldBand = HeldBand { from_s: 0.02, for_s: 0.04, band: 0.5 };

    /// t = 0, 0.01, ... s.
    fn times(n: usize) -> Vec<f64> {
        (0..n).map(|k| k as f64 * 0.01).collect()
    }

    #[test]
    fn a_hold_is_judged_against_the_value_it_began_at_not_a_set_point() {
        // A climb to 3.1 m, then held within 0.3 of the 3.1 it had at 0.02 s; what comes after 0.06 s is not judged.
        let x = [0.0, 2.0, 3.1, 3.4, 2.9, 3.2, 3.0, 9.0];
        let (measured, failure, widest) = held("alt_m", &times(8), &x, HOLD).expect("flown to its end");
        assert_eq!(failure, None, "{measured}");
        assert!((widest - 0.3).abs() < 1e-9, "{widest}");
        assert_eq!(measured, "3.10 at 0.02 s, then 2.90 to 3.40 (widest 0.30 at 0.03 s)");
        // Sinking 0.6 below where the hold began fails, saying by how much and when.
        let sank = [0.0, 2.0, 3.1, 3.0, 2.5, 2.8, 3.0];
        let (_, failure, _) = held("alt_m", &times(7), &sank, HOLD).unwrap();
        let failure = failure.expect("0.6 is outside a band of 0.5");
        assert!(failure.contains("alt_m left the band of +-0.5 around the 3.10 it had at 0.02 s: 0.60 away at 0.04 s"));
        // A NaN fails; a trace ending before the hold's end is no evidence.
        let lost = [0.0, 2.0, 3.1, f64::NAN, 3.1, 3.1, 3.1];
        assert!(held("alt_m", &times(7), &lost, HOLD).unwrap().1.is_some());
        assert!(held("alt_m", &times(5), &x[..5], HOLD).is_none());
    }

    #[test]
    fn held_needs_no_set_point_and_is_judged_by_name_in_a_suite() {
        let mut trace = Trace::new(["t_s", "alt_m"].map(String::from).to_vec());
        trace.rows = times(8).iter().zip([0.0, 2.0, 3.1, 3.4, 2.9, 3.2, 3.0, 9.0]).map(|(t, a)| vec![*t, a]).collect();
        let c: Criteria =
            toml::from_str("[outputs.alt_m]\nheld = { from_s = 0.02, for_s = 0.04, band = 0.2 }").unwrap();
        c.validate_flight(0.07, &|_| false).expect("no set point needed");
        let j = judge_flight(&c, &Scenario::embedded_default(), Some(&trace), None);
        assert_eq!(j[0].criterion, "outputs.alt_m.held");
        assert_eq!(j[0].limit, "within 0.2 of its value at 0.02 s, for 0.04 s");
        assert!(!j[0].passed, "0.3 from 3.1 is outside 0.2");
        // A hold that would end after the run is refused, saying how to fix it.
        let e = c.validate_flight(0.05, &|_| false).unwrap_err();
        assert!(e.contains("`criteria.outputs.alt_m.held` ends at 0.06 s, after the run's 0.05 s"), "{e}");
    }
}
