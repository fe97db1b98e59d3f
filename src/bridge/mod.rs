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

pub mod frame;
pub mod net;
pub mod peer;

use frame::{CommandTrailer, Hello, RunInfo, Side};
use net::{Arrival, Inbox, Keys};
use peer::{PeerChange, PeerWatch};
use silrig_flight::role::Role;
use silrig_rig::events::EventLog;
use silrig_rig::report::{ProcessReport, Recorder, ReportMeta};
use silrig_rig::{ProcessArgs, RigMode, SCENARIO_ENV, signals};
use silrig_wire::clock::monotonic_ns;
use silrig_wire::topology::CONSUMER_BUFFER;
use silrig_wire::topology::LOGGER_BUFFER;
use silrig_wire::topology::Stream;
use silrig_wire::wire::{CommandSample, ControllerInfo, PlantSample, WIRE_LAYOUT_VERSION, WireSample};
use silrig_wire::{ipc, ipc::IpcError, ipc::StreamPublisher, ipc::StreamSubscriber};
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Duration;
use zenoh::Wait;
use zenoh::qos::{CongestionControl, Priority};

/// How often each bridge says hello.
pub const HELLO_PERIOD: Duration = Duration::from_millis(100);
/// A controller-side bridge the plant side keeps refusing for this long (it serves another, alive one) gives up.
pub const REFUSED_AFTER: Duration = Duration::from_millis(1500);
/// How long the controller side waits for the run's scenario once the plant side answers.
pub const RUN_INFO_TIMEOUT: Duration = Duration::from_secs(5);
/// The controller side ends this long after the plant's last sample (the controller has ended by then).
pub const FINISHED_GRACE: Duration = Duration::from_millis(500);
/// Plant-sample send stamps kept for the network leg (ticks a command may lag and still be timed).
const STAMPS: usize = 64;

const NETWORK_RTT: usize = 0;
const CONTROLLER_HOST_RESIDENCE: usize = 0;

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
    /// The run: its id, and on the plant side its scenario, mode and tuning (the controller side takes those from
    /// the plant side and writes them to <out>/scenario.toml and <out>/controller.env for its controller).
    #[command(flatten)]
    pub process: ProcessArgs,
}

/// Failures of a bridge, each phrased for the person running it.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// A flag out of range or malformed.
    #[error("{0}")]
    Usage(String),
    /// Zenoh refused to start or to declare something.
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// The iceoryx2 side.
    #[error(transparent)]
    Ipc(#[from] IpcError),
    /// Nobody answered at the endpoint.
    #[error(
        "no plant-side bridge answered at {endpoint} within {waited_s} s: is `silrig run --bridge-listen` running \
         on that host, is the address right, and is the port open in its firewall?"
    )]
    Unreachable {
        /// Where we connected.
        endpoint: String,
        /// How long we waited.
        waited_s: f64,
    },
    /// The bridge at the endpoint serves another run.
    #[error("the plant-side bridge at {endpoint} serves run `{theirs}`, not `{ours}`: use --run-id {theirs}")]
    OtherRun {
        /// Where we connected.
        endpoint: String,
        /// Its run.
        theirs: String,
        /// Ours.
        ours: String,
    },
    /// The other bridge speaks another layout version.
    #[error(
        "the plant-side bridge at {endpoint} speaks wire layout version {theirs}, this build speaks {ours}: build \
         silrig on both hosts from the same commit"
    )]
    OtherLayout {
        /// Where we connected.
        endpoint: String,
        /// Its version.
        theirs: u32,
        /// Ours.
        ours: u32,
    },
    /// The plant side serves another controller-side bridge of this run.
    #[error(
        "run `{run}` already has a controller-side bridge (epoch {serving:x}) that the plant side serves; stop it \
         first: one controller per run"
    )]
    Refused {
        /// The run.
        run: String,
        /// The epoch of the one served.
        serving: u64,
    },
    /// A file could not be written or read.
    #[error("{0}")]
    Io(String),
}

fn zenoh_err(what: &str) -> impl Fn(zenoh::Error) -> BridgeError + '_ {
    move |e| BridgeError::Zenoh(format!("{what}: {e}"))
}

