//! The controller's host ([`ControllerSide`], `silrig-bridge --connect`): waits for the plant side of this run,
//! fetches the run's scenario and arguments and writes them for the controller here, then plant samples in from the
//! network, commands and controller info out, each command with the time its tick spent on this host
//! (`bridge.controller_host_residence`), until the flight ends.

use super::error::{BridgeError, zenoh_err};
use super::frame::{self, CommandTrailer, Hello, RunInfo, Side};
use super::link::{Link, listener_fd, read_hello};
use super::loop_watch::{LoopWatch, Step};
use super::net::{self, Arrival, Keys};
use super::options::{
    BridgeOptions, CONTROLLER_REPORT, FINISHED_GRACE, Plan, REFUSED_AFTER, REPORT_RECEIVED, REPORT_WAIT,
    RUN_INFO_TIMEOUT,
};
use super::peer::{PeerChange, PeerWatch};
use super::stamps::TickStamps;
use silrig_rig::report::Recorder;
use silrig_rig::{ProcessArgs, SCENARIO_ENV, signals};
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::namespace::RunId;
use silrig_wire::topology::CONSUMER_BUFFER;
use silrig_wire::topology::Stream;
use silrig_wire::wire::{CommandSample, ControllerInfo, PlantInfo, PlantSample};
use silrig_wire::{ipc, ipc::StreamPublisher, ipc::StreamSubscriber};
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::qos::CongestionControl;

const CONTROLLER_HOST_RESIDENCE: usize = 0;

