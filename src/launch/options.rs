//! What `silrig run` is asked to do: its options as the command line gives them (`silrig run --help`), where the
//! plant and the controller come from, who takes the OS floor and where the run is served live.

use crate::supervision::{ControllerLaunch, SupervisionOptions};
use silrig_flight::fault::Fault;
use silrig_flight::scenario::Scenario;
use silrig_rig::{ProcessOptions, RigMode};
use silrig_wire::ipc::RunId;
use std::net::SocketAddr;
use std::path::PathBuf;

/// What `silrig run` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct LaunchOptions {
    /// Scenario file (TOML); without it, the embedded default scenario (for a plant of your own, --plant-cmd,
    /// --plant-fmu or --plant external: the embedded any-plant scenario, set points and timing only).
    pub config: Option<PathBuf>,
    /// realtime (the scenario's rate on the wall clock) or lockstep (as fast as possible, deterministic).
    #[arg(long, value_enum, default_value = "realtime")]
    pub mode: RigMode,
    /// Override the scenario's duration, s.
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Output folder (default: out/run-<run id>); must not hold a run already.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run id (default: a fresh one).
    #[arg(long)]
    pub run_id: Option<RunId>,
    /// Do not run the OS-floor timer loop beside a realtime rig.
    #[arg(long)]
    pub no_baseline: bool,
    /// Who takes the OS floor beside a realtime rig: builtin (`silrig timer-baseline`) or cyclictest (rt-tests,
    /// which must be installed); the report names which.
    #[arg(long, value_enum, default_value = "builtin")]
    pub floor: FloorSource,
    /// No live status line while the run goes.
    #[arg(long)]
    pub quiet: bool,
    /// Draw no figures (the trace, report and timing files are written as ever): for runs judged from their files
    /// alone, such as the cases of `silrig sweep --controller-cmd`, where drawing them would take as long as flying.
    #[arg(long)]
    pub no_figures: bool,
    /// Loop and watchdog tuning, passed on to every process.
    #[command(flatten)]
    pub process: ProcessOptions,
    /// A fault to inject, added to the scenario's [[faults]]: TARGET:ACTION@TIME[,KEY=VALUE...], e.g.
    /// `controller:kill@3s,restart_after=0.5s`, `logger:stop@2s,for=500ms`, `plant:delay@2s,delay=15ms`,
    /// `device:cut@12s,packet=rc,for=3s` (a device's packet not sent), `device:kill@20s`. Repeatable.
    #[arg(long = "fault", value_parser = silrig_flight::fault::parse_fault_flag)]
    pub faults: Vec<Fault>,
    /// What to do when a process dies.
    #[command(flatten)]
    pub supervision: SupervisionOptions,
    /// Fly your own controller: run this command in place of silrig-controller, with the run's SILRIG_* variables
    /// in its environment (`silrig contract` lists them). Split into words like a shell does, but run directly
    /// (wrap it in `sh -c '...'` yourself for shell syntax). Supervised, restarted and faulted like ours; its stdout
    /// and stderr go to <out>/controller.stderr.log.
    #[arg(long, value_name = "CMD")]
    pub controller_cmd: Option<String>,
    /// Fly your own vehicle model: run this command in place of silrig-plant, with the run's SILRIG_* variables in
    /// its environment; it opens a plant session of libsilrig_client.so (Python: `silrig_client.serve_plant`),
    /// announces its signals and steps its model with the inputs each tick hands it, while the rig keeps the
    /// clock, the watchdog, the failsafe and the faults. Split and supervised like --controller-cmd; its stdout and
    /// stderr go to <out>/plant.stderr.log.
    #[arg(long, value_name = "CMD")]
    pub plant_cmd: Option<String>,
    /// Fly a co-simulation FMU (FMI 2.0 or 3.0, with a Linux x86-64 binary) as the plant: silrig-plant loads it,
    /// announces its Real, Integer and Boolean outputs and inputs as the plant's signals and steps it once per tick;
    /// the scenario's `[plant.parameters]` set its parameters by variable name. Same as the scenario key
    /// `[plant] fmu`.
    #[arg(long, value_name = "FILE.fmu", conflicts_with_all = ["plant_cmd", "plant"])]
    pub plant_fmu: Option<PathBuf>,
    /// Fly a co-simulation FMU (FMI 2.0 or 3.0, with a Linux x86-64 binary) as the controller: silrig-controller
    /// loads it, feeds its inputs (Real, Integer, Boolean) the plant's outputs of the same name (an input `<output>_sp`
    /// the scenario's set point of that output; an input that names nothing of the plant its start value), commands
    /// the plant's inputs with its outputs of the same name and logs all its outputs as diagnostics;
    /// `[controller.map]` renames or holds an input at a constant, `[controller.parameters]` sets its parameters.
    /// Same as the scenario key `[controller] fmu`.
    #[arg(long, value_name = "FILE.fmu", conflicts_with_all = ["controller_cmd", "controller", "bridge_listen"])]
    pub controller_fmu: Option<PathBuf>,
    /// builtin (silrig-plant, or --plant-cmd) or external: wait for a plant started by hand (in a debugger, in a
    /// simulation tool) with the variables printed and written to <out>/plant.env.
    #[arg(long, value_enum, default_value = "builtin", conflicts_with = "plant_cmd")]
    pub plant: PlantKind,
    /// builtin (silrig-controller, or --controller-cmd) or external: wait for a controller started by hand (in a
    /// debugger, in MATLAB) with the variables printed and written to <out>/controller.env.
    #[arg(long, value_enum, default_value = "builtin", conflicts_with = "controller_cmd")]
    pub controller: ControllerKind,
    /// --controller or --plant external: how long the rig waits for the process started by hand to connect, s.
    #[arg(long, default_value_t = 120.0)]
    pub external_timeout_s: f64,
    /// The controller runs on another host: start the plant-side bridge listening here (IP:PORT, tcp/IP:PORT or
    /// udp/IP:PORT) instead of a controller, and wait up to --external-timeout-s for `silrig-bridge --connect` and a
    /// controller on the other host. Any address but the loopback needs --bridge-key (or --bridge-insecure).
    /// Next-tick timing unless --command-timing says otherwise. Needs silrig-bridge (`cargo build --release
    /// --features bridge`).
    #[arg(long, value_name = "ENDPOINT", conflicts_with_all = ["controller_cmd", "controller"])]
    pub bridge_listen: Option<String>,
    /// The bridge key for --bridge-listen (`silrig-bridge keygen FILE`, the same file on the controller's host,
    /// readable by its owner only): the link runs over TLS and only a bridge holding the key can join. Needed on
    /// any address but the loopback.
    #[arg(long, value_name = "FILE", requires = "bridge_listen")]
    pub bridge_key: Option<PathBuf>,
    /// --bridge-listen off the loopback without a key: anyone who reaches the port can join the run, read its
    /// samples and command the plant. Only on a network you trust.
    #[arg(long, requires = "bridge_listen", conflicts_with = "bridge_key")]
    pub bridge_insecure: bool,
    /// Override the scenario's command timing: same-tick (the plant waits up to --command-budget-ms for the answer
    /// to the tick it just published) or next-tick.
    #[arg(long, value_enum)]
    pub command_timing: Option<silrig_flight::scenario::CommandTiming>,
    /// Serve the run live while it flies: `foxglove` or `foxglove=IP:PORT` (default 127.0.0.1:8765), the
    /// recording's channels over the Foxglove WebSocket protocol, from the logger, for Foxglove or Lichtblick to
    /// connect to. Needs the `live` feature (`cargo build --release --features live`).
    #[arg(long, value_name = "foxglove[=IP:PORT]", value_parser = parse_live)]
    pub live: Option<LiveServe>,
}