impl BridgeOptions {
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

/// Run a bridge until SIGTERM (plant side) or the end of the flight (controller side), and write its report
/// (`<out>/bridge.report.json`).
pub fn run_bridge(opts: &BridgeOptions) -> anyhow::Result<ProcessReport> {
    signals::install_termination_flag();
    let (side, endpoint) = opts.side()?;
    let args = &opts.process;
    if args.mode == RigMode::Realtime {
        // Before Zenoh starts its threads, so they inherit it: the network leg is on the loop's critical path.
        let status = silrig_wire::clock::try_realtime(Role::Controller.fifo_priority().unwrap_or(1));
        if let Some(w) = status.warning {
            eprintln!("silrig-bridge: warning: {w}");
        }
    }
    let scheduling = silrig_wire::clock::current_policy().to_string();
    let (mut rec, scenario, ended) = match side {
        Side::Plant => PlantSide::start(opts, &endpoint)?.run()?,
        Side::Controller => ControllerSide::start(opts, &endpoint)?.run()?,
    };
    rec.declare(&["peer_losses"]);
    let meta = ReportMeta::new(args, &scenario, scheduling, ended);
    Ok(rec.finish(meta, &args.out)?)
}

/// The Zenoh ends every bridge has: the session, the inbox its subscribers fill, and the hello.
struct Link {
    endpoint: String,
    run: String,
    keys: Keys,
    session: zenoh::Session,
    inbox: Arc<Inbox>,
    subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
    hello: zenoh::pubsub::Publisher<'static>,
    epoch: u64,
    next_hello_ns: u64,
    events: EventLog,
    /// Messages already said once (a rival, another run), so a hello every 100 ms does not repeat them.
    said: BTreeSet<String>,
}

impl Link {
    fn open(side: Side, endpoint: &str, args: &ProcessArgs) -> Result<Self, BridgeError> {
        std::fs::create_dir_all(&args.out).map_err(|e| BridgeError::Io(format!("{}: {e}", args.out.display())))?;
        let session = net::open_session(side, endpoint)?;
        let run = args.run_id.to_string();
        let keys = Keys::new(&run);
        let hello = session
            .declare_publisher(keys.hello(side))
            .congestion_control(CongestionControl::Drop)
            .wait()
            .map_err(zenoh_err("hello publisher"))?;
        Ok(Self {
            endpoint: endpoint.into(),
            run,
            keys,
            session,
            inbox: Inbox::new().map_err(|e| BridgeError::Io(format!("eventfd: {e}")))?,
            subscribers: Vec::new(),
            hello,
            epoch: ipc::new_epoch(),
            next_hello_ns: 0,
            events: EventLog::new(&args.out, "bridge"),
            said: BTreeSet::new(),
        })
    }

    /// Deliver what arrives on `key` to the inbox.
    fn subscribe(&mut self, key: String, what: &'static str) -> Result<(), BridgeError> {
        let inbox = self.inbox.clone();
        let finished = what == "finished";
        let hello = what == "hello";
        let subscriber = self
            .session
            .declare_subscriber(key)
            .callback(move |sample| {
                let bytes = sample.payload().to_bytes().into_owned();
                inbox.push(if finished {
                    Arrival::Finished
                } else if hello {
                    Arrival::Hello { key: sample.key_expr().to_string(), bytes }
                } else {
                    let attachment = sample.attachment().map(|a| a.to_bytes().into_owned());
                    Arrival::Sample { what, bytes, attachment }
                });
            })
            .wait()
            .map_err(zenoh_err("subscriber"))?;
        self.subscribers.push(subscriber);
        Ok(())
    }

    /// A publisher for a stream: express (no batching) at real-time priority; a full queue drops rather than
    /// blocks, because a late sample is worth nothing to the loop.
    fn stream_publisher(
        &self,
        what: &str,
        congestion: CongestionControl,
    ) -> Result<zenoh::pubsub::Publisher<'static>, BridgeError> {
        self.session
            .declare_publisher(self.keys.of(what))
            .congestion_control(congestion)
            .priority(Priority::RealTime)
            .express(true)
            .wait()
            .map_err(zenoh_err("publisher"))
    }

    /// Say hello when it is due; returns the time to wait until at most.
    fn say_hello(&mut self, hello: impl FnOnce(u64) -> Hello) -> u64 {
        let now = monotonic_ns();
        if now >= self.next_hello_ns {
            let _ = self.hello.put(hello(self.epoch).to_bytes()).wait();
            self.next_hello_ns = now + HELLO_PERIOD.as_nanos() as u64;
        }
        self.next_hello_ns
    }

