//! `report.html` in a real browser: a run (with a fault, so the fault timeline is drawn), a check (a case that
//! passes, flown twice, and one that fails, whose figures the check's page shows) and a sweep each write their
//! page; headless Chromium (Debian's `chromium`) loads each, the test fails on any console message (the pages log
//! none) and on a script error, checks that every figure the folder holds is in the page and rendered with a size,
//! and takes a screenshot that must be a PNG. The page's own script marks on `<body>` how many figures there are,
//! how many rendered and how many errors happened; `--dump-dom` gives the test the document after loading. A run's
//! page answers first: verdict, response, faults, timing, then the details folded, and its first screen (1400x900)
//! shows the response figure whole.
//!
//! `SILRIG_HTML_KEEP=dir` keeps the pages' folders and screenshots there for a look.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// One browser at a time: the machine is small, and each Chromium is several processes.
static BROWSER: Mutex<()> = Mutex::new(());

/// The browser, or None (then the test is skipped outside CI, whose `.ci/run` installs it).
fn chromium() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser"].into_iter().find(|name| {
        Command::new("sh").args(["-c", &format!("command -v {name}")]).output().is_ok_and(|o| o.status.success())
    });
    if found.is_none() {
        assert!(std::env::var_os("CI").is_none(), "CI must have Chromium (.ci/run installs chromium)");
        eprintln!("skipped: chromium is not installed (Debian: apt-get install chromium)");
    }
    found
}

/// What the browser made of a page.
struct Loaded {
    /// The document after the load event (`--dump-dom`).
    dom: String,
    /// Console messages Chromium logged.
    console: Vec<String>,
}

impl Loaded {
    /// A number the page's script set on `<body>`; the test fails when it is missing (the script did not run).
    fn body_number(&self, attribute: &str) -> usize {
        let body = &self.dom[self.dom.find("<body").expect("a body")..];
        let body = &body[..body.find('>').unwrap()];
        let at = body.find(&format!("{attribute}=\"")).unwrap_or_else(|| panic!("no {attribute} on {body}"));
        let value = &body[at + attribute.len() + 2..];
        value[..value.find('"').unwrap()].parse().unwrap()
    }
}

/// What a browser run left: its exit and what it wrote.
struct Browsed {
    success: bool,
    stdout: String,
    stderr: String,
}

/// Run Chromium headless on `page` with `args` and a throwaway profile in `scratch`, its output into files (a
/// dumped document far larger than a pipe's buffer must not stall it); 180 s at most, then its whole process
/// group (Chromium and the helpers it started) is killed and the test fails.
fn browse(browser: &str, page: &Path, scratch: &Path, args: &[&str]) -> Browsed {
    use std::os::unix::process::CommandExt;
    let _one = BROWSER.lock().unwrap_or_else(|e| e.into_inner());
    let profile = scratch.join("chromium-profile");
    let (stdout, stderr) = (scratch.join("chromium.stdout"), scratch.join("chromium.stderr"));
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--enable-unsafe-swiftshader",
            "--no-first-run",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(args)
        .arg(format!("file://{}", page.display()))
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&stdout).unwrap())
        .stderr(std::fs::File::create(&stderr).unwrap())
        .process_group(0)
        .spawn()
        .expect("chromium starts");
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > Duration::from_secs(180) {
            // SAFETY: kill(2) on the process group this test created for the browser.
            unsafe { libc::kill(-(child.id() as i32), libc::SIGKILL) };
            let _ = child.wait();
            panic!("chromium on {} did not end within 180 s", page.display());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let read = |path: &Path| String::from_utf8_lossy(&std::fs::read(path).unwrap_or_default()).into_owned();
    let browsed = Browsed { success: status.success(), stdout: read(&stdout), stderr: read(&stderr) };
    for leftover in [&stdout, &stderr] {
        let _ = std::fs::remove_file(leftover);
    }
    let _ = std::fs::remove_dir_all(&profile);
    browsed
}

