//! Rooms of a readable size, checked (the layer test's sibling, named by `tests/layers.rs`): no file of `src/` or
//! `bins/` over 700 lines and no function over 80, tests aside (`#[cfg(test)]` items and files named `tests.rs` or
//! `*_tests.rs`). A function is a `fn` item with a body, counted from the line of its `fn` keyword (doc comments
//! and attributes above it excluded) to the line of its closing brace. A failure names every file and function
//! over its limit with its length, so a split can be planned from the message alone.

use std::path::{Path, PathBuf};

const MAX_FILE_LINES: usize = 700;
const MAX_FN_LINES: usize = 80;

/// The code with comments, string and character literals blanked to spaces (newlines kept, so line numbers hold):
/// a brace or a `fn` inside a string or a comment is no code.
fn blank_literals(text: &str) -> Vec<u8> {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to.min(b.len())] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut i = 0;
    while i < b.len() {
        let rest = &b[i..];
        if rest.starts_with(b"//") {
            let end = rest.iter().position(|&c| c == b'\n').map_or(b.len(), |e| i + e);
            blank(&mut out, i, end);
            i = end;
        } else if rest.starts_with(b"/*") {
            // Block comments nest in Rust.
            let (mut depth, mut j) = (1, i + 2);
            while j < b.len() && depth > 0 {
                if b[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if b[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                } else {
                    j += 1;
                }
            }
            blank(&mut out, i, j);
            i = j;
        } else if let Some(end) = raw_string_end(b, i).filter(|_| i == 0 || !ident(b[i - 1])) {
            blank(&mut out, i, end);
            i = end;
        } else if b[i] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            blank(&mut out, i, j + 1);
            i = j + 1;
        } else if b[i] == b'\'' {
            // A character literal ('x', '\n', '\u{..}', '{'), not a lifetime ('a).
            let close = if rest.get(1) == Some(&b'\\') {
                rest[2..].iter().position(|&c| c == b'\'').map(|p| p + 2)
            } else {
                let len = std::str::from_utf8(&rest[1..]).ok().and_then(|s| s.chars().next()).map_or(1, char::len_utf8);
                (rest.get(1 + len) == Some(&b'\'')).then_some(1 + len)
            };
            match close {
                Some(c) => {
                    blank(&mut out, i, i + c + 1);
                    i += c + 1;
                }
                None => i += 1,
            }
        } else {
            i += 1;
        }
    }
    out
}

/// Where a raw string starting at `i` (`r"..."`, `r#"..."#`, `br"..."`) ends, if one starts there.
fn raw_string_end(b: &[u8], i: usize) -> Option<usize> {
    let mut j = i + if b[i..].starts_with(b"br") { 2 } else { usize::from(b[i] == b'r') };
    if j == i {
        return None;
    }
    let hashes = b[j..].iter().take_while(|&&c| c == b'#').count();
    j += hashes;
    if b.get(j) != Some(&b'"') {
        return None;
    }
    let mut closing = vec![b'"'];
    closing.extend(std::iter::repeat_n(b'#', hashes));
    let body = j + 1;
    let end = b[body..].windows(closing.len()).position(|w| w == closing.as_slice())?;
    Some(body + end + closing.len())
}

/// The index just past the brace matching the `{` at `open`.
fn matching_brace(code: &[u8], open: usize) -> usize {
    let mut depth = 0usize;
    for (k, &c) in code.iter().enumerate().skip(open) {
        match c {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    code.len()
}

/// The end of the item starting at `from`: past its first `;` or its first brace block, whichever comes first.
fn item_end(code: &[u8], from: usize) -> usize {
    match code[from..].iter().position(|&c| c == b';' || c == b'{') {
        Some(p) if code[from + p] == b';' => from + p + 1,
        Some(p) => matching_brace(code, from + p),
        None => code.len(),
    }
}

/// The byte ranges of every `#[cfg(test)]` item (a test module, a helper only tests use) in blanked code.
fn test_items(code: &[u8]) -> Vec<(usize, usize)> {
    const MARK: &[u8] = b"#[cfg(test)]";
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(p) = code[at..].windows(MARK.len()).position(|w| w == MARK) {
        let start = at + p;
        let end = item_end(code, start + MARK.len());
        out.push((start, end));
        at = end;
    }
    out
}

/// A `fn` item with a body: its name, the line of its `fn` keyword and its length in lines.
struct Function {
    name: String,
    first_line: usize,
    lines: usize,
}

/// Every `fn` item with a body in the code (nested ones too), with its length in lines.
fn functions(code: &[u8]) -> Vec<Function> {
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(p) = code[i..].windows(3).position(|w| w[..2] == *b"fn" && w[2].is_ascii_whitespace()) {
        let at = i + p;
        i = at + 2;
        if at > 0 && ident(code[at - 1]) {
            continue;
        }
        let name_start = at + 2 + code[at + 2..].iter().take_while(|c| c.is_ascii_whitespace()).count();
        let name_len = code[name_start..].iter().take_while(|&&c| ident(c)).count();
        if name_len == 0 {
            continue; // a function pointer type such as `fn (u8)`
        }
        // The body opens at the first `{` outside the signature's parentheses; a `;` there means no body.
        let mut depth = 0i32;
        let mut body = None;
        for (k, &c) in code.iter().enumerate().skip(name_start + name_len) {
            match c {
                b'(' | b'[' => depth += 1,
                b')' | b']' => depth -= 1,
                b';' if depth == 0 => break,
                b'{' if depth == 0 => {
                    body = Some(k);
                    break;
                }
                _ => {}
            }
        }
        let Some(open) = body else { continue };
        let close = matching_brace(code, open);
        let first_line = line_of(code, at);
        out.push(Function {
            name: String::from_utf8_lossy(&code[name_start..name_start + name_len]).into_owned(),
            first_line,
            lines: line_of(code, close - 1) - first_line + 1,
        });
    }
    out
}

/// The number of the line holding byte `at` (from 1).
fn line_of(code: &[u8], at: usize) -> usize {
    code[..at].iter().filter(|&&c| c == b'\n').count() + 1
}

/// A file's code as the limits see it, literals, comments and test items blanked, and its length in lines
/// without its test items.
fn measured(text: &str) -> (Vec<u8>, usize) {
    let mut code = blank_literals(text);
    let mut lines = text.lines().count();
    for (start, end) in test_items(&code) {
        lines -= line_of(&code, end) - line_of(&code, start) + 1;
        for c in &mut code[start..end] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    }
    (code, lines)
}

/// Every `.rs` file under `dir`, test files aside.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap().to_str().unwrap();
        if path.is_dir() {
            rust_files(&path, out);
        } else if name.ends_with(".rs") && name != "tests.rs" && !name.ends_with("_tests.rs") {
            out.push(path);
        }
    }
}

