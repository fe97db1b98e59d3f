//! What a bridge is asked to do: the `silrig-bridge` flags ([`BridgeOptions`]), checked into a [`Plan`] (a side,
//! a Zenoh endpoint and the bridge key, or the reason none is needed), and the fixed timings both sides keep beside
//! them.

use super::error::BridgeError;
use super::frame::Side;
use super::key::BridgeKey;
use super::net;
use silrig_rig::ProcessArgs;
use std::path::PathBuf;
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
    /// Plant's host: listen for the controller side's bridge here (IP:PORT, tcp/IP:PORT or udp/IP:PORT; any
    /// address but the loopback needs --key). `silrig run --bridge-listen` starts this side for you.
    #[arg(long, value_name = "ENDPOINT", required_unless_present = "connect", conflicts_with = "connect")]
    pub listen: Option<String>,
    /// Controller's host: connect to the plant-side bridge there (IP:PORT, tcp/IP:PORT or udp/IP:PORT; any
    /// address but the loopback needs --key, the plant side's key file).
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
    /// The bridge key, the same file on both hosts (make it with `silrig-bridge keygen FILE`, copy it with `scp
    /// -p`): the link runs over TLS and each bridge admits only a peer holding the key. Needed on any address but
    /// the loopback; the file must be readable by its owner only.
    #[arg(long, value_name = "FILE")]
    pub key: Option<PathBuf>,
    /// No key on an address other than the loopback: anyone who reaches the port can join the run, read its
    /// samples and command the plant, and the link is not encrypted. Only on a network you trust.
    #[arg(long, conflicts_with = "key")]
    pub insecure: bool,
    /// Check the flags and the key, then exit (0: the bridge would start; 2: why not). `silrig run
    /// --bridge-listen` does this before it starts anything.
    #[arg(long)]
    pub check: bool,
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

    /// What this bridge will do, checked: its side, its endpoint and its key (read from its owner-only file).
    pub fn plan(&self) -> Result<Plan, BridgeError> {
        let (side, endpoint) = self.side()?;
        let key = self.key.as_deref().map(BridgeKey::read).transpose()?;
        let flag = if side == Side::Plant { "--listen" } else { "--connect" };
        let endpoint = match &key {
            Some(_) => net::on_tls(&endpoint).map_err(|e| BridgeError::Usage(format!("{flag}: {e}")))?,
            None if endpoint.starts_with("tls/") => {
                return Err(BridgeError::Key(format!("{flag} {endpoint}: TLS needs the bridge key: give --key FILE")));
            }
            None if self.insecure || net::is_loopback(&endpoint) => endpoint,
            None => return Err(BridgeError::Key(no_key_refusal(side, &endpoint, &self.process.run_id.to_string()))),
        };
        let insecure = key.is_none() && !net::is_loopback(&endpoint);
        Ok(Plan { side, endpoint, key, insecure })
    }

    /// The side and the Zenoh endpoint, checked.
    fn side(&self) -> Result<(Side, String), BridgeError> {
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

/// What a bridge will do, its flags checked.
#[derive(Debug)]
pub struct Plan {
    /// Which host it serves.
    pub side: Side,
    /// The Zenoh locator (`tls/...` with a key).
    pub endpoint: String,
    /// The bridge key, if given.
    pub key: Option<BridgeKey>,
    /// No key, off the loopback, because `--insecure` said so: said when the bridge starts.
    pub insecure: bool,
}

impl Plan {
    /// How the link is secured, for the line a bridge prints when it starts.
    pub fn security(&self) -> String {
        match &self.key {
            Some(key) => format!("TLS with bridge key {}", key.fingerprint()),
            None if self.insecure => "NO bridge key (--insecure): anyone who reaches the port can join the run, read \
                                      its samples and command the plant"
                .to_string(),
            None => "no bridge key, on the loopback: only this host's processes reach it".to_string(),
        }
    }
}

/// Why a bridge without a key may not use an address off the loopback, and what to do.
fn no_key_refusal(side: Side, endpoint: &str, run: &str) -> String {
    let risk = match side {
        Side::Plant => format!(
            "any peer that reaches {endpoint} could join run `{run}` as its controller, read its samples and command \
             the plant"
        ),
        Side::Controller => format!(
            "the link to {endpoint} would be open: anyone on the way could read the samples and pose as the plant"
        ),
    };
    format!(
        "refused to {} {endpoint} without a bridge key: {risk}. Make a key with `silrig-bridge keygen lab.key`, copy \
         it to the other host (scp -p lab.key ...), and give it to both bridges (silrig-bridge --key lab.key, \
         silrig run --bridge-key lab.key); or, on a network you trust, say --insecure (silrig run \
         --bridge-insecure)",
        if side == Side::Plant { "listen on" } else { "connect to" }
    )
}
