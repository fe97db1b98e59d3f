//! `silrig-bridge`: the rig's streams between two hosts over Zenoh, for a controller that runs on another machine
//! than the plant. The plant side (started by `silrig run --bridge-listen`) reads the run's plant samples from
//! iceoryx2 and publishes them under `silrig/<run id>/plant`, and passes the commands and controller info that come
//! back into the plant's iceoryx2 namespace; the controller side (`silrig-bridge --connect`) does the mirror image
//! in the run's namespace on its own host, where any controller of the contract runs unchanged.
//!
//! Samples cross as the contract's bytes, header included, checked on arrival ([`frame`]); the bridge keeps their
//! `seq`, `tick` and `epoch` ([`silrig_wire::ipc::StreamPublisher::forward`]), so readers on either host see the original
//! publisher's losses and restarts, and only `t_send_ns` is stamped anew (the other host's clock means nothing
//! here). Each bridge says hello every [`HELLO_PERIOD`]; a peer silent for `--peer-timeout-ms` is lost, said at
//! once on stderr and in the events ([`peer`]). The plant side serves one controller-side bridge at a time: a
//! second one is refused while the first is alive, and a restarted one (a new epoch) takes over once the old one
//! is lost. Losing the peer stops the commands; the plant's own staleness watchdog and failsafe do the rest.
//!
//! The network leg is measured without a shared clock: the plant side times each plant sample out to the command
//! answering it back, and subtracts the time that tick spent on the controller's host, which the controller side
//! measures and sends beside the command ([`frame::CommandTrailer`]). That is `bridge.network_rtt`: both ways
//! across the network and through both Zenoh stacks.
//!
//! The folder, each file with what it owns (none imports a file that imports it back):
//!
//! - `lib.rs`: [`run_bridge`], which picks the side and writes the report, and this map.
//! - `options.rs`: [`BridgeOptions`] (the flags, checked into a [`Plan`]: side, endpoint, key) and the fixed
//!   timings ([`HELLO_PERIOD`], [`REFUSED_AFTER`], [`RUN_INFO_TIMEOUT`], [`FINISHED_GRACE`]).
//! - `error.rs`: [`BridgeError`], each failure phrased for the person running the bridge.
//! - [`key`]: the bridge key both hosts hold (made by `silrig-bridge keygen`, read from an owner-only file) and
//!   the TLS settings it gives Zenoh.
//! - [`tls_watch`]: Zenoh's TLS handshake failures, which it only logs, caught for the bridge to say in words.
//! - [`frame`]: what crosses the network, as bytes, checked on arrival; pure.
//! - [`net`]: the Zenoh session, the run's keys and the inbox Zenoh's threads fill.
//! - [`impair`]: the test-only delay and loss of arrivals (`SILRIG_BRIDGE_TEST_*`), for want of `sch_netem`.
//! - [`peer`]: who is at the other end (joined, lost, replaced, a rival); pure.
//! - `link.rs`: what both sides share: the Zenoh ends and the hello, the check of a peer's hello against this
//!   run, an iceoryx2 listener's descriptor to poll.
//! - `stamps.rs`: when each recent tick went out, for timing the network leg.
//! - [`loop_watch`]: a thread that says when a bridge's own loop stands still, and in which step.
//! - `plant_side.rs`: the plant's host.
//! - `controller_side.rs`: the controller's host.

mod controller_side;
mod error;
pub mod frame;
pub mod impair;
pub mod key;
mod link;
pub mod loop_watch;
pub mod net;
mod options;
pub mod peer;
mod plant_side;
mod stamps;
pub mod tls_watch;

pub use error::BridgeError;
pub use options::{
    BridgeOptions, CONTROLLER_REPORT, FINISHED_GRACE, HELLO_PERIOD, Plan, REFUSED_AFTER, REPORT_ABSENT,
    REPORT_RECEIVED, REPORT_WAIT, RUN_INFO_TIMEOUT,
};
/// Zenoh as the bridge uses it, for a test's raw peer beside the bridges (`tests/bridge.rs`'s stranger).
pub use zenoh;

use controller_side::ControllerSide;
use frame::Side;
use plant_side::PlantSide;
use silrig_flight::role::Role;
use silrig_rig::report::{ProcessReport, ReportMeta};
use silrig_rig::{RigMode, signals};

/// Run a bridge until SIGTERM (plant side) or the end of the flight (controller side), and write its report
/// (`<out>/bridge.report.json`).
pub fn run_bridge(opts: &BridgeOptions) -> anyhow::Result<ProcessReport> {
    signals::install_termination_flag();
    let plan = opts.plan()?;
    let args = &opts.process;
    if args.mode == RigMode::Realtime {
        // Before Zenoh starts its threads, so they inherit it: the network leg is on the loop's critical path.
        let status = silrig_wire::clock::try_realtime(Role::Controller.fifo_priority().unwrap_or(1));
        if let Some(w) = status.warning {
            eprintln!("silrig-bridge: warning: {w}");
        }
    }
    let scheduling = silrig_wire::clock::current_policy().to_string();
    let flown = match plan.side {
        Side::Plant => PlantSide::start(opts, &plan).and_then(PlantSide::run),
        Side::Controller => ControllerSide::start(opts, &plan).and_then(ControllerSide::run).inspect(|_| {
            clean_controller_host(opts.local_run_id());
        }),
    };
    // Said in the run's events too, beside the controller's or the plant's: on the controller's host there is no
    // launcher to quote the bridge's stderr, and a controller there only sees its plant go quiet.
    let (mut rec, scenario, ended) = flown.inspect_err(|e| {
        silrig_rig::events::EventLog::new(&args.out, "bridge").emit(None, "bridge-failed", format!("{e:#}"));
    })?;
    rec.declare(&["peer_losses"]);
    let meta = ReportMeta::new(args, &scenario, scheduling, ended);
    Ok(rec.finish(meta, &args.out)?)
}

/// `--check`: what the bridge would do, in a line, or why it would not start.
pub fn check(opts: &BridgeOptions) -> Result<String, BridgeError> {
    let plan = opts.plan()?;
    let verb = if plan.side == Side::Plant { "listen on" } else { "connect to" };
    Ok(format!("would {verb} {} with {}", plan.endpoint, plan.security()))
}

/// The controller's host has no launcher to remove the iceoryx2 files of its half of the run: the bridge, ending
/// after the flight (its own node gone), removes them once no process there is alive. A controller still running
/// keeps them, and is named.
fn clean_controller_host(local: &silrig_wire::ipc::namespace::RunId) {
    match silrig_wire::ipc::namespace::cleanup_run(local) {
        Ok(r) if !r.alive.is_empty() => {
            let who: Vec<String> = r.alive.iter().map(|n| format!("{} (pid {})", n.name, n.pid)).collect();
            eprintln!(
                "silrig-bridge: {} still running in namespace {local}: its iceoryx2 files are left to it",
                who.join(", ")
            );
        }
        Ok(_) => {}
        Err(e) => eprintln!("silrig-bridge: warning: cleaning namespace {local}: {e}"),
    }
}
