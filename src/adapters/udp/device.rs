//! A device over UDP as the rig's controller (`[controller] device = "<layout file>"`): each plant sample, the
//! packets the layout sends that tick go to the device, and the newest valid packet back is the command, waiting
//! for a fresh one up to the command budget. With none, the last command stays (the plant's own budget has run out
//! by then, so the plant counts the miss as for any late controller). A packet of the wrong size or carrying NaN is
//! refused whole and counted, and the last good command held. The link's round trip (a tick's send to the first
//! valid packet after it) is measured into the controller's report beside iceoryx2's figures. A device that sends
//! nothing valid for `silent_after_s` fails the run naming its address and ports.
//!
//! When the layout says how to start the device ([`super::supervise`]), the adapter starts it, restarts it if it
//! dies, and arms it ([`super::arming`]) before the scenario's throttle reaches it; what it then says of its state
//! (armed, flight modes, its own failsafe) is told as the run's events ([`super::device_state`]).

use super::arming::Arming;
use super::codec::SendValues;
use super::device_faults::DeviceFaults;
use super::device_state::StateLog;
use super::layout::{BoundLayout, DeviceLayout, SignalNames};
use super::link::Link;
use super::supervise::Supervisor;
use silrig_flight::scenario::Scenario;
use silrig_flight::setpoints::SetpointTrack;
use silrig_flight::signals::PlantSignals;
use silrig_rig::ProcessArgs;
use silrig_rig::controller::{Controller, ControllerFigures, serve};
use silrig_rig::events::EventLog;
use silrig_rig::report::ProcessReport;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::timing::LatencyHistogram;
use silrig_wire::wire::PlantSample;
use std::path::Path;

/// The counters a device link adds to the controller's report.
const COUNTERS: [&str; 6] = [
    "device_packets_sent",
    "device_packets_received",
    "device_packets_refused_size",
    "device_packets_refused_nan",
    "device_replies_missing",
    "device_restarts",
];
const SENT: usize = 0;
const RECEIVED: usize = 1;
const REFUSED_SIZE: usize = 2;
const REFUSED_NAN: usize = 3;
const MISSING: usize = 4;
const RESTARTS: usize = 5;

/// A device over UDP flown as the controller.
pub struct DeviceController {
    layout: DeviceLayout,
    link: Link,
    bound: Option<BoundLayout>,
    /// The scenario's set points by name, in the order the layout was bound against: their histories over the run,
    /// and the values sent this tick.
    setpoint_names: Vec<String>,
    setpoint_tracks: Vec<SetpointTrack>,
    setpoints: Vec<f64>,
    budget_ns: u64,
    silent_after_ns: u64,
    /// The command the newest valid packet gave, one value per plant input (inputs the device does not command
    /// stay where the session's held command puts them).
    command: Vec<f64>,
    /// Per packet to the device, the tick it is next due at.
    next_due: Vec<u64>,
    /// The plant inputs the device commands.
    commanded: Vec<usize>,
    /// Lockstep: the plant waits for each command, so a device starting up is waited for ([`Self::await_first`]);
    /// realtime, its start-up costs misses, as any controller's does, and the device sees time go on (Betaflight's
    /// clock follows the packets' time: the same packet sent again and again would stop it).
    lockstep: bool,
    /// Whether the device has sent a valid packet since it was (re)started.
    answered: bool,
    /// When the device last sent a valid packet (or the link started, or the device was restarted), monotonic ns.
    heard_ns: Option<u64>,
    round_trip: LatencyHistogram,
    counts: [u64; COUNTERS.len()],
    /// The first refusal, said once on stderr and again if the device falls silent.
    first_refusal: Option<String>,
    failure: Option<String>,
    supervisor: Option<Supervisor>,
    arming: Option<Arming>,
    /// The device's state over MSP (with `[arming]`), each change an event.
    state: Option<StateLog>,
    events: EventLog,
    /// The plan's device faults (a packet cut, the program killed).
    faults: DeviceFaults,
    /// Realtime, from the device's restart until it is armed again (or, without `[arming]`, answers): no command
    /// is sent, so the plant holds the last one and then flies its failsafe, as for any silent controller, rather
    /// than flying a restarted device's idle motors.
    down: bool,
    packet: Vec<u8>,
}

