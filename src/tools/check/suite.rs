//! Check suites: the TOML a `silrig check` runs (cases, each a scenario, a mode, faults and criteria), the embedded
//! default suite, and the validation that refuses a malformed suite before anything flies, naming the case and key.

use super::criteria::{Criteria, RigCriteria};
use serde::Deserialize;
use silrig_flight::dispersion::Distribution;
use silrig_flight::fault::{Fault, parse_fault_flag};
use silrig_flight::scenario::Scenario;
use silrig_rig::RigMode;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The embedded default suite (what `silrig check` runs without a suite file).
pub const DEFAULT_SUITE_TOML: &str = include_str!("../../../configs/check-default.toml");
/// The embedded default suite for a plant of your own (`--plant-cmd`, `--plant-fmu` without a suite file).
pub const ANY_PLANT_SUITE_TOML: &str = include_str!("../../../configs/check-any-plant.toml");
/// The scenario its cases fly: set points and timing, nothing of the F-16.
pub use silrig_flight::scenario::ANY_PLANT_SCENARIO_TOML;

/// The scenario a case starts from when neither it nor its suite names one: its text and how errors name it.
#[derive(Debug, Clone, Copy)]
struct BaseScenario {
    text: &'static str,
    origin: &'static str,
}

/// The embedded default scenario (the F-16's), for a suite file and the default suite.
const DEFAULT_BASE: BaseScenario =
    BaseScenario { text: silrig_flight::scenario::DEFAULT_SCENARIO_TOML, origin: "embedded default scenario" };

/// A suite file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct SuiteFile {
    name: String,
    #[serde(default)]
    description: String,
    /// Scenario file every case starts from unless it names its own (relative to the suite file); default: the
    /// embedded default scenario.
    #[serde(default)]
    scenario: Option<PathBuf>,
    #[serde(default)]
    cases: Vec<CaseFile>,
}

/// One case as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseFile {
    name: String,
    #[serde(default)]
    why: String,
    #[serde(default)]
    scenario: Option<PathBuf>,
    /// Inline overrides of the scenario: a table merged key by key (e.g. `set.setpoint.phi_deg = 20`).
    #[serde(default)]
    set: Option<toml::Table>,
    #[serde(default = "realtime")]
    mode: RigMode,
    #[serde(default)]
    duration_s: Option<f64>,
    /// Faults in the `--fault` syntax of `silrig run`.
    #[serde(default)]
    faults: Vec<String>,
    /// A dispersed case: this many cases of the scenario's dispersions, judged on the pass rate.
    #[serde(default)]
    sweep: Option<SweepCase>,
    /// Dispersions added to the scenario's own (`[cases.dispersions]`, as a scenario's `[dispersions]`).
    #[serde(default)]
    dispersions: BTreeMap<String, Distribution>,
    criteria: Criteria,
}

/// `[cases.sweep]`: a case that is a Monte Carlo sweep of its scenario's dispersions, flown in one process like
/// `silrig sweep`, each dispersed case judged by `[cases.criteria]` (flight criteria only) and the whole case by
/// its pass rate.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepCase {
    /// Dispersed cases to fly (1..=100,000).
    pub runs: u64,
    /// Seed of the dispersions (default: the scenario's `seed`).
    #[serde(default)]
    pub seed: Option<u64>,
    /// The 95 % Wilson lower bound of the pass rate must be at least this (0..1]: 0.9 asks for 90 % with
    /// 95 % confidence.
    pub pass_rate_min: f64,
}

/// Most dispersed cases a sweep case may fly (a check is a gate, not the campaign itself).
pub const MAX_SWEEP_CASE_RUNS: u64 = 100_000;

fn realtime() -> RigMode {
    RigMode::Realtime
}

/// A suite ready to run: every case's scenario loaded and validated, its faults parsed.
#[derive(Debug, Clone)]
pub struct Suite {
    /// Short name (JUnit suite name, default output folder).
    pub name: String,
    /// What the suite is for.
    pub description: String,
    /// Where it came from: a path, or `None` for the embedded default.
    pub path: Option<PathBuf>,
    /// The cases, in order.
    pub cases: Vec<Case>,
}

/// One case: a run (or two, for determinism) and the criteria it is judged by.
#[derive(Debug, Clone)]
pub struct Case {
    /// Name (letters, digits, '-', '_'); `--case NAME` runs just this one.
    pub name: String,
    /// Why the case is in the suite, in one line.
    pub why: String,
    /// The scenario to fly, overrides, duration and faults applied.
    pub scenario: Scenario,
    /// realtime or lockstep.
    pub mode: RigMode,
    /// The fault flags as written (for the reproducing command and the report).
    pub fault_flags: Vec<String>,
    /// What the run must meet (a sweep case: each of its dispersed cases).
    pub criteria: Criteria,
    /// A sweep case's runs, seed and pass-rate bound (its scenario carries the dispersions and the criteria).
    pub sweep: Option<SweepCase>,
}

