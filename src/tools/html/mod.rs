//! `report.html`: one self-contained page per `silrig run` ([`run`]), `silrig check` ([`check`]) and `silrig sweep`
//! ([`sweep`]), written into the output folder beside the files it reads. Everything the page shows is inside it:
//! the figures as inline SVG (the files `silrig-plot` drew), the style sheet, and one small script of our own
//! (zooming a figure, filtering the events, and marking in the page how many figures rendered and whether a
//! script error happened, which the browser test reads). No network is needed to open it; links to the folder's
//! other files work as long as the folder stays together.
//!
//! This file holds what the three pages share: the page with its sections (each with the command that reproduces
//! it), escaping, tables, inline figures, the events and the file list.

pub mod check;
mod control;
pub mod run;
pub mod sweep;
pub mod view3d;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The page's file name in its folder.
pub const FILE: &str = "report.html";

/// Events shown in a page at most; the rest are in `events.jsonl`.
pub const EVENTS_SHOWN: usize = 2000;

/// A page under construction: a title, a status line and its sections in order.
pub struct Page {
    title: String,
    /// `pass`, `fail` or `warn`: the colour of the status badge.
    status_class: &'static str,
    status: String,
    sections: Vec<Section>,
}

/// One section of a page, with an anchor in the page's table of contents.
struct Section {
    id: String,
    heading: String,
    /// The commands that make what the section shows again (label, command).
    commands: Vec<(String, String)>,
    body: String,
}

/// How a result reads at a glance: the badge's colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tone {
    /// Passed, ended cleanly.
    Good,
    /// Failed.
    Bad,
    /// Neither: inconclusive, stopped by the user.
    Unsure,
}

impl Tone {
    fn class(self) -> &'static str {
        match self {
            Tone::Good => "pass",
            Tone::Bad => "fail",
            Tone::Unsure => "warn",
        }
    }
}

impl Page {
    /// A page titled `title` whose badge says `status`.
    pub fn new(title: impl Into<String>, tone: Tone, status: impl Into<String>) -> Self {
        Self { title: title.into(), status_class: tone.class(), status: status.into(), sections: Vec::new() }
    }

    /// Add a section: `body` is HTML; `command` the command that makes what it shows again.
    pub fn section(&mut self, id: &str, heading: &str, command: &str, body: String) {
        self.section_with(id, heading, vec![("reproduce".into(), command.into())], body);
    }

    /// Add a section with several labelled commands (or none).
    pub fn section_with(&mut self, id: &str, heading: &str, commands: Vec<(String, String)>, body: String) {
        self.sections.push(Section { id: id.into(), heading: heading.into(), commands, body });
    }

    /// The whole document.
    pub fn render(&self) -> String {
        let mut out = String::with_capacity(self.sections.iter().map(|s| s.body.len()).sum::<usize>() + 8192);
        let _ = write!(
            out,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
             <meta name=\"generator\" content=\"silrig {}\">\n<title>{}</title>\n<style>{STYLE}</style>\n\
             <script>{SCRIPT}</script>\n</head>\n<body>\n<header>\n<h1>{}</h1>\n<p class=\"badge {}\">{}</p>\n<nav>",
            env!("CARGO_PKG_VERSION"),
            esc(&self.title),
            esc(&self.title),
            self.status_class,
            esc(&self.status)
        );
        for s in &self.sections {
            let _ = write!(out, "<a href=\"#{}\">{}</a>", esc(&s.id), esc(&s.heading));
        }
        out += "</nav>\n</header>\n<main>\n";
        for s in &self.sections {
            let _ = write!(out, "<section id=\"{}\">\n<h2>{}</h2>\n", esc(&s.id), esc(&s.heading));
            for (label, command) in &s.commands {
                out += &command_line(label, command);
            }
            out += &s.body;
            out += "\n</section>\n";
        }
        out += "</main>\n<footer>written by silrig; every figure and style is inside this file, no network is needed \
                to read it</footer>\n</body>\n</html>\n";
        out
    }

    /// Write the page as `<out>/report.html` (whole or not at all); returns its path.
    pub fn write(&self, out: &Path) -> anyhow::Result<PathBuf> {
        let path = out.join(FILE);
        silrig_flight::files::write_atomically(&path, &self.render())?;
        Ok(path)
    }
}

