//! The README and the book (docs/src) kept true: every ```console example is run and compared with what it prints,
//! and every relative link and `#anchor` resolves.
//!
//! A console example is trycmd's markdown form: `$ command` lines (a trailing `\` continues one on the next line),
//! each followed by what it prints (stdout and stderr as they interleave on one pipe), then optionally `? N` for an
//! exit status other than 0. In the expected text `[..]` matches anything within a line and a line `...` matches
//! any number of lines, so only what varies (times, pids, run ids, latencies) is left open. The commands of one
//! markdown file run in order, through bash, in one scratch folder of their own that links the repository's
//! top-level folders (`configs`, `examples`, `tests`, ...), with the release binaries first on PATH, so `--out x`
//! never lands in the repository. `SILRIG_DOCS_FILE=<part of a path>` runs the files that match only.

mod common;

use std::io::Read;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
/// A command slower than this is killed (with its process group) and fails its example.
const COMMAND_LIMIT: Duration = Duration::from_secs(300);

/// Every markdown file the checks cover: the README and the book's chapters.
fn markdown_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut files = vec![Path::new(ROOT).join("README.md")];
    walk(&Path::new(ROOT).join("docs/src"), &mut files);
    files
}

/// One `$ command` of a console block, with what it must print and its exit status.
#[derive(Debug)]
struct Example {
    line: usize,
    command: String,
    expected: Vec<String>,
    status: i32,
}

/// The console examples of a markdown file, in order.
fn console_examples(text: &str) -> Vec<Example> {
    let mut examples: Vec<Example> = Vec::new();
    let mut in_console = false;
    let mut in_other_block = false;
    let mut continuing = false;
    for (index, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("```") {
            if in_console || in_other_block {
                in_console = false;
                in_other_block = false;
            } else if trimmed.trim_start_matches('`').trim() == "console" {
                in_console = true;
            } else {
                in_other_block = true;
            }
            continuing = false;
            continue;
        }
        if !in_console {
            continue;
        }
        if continuing {
            let example = examples.last_mut().unwrap();
            example.command.push('\n');
            example.command.push_str(line);
            continuing = line.ends_with('\\');
        } else if let Some(command) = line.strip_prefix("$ ") {
            examples.push(Example { line: index + 1, command: command.to_string(), expected: Vec::new(), status: 0 });
            continuing = command.ends_with('\\');
        } else if let Some(status) = line.strip_prefix("? ") {
            let example = examples.last_mut().expect("`? N` before any `$ command`");
            example.status = status.trim().parse().unwrap_or_else(|_| panic!("line {}: `? {status}`", index + 1));
        } else {
            let example = examples.last_mut().unwrap_or_else(|| panic!("line {}: output before any `$ `", index + 1));
            example.expected.push(line.to_string());
        }
    }
    examples
}

