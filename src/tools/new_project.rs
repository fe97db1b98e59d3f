//! `silrig new controller|plant --lang python|c|rust DIR`: a working starting point for a controller or a plant of
//! the user's own, written from the examples embedded in the binary (one source of truth: the examples are the
//! templates), with a scenario and a check suite of its own and a README that says how to build, fly and check it.
//! A plant's starting point also gets the example Python PID (`pid.py`), the controller that flies it.

use std::path::{Path, PathBuf};

/// What to start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// A controller, flown against the built-in F-16.
    Controller,
    /// A plant (a vehicle model), flown by the example PID.
    Plant,
}

/// In which language.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Lang {
    /// Python 3 over `silrig_client.py` (ctypes, no build).
    Python,
    /// C11 over `libsilrig_client.so` (a `build.sh` with `cc`).
    C,
    /// Rust over silrig's crates by path (`cargo build --release`).
    Rust,
}

/// One file written: its path inside DIR and its text.
type File = (&'static str, String);

const PYTHON_CLIENT: &str = include_str!("../../examples/python/silrig_client.py");
const PYTHON_CONTRACT: &str = include_str!("../../examples/python/silrig_contract.py");
const PYTHON_PID: &str = include_str!("../../examples/python/pid_attitude.py");
const C_CONTRACT: &str = include_str!("../../examples/c/silrig_contract.h");
/// silrig's own lock file: a Rust starting point builds with the versions silrig was tested with.
const CARGO_LOCK: &str = include_str!("../../Cargo.lock");

/// The silrig checkout this binary was built from (`src/tools/../..`), if it is still there.
fn built_from() -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent()?.parent()?;
    root.join("src/rig/Cargo.toml").exists().then(|| root.to_path_buf())
}

/// The files of a starting point: the program, what it links, scenario.toml and check.toml. `lib_dir` is where
/// `libsilrig_client.so` is (beside `silrig`), `silrig_path` the silrig checkout a Rust project depends on.
pub fn files(kind: Kind, lang: Lang, lib_dir: &Path, silrig_path: &Path) -> Vec<File> {
    let mut files: Vec<File> = match kind {
        Kind::Controller => vec![
            ("scenario.toml", silrig_flight::scenario::DEFAULT_SCENARIO_TOML.to_string()),
            ("check.toml", include_str!("../../examples/new/controller_check.toml").to_string()),
        ],
        Kind::Plant => vec![
            ("scenario.toml", include_str!("../../examples/new/plant_scenario.toml").to_string()),
            ("check.toml", include_str!("../../examples/new/plant_check.toml").to_string()),
            ("pid.py", PYTHON_PID.to_string()),
        ],
    };
    if kind == Kind::Plant || lang == Lang::Python {
        files.push(("silrig_client.py", PYTHON_CLIENT.to_string()));
        files.push(("silrig_contract.py", PYTHON_CONTRACT.to_string()));
    }
    match lang {
        Lang::Python => files.push(match kind {
            Kind::Controller => ("controller.py", PYTHON_PID.to_string()),
            Kind::Plant => ("plant.py", include_str!("../../examples/python/toy_plant.py").to_string()),
        }),
        Lang::C => {
            let (source, name) = match kind {
                Kind::Controller => (include_str!("../../examples/c/pid_attitude.c"), "controller"),
                Kind::Plant => (include_str!("../../examples/c/toy_plant.c"), "plant"),
            };
            files.push((if name == "plant" { "plant.c" } else { "controller.c" }, source.to_string()));
            files.push(("silrig_client.h", crate::contract::C_CLIENT_HEADER.to_string()));
            files.push(("silrig_contract.h", C_CONTRACT.to_string()));
            files.push(("build.sh", c_build_script(name, lib_dir)));
        }
        Lang::Rust => {
            let (manifest, main) = match kind {
                Kind::Controller => (
                    include_str!("../../examples/rust/pid_controller/Cargo.toml"),
                    include_str!("../../examples/rust/pid_controller/src/main.rs"),
                ),
                Kind::Plant => (
                    include_str!("../../examples/rust/toy_plant/Cargo.toml"),
                    include_str!("../../examples/rust/toy_plant/src/main.rs"),
                ),
            };
            files.push(("Cargo.toml", manifest.replace("\"../../../", &format!("\"{}/", silrig_path.display()))));
            files.push(("Cargo.lock", CARGO_LOCK.to_string()));
            files.push(("src/main.rs", main.to_string()));
        }
    }
    files.push(("README.md", readme(kind, lang)));
    files
}

