//! A sweep's figures (`histograms`, `scatter`, `envelope`), gathered case by case in index order in memory bounded
//! whatever the number of cases: the envelope's band of the passed cases as a running lowest and highest per tick,
//! the first failed cases drawn one by one, and for the histograms and the scatter every flown case up to
//! [`FIGURE_SAMPLE_MAX`], past it a sample of that many (the same cases whatever the threads or shards, and the
//! figures say so).

use super::case::{CaseResult, EnvelopeSignal, Outcome};
use super::report::{SweepSummary, spearman};
use silrig_flight::criteria::Criteria;
use silrig_plot::{Envelope, Histogram, Scatter};
use std::collections::BinaryHeap;
use std::path::{Path, PathBuf};

/// Flown cases in the histograms and the scatter, at most: beyond it, a sample of this many.
pub const FIGURE_SAMPLE_MAX: usize = 5000;
/// Failed cases drawn one by one in the envelope.
const ENVELOPE_FAILED_DRAWN: usize = 30;
/// Parameters in the scatter figure.
const SCATTER_PARAMETERS: usize = 4;

/// A flown case as the histograms and the scatter need it.
struct Point {
    /// Its rank in the sample: the cases of the smallest ranks are kept (a bottom-k sample, so which cases are kept
    /// depends on their indices alone, not on the order they came in).
    rank: u64,
    index: u64,
    values: Vec<f64>,
    /// Per criterion: its figure and whether it passed.
    judged: Vec<(Option<f64>, bool)>,
}

impl PartialEq for Point {
    fn eq(&self, other: &Self) -> bool {
        self.rank == other.rank
    }
}
impl Eq for Point {}
impl PartialOrd for Point {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Point {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.rank.cmp(&other.rank).then(self.index.cmp(&other.index))
    }
}

