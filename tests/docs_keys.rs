//! The book's reference of the scenario and suite keys (docs/src/reference/scenario.md and suite.md) kept true by
//! the code that reads those files. Each row of a page's key tables (first column the full dotted key, a column
//! "example" with a TOML value, optionally "needs" with the other `key = value`s that value needs) is written into a
//! file, configs/robust.toml for a scenario key, a minimal suite for a suite key, and that file must load through
//! the loaders `silrig sim` and `silrig check` use (a scenario for the built-in F-16 also passes the F-16's own
//! checks); the same file with an unknown key beside it must be refused, naming that key, so a renamed key fails.
//! The other columns hold too: every value a row lists as "one of" loads; a documented range's included ends load
//! and a step beyond them is refused (an excluded end is refused); a "required" key's file without it is refused, and
//! omitting a key with a default in backticks loads the same as setting that default. The fault actions' table is
//! checked against the validation (targets, required keys, keys that do not apply), and the converse: every field
//! of the serde structs these files are read into, as the source declares them, has a row. Nothing here starts a
//! process.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SCENARIO_PAGE: &str = "docs/src/reference/scenario.md";
const SUITE_PAGE: &str = "docs/src/reference/suite.md";
/// A key no struct has: set beside a documented key, it must be refused.
const UNKNOWN: &str = "docs_unknown_key";
/// What each placeholder of the pages' keys stands for here: a name the F-16 and robust.toml have.
const PLACEHOLDERS: [(&str, &str); 5] = [
    ("<input>", "elevator_deg"),
    ("<output>", "alt_ft"),
    ("<parameter>", "gain_k"),
    ("<variable>", "pitch_cmd"),
    ("<key>", "initial.alpha_deg"),
];
/// Keys that hold a list of tables (`[[faults]]`, `[[cases]]`, `[[setpoint_steps]]`): a row's key below one sets it
/// in the first entry.
const TABLE_LISTS: [&str; 3] = ["faults", "cases", "setpoint_steps"];
/// The minimal suite every suite row starts from.
const MINIMAL_SUITE: &str = "name = \"docs\"\n[[cases]]\nname = \"c\"\n[cases.criteria]\n";

/// One row of a markdown table: its line in the page and its cells under their headers.
#[derive(Debug, Clone)]
struct Row {
    page: &'static str,
    line: usize,
    cells: Vec<(String, String)>,
}

impl Row {
    fn cell(&self, header: &str) -> Option<&str> {
        self.cells.iter().find(|(h, _)| h == header).map(|(_, c)| c.as_str())
    }

    /// The row's first cell without its backticks (the full dotted key, or the action).
    fn name(&self) -> String {
        let first = &self.cells[0].1;
        assert!(
            first.starts_with('`') && first.ends_with('`') && first.matches('`').count() == 2,
            "{}:{}: the first cell must be one `key` in backticks, got {first:?}",
            self.page,
            self.line
        );
        first.trim_matches('`').to_string()
    }

    fn at(&self) -> String {
        format!("{}:{} `{}`", self.page, self.line, self.name())
    }
}

/// Cells of a table line, split at the pipes that are not escaped (`\|` is a pipe inside a cell).
fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    let mut out = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => out.last_mut().unwrap().push(chars.next().unwrap()),
            '|' => out.push(String::new()),
            _ => out.last_mut().unwrap().push(c),
        }
    }
    out.into_iter().map(|c| c.trim().to_string()).collect()
}

/// The rows of every table of `page` whose first header is `first_header`.
fn table_rows(page: &'static str, first_header: &str) -> Vec<Row> {
    let text = std::fs::read_to_string(Path::new(ROOT).join(page)).unwrap_or_else(|e| panic!("{page}: {e}"));
    let lines: Vec<&str> = text.lines().collect();
    let mut rows = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        if !lines[i].starts_with('|') {
            i += 1;
            continue;
        }
        let header = cells(lines[i]);
        let mut j = i + 2;
        while j < lines.len() && lines[j].starts_with('|') {
            if header[0] == first_header {
                let c = cells(lines[j]);
                assert_eq!(c.len(), header.len(), "{page}:{}: {} cells under {} headers", j + 1, c.len(), header.len());
                rows.push(Row { page, line: j + 1, cells: header.iter().cloned().zip(c).collect() });
            }
            j += 1;
        }
        i = j;
    }
    assert!(!rows.is_empty(), "{page} has no table headed `{first_header}`");
    rows
}