/// The controller's host: plant samples in, commands and controller info out.
pub(super) struct ControllerSide {
    link: Link,
    scenario: String,
    peer: PeerWatch,
    plant: StreamPublisher<PlantSample>,
    /// The plant's announcement as it last came from the network, passed on when it changes.
    plant_info: StreamPublisher<PlantInfo>,
    plant_info_in: Option<PlantInfo>,
    commands: StreamSubscriber<CommandSample>,
    infos: StreamSubscriber<ControllerInfo>,
    plant_stream: ipc::StreamService<PlantSample>,
    command_stream: ipc::StreamService<CommandSample>,
    command_out: zenoh::pubsub::Publisher<'static>,
    info_out: zenoh::pubsub::Publisher<'static>,
    published: TickStamps,
    /// This host's folder of the run, where the controller writes its report.
    out: std::path::PathBuf,
    /// The namespace of the run's half on this host: the id in its controller's report.
    local_run: RunId,
    refused_since_ns: Option<u64>,
    finished_at_ns: Option<u64>,
    rec: Recorder,
    _info_stream: ipc::StreamService<ControllerInfo>,
    // Dropped last: the services and ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl ControllerSide {
    pub(super) fn start(opts: &BridgeOptions, plan: &Plan) -> anyhow::Result<Self> {
        let args = &opts.process;
        let mut link = Link::open(plan, args)?;
        eprintln!("silrig-bridge: connecting to {} ({})", plan.endpoint, plan.security());
        link.subscribe(link.keys.of("plant"), "plant")?;
        link.subscribe(link.keys.of("plant-info"), "plant-info")?;
        link.subscribe(link.keys.of("finished"), "finished")?;
        link.subscribe(link.keys.of(REPORT_RECEIVED), REPORT_RECEIVED)?;
        link.subscribe(Keys::any_hello(Side::Plant), "hello")?;
        let mut peer = PeerWatch::new((opts.peer_timeout_ms * 1e6) as u64);
        Self::wait_for_plant_side(&mut link, &mut peer, opts.connect_timeout_s)?;
        let local_run = opts.local_run_id();
        let scenario = Self::fetch_run(&link, args, local_run)?;
        let node = ipc::create_node(local_run, "bridge")?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let info_stream = ipc::open_stream::<ControllerInfo>(&node, Stream::ControllerInfo)?;
        let plant = plant_stream.publisher()?;
        let plant_info = ipc::open_stream::<PlantInfo>(&node, Stream::PlantInfo)?.publisher()?;
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
            plant_info,
            plant_info_in: None,
            commands,
            infos,
            plant_stream,
            command_stream,
            command_out,
            info_out,
            published: TickStamps::new(),
            out: args.out.clone(),
            local_run: local_run.clone(),
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
                if let Arrival::LinkRefused { text } = &arrival {
                    link.wrong_key(text)?;
                }
                let Arrival::Hello { bytes, .. } = arrival else { continue };
                let Ok(h) = Hello::from_bytes(&bytes) else { continue };
                if h.run_id != link.run {
                    let (theirs, ours) = (h.run_id, link.run.clone());
                    return Err(BridgeError::OtherRun { endpoint: link.endpoint.clone(), theirs, ours });
                }
                if h.layout_version != link.layout_version {
                    let (theirs, ours) = (h.layout_version, link.layout_version);
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
    fn fetch_run(link: &Link, args: &ProcessArgs, local_run: &RunId) -> anyhow::Result<String> {
        let replies = link
            .session
            .get(link.keys.of("run"))
            .timeout(RUN_INFO_TIMEOUT)
            .wait()
            .map_err(zenoh_err("asking for the run's scenario"))?;
        let reply = replies.recv().map_err(|_| {
            anyhow::anyhow!("the plant-side bridge did not send the run's scenario within {RUN_INFO_TIMEOUT:?}")
        })?;
        // The plant side's refusal is text: said as such, not as a list of bytes.
        let sample = reply.result().map_err(|e| {
            anyhow::anyhow!(
                "the plant-side bridge refused the run's scenario: {}",
                String::from_utf8_lossy(&e.payload().to_bytes())
            )
        })?;
        let info: RunInfo = serde_json::from_slice(&sample.payload().to_bytes())?;
        let scenario_path = args.out.join("scenario.toml");
        silrig_flight::files::write_atomically(&scenario_path, &info.scenario_toml)?;
        let mut env: Vec<(String, String)> = info
            .env
            .into_iter()
            .filter(|(k, _)| ![SCENARIO_ENV, "SILRIG_OUT", "SILRIG_RESUME", "SILRIG_RUN_ID"].contains(&k.as_str()))
            .collect();
        env.push(("SILRIG_RUN_ID".into(), local_run.to_string()));
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

    pub(super) fn run(mut self) -> anyhow::Result<(Recorder, String, String)> {
        let watch = LoopWatch::start(self.link.events.clone());
        let ended = loop {
            if signals::termination_requested() {
                break "terminated by signal".to_string();
            }
            if self.finished_at_ns.is_some_and(|t| monotonic_ns() >= t + FINISHED_GRACE.as_nanos() as u64) {
                break "completed".to_string();
            }
            let fds = [listener_fd(&self.commands), listener_fd(&self.infos), self.link.inbox.fd()];
            watch.at(Step::Waiting);
            net::wait_readable(&fds, self.link.next_hello_ns);
            watch.at(Step::Arrivals);
            for arrival in self.link.inbox.take() {
                self.on_arrival(arrival)?;
            }
            self.plant_info.deliver_history()?;
            watch.at(Step::Sending);
            self.forward_commands()?;
            watch.at(Step::Hello);
            let connected =
                self.plant_stream.number_of_subscribers() >= 1 && self.command_stream.number_of_publishers() >= 1;
            let (run_id, layout_version) = (self.link.run.clone(), self.link.layout_version);
            self.link.say_hello(|epoch| Hello {
                side: Side::Controller,
                run_id,
                layout_version,
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
        // The report's exchange waits on purpose.
        drop(watch);
        if ended == "completed" {
            self.send_controller_report();
        }
        if let Some(n) = self.link.test_losses() {
            self.rec.count("test_losses", n);
        }
        Ok((self.rec, self.scenario, ended))
    }

    /// The controller's report (`controller.report.json`, written when it ends, about with the flight) back to the
    /// plant's host, so the run's report there is whole: waited for up to [`REPORT_WAIT`], sent (empty when there
    /// is none: a controller that does not use the session library writes none), and its receipt waited for as long.
    /// What happened is said here; the plant's host says it too.
    fn send_controller_report(&mut self) {
        let path = self.out.join("controller.report.json");
        let run = self.local_run.to_string();
        let this_run = |text: &str| {
            serde_json::from_str::<serde_json::Value>(text).is_ok_and(|v| v["run_id"].as_str() == Some(run.as_str()))
        };
        let deadline = Instant::now() + REPORT_WAIT;
        let report = loop {
            match std::fs::read_to_string(&path) {
                Ok(text) if this_run(&text) => break Some(text),
                _ if Instant::now() >= deadline => break None,
                _ => std::thread::sleep(Duration::from_millis(20)),
            }
        };
        let had_report = report.is_some();
        let trailer = CommandTrailer { bridge_epoch: self.link.epoch, residence_ns: 0 };
        let sent = self
            .link
            .session
            .put(self.link.keys.of(CONTROLLER_REPORT), report.unwrap_or_default())
            .attachment(trailer.to_bytes().to_vec())
            .congestion_control(CongestionControl::Block)
            .wait();
        let received = sent.is_ok() && {
            let deadline = monotonic_ns() + REPORT_WAIT.as_nanos() as u64;
            loop {
                let arrivals = self.link.inbox.take();
                if arrivals.iter().any(|a| matches!(a, Arrival::Sample { what: REPORT_RECEIVED, .. })) {
                    break true;
                }
                if monotonic_ns() >= deadline {
                    break false;
                }
                net::wait_readable(&[self.link.inbox.fd()], deadline);
            }
        };
        let what = if had_report {
            format!("the controller's report ({})", path.display())
        } else {
            format!("word that the controller wrote no report within {REPORT_WAIT:?} of the end")
        };
        let text = if received {
            format!("sent {what} to the plant's host")
        } else {
            format!("warning: sent {what} to the plant's host, which did not confirm it within {REPORT_WAIT:?}")
        };
        self.link.say("controller-report-sent", text, false);
    }

    fn on_arrival(&mut self, arrival: Arrival) -> anyhow::Result<()> {
        let now = monotonic_ns();
        match arrival {
            Arrival::Hello { bytes, .. } => {
                let h = match read_hello(&bytes, &self.link.run, self.link.layout_version) {
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
            Arrival::Sample { what: "plant-info", bytes, .. } => match frame::from_bytes::<PlantInfo>(&bytes) {
                Ok(info) if self.plant_info_in != Some(info) => {
                    self.plant_info.forward(&info)?;
                    self.plant_info_in = Some(info);
                }
                Ok(_) => {}
                Err(e) => {
                    self.rec.count("samples_refused", 1);
                    let text = format!("refused the plant's announcement from the network: {e}");
                    self.link.say("bridge-sample-refused", text, true);
                }
            },
            Arrival::Sample { what, bytes, .. } => match frame::from_bytes::<PlantSample>(&bytes) {
                Ok(s) if self.peer.alive().is_some() => {
                    self.plant.forward(&s)?;
                    self.published.put(s.header.tick, s.header.epoch, monotonic_ns());
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
            // The link was lost and, reconnecting, met another key (the plant side restarted with it): the plant's
            // watchdog sees the commands stop; said here once, and the bridge keeps trying.
            Arrival::LinkRefused { text } => {
                if let Err(e) = self.link.wrong_key(&text) {
                    self.rec.count("connections_refused", 1);
                    self.link.say("bridge-connection-refused", e.to_string(), true);
                }
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