/// How the program of a starting point runs, from DIR.
pub fn command(kind: Kind, lang: Lang) -> &'static str {
    match (kind, lang) {
        (Kind::Controller, Lang::Python) => "python3 controller.py",
        (Kind::Plant, Lang::Python) => "python3 plant.py",
        (Kind::Controller, Lang::C) => "./controller",
        (Kind::Plant, Lang::C) => "./plant",
        (Kind::Controller, Lang::Rust) => "target/release/pid_controller",
        (Kind::Plant, Lang::Rust) => "target/release/toy_plant",
    }
}

/// The build step of a starting point, from DIR (none for Python).
pub fn build_step(lang: Lang) -> Option<&'static str> {
    match lang {
        Lang::Python => None,
        Lang::C => Some("sh build.sh"),
        Lang::Rust => Some("cargo build --release"),
    }
}

/// The `silrig run` and `silrig check` flags that fly a starting point, from DIR.
pub fn fly_flags(kind: Kind, lang: Lang) -> String {
    match kind {
        Kind::Controller => format!("--controller-cmd \"{}\"", command(kind, lang)),
        Kind::Plant => format!("--plant-cmd \"{}\" --controller-cmd \"python3 pid.py\"", command(kind, lang)),
    }
}

fn c_build_script(name: &str, lib_dir: &Path) -> String {
    let lib = lib_dir.display();
    format!(
        "#!/bin/sh\n# Compile {name}.c against libsilrig_client.so, which is beside the silrig that wrote this file\n\
         # ({lib}); the binary finds it there at run time too (rpath).\nset -eu\ncd \"$(dirname \"$0\")\"\n\
         ${{CC:-cc}} -std=c11 -O2 -Wall -I. {name}.c -L\"{lib}\" -lsilrig_client -lm -Wl,-rpath,\"{lib}\" -o {name}\n"
    )
}

fn readme(kind: Kind, lang: Lang) -> String {
    let (what, program) = match kind {
        Kind::Controller => ("controller", "flies the built-in F-16 (scenario.toml, the default scenario)"),
        Kind::Plant => ("plant", "is flown by the example PID in Python (pid.py) through scenario.toml"),
    };
    let build = build_step(lang).map(|b| format!("{b}\n")).unwrap_or_default();
    let flags = fly_flags(kind, lang);
    format!(
        "# A {what} of your own\n\nWritten by `silrig new {what} --lang {lang}`: the example {what} as a starting \
         point. It {program}; check.toml is its check suite. Change the program, then:\n\n```sh\n{build}\
         silrig run --mode lockstep {flags} scenario.toml\nsilrig check check.toml {flags}\n```\n",
        lang = match lang {
            Lang::Python => "python",
            Lang::C => "c",
            Lang::Rust => "rust",
        },
    )
}

/// What `silrig new` prints after writing: the files, then the commands that build, fly and check it.
pub fn summary(kind: Kind, lang: Lang, dir: &Path, written: &[PathBuf]) -> String {
    let mut lines: Vec<String> = written.iter().map(|path| format!("wrote {}", path.display())).collect();
    lines.push(format!("next, in {}:", dir.display()));
    lines.extend(build_step(lang).map(|build| format!("  {build}")));
    let flags = fly_flags(kind, lang);
    lines.push(format!("  silrig run --mode lockstep {flags} scenario.toml"));
    lines.push(format!("  silrig check check.toml {flags}"));
    lines.join("\n") + "\n"
}