/// `text` safe inside HTML text and attribute values.
pub fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out += "&amp;",
            '<' => out += "&lt;",
            '>' => out += "&gt;",
            '"' => out += "&quot;",
            '\'' => out += "&#39;",
            c => out.push(c),
        }
    }
    out
}

/// A command as one line the reader selects with a click.
pub fn command_line(label: &str, command: &str) -> String {
    format!("<p class=\"cmd\"><span>{}</span> <code>{}</code></p>\n", esc(label), esc(command))
}

/// A table: `header` cells and `rows` of cells, all HTML already (escape text with [`esc`]); a number (or a dash
/// alone, for none) is right-aligned.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let rows: Vec<(&str, &[String])> = rows.iter().map(|r| ("", r.as_slice())).collect();
    table_with(None, header, &rows)
}

/// [`table`] with an id (for a filter) and a class per row (`""` for none).
pub fn table_with(id: Option<&str>, header: &[&str], rows: &[(&str, &[String])]) -> String {
    let id = id.map_or(String::new(), |id| format!(" id=\"{}\"", esc(id)));
    let mut out = format!("<div class=\"scroll\"><table{id}>\n<thead><tr>");
    for h in header {
        let _ = write!(out, "<th>{}</th>", esc(h));
    }
    out += "</tr></thead>\n<tbody>\n";
    for (class, row) in rows {
        out += &if class.is_empty() { "<tr>".to_string() } else { format!("<tr class=\"{class}\">") };
        for cell in row.iter() {
            let numeric = cell == "-" || cell.parse::<f64>().is_ok();
            out += if numeric { "<td class=\"num\">" } else { "<td>" };
            out += cell;
            out += "</td>";
        }
        out += "</tr>\n";
    }
    out += "</tbody></table></div>\n";
    out
}

/// A key-value table (keys and values are text).
pub fn facts(rows: &[(&str, String)]) -> String {
    let mut out = String::from("<table class=\"facts\">\n");
    for (k, v) in rows {
        let _ = writeln!(out, "<tr><th>{}</th><td>{}</td></tr>", esc(k), esc(v));
    }
    out + "</table>\n"
}

/// A pass/fail/inconclusive cell.
pub fn outcome_cell(outcome: silrig_flight::criteria::Outcome) -> String {
    use silrig_flight::criteria::Outcome;
    let class = match outcome {
        Outcome::Pass => "pass",
        Outcome::Fail => "fail",
        Outcome::Inconclusive => "warn",
    };
    format!("<span class=\"tag {class}\">{}</span>", outcome.label())
}

/// The figure `<dir>/<stem>.svg` inline, with a caption linking its PNG and SVG files (relative to the page in
/// `page_dir`); `None` when there is no such figure.
pub fn figure(page_dir: &Path, dir: &Path, stem: &str) -> Option<String> {
    figure_with(page_dir, dir, stem, "")
}

/// [`figure`] with a one-line caption, before the file links, saying what to look for in it (`""` for none).
pub fn figure_with(page_dir: &Path, dir: &Path, stem: &str, look_for: &str) -> Option<String> {
    let svg = dir.join(format!("{stem}.svg"));
    let text = std::fs::read_to_string(&svg).ok()?;
    // The document's own `<svg>` element, without the XML prolog a file may carry.
    let start = text.find("<svg")?;
    let body = &text[start..];
    let link = |ext: &str| {
        let file = dir.join(format!("{stem}.{ext}"));
        file.exists().then(|| {
            let rel = file.strip_prefix(page_dir).unwrap_or(&file);
            format!(" <a href=\"{}\">{ext}</a>", esc(&rel.display().to_string()))
        })
    };
    let rel = dir.strip_prefix(page_dir).ok().filter(|r| !r.as_os_str().is_empty());
    let name = rel.map_or(stem.to_string(), |r| format!("{}/{stem}", r.display()));
    let look_for =
        if look_for.is_empty() { String::new() } else { format!("<span class=\"look\">{}</span> ", esc(look_for)) };
    Some(format!(
        "<figure data-figure=\"{}\">\n{}\n<figcaption>{look_for}{}{}{} <span class=\"hint\">(click to zoom)</span>\
         </figcaption>\n</figure>\n",
        esc(&name),
        body.trim_end(),
        esc(&name),
        link("png").unwrap_or_default(),
        link("svg").unwrap_or_default()
    ))
}

