//! The house's layers, checked: the library crates in `src/` depend only on crates below them (cargo refuses a
//! circle between crates, this test refuses a crate reaching up past its layer), the model and the flight reach no
//! transport, the model does no I/O, and inside every crate no file imports from a file that imports it back
//! (`crate::` and `super::` paths, test modules aside). A failure names the crate, the dependency or the circle.
//! The rooms' sizes (no file over 700 lines, no function over 80) are kept by its sibling, `tests/sizes.rs`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The library crates from the bottom up, each with the crates it may depend on.
const LAYERS: [(&str, &[&str]); 10] = [
    ("model", &[]),
    // The FMU importer knows no silrig crate: it opens, instantiates and steps any co-simulation FMU.
    ("fmi", &[]),
    ("flight", &["model"]),
    ("wire", &["model", "flight"]),
    // What the logger writes (CSV, MCAP) and replay reads: the wire's samples in files.
    ("recording", &["model", "flight", "wire"]),
    ("plot", &["flight"]),
    // The process bodies and sessions: they fly whatever plant model or controller they are handed.
    ("rig", &["model", "flight", "wire", "recording"]),
    // What turns a foreign or built-in thing (the F-16, our law, an FMU, a device over UDP) into a plant or a
    // controller, and which of them a process flies.
    ("adapters", &["model", "flight", "wire", "rig", "fmi"]),
    // The launcher checks a run's FMUs through their adapters before it starts anything.
    ("launch", &["flight", "wire", "recording", "plot", "rig", "adapters"]),
    // `silrig export-fmu` writes the description the FMU's binary checks its GUID with.
    ("tools", &["model", "flight", "wire", "recording", "plot", "rig", "adapters", "launch", "fmu-f16-description"]),
];

/// The crates beside the layers, each linking only what its users need: the C ABI a user's controller loads, the
/// Zenoh bridge, and the F-16 as an FMU (the model alone: an importer loads it into any process).
const LEAVES: [(&str, &[&str]); 4] = [
    ("client", &["wire", "rig"]),
    ("bridge", &["model", "flight", "wire", "rig"]),
    ("fmu_f16", &["model", "fmu-f16-description"]),
    ("fmu_f16_description", &["model"]),
];

/// Crates that link the rig with the OS or draw: never below the wire, nor (plotting) under the client.
const TRANSPORT_DEPS: [&str; 4] = ["iceoryx2", "libc", "mcap", "zenoh"];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The `[dependencies]` names of a member crate's manifest.
fn dependencies(krate: &str) -> BTreeSet<String> {
    let manifest = std::fs::read_to_string(src().join(krate).join("Cargo.toml")).unwrap();
    let table = manifest.split("[dependencies]").nth(1).unwrap_or("").split("\n[").next().unwrap();
    table
        .lines()
        .filter_map(|l| l.split(['=', '.', ' ']).next())
        .filter(|name| !name.is_empty() && !name.starts_with('#'))
        .map(str::to_string)
        .collect()
}

#[test]
fn every_crate_depends_only_on_the_layers_below_it() {
    for (krate, allowed) in LAYERS.into_iter().chain(LEAVES) {
        for dep in dependencies(krate).iter().filter_map(|d| d.strip_prefix("silrig-")) {
            assert!(
                allowed.contains(&dep),
                "silrig-{krate} depends on silrig-{dep}, which is not below it: {allowed:?}"
            );
        }
    }
    for krate in ["model", "flight"] {
        for dep in dependencies(krate) {
            assert!(!TRANSPORT_DEPS.contains(&dep.as_str()), "silrig-{krate} depends on the transport crate {dep}");
        }
    }
    let model = dependencies("model");
    for dep in ["clap", "toml", "plotters", "anyhow"] {
        assert!(!model.contains(dep), "silrig-model depends on {dep}: the model is plain math");
    }
    let wire = dependencies("wire");
    for dep in ["mcap", "foxglove", "lz4", "zstd"] {
        assert!(!wire.contains(dep), "silrig-wire depends on {dep}: files and their formats are silrig-recording's");
    }
    let client = dependencies("client");
    assert!(client.iter().all(|d| ["silrig-rig", "silrig-wire"].contains(&d.as_str())), "the client links {client:?}");
    let fmu = dependencies("fmu_f16");
    let alone = ["silrig-model", "silrig-fmu-f16-description"];
    assert!(fmu.iter().all(|d| alone.contains(&d.as_str())), "the FMU links {fmu:?}: the model alone");
}

