//! What a bridge is asked to do: the `silrig-bridge` flags ([`BridgeOptions`]), checked into a side and a Zenoh
//! endpoint, and the fixed timings both sides keep beside them.

use super::error::BridgeError;
use super::frame::Side;
use super::net;
use silrig_rig::ProcessArgs;
use std::time::Duration;

/// How often each bridge says hello.
pub const HELLO_PERIOD: Duration = Duration::from_millis(100);
/// A controller-side bridge the plant side keeps refusing for this long (it serves another, alive one) gives up.
pub const REFUSED_AFTER: Duration = Duration::from_millis(1500);
/// How long the controller side waits for the run's scenario once the plant side answers.
pub const RUN_INFO_TIMEOUT: Duration = Duration::from_secs(5);
/// The controller side ends this long after the plant's last sample (the controller has ended by then).
pub const FINISHED_GRACE: Duration = Duration::from_millis(500);
/// At the end the controller side waits this long for the controller's report, then as long for the plant side's
/// receipt of it.
pub const REPORT_WAIT: Duration = Duration::from_secs(3);
/// Key of the controller's report on its way to the plant's host (empty: there is none).
pub const CONTROLLER_REPORT: &str = "controller-report";
/// Key of the plant side's receipt of it.
pub const REPORT_RECEIVED: &str = "controller-report-received";
/// The plant side's event when the report cannot be had: none was written, or it was unusable.
pub const REPORT_ABSENT: &str = "controller-report-absent";

/// What `silrig-bridge` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct BridgeOptions {
    /// Plant's host: listen for the controller side's bridge here (IP:PORT, tcp/IP:PORT or udp/IP:PORT).
    /// `silrig run --bridge-listen` starts this side for you.
    #[arg(long, value_name = "ENDPOINT", required_unless_present = "connect", conflicts_with = "connect")]
    pub listen: Option<String>,
    /// Controller's host: connect to the plant-side bridge there (IP:PORT, tcp/IP:PORT or udp/IP:PORT).
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Option<String>,
    /// Controller side: give up when no plant-side bridge of this run answers within this long, s.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    pub connect_timeout_s: f64,
    /// The other bridge counts as lost after this long without its hello (sent every 100 ms), ms.
    #[arg(long, default_value_t = 500.0, allow_negative_numbers = true)]
    pub peer_timeout_ms: f64,
    /// Controller side: the iceoryx2 namespace of the run's half on this host, for its controller's
    /// `--run-id` (default: the run id). Another id puts both hosts' halves on one machine, as `silrig soak
    /// --bridge` does.
    #[arg(long, value_name = "RUN_ID", requires = "connect")]
    pub local_run_id: Option<silrig_wire::ipc::namespace::RunId>,
    /// The run: its id, and on the plant side its scenario, mode and tuning (the controller side takes those from
    /// the plant side and writes them to <out>/scenario.toml and <out>/controller.env for its controller).
    #[command(flatten)]
    pub process: ProcessArgs,
}

impl BridgeOptions {
    /// The namespace of the run's half on this host.
    pub fn local_run_id(&self) -> &silrig_wire::ipc::namespace::RunId {
        self.local_run_id.as_ref().unwrap_or(&self.process.run_id)
    }

    /// The side and the Zenoh endpoint, checked.
    pub fn side(&self) -> Result<(Side, String), BridgeError> {
        silrig_rig::flag_in_range("connect-timeout-s", self.connect_timeout_s, 0.1, 3600.0, "s")
            .and_then(|()| silrig_rig::flag_in_range("peer-timeout-ms", self.peer_timeout_ms, 150.0, 60_000.0, "ms"))
            .and_then(|()| self.process.options.validate())
            .map_err(BridgeError::Usage)?;
        let (side, text) = match (&self.listen, &self.connect) {
            (Some(l), None) => (Side::Plant, l),
            (None, Some(c)) => (Side::Controller, c),
            _ => return Err(BridgeError::Usage("give exactly one of --listen and --connect".into())),
        };
        let flag = if side == Side::Plant { "--listen" } else { "--connect" };
        Ok((side, net::endpoint(text).map_err(|e| BridgeError::Usage(format!("{flag}: {e}")))?))
    }
}
