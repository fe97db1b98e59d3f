//! The in-process tools: [`sim`] flies a scenario's closed loop as `silrig sim` does
//! ([`silrig_tools::outputs::fly_one_process`], the same trace and summary, no files written) and [`sweep`] flies a
//! Monte Carlo campaign as `silrig sweep` does ([`silrig_tools::campaign::Campaign`], the same case table and
//! summary). Both fly the scenario's controller, or a Python controller handed to them (`controller=`, flown by
//! [`crate::in_process`] in the rig's in-process loop). Both run with the interpreter's lock released (a Python
//! controller takes it for its calls), and hand back columns: lists of floats, or NumPy arrays when asked
//! (`numpy=True`, NumPy imported then, never required otherwise).

use crate::in_process::{self, RaisedSlot};
use crate::silrig_error;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString};
use silrig_adapters::in_process::{FmuFlags, MakeController, Models};
use silrig_flight::scenario::Scenario;
use silrig_rig::session::Status;
use silrig_tools::campaign::{self, Campaign, report};
use std::path::PathBuf;

/// Where a scenario comes from.
enum Source {
    /// None: the embedded default scenario.
    Default,
    /// A file (FMU paths relative to it).
    File(PathBuf),
    /// TOML text.
    Text(String),
}

/// What names the scenario in errors when it was given as text.
const TEXT_ORIGIN: &str = "<scenario text>";

/// A `str` holding a newline or `=` is TOML text; any other `str` or `os.PathLike` is a file; None the default.
fn source(scenario: Option<&Bound<'_, PyAny>>) -> PyResult<Source> {
    let Some(scenario) = scenario.filter(|s| !s.is_none()) else { return Ok(Source::Default) };
    if let Ok(text) = scenario.cast::<PyString>() {
        let text = text.to_cow()?;
        if text.contains(['\n', '=']) {
            return Ok(Source::Text(text.into_owned()));
        }
    }
    Ok(Source::File(scenario.extract()?))
}

/// `{name: values}` in column order; values a list of floats, or a NumPy array with `numpy`.
fn columns<'py>(
    py: Python<'py>,
    names: &[String],
    values: Vec<Vec<f64>>,
    numpy: Option<&Bound<'py, PyModule>>,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for (name, column) in names.iter().zip(values) {
        out.set_item(name, float_column(py, column, numpy)?)?;
    }
    Ok(out)
}

fn float_column<'py>(
    py: Python<'py>,
    column: Vec<f64>,
    numpy: Option<&Bound<'py, PyModule>>,
) -> PyResult<Bound<'py, PyAny>> {
    match numpy {
        None => Ok(PyList::new(py, column)?.into_any()),
        Some(np) => {
            let bytes: Vec<u8> = column.iter().flat_map(|v| v.to_ne_bytes()).collect();
            // frombuffer reads the bytes in place (read-only); the copy is the caller's own, writable array.
            let array = np.call_method1("frombuffer", (PyBytes::new(py, &bytes), "float64"))?;
            array.call_method0("copy")
        }
    }
}

fn import_numpy<'py>(py: Python<'py>, numpy: bool) -> PyResult<Option<Bound<'py, PyModule>>> {
    numpy.then(|| py.import("numpy")).transpose()
}

fn json_to_python<'py>(py: Python<'py>, json: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (json,))
}

/// What a flight gives back, computed without the interpreter's lock.
struct Simulated {
    columns: Vec<String>,
    values: Vec<Vec<f64>>,
    summary_json: String,
    ended_early: Option<(f64, String)>,
    refusals: Vec<String>,
}

fn simulate(source: Source, controller: Option<MakeController>) -> Result<Simulated, String> {
    let scenario = match source {
        Source::Default => Scenario::embedded_default(),
        Source::File(path) => Scenario::load(&path).map_err(|e| e.to_string())?,
        Source::Text(text) => Scenario::from_toml(&text, TEXT_ORIGIN).map_err(|e| e.to_string())?,
    };
    let mut models = Models::open(&scenario).map_err(|e| format!("{e:#}"))?;
    if let Some(make) = controller {
        models.fly_controller(make);
    }
    let flight = silrig_tools::outputs::fly_one_process(&models, &scenario)?;
    let summary = silrig_flight::summary::summarize(&flight.trace, &scenario, flight.plant.as_ref());
    let summary_json = serde_json::to_string(&summary).map_err(|e| e.to_string())?;
    let trace = flight.trace;
    let values = (0..trace.columns.len()).map(|k| trace.rows.iter().map(|row| row[k]).collect()).collect();
    Ok(Simulated {
        columns: trace.columns,
        values,
        summary_json,
        ended_early: flight.ended_early,
        refusals: flight.refusals,
    })
}