/// A suite that cannot be run, with where the problem is.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    /// The file could not be read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        cause: std::io::Error,
    },
    /// Malformed TOML, or an unknown or mistyped key (the parser's message names it).
    #[error("{origin}: {message}")]
    Parse {
        /// File name or "embedded default suite".
        origin: String,
        /// What the parser said.
        message: String,
    },
    /// A case that cannot be run as written.
    #[error("{origin}: case `{case}`: {problem}")]
    Case {
        /// File name or "embedded default suite".
        origin: String,
        /// The case's name.
        case: String,
        /// What is wrong, naming the key.
        problem: String,
    },
    /// A problem with the suite as a whole.
    #[error("{origin}: {problem}")]
    Suite {
        /// File name or "embedded default suite".
        origin: String,
        /// What is wrong.
        problem: String,
    },
}

/// Merge `overrides` into `base` key by key: tables merge, anything else replaces.
fn merge(base: &mut toml::Table, overrides: &toml::Table) {
    for (key, value) in overrides {
        match (base.get_mut(key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            _ => {
                base.insert(key.clone(), value.clone());
            }
        }
    }
}

impl Suite {
    /// The embedded default suite.
    pub fn embedded_default() -> Self {
        Self::from_toml(DEFAULT_SUITE_TOML, None).expect("the embedded default suite is valid")
    }

    /// The embedded default suite for a plant of your own: no F-16 scenario or criterion.
    pub fn embedded_any_plant() -> Self {
        let base = BaseScenario { text: ANY_PLANT_SCENARIO_TOML, origin: "embedded any-plant scenario" };
        Self::parse(ANY_PLANT_SUITE_TOML, None, base).expect("the embedded any-plant suite is valid")
    }

    /// Read a suite file; scenario paths in it are relative to its folder.
    pub fn load(path: &Path) -> Result<Self, SuiteError> {
        let text = std::fs::read_to_string(path)
            .map_err(|cause| SuiteError::Io { path: path.display().to_string(), cause })?;
        Self::from_toml(&text, Some(path))
    }

    /// Parse and validate suite text; `path` (None: embedded) names it in errors and anchors relative paths.
    pub fn from_toml(text: &str, path: Option<&Path>) -> Result<Self, SuiteError> {
        Self::parse(text, path, DEFAULT_BASE)
    }

    /// [`Suite::from_toml`], its cases starting from `base` when they name no scenario.
    fn parse(text: &str, path: Option<&Path>, base: BaseScenario) -> Result<Self, SuiteError> {
        let origin = path.map_or("embedded default suite".to_string(), |p| p.display().to_string());
        let file: SuiteFile = toml::from_str(text)
            .map_err(|e| SuiteError::Parse { origin: origin.clone(), message: e.to_string().trim_end().into() })?;
        let suite_err = |problem: String| SuiteError::Suite { origin: origin.clone(), problem };
        if !valid_name(&file.name) {
            return Err(suite_err(format!("`name` must be letters, digits, '-' or '_', got {:?}", file.name)));
        }
        if file.cases.is_empty() {
            return Err(suite_err("no [[cases]]".into()));
        }
        let dir = path.and_then(Path::parent).unwrap_or(Path::new("."));
        let mut cases: Vec<Case> = Vec::new();
        for c in &file.cases {
            let case_err = |problem: String| SuiteError::Case { origin: origin.clone(), case: c.name.clone(), problem };
            if !valid_name(&c.name) {
                return Err(case_err("`name` must be letters, digits, '-' or '_'".into()));
            }
            if cases.iter().any(|other| other.name == c.name) {
                return Err(case_err("a second case of this name".into()));
            }
            let scenario_path = c.scenario.as_ref().or(file.scenario.as_ref()).map(|p| dir.join(p));
            let mut scenario = case_scenario(c, scenario_path.as_deref(), base).map_err(case_err)?;
            match &c.sweep {
                Some(sweep) => sweep_scenario(c, sweep, &mut scenario).map_err(case_err)?,
                None if !c.dispersions.is_empty() => {
                    return Err(case_err(
                        "`dispersions` are flown by a sweep case: add `[cases.sweep]` with `runs` and \
                         `pass_rate_min`"
                            .into(),
                    ));
                }
                None => c.criteria.validate(c.mode, &scenario).map_err(case_err)?,
            }
            cases.push(Case {
                name: c.name.clone(),
                why: c.why.clone(),
                scenario,
                mode: c.mode,
                fault_flags: c.faults.clone(),
                criteria: c.criteria.clone(),
                sweep: c.sweep,
            });
        }
        Ok(Suite { name: file.name, description: file.description, path: path.map(Path::to_path_buf), cases })
    }

    /// Keep only the case named `name`.
    pub fn only(&mut self, name: &str) -> Result<(), String> {
        let names: Vec<&str> = self.cases.iter().map(|c| c.name.as_str()).collect();
        if !names.contains(&name) {
            return Err(format!("--case {name}: no such case; the suite has {}", names.join(", ")));
        }
        self.cases.retain(|c| c.name == name);
        Ok(())
    }
}

fn valid_name(name: &str) -> bool {
    !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
}

/// A sweep case's scenario: its criteria become the scenario's `[criteria]` (flight criteria only, as a sweep's),
/// and it must have dispersions; the case flies in lockstep. Errors name the key.
fn sweep_scenario(c: &CaseFile, sweep: &SweepCase, scenario: &mut Scenario) -> Result<(), String> {
    if c.mode != RigMode::Lockstep {
        return Err(
            "a sweep case flies its dispersed cases in one process, in lockstep: set `mode = \"lockstep\"`".into()
        );
    }
    if !(1..=MAX_SWEEP_CASE_RUNS).contains(&sweep.runs) {
        return Err(format!("`sweep.runs` must be within 1..={MAX_SWEEP_CASE_RUNS}, got {}", sweep.runs));
    }
    if !(sweep.pass_rate_min > 0.0 && sweep.pass_rate_min <= 1.0) {
        return Err(format!("`sweep.pass_rate_min` must be within (0, 1], got {}", sweep.pass_rate_min));
    }
    if scenario.dispersions.is_empty() {
        return Err("a sweep case needs dispersions: `[cases.dispersions]`, or a scenario with `[dispersions]`".into());
    }
    if !c.criteria.has_flight_criteria() {
        return Err(
            "a sweep case judges each dispersed case by flight criteria (settled, alpha_max_deg, outputs, ...): \
                    `[cases.criteria]` names none"
                .into(),
        );
    }
    scenario.criteria = Some(c.criteria.clone());
    scenario.validate().map_err(|(key, problem)| format!("`{key}`: {problem}"))
}

/// The case's scenario: the file (or the embedded default), the `set` overrides, the duration, the faults; validated
/// as `silrig run` would validate it. Errors name the key.
fn case_scenario(c: &CaseFile, path: Option<&Path>, base: BaseScenario) -> Result<Scenario, String> {
    let (text, origin) = match path {
        Some(p) => (
            std::fs::read_to_string(p).map_err(|e| format!("`scenario`: {}: {e}", p.display()))?,
            p.display().to_string(),
        ),
        None => (base.text.to_string(), base.origin.to_string()),
    };
    let mut table: toml::Table =
        toml::from_str(&text).map_err(|e| format!("`scenario`: {origin}: {}", e.to_string().trim_end()))?;
    if let Some(set) = &c.set {
        merge(&mut table, set);
    }
    if !c.dispersions.is_empty() {
        let dispersions = toml::Table::try_from(&c.dispersions).map_err(|e| format!("`dispersions`: {e}"))?;
        merge(&mut table, &toml::Table::from_iter([("dispersions".to_string(), toml::Value::Table(dispersions))]));
    }
    if let Some(d) = c.duration_s {
        let timing = table.entry("timing").or_insert_with(|| toml::Value::Table(toml::Table::new()));
        if let toml::Value::Table(t) = timing {
            t.insert("duration_s".into(), toml::Value::Float(d));
        }
    }
    let mut scenario = Scenario::from_toml(&table.to_string(), &format!("{origin} with the case's `set`"))
        .map_err(|e| e.to_string())?;
    // The case's scenario is written into its own folder: the files it names are read beside the scenario file.
    if let Some(p) = path {
        scenario.files_beside(p);
    }
    for (i, flag) in c.faults.iter().enumerate() {
        scenario.faults.push(parse_fault_flag(flag).map_err(|e| format!("`faults[{i}]`: {e}"))?);
    }
    scenario.validate().map_err(|(key, problem)| format!("`faults`: `{key}`: {problem}"))?;
    // The quadrotor's own checks (every key of the F-16's refused) need nothing that flies: a case is refused now.
    if silrig_flight::quad::is_quad(&scenario) {
        silrig_flight::quad::check_for_quad(&scenario).map_err(|(key, problem)| format!("`{key}`: {problem}"))?;
    }
    if c.mode == RigMode::Lockstep
        && let Some(f) = scenario.faults.iter().find(|f: &&Fault| !f.action().is_plant_model_fault())
    {
        return Err(format!("`faults`: {} needs `mode = \"realtime\"` (lockstep has no clock to fault)", f.describe()));
    }
    Ok(scenario)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_suite_and_the_shipped_suites_load() {
        let default = Suite::embedded_default();
        assert_eq!(default.cases.len(), 7);
        assert!(default.cases.iter().all(|c| !c.why.is_empty()), "every default case says why it is there");
        // A plant of your own: no F-16 section in the scenario, no F-16 criterion in the cases.
        let any = Suite::embedded_any_plant();
        assert_eq!(any.cases.len(), 4);
        for case in &any.cases {
            assert!(!case.why.is_empty());
            assert_eq!(case.scenario.name, "any-plant");
            let c = &case.criteria;
            assert!(c.setpoints_held.is_some() && c.settled.is_none(), "{}", case.name);
            assert!(c.alpha_max_deg.is_none() && c.body_rate_max_dps.is_none() && c.resume_jump_max_deg.is_none());
            assert!(c.rate_limit_fraction_max.is_none() && !c.no_sustained_oscillation && case.sweep.is_none());
        }
        let names: Vec<&str> = any.cases.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["lockstep-determinism", "realtime-deadline", "controller-kill-restart", "plant-restart"]);
        let paper =
            Suite::load(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/check-paper-gains.toml")))
                .expect("the paper-gains suite loads");
        assert_eq!(paper.cases[0].scenario.name, "paper");
        assert_eq!(paper.cases[1].scenario.name, "paper-next-tick");
        // A device's layout, named relative to the suite's scenario, is found from the case's own folder too.
        let bf = Suite::load(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/check-betaflight.toml")))
            .expect("the Betaflight suite loads");
        let layout = bf.cases[0].scenario.controller.device.clone().expect("a device");
        assert!(layout.is_absolute() && layout.ends_with("configs/devices/betaflight-sitl.toml"), "{layout:?}");
        assert!(layout.exists(), "{layout:?}");
    }

    #[test]
    fn set_overrides_merge_key_by_key_and_faults_parse() {
        let suite = Suite::from_toml(
            "name = \"s\"\n[[cases]]\nname = \"c\"\nduration_s = 4.0\nfaults = [\"plant:delay@1s,delay=15ms\"]\n\
             set.setpoint.phi_deg = 20.0\n[cases.criteria]\n",
            None,
        )
        .unwrap();
        let s = &suite.cases[0].scenario;
        assert_eq!((s.setpoint.phi_deg, s.setpoint.theta_deg), (20.0, 10.0), "only the key set changes");
        assert_eq!(s.timing.duration_s, 4.0);
        assert_eq!(s.faults.len(), 1);
        assert_eq!(suite.cases[0].mode, RigMode::Realtime, "realtime unless the case says otherwise");
    }

    #[test]
    fn bad_suites_name_the_case_and_the_key() {
        let err = |text: &str| Suite::from_toml(text, None).unwrap_err().to_string();
        let case = |body: &str| format!("name = \"s\"\n[[cases]]\nname = \"c\"\n{body}");
        assert!(err("name = \"s\"\n").contains("no [[cases]]"));
        assert!(err(&case("[cases.criteria]\nfoo = 1\n")).contains("unknown field `foo`"));
        assert!(
            err(&case("[cases.criteria]\nsettled = { within_s = 12.0, band_deg = 1.0 }\n"))
                .contains("case `c`: `criteria.settled.within_s` must be within 0..10 s")
        );
        assert!(err(&case("[cases.criteria]\ndeterministic = true\n")).contains("needs `mode = \"lockstep\"`"));
        assert!(
            err(&case("[cases.criteria]\nrecovered_within_s = 1.0\n"))
                .contains("needs a fault a process comes back from")
        );
        assert!(
            err(&case("[cases.criteria]\ncompute_p99 = {}\n"))
                .contains("needs one or more of `max_us`, `max_period_fraction` and `max_os_floor_ratio`")
        );
        assert!(err(&case("faults = [\"plant:explode@1s\"]\n[cases.criteria]\n")).contains("case `c`: `faults[0]`"));
        assert!(
            err(&format!("{}[[cases]]\nname = \"c\"\n[cases.criteria]\n", case("[cases.criteria]\n")))
                .contains("a second case of this name")
        );
    }
}