/// The stems of every `*.svg` in `dir`, sorted.
pub fn figure_stems(dir: &Path) -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.strip_suffix(".svg").map(str::to_string)
        })
        .collect();
    stems.sort();
    stems
}

/// The run's events (`events.jsonl`) as a table a reader can filter: wall time from the first event, tick, process,
/// kind and detail; at most [`EVENTS_SHOWN`] rows.
pub fn events(dir: &Path) -> String {
    let events = silrig_rig::events::read_events(dir);
    let Some(first) = events.first().map(|e| e.t_ns) else {
        return "<p>No events were logged (events.jsonl is absent or empty).</p>\n".into();
    };
    let rows: Vec<Vec<String>> = events
        .iter()
        .take(EVENTS_SHOWN)
        .map(|e| {
            vec![
                format!("{:.3}", (e.t_ns - first) as f64 / 1e9),
                e.tick.map_or("-".into(), |t| t.to_string()),
                esc(&e.process),
                format!("<span class=\"kind\">{}</span>", esc(&e.kind)),
                esc(&e.detail),
            ]
        })
        .collect();
    let out = format!(
        "<p>{} event{} from events.jsonl, times in wall-clock seconds from the first.{}</p>\n\
         <p><input type=\"search\" class=\"filter\" data-table=\"events-table\" placeholder=\"filter events \
         (process, kind, detail)\"></p>\n",
        events.len(),
        if events.len() == 1 { "" } else { "s" },
        if events.len() > EVENTS_SHOWN {
            format!(" The first {EVENTS_SHOWN} are shown; the file holds every one.")
        } else {
            String::new()
        }
    );
    let rows: Vec<(&str, &[String])> = rows.iter().map(|r| ("", r.as_slice())).collect();
    out + &table_with(Some("events-table"), &["t (s)", "tick", "process", "kind", "detail"], &rows)
}

/// What a file of an output folder holds, for the file list.
fn file_role(name: &str) -> &'static str {
    match name {
        "report.json" => "the run's report as data (timing, control quality, faults)",
        "check.json" => "the verdict as data",
        "check.junit.xml" => "the verdict for CI test reporters (JUnit XML)",
        "sweep.json" => "the sweep's summary as data",
        "cases.csv" => "one row per case: sampled values, figures, criteria",
        "trace.csv" => "the logged flight, one row per tick",
        "timing.csv" => "per-tick timing of the plant, controller and logger",
        "events.jsonl" => "every event of the run, one JSON object per line",
        "scenario.toml" | "case-scenario.toml" => "the scenario as flown",
        "controller.env" | "plant.env" => "the run's SILRIG_* variables",
        "timer-baseline.json" => "the OS timer floor measured beside the run",
        "foxglove-layout.json" => "a Foxglove or Lichtblick layout for this plant's recording: import it there",
        n if n.ends_with(".mcap") => "the recording (MCAP)",
        n if n.ends_with(".report.json") => "a process's own report",
        n if n.ends_with(".checkpoint.json") => "a process's checkpoint (a restart resumes from it)",
        n if n.ends_with(".hgrm") => "a latency histogram (HdrHistogram percentile text)",
        n if n.ends_with(".log") => "a process's output",
        n if n.ends_with(".png") || n.ends_with(".svg") => "a figure",
        _ => "",
    }
}

/// Every file and folder of `dir` with its size and what it holds, linked relative to the page in `page_dir`.
pub fn files(page_dir: &Path, dir: &Path) -> String {
    let mut entries: Vec<(String, Option<u64>)> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| {
            let meta = e.metadata().ok();
            let name = e.file_name().to_string_lossy().into_owned();
            (name, meta.filter(|m| m.is_file()).map(|m| m.len()))
        })
        .filter(|(name, _)| name != FILE)
        .collect();
    entries.sort();
    let rows: Vec<Vec<String>> = entries
        .iter()
        .map(|(name, size)| {
            let path = dir.join(name);
            let rel = path.strip_prefix(page_dir).unwrap_or(&path).display().to_string();
            let shown = if size.is_none() { format!("{name}/") } else { name.clone() };
            vec![
                format!("<a href=\"{}\">{}</a>", esc(&rel), esc(&shown)),
                size.map_or("folder".into(), human_size),
                esc(file_role(name)),
            ]
        })
        .collect();
    table(&["file", "size", "what it holds"], &rows)
}