/// SplitMix64's finaliser: a case's index to its rank in the sample.
fn rank(index: u64) -> u64 {
    let mut z = index.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// What the figures need of the cases seen so far.
#[derive(Default)]
pub struct Figures {
    sample: BinaryHeap<Point>,
    flown: u64,
    failed: u64,
    /// Per envelope row: t, and the lowest and highest of each set-point output over the passed cases that reached
    /// it.
    band: Vec<(f32, Vec<f64>, Vec<f64>)>,
    /// The first failed cases' (t, then each set-point output), up to their departure.
    failed_drawn: Vec<Vec<Vec<f32>>>,
}

impl Figures {
    /// Take in the next case (cases come in index order).
    pub fn add(&mut self, c: &CaseResult) {
        if c.outcome == Outcome::Infeasible {
            return;
        }
        self.flown += 1;
        let (rank, index) = (rank(c.index), c.index);
        let full = self.sample.len() >= FIGURE_SAMPLE_MAX;
        if !full || self.sample.peek().is_some_and(|top| (rank, index) < (top.rank, top.index)) {
            if full {
                self.sample.pop();
            }
            let judged = c.judgements.iter().map(|j| (j.value, j.passed)).collect();
            self.sample.push(Point { rank, index, values: c.values.clone(), judged });
        }
        match c.outcome {
            Outcome::Pass => {
                for (k, r) in c.envelope.iter().enumerate() {
                    let signals = r.len() - 1;
                    if k == self.band.len() {
                        self.band.push((r[0], vec![f64::INFINITY; signals], vec![f64::NEG_INFINITY; signals]));
                    }
                    let (_, lo, hi) = &mut self.band[k];
                    for (a, v) in r[1..].iter().enumerate().take(lo.len()) {
                        lo[a] = lo[a].min(*v as f64);
                        hi[a] = hi[a].max(*v as f64);
                    }
                }
            }
            _ => {
                self.failed += 1;
                if self.failed_drawn.len() < ENVELOPE_FAILED_DRAWN {
                    // A departed flight is drawn up to its departure: past it the model has no data to show.
                    let until = c.figures.as_ref().and_then(|f| f.departed_at_s).unwrap_or(f64::INFINITY);
                    self.failed_drawn.push(c.envelope.iter().filter(|r| (r[0] as f64) <= until).cloned().collect());
                }
            }
        }
    }

    /// Draw `histograms`, `scatter` (the parameters that move the most-failed criterion's figure the most, by
    /// |Spearman's rho|) and `envelope` of the sweep `summary` into `out`; `signals` are what the cases' envelope rows
    /// carry ([`super::case::envelope_signals`]).
    pub fn write(
        self,
        summary: &SweepSummary,
        criteria: &Criteria,
        signals: &[EnvelopeSignal],
        out: &Path,
    ) -> anyhow::Result<Vec<PathBuf>> {
        use silrig_plot::{plot_envelope, plot_histograms, plot_scatter};
        let mut files = Vec::new();
        if self.flown == 0 {
            return Ok(files);
        }
        let (envelopes, envelope_title) = self.envelopes(summary, signals);
        let mut flown = self.sample.into_vec();
        flown.sort_by_key(|p| p.index);
        let sampled = (flown.len() as u64) < self.flown;
        let limits = criterion_limits(criteria);
        let mut title = format!("{}: {} cases, seed {}", summary.scenario, summary.runs, summary.seed);
        let of_sample = if sampled {
            title += &format!(" (a sample of {} of the {} flown drawn)", flown.len(), self.flown);
            " of the sample"
        } else {
            ""
        };
        let histograms = histograms(summary, &flown, &limits, of_sample, self.flown);
        let histogram_title = format!("{title}: criteria");
        let scatters = scatters(summary, &flown, &limits, &title);
        // Each figure is drawn on a thread of its own: drawing is most of a short sweep's time after its flying.
        let (h, s, e) = std::thread::scope(|scope| {
            let h = scope.spawn(|| plot_histograms(&histograms, out, "histograms", &histogram_title));
            let s = scope.spawn(|| scatters.map(|(panels, title)| plot_scatter(&panels, out, "scatter", &title)));
            // A plant with no set point on its outputs has no envelope to draw.
            let e = (!envelopes.is_empty()).then(|| plot_envelope(&envelopes, out, "envelope", &envelope_title));
            (h.join().expect("drawing does not panic"), s.join().expect("drawing does not panic"), e)
        });
        files.extend(h?);
        for drawn in [s, e].into_iter().flatten() {
            files.extend(drawn?);
        }
        Ok(files)
    }

    /// The envelope of the passed cases with the failed ones drawn, a panel per set-point output, and its title.
    fn envelopes(&self, summary: &SweepSummary, signals: &[EnvelopeSignal]) -> (Vec<Envelope>, String) {
        // A band row narrower than the signals (no case reached them) draws none of them.
        let at = |values: &[f64], a: usize| values.get(a).copied().unwrap_or(f64::NAN);
        let envelopes: Vec<Envelope> = signals
            .iter()
            .enumerate()
            .map(|(a, s)| Envelope {
                caption: envelope_caption(&s.name),
                unit: s.unit.clone(),
                band: self.band.iter().map(|(t, lo, hi)| (*t as f64, at(lo, a), at(hi, a))).collect(),
                failed: self
                    .failed_drawn
                    .iter()
                    .map(|rows| rows.iter().filter_map(|r| Some((r[0] as f64, *r.get(a + 1)? as f64))).collect())
                    .collect(),
                setpoint: s.setpoint.clone(),
            })
            .collect();
        let envelope_title = format!(
            "{}: {} cases, seed {}: set points, {} passed (band), {} of {} failed (drawn to their departure, if any)",
            summary.scenario,
            summary.runs,
            summary.seed,
            summary.passed,
            self.failed_drawn.len(),
            self.failed
        );
        (envelopes, envelope_title)
    }
}

/// A panel's caption: the attitude's by its axis (as the F-16's envelope has always named them), any other output
/// by its name.
fn envelope_caption(name: &str) -> String {
    match name {
        "phi_deg" => "φ roll".into(),
        "theta_deg" => "θ pitch".into(),
        "psi_deg" => "ψ yaw".into(),
        other => other.into(),
    }
}

/// A criterion's limit, if it has one.
fn limit_of(limits: &[(String, Option<f64>)], criterion: &str) -> Option<f64> {
    limits.iter().find(|(c, _)| c == criterion).and_then(|(_, l)| *l)
}

/// One histogram a criterion: its figure in every flown case (of the sample), with its limit.
fn histograms(
    summary: &SweepSummary,
    flown: &[Point],
    limits: &[(String, Option<f64>)],
    of_sample: &str,
    flown_total: u64,
) -> Vec<Histogram> {
    summary
        .failures_by_criterion
        .iter()
        .enumerate()
        .map(|(k, (criterion, failures))| {
            let limit = limit_of(limits, criterion);
            // Departed flights reach absurd figures; they are shown in the last bin, not as the axis.
            let cap = limit.map_or(f64::INFINITY, |l| 3.0 * l.abs().max(1e-9));
            let values: Vec<f64> = flown.iter().filter_map(|c| c.judged[k].0).map(|v| v.min(cap)).collect();
            let missing = flown.len() - values.len();
            let never = if missing > 0 { format!(", {missing}{of_sample} never") } else { String::new() };
            Histogram {
                caption: format!("{criterion}: {failures} of {flown_total} failed{never}"),
                unit: criterion_unit(criterion).into(),
                values,
                limit,
            }
        })
        .collect()
}

/// The criterion that failed most, and the parameters whose rank moves its figure most: one scatter panel each,
/// with the figure's title.
fn scatters(
    summary: &SweepSummary,
    flown: &[Point],
    limits: &[(String, Option<f64>)],
    title: &str,
) -> Option<(Vec<Scatter>, String)> {
    let (k, (criterion, _)) =
        summary.failures_by_criterion.iter().enumerate().max_by_key(|(k, (_, n))| (*n, usize::MAX - k))?;
    let figure: Vec<f64> = flown.iter().map(|c| c.judged[k].0.unwrap_or(f64::INFINITY)).collect();
    let mut influence: Vec<(usize, f64)> = (0..summary.parameters.len())
        .map(|p| {
            let x: Vec<f64> = flown.iter().map(|c| c.values[p]).collect();
            (p, spearman_or_zero(&x, &figure))
        })
        .collect();
    influence.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()).then(a.0.cmp(&b.0)));
    // Departed flights reach absurd figures: the axis stops at 3x the limit, and a case beyond it (or that never
    // settled) is drawn at that edge.
    let largest = figure.iter().copied().filter(|v| v.is_finite()).fold(0.0_f64, f64::max);
    let shown = limit_of(limits, criterion).map_or(largest, |l| largest.min(3.0 * l.abs()));
    let panels = influence
        .iter()
        .take(SCATTER_PARAMETERS)
        .map(|(p, rho)| {
            let split = |passed: bool| {
                flown
                    .iter()
                    .filter(|c| c.judged[k].1 == passed)
                    .map(|c| (c.values[*p], c.judged[k].0.unwrap_or(shown).min(shown)))
                    .collect()
            };
            Scatter {
                caption: format!("{} (Spearman rho {rho:+.2})", summary.parameters[*p]),
                x_desc: summary.parameters[*p].clone(),
                y_desc: format!("{} (cap {shown:.3})", criterion_unit(criterion)),
                passed: split(true),
                failed: split(false),
            }
        })
        .collect();
    Some((panels, format!("{title}: what drives {criterion}")))
}