    /// Say `text` on stderr and in the events, the first time only when `once`.
    fn say(&mut self, kind: &str, text: String, once: bool) {
        if once && !self.said.insert(text.clone()) {
            return;
        }
        eprintln!("silrig-bridge: {text}");
        self.events.emit(None, kind, text);
    }
}

/// A hello from the network, with what is wrong with it for this run (another run, another layout).
fn read_hello(bytes: &[u8], run: &str) -> Result<Hello, String> {
    let h = Hello::from_bytes(bytes)?;
    if h.run_id != run {
        return Err(format!(
            "a {} bridge of run `{}` is connected; this one serves run `{run}`",
            h.side.label(),
            h.run_id
        ));
    }
    if h.layout_version != WIRE_LAYOUT_VERSION {
        return Err(format!(
            "the {} bridge speaks wire layout version {}, this build speaks {WIRE_LAYOUT_VERSION}: build silrig on \
             both hosts from the same commit",
            h.side.label(),
            h.layout_version
        ));
    }
    Ok(h)
}

/// The listener's descriptor, for polling beside the inbox.
fn listener_fd<T: WireSample>(s: &StreamSubscriber<T>) -> i32 {
    use iceoryx2::prelude::FileDescriptorBased;
    // SAFETY: only polled, never closed; the listener owns it and outlives every poll.
    unsafe { s.listener().file_descriptor().native_handle() }
}

/// Send stamps of recent ticks, by tick.
#[derive(Debug)]
struct TickStamps([(u64, u64); STAMPS]);

impl TickStamps {
    fn new() -> Self {
        Self([(u64::MAX, 0); STAMPS])
    }

    fn put(&mut self, tick: u64, t_ns: u64) {
        self.0[(tick % STAMPS as u64) as usize] = (tick, t_ns);
    }

    fn get(&self, tick: u64) -> Option<u64> {
        let (t, at) = self.0[(tick % STAMPS as u64) as usize];
        (t == tick).then_some(at)
    }
}

/// The plant's host: plant samples out, commands and controller info in.
struct PlantSide {
    link: Link,
    scenario: String,
    peer: PeerWatch,
    samples: StreamSubscriber<PlantSample>,
    command_stream: ipc::StreamService<CommandSample>,
    info_stream: ipc::StreamService<ControllerInfo>,
    /// Created once the controller side reports a controller: until then the plant waits for its peers.
    commands: Option<(StreamPublisher<CommandSample>, StreamPublisher<ControllerInfo>)>,
    plant_out: zenoh::pubsub::Publisher<'static>,
    finished_out: zenoh::pubsub::Publisher<'static>,
    _queryable: zenoh::query::Queryable<()>,
    sent: TickStamps,
    rec: Recorder,
    _plant_stream: ipc::StreamService<PlantSample>,
    // Dropped last: the services and ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl PlantSide {
    fn start(opts: &BridgeOptions, endpoint: &str) -> anyhow::Result<Self> {
        let args = &opts.process;
        let scenario = args.scenario()?;
        let scenario_toml = match &args.config {
            Some(path) => std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?,
            None => scenario.to_toml(),
        };
        let node = ipc::create_node(&args.run_id, "bridge")?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let info_stream = ipc::open_stream::<ControllerInfo>(&node, Stream::ControllerInfo)?;
        // Every sample goes on, as to the logger.
        let samples = plant_stream.subscriber(LOGGER_BUFFER)?;
        let mut link = Link::open(Side::Plant, endpoint, args)?;
        link.subscribe(link.keys.of("command"), "command")?;
        link.subscribe(link.keys.of("controller-info"), "controller-info")?;
        link.subscribe(Keys::any_hello(Side::Controller), "hello")?;
        let info = RunInfo { scenario_toml, env: args.to_env() };
        let reply = serde_json::to_vec(&info)?;
        let queryable = link
            .session
            .declare_queryable(link.keys.of("run"))
            .callback(move |query| {
                let _ = query.reply(query.key_expr().clone(), reply.clone()).wait();
            })
            .wait()
            .map_err(zenoh_err("run info queryable"))?;
        let plant_out = link.stream_publisher("plant", CongestionControl::Drop)?;
        // The end of the run must arrive.
        let finished_out = link.stream_publisher("finished", CongestionControl::Block)?;
        let rec = Recorder::new(
            "bridge",
            &[(
                "network_rtt",
                "plant-side bridge sends a plant sample to the command answering it back there, minus the time on the \
                 controller's host: both network legs and both Zenoh stacks",
            )],
        );
        eprintln!(
            "silrig-bridge: run {} listening on {endpoint}; on the controller's host run\n  silrig-bridge --connect \
             <this host>:{} --run-id {} --out <folder>",
            link.run,
            endpoint.rsplit(':').next().unwrap_or("7447"),
            link.run
        );
        Ok(Self {
            scenario: scenario.name,
            peer: PeerWatch::new((opts.peer_timeout_ms * 1e6) as u64),
            samples,
            command_stream,
            info_stream,
            commands: None,
            plant_out,
            finished_out,
            _queryable: queryable,
            sent: TickStamps::new(),
            rec,
            link,
            _plant_stream: plant_stream,
            _node: node,
        })
    }