/// The texts between pairs of backticks.
fn code_spans(cell: &str) -> Vec<String> {
    cell.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

/// A row's example: a TOML value in backticks.
fn example_of(row: &Row) -> toml::Value {
    let cell = row.cell("example").unwrap_or_else(|| panic!("{}: no example column", row.at()));
    let spans = code_spans(cell);
    assert!(
        spans.len() == 1 && cell == format!("`{}`", spans[0]),
        "{}: the example must be one TOML value in backticks, got {cell:?}",
        row.at()
    );
    value(&spans[0], &row.at())
}

/// A TOML value as a page writes it.
fn value(text: &str, at: &str) -> toml::Value {
    let mut t: toml::Table =
        toml::from_str(&format!("v = {text}")).unwrap_or_else(|e| panic!("{at}: {text:?} is not a TOML value: {e}"));
    t.remove("v").unwrap()
}

/// A dotted key's parts with the placeholders filled in.
fn parts(key: &str) -> Vec<String> {
    key.split('.')
        .map(|p| PLACEHOLDERS.iter().find(|(ph, _)| *ph == p).map_or(p, |(_, name)| name).to_string())
        .inspect(|p| assert!(!p.contains(['<', '>']), "`{key}`: unknown placeholder {p}"))
        .collect()
}

/// The table at `path` (created where missing; the first entry of a list of tables).
fn table_at<'a>(root: &'a mut toml::Table, path: &[String]) -> &'a mut toml::Table {
    let mut node = root;
    for (depth, part) in path.iter().enumerate() {
        if depth == 0 && TABLE_LISTS.contains(&part.as_str()) {
            let list = node.entry(part.clone()).or_insert_with(|| toml::Value::Array(vec![]));
            let toml::Value::Array(list) = list else { panic!("`{part}` is not a list of tables") };
            if list.is_empty() {
                list.push(toml::Value::Table(toml::Table::new()));
            }
            let toml::Value::Table(t) = &mut list[0] else { panic!("`{part}` is not a list of tables") };
            node = t;
        } else {
            let next = node.entry(part.clone()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
            let toml::Value::Table(t) = next else { panic!("`{}` is not a table", path[..=depth].join(".")) };
            node = t;
        }
    }
    node
}

fn set(root: &mut toml::Table, key: &[String], v: toml::Value) {
    let (last, parent) = key.split_last().unwrap();
    table_at(root, parent).insert(last.clone(), v);
}

/// The `key = value`s of a row's "needs" cell.
fn needs(row: &Row) -> Vec<(Vec<String>, toml::Value)> {
    let Some(cell) = row.cell("needs") else { return vec![] };
    code_spans(cell)
        .iter()
        .map(|span| {
            let (k, v) =
                span.split_once(" = ").unwrap_or_else(|| panic!("{}: needs `key = value`, got {span}", row.at()));
            (parts(k), value(v, &row.at()))
        })
        .collect()
}

/// The folder for the scenario files the checks write (each removed once loaded).
fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("docs_keys");
        std::fs::create_dir_all(&dir).unwrap();
        dir
    })
}

fn robust() -> toml::Table {
    toml::from_str(&std::fs::read_to_string(Path::new(ROOT).join("configs/robust.toml")).unwrap()).unwrap()
}

/// What a file loaded into, as text to compare (the Debug form of what the loader returned).
type Loaded = Result<String, String>;

/// Load a scenario as `silrig sim` and `silrig run` do, from a file of its own (the tests run in parallel); one for
/// the built-in F-16 (no plant FMU or parameters of a plant of your own) must pass the F-16's checks too.
fn load_scenario(doc: &toml::Table) -> Loaded {
    static N: AtomicUsize = AtomicUsize::new(0);
    let path = scratch().join(format!("scenario-{}-{}.toml", std::process::id(), N.fetch_add(1, Ordering::Relaxed)));
    std::fs::write(&path, doc.to_string()).unwrap();
    let loaded = silrig::rig::load_scenario(Some(&path), None);
    std::fs::remove_file(&path).unwrap();
    let s = loaded.map_err(|e| format!("{e:#}"))?;
    if s.plant.fmu.is_none() && s.plant.parameters.is_empty() {
        silrig::sim::check_for_f16(&s).map_err(|(key, problem)| format!("`{key}`: {problem}"))?;
    }
    Ok(format!("{s:?}"))
}