fn spearman_or_zero(x: &[f64], y: &[f64]) -> f64 {
    let r = spearman(x, y);
    if r.is_finite() { r } else { 0.0 }
}

/// The unit of a criterion's figure (as `Judgement::value` holds it).
fn criterion_unit(criterion: &str) -> &'static str {
    match criterion {
        "settled" => "settling time (s)",
        "alpha_max_deg" => "largest alpha (deg)",
        "overshoot_max_deg" => "overshoot (deg)",
        "final_error_max_deg" => "final error (deg)",
        "body_rate_max_dps" => "late |p|,|q|,|r| (deg/s)",
        "rate_limit_fraction_max" => "ticks at rate limit",
        "position_limit_fraction_max" => "ticks at position limit",
        "no_sustained_oscillation" => "oscillation / threshold",
        _ => "",
    }
}

/// Each flight criterion's limit as a number in the unit of its figure.
fn criterion_limits(c: &Criteria) -> Vec<(String, Option<f64>)> {
    vec![
        ("settled".into(), c.settled.map(|s| s.within_s)),
        ("alpha_max_deg".into(), c.alpha_max_deg),
        ("overshoot_max_deg".into(), c.overshoot_max_deg),
        ("final_error_max_deg".into(), c.final_error_max_deg),
        ("body_rate_max_dps".into(), c.body_rate_max_dps.map(|b| b.max)),
        ("rate_limit_fraction_max".into(), c.rate_limit_fraction_max),
        ("position_limit_fraction_max".into(), c.position_limit_fraction_max),
        ("no_sustained_oscillation".into(), Some(1.0)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sample_keeps_the_same_cases_whatever_order_they_come_in() {
        let case = |index: u64| CaseResult {
            index,
            values: vec![index as f64],
            outcome: Outcome::Pass,
            reason: String::new(),
            figures: None,
            judgements: Vec::new(),
            envelope: vec![vec![0.0, index as f32, 0.0, 0.0]],
        };
        let n = FIGURE_SAMPLE_MAX as u64 * 3;
        let (mut forward, mut backward) = (Figures::default(), Figures::default());
        (0..n).for_each(|i| forward.add(&case(i)));
        (0..n).rev().for_each(|i| backward.add(&case(i)));
        let kept = |f: Figures| {
            let mut v: Vec<u64> = f.sample.into_vec().iter().map(|p| p.index).collect();
            v.sort_unstable();
            v
        };
        assert_eq!(forward.band[0].1[0], 0.0);
        assert_eq!(forward.band[0].2[0], (n - 1) as f32 as f64);
        let (f, b) = (kept(forward), kept(backward));
        assert_eq!(f.len(), FIGURE_SAMPLE_MAX);
        assert_eq!(f, b);
        // Spread over the whole sweep, not its first cases.
        assert!(f.iter().filter(|i| **i >= 2 * n / 3).count() > FIGURE_SAMPLE_MAX / 4, "{:?}", &f[..10]);
    }
}