/// A Python controller's maker and where its exception goes, when one was given.
fn given_controller(
    py: Python<'_>,
    controller: Option<&Bound<'_, PyAny>>,
    copy_per_flight: bool,
) -> PyResult<(Option<MakeController>, RaisedSlot)> {
    let raised = RaisedSlot::default();
    let make = controller
        .filter(|c| !c.is_none())
        .map(|c| in_process::maker(py, c, copy_per_flight, raised.clone()))
        .transpose()?;
    Ok((make, raised))
}

/// Fly a scenario's closed loop in this process, as `silrig sim` does (deterministic; no files written).
///
/// `scenario`: a scenario file (str or path), TOML text (a str holding a newline or `=`), or None for the embedded
/// default. `controller`: a `silrig.Controller` (what `serve()` flies) to fly in place of the scenario's, in the
/// lockstep rig's loop, so the trace is the one `silrig run --mode lockstep --controller-cmd` gives for it; its
/// `start` is handed a `silrig.InProcessSession`, and an exception it raises is raised here. Returns a dict: `trace` (`{column: values}` in trace.csv's order and with its values), `summary` (what
/// summary.json holds), `ended_early` (None, or `{"t_s": ..., "reason": ...}` when the flight ended before the
/// scenario's end; the trace holds it up to there) and `refusals` (what the rig refused on the way, as sentences).
/// With `numpy=True` each column is a NumPy float64 array instead of a list. A scenario that does not load raises
/// `SilrigError` (`ERR_SETUP`) naming the file, key and problem.
#[pyfunction]
#[pyo3(signature = (scenario = None, *, controller = None, numpy = false))]
pub fn sim<'py>(
    py: Python<'py>,
    scenario: Option<&Bound<'py, PyAny>>,
    controller: Option<&Bound<'py, PyAny>>,
    numpy: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let np = import_numpy(py, numpy)?;
    let source = source(scenario)?;
    let (make, raised) = given_controller(py, controller, false)?;
    let flown = py.detach(move || simulate(source, make));
    if let Some(err) = in_process::raised(&raised) {
        return Err(err);
    }
    let flown = flown.map_err(|e| silrig_error(py, Status::ErrSetup, e))?;
    let out = PyDict::new(py);
    out.set_item("trace", columns(py, &flown.columns, flown.values, np.as_ref())?)?;
    out.set_item("summary", json_to_python(py, &flown.summary_json)?)?;
    let ended_early = flown.ended_early.map(|(t_s, reason)| -> PyResult<_> {
        let e = PyDict::new(py);
        e.set_item("t_s", t_s)?;
        e.set_item("reason", reason)?;
        Ok(e)
    });
    out.set_item("ended_early", ended_early.transpose()?)?;
    out.set_item("refusals", flown.refusals)?;
    Ok(out)
}

/// What a sweep gives back, computed without the interpreter's lock.
struct Swept {
    cases_csv: String,
    summary_json: String,
    fly_s: f64,
    jobs: usize,
}

fn fly_sweep(
    source: Source,
    runs: u64,
    seed: Option<u64>,
    jobs: Option<usize>,
    controller: Option<MakeController>,
) -> Result<Swept, String> {
    let error = |e: anyhow::Error| format!("{e:#}");
    if !(1..=campaign::MAX_RUNS).contains(&runs) {
        return Err(format!("runs must be within 1..={}, got {runs}", campaign::MAX_RUNS));
    }
    let campaign = match source {
        Source::Default => Campaign::from_scenario(Scenario::embedded_default(), "the embedded default scenario"),
        Source::File(path) => Campaign::load(&path, &FmuFlags::default(), &campaign::RigCommands::default()),
        Source::Text(text) => Campaign::from_text(&text, TEXT_ORIGIN),
    }
    .map_err(error)?;
    let mut campaign = campaign;
    if let Some(make) = controller {
        campaign.models.fly_controller(make);
    }
    let seed = seed.unwrap_or(campaign.scenario.seed);
    let jobs = campaign.threads(campaign::jobs(jobs).map_err(error)?);
    let started = std::time::Instant::now();
    // As `silrig sweep` writes them, case by case in index order: cases.csv's rows and sweep.json's tally.
    let names = campaign.criterion_names();
    let columns = campaign.figure_columns().map_err(error)?;
    let mut cases_csv = report::cases_csv_header(&campaign.parameters, &columns, &names);
    let mut tally = campaign.tally(seed, &names);
    let interrupted = campaign
        .fly_each(seed, 0..runs, jobs, |case| {
            report::case_csv_row(&mut cases_csv, &case, &columns, names.len());
            tally.add(&case);
            Ok(())
        })
        .map_err(error)?;
    let fly_s = started.elapsed().as_secs_f64();
    let flown = tally.cases();
    let summary =
        tally.finish(interrupted.map(|i| format!("stopped by {} after {flown} of the {runs} cases asked", i.0)));
    Ok(Swept { cases_csv, summary_json: serde_json::to_string(&summary).map_err(|e| e.to_string())?, fly_s, jobs })
}

