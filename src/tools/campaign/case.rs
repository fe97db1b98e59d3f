//! One case of a campaign: sample i of the scenario's dispersions flown in one process (its FMUs too) and judged by the
//! scenario's criteria. A pure function of (scenario, seed, index), so a case flown alone (`silrig sim --sample I`)
//! gives the numbers it gave inside any sweep, on any machine or shard.

use crate::outputs::{FlownScenario, fly_one_process};
use serde::{Deserialize, Serialize};
use silrig_adapters::in_process::Models;
use silrig_flight::criteria::{Criteria, Judgement};
use silrig_flight::dispersion;
use silrig_flight::judge::judge_flight;
use silrig_flight::scenario::Scenario;
use silrig_flight::setpoints::SetpointTrack;
use silrig_flight::signals::PlantSignals;
use silrig_flight::summary::{Summary, summarize};
use silrig_flight::trace::Trace;

/// How a case ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// Flown; every criterion met.
    Pass,
    /// Flown; a criterion failed.
    Fail,
    /// Could not be flown: the sampled scenario is out of range, or its initial condition cannot be trimmed.
    Infeasible,
}

impl Outcome {
    /// Name as in the outputs.
    pub fn label(self) -> &'static str {
        match self {
            Outcome::Pass => "pass",
            Outcome::Fail => "fail",
            Outcome::Infeasible => "infeasible",
        }
    }
}

/// Figures of a flown case (beside its criteria), from the summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseFigures {
    /// The summary's figures by `cases.csv` column, named by the plant's signals
    /// ([`silrig_flight::summary::Summary::case_figures`]); `None`: no such number (never settled, not a number).
    pub figures: Vec<(String, Option<f64>)>,
    /// A sustained oscillation at the end.
    pub limit_cycle: bool,
    /// When the aircraft left the aerodynamic data (alpha or beta beyond the tables, or a non-finite state), or
    /// the plant or controller stopped (an FMU's failed call), s.
    pub departed_at_s: Option<f64>,
}

impl CaseFigures {
    fn new(s: &Summary, departure: Option<(f64, String)>) -> Self {
        Self { figures: s.case_figures(), limit_cycle: s.limit_cycle, departed_at_s: departure.map(|(t, _)| t) }
    }

    /// The figure of column `name`, if the flight has one.
    pub fn figure(&self, name: &str) -> Option<f64> {
        self.figures.iter().find(|(n, _)| n == name).and_then(|(_, v)| *v)
    }
}

/// The first tick at which the flight leaves what the F-16's model knows: alpha or |beta| beyond the aerodynamic
/// tables (which only extrapolate there), or a state that is no longer a number. Returns when, and what. A trace
/// without the F-16's columns (a plant of the user's own) has no such bounds: None.
pub fn departure(trace: &Trace) -> Option<(f64, String)> {
    use silrig_model::plant::aero::{ALPHA_DATA_DEG, BETA_DATA_MAX_DEG};
    if !silrig_flight::trace::LOOP_COLUMNS.iter().all(|c| trace.index(c).is_some()) {
        return None;
    }
    let [t, alpha, beta] = ["t_s", "alpha_deg", "beta_deg"].map(|c| trace.index(c).expect("loop columns"));
    // The state columns run from t_s to alt_ft; the command columns after them are NaN without a command.
    let states = trace.index("alt_ft").expect("loop columns") + 1;
    trace.rows.iter().find_map(|r| {
        let why = if r[..states].iter().any(|v| !v.is_finite()) {
            "the state is no longer a number".to_string()
        } else if !(ALPHA_DATA_DEG.0..=ALPHA_DATA_DEG.1).contains(&r[alpha]) {
            format!(
                "alpha {:.1} deg left the aerodynamic data ({} .. {} deg)",
                r[alpha], ALPHA_DATA_DEG.0, ALPHA_DATA_DEG.1
            )
        } else if r[beta].abs() > BETA_DATA_MAX_DEG {
            format!("beta {:.1} deg left the aerodynamic data (|beta| <= {BETA_DATA_MAX_DEG} deg)", r[beta])
        } else {
            return None;
        };
        Some((r[t], why))
    })
}

/// Every `ENVELOPE_STEP`th tick of the set-point outputs is kept for the envelope plot.
pub const ENVELOPE_STEP: usize = 5;

/// One output the envelope draws: its name, its set point and its unit.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvelopeSignal {
    /// The output (`theta_deg`, `alt_m`).
    pub name: String,
    /// Its set point in the scenario, with any steps.
    pub setpoint: SetpointTrack,
    /// Its unit.
    pub unit: String,
}

/// What the envelope draws: every set point of `scenario` whose output the plant announces, in
/// [`silrig_flight::scenario::Setpoint::all`]'s order (the F-16's three angles first, then any other of its
/// outputs given one; the quadrotor's angles and `alt_m`). `plant` is `None` for the built-in F-16.
pub fn envelope_signals(scenario: &Scenario, plant: Option<&PlantSignals>) -> Vec<EnvelopeSignal> {
    let f16;
    let plant = match plant {
        Some(p) => p,
        None => {
            f16 = silrig_flight::f16_signals::f16_signals([0.0; 4]);
            &f16
        }
    };
    let signal = |(name, _): (&str, f64)| {
        let output = plant.outputs.iter().find(|o| o.name == name && o.in_trace)?;
        let setpoint = scenario.setpoint_track(name)?;
        Some(EnvelopeSignal { name: name.to_string(), setpoint, unit: output.unit.clone() })
    };
    scenario.setpoint.all().into_iter().filter_map(signal).collect()
}