/// Load `page`, read its document and console, and screenshot it into `<scratch>/<name>.png`.
fn load(browser: &str, page: &Path, scratch: &Path, name: &str) -> Loaded {
    let o = browse(browser, page, scratch, &["--enable-logging=stderr", "--v=0", "--dump-dom"]);
    assert!(o.success, "chromium --dump-dom {}: {}", page.display(), o.stderr);
    let loaded = Loaded {
        console: o.stderr.lines().filter(|l| l.contains(":CONSOLE")).map(str::to_string).collect(),
        dom: o.stdout,
    };
    let shot = scratch.join(format!("{name}.png"));
    let o = browse(browser, page, scratch, &[&format!("--screenshot={}", shot.display()), "--window-size=1400,3000"]);
    assert!(o.success, "chromium --screenshot {}: {}", page.display(), o.stderr);
    let png = std::fs::read(&shot).unwrap_or_else(|e| panic!("no screenshot {}: {e}", shot.display()));
    assert!(png.len() > 1000 && png.starts_with(b"\x89PNG\r\n\x1a\n"), "{} is not a PNG screenshot", shot.display());
    loaded
}

/// Where the page's first figure ends in a 1400x900 window (the first screen of a laptop, what a reader sees before
/// scrolling), px from the top, as the page's script measured it.
fn load_first_figure_bottom(browser: &str, page: &Path, scratch: &Path) -> usize {
    let o = browse(browser, page, scratch, &["--dump-dom", "--window-size=1400,900"]);
    assert!(o.success, "chromium --dump-dom {}: {}", page.display(), o.stderr);
    Loaded { dom: o.stdout, console: Vec::new() }.body_number("data-first-figure-bottom")
}

/// `text` as the pages write it.
fn esc(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace('\'', "&#39;")
}

/// The page of a folder: self-contained, opened without a console message or a script error, holding each of
/// `figures` (by the names the page gives them) and every one of its figures rendered.
fn check_page(browser: &str, page: &Path, scratch: &Path, name: &str, figures: &[&str]) -> String {
    let html = std::fs::read_to_string(page).unwrap_or_else(|e| panic!("{}: {e}", page.display()));
    for fetch in ["src=", "<link", "@import", "url("] {
        assert!(!html.contains(fetch), "{} fetches something ({fetch}): it must be whole", page.display());
    }
    for f in figures {
        assert!(html.contains(&format!("<figure data-figure=\"{f}\">")), "{} lacks the figure {f}", page.display());
    }
    let loaded = load(browser, page, scratch, name);
    assert!(loaded.console.is_empty(), "{}: console messages: {:#?}", page.display(), loaded.console);
    assert_eq!(loaded.body_number("data-errors"), 0, "{}: script errors", page.display());
    let in_page = html.matches("<figure ").count();
    assert_eq!(loaded.body_number("data-figures"), in_page, "{}: the browser found other figures", page.display());
    assert_eq!(loaded.body_number("data-figures-rendered"), in_page, "{}: a figure did not render", page.display());
    html
}

/// Where a test's folders go: a fresh temporary one, or `$SILRIG_HTML_KEEP/<test>` to look at afterwards.
fn scratch(test: &str) -> (PathBuf, bool) {
    match std::env::var_os("SILRIG_HTML_KEEP") {
        Some(keep) => {
            let dir = Path::new(&keep).join(test);
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            (dir, true)
        }
        None => (common::temp_dir("html", test), false),
    }
}

/// The stems of the SVG figures in `dir`, as the page of `page_dir` names them.
fn svgs(page_dir: &Path, dir: &Path) -> Vec<String> {
    let rel = dir.strip_prefix(page_dir).unwrap();
    let mut out: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.unwrap().file_name().to_str()?.strip_suffix(".svg").map(str::to_string))
        .map(|stem| if rel.as_os_str().is_empty() { stem } else { format!("{}/{stem}", rel.display()) })
        .collect();
    out.sort();
    out
}

fn silrig(args: &[&str]) -> std::process::Output {
    let child = Command::new(SILRIG)
        .args(args)
        .current_dir(ROOT)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_with_watchdog(child, Duration::from_secs(300))
}