impl DeviceController {
    /// Read the layout, check every field's type, listen on its ports and start the device's program if it has
    /// one: everything that can be refused before the plant is known, named. `run_dir` takes the device's log.
    pub fn open(path: &Path, scenario: &Scenario, args: &ProcessArgs) -> Result<Self, String> {
        let (budget_ms, run_dir) = (args.options.command_budget_ms, args.out.as_path());
        let layout = DeviceLayout::load(path).map_err(|e| e.to_string())?;
        layout.check_types().map_err(|e| format!("device layout {}: {e}", path.display()))?;
        if !(layout.silent_after_s > 0.0 && layout.silent_after_s <= 3600.0) {
            return Err(format!(
                "device layout {}: silent_after_s must be within 0..3600 s, got {}",
                path.display(),
                layout.silent_after_s
            ));
        }
        let link = Link::open(&layout)?;
        let folder = path.parent().unwrap_or(Path::new("."));
        // The device is the controller: in realtime its program gets the controller's real-time priority.
        let realtime = args.mode == silrig_rig::RigMode::Realtime;
        let fifo_priority = silrig_flight::role::Role::Controller.fifo_priority().filter(|_| realtime);
        let supervisor =
            layout.process.as_ref().map(|p| Supervisor::start(&layout.name, p, folder, run_dir, fifo_priority));
        let supervisor = supervisor.transpose()?;
        let arming =
            layout.arming.as_ref().map(|a| Arming::new(a, &layout.name, layout.address, scenario)).transpose()?;
        let (setpoint_names, setpoints): (Vec<String>, Vec<f64>) =
            scenario.setpoint.all().into_iter().map(|(n, v)| (n.to_string(), v)).unzip();
        let setpoint_tracks =
            setpoint_names.iter().map(|n| scenario.setpoint_track(n).expect("a name of [setpoint]")).collect();
        let events = EventLog::new(run_dir, silrig_flight::role::Role::Controller.label());
        let state = arming.as_ref().map(|_| StateLog::new(&layout.name, events.clone()));
        let packets: Vec<&str> = layout.to_device.iter().map(|p| p.name.as_str()).collect();
        let faults = DeviceFaults::new(&scenario.faults, &layout.name, &packets, supervisor.is_some(), events.clone())?;
        Ok(Self {
            silent_after_ns: (layout.silent_after_s * 1e9) as u64,
            layout,
            link,
            bound: None,
            setpoint_names,
            setpoint_tracks,
            setpoints,
            budget_ns: (budget_ms * 1e6) as u64,
            command: Vec::new(),
            commanded: Vec::new(),
            next_due: Vec::new(),
            heard_ns: None,
            answered: false,
            lockstep: args.mode == silrig_rig::RigMode::Lockstep,
            round_trip: LatencyHistogram::new(),
            counts: [0; COUNTERS.len()],
            first_refusal: None,
            failure: None,
            supervisor,
            arming,
            state,
            events,
            faults,
            down: false,
            packet: Vec::new(),
        })
    }

    /// Send this tick's packets; the time the first went out, if any did.
    fn send(&mut self, sample: &PlantSample) -> Option<u64> {
        let bound = self.bound.as_ref().expect("connect comes before the first step");
        // The values in force at the sample's time, then the arming's hold over them.
        for (value, track) in self.setpoints.iter_mut().zip(&self.setpoint_tracks) {
            *value = track.at(sample.t_sim_s);
        }
        if let Some(arming) = &mut self.arming {
            if !arming.ready() {
                // Still starting: its silence is counted from when it is ready.
                self.heard_ns = Some(monotonic_ns());
                return None;
            }
            arming.hold(&mut self.setpoints);
        }
        let values = SendValues { t_s: sample.t_sim_s, outputs: sample.outputs(), setpoints: &self.setpoints };
        let mut sent_ns = None;
        let tick = sample.header.tick;
        // Due when its period has passed since it last went out: a controller that skipped samples (a stall) still
        // sends it at its rate, not only on the ticks that are multiples of it.
        for (k, (packet, next)) in bound.to_device.iter().zip(&mut self.next_due).enumerate() {
            if tick < *next && tick >= next.saturating_sub(u64::from(packet.every_ticks)) {
                continue;
            }
            *next = tick + u64::from(packet.every_ticks);
            // Cut: due, but not sent (its cadence goes on, so it comes back at its rate when the window ends).
            if self.faults.is_cut(k) {
                continue;
            }
            packet.encode(bound.byte_order, &values, &mut self.packet);
            sent_ns.get_or_insert_with(monotonic_ns);
            if self.link.send(packet.port, &self.packet).is_ok() {
                self.counts[SENT] += 1;
            }
        }
        sent_ns
    }