/// Load a suite as `silrig check` does (`Suite::load` is reading the file and this), as if it lay in configs/, so a
/// `scenario = "robust.toml"` is configs/robust.toml.
fn load_suite(doc: &toml::Table) -> Loaded {
    let beside = Path::new(ROOT).join("configs/docs-keys-suite.toml");
    let s = silrig::check::suite::Suite::from_toml(&doc.to_string(), Some(&beside)).map_err(|e| e.to_string())?;
    Ok(format!("{:?} {:?} {:?}", s.name, s.description, s.cases))
}

/// One end of a documented range, and whether the range includes it.
#[derive(Debug, Clone, Copy)]
struct Bound {
    at: f64,
    included: bool,
}

/// The range a "range or values" cell states before its first ';', in the forms the pages use: `a..b`, `(a, b]`,
/// `[a, b)`, `> a`, `>= a`, `a or more`, each of them after `each ` for a list; "run duration" is `duration_s`.
/// None for anything else (names, lists of values, words).
fn range(cell: &str, duration_s: f64) -> Option<[Option<Bound>; 2]> {
    let text = cell.split(';').next().unwrap().trim().replace("run duration", &duration_s.to_string());
    let text = text.strip_prefix("each ").unwrap_or(&text);
    let number = |t: &str| t.trim().replace(',', "").parse::<f64>().ok();
    let first_word = |t: &str| t.split([',', ' ']).next().unwrap_or("").to_string();
    let from = |at, included| Some([Some(Bound { at, included }), None]);
    if let Some(rest) = text.strip_prefix(">= ") {
        return from(number(&first_word(rest))?, true);
    }
    if let Some(rest) = text.strip_prefix("> ") {
        return from(number(&first_word(rest))?, false);
    }
    if let Some((n, _)) = text.split_once(" or more") {
        return from(number(n)?, true);
    }
    if text.starts_with(['(', '[']) {
        let close = text.find([')', ']'])?;
        let (a, b) = text[1..close].split_once(", ")?;
        return Some([
            Some(Bound { at: number(a)?, included: text.starts_with('[') }),
            Some(Bound { at: number(b)?, included: text[close..].starts_with(']') }),
        ]);
    }
    let (a, b) = text.split(' ').next()?.split_once("..")?;
    Some([Some(Bound { at: number(a)?, included: true }), Some(Bound { at: number(b)?, included: true })])
}

/// Values a documented range must accept, and values just beyond it it must refuse: each included end and one step
/// outside it, each excluded end and one step inside it (steps of 1 for a whole number).
fn probes([lower, upper]: [Option<Bound>; 2], whole: bool) -> (Vec<f64>, Vec<f64>) {
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    let span = match (lower, upper) {
        (Some(a), Some(b)) => b.at - a.at,
        _ => 1.0,
    };
    let step = |x: f64| if whole { 1.0 } else { 1e-6 * x.abs().max(1.0) };
    let into = if whole { 1.0 } else { span * 1e-3 };
    for (bound, outward) in [(lower, -1.0), (upper, 1.0)] {
        let Some(b) = bound else { continue };
        if b.included {
            inside.push(b.at);
            outside.push(b.at + outward * step(b.at));
        } else {
            outside.push(b.at);
            inside.push(b.at - outward * into);
        }
    }
    (inside, outside)
}

/// `x` in the shape of `example`: a whole number, a float, or a list of them all `x`.
fn shaped(example: &toml::Value, x: f64) -> Option<toml::Value> {
    match example {
        toml::Value::Integer(_) => Some(toml::Value::Integer(x as i64)),
        toml::Value::Float(_) => Some(toml::Value::Float(x)),
        toml::Value::Array(list) if !list.is_empty() => {
            Some(toml::Value::Array(list.iter().map(|v| shaped(v, x)).collect::<Option<Vec<_>>>()?))
        }
        _ => None,
    }
}