/// A byte count as a person reads it.
fn human_size(bytes: u64) -> String {
    match bytes {
        b if b < 1024 => format!("{b} B"),
        b if b < 1024 * 1024 => format!("{:.1} KiB", b as f64 / 1024.0),
        b => format!("{:.1} MiB", b as f64 / 1024.0 / 1024.0),
    }
}

/// The page's style: plain, readable, printable; figures fit the width and zoom on a click.
const STYLE: &str = "
:root{--fg:#1d2327;--muted:#5f6b76;--line:#d8dee4;--bg:#fff;--band:#f5f7f9;--pass:#1a7f37;--fail:#c62828;--warn:#a15c00}
*{box-sizing:border-box}
body{margin:0;font:15px/1.45 system-ui,-apple-system,'Segoe UI',Roboto,'DejaVu Sans',sans-serif;color:var(--fg);background:var(--bg)}
header{padding:18px 28px 10px;border-bottom:1px solid var(--line);background:var(--band);position:sticky;top:0;z-index:2}
h1{font-size:21px;margin:0 0 6px}
h2{font-size:18px;margin:0 0 8px;padding-top:6px}
h3{font-size:15px;margin:16px 0 6px}
nav a{margin-right:16px;color:#0b5cad;text-decoration:none;font-size:14px}
nav a:hover{text-decoration:underline}
main{padding:6px 28px 28px;max-width:1500px}
section{padding:14px 0 10px;border-bottom:1px solid var(--line);scroll-margin-top:110px}
footer{padding:14px 28px;color:var(--muted);font-size:13px}
.badge{display:inline-block;margin:0 0 8px;padding:2px 10px;border-radius:12px;font-weight:600;color:#fff}
.badge.pass,.tag.pass{background:var(--pass)}.badge.fail,.tag.fail{background:var(--fail)}.badge.warn,.tag.warn{background:var(--warn)}
.tag{display:inline-block;padding:0 7px;border-radius:9px;color:#fff;font-size:13px;font-weight:600}
p.cmd{margin:4px 0 10px;font-size:13px;color:var(--muted)}
p.cmd code{user-select:all;background:#eef1f4;color:var(--fg);padding:2px 6px;border-radius:4px;font-size:13px;word-break:break-all}
code,pre{font-family:'DejaVu Sans Mono',Menlo,Consolas,monospace}
pre{background:var(--band);padding:10px;border-radius:4px;overflow-x:auto;font-size:13px}
.scroll{overflow-x:auto;max-height:640px;overflow-y:auto;margin:6px 0 10px}
table{border-collapse:collapse;font-size:13px}
th,td{border:1px solid var(--line);padding:3px 8px;text-align:left;vertical-align:top}
thead th{background:var(--band);position:sticky;top:0}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
table.facts th{background:var(--band);font-weight:600;white-space:nowrap}
tr.fail td{background:#fdecea}tr.warn td{background:#fff4e0}
ul.problems li{color:var(--fail)}ul.notes li{color:var(--muted)}
.kind{font-family:'DejaVu Sans Mono',monospace;font-size:12px}
figure{margin:12px 0 18px;max-width:1100px}
figure svg{width:100%;height:auto;display:block;border:1px solid var(--line);cursor:zoom-in;background:#fff}
figure.zoomed{max-width:none}
figure.zoomed svg{cursor:zoom-out}
figcaption{font-size:13px;color:var(--muted);margin-top:4px}
figcaption .look{color:var(--fg);font-size:14px}
ul.verdict{list-style:none;padding:0;margin:4px 0 8px}ul.verdict li{margin:3px 0}
ul.verdict .tag{min-width:74px;text-align:center;margin-right:8px}
details{margin:6px 0}details>summary{cursor:pointer;font-weight:600;font-size:14px;padding:3px 0}
.hint{font-size:12px}
input.filter{width:360px;max-width:100%;padding:4px 8px;font-size:13px}
#view3d canvas{width:100%;max-width:960px;height:auto;display:block;border:1px solid var(--line);cursor:grab}
.view3d-controls{margin:6px 0;font-size:13px}.view3d-controls input[type=range]{width:420px;max-width:60%;vertical-align:middle}
.view3d-status{color:var(--muted);font-variant-numeric:tabular-nums}
@media print{header{position:static}.scroll{max-height:none}.hint,input.filter{display:none}}
";

/// The page's only script: click a figure to zoom it to the window's width, type to filter a table, and, once the
/// page has loaded, mark on `<body>` how many figures there are (`data-figures`), how many rendered with a size
/// (`data-figures-rendered`), how many script errors happened (`data-errors`) and where the first figure ends,
/// px from the page's top (`data-first-figure-bottom`, whether it is on the first screen): what the browser test
/// reads.
const SCRIPT: &str = "
(function(){
var errors=0;
window.addEventListener('error',function(){errors++;});
document.addEventListener('click',function(e){
var f=e.target.closest&&e.target.closest('figure');
if(f&&!e.target.closest('a'))f.classList.toggle('zoomed');
});
document.addEventListener('input',function(e){
var t=e.target;if(!t.classList||!t.classList.contains('filter'))return;
var q=t.value.toLowerCase(),table=document.getElementById(t.getAttribute('data-table'));
if(!table)return;
table.querySelectorAll('tbody tr').forEach(function(r){r.style.display=r.textContent.toLowerCase().indexOf(q)<0?'none':'';});
});
window.addEventListener('load',function(){
var figs=document.querySelectorAll('figure svg'),shown=0;
figs.forEach(function(s){var r=s.getBoundingClientRect();if(r.width>0&&r.height>0&&s.childElementCount>0)shown++;});
document.body.setAttribute('data-figures',String(figs.length));
document.body.setAttribute('data-figures-rendered',String(shown));
document.body.setAttribute('data-errors',String(errors));
var first=figs.length?figs[0].getBoundingClientRect():null;
document.body.setAttribute('data-first-figure-bottom',String(first?Math.ceil(first.bottom+window.scrollY):0));
});
})();
";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_numbers_align_right() {
        assert_eq!(esc("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;");
        let t = table(&["name", "value"], &[vec!["x".into(), "-1.5".into()], vec!["-".into(), "3 s".into()]]);
        assert!(t.contains("<td>x</td><td class=\"num\">-1.5</td>"), "{t}");
        assert!(t.contains("<td class=\"num\">-</td><td>3 s</td>"), "{t}");
    }

    #[test]
    fn a_page_lists_its_sections_with_their_commands() {
        let mut page = Page::new("t <1>", Tone::Bad, "FAILED");
        page.section("a", "First", "silrig run --duration-s 3", "<p>one</p>".into());
        page.section_with("b", "Second", Vec::new(), "<p>two</p>".into());
        let html = page.render();
        assert!(html.contains("<title>t &lt;1&gt;</title>"));
        assert!(html.contains("<p class=\"badge fail\">FAILED</p>"));
        assert!(html.contains("<a href=\"#a\">First</a><a href=\"#b\">Second</a>"));
        assert!(html.contains("<code>silrig run --duration-s 3</code>"));
        assert!(html.find("<p>one</p>").unwrap() < html.find("<p>two</p>").unwrap());
        // Self-contained: nothing is fetched.
        assert!(!html.contains("src=") && !html.contains("<link") && !html.contains("@import"));
    }

    #[test]
    fn a_figure_is_inlined_without_its_prolog_and_links_its_files() {
        let dir = std::env::temp_dir().join(format!("silrig-html-figure-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("case")).unwrap();
        std::fs::write(
            dir.join("case/attitude.svg"),
            "<?xml version=\"1.0\"?>\n<svg width=\"10\" height=\"5\" viewBox=\"0 0 10 5\"><rect/></svg>\n",
        )
        .unwrap();
        std::fs::write(dir.join("case/attitude.png"), b"png").unwrap();
        let f = figure(&dir, &dir.join("case"), "attitude").unwrap();
        assert!(f.contains("<figure data-figure=\"case/attitude\">\n<svg width"), "{f}");
        assert!(!f.contains("<?xml"));
        assert!(f.contains("<a href=\"case/attitude.png\">png</a> <a href=\"case/attitude.svg\">svg</a>"), "{f}");
        assert!(figure(&dir, &dir, "missing").is_none());
        assert_eq!(figure_stems(&dir.join("case")), ["attitude"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
