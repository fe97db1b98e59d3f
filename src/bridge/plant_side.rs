//! The plant's host ([`PlantSide`], started by `silrig run --bridge-listen`): the run's plant samples out to the
//! network, commands and controller info from the one controller-side bridge it serves back into the plant's
//! iceoryx2 namespace, the run's scenario and arguments served to whoever asks, and the network leg timed
//! (`bridge.network_rtt`).

use super::error::zenoh_err;
use super::frame::{self, CommandTrailer, Hello, RunInfo, Side};
use super::link::{Link, listener_fd, read_hello};
use super::loop_watch::{LoopWatch, Step};
use super::net::{self, Arrival, Keys};
use super::options::{BridgeOptions, CONTROLLER_REPORT, Plan, REPORT_ABSENT, REPORT_RECEIVED};
use super::peer::{PeerChange, PeerWatch};
use super::stamps::TickStamps;
use silrig_rig::report::Recorder;
use silrig_rig::signals;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::topology::Stream;
use silrig_wire::topology::{CONSUMER_BUFFER, LOGGER_BUFFER};
use silrig_wire::wire::{CommandSample, ControllerInfo, PlantInfo, PlantSample};
use silrig_wire::{ipc, ipc::StreamPublisher, ipc::StreamSubscriber};
use zenoh::Wait;
use zenoh::qos::CongestionControl;

const NETWORK_RTT: usize = 0;

/// The plant's host: plant samples out, commands and controller info in.
pub(super) struct PlantSide {
    link: Link,
    scenario: String,
    peer: PeerWatch,
    samples: StreamSubscriber<PlantSample>,
    plant_infos: StreamSubscriber<PlantInfo>,
    /// The plant's announcement, sent on with every hello: a controller-side bridge that joins late or restarts
    /// gets it within one hello period.
    plant_info: Option<PlantInfo>,
    plant_info_out: zenoh::pubsub::Publisher<'static>,
    command_stream: ipc::StreamService<CommandSample>,
    info_stream: ipc::StreamService<ControllerInfo>,
    /// Created once the controller side reports a controller: until then the plant waits for its peers.
    commands: Option<(StreamPublisher<CommandSample>, StreamPublisher<ControllerInfo>)>,
    plant_out: zenoh::pubsub::Publisher<'static>,
    finished_out: zenoh::pubsub::Publisher<'static>,
    _queryable: zenoh::query::Queryable<()>,
    sent: TickStamps,
    /// The run's folder, where the controller's report from the other host goes.
    out: std::path::PathBuf,
    rec: Recorder,
    _plant_stream: ipc::StreamService<PlantSample>,
    // Dropped last: the services and ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl PlantSide {
    pub(super) fn start(opts: &BridgeOptions, plan: &Plan) -> anyhow::Result<Self> {
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
        let plant_infos = ipc::open_stream::<PlantInfo>(&node, Stream::PlantInfo)?.subscriber(CONSUMER_BUFFER)?;
        let mut link = Link::open(plan, args)?;
        link.subscribe(link.keys.of("command"), "command")?;
        link.subscribe(link.keys.of("controller-info"), "controller-info")?;
        link.subscribe(link.keys.of(CONTROLLER_REPORT), CONTROLLER_REPORT)?;
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
        let plant_info_out = link.stream_publisher("plant-info", CongestionControl::Block)?;
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
        let key_flag = if plan.key.is_some() { " --key <the same key file>" } else { "" };
        eprintln!(
            "silrig-bridge: run {} listening on {} ({}); on the controller's host run\n  silrig-bridge --connect \
             <this host>:{} --run-id {}{key_flag} --out <folder>",
            link.run,
            plan.endpoint,
            plan.security(),
            plan.endpoint.rsplit(':').next().unwrap_or("7447"),
            link.run
        );
        Ok(Self {
            scenario: scenario.name,
            peer: PeerWatch::new((opts.peer_timeout_ms * 1e6) as u64),
            samples,
            plant_infos,
            plant_info: None,
            plant_info_out,
            command_stream,
            info_stream,
            commands: None,
            plant_out,
            finished_out,
            _queryable: queryable,
            sent: TickStamps::new(),
            out: args.out.clone(),
            rec,
            link,
            _plant_stream: plant_stream,
            _node: node,
        })
    }

