//! `silrig soak`: the chaos soak. A realtime `silrig run` of the default scenario whose fault plan is drawn from a
//! seed ([`schedule`]): every process killed, terminated, stopped, delayed, jittered and restarted, the plant's
//! and controller's publishing dropped, the plant's sensors and actuators faulted, at times a few seconds apart.
//! The soak watches the run's processes from outside while it flies ([`probe`]), then reads the run folder and
//! gives its figures and verdict ([`figures`]; the rows lost, and which of them a stall of the machine explains:
//! [`losses`]), printed ([`text`]) and written as `soak.json` in the run folder. With
//! `--bridge` the controller flies behind the bridge, its host emulated on this machine ([`controller_host`]).

pub mod controller_host;
pub mod figures;
pub mod losses;
pub mod probe;
pub mod schedule;
pub mod text;

use anyhow::Context;
use controller_host::ControllerHost;
use figures::{ControllerHostFigures, Measured, SoakReport};
use probe::ProcessProbe;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Shortest and longest soak, s: the first fault comes 5 s in and the last 6 s before the end.
pub const DURATION_RANGE_S: (f64, f64) = (15.0, 86_400.0);
/// How often the soak looks at the run's processes.
const POLL: Duration = Duration::from_millis(250);

/// `silrig soak`'s options.
#[derive(Debug, Clone, clap::Args)]
pub struct SoakArgs {
    /// Length of the realtime run, s (15..86400).
    #[arg(long, default_value_t = 600.0)]
    pub duration_s: f64,
    /// Seed of the fault schedule: the same seed, the same faults at the same times.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The run's folder (default: out/soak-<run id>); soak.json is written there beside the run's files.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run id (default: soak<seed>-<pid>).
    #[arg(long)]
    pub run_id: Option<String>,
    /// Print the schedule's `--fault` flags and stop.
    #[arg(long)]
    pub print_schedule: bool,
    /// Fly the controller behind the bridge: the plant's host (`silrig run --bridge-listen` on 127.0.0.1) and the
    /// controller's host (`silrig-bridge --connect` and the controller, in a namespace of their own) on this
    /// machine; the plant-side bridge is killed, terminated and stopped in place of the controller's faults. Needs
    /// a build with the `bridge` feature.
    #[arg(long)]
    pub bridge: bool,
}