    /// Read every packet waiting; whether a valid one came.
    fn receive(&mut self) -> bool {
        let bound = self.bound.as_ref().expect("connect comes before the first step");
        let mut valid = false;
        for k in 0..self.link.receivers() {
            while let Some(bytes) = self.link.try_receive(k) {
                self.counts[RECEIVED] += 1;
                match bound.from_device[k].decode(bound.byte_order, bytes, &mut self.command) {
                    Ok(()) => {
                        (valid, self.answered) = (true, true);
                        self.heard_ns = Some(monotonic_ns());
                    }
                    Err(e) => {
                        let which = match e {
                            super::codec::DecodeError::WrongSize { .. } => REFUSED_SIZE,
                            super::codec::DecodeError::NotFinite { .. } => REFUSED_NAN,
                        };
                        self.counts[which] += 1;
                        if self.first_refusal.is_none() {
                            let said = format!("device `{}`: {e}; the last good command is held", self.layout.name);
                            eprintln!("silrig controller: {said}");
                            self.first_refusal = Some(said);
                        }
                    }
                }
            }
        }
        valid
    }

    /// Wait for a valid packet sent after `sent_ns`, up to the budget; the round trip when one came.
    fn await_reply(&mut self, sent_ns: u64) -> Option<u64> {
        let deadline_ns = sent_ns + self.budget_ns;
        loop {
            if self.receive() {
                return Some(monotonic_ns() - sent_ns);
            }
            if !self.link.wait(deadline_ns) && monotonic_ns() >= deadline_ns {
                return None;
            }
        }
    }

    /// Lockstep, until the device (just started, or restarted) has answered once, send it the tick's packets again
    /// every budget until it does or `silent_after_s` has passed since the first: a program starting up is not yet
    /// listening, and its start-up should not count as misses.
    fn await_first(&mut self, sample: &PlantSample) -> Option<Option<u64>> {
        let since_ns = self.heard_ns.unwrap_or_else(monotonic_ns);
        while monotonic_ns() < since_ns + self.silent_after_ns {
            // Every packet of the tick again, whatever its period.
            self.next_due.fill(0);
            let sent_ns = self.send(sample)?;
            if let Some(round_trip_ns) = self.await_reply(sent_ns) {
                return Some(Some(round_trip_ns));
            }
        }
        Some(None)
    }

    /// The run's failure when the device has been silent too long.
    fn silence(&self, now_ns: u64) -> Option<String> {
        let since = self.heard_ns?;
        if now_ns.saturating_sub(since) < self.silent_after_ns {
            return None;
        }
        let ports = |p: Vec<u16>| p.iter().map(u16::to_string).collect::<Vec<_>>().join(", ");
        let bound = self.bound.as_ref()?;
        let refused = match &self.first_refusal {
            Some(first) => format!("; {} packets came but were refused, the first: {first}", self.refused()),
            None => String::new(),
        };
        Some(format!(
            "device `{}` at {} sent no valid packet to UDP port {} for {} s (packets to it went to port {}){refused}; \
             is it running, and sending to this host?",
            self.layout.name,
            self.layout.address,
            ports(bound.from_device.iter().map(|p| p.port).collect()),
            self.layout.silent_after_s,
            ports(bound.to_device.iter().map(|p| p.port).collect()),
        ))
    }

    fn refused(&self) -> u64 {
        self.counts[REFUSED_SIZE] + self.counts[REFUSED_NAN]
    }

    /// Watch the device's program: restarted when it died (silence is then counted from the restart, and it is
    /// armed again); an error when it cannot be.
    fn supervise(&mut self, now_ns: u64) {
        let Some(supervisor) = &mut self.supervisor else { return };
        match supervisor.check(now_ns) {
            Ok(false) => {}
            Ok(true) => {
                self.counts[RESTARTS] += 1;
                (self.heard_ns, self.answered, self.down) = (Some(now_ns), false, !self.lockstep);
                if let Some(arming) = &mut self.arming {
                    arming.restart(now_ns);
                }
                if let Some(state) = &mut self.state {
                    state.restart();
                }
                let detail = format!(
                    "device `{}`: its program ended; started again (pid {})",
                    self.layout.name,
                    supervisor.pid()
                );
                self.events.emit(None, "device-restarted", detail);
            }
            Err(e) => self.failure = Some(e),
        }
    }
}

impl Controller for DeviceController {
    fn diagnostic_names(&self) -> Vec<String> {
        Vec::new()
    }