    fn run(mut self) -> anyhow::Result<(Recorder, String, String)> {
        let mut finished_seen = 0;
        while !signals::termination_requested() {
            let hello_due = self.link.next_hello_ns;
            net::wait_readable(&[listener_fd(&self.samples), self.link.inbox.fd()], hello_due);
            self.forward_samples()?;
            let finished = self.samples.stats().finished_notices;
            if finished > finished_seen {
                finished_seen = finished;
                let _ = self.finished_out.put(Vec::<u8>::new()).wait();
            }
            for arrival in self.link.inbox.take() {
                self.on_arrival(arrival)?;
            }
            let serving = self.peer.alive().map(|h| h.epoch);
            let run_id = self.link.run.clone();
            self.link.say_hello(|epoch| Hello {
                side: Side::Plant,
                run_id,
                layout_version: WIRE_LAYOUT_VERSION,
                epoch,
                serving,
                controller_connected: false,
            });
            if let Some(PeerChange::Lost { epoch, silent_ns }) = self.peer.check(monotonic_ns()) {
                self.rec.count("peer_losses", 1);
                let text = format!(
                    "lost the controller-side bridge (epoch {epoch:x}): no hello for {} ms; no commands reach the \
                     plant until it is back",
                    silent_ns / 1_000_000
                );
                self.link.say("bridge-peer-lost", text, false);
            }
            self.open_command_ports()?;
        }
        Ok((self.rec, self.scenario, "terminated by signal".into()))
    }

    fn forward_samples(&mut self) -> anyhow::Result<()> {
        let (out, sent, rec) = (&self.plant_out, &mut self.sent, &mut self.rec);
        self.samples.drain(|r| {
            if r.invalid.is_some() {
                return;
            }
            let t_ns = monotonic_ns();
            match out.put(frame::to_bytes(&r.sample)).wait() {
                Ok(()) => {
                    sent.put(r.sample.header.tick, t_ns);
                    rec.count("plant_samples_out", 1);
                }
                Err(_) => rec.count("plant_samples_not_sent", 1),
            }
        })?;
        Ok(())
    }

    /// The plant sees a command publisher only once a controller is there to answer: then it starts flying.
    fn open_command_ports(&mut self) -> anyhow::Result<()> {
        if self.commands.is_none() && self.peer.alive().is_some_and(|h| h.controller_connected) {
            self.commands = Some((self.command_stream.publisher()?, self.info_stream.publisher()?));
            self.link.events.emit(None, "bridge-controller-connected", "a controller is connected on the other host");
        }
        Ok(())
    }