/// Whether `actual` matches the pattern line `expected`, where `[..]` stands for any text.
fn line_matches(expected: &str, actual: &str) -> bool {
    let parts: Vec<&str> = expected.split("[..]").collect();
    if parts.len() == 1 {
        return expected == actual;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !actual.starts_with(first) || actual.len() < first.len() + last.len() || !actual.ends_with(last) {
        return false;
    }
    let mut rest = &actual[first.len()..actual.len() - last.len()];
    for part in &parts[1..parts.len() - 1] {
        match rest.find(part) {
            Some(at) => rest = &rest[at + part.len()..],
            None => return false,
        }
    }
    true
}

/// Whether the lines `actual` match the pattern `expected`, where a line `...` stands for any number of lines.
fn lines_match(expected: &[String], actual: &[&str]) -> bool {
    match expected.split_first() {
        None => actual.is_empty(),
        Some((first, rest)) if first == "..." => (0..=actual.len()).any(|skip| lines_match(rest, &actual[skip..])),
        Some((first, rest)) => !actual.is_empty() && line_matches(first, actual[0]) && lines_match(rest, &actual[1..]),
    }
}

/// A scratch folder for one markdown file's examples, holding links to the repository's top-level entries.
fn scratch_for(file: &Path) -> PathBuf {
    let name = file.strip_prefix(ROOT).unwrap().display().to_string().replace(['/', '.'], "_");
    let dir = common::temp_dir("docs", &name);
    for entry in std::fs::read_dir(ROOT).unwrap() {
        let entry = entry.unwrap();
        let entry_name = entry.file_name();
        if ["target", "out", ".git"].iter().any(|n| entry_name == *n) {
            continue;
        }
        std::os::unix::fs::symlink(entry.path(), dir.join(&entry_name)).unwrap();
    }
    dir
}

/// Runs `command` through bash in `dir` and returns its merged output and exit status.
fn run(command: &str, dir: &Path) -> (String, i32) {
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_silrig")).parent().unwrap();
    let path = format!("{}:{}", bin_dir.display(), std::env::var("PATH").unwrap_or_default());
    let (mut reader, writer) = std::io::pipe().unwrap();
    let mut child = Command::new("bash")
        .args(["-c", command])
        .current_dir(dir)
        .env("PATH", path)
        .stdin(Stdio::null())
        .stdout(writer.try_clone().unwrap())
        .stderr(writer)
        .process_group(0)
        .spawn()
        .unwrap();
    let pgid = child.id() as i32;
    let reading = std::thread::spawn(move || {
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).unwrap();
        bytes
    });
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > COMMAND_LIMIT {
            unsafe { libc::kill(-pgid, libc::SIGKILL) };
            break child.wait().unwrap();
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    // What the command left running in the background ends with it.
    unsafe { libc::kill(-pgid, libc::SIGKILL) };
    let mut output = String::from_utf8_lossy(&reading.join().unwrap()).into_owned();
    // Blank lines at the end are not shown in a console block.
    output.truncate(output.trim_end().len());
    (output, status.code().unwrap_or(128 + std::os::unix::process::ExitStatusExt::signal(&status).unwrap_or(0)))
}

/// Runs every console example of `file`; returns one message per example that printed something else.
fn check_file(file: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap();
    let examples = console_examples(&text);
    if examples.is_empty() {
        return Vec::new();
    }
    let dir = scratch_for(file);
    let shown = file.strip_prefix(ROOT).unwrap().display().to_string();
    let mut failures = Vec::new();
    let bridge_built = Path::new(env!("CARGO_BIN_EXE_silrig")).with_file_name("silrig-bridge").exists();
    for example in &examples {
        if example.command.starts_with("silrig-bridge") && !bridge_built {
            eprintln!("{shown}:{}: skipped: silrig-bridge is built with --features bridge only", example.line);
            continue;
        }
        let (output, status) = run(&example.command, &dir);
        let actual: Vec<&str> = output.lines().collect();
        if status != example.status || !lines_match(&example.expected, &actual) {
            failures.push(format!(
                "{shown}:{}: `{}` exited {status} (expected {}) and printed:\n{output}\n--- where the example says:\n{}\n",
                example.line,
                example.command,
                example.status,
                example.expected.join("\n")
            ));
        }
    }
    failures
}

#[test]
fn every_console_example_prints_what_the_docs_say() {
    // The examples fly controllers of other languages through the client library, which `cargo test` does not build.
    common::client_lib(env!("CARGO_BIN_EXE_silrig"));
    let only = std::env::var("SILRIG_DOCS_FILE").ok();
    let files: Vec<PathBuf> = markdown_files()
        .into_iter()
        .filter(|f| only.as_ref().is_none_or(|o| f.display().to_string().contains(o.as_str())))
        .collect();
    let total: usize = files.iter().map(|f| console_examples(&std::fs::read_to_string(f).unwrap()).len()).sum();
    assert!(only.is_some() || total >= 30, "only {total} console examples found: the parser lost some");
    // Two files at a time: realtime examples fly at their own pace, so a second one costs little.
    let queue = std::sync::Mutex::new(files);
    let failures = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| {
                loop {
                    let next = queue.lock().unwrap().pop();
                    let Some(file) = next else { break };
                    let found = check_file(&file);
                    failures.lock().unwrap().extend(found);
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} console example(s) differ from the docs:\n\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// mdBook's anchor of a heading: lower case, spaces to `-`, only letters, digits, `-` and `_` kept.
fn anchor_of(heading: &str) -> String {
    let text = heading.trim_start_matches('#').trim().replace('`', "");
    text.chars()
        .filter_map(|c| {
            if c.is_alphanumeric() || c == '_' || c == '-' {
                Some(c.to_ascii_lowercase())
            } else if c.is_whitespace() {
                Some('-')
            } else {
                None
            }
        })
        .collect()
}

/// The anchors of a markdown file's headings (outside code blocks).
fn anchors(text: &str) -> Vec<String> {
    let mut in_code = false;
    let mut found = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        } else if !in_code && line.starts_with('#') {
            found.push(anchor_of(line));
        }
    }
    found
}

/// The targets of a markdown file's links and images (`](target)`), outside code blocks and code spans.
fn link_targets(text: &str) -> Vec<(usize, String)> {
    let mut in_code = false;
    let mut targets = Vec::new();
    for (index, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        let mut outside_spans = String::new();
        for (k, piece) in line.split('`').enumerate() {
            if k % 2 == 0 {
                outside_spans.push_str(piece);
            }
        }
        let mut rest = outside_spans.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            targets.push((index + 1, after[..end].to_string()));
            rest = &after[end..];
        }
    }
    targets
}