    fn connect(&mut self, plant: &PlantSignals) -> Result<(), String> {
        let outputs: Vec<String> = plant.outputs.iter().map(|s| s.name.clone()).collect();
        let inputs: Vec<String> = plant.inputs.iter().map(|s| s.name.clone()).collect();
        let names = SignalNames { outputs: &outputs, inputs: &inputs, setpoints: &self.setpoint_names };
        let bound = self.layout.bind(&names).map_err(|e| format!("device `{}`: {e}", self.layout.name))?;
        self.commanded = bound
            .from_device
            .iter()
            .flat_map(|p| p.groups.iter().flat_map(|g| g.targets.iter().flatten().copied()))
            .collect();
        self.command = plant.inputs.iter().map(|i| i.hold).collect();
        self.next_due = vec![0; bound.to_device.len()];
        if let Some(arming) = &mut self.arming {
            arming.bind(&self.setpoint_names)?;
        }
        self.bound = Some(bound);
        Ok(())
    }

    fn step(&mut self, sample: &PlantSample, _dt_s: f64, command: &mut [f64], _diagnostics: &mut [f64]) {
        let pid = self.supervisor.as_ref().map(Supervisor::pid);
        if self.faults.at(sample.t_sim_s, sample.header.tick, pid)
            && let Some(supervisor) = &mut self.supervisor
        {
            supervisor.kill();
            self.down = !self.lockstep;
        }
        let now_ns = monotonic_ns();
        self.supervise(now_ns);
        if let Some(arming) = &mut self.arming {
            if let Err(e) = arming.check(now_ns) {
                self.failure = Some(e);
            }
            if arming.stuck(now_ns)
                && let Some(supervisor) = &mut self.supervisor
            {
                let what =
                    if arming.latest().status.is_some() { "answers but has not" } else { "has not answered nor" };
                let detail = format!(
                    "device `{}` {what} set its receiver up 5 s after it started: started again",
                    self.layout.name
                );
                eprintln!("silrig controller: {detail}");
                self.events.emit(None, "device-stuck", detail);
                supervisor.kill();
                arming.restart(now_ns);
            }
            if let Some(state) = &mut self.state {
                state.observe(arming.latest(), sample.header.tick, sample.t_sim_s);
            }
        }
        // Silence is counted from the first packet sent.
        self.heard_ns.get_or_insert(now_ns);
        // Packets that came since the last step answer earlier ticks: taken as the newest command, not as fresh.
        self.receive();
        let reply = match self.send(sample).map(|sent_ns| self.await_reply(sent_ns)) {
            Some(None) if !self.answered && self.lockstep => self.await_first(sample),
            reply => reply,
        };
        match reply {
            Some(Some(round_trip_ns)) => self.round_trip.record_ns(round_trip_ns as i64),
            Some(None) => self.counts[MISSING] += 1,
            // Nothing due this tick: take what came meanwhile.
            None => {
                self.receive();
            }
        }
        for &k in &self.commanded {
            command[k] = self.command[k];
        }
        // Down until armed again (or, without arming, until it answers).
        self.down &= !self.arming.as_ref().map_or(self.answered, Arming::armed);
        if self.failure.is_none() {
            self.failure = self.silence(monotonic_ns());
        }
    }

    fn failure(&mut self) -> Option<String> {
        self.failure.take()
    }

    fn withholds(&self) -> bool {
        self.down
    }

    fn figures(&self) -> ControllerFigures {
        let description = format!(
            "device `{}` link: a tick's first packet sent to the first valid packet back after it",
            self.layout.name
        );
        ControllerFigures {
            distributions: vec![("device_round_trip".into(), description, self.round_trip.clone())],
            counters: COUNTERS
                .iter()
                .zip(self.counts)
                .map(|(n, c)| (n.to_string(), c))
                .chain(self.arming.iter().flat_map(Arming::counters))
                .chain(self.state.iter().flat_map(StateLog::counters))
                .collect(),
        }
    }
}

/// Fly the scenario's device (its layout file `layout`) as the run's controller until the run ends (or SIGTERM),
/// and write the controller's report.
pub fn run_device_controller(args: &ProcessArgs, layout: &Path) -> anyhow::Result<ProcessReport> {
    let scenario = args.scenario()?;
    let device = DeviceController::open(layout, &scenario, args).map_err(anyhow::Error::msg)?;
    serve(args, scenario, Box::new(device))
}