    pub(super) fn run(mut self) -> anyhow::Result<(Recorder, String, String)> {
        let mut finished_seen = 0;
        let watch = LoopWatch::start(self.link.events.clone());
        while !signals::termination_requested() {
            let hello_due = self.link.next_hello_ns;
            watch.at(Step::Waiting);
            net::wait_readable(&[listener_fd(&self.samples), self.link.inbox.fd()], hello_due);
            watch.at(Step::Sending);
            self.forward_samples()?;
            let finished = self.samples.stats().finished_notices;
            if finished > finished_seen {
                finished_seen = finished;
                let _ = self.finished_out.put(Vec::<u8>::new()).wait();
            }
            watch.at(Step::Arrivals);
            for arrival in self.link.inbox.take() {
                self.on_arrival(arrival)?;
            }
            watch.at(Step::Hello);
            let serving = self.peer.alive().map(|h| h.epoch);
            let (run_id, layout_version) = (self.link.run.clone(), self.link.layout_version);
            if monotonic_ns() >= self.link.next_hello_ns {
                self.forward_plant_info()?;
            }
            self.link.say_hello(|epoch| Hello {
                side: Side::Plant,
                run_id,
                layout_version,
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
        if let Some(n) = self.link.test_losses() {
            self.rec.count("test_losses", n);
        }
        Ok((self.rec, self.scenario, "terminated by signal".into()))
    }

    /// The plant's newest announcement, out again (it is small, and a late peer needs it before any sample).
    fn forward_plant_info(&mut self) -> anyhow::Result<()> {
        let latest = &mut self.plant_info;
        self.plant_infos.drain(|r| {
            if r.invalid.is_none() {
                *latest = Some(r.sample);
            }
        })?;
        if let Some(info) = &self.plant_info
            && self.plant_info_out.put(frame::to_bytes(info)).wait().is_err()
        {
            self.rec.count("plant_infos_not_sent", 1);
        }
        Ok(())
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
                    sent.put(r.sample.header.tick, r.sample.header.epoch, t_ns);
                    rec.count("plant_samples_out", 1);
                }
                Err(_) => rec.count("plant_samples_not_sent", 1),
            }
        })?;
        Ok(())
    }

    /// The controller's report from the other host, written beside the plant's as `controller.report.json` (the
    /// launcher waits for it before it writes the run's report), or word that there is none; confirmed either way.
    fn take_controller_report(&mut self, bytes: &[u8]) {
        let path = self.out.join("controller.report.json");
        let (kind, text) = if bytes.is_empty() {
            (REPORT_ABSENT, "the controller on the other host wrote no report".to_string())
        } else {
            let checked = std::str::from_utf8(bytes)
                .map_err(|e| e.to_string())
                .and_then(|t| serde_json::from_str::<serde_json::Value>(t).map(|_| t).map_err(|e| e.to_string()))
                .and_then(|t| silrig_flight::files::write_atomically(&path, t).map_err(|e| e.to_string()));
            match checked {
                Ok(()) => ("controller-report-received", format!("the controller's report, as {}", path.display())),
                Err(e) => (REPORT_ABSENT, format!("the controller's report from the other host is unusable: {e}")),
            }
        };
        self.link.say(kind, text, false);
        let _ = self
            .link
            .session
            .put(self.link.keys.of(REPORT_RECEIVED), Vec::<u8>::new())
            .congestion_control(CongestionControl::Block)
            .wait();
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
            Arrival::Hello { bytes, .. } => self.on_hello(&bytes, now),
            Arrival::Sample { what, bytes, attachment } => {
                let trailer = attachment.as_deref().and_then(CommandTrailer::from_bytes);
                let serving = self.peer.alive().map(|h| h.epoch);
                if serving.is_none() || trailer.map(|t| t.bridge_epoch) != serving {
                    self.rec.count("samples_from_unserved_bridges", 1);
                    return Ok(());
                }
                if what == CONTROLLER_REPORT {
                    self.take_controller_report(&bytes);
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
            Arrival::LinkRefused { text } => self.on_link_refused(&text),
        }
        Ok(())
    }

    /// A controller-side bridge's hello: who joined, or who was refused and why.
    fn on_hello(&mut self, bytes: &[u8], now: u64) {
        match read_hello(bytes, &self.link.run, self.link.layout_version) {
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
        }
    }

    /// A connection Zenoh's TLS refused (from its log): counted and said, with what the peer lacks.
    fn on_link_refused(&mut self, text: &str) {
        if let Some(r) = super::tls_watch::refusal(text) {
            self.rec.count("connections_refused", 1);
            let why = if r.certificate {
                "the peer does not hold this run's bridge key: if it is your controller-side bridge, give it \
                 the same key file"
            } else {
                "the peer did not speak TLS: a bridge without --key, or another program on this port"
            };
            let text = format!("refused a connection from the network (TLS: {}): {why}", r.detail);
            self.link.say("bridge-connection-refused", text, true);
        }
    }
}