    fn on_arrival(&mut self, arrival: Arrival) -> anyhow::Result<()> {
        let now = monotonic_ns();
        match arrival {
            Arrival::Hello { bytes, .. } => match read_hello(&bytes, &self.link.run) {
                Err(problem) => self.link.say("bridge-peer-refused", format!("{problem}: ignored"), true),
                Ok(h) => match self.peer.heard(h, now) {
                    Some(PeerChange::Joined { epoch, replaced }) => {
                        let how = replaced.map_or(String::new(), |old| format!(" (replacing epoch {old:x})"));
                        let text = format!("controller-side bridge (epoch {epoch:x}) connected from the network{how}");
                        self.link.say("bridge-peer-joined", text, false);
                    }
                    Some(PeerChange::Rival { epoch }) => {
                        let serving = self.peer.alive().map_or(0, |h| h.epoch);
                        let text = format!(
                            "refused a second controller-side bridge for run {} (epoch {epoch:x}): serving epoch \
                             {serving:x}",
                            self.link.run
                        );
                        self.link.say("bridge-peer-refused", text, true);
                    }
                    _ => {}
                },
            },
            Arrival::Sample { what, bytes, attachment } => {
                let trailer = attachment.as_deref().and_then(CommandTrailer::from_bytes);
                let serving = self.peer.alive().map(|h| h.epoch);
                if serving.is_none() || trailer.map(|t| t.bridge_epoch) != serving {
                    self.rec.count("samples_from_unserved_bridges", 1);
                    return Ok(());
                }
                let Some((commands, infos)) = self.commands.as_mut() else { return Ok(()) };
                let refused = match what {
                    "command" => match frame::from_bytes::<CommandSample>(&bytes) {
                        Ok(c) => {
                            commands.forward(&c)?;
                            self.rec.count("commands_in", 1);
                            let residence = trailer.map_or(0, |t| t.residence_ns);
                            if let Some(sent_ns) = self.sent.get(c.answers_tick).filter(|_| residence > 0) {
                                let rtt_ns = now.saturating_sub(sent_ns).saturating_sub(residence);
                                self.rec.record(NETWORK_RTT, rtt_ns as i64);
                            }
                            None
                        }
                        Err(e) => Some(e),
                    },
                    _ => match frame::from_bytes::<ControllerInfo>(&bytes) {
                        Ok(i) => {
                            infos.forward(&i)?;
                            None
                        }
                        Err(e) => Some(e),
                    },
                };
                if let Some(e) = refused {
                    self.rec.count("samples_refused", 1);
                    self.link.say(
                        "bridge-sample-refused",
                        format!("refused a {what} sample from the network: {e}"),
                        true,
                    );
                }
            }
            Arrival::Finished => {}
        }
        Ok(())
    }
}

/// The controller's host: plant samples in, commands and controller info out.
struct ControllerSide {
    link: Link,
    scenario: String,
    peer: PeerWatch,
    plant: StreamPublisher<PlantSample>,
    commands: StreamSubscriber<CommandSample>,
    infos: StreamSubscriber<ControllerInfo>,
    plant_stream: ipc::StreamService<PlantSample>,
    command_stream: ipc::StreamService<CommandSample>,
    command_out: zenoh::pubsub::Publisher<'static>,
    info_out: zenoh::pubsub::Publisher<'static>,
    published: TickStamps,
    refused_since_ns: Option<u64>,
    finished_at_ns: Option<u64>,
    rec: Recorder,
    _info_stream: ipc::StreamService<ControllerInfo>,
    // Dropped last: the services and ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl ControllerSide {
    fn start(opts: &BridgeOptions, endpoint: &str) -> anyhow::Result<Self> {
        let args = &opts.process;
        let mut link = Link::open(Side::Controller, endpoint, args)?;
        link.subscribe(link.keys.of("plant"), "plant")?;
        link.subscribe(link.keys.of("finished"), "finished")?;
        link.subscribe(Keys::any_hello(Side::Plant), "hello")?;
        let mut peer = PeerWatch::new((opts.peer_timeout_ms * 1e6) as u64);
        Self::wait_for_plant_side(&mut link, &mut peer, opts.connect_timeout_s)?;
        let scenario = Self::fetch_run(&link, args)?;
        let node = ipc::create_node(&args.run_id, "bridge")?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let info_stream = ipc::open_stream::<ControllerInfo>(&node, Stream::ControllerInfo)?;
        let plant = plant_stream.publisher()?;
        let commands = command_stream.subscriber(CONSUMER_BUFFER)?;
        let infos = info_stream.subscriber(CONSUMER_BUFFER)?;
        let command_out = link.stream_publisher("command", CongestionControl::Drop)?;
        // Sent once per controller epoch: it must arrive.
        let info_out = link.stream_publisher("controller-info", CongestionControl::Block)?;
        let rec = Recorder::new(
            "bridge",
            &[(
                "controller_host_residence",
                "controller-side bridge publishes a plant sample to the command answering it received there",
            )],
        );
        Ok(Self {
            link,
            scenario,
            peer,
            plant,
            commands,
            infos,
            plant_stream,
            command_stream,
            command_out,
            info_out,
            published: TickStamps::new(),
            refused_since_ns: None,
            finished_at_ns: None,
            rec,
            _info_stream: info_stream,
            _node: node,
        })
    }