#[test]
fn a_runs_page_answers_first_then_gives_timing_figures_and_the_details_folded() {
    let Some(browser) = chromium() else { return };
    let (dir, keep) = scratch("run");
    let id = format!("html{}-run", std::process::id());
    let out = dir.join("run");
    let o = silrig(&[
        "run",
        "--duration-s",
        "3",
        "--quiet",
        "--fault",
        "controller:kill@1s,restart_after=0.3s",
        "--run-id",
        &id,
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    let page = out.join("report.html");
    assert!(stdout.contains(&format!("page: {}", page.display())), "{stdout}");
    let figures = svgs(&out, &out);
    for expected in ["faults", "fig1_states", "latency", "latency_histogram", "response", "signals"] {
        assert!(figures.iter().any(|f| f == expected), "the run drew no {expected}: {figures:?}");
    }
    let figures: Vec<&str> = figures.iter().map(String::as_str).collect();
    let html = check_page(browser, &page, &dir, "run", &figures);
    // Answer first: the verdict, the response, the faults, timing, the figures; the details folded below.
    let sections = ["verdict", "response", "faults", "timing", "figures", "view3d-section", "run", "events", "files"];
    let at: Vec<usize> = sections
        .iter()
        .map(|s| html.find(&format!("<section id=\"{s}\">")).unwrap_or_else(|| panic!("no {s} section")))
        .collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "the sections are not in the order {sections:?}");
    for folded in ["run", "events", "files"] {
        let body = &html[html.find(&format!("<section id=\"{folded}\">")).unwrap()..];
        let body = &body[..body.find("</section>").unwrap()];
        assert!(body.contains("<details><summary>"), "the {folded} section is not folded");
    }
    let first = &html[at[0]..at[1]];
    assert!(
        first.contains(
            "<span class=\"tag pass\">survived</span>controller kill at 1 s, restart after 0.3 s: injected at"
        ),
        "the verdict does not say the rig survived the fault: {first}"
    );
    let response = &html[at[1]..at[2]];
    assert!(response.find("<figure data-figure=\"response\">").is_some(), "the response figure is not in its section");
    for header in ["<th>output</th>", "<th>set point</th>", "<th>actuator</th>"] {
        assert!(response.contains(header), "the control quality has no table with {header}");
    }
    assert!(!response.contains("<pre>"), "the control quality is a monospace dump");
    assert_eq!(html.matches("<span class=\"look\">").count(), figures.len(), "a figure without what to look for");
    // The first screen (1400x900) shows the verdict and the response figure whole: it is the page's first figure.
    let bottom = load_first_figure_bottom(browser, &page, &dir);
    assert!(bottom > 0 && bottom <= 900, "the response figure ends {bottom} px down, below the first screen");
    // Each section names the command that flies the run again, as a shell reads it.
    let command = format!(
        "<code>silrig run --duration-s 3 --quiet --fault {} --run-id {id} --out {}</code>",
        esc("'controller:kill@1s,restart_after=0.3s'"),
        out.display()
    );
    assert_eq!(html.matches(&command).count(), 8, "{command} in every section but the files");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    for latency in report["processes"].as_array().unwrap().iter().flat_map(|p| p["latencies"].as_array().unwrap()) {
        if latency["summary"]["count"].as_u64().unwrap() > 0 {
            let name = latency["name"].as_str().unwrap();
            assert!(html.contains(&format!("<td>{name}</td>")), "the timing table lacks {name}");
        }
    }
    assert!(html.contains("<td>controller kill at 1 s, restart after 0.3 s</td>"), "the fault table lacks the fault");
    assert!(html.contains("<td>controller #2</td>"), "the controller's second life is listed");
    let kinds: Vec<String> = silrig::rig::events::read_events(&out).into_iter().map(|e| e.kind).collect();
    assert!(kinds.iter().any(|k| k == "fault-injected"), "{kinds:?}");
    for kind in &kinds {
        assert!(html.contains(&format!("<span class=\"kind\">{kind}</span>")), "the events lack {kind}");
    }
    common::no_shared_memory_left(&id);
    if !keep {
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn a_checks_page_gives_every_criterion_and_the_figures_of_a_failed_case() {
    let Some(browser) = chromium() else { return };
    let (dir, keep) = scratch("check");
    let suite = dir.join("suite.toml");
    std::fs::write(
        &suite,
        r#"name = "html"
description = "one case that passes, flown twice, and one that fails"

[[cases]]
name = "steady"
why = "the same flight twice"
mode = "lockstep"
duration_s = 2.0
[cases.criteria]
alpha_max_deg = 15.0
deterministic = true

[[cases]]
name = "too-strict"
why = "an alpha limit no flight of this scenario meets"
mode = "lockstep"
duration_s = 2.0
[cases.criteria]
alpha_max_deg = 1.0
"#,
    )
    .unwrap();
    let out = dir.join("check");
    let o = silrig(&["check", suite.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let verdict: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("check.json")).unwrap()).unwrap();
    let failed_dir = out.join("too-strict");
    let figures = svgs(&out, &failed_dir);
    assert!(figures.iter().any(|f| f == "too-strict/fig1_states"), "{figures:?}");
    let figures: Vec<&str> = figures.iter().map(String::as_str).collect();
    let html = check_page(browser, &out.join("report.html"), &dir, "check", &figures);
    assert!(html.contains("FAIL: 1 of 2 cases passed, 1 of"), "the verdict in the badge");
    for case in verdict["cases"].as_array().unwrap() {
        let reproduce = case["reproduce"].as_str().unwrap();
        assert!(html.contains(&format!("<code>{reproduce}</code>")), "no reproduce command {reproduce}");
        for j in case["judgements"].as_array().unwrap() {
            let cell = |key: &str| esc(j[key].as_str().unwrap());
            let row = format!("<td>{}</td><td>{}</td>", cell("criterion"), cell("measured"));
            assert!(html.contains(&row), "no row {row}");
        }
        // Every run folder of a case has its own page, linked from the check's.
        for run in case["run_dirs"].as_array().unwrap() {
            let run = Path::new(run.as_str().unwrap());
            assert!(run.join("report.html").exists(), "{} has no page", run.display());
            let rel = run.strip_prefix(&out).unwrap().join("report.html");
            assert!(html.contains(&format!("href=\"{}\"", rel.display())), "no link to {}", rel.display());
        }
    }
    assert!(!html.contains("data-figure=\"steady/"), "a passed case's figures stay on its own page");
    // A case's run page gives the check's command for that case.
    let run_dir = out.join("steady/run-1");
    let run_page = run_dir.join("report.html");
    let figures = svgs(&run_dir, &run_dir);
    let figures: Vec<&str> = figures.iter().map(String::as_str).collect();
    let run_html = check_page(browser, &run_page, &dir, "check-run", &figures);
    assert!(run_html.contains(&format!("<code>silrig check {} --case steady</code>", suite.display())));
    if !keep {
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn a_sweeps_page_gives_the_pass_rate_the_worst_cases_and_the_figures() {
    let Some(browser) = chromium() else { return };
    let (dir, keep) = scratch("sweep");
    let out = dir.join("sweep");
    let o = silrig(&["sweep", "configs/sweep-robust.toml", "--runs", "20", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains(&format!("wrote {}", out.join("report.html").display())));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let html = check_page(browser, &out.join("report.html"), &dir, "sweep", &["envelope", "histograms", "scatter"]);
    let seed = summary["seed"].as_u64().unwrap();
    assert!(html.contains(&format!("<code>silrig sweep configs/sweep-robust.toml --runs 20 --seed {seed}</code>")));
    let rate = summary["pass_rate"].as_f64().unwrap() * 100.0;
    assert!(html.contains(&format!("pass rate {rate:.1} %")), "the pass rate {rate:.1} %");
    for (criterion, cases) in summary["worst"].as_array().unwrap().iter().map(|w| (&w[0], &w[1])) {
        assert!(html.contains(&format!("<h3>{}</h3>", criterion.as_str().unwrap())));
        for case in cases.as_array().unwrap() {
            let reproduce = case["reproduce"].as_str().unwrap();
            assert!(html.contains(&format!("<code>{reproduce}</code>")), "no {reproduce}");
        }
    }
    if !keep {
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// `<div id="view3d" ...>`'s attribute `name`, as the view's script set it.
fn view_attribute(dom: &str, name: &str) -> Option<u64> {
    let div = &dom[dom.find("<div id=\"view3d\"")?..];
    let div = &div[..div.find('>')?];
    let at = div.find(&format!("{name}=\""))? + name.len() + 2;
    div[at..at + div[at..].find('"')?].parse().ok()
}

/// Load `page` with the address `#view3d-test` (the view then reads its pixels back at the first and last frame).
fn load_view(browser: &str, page: &Path, scratch: &Path) -> Loaded {
    let o = browse(
        browser,
        Path::new(&format!("{}#view3d-test", page.display())),
        scratch,
        &["--enable-logging=stderr", "--v=0", "--dump-dom"],
    );
    assert!(o.success, "chromium --dump-dom {}: {}", page.display(), o.stderr);
    // The browser's notice that reading pixels back stalled its GPU is what the test asked for: any other message
    // fails the test.
    let console = o.stderr.lines().filter(|l| l.contains(":CONSOLE") && !l.contains("GPU stall due to ReadPixels"));
    Loaded { console: console.map(str::to_string).collect(), dom: o.stdout }
}

/// The 3-D view's bytes in `html`: its data and its script.
fn view_bytes(html: &str) -> usize {
    let start = html.find("<div id=\"view3d\"").expect("a 3-D view");
    let data = start + html[start..].find("id=\"view3d-data\"").unwrap();
    data + html[data..].find("</div>").unwrap() - start
}

#[test]
fn the_flight_is_drawn_in_3d_and_moves_for_the_f16_and_the_quadrotor() {
    let Some(browser) = chromium() else { return };
    let (dir, keep) = scratch("view3d");
    for (name, config, kind) in
        [("f16", None, "\"kind\":\"aircraft\""), ("quad", Some("configs/quad-steps.toml"), "\"kind\":\"quadrotor\"")]
    {
        let id = format!("html{}-{name}", std::process::id());
        let out = dir.join(name);
        let mut args = vec!["run", "--duration-s", "10", "--mode", "lockstep", "--quiet", "--run-id", &id];
        let out_arg = out.to_str().unwrap();
        args.extend(["--out", out_arg]);
        args.extend(config);
        let o = silrig(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let page = out.join("report.html");
        let html = std::fs::read_to_string(&page).unwrap();
        assert!(html.contains(kind), "{name}: the view draws the wrong vehicle");
        // A 10 s run's view (its data and our script) stays small: the page's size is the figures'.
        let bytes = view_bytes(&html);
        assert!(bytes < 80_000, "{name}: the 3-D view takes {bytes} bytes of the page");
        let loaded = load_view(browser, &page, &dir);
        assert!(loaded.console.is_empty(), "{name}: console messages: {:#?}", loaded.console);
        assert_eq!(loaded.body_number("data-errors"), 0, "{name}: script errors");
        assert_eq!(view_attribute(&loaded.dom, "data-view3d-frames"), Some(501), "{name}: 50 frames a second of 10 s");
        let (first, last) =
            (view_attribute(&loaded.dom, "data-view3d-first"), view_attribute(&loaded.dom, "data-view3d-last"));
        assert!(first.is_some() && first != last, "{name}: the first and last frames draw alike: {first:?} {last:?}");
        let colours = view_attribute(&loaded.dom, "data-view3d-colours").unwrap();
        assert!(colours > 20, "{name}: {colours} colours: the vehicle, grid and path were not drawn");
        common::no_shared_memory_left(&id);
    }
    if !keep {
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn the_views_surfaces_turn_as_foxgloves_and_its_rotation_is_the_quaternions() {
    let Some(browser) = chromium() else { return };
    let (dir, keep) = scratch("view3d-math");
    let angles = [[0.0, 0.0, 0.0], [0.2, -0.3, 0.1], [-0.35, 0.4, -0.25]];
    let quaternion = silrig::recording::foxglove::enu_flu_quaternion(0.3, -0.2, 1.1);
    let page = dir.join("math.html");
    std::fs::write(
        &page,
        format!(
            "<!DOCTYPE html><html><body><script>{}</script><script>\
             var model={},out=[];{angles:?}.forEach(function(a){{model.surfaces.forEach(function(s){{\
             var p=silrigView3d.surfacePose(s,a);out.push(p.center.concat(p.q));}});}});\
             document.body.setAttribute('data-poses',JSON.stringify(out));\
             document.body.setAttribute('data-matrix',JSON.stringify(silrigView3d.quatMatrix({quaternion:?})));\
             </script></body></html>",
            silrig::html::view3d::SCRIPT,
            silrig::recording::foxglove::aircraft_model(),
        ),
    )
    .unwrap();
    let loaded = load_view(browser, &page, &dir);
    let attribute = |name: &str| -> Vec<Vec<f64>> {
        let at = loaded.dom.find(&format!("{name}=\"")).unwrap_or_else(|| panic!("no {name}")) + name.len() + 2;
        let text = &loaded.dom[at..at + loaded.dom[at..].find('"').unwrap()];
        serde_json::from_str(&text.replace("&quot;", "\"")).unwrap()
    };
    let expected: Vec<Vec<f64>> = angles
        .iter()
        .flat_map(|a| silrig::recording::foxglove::surface_poses(*a))
        .map(|(c, q)| c.into_iter().chain(q).collect())
        .collect();
    let poses = attribute("data-poses");
    assert_eq!(poses.len(), expected.len());
    for (js, rust) in poses.iter().zip(&expected) {
        assert!(js.iter().zip(rust).all(|(a, b)| (a - b).abs() < 1e-12), "script {js:?}, Rust {rust:?}");
    }
    // The matrix's columns are the body's axes in the world: x the nose, z the top.
    let [x, y, z, w] = quaternion;
    let nose = [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)];
    let m = attribute("data-matrix");
    for r in 0..3 {
        assert!((m[r][0] - nose[r]).abs() < 1e-12, "{m:?} {nose:?}");
    }
    if !keep {
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