/// Each row's example (with what it needs) loads, every value it lists as "one of" loads, its documented range's
/// ends are where the validation puts them, and an unknown key beside it is refused by name. Returns the problems.
fn check_rows(rows: &[Row], base: &toml::Table, load: fn(&toml::Table) -> Loaded) -> Vec<String> {
    // The run duration the ranges speak of: robust.toml's, which a minimal suite's cases fly too.
    let duration_s = robust()["timing"]["duration_s"].as_float().unwrap();
    let mut problems = Vec::new();
    for row in rows {
        let key = parts(&row.name());
        let example = example_of(row);
        let mut doc = base.clone();
        for (k, v) in needs(row) {
            set(&mut doc, &k, v);
        }
        let with = |v: toml::Value| {
            let mut d = doc.clone();
            set(&mut d, &key, v);
            d
        };
        if let Err(e) = load(&with(example.clone())) {
            problems.push(format!("{}: the example {example} is refused: {e}", row.at()));
            continue;
        }
        let range_cell = row.cell("range or values").unwrap_or_default();
        if example.is_str() && range_cell.contains("one of") {
            for span in code_spans(range_cell) {
                let v = value(&span, &row.at());
                if let Err(e) = load(&with(v)) {
                    problems.push(format!("{}: the value {span} it lists is refused: {e}", row.at()));
                }
            }
        }
        let default = row.cell("default").unwrap_or_default();
        let mut without = doc.clone();
        table_at(&mut without, &key[..key.len() - 1]).remove(key.last().unwrap());
        if default.contains("required") {
            if load(&without).is_ok() {
                problems.push(format!("{}: documented as required, and a file without it loads", row.at()));
            }
        } else if default.starts_with('`') {
            let span = &code_spans(default)[0];
            let mut v = value(span, &row.at());
            if let (toml::Value::Float(_), toml::Value::Integer(i)) = (&example, &v) {
                v = toml::Value::Float(*i as f64);
            }
            match (load(&without), load(&with(v))) {
                (Ok(a), Ok(b)) if a == b => {}
                (Ok(_), Ok(_)) => {
                    problems.push(format!("{}: omitting it is not the same as setting the default {span}", row.at()))
                }
                (a, b) => problems.push(format!("{}: default {span}: omitted {a:?}, set {b:?}", row.at())),
            }
        }
        let whole = matches!(example, toml::Value::Integer(_));
        if let Some(bounds) = range(range_cell, duration_s)
            && shaped(&example, 0.0).is_some()
        {
            let (inside, outside) = probes(bounds, whole);
            for x in inside {
                if let Err(e) = load(&with(shaped(&example, x).unwrap())) {
                    problems
                        .push(format!("{}: {x} is within the documented {range_cell:?}, and refused: {e}", row.at()));
                }
            }
            for x in outside {
                if load(&with(shaped(&example, x).unwrap())).is_ok() {
                    problems.push(format!("{}: {x} is outside the documented {range_cell:?}, and accepted", row.at()));
                }
            }
        }
        // A key below a name of your choice has siblings by design.
        if row.name().ends_with('>') {
            continue;
        }
        let mut sibling = with(example.clone());
        let mut beside = key.clone();
        *beside.last_mut().unwrap() = UNKNOWN.into();
        set(&mut sibling, &beside, example.clone());
        match load(&sibling) {
            Ok(_) => {
                problems.push(format!("{}: an unknown key `{}` beside it is accepted", row.at(), beside.join(".")))
            }
            Err(e) if !e.contains(UNKNOWN) => {
                problems.push(format!("{}: an unknown key beside it is refused without naming it: {e}", row.at()))
            }
            Err(_) => {}
        }
    }
    problems
}

#[test]
fn every_scenario_key_on_the_page_loads_and_an_unknown_key_beside_it_is_refused() {
    let rows = table_rows(SCENARIO_PAGE, "key");
    let problems = check_rows(&rows, &robust(), load_scenario);
    assert!(problems.is_empty(), "{} of {} rows:\n{}", problems.len(), rows.len(), problems.join("\n"));
}

#[test]
fn every_suite_key_on_the_page_loads_and_an_unknown_key_beside_it_is_refused() {
    let rows = table_rows(SUITE_PAGE, "key");
    let base: toml::Table = toml::from_str(MINIMAL_SUITE).unwrap();
    load_suite(&base).expect("the minimal suite loads");
    let problems = check_rows(&rows, &base, load_suite);
    assert!(problems.is_empty(), "{} of {} rows:\n{}", problems.len(), rows.len(), problems.join("\n"));
}