/// What is over the limits in one file, as lines of the failure message.
fn oversized(shown: &str, text: &str) -> Vec<String> {
    let (code, lines) = measured(text);
    let mut out = Vec::new();
    if lines > MAX_FILE_LINES {
        out.push(format!("{shown}: {lines} lines (at most {MAX_FILE_LINES})"));
    }
    for f in functions(&code).into_iter().filter(|f| f.lines > MAX_FN_LINES) {
        out.push(format!("{shown}:{} fn {}: {} lines (at most {MAX_FN_LINES})", f.first_line, f.name, f.lines));
    }
    out
}

#[test]
fn no_file_over_700_lines_and_no_function_over_80() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["src", "bins"] {
        rust_files(&root.join(dir), &mut files);
    }
    assert!(files.len() > 100, "only {} files found under src/ and bins/", files.len());
    let over: Vec<String> = files
        .iter()
        .flat_map(|path| {
            let shown = path.strip_prefix(root).unwrap().display().to_string();
            oversized(&shown, &std::fs::read_to_string(path).unwrap())
        })
        .collect();
    assert!(
        over.is_empty(),
        "{} over the limits; split each by concern (a phase, a role, a record type):\n{}",
        over.len(),
        over.join("\n")
    );
}

/// A function of `body_lines` lines of code between its `fn` line and its closing brace.
fn function_of(name: &str, body_lines: usize) -> String {
    let body: String = (0..body_lines).map(|k| format!("    let x{k} = {k};\n")).collect();
    format!("/// Its doc, not counted.\n#[inline]\npub fn {name}(a: u8) -> u8 {{\n{body}    a\n}}\n")
}

#[test]
fn the_scanner_names_a_function_one_line_over_and_passes_one_at_the_limit() {
    // `fn` line + lines + `a` + closing brace: 78 lines of body make 81 lines.
    let text = format!("{}\n{}", function_of("long", 78), function_of("at_limit", 77));
    let over = oversized("src/x.rs", &text);
    assert_eq!(over, ["src/x.rs:3 fn long: 81 lines (at most 80)"]);
}

#[test]
fn the_scanner_names_a_file_over_700_lines_and_leaves_test_modules_out() {
    let code: String = (0..700).map(|k| format!("const C{k}: u8 = 0;\n")).collect();
    assert!(oversized("src/x.rs", &code).is_empty());
    let tests = format!("#[cfg(test)]\nmod tests {{\n{}}}\n", function_of("long_test", 200));
    assert!(oversized("src/x.rs", &format!("{code}{tests}")).is_empty(), "a test module is not counted");
    assert_eq!(oversized("src/x.rs", &format!("{code}const D: u8 = 0;\n")), ["src/x.rs: 701 lines (at most 700)"]);
}

#[test]
fn braces_and_fn_in_strings_comments_and_characters_are_not_code() {
    let text = r####"
fn a() -> &'static str {
    let _ = '{';
    let _ = b'}';
    let _ = '\'';
    let _ = "fn b() { } \" {";
    let _ = r#"fn c() { "# ;
    // fn d() {
    /* fn e() { /* nested */ { */
    "}"
}
fn f<'a>(x: &'a [u8; 2]) -> impl Fn(u8) -> u8 + 'a { move |k| x[0] + k }
trait T { fn g(&self); fn h(&self) -> u8 { 1 } }
type P = fn (u8) -> u8;
"####;
    let found: Vec<(String, usize)> = functions(&measured(text).0).into_iter().map(|f| (f.name, f.lines)).collect();
    let expected = [("a", 10), ("f", 1), ("h", 1)].map(|(n, l)| (n.to_string(), l));
    assert_eq!(found, expected);
}