/// Where `--live` serves the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LiveServe {
    /// The Foxglove WebSocket protocol, on this address.
    Foxglove(SocketAddr),
}

/// Where `--live foxglove` serves without an address: Foxglove's own default.
pub const LIVE_FOXGLOVE_DEFAULT: &str = "127.0.0.1:8765";

/// `--live`'s value: `foxglove` or `foxglove=IP:PORT`.
pub fn parse_live(value: &str) -> Result<LiveServe, String> {
    let (protocol, addr) = value.split_once('=').unwrap_or((value, LIVE_FOXGLOVE_DEFAULT));
    if protocol != "foxglove" {
        return Err(format!("`{protocol}` is no live protocol: the one served is `foxglove` (foxglove[=IP:PORT])"));
    }
    addr.parse()
        .map(LiveServe::Foxglove)
        .map_err(|e| format!("`{addr}` is no IP:PORT address ({e}), e.g. foxglove=127.0.0.1:8765"))
}

/// The line the launcher prints when it serves the run live on `addr`: where, and who can reach it (the server
/// has no authentication and no TLS, so off the loopback it is anyone on the network).
pub fn live_line(addr: SocketAddr) -> String {
    let reach = if addr.ip().is_loopback() {
        format!(
            "on the loopback only: programs on this host can connect, no other machine (serve the network with \
                 --live foxglove=0.0.0.0:{})",
            addr.port()
        )
    } else {
        format!(
            "open to the network: anyone who reaches port {} of this host can watch the run (no \
                 authentication, no TLS)",
            addr.port()
        )
    };
    format!("silrig run: serving the run live on ws://{addr} (Foxglove WebSocket protocol), {reach}")
}