/// Write the starting point into `dir` (created; refused when it exists and is not empty) and return what was
/// written. `silrig_path` overrides the checkout a Rust project depends on.
pub fn write(kind: Kind, lang: Lang, dir: &Path, silrig_path: Option<&Path>) -> anyhow::Result<Vec<PathBuf>> {
    if std::fs::read_dir(dir).is_ok_and(|mut entries| entries.next().is_some()) {
        anyhow::bail!("{} is not empty: give a new folder (silrig new writes a whole starting point)", dir.display());
    }
    let silrig_path = match (silrig_path, lang) {
        (Some(p), _) => std::path::absolute(p)?,
        (None, Lang::Rust) => built_from().ok_or_else(|| {
            anyhow::anyhow!(
                "the silrig checkout this binary was built from ({}) is gone: give the path of a silrig checkout \
                 with --silrig-path, for the Rust project's dependencies",
                env!("CARGO_MANIFEST_DIR")
            )
        })?,
        (None, _) => PathBuf::new(),
    };
    if lang == Lang::Rust && !silrig_path.join("src/rig/Cargo.toml").exists() {
        anyhow::bail!("--silrig-path {}: not a silrig checkout (it has no src/rig/Cargo.toml)", silrig_path.display());
    }
    let exe = std::env::current_exe()?;
    let lib_dir = exe.parent().ok_or_else(|| anyhow::anyhow!("{} has no folder", exe.display()))?;
    let mut written = Vec::new();
    for (name, text) in files(kind, lang, lib_dir, &silrig_path) {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().expect("a file in DIR"))
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", path.parent().unwrap_or(dir).display()))?;
        std::fs::write(&path, text).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(kind: Kind, lang: Lang) -> Vec<&'static str> {
        files(kind, lang, Path::new("/lib"), Path::new("/silrig")).into_iter().map(|(n, _)| n).collect()
    }

    #[test]
    fn each_starting_point_has_its_program_a_scenario_a_suite_and_a_readme() {
        for kind in [Kind::Controller, Kind::Plant] {
            for lang in [Lang::Python, Lang::C, Lang::Rust] {
                let n = names(kind, lang);
                for needed in ["scenario.toml", "check.toml", "README.md"] {
                    assert!(n.contains(&needed), "{kind:?} {lang:?}: {n:?}");
                }
                // A plant is flown by the Python PID, whatever its language.
                assert_eq!(n.contains(&"pid.py"), kind == Kind::Plant, "{kind:?} {lang:?}: {n:?}");
            }
        }
        assert!(names(Kind::Controller, Lang::C).contains(&"build.sh"));
        assert!(names(Kind::Plant, Lang::Rust).contains(&"src/main.rs"));
    }

    #[test]
    fn a_rust_project_depends_on_the_given_checkout_and_c_links_the_given_library() {
        let rust = files(Kind::Controller, Lang::Rust, Path::new("/lib"), Path::new("/opt/silrig"));
        let manifest = &rust.iter().find(|(n, _)| *n == "Cargo.toml").unwrap().1;
        assert!(manifest.contains("silrig-rig = { path = \"/opt/silrig/src/rig\" }"), "{manifest}");
        assert!(!manifest.contains("../../../"), "{manifest}");
        let c = files(Kind::Plant, Lang::C, Path::new("/opt/bin"), Path::new(""));
        let build = &c.iter().find(|(n, _)| *n == "build.sh").unwrap().1;
        assert!(build.contains("plant.c -L\"/opt/bin\" -lsilrig_client"), "{build}");
    }

    #[test]
    fn a_folder_that_is_not_empty_is_refused() {
        let dir = std::env::temp_dir().join(format!("silrig-new-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("mine.txt"), "x").unwrap();
        let e = write(Kind::Controller, Lang::Python, &dir, None).unwrap_err().to_string();
        assert!(e.contains("is not empty"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }
}