    /// Until the plant side of this run says hello: another run or layout there is an error at once; silence
    /// until the timeout is an unreachable endpoint.
    fn wait_for_plant_side(link: &mut Link, peer: &mut PeerWatch, timeout_s: f64) -> Result<(), BridgeError> {
        let deadline = monotonic_ns() + (timeout_s * 1e9) as u64;
        loop {
            for arrival in link.inbox.take() {
                let Arrival::Hello { bytes, .. } = arrival else { continue };
                let Ok(h) = Hello::from_bytes(&bytes) else { continue };
                if h.run_id != link.run {
                    let (theirs, ours) = (h.run_id, link.run.clone());
                    return Err(BridgeError::OtherRun { endpoint: link.endpoint.clone(), theirs, ours });
                }
                if h.layout_version != WIRE_LAYOUT_VERSION {
                    let (theirs, ours) = (h.layout_version, WIRE_LAYOUT_VERSION);
                    return Err(BridgeError::OtherLayout { endpoint: link.endpoint.clone(), theirs, ours });
                }
                peer.heard(h, monotonic_ns());
                return Ok(());
            }
            if signals::termination_requested() || monotonic_ns() >= deadline {
                return Err(BridgeError::Unreachable { endpoint: link.endpoint.clone(), waited_s: timeout_s });
            }
            net::wait_readable(&[link.inbox.fd()], deadline);
        }
    }

    /// The run's scenario and arguments from the plant side, written to `<out>/scenario.toml` and
    /// `<out>/controller.env` (with this host's paths) for the controller that runs here.
    fn fetch_run(link: &Link, args: &ProcessArgs) -> anyhow::Result<String> {
        let replies = link
            .session
            .get(link.keys.of("run"))
            .timeout(RUN_INFO_TIMEOUT)
            .wait()
            .map_err(zenoh_err("asking for the run's scenario"))?;
        let reply = replies.recv().map_err(|_| {
            anyhow::anyhow!("the plant-side bridge did not send the run's scenario within {RUN_INFO_TIMEOUT:?}")
        })?;
        let sample = reply.result().map_err(|e| anyhow::anyhow!("the run's scenario: {:?}", e.payload().to_bytes()))?;
        let info: RunInfo = serde_json::from_slice(&sample.payload().to_bytes())?;
        let scenario_path = args.out.join("scenario.toml");
        silrig_flight::files::write_atomically(&scenario_path, &info.scenario_toml)?;
        let mut env: Vec<(String, String)> = info
            .env
            .into_iter()
            .filter(|(k, _)| k != SCENARIO_ENV && k != "SILRIG_OUT" && k != "SILRIG_RESUME")
            .collect();
        env.push((SCENARIO_ENV.into(), scenario_path.display().to_string()));
        env.push(("SILRIG_OUT".into(), args.out.display().to_string()));
        let local =
            ProcessArgs::from_env(env).map_err(|e| anyhow::anyhow!("the run's arguments from the plant side: {e}"))?;
        let lines: String =
            local.to_env().iter().map(|(k, v)| format!("export {k}='{}'\n", v.replace('\'', "'\\''"))).collect();
        let env_path = args.out.join("controller.env");
        silrig_flight::files::write_atomically(&env_path, &lines)?;
        let scenario = local.scenario()?;
        eprintln!(
            "silrig-bridge: connected to run {} at {}; start the controller on this host, e.g.\n  silrig-controller \
             {}\n  or: . {} && python3 examples/python/pid_attitude.py",
            link.run,
            link.endpoint,
            local.to_argv().join(" "),
            env_path.display()
        );
        Ok(scenario.name)
    }

    fn run(mut self) -> anyhow::Result<(Recorder, String, String)> {
        let ended = loop {
            if signals::termination_requested() {
                break "terminated by signal".to_string();
            }
            if self.finished_at_ns.is_some_and(|t| monotonic_ns() >= t + FINISHED_GRACE.as_nanos() as u64) {
                break "completed".to_string();
            }
            let fds = [listener_fd(&self.commands), listener_fd(&self.infos), self.link.inbox.fd()];
            net::wait_readable(&fds, self.link.next_hello_ns);
            for arrival in self.link.inbox.take() {
                self.on_arrival(arrival)?;
            }
            self.forward_commands()?;
            let connected =
                self.plant_stream.number_of_subscribers() >= 1 && self.command_stream.number_of_publishers() >= 1;
            let run_id = self.link.run.clone();
            self.link.say_hello(|epoch| Hello {
                side: Side::Controller,
                run_id,
                layout_version: WIRE_LAYOUT_VERSION,
                epoch,
                serving: None,
                controller_connected: connected,
            });
            if let Some(PeerChange::Lost { silent_ns, .. }) = self.peer.check(monotonic_ns()) {
                self.rec.count("peer_losses", 1);
                let text = format!(
                    "lost the plant-side bridge at {}: no hello for {} ms; the controller here sees its plant go \
                     stale; reconnecting",
                    self.link.endpoint,
                    silent_ns / 1_000_000
                );
                self.link.say("bridge-peer-lost", text, false);
            }
        };
        Ok((self.rec, self.scenario, ended))
    }