/// The cells of one line of cases.csv (a quoted cell may hold commas and doubled quotes).
fn csv_cells(line: &str) -> Vec<String> {
    let mut cells = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                cells.last_mut().expect("one cell at least").push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(String::new()),
            (c, _) => cells.last_mut().expect("one cell at least").push(c),
        }
    }
    cells
}

/// Fly a Monte Carlo campaign in this process, as `silrig sweep SCENARIO --runs N` does (no files written).
///
/// `scenario`: a scenario file with `[dispersions]` and `[criteria]` (str or path), or TOML text. `runs` cases,
/// dispersed with `seed` (default: the scenario's), on `jobs` threads (default: one per core). `controller`: a
/// `silrig.Controller` flown in place of the scenario's, a `copy.deepcopy` of it per case (as `sim` flies it; its
/// calls take the interpreter's lock, so its cases gain little from more threads). Returns a dict:
/// `cases`, the case table (`{column: values}`, the columns of cases.csv: `index` ints, `outcome` and `reason`
/// strings, the rest floats, NaN where cases.csv has an empty cell; NumPy arrays for the floats with `numpy=True`),
/// `summary` (what sweep.json holds: pass rate, worst cases, ...), `fly_s` (wall time of the flights, s) and
/// `jobs` (threads used). Progress goes to stderr as `silrig sweep` prints it. A scenario that cannot be swept raises
/// `SilrigError` (`ERR_SETUP`) saying why.
#[pyfunction]
#[pyo3(signature = (scenario, runs, *, seed = None, jobs = None, controller = None, numpy = false))]
pub fn sweep<'py>(
    py: Python<'py>,
    scenario: Option<&Bound<'py, PyAny>>,
    runs: u64,
    seed: Option<u64>,
    jobs: Option<usize>,
    controller: Option<&Bound<'py, PyAny>>,
    numpy: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let np = import_numpy(py, numpy)?;
    let source = source(scenario)?;
    let (make, raised) = given_controller(py, controller, true)?;
    let swept = py.detach(move || fly_sweep(source, runs, seed, jobs, make));
    if let Some(err) = in_process::raised(&raised) {
        return Err(err);
    }
    let swept = swept.map_err(|e| silrig_error(py, Status::ErrSetup, e))?;
    let mut lines = swept.cases_csv.lines();
    let names = csv_cells(lines.next().unwrap_or_default());
    let mut cells: Vec<Vec<String>> = vec![Vec::new(); names.len()];
    for line in lines {
        for (k, cell) in csv_cells(line).into_iter().enumerate().take(names.len()) {
            cells[k].push(cell);
        }
    }
    let cases = PyDict::new(py);
    for (name, column) in names.iter().zip(cells) {
        match name.as_str() {
            "index" => {
                let index: Vec<u64> = column.iter().map(|c| c.parse().unwrap_or(u64::MAX)).collect();
                cases.set_item(name, index)?
            }
            "outcome" | "reason" => cases.set_item(name, column)?,
            _ => {
                let values = column.iter().map(|c| c.parse().unwrap_or(f64::NAN)).collect();
                cases.set_item(name, float_column(py, values, np.as_ref())?)?
            }
        }
    }
    let out = PyDict::new(py);
    out.set_item("cases", cases)?;
    out.set_item("summary", json_to_python(py, &swept.summary_json)?)?;
    out.set_item("fly_s", swept.fly_s)?;
    out.set_item("jobs", swept.jobs)?;
    Ok(out)
}