/// Every `.rs` file of a crate with its module path (`""` for lib.rs, `a::b` for a/b.rs or a/b/mod.rs).
fn modules(krate: &str) -> BTreeMap<String, PathBuf> {
    fn walk(dir: &Path, prefix: &str, out: &mut BTreeMap<String, PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_stem().unwrap().to_str().unwrap().to_string();
            let joined = if prefix.is_empty() { name.clone() } else { format!("{prefix}::{name}") };
            if path.is_dir() {
                walk(&path, &joined, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let module = match name.as_str() {
                    "lib" if prefix.is_empty() => String::new(),
                    "mod" => prefix.to_string(),
                    _ => joined,
                };
                out.insert(module, path);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(&src().join(krate), "", &mut out);
    out
}

/// A file's code without comments and without its test module (which may use anything it tests).
fn code_of(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.split("#[cfg(test)]\nmod tests").next().unwrap();
    text.lines().map(|l| l.split("//").next().unwrap()).collect::<Vec<_>>().join("\n")
}

/// The paths a file names through `crate::` and `super::` (resolved to absolute segments in its crate); a group
/// `a::{b, c::d}` gives `a::b` and `a::c`.
fn named_paths(code: &str, module: &str) -> Vec<Vec<String>> {
    let bytes = code.as_bytes();
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut out = Vec::new();
    let mut at = 0;
    while at < code.len() {
        // Bytes, not `&code[at..]`: `at` steps through multi-byte characters such as `±`.
        let rest = &bytes[at..];
        let Some(base) = ["crate::", "super::"].into_iter().find(|b| rest.starts_with(b.as_bytes())) else {
            at += 1;
            continue;
        };
        if at > 0 && (ident(bytes[at - 1]) || bytes[at - 1] == b'$') {
            at += 1;
            continue;
        }
        let mut segments: Vec<String> = if base == "crate::" {
            Vec::new()
        } else {
            module.split("::").filter(|s| !s.is_empty()).map(str::to_string).collect()
        };
        if base == "super::" {
            segments.pop();
        }
        let mut i = at + base.len();
        loop {
            let start = i;
            while i < code.len() && ident(bytes[i]) {
                i += 1;
            }
            let word = &code[start..i];
            if word == "super" {
                segments.pop();
            } else if !word.is_empty() {
                segments.push(word.to_string());
            }
            let group =
                if code[i..].starts_with("::{") { Some(i + 3) } else { code[i..].starts_with('{').then_some(i + 1) };
            if let Some(open) = group {
                let close = code[open..].find('}').map_or(code.len(), |c| open + c);
                for member in code[open..close].split(',') {
                    let first = member.trim().split("::").next().unwrap_or("").trim();
                    if !first.is_empty() && first != "self" && first != "*" {
                        let mut path = segments.clone();
                        path.push(first.to_string());
                        out.push(path);
                    }
                }
                segments.clear();
                i = close;
                break;
            }
            if code[i..].starts_with("::") {
                i += 2;
            } else {
                break;
            }
        }
        if !segments.is_empty() {
            out.push(segments);
        }
        at = i.max(at + 1);
    }
    out
}

/// The module a path lands in: its longest prefix that is a file of the crate.
fn module_of(path: &[String], files: &BTreeMap<String, PathBuf>) -> Option<String> {
    (1..=path.len()).rev().map(|k| path[..k].join("::")).find(|m| files.contains_key(m))
}

/// A circle in `graph`, as the modules along it, if there is one.
fn find_circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        done: &mut BTreeSet<String>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|p| p == node) {
            let mut circle = path[at..].to_vec();
            circle.push(node.to_string());
            return Some(circle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(c) = visit(next, graph, done, path) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph.keys().find_map(|start| visit(start, graph, &mut done, &mut Vec::new()))
}

#[test]
fn no_crate_has_an_import_circle_between_its_files() {
    for (krate, _) in LAYERS.into_iter().chain(LEAVES) {
        let files = modules(krate);
        let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (module, path) in &files {
            let targets = named_paths(&code_of(path), module).into_iter().filter_map(|p| module_of(&p, &files));
            graph.entry(module.clone()).or_default().extend(targets.filter(|t| t != module));
        }
        if let Some(circle) = find_circle(&graph) {
            panic!("silrig-{krate}: import circle {}", circle.join(" -> "));
        }
    }
}

#[test]
fn the_circle_finder_sees_a_circle_through_a_group_and_super() {
    let files: BTreeMap<String, PathBuf> =
        ["", "ipc", "ipc::stream", "ipc::subscriber"].iter().map(|m| (m.to_string(), PathBuf::new())).collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, code) in [
        ("ipc::stream", "use super::{IpcError, subscriber::StreamSubscriber};"),
        ("ipc::subscriber", "fn f() { crate::ipc::stream::open(); } // crate::nothing"),
    ] {
        let code: String = code.lines().map(|l| l.split("//").next().unwrap()).collect();
        let targets = named_paths(&code, module).into_iter().filter_map(|p| module_of(&p, &files));
        graph.entry(module.to_string()).or_default().extend(targets.filter(|t| t != module));
    }
    assert_eq!(graph["ipc::stream"], BTreeSet::from(["ipc".to_string(), "ipc::subscriber".to_string()]));
    let circle = find_circle(&graph).expect("stream <-> subscriber is a circle");
    assert_eq!(circle.first(), circle.last());
    assert!(circle.contains(&"ipc::stream".to_string()) && circle.contains(&"ipc::subscriber".to_string()));
}

#[test]
fn the_model_does_no_io_and_reads_no_clock() {
    for (module, path) in modules("model") {
        let code = code_of(&path);
        for forbidden in ["std::fs", "std::io", "std::time", "std::thread", "std::process", "std::net", "std::env"] {
            assert!(!code.contains(forbidden), "silrig-model's {module} ({}) uses {forbidden}", path.display());
        }
    }
    let lib = std::fs::read_to_string(src().join("model/lib.rs")).unwrap();
    assert!(lib.contains("#![forbid(unsafe_code)]"));
}