/// The fault actions' table: each example loads; exactly the targets it names are accepted; each required key it
/// gives is missed when removed; every fault key it names neither required nor optional does not apply.
#[test]
fn the_fault_actions_table_says_what_the_validation_does() {
    let actions = table_rows(SCENARIO_PAGE, "action");
    let fault_rows: Vec<Row> =
        table_rows(SCENARIO_PAGE, "key").into_iter().filter(|r| r.name().starts_with("faults.")).collect();
    let always = ["at_s", "target", "action"];
    let mut problems = Vec::new();
    let with_fault = |fault: &toml::Table| {
        let mut doc = robust();
        doc.insert("faults".into(), toml::Value::Array(vec![toml::Value::Table(fault.clone())]));
        load_scenario(&doc)
    };
    for row in &actions {
        let label = row.name().trim_matches('"').to_string();
        let toml::Value::Table(example) = example_of(row) else {
            panic!("{}: the example must be an inline table", row.at())
        };
        if example.get("action").and_then(|a| a.as_str()) != Some(label.as_str()) {
            problems.push(format!("{}: the example's action is not {label:?}", row.at()));
        }
        if let Err(e) = with_fault(&example) {
            problems.push(format!("{}: the example is refused: {e}", row.at()));
            continue;
        }
        let targets = row.cell("targets").unwrap();
        for role in ["plant", "controller", "logger", "bridge"] {
            let mut f = example.clone();
            f.insert("target".into(), role.into());
            let listed = targets == "any" || targets.split(", ").any(|t| t == role);
            match (with_fault(&f), listed) {
                (Ok(_), false) => problems.push(format!("{}: target {role} is accepted, not listed", row.at())),
                (Err(e), true) => problems.push(format!("{}: target {role} is listed, refused: {e}", row.at())),
                _ => {}
            }
        }
        let required = code_spans(row.cell("required keys").unwrap());
        let optional = code_spans(row.cell("optional keys").unwrap());
        for key in required.iter().filter(|k| example.contains_key(*k)) {
            let mut f = example.clone();
            f.remove(key);
            if with_fault(&f).is_ok() {
                problems.push(format!("{}: `{key}` is listed as required, and the fault loads without it", row.at()));
            }
        }
        for other in &fault_rows {
            let key = other.name()["faults.".len()..].to_string();
            if always.contains(&key.as_str()) || required.contains(&key) || optional.contains(&key) {
                continue;
            }
            let mut f = example.clone();
            f.insert(key.clone(), example_of(other));
            match with_fault(&f) {
                Ok(_) => problems.push(format!("{}: `{key}` is not listed, and the fault takes it", row.at())),
                Err(e) if !e.contains("does not apply") => problems
                    .push(format!("{}: `{key}` is not listed, and is refused for another reason: {e}", row.at())),
                Err(_) => {}
            }
        }
        for key in &optional {
            if !example.contains_key(key) {
                let other = fault_rows.iter().find(|r| r.name() == format!("faults.{key}"));
                let Some(other) = other else {
                    problems.push(format!("{}: `{key}` has no `faults.{key}` row", row.at()));
                    continue;
                };
                let mut f = example.clone();
                f.insert(key.clone(), example_of(other));
                if let Err(e) = with_fault(&f) {
                    problems.push(format!("{}: the optional `{key}` is refused: {e}", row.at()));
                }
            }
        }
    }
    // The converse: every action the code names has a row.
    let source = std::fs::read_to_string(Path::new(ROOT).join("src/flight/fault.rs")).unwrap();
    let body = &source[source.find("pub fn label(self)").unwrap()..];
    let body = &body[..body.find("\n    }\n").unwrap()];
    let documented: BTreeSet<String> = actions.iter().map(|r| r.name().trim_matches('"').to_string()).collect();
    for label in body.split("=> \"").skip(1).map(|s| s[..s.find('"').unwrap()].to_string()) {
        if !documented.contains(&label) {
            problems.push(format!("{SCENARIO_PAGE}: the action {label:?} has no row"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The fields of `struct name` (or of every variant of `enum name`) in `file` as serde reads them: flattened and
/// skipped fields left out.
fn fields(file: &str, name: &str) -> Vec<String> {
    let source = std::fs::read_to_string(Path::new(ROOT).join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
    let lines: Vec<&str> = source.lines().collect();
    let start = lines
        .iter()
        .position(|l| {
            let l = l.trim_start_matches("pub ");
            l == format!("struct {name} {{") || l == format!("enum {name} {{")
        })
        .unwrap_or_else(|| panic!("{file} declares no struct or enum {name}"));
    let indent = if lines[start].contains("enum ") { "        " } else { "    " };
    let mut out = Vec::new();
    let mut attributes = String::new();
    for line in &lines[start + 1..] {
        if *line == "}" {
            break;
        }
        let Some(rest) = line.strip_prefix(indent).filter(|r| !r.starts_with(' ')) else { continue };
        if rest.starts_with("#[") {
            attributes += rest;
            continue;
        }
        let rest = rest.trim_start_matches("pub ");
        if let Some((field, _)) = rest.split_once(": ")
            && field.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            let skipped = attributes.contains("flatten")
                || attributes.contains("skip)")
                || attributes.contains("skip,")
                || attributes.contains("skip_deserializing");
            if !skipped && !out.contains(&field.to_string()) {
                out.push(field.to_string());
            }
        }
        if !rest.starts_with("///") {
            attributes.clear();
        }
    }
    // An internally tagged enum's tag is a key too.
    if let Some(tag) = lines[start.saturating_sub(3)..start].iter().find_map(|l| l.split("tag = \"").nth(1)) {
        out.push(tag[..tag.find('"').unwrap()].to_string());
    }
    assert!(!out.is_empty(), "{file}: {name} has no fields");
    out
}

/// The structs (and the one enum) scenario and suite files are read into, with the files that declare them and
/// the key prefix each has on each page.
const STRUCTS: [(&str, &str, &[&str], &[&str]); 23] = [
    ("src/flight/scenario.rs", "Scenario", &[""], &[]),
    ("src/model/vehicle.rs", "InitialCondition", &["initial"], &[]),
    ("src/flight/setpoints.rs", "Setpoint", &["setpoint"], &[]),
    ("src/flight/setpoints.rs", "SetpointStep", &["setpoint_steps"], &[]),
    ("src/flight/disturbance.rs", "Disturbance", &["disturbance"], &[]),
    ("src/flight/scenario.rs", "PlantOptions", &["plant"], &[]),
    ("src/flight/scenario.rs", "AeroScale", &["plant.aero_scale"], &[]),
    ("src/flight/scenario.rs", "ControllerOptions", &["controller"], &[]),
    ("src/model/control/mod.rs", "ControllerGains", &["controller"], &[]),
    ("src/model/control/rbf.rs", "RbfLayout", &["controller.rbf"], &[]),
    ("src/model/actuator.rs", "ActuatorLimits", &["actuators.<input>"], &[]),
    ("src/flight/timing.rs", "Timing", &["timing"], &[]),
    ("src/flight/fault.rs", "Fault", &["faults"], &[]),
    ("src/flight/dispersion.rs", "Distribution", &["dispersions.<key>"], &["cases.dispersions.<key>"]),
    // The rig's criteria have no row on the scenario page: see `rig_criteria_are_refused_in_a_scenario`.
    ("src/flight/criteria.rs", "Criteria", &[], &["cases.criteria"]),
    ("src/flight/criteria.rs", "OutputCriteria", &["criteria.outputs.<output>"], &["cases.criteria.outputs.<output>"]),
    (
        "src/flight/criteria.rs",
        "SettledBand",
        &["criteria.outputs.<output>.settled"],
        &["cases.criteria.outputs.<output>.settled"],
    ),
    (
        "src/flight/criteria.rs",
        "AbsMax",
        &["criteria.outputs.<output>.abs_max"],
        &["cases.criteria.outputs.<output>.abs_max"],
    ),
    (
        "src/flight/criteria.rs",
        "HeldBand",
        &["criteria.outputs.<output>.held"],
        &["cases.criteria.outputs.<output>.held"],
    ),
    ("src/flight/criteria.rs", "Settled", &["criteria.settled"], &["cases.criteria.settled"]),
    ("src/flight/criteria.rs", "BodyRateLimit", &["criteria.body_rate_max_dps"], &["cases.criteria.body_rate_max_dps"]),
    ("src/flight/criteria.rs", "Budget", &[], &["cases.criteria.compute_p99", "cases.criteria.sense_to_actuate_p99"]),
    ("src/tools/check/suite.rs", "SweepCase", &[], &["cases.sweep"]),
];
/// The suite file's own structs (private to the suite module).
const SUITE_STRUCTS: [(&str, &str); 2] = [("SuiteFile", ""), ("CaseFile", "cases")];
/// Structs with `deny_unknown_fields` in these files that no file a user writes is read into.
const NOT_WRITTEN: [&str; 1] = ["ActuatorSetLimits"];

fn documented(keys: &BTreeSet<String>, prefix: &str, field: &str) -> bool {
    let full = if prefix.is_empty() { field.to_string() } else { format!("{prefix}.{field}") };
    keys.iter().any(|k| *k == full || k.starts_with(&format!("{full}.")))
}

#[test]
fn every_key_the_code_reads_has_a_row() {
    let scenario: BTreeSet<String> = table_rows(SCENARIO_PAGE, "key").iter().map(Row::name).collect();
    let suite: BTreeSet<String> = table_rows(SUITE_PAGE, "key").iter().map(Row::name).collect();
    let mut missing = Vec::new();
    let mut check = |page: &str, keys: &BTreeSet<String>, file: &str, name: &str, prefix: &str| {
        for field in fields(file, name) {
            if !documented(keys, prefix, &field) {
                let full = if prefix.is_empty() { field } else { format!("{prefix}.{field}") };
                missing.push(format!("{page}: `{full}` ({name} in {file}) has no row"));
            }
        }
    };
    for (file, name, on_scenario, on_suite) in STRUCTS {
        for prefix in on_scenario {
            check(SCENARIO_PAGE, &scenario, file, name, prefix);
        }
        for prefix in on_suite {
            check(SUITE_PAGE, &suite, file, name, prefix);
        }
    }
    for (name, prefix) in SUITE_STRUCTS {
        check(SUITE_PAGE, &suite, "src/tools/check/suite.rs", name, prefix);
    }
    // A struct added to these files is either mapped above or said not to be written.
    let mapped: BTreeSet<&str> =
        STRUCTS.iter().map(|s| s.1).chain(SUITE_STRUCTS.iter().map(|s| s.0)).chain(NOT_WRITTEN).collect();
    for file in STRUCTS.iter().map(|s| s.0).collect::<BTreeSet<_>>() {
        let source = std::fs::read_to_string(Path::new(ROOT).join(file)).unwrap();
        let lines: Vec<&str> = source.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            if !line.starts_with("#[serde(") || !line.contains("deny_unknown_fields") {
                continue;
            }
            let decl = lines[i + 1..].iter().find(|l| !l.starts_with("#[")).unwrap();
            let name = decl.trim_start_matches("pub ").split([' ', '{', '<']).nth(1).unwrap();
            if !mapped.contains(name) {
                missing.push(format!("{file}: `{name}` refuses unknown keys, and this test maps it to no page"));
            }
        }
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

/// The criteria with no row on the scenario page are the rig's: set in a scenario's `[criteria]` (with the suite
/// page's example), each is refused as one for `silrig check`.
#[test]
fn rig_criteria_are_refused_in_a_scenario() {
    let scenario: BTreeSet<String> = table_rows(SCENARIO_PAGE, "key").iter().map(Row::name).collect();
    let suite_rows = table_rows(SUITE_PAGE, "key");
    let mut problems = Vec::new();
    let mut seen = 0;
    for field in fields("src/flight/criteria.rs", "Criteria") {
        if documented(&scenario, "criteria", &field) {
            continue;
        }
        let Some(row) = suite_rows.iter().find(|r| documented(&BTreeSet::from([r.name()]), "cases.criteria", &field))
        else {
            problems.push(format!("`criteria.{field}` is on neither page"));
            continue;
        };
        seen += 1;
        let mut doc = robust();
        let key = parts(&row.name().replacen("cases.criteria", "criteria", 1));
        set(&mut doc, &key, example_of(row));
        match load_scenario(&doc) {
            Ok(_) => problems.push(format!("`{}` is not on the scenario page, and a scenario takes it", key.join("."))),
            Err(e) if !e.contains("is judged by `silrig check` on the rig") => {
                problems.push(format!("`{}` is refused in a scenario for another reason: {e}", key.join(".")))
            }
            Err(_) => {}
        }
    }
    assert!(seen > 0, "the scenario page documents every criterion, the rig's too");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