#[test]
fn every_link_of_the_readme_and_the_book_resolves() {
    let mut broken = Vec::new();
    let files = markdown_files();
    assert!(files.len() > 10, "the book's chapters are missing: {files:?}");
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (line, target) in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, anchor) = match target.split_once('#') {
                Some((path, anchor)) => (path, Some(anchor)),
                None => (target.as_str(), None),
            };
            let resolved = if path.is_empty() { file.clone() } else { file.parent().unwrap().join(path) };
            let shown = format!("{}:{line}: `{target}`", file.strip_prefix(ROOT).unwrap().display());
            if !resolved.exists() {
                broken.push(format!("{shown}: no file {}", resolved.display()));
            } else if let Some(anchor) = anchor {
                if resolved.extension().is_none_or(|e| e != "md") {
                    continue;
                }
                let their = anchors(&std::fs::read_to_string(&resolved).unwrap());
                if !their.iter().any(|a| a == anchor) {
                    broken.push(format!("{shown}: no heading with anchor `{anchor}` (it has: {})", their.join(", ")));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_example_matcher_leaves_open_only_what_it_is_told() {
    let lines = |s: &str| s.lines().map(String::from).collect::<Vec<_>>();
    assert!(lines_match(&lines("a [..] c\n...\nend"), &["a b c", "x", "y", "end"]));
    assert!(lines_match(&lines("a [..] c\n...\nend"), &["a  c", "end"]));
    assert!(!lines_match(&lines("a [..] c\nend"), &["a b c", "x", "end"]));
    assert!(!lines_match(&lines("flag --out"), &["flag --output"]));
    assert!(line_matches("[..]x[..]y", "axbxy"));
    assert!(!line_matches("[..]x[..]y", "ayx"));
    let parsed = console_examples("```console\n$ a \\\n  b\nout\n? 2\n```\n```sh\n$ not run\n```\n");
    assert_eq!(parsed.len(), 1);
    assert_eq!(parsed[0].command, "a \\\n  b");
    assert_eq!(parsed[0].expected, vec!["out"]);
    assert_eq!(parsed[0].status, 2);
    assert_eq!(
        anchor_of("### FMUs: your modelling tool's plant (`--plant-fmu`)"),
        "fmus-your-modelling-tools-plant---plant-fmu"
    );
}

/// The subcommands of `silrig` that have subcommands of their own.
const NESTED: [&str; 3] = ["plant", "sweep", "bench"];

/// Every `silrig ...` (or `silrig-plant ...`, ...) command written in a code block or a code span of the docs,
/// with its line: the binary, its subcommand words and the `--flags` it uses.
fn commands_in_docs(text: &str) -> Vec<(usize, String, Vec<String>, Vec<String>)> {
    let mut found = Vec::new();
    let mut in_code = false;
    let mut in_commands = false;
    let mut pending = String::new();
    let mut pending_line = 0;
    for (index, line) in text.lines().enumerate() {
        if let Some(info) = line.trim_start().strip_prefix("```") {
            in_code = !in_code;
            in_commands = in_code && matches!(info.trim(), "sh" | "bash" | "console");
            continue;
        }
        if in_code && !in_commands {
            continue;
        }
        let mut pieces: Vec<String> = Vec::new();
        if in_code {
            if pending.is_empty() {
                pending_line = index + 1;
            }
            pending.push_str(line.trim_end_matches('\\'));
            pending.push(' ');
            if line.ends_with('\\') {
                continue;
            }
            pieces.push(std::mem::take(&mut pending));
        } else {
            pending_line = index + 1;
            pieces.extend(line.split('`').skip(1).step_by(2).map(String::from));
        }
        for piece in pieces {
            // A command ends at a pipe, a list operator or a comment.
            for part in piece.split(['|', ';', '&', '#', '(', ')']) {
                let words: Vec<&str> = part.split_whitespace().collect();
                let Some(at) = words.iter().position(|w| {
                    let name = w.rsplit('/').next().unwrap();
                    matches!(name, "silrig" | "silrig-plant" | "silrig-controller" | "silrig-logger" | "silrig-bridge")
                }) else {
                    continue;
                };
                let binary = words[at].rsplit('/').next().unwrap().to_string();
                let mut subcommand = Vec::new();
                let mut rest = &words[at + 1..];
                let is_word = |w: &&&str| !w.starts_with('-') && w.chars().all(|c| c.is_ascii_lowercase() || c == '-');
                if binary == "silrig"
                    && let Some(first) = rest.first().filter(is_word)
                {
                    subcommand.push(first.to_string());
                    rest = &rest[1..];
                    if NESTED.contains(first)
                        && let Some(second) = rest.first().filter(is_word)
                    {
                        subcommand.push(second.to_string());
                        rest = &rest[1..];
                    }
                }
                let flags: Vec<String> = rest
                    .iter()
                    .filter(|w| w.starts_with("--") && w.len() > 2)
                    .map(|w| w.split('=').next().unwrap().trim_end_matches([',', '.', ':', '"', '\'']).to_string())
                    .filter(|f| {
                        f.len() > 2 && f[2..].chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
                    })
                    .collect();
                found.push((pending_line, binary, subcommand, flags));
            }
        }
    }
    found
}

#[test]
fn every_flag_the_docs_write_exists() {
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_silrig")).parent().unwrap().to_path_buf();
    let mut helps: std::collections::HashMap<(String, Vec<String>), Option<String>> = Default::default();
    let mut wrong = Vec::new();
    let mut checked = 0;
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        for (line, binary, subcommand, flags) in commands_in_docs(&text) {
            let help = helps.entry((binary.clone(), subcommand.clone())).or_insert_with(|| {
                let exe = bin_dir.join(&binary);
                if !exe.exists() {
                    return None; // silrig-bridge without the bridge feature
                }
                let out = Command::new(exe).args(&subcommand).arg("--help").output().unwrap();
                out.status.success().then(|| String::from_utf8_lossy(&out.stdout).into_owned())
            });
            let shown =
                format!("{}:{line}: `{binary} {}`", file.strip_prefix(ROOT).unwrap().display(), subcommand.join(" "));
            let Some(help) = help else {
                if binary != "silrig-bridge" {
                    wrong.push(format!("{shown}: no such command"));
                }
                continue;
            };
            // The exit statuses page shows what an unknown flag gets.
            for flag in flags.into_iter().filter(|f| f != "--no-such-flag") {
                checked += 1;
                let known = help.split(|c: char| !(c.is_ascii_alphanumeric() || c == '-')).any(|w| w == flag);
                if !known {
                    wrong.push(format!("{shown}: no flag {flag}"));
                }
            }
        }
    }
    assert!(checked > 100, "only {checked} flags found in the docs: the parser lost some");
    assert!(wrong.is_empty(), "the docs use flags the commands do not have:\n{}", wrong.join("\n"));
}