/// Run a soak with the `silrig` binary `silrig`; the report (also in `<out>/soak.json`).
pub fn run(args: &SoakArgs, silrig: &Path) -> anyhow::Result<SoakReport> {
    let (lo, hi) = DURATION_RANGE_S;
    anyhow::ensure!(
        args.duration_s.is_finite() && (lo..=hi).contains(&args.duration_s),
        "--duration-s must be within {lo}..{hi} s, got {}",
        args.duration_s
    );
    let plan = schedule::schedule(args.seed, args.duration_s, args.bridge);
    let run_id = args.run_id.clone().unwrap_or_else(|| format!("soak{}-{}", args.seed % 100_000, std::process::id()));
    silrig_wire::ipc::namespace::RunId::new(&run_id).with_context(|| format!("--run-id {run_id:?}"))?;
    let out = args.out.clone().unwrap_or_else(|| Path::new("out").join(format!("soak-{run_id}")));
    let dt_s = silrig_rig::load_scenario(None, Some(args.duration_s))?.timing.dt_s;
    let mut command: Vec<String> = ["run", "--quiet", "--duration-s"].map(String::from).to_vec();
    command.extend([args.duration_s.to_string(), "--out".into(), out.display().to_string()]);
    command.extend(["--run-id".into(), run_id.clone()]);
    for f in schedule::flags(args.seed, args.duration_s, args.bridge) {
        command.extend(["--fault".into(), f]);
    }
    let mut host = if args.bridge {
        let endpoint = format!("127.0.0.1:{}", free_tcp_port()?);
        command.extend(["--bridge-listen".into(), endpoint.clone()]);
        let bin_dir = silrig.parent().context("the silrig binary's folder")?;
        Some(ControllerHost::new(bin_dir, &endpoint, &run_id, &out)?)
    } else {
        None
    };
    let started_utc = utc_now();
    let load_start = load_average();
    let mut child =
        Command::new(silrig).args(&command).spawn().with_context(|| format!("starting {}", silrig.display()))?;
    let last_fault_s = plan.iter().map(|f| f.at_s).fold(0.0, f64::max);
    let (status, watched) = watch(&mut child, &out, &run_id, host.as_mut(), last_fault_s, args.duration_s)?;
    // The controller's host first: the bridge ends after sending the controller's report, the controller with the
    // flight; what had to be ended is a problem of its own, not a leftover.
    let controller_host = host.as_mut().map(|h| {
        let still_running = h.finish(Duration::from_secs(10));
        ControllerHostFigures {
            local_run_id: h.local.to_string(),
            folder: h.out.display().to_string(),
            bridge_starts: h.starts.0,
            controller_starts: h.starts.1,
            still_running,
        }
    });
    let mut leftovers = probe::Leftovers::find(&run_id, &out, &watched.seen);
    if let Some(h) = &host {
        leftovers.extend(probe::Leftovers::find(h.local.as_str(), &h.out, &h.pids));
    }
    let measured = Measured {
        seed: args.seed,
        duration_s: args.duration_s,
        run_id,
        out: out.clone(),
        command: std::iter::once("silrig".to_string()).chain(command).collect(),
        started_utc,
        load_average: (load_start, load_average()),
        run_exit: status.code(),
        start: watched.start,
        end: watched.end,
        lives: watched.lives.into_vec(),
        leftovers,
        controller_host,
    };
    let report = figures::report(&plan, dt_s, measured);
    if out.is_dir() {
        let path = out.join("soak.json");
        silrig_flight::files::write_atomically(&path, &serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(report)
}

/// What the soak saw of the run while it went: every pid, the processes and the run's /dev/shm entries once settled
/// and after the last fault, and every life's figures.
struct Watched {
    seen: probe::SeenPids,
    start: Option<(Vec<ProcessProbe>, Vec<String>)>,
    end: Option<(Vec<ProcessProbe>, Vec<String>)>,
    lives: probe::Lives,
}

/// Probe the run's processes (and the controller's host's, kept up) every [`POLL`] until the launcher exits.
fn watch(
    child: &mut std::process::Child,
    out: &Path,
    run_id: &str,
    mut host: Option<&mut ControllerHost>,
    last_fault_s: f64,
    duration_s: f64,
) -> anyhow::Result<(std::process::ExitStatus, Watched)> {
    let launcher = child.id();
    let host_prefix = host.as_ref().map(|h| h.local.prefix());
    let mut host_trouble = String::new();
    let shm_prefix = format!("sr_{run_id}_");
    let mut w = Watched { seen: probe::SeenPids::new(), start: None, end: None, lives: probe::Lives::default() };
    probe::note_seen(&mut w.seen, launcher);
    let mut t0_ns: Option<u64> = None;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if t0_ns.is_none() {
            t0_ns = silrig_launch::fault_report::plant_t0_ns(out);
        }
        let mut probes = probe::probe_run(launcher, &shm_prefix);
        if let Some(h) = host.as_deref_mut() {
            if let Err(e) = h.keep_up() {
                let said = format!("silrig soak: the controller's host: {e:#}");
                if said != host_trouble {
                    eprintln!("{said}");
                    host_trouble = said;
                }
            }
            probes.extend(h.probes());
        }
        for p in &probes {
            probe::note_seen(&mut w.seen, p.pid);
        }
        // Wall seconds from tick 0; measurements stop a second before the end, when the launcher ends the rig.
        let wall_s = t0_ns.map(|t0| silrig_wire::clock::monotonic_ns().saturating_sub(t0) as f64 / 1e9);
        if let Some(wall_s) = wall_s.filter(|t| *t <= duration_s - 1.0) {
            w.lives.observe(&probes, wall_s);
        }
        let rig_up = ["plant", "controller", "logger"].iter().all(|r| probes.iter().any(|p| p.process == *r));
        if let Some(wall_s) = wall_s
            && rig_up
        {
            let mut shm = probe::shm_entries(&shm_prefix);
            shm.extend(host_prefix.iter().flat_map(|p| probe::shm_entries(p)));
            if w.start.is_none() && (probe::SETTLE_S..schedule::FIRST_FAULT_S - 0.5).contains(&wall_s) {
                w.start = Some((probes.clone(), shm.clone()));
            }
            // After the last fault's recovery (the schedule leaves the last seconds quiet), before the run's end.
            if wall_s >= last_fault_s + 3.0 && wall_s <= duration_s - 1.0 {
                w.end = Some((probes, shm));
            }
        }
        std::thread::sleep(POLL);
    };
    Ok((status, w))
}

/// A TCP port of 127.0.0.1 nobody listens on now, for the plant-side bridge.
fn free_tcp_port() -> anyhow::Result<u16> {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").context("finding a free TCP port for the bridge")?;
    Ok(listener.local_addr()?.port())
}

/// 1, 5 and 15 minute load averages.
fn load_average() -> Vec<f64> {
    silrig_rig::report::MachineConditions::now().load_average.to_vec()
}

/// Now, as `YYYY-MM-DD hh:mm:ss UTC`.
fn utc_now() -> String {
    let iso = crate::check::verdict::utc_iso(crate::check::verdict::unix_now_s());
    format!("{} UTC", iso.replace('T', " "))
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_date_is_the_calendar_date() {
        let s = super::utc_now();
        assert!(s.starts_with("20") && s.ends_with(" UTC") && s.len() == 23, "{s}");
    }
}