    fn on_arrival(&mut self, arrival: Arrival) -> anyhow::Result<()> {
        let now = monotonic_ns();
        match arrival {
            Arrival::Hello { bytes, .. } => {
                let h = match read_hello(&bytes, &self.link.run) {
                    Ok(h) => h,
                    Err(problem) => {
                        self.link.say("bridge-peer-refused", format!("{problem}: ignored"), true);
                        return Ok(());
                    }
                };
                match h.serving {
                    Some(serving) if serving != self.link.epoch => {
                        let since = *self.refused_since_ns.get_or_insert(now);
                        if now - since >= REFUSED_AFTER.as_nanos() as u64 {
                            Err(BridgeError::Refused { run: self.link.run.clone(), serving })?;
                        }
                    }
                    _ => self.refused_since_ns = None,
                }
                match self.peer.heard(h, now) {
                    Some(PeerChange::Joined { epoch, replaced }) => {
                        let how =
                            replaced.map_or(" again".to_string(), |old| format!(" (restarted: epoch {old:x} before)"));
                        let text = format!("the plant-side bridge (epoch {epoch:x}) answers{how}");
                        self.link.say("bridge-peer-joined", text, false);
                    }
                    Some(PeerChange::Rival { epoch }) => {
                        let text =
                            format!("a second plant-side bridge (epoch {epoch:x}) for run {}: ignored", self.link.run);
                        self.link.say("bridge-peer-refused", text, true);
                    }
                    _ => {}
                }
            }
            Arrival::Sample { what, bytes, .. } => match frame::from_bytes::<PlantSample>(&bytes) {
                Ok(s) if self.peer.alive().is_some() => {
                    self.plant.forward(&s)?;
                    self.published.put(s.header.tick, monotonic_ns());
                    self.rec.count("plant_samples_in", 1);
                }
                Ok(_) => self.rec.count("samples_from_unserved_bridges", 1),
                Err(e) => {
                    self.rec.count("samples_refused", 1);
                    self.link.say(
                        "bridge-sample-refused",
                        format!("refused a {what} sample from the network: {e}"),
                        true,
                    );
                }
            },
            Arrival::Finished => {
                let _ = self.plant.announce_finished();
                self.finished_at_ns.get_or_insert(now);
            }
        }
        Ok(())
    }

    fn forward_commands(&mut self) -> anyhow::Result<()> {
        let (out, published, rec, epoch) = (&self.command_out, &self.published, &mut self.rec, self.link.epoch);
        self.commands.drain(|r| {
            if r.invalid.is_some() {
                return;
            }
            let residence_ns = published.get(r.sample.answers_tick).map_or(0, |t| r.t_recv_ns.saturating_sub(t));
            if residence_ns > 0 {
                rec.record(CONTROLLER_HOST_RESIDENCE, residence_ns as i64);
            }
            let trailer = CommandTrailer { bridge_epoch: epoch, residence_ns };
            match out.put(frame::to_bytes(&r.sample)).attachment(trailer.to_bytes().to_vec()).wait() {
                Ok(()) => rec.count("commands_out", 1),
                Err(_) => rec.count("commands_not_sent", 1),
            }
        })?;
        let (out, rec) = (&self.info_out, &mut self.rec);
        self.infos.drain(|r| {
            if r.invalid.is_none() {
                let trailer = CommandTrailer { bridge_epoch: epoch, residence_ns: 0 };
                if out.put(frame::to_bytes(&r.sample)).attachment(trailer.to_bytes().to_vec()).wait().is_err() {
                    rec.count("infos_not_sent", 1);
                }
            }
        })?;
        Ok(())
    }
}