/// Who measures the OS floor beside a realtime run (`--floor`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FloorSource {
    /// `silrig timer-baseline`: a bare clock_nanosleep loop with the rig's skip-on-overrun rule, which also gives
    /// the floor's steady state apart from warm-up.
    Builtin,
    /// cyclictest itself (`cyclictest -q -m -t1 -p80 -i<period> -h`), the reference engineers already trust.
    Cyclictest,
}

/// Where the run's controller comes from (`--controller`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ControllerKind {
    /// The launcher starts it: silrig-controller, or the `--controller-cmd` command.
    Builtin,
    /// Somebody else starts it; the launcher waits for it.
    External,
}

/// Where the run's plant comes from (`--plant`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PlantKind {
    /// The launcher starts it: silrig-plant, or the `--plant-cmd` command.
    Builtin,
    /// Somebody else starts it; the launcher waits for it.
    External,
}

impl LaunchOptions {
    /// The plant-side bridge's flags for its security: `--key FILE` or `--insecure`, or none (the loopback).
    pub fn bridge_security(&self) -> Vec<String> {
        match (&self.bridge_key, self.bridge_insecure) {
            (Some(key), _) => vec!["--key".into(), key.display().to_string()],
            (None, true) => vec!["--insecure".into()],
            (None, false) => Vec::new(),
        }
    }

    /// Whether the plant is a built-in vehicle (no `--plant-cmd`, `--plant external` or plant FMU).
    pub(crate) fn flies_builtin(&self, scenario: &Scenario) -> bool {
        self.plant_cmd.is_none() && self.plant != PlantKind::External && scenario.plant.fmu.is_none()
    }

    /// Whether the plant is the built-in F-16.
    pub(crate) fn flies_builtin_f16(&self, scenario: &Scenario) -> bool {
        self.flies_builtin(scenario) && !silrig_flight::quad::is_quad(scenario)
    }

    pub(crate) fn controller_launch(&self) -> ControllerLaunch {
        match (&self.controller_cmd, self.controller) {
            _ if self.bridge_listen.is_some() => ControllerLaunch::External,
            (_, ControllerKind::External) => ControllerLaunch::External,
            (Some(cmd), _) => ControllerLaunch::Command(cmd.clone()),
            (None, _) => ControllerLaunch::Ours,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_live_line_says_who_can_reach_the_server() {
        let LiveServe::Foxglove(local) = parse_live("foxglove").unwrap();
        assert_eq!(local.to_string(), LIVE_FOXGLOVE_DEFAULT, "the loopback unless told otherwise");
        let line = live_line(local);
        assert!(line.contains("ws://127.0.0.1:8765") && line.contains("on the loopback only"), "{line}");
        assert!(line.contains("foxglove=0.0.0.0:8765"), "says how to serve the network: {line}");
        let LiveServe::Foxglove(open) = parse_live("foxglove=0.0.0.0:9000").unwrap();
        let line = live_line(open);
        assert!(line.contains("open to the network") && line.contains("port 9000"), "{line}");
        assert!(!line.contains("loopback"), "{line}");
    }

    #[test]
    fn the_bridge_s_security_flags_follow_silrig_run_s() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            opts: LaunchOptions,
        }
        let parse = |args: &[&str]| Cli::try_parse_from([&["silrig"], args].concat()).map(|c| c.opts);
        let keyed = parse(&["--bridge-listen", "0.0.0.0:7447", "--bridge-key", "lab.key"]).unwrap();
        assert_eq!(keyed.bridge_security(), ["--key", "lab.key"]);
        let open = parse(&["--bridge-listen", "0.0.0.0:7447", "--bridge-insecure"]).unwrap();
        assert_eq!(open.bridge_security(), ["--insecure"]);
        assert!(parse(&["--bridge-listen", "127.0.0.1:7447"]).unwrap().bridge_security().is_empty());
        assert!(parse(&["--bridge-key", "lab.key"]).is_err(), "a key without --bridge-listen");
        assert!(parse(&["--bridge-listen", "0.0.0.0:7447", "--bridge-key", "k", "--bridge-insecure"]).is_err());
    }
}
