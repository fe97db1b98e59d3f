//! Every controller or plant snippet of the README and the book (a ```python or ```c block) is an excerpt of an
//! example the suite flies: the block names its file (`examples/...` in the block or in the paragraph before it),
//! and each of its code lines is a line of that file, in the file's order (comments aside; a line `...` stands for
//! lines left out, and `...` inside a line for a part of it). The examples themselves are flown by the tests that
//! name them (tests/clients.rs, tests/plants.rs and others), which this test checks too. The Python guide's blocks
//! are whole programs, run by the package's own tests (python/tests/test_guide.py), and are left to them.

use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The pages the snippets are in.
fn pages() -> Vec<PathBuf> {
    let mut out = vec![Path::new(ROOT).join("README.md")];
    let mut stack = vec![Path::new(ROOT).join("docs/src")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "md") && !path.ends_with("guides/python.md") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// A line without its comment (`#` in Python, `/* */` and `//` in C), trimmed.
fn code(line: &str, python: bool) -> String {
    let cut = if python {
        // The first `#` outside a string.
        let mut quote = None;
        line.char_indices()
            .find(|&(_, c)| match (quote, c) {
                (None, '"' | '\'') => {
                    quote = Some(c);
                    false
                }
                (Some(q), c) if c == q => {
                    quote = None;
                    false
                }
                (None, '#') => true,
                _ => false,
            })
            .map_or(line.len(), |(k, _)| k)
    } else {
        [line.find("/*"), line.find("//")].into_iter().flatten().min().unwrap_or(line.len())
    };
    line[..cut].trim().to_string()
}

/// Whether snippet line `want` stands for file line `have`: equal, or equal around its `...`.
fn matches(want: &str, have: &str) -> bool {
    match want.split_once("...") {
        None => want == have,
        Some((head, tail)) => have.len() >= head.len() + tail.len() && have.starts_with(head) && have.ends_with(tail),
    }
}

/// (page, line, language, the example it names, its lines) of every python or c block.
fn snippets() -> Vec<(PathBuf, usize, bool, Option<String>, Vec<String>)> {
    let mut out = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let mut k = 0;
        while k < lines.len() {
            let python = lines[k] == "```python";
            if !(python || lines[k] == "```c") {
                k += 1;
                continue;
            }
            let end = k + 1 + lines[k + 1..].iter().position(|l| *l == "```").expect("a closed block");
            let block = &lines[k + 1..end];
            // The example: named in the block, else the last one the text before it names (within 12 lines).
            let ext = if python { ".py" } else { ".c" };
            let named = |l: &&str| -> Option<String> {
                l.split(|c: char| c == '`' || c.is_whitespace() || c == '(' || c == ')' || c == ',')
                    .filter(|w| w.starts_with("examples/") && w.ends_with(ext))
                    .last()
                    .map(str::to_string)
            };
            let source =
                block.iter().find_map(named).or_else(|| lines[k.saturating_sub(12)..k].iter().rev().find_map(named));
            out.push((page.clone(), k + 1, python, source, block.iter().map(|l| l.to_string()).collect()));
            k = end + 1;
        }
    }
    out
}

#[test]
fn every_controller_and_plant_snippet_is_an_excerpt_of_an_example_the_suite_flies() {
    let all = snippets();
    assert!(all.len() >= 4, "the README and the book have python and c snippets: found {}", all.len());
    let tests: String = std::fs::read_dir(Path::new(ROOT).join("tests"))
        .unwrap()
        .filter_map(|e| std::fs::read_to_string(e.unwrap().path()).ok())
        .collect();
    let mut problems = Vec::new();
    for (page, line, python, source, block) in all {
        let at = format!("{}:{line}", page.strip_prefix(ROOT).unwrap().display());
        let Some(source) = source else {
            problems.push(format!("{at}: the block names no example file (examples/...) in it or just before it"));
            continue;
        };
        let Ok(file) = std::fs::read_to_string(Path::new(ROOT).join(&source)) else {
            problems.push(format!("{at}: {source} does not exist"));
            continue;
        };
        let name = Path::new(&source).file_name().unwrap().to_string_lossy().into_owned();
        if !tests.contains(name.as_str()) {
            problems.push(format!("{at}: no test under tests/ names {name}, so nothing flies it"));
        }
        let have: Vec<String> = file.lines().map(|l| code(l, python)).filter(|l| !l.is_empty()).collect();
        let mut from = 0;
        for want in block.iter().map(|l| code(l, python)).filter(|l| !l.is_empty() && l != "...") {
            match have[from..].iter().position(|h| matches(&want, h)) {
                Some(k) => from += k + 1,
                None => {
                    problems.push(format!("{at}: `{want}` is not a line of {source} (after the lines before it)"));
                    break;
                }
            }
        }
    }
    assert!(problems.is_empty(), "snippets that are not what the examples fly:\n{}", problems.join("\n"));
}

#[test]
fn the_matcher_sees_comments_and_elisions() {
    assert_eq!(code("x = 1  # one", true), "x = 1");
    assert_eq!(code("s = \"a#b\"  # c", true), "s = \"a#b\"");
    assert_eq!(code("f(\"x\")  # the scenario's", true), "f(\"x\")");
    assert_eq!(code("f(x); /* call */", false), "f(x);");
    assert!(matches("return {...}, errors", "return {\"a\": a}, errors"));
    assert!(!matches("return {...}, errors", "return errors"));
    assert!(matches("x = 1", "x = 1") && !matches("x = 1", "x = 2"));
}