/// One case's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// Sample index.
    pub index: u64,
    /// The sampled values, in the dispersions' key order.
    pub values: Vec<f64>,
    /// How it ended.
    pub outcome: Outcome,
    /// Infeasible: why; failed: the criteria that failed.
    pub reason: String,
    /// Figures of the flight (None if infeasible).
    pub figures: Option<CaseFigures>,
    /// The criteria, judged (empty if infeasible).
    pub judgements: Vec<Judgement>,
    /// (t, then each of [`envelope_signals`]) every `ENVELOPE_STEP` ticks (empty if infeasible); carried by shard
    /// files so a merged sweep draws the same envelope.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub envelope: Vec<Vec<f32>>,
}

/// A flown case in full: the sampled scenario, its trace and its summary (what `silrig sim --sample` writes).
pub struct Flight {
    /// The scenario with the case's sampled values.
    pub scenario: Scenario,
    /// Its trace.
    pub trace: Trace,
    /// The plant's signals when it is not the built-in F-16's reference loop (for its figures).
    pub plant: Option<PlantSignals>,
    /// Its control-quality figures.
    pub summary: Summary,
}

/// Case `index` of `scenario`'s dispersions under `seed`: its sampled values (in the dispersions' key order) and its
/// scenario, or why it is infeasible (the sampled scenario is out of range).
pub fn sample(scenario: &Scenario, seed: u64, index: u64) -> (Vec<f64>, Result<Scenario, String>) {
    let sampled = dispersion::sample(&scenario.dispersions, seed, index);
    let values: Vec<f64> = sampled.iter().map(|(_, v)| *v).collect();
    let case = scenario.with_values(&sampled).map_err(|e| format!("sampled scenario out of range: {e}"));
    (values, case)
}

/// The result of a case that could not be flown, and why.
pub fn infeasible(index: u64, values: Vec<f64>, reason: String) -> CaseResult {
    CaseResult {
        index,
        values,
        outcome: Outcome::Infeasible,
        reason,
        figures: None,
        judgements: Vec::new(),
        envelope: Vec::new(),
    }
}

/// Judge a flown case by `criteria`, the same way whichever loop flew it (so an in-process sweep and a sweep
/// through the rig give comparable results); returns the result and the flight.
pub fn judge(
    criteria: &Criteria,
    index: u64,
    values: Vec<f64>,
    case: Scenario,
    flown: FlownScenario,
) -> (CaseResult, Flight) {
    let FlownScenario { trace, plant, ended_early, refusals } = flown;
    let summary = summarize(&trace, &case, plant.as_ref());
    let judgements = judge_flight(criteria, &case, Some(&trace), Some(&summary));
    // A flight that left the model's envelope (or whose FMU failed) ended there; if it had not left the data
    // before, that is when.
    let departed = departure(&trace).or(ended_early);
    let mut failed: Vec<String> = judgements.iter().filter(|j| !j.passed).map(|j| j.criterion.clone()).collect();
    // A departure fails the case whatever the criteria say: past it the model has no data.
    if let Some((t, why)) = &departed {
        failed.insert(0, format!("departed at {t:.2} s: {why};"));
    }
    // What the rig refuses (a NaN command or output) is a fault of the controller or the plant under test.
    failed.extend(refusals.into_iter().map(|r| format!("{r};")));
    // Up to the first row that is no longer a number (a departed flight): nothing past it can be drawn. A trace
    // without a set-point output's column has no envelope to draw.
    let names = envelope_signals(&case, plant.as_ref()).into_iter().map(|s| s.name);
    let columns: Option<Vec<usize>> =
        std::iter::once("t_s".to_string()).chain(names).map(|c| trace.index(&c)).collect();
    let envelope = match columns {
        Some(columns) if columns.len() > 1 => trace
            .rows
            .iter()
            .step_by(ENVELOPE_STEP)
            .map(|r| columns.iter().map(|c| r[*c] as f32).collect::<Vec<f32>>())
            .take_while(|r| r.iter().all(|v| v.is_finite()))
            .collect(),
        _ => Vec::new(),
    };
    let result = CaseResult {
        index,
        values,
        outcome: if failed.is_empty() { Outcome::Pass } else { Outcome::Fail },
        reason: failed.join(" "),
        figures: Some(CaseFigures::new(&summary, departed)),
        judgements,
        envelope,
    };
    (result, Flight { scenario: case, trace, plant, summary })
}

/// Fly case `index` of `scenario`'s dispersions under `seed` in one process with `scenario`'s `models`; returns the
/// result and, when flown, the flight.
pub fn fly_with_trace(
    models: &Models,
    scenario: &Scenario,
    criteria: &Criteria,
    seed: u64,
    index: u64,
) -> (CaseResult, Option<Flight>) {
    let (values, case) = sample(scenario, seed, index);
    let case = match case {
        Ok(case) => case,
        Err(reason) => return (infeasible(index, values, reason), None),
    };
    let flown = match fly_one_process(models, &case) {
        Ok(flown) => flown,
        Err(e) => return (infeasible(index, values, e), None),
    };
    let (result, flight) = judge(criteria, index, values, case, flown);
    (result, Some(flight))
}

/// Fly case `index` (the result only).
pub fn fly(models: &Models, scenario: &Scenario, criteria: &Criteria, seed: u64, index: u64) -> CaseResult {
    fly_with_trace(models, scenario, criteria, seed, index).0
}
