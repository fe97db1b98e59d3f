//! The wire contract as other languages see it: the checked-in C header and Python module are exactly what
//! `silrig contract` generates (so they cannot drift from the Rust types), the header compiles as C11 and C++11
//! with its static assertions on every size and offset holding, and Python's `ctypes` lays every field out at the
//! offset Rust gives it. Needs a C and a C++ compiler (`cc`, `c++`) and `python3`, which `.ci/run` installs.

use silrig::contract;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("silrig-contract-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(cmd: &mut Command) -> String {
    let o = cmd.output().unwrap_or_else(|e| panic!("cannot run {cmd:?} (is it installed?): {e}"));
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{cmd:?} failed:\n{text}");
    String::from_utf8_lossy(&o.stdout).to_string()
}

#[test]
fn checked_in_copies_are_what_silrig_contract_generates() {
    let regenerate = "regenerate with `silrig contract --c-header examples/c/silrig_contract.h --python \
                      examples/python/silrig_contract.py`";
    let header = std::fs::read_to_string(root().join("examples/c/silrig_contract.h")).unwrap();
    assert!(header == contract::c_header(), "examples/c/silrig_contract.h is out of date: {regenerate}");
    let module = std::fs::read_to_string(root().join("examples/python/silrig_contract.py")).unwrap();
    assert!(module == contract::python_module(), "examples/python/silrig_contract.py is out of date: {regenerate}");

    // The command writes the same bytes.
    let dir = temp_dir("cli");
    let (h, p) = (dir.join("h.h"), dir.join("m.py"));
    run(Command::new(env!("CARGO_BIN_EXE_silrig")).args(["contract", "--c-header"]).arg(&h).arg("--python").arg(&p));
    assert_eq!(std::fs::read_to_string(&h).unwrap(), header);
    assert_eq!(std::fs::read_to_string(&p).unwrap(), module);
    let text = run(Command::new(env!("CARGO_BIN_EXE_silrig")).arg("contract"));
    assert!(text.contains("silrig::CommandSample::v") && text.contains("service \"silrig/plant\""), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn c_dir_writes_every_header_the_c_examples_include() {
    let dir = temp_dir("c-dir");
    let include = dir.join("include");
    let printed = run(Command::new(env!("CARGO_BIN_EXE_silrig")).args(["contract", "--c-dir"]).arg(&include));
    let mut written: Vec<String> =
        std::fs::read_dir(&include).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    written.sort();
    assert_eq!(written, ["silrig_client.h", "silrig_contract.h"], "{printed}");
    for name in &written {
        let ours = std::fs::read_to_string(include.join(name)).unwrap();
        let checked_in = std::fs::read_to_string(root().join("examples/c").join(name)).unwrap();
        assert!(ours == checked_in, "{name}: `silrig contract --c-dir` writes another text than examples/c has");
        assert!(printed.contains(&format!("wrote {}", include.join(name).display())), "{printed}");
    }
    // The examples compile against what the command wrote and nothing else (a copy outside examples/c).
    for example in ["pid_attitude.c", "toy_plant.c"] {
        let source = dir.join(example);
        std::fs::copy(root().join("examples/c").join(example), &source).unwrap();
        run(Command::new("cc")
            .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-fsyntax-only", "-I"])
            .arg(&include)
            .arg(&source));
    }
    // The obligations of a raw peer are in the header's comments, not only in the text.
    let header = std::fs::read_to_string(include.join("silrig_contract.h")).unwrap();
    for rule in contract::PEER_RULES.iter().chain(&contract::SIGNAL_RULES) {
        assert!(header.contains(rule), "silrig_contract.h lacks the rule: {rule}");
    }
    assert!(header.contains("[setpoint]") && header.contains("input_hold"), "set points, uncommanded inputs");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_header_compiles_as_c_and_cpp_with_every_assertion_holding() {
    let dir = temp_dir("cc");
    let src = dir.join("use.c");
    // Uses every type, so an unused-type warning cannot hide one.
    std::fs::write(
        &src,
        "#include \"silrig_contract.h\"\nint main(void) {\n  static silrig_plant_sample_t p;\n  \
         static silrig_command_sample_t c;\n  static silrig_log_ack_sample_t a;\n  \
         static silrig_plant_info_t i;\n  \
         return (int)(p.header.seq + c.header.seq + a.rows_written + i.outputs_len) + (SILRIG_WIRE_LAYOUT_VERSION > 0u ? 0 : 1);\n}\n",
    )
    .unwrap();
    let include = root().join("examples/c");
    for (compiler, std) in [("cc", "-std=c11"), ("c++", "-std=c++11")] {
        let exe = dir.join(format!("use-{compiler}"));
        let lang: &[&str] = if compiler == "c++" { &["-x", "c++"] } else { &[] };
        run(Command::new(compiler)
            .args([std, "-Wall", "-Wextra", "-Werror", "-pedantic"])
            .args(lang)
            .arg("-I")
            .arg(&include)
            .arg(&src)
            .arg("-o")
            .arg(&exe));
        run(&mut Command::new(&exe));
    }

    // The client library's header, on top of it, is valid C and C++ too (the library itself is linked by the
    // examples in tests/clients.rs).
    let client = dir.join("client.c");
    std::fs::write(
        &client,
        "#include \"silrig_client.h\"\nint main(void) {\n  silrig_session *s = 0;\n  \
         return (int)sizeof(&silrig_session_open) + (int)sizeof(s) + SILRIG_ERR_COMMAND_REFUSED;\n}\n",
    )
    .unwrap();
    for (compiler, std) in [("cc", "-std=c11"), ("c++", "-std=c++11")] {
        let lang: &[&str] = if compiler == "c++" { &["-x", "c++"] } else { &[] };
        run(Command::new(compiler)
            .args([std, "-Wall", "-Wextra", "-Werror", "-pedantic", "-fsyntax-only"])
            .args(lang)
            .arg("-I")
            .arg(&include)
            .arg(&client));
    }

    // A header whose layout disagrees must not compile: the assertions are real.
    let broken = contract::c_header().replacen(
        "    silrig_sample_header_t header;\n",
        "    silrig_sample_header_t header;\n    uint64_t inserted;\n",
        1,
    );
    std::fs::write(dir.join("silrig_contract.h"), broken).unwrap();
    let o = Command::new("cc").args(["-std=c11", "-fsyntax-only", "-I"]).arg(&dir).arg(&src).output().unwrap();
    assert!(!o.status.success(), "a wrong layout compiled");
    assert!(String::from_utf8_lossy(&o.stderr).contains("offset of PlantSample"), "{o:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn python_ctypes_offsets_equal_rusts() {
    let names: Vec<String> = contract::types().iter().map(|t| format!("'{}'", t.name)).collect();
    let script = "import json, silrig_contract as c\n\
                  out = {}\n\
                  for name in [NAMES]:\n\
                  \x20   t = getattr(c, name)\n\
                  \x20   out[name] = {'size': c.ctypes.sizeof(t), 'type_name': t.type_name(),\n\
                  \x20                'fields': [[f[0], getattr(t, f[0]).offset, getattr(t, f[0]).size] for f in t._fields_]}\n\
                  print(json.dumps(out))\n"
        .replace("NAMES", &names.join(", "));
    let stdout = run(Command::new("python3").arg("-c").arg(script).env("PYTHONPATH", root().join("examples/python")));
    let got: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    for t in contract::types() {
        let g = &got[t.name];
        assert_eq!(g["size"], t.size, "{}", t.name);
        assert_eq!(g["type_name"], t.type_name, "{}", t.name);
        let fields = g["fields"].as_array().unwrap();
        assert_eq!(fields.len(), t.fields.len(), "{}", t.name);
        for (f, py) in t.fields.iter().zip(fields) {
            assert_eq!(py[0], f.name, "{}", t.name);
            assert_eq!(
                (py[1].as_u64().unwrap() as usize, py[2].as_u64().unwrap() as usize),
                (f.offset, f.size),
                "{}.{}",
                t.name,
                f.name
            );
        }
    }
}
