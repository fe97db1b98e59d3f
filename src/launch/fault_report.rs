//! The fault report: for every fault of the plan, when it was injected, when and by whom it was detected, when the
//! failsafe engaged, when the loop recovered, and what was lost on each stream, from the run's event log and the
//! logger's `timing.csv`. Times are simulated seconds, as the figures' axes are: an event is placed at the tick the
//! plant had published when it happened (from `timing.csv`), so a stall or a restart does not shift the marks by the
//! outage; the injection's wall time from tick 0 is kept beside it.

use serde::{Deserialize, Serialize};
use silrig_flight::fault::{Fault, FaultAction};
use silrig_flight::role::Role;
use silrig_rig::events::{Event, read_events};
use std::path::Path;

/// What became of one fault.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FaultRecord {
    /// The fault, as planned.
    pub fault: String,
    /// When it was injected, simulated s (None: never, e.g. its target was not running).
    pub injected_at_s: Option<f64>,
    /// When it was injected, wall-clock s from the plant's tick 0 (later than `injected_at_s` once a stall or a
    /// restart has held simulated time back).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub injected_at_wall_s: Option<f64>,
    /// First detection after injection: when, s.
    pub detected_at_s: Option<f64>,
    /// ... by which process, and how.
    pub detected_by: Option<String>,
    /// When the plant's failsafe engaged, s.
    pub failsafe_at_s: Option<f64>,
    /// When the loop recovered (commands or samples resumed, or the fault ended), s.
    pub recovered_at_s: Option<f64>,
    /// Plant ticks absent from the log between injection and recovery.
    pub plant_samples_lost: u64,
    /// Ticks between injection and recovery whose command is not in the log: rows without a command, and the ticks
    /// absent from the log (their commands went with them: a stopped logger loses both).
    pub command_samples_lost: u64,
    /// Where the logged flight joins a re-flown one after this fault (a restarted plant), and by how much.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discontinuity: Option<Discontinuity>,
    /// Where a plant restarted after this fault flew on from, and how many ticks it flew again.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plant_resume: Option<PlantResume>,
    /// How the process came back, for a kill or term with `restart_after`: its start-up apart from the loop's
    /// recovery, so that a slow start is not judged as slow control.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rejoin: Option<Rejoin>,
}

/// How a restarted process came back, in wall-clock s from the plant's first tick 0 (simulated time stands still
/// while a plant is down, so it cannot time a plant's restart).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rejoin {
    /// When the launcher started it again.
    pub restarted_at_wall_s: f64,
    /// When it joined the flight again: the controller's first sample, the plant's first tick, the logger's first
    /// row (None: never).
    pub joined_at_wall_s: Option<f64>,
    /// When the loop closed again after that: the plant's first fresh command after a controller came back, the
    /// controller's first sample after a plant came back, the join itself for the logger (None: never).
    pub closed_at_wall_s: Option<f64>,
}

/// The event by which a restarted process of `role` says it joined the flight again.
fn join_kind(role: Role) -> &'static str {
    match role {
        Role::Controller => "controller-joined",
        Role::Plant => "ticking",
        Role::Logger => "logger-resumed",
    }
}

/// The peer's event that says the loop closed again after `role` joined (None: the join closes it).
fn closed_kind(role: Role) -> Option<(Role, &'static str)> {
    match role {
        Role::Controller => Some((Role::Plant, "controller-recovered")),
        Role::Plant => Some((Role::Controller, "plant-recovered")),
        Role::Logger => None,
    }
}

/// How the target of a kill or term with `restart_after` came back, from the events of its window.
fn rejoin(f: &Fault, window: &[&Event], t0_ns: u64) -> Option<Rejoin> {
    if !matches!(f.action(), FaultAction::Kill | FaultAction::Term) || f.restart_after_s.is_none() {
        return None;
    }
    // The bridge has no rig process to join: how it came back is the bridge's own report.
    let role = f.target().role()?;
    let wall = |e: &Event| (e.t_ns as f64 - t0_ns as f64) / 1e9;
    let restarted = window.iter().copied().find(|e| {
        e.process == "launcher" && e.kind == "process-restarted" && e.detail.starts_with(&format!("{} ", role.label()))
    })?;
    let joined = window
        .iter()
        .copied()
        .find(|e| e.t_ns >= restarted.t_ns && e.process == role.label() && e.kind == join_kind(role));
    let closed = joined.and_then(|j| match closed_kind(role) {
        None => Some(j),
        Some((peer, kind)) => {
            window.iter().copied().find(|e| e.t_ns >= j.t_ns && e.process == peer.label() && e.kind == kind)
        }
    });
    Some(Rejoin {
        restarted_at_wall_s: wall(restarted),
        joined_at_wall_s: joined.map(&wall),
        closed_at_wall_s: closed.map(wall),
    })
}

/// A place where the logged flight joins a re-flown one: a restarted plant flew again from a tick older than the
/// last one written.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Discontinuity {
    /// Simulated time of the first row of the re-flown flight, s.
    pub at_s: f64,
    /// Which ticks were flown twice, and the jump between the two flights.
    pub detail: String,
}

/// Every flight discontinuity of the run (`flight-discontinuity` events of the logger), planned or not.
pub fn discontinuities(out_dir: &Path, dt_s: f64) -> Vec<Discontinuity> {
    read_events(out_dir).iter().filter(|e| e.kind == "flight-discontinuity").map(|e| discontinuity(e, dt_s)).collect()
}

fn discontinuity(e: &Event, dt_s: f64) -> Discontinuity {
    Discontinuity { at_s: e.tick.unwrap_or(0) as f64 * dt_s, detail: e.detail.clone() }
}

/// Where a restarted plant flew on from: the tick of the checkpoint it resumed from (0: from the start), and how many
/// ticks its predecessor had already flown that it flew again (the rollback; at most one checkpoint interval).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlantResume {
    /// The first tick the restarted plant flew.
    pub at_tick: u64,
    /// Ticks flown again (None: its predecessor's newest tick is unknown, a plant not using our library).
    pub ticks_flown_again: Option<u64>,
}

impl PlantResume {
    /// "resumed at tick N, K ticks flown again", as the fault table and the run page say it.
    pub fn describe(&self) -> String {
        match self.ticks_flown_again {
            Some(k) => format!("resumed at tick {}, {k} ticks flown again", self.at_tick),
            None => format!("resumed at tick {}", self.at_tick),
        }
    }
}

/// Every restart of the plant in the run (its `plant-resumed` and `plant-restarted-from-start` events), planned or
/// not.
pub fn plant_resumes(out_dir: &Path) -> Vec<PlantResume> {
    read_events(out_dir).iter().filter_map(plant_resume).collect()
}

/// The resumption a restarted plant's event says (the plant writes "...: K ticks flown again" when it knows).
fn plant_resume(e: &Event) -> Option<PlantResume> {
    if e.process != Role::Plant.label() || !["plant-resumed", "plant-restarted-from-start"].contains(&e.kind.as_str()) {
        return None;
    }
    let again = e.detail.rsplit_once(": ").and_then(|(_, k)| k.strip_suffix(" ticks flown again")?.parse().ok());
    Some(PlantResume { at_tick: e.tick.unwrap_or(0), ticks_flown_again: again })
}

/// CLOCK_MONOTONIC time of the plant's first tick 0, from its `ticking` event.
pub fn plant_t0_ns(out_dir: &Path) -> Option<u64> {
    read_events(out_dir)
        .iter()
        .find(|e| e.process == Role::Plant.label() && e.kind == "ticking")
        .and_then(|e| e.detail.strip_prefix("t0_ns=")?.parse().ok())
}

const DETECTIONS: [&str; 7] = [
    "controller-stale",
    "plant-stale",
    "failsafe-engaged",
    "plant-gap",
    "commands-missing",
    "overrun",
    "process-ended",
];
const RECOVERIES: [&str; 6] = [
    "controller-recovered",
    "plant-recovered",
    "commands-resumed",
    "logger-resumed",
    "controller-joined",
    "fault-ended",
];
/// A device's fault is detected by the device (its own failsafe, read over MSP) or the controller seeing its program
/// dead, and it has recovered when the device ends its failsafe or is armed again: the rig's own detections on a
/// loaded machine (a late command) in its window are not its.
const DEVICE_DETECTIONS: [&str; 2] = ["device-failsafe-engaged", "device-restarted"];
const DEVICE_RECOVERIES: [&str; 2] = ["device-failsafe-ended", "device-armed"];

/// The events that detect `f`, and those that say the loop recovered from it. (Its failsafe is the plant's or the
/// device's own, whichever engaged first: a cut RC link engages Betaflight's.)
fn detections_of(f: &Fault) -> (&'static [&'static str], &'static [&'static str]) {
    match f.target() {
        silrig_flight::fault::FaultTarget::Device => (&DEVICE_DETECTIONS, &DEVICE_RECOVERIES),
        _ => (&DETECTIONS, &RECOVERIES),
    }
}

/// When each fault of `order` was injected, with its description: the launcher's or the process's own
/// `fault-injected`; a plant-model fault acts when the flight reaches `at_s`, which after stalls and restarts is
/// seconds of wall time after t0 + at_s.
fn injections(order: &[&Fault], events: &[Event], clock: &SimClock) -> Vec<(String, Option<u64>)> {
    order
        .iter()
        .map(|f| {
            let desc = f.describe();
            let at = events
                .iter()
                .find(|e| e.kind == "fault-injected" && e.detail.starts_with(&desc))
                .map(|e| e.t_ns)
                .or_else(|| f.action().is_plant_model_fault().then(|| clock.wall_ns(f.at_s)));
            (desc, at)
        })
        .collect()
}

/// Records for every fault of `plan`.
pub fn fault_records(plan: &[Fault], out_dir: &Path, dt_s: f64) -> Vec<FaultRecord> {
    let events = read_events(out_dir);
    let Some(t0) = plant_t0_ns(out_dir) else {
        return plan.iter().map(empty).collect();
    };
    let timing = read_timing(out_dir);
    let clock = SimClock::new(&timing, t0, dt_s);
    let rel = |t_ns: u64| clock.sim_s(t_ns);
    let mut order: Vec<&Fault> = plan.iter().collect();
    order.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
    let injected = injections(&order, &events, &clock);
    order
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let (desc, Some(inj)) = injected[i].clone() else { return empty(f) };
            // Only events before the next fault's injection belong to this one; a next fault never injected
            // would have come when the flight reached its time.
            let next_ns = order
                .get(i + 1)
                .map_or(u64::MAX, |n| injected[i + 1].1.unwrap_or_else(|| clock.wall_ns(n.at_s)))
                .max(inj);
            let window: Vec<&Event> = events.iter().filter(|e| e.t_ns >= inj && e.t_ns < next_ns).collect();
            // The rig has no detector of sensor or actuator faults: whatever a process notices in a plant-model
            // fault's window (a command missed on a loaded machine) is not its detection, nor the failsafe and
            // recovery that follow it.
            let model_fault = f.action().is_plant_model_fault();
            let noticed: &[&Event] = if model_fault { &[] } else { &window };
            // A peer's detection outranks the target's own, and the launcher's comes last: a stopped plant only
            // sees its outage once continued, the controller saw it at once. But a delayed or jittered plant sees it
            // itself, at once, as an overrun (the rig's detector for it); a peer missing a command then is a
            // consequence. Another process's overrun is never a detection of this fault: on a loaded machine any
            // process overruns now and then (the CI run that credited a stopped logger's fault to a plant overrun
            // seconds later).
            let target = f.target().label();
            let own_first = f.target() == Role::Plant && matches!(f.action(), FaultAction::Delay | FaultAction::Jitter);
            let (detections, recoveries) = detections_of(f);
            let detection = noticed
                .iter()
                .filter(|e| detections.contains(&e.kind.as_str()) && (e.kind != "overrun" || e.process == target))
                .min_by_key(|e| (e.process == "launcher", (e.process == target) != own_first, e.t_ns));
            let failsafe = noticed.iter().find(|e| e.kind == "failsafe-engaged" || e.kind == "device-failsafe-engaged");
            // A restarted logger says it resumed before it sees (and reports) the gap its absence left.
            let recovery = noticed.iter().find(|e| {
                recoveries.contains(&e.kind.as_str())
                    && (e.kind == "logger-resumed" || detection.is_none_or(|d| e.t_ns >= d.t_ns))
            });
            let end_ns = recovery.map_or(next_ns.min(inj + 2_000_000_000), |e| e.t_ns);
            let (plant_lost, command_lost) = losses(&timing, inj, end_ns);
            // A plant-model fault acts at its planned simulated time, whatever the wall clock says.
            let injected_at_s = if model_fault { f.at_s } else { rel(inj) };
            FaultRecord {
                fault: desc,
                injected_at_s: Some(injected_at_s),
                injected_at_wall_s: Some((inj as f64 - t0 as f64) / 1e9),
                detected_at_s: detection.map(|e| rel(e.t_ns)),
                detected_by: detection.map(|e| format!("{} ({})", e.process, e.kind)),
                failsafe_at_s: failsafe.map(|e| rel(e.t_ns)),
                recovered_at_s: recovery.map(|e| rel(e.t_ns)),
                plant_samples_lost: plant_lost,
                command_samples_lost: command_lost,
                discontinuity: window.iter().find(|e| e.kind == "flight-discontinuity").map(|e| discontinuity(e, dt_s)),
                plant_resume: window.iter().find_map(|e| plant_resume(e)),
                rejoin: rejoin(f, &window, t0),
            }
        })
        .collect()
}

fn empty(f: &Fault) -> FaultRecord {
    FaultRecord {
        fault: f.describe(),
        injected_at_s: None,
        injected_at_wall_s: None,
        detected_at_s: None,
        detected_by: None,
        failsafe_at_s: None,
        recovered_at_s: None,
        plant_samples_lost: 0,
        command_samples_lost: 0,
        discontinuity: None,
        plant_resume: None,
        rejoin: None,
    }
}

/// Simulated time of a CLOCK_MONOTONIC instant: the tick the plant had last published by then, plus the time since,
/// up to one period (past that the plant was not ticking: stopped, delayed, dead, and simulated time waited).
struct SimClock {
    /// (plant send time ns, tick), by send time.
    sent: Vec<(u64, u64)>,
    t0_ns: u64,
    dt_s: f64,
}

impl SimClock {
    fn new(timing: &[(u64, u64, bool)], t0_ns: u64, dt_s: f64) -> Self {
        let mut sent: Vec<(u64, u64)> = timing.iter().map(|r| (r.1, r.0)).collect();
        sent.sort_unstable();
        Self { sent, t0_ns, dt_s }
    }

    /// The CLOCK_MONOTONIC instant the flight reached `sim_s`: the send time of the first logged tick at or past
    /// it, less the periods between (a tick the logger lost happened that much earlier); past the last logged tick,
    /// the last one's offset from simulated time carried on; without timing.csv, t0 + `sim_s`.
    fn wall_ns(&self, sim_s: f64) -> u64 {
        let dt_ns = self.dt_s * 1e9;
        let tick = (sim_s / self.dt_s - 1e-9).ceil().max(0.0) as u64;
        let first_at_or_past = self.sent.iter().find(|(_, t)| *t >= tick);
        match (first_at_or_past, self.sent.last()) {
            (Some(&(sent, t)), _) => sent.saturating_sub(((t - tick) as f64 * dt_ns) as u64),
            (None, Some(&(sent, t))) => sent + ((tick - t) as f64 * dt_ns) as u64,
            (None, None) => self.t0_ns + (sim_s.max(0.0) * 1e9) as u64,
        }
    }

    fn sim_s(&self, t_ns: u64) -> f64 {
        let k = self.sent.partition_point(|(sent, _)| *sent <= t_ns);
        match k.checked_sub(1).map(|i| self.sent[i]) {
            Some((sent, tick)) => tick as f64 * self.dt_s + ((t_ns - sent) as f64 / 1e9).min(self.dt_s),
            // Before the first logged tick (or without timing.csv): the wall clock from tick 0.
            None => (t_ns as f64 - self.t0_ns as f64) / 1e9,
        }
    }
}

/// (tick, plant send time ns, command missing) per logged row.
fn read_timing(out_dir: &Path) -> Vec<(u64, u64, bool)> {
    let text = std::fs::read_to_string(out_dir.join("timing.csv")).unwrap_or_default();
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            Some((c.first()?.parse().ok()?, c.get(3)?.parse().ok()?, *c.get(11)? == "1"))
        })
        .collect()
}

/// Plant ticks missing, and commands missing (rows without one, and the missing ticks', which went with them), among
/// the rows published in [from_ns, to_ns].
fn losses(timing: &[(u64, u64, bool)], from_ns: u64, to_ns: u64) -> (u64, u64) {
    let rows: Vec<&(u64, u64, bool)> = timing.iter().filter(|r| r.1 >= from_ns && r.1 <= to_ns).collect();
    let command_lost = rows.iter().filter(|r| r.2).count() as u64;
    // Gaps in the tick sequence from the last row before the window to the first row after it.
    let before = timing.iter().filter(|r| r.1 < from_ns).map(|r| r.0).max();
    let after = timing.iter().filter(|r| r.1 > to_ns).map(|r| r.0).min();
    let mut ticks: Vec<u64> = rows.iter().map(|r| r.0).collect();
    ticks.extend(before);
    ticks.extend(after);
    ticks.sort_unstable();
    ticks.dedup();
    let plant_lost = ticks.windows(2).map(|w| w[1] - w[0] - 1).sum();
    (plant_lost, command_lost + plant_lost)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simulated_time_waits_while_the_plant_does_not_tick() {
        // Ticks 0..=9 every 10 ms from t0 = 1 s, then a 500 ms stall, then ticks 10.. again every 10 ms.
        let t0 = 1_000_000_000;
        let mut timing: Vec<(u64, u64, bool)> = (0..10).map(|k| (k, t0 + k * 10_000_000, false)).collect();
        timing.extend((10..20).map(|k| (k, t0 + 590_000_000 + k * 10_000_000, false)));
        let clock = SimClock::new(&timing, t0, 0.01);
        let at = |ms: u64| clock.sim_s(t0 + ms * 1_000_000);
        assert!((at(45) - 0.045).abs() < 1e-9, "between ticks 4 and 5: {}", at(45));
        // In the stall simulated time stands one period after tick 9.
        assert!((at(300) - 0.10).abs() < 1e-9, "{}", at(300));
        // After it, 0.5 s of wall time behind.
        assert!((at(705) - 0.115).abs() < 1e-9, "{}", at(705));
        // Before tick 0: the wall clock.
        assert!((clock.sim_s(t0 - 5_000_000) + 0.005).abs() < 1e-9);
        // And back: tick 15 came 0.5 s late, a time between ticks at the next tick, past the log the same offset.
        assert_eq!(clock.wall_ns(0.15), t0 + 740_000_000);
        assert_eq!(clock.wall_ns(0.0449), t0 + 50_000_000);
        assert_eq!(clock.wall_ns(0.25), t0 + 840_000_000);
    }
}

#[cfg(test)]
mod detection_tests {
    use super::*;
    use silrig_flight::fault::parse_fault_flag;

    /// A run folder with 300 ticks every 10 ms from t0 = 1 s and the given events (ms from t0, process, kind).
    fn run_with(name: &str, events: &[(u64, &str, &str, &str)]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("silrig-fault-report-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let t0: u64 = 1_000_000_000;
        let mut timing = String::from("tick,a,b,t_plant_send_ns,c,d,e,f,g,h,i,command_missing\n");
        for k in 0..300u64 {
            timing += &format!("{k},0,0,{},0,0,0,0,0,0,0,0\n", t0 + k * 10_000_000);
        }
        std::fs::write(dir.join("timing.csv"), timing).unwrap();
        let mut lines = format!(
            "{{\"t_ns\":{t0},\"tick\":0,\"process\":\"plant\",\"kind\":\"ticking\",\"detail\":\"t0_ns={t0}\"}}\n"
        );
        for (ms, process, kind, detail) in events {
            lines += &format!(
                "{{\"t_ns\":{},\"process\":\"{process}\",\"kind\":\"{kind}\",\"detail\":\"{detail}\"}}\n",
                t0 + ms * 1_000_000
            );
        }
        std::fs::write(dir.join("events.jsonl"), lines).unwrap();
        dir
    }

    #[test]
    fn another_process_overrunning_is_not_a_detection_of_the_fault() {
        let fault = parse_fault_flag("logger:stop@1s,for=0.5s").unwrap();
        let dir = run_with(
            "overrun",
            &[
                (1000, "launcher", "fault-injected", "logger stop at 1 s, for 0.5 s (SIGSTOP to pid 7)"),
                (1500, "launcher", "fault-ended", "SIGCONT to logger (pid 7)"),
                (2200, "plant", "overrun", "tick 220 ran past the next one's due time"),
            ],
        );
        let r = &fault_records(&[fault], &dir, 0.01)[0];
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(r.detected_by, None);
        assert_eq!(r.recovered_at_s, Some(1.5));
    }

    #[test]
    fn a_delayed_plant_detects_its_delay_itself_before_a_peer_misses_a_command() {
        // A docs run on the loaded machine credited the plant's 15 ms delay to the logger's missing command.
        let fault = parse_fault_flag("plant:delay@1s,delay=15ms").unwrap();
        let dir = run_with(
            "delay",
            &[
                (1000, "plant", "fault-injected", "plant delay at 1 s, delay 15 ms"),
                (1009, "logger", "commands-missing", "rows written without a command from here"),
                (1015, "plant", "overrun", "woke 15 ms late"),
            ],
        );
        let r = &fault_records(&[fault], &dir, 0.01)[0];
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(r.detected_by.as_deref(), Some("plant (overrun)"));
    }

    #[test]
    fn nothing_noticed_in_a_plant_model_faults_window_is_its_detection() {
        // The CI run where a command missed on the loaded machine 1.6 s into a stuck rudder's window was shown as
        // the stuck rudder "detected by logger (commands-missing)".
        let fault = parse_fault_flag("plant:actuator-stuck@1s,surface=rudder,for=1s").unwrap();
        let dir = run_with(
            "model",
            &[
                (2600, "logger", "commands-missing", "rows written without a command from here"),
                (2610, "logger", "commands-resumed", "1 rows without a command"),
            ],
        );
        let r = &fault_records(&[fault], &dir, 0.01)[0];
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!((r.injected_at_s, r.detected_by.as_deref(), r.recovered_at_s), (Some(1.0), None, None));
    }

    #[test]
    fn a_fault_late_in_a_stalled_flight_keeps_its_own_detection() {
        // The plant stalled 1 s early on, so the flight reaches 1.5 s at 2.5 s of wall time. The plant stop planned
        // at 1.5 s lands there; a hard-over planned at 1.54 s acts at 2.54 s of wall time, after the stop's
        // detection. (Taken at t0 + 1.54 s, the hard-over's window opened before the stop and took its detection.)
        let dir = run_with("stalled", &[]);
        let t0: u64 = 1_000_000_000;
        let mut timing = String::from("tick,a,b,t_plant_send_ns,c,d,e,f,g,h,i,command_missing\n");
        for k in 0..300u64 {
            let stall = if k >= 50 { 1_000_000_000 } else { 0 };
            timing += &format!("{k},0,0,{},0,0,0,0,0,0,0,0\n", t0 + k * 10_000_000 + stall);
        }
        std::fs::write(dir.join("timing.csv"), timing).unwrap();
        let mut events = std::fs::read_to_string(dir.join("events.jsonl")).unwrap();
        for (ms, process, kind, detail) in [
            (2500, "launcher", "fault-injected", "plant stop at 1.5 s, for 0.02 s (SIGSTOP to pid 7)"),
            (2520, "launcher", "fault-ended", "SIGCONT to plant (pid 7)"),
            (2530, "controller", "plant-stale", "no sample for 50 ms"),
        ] {
            events += &format!(
                "{{\"t_ns\":{},\"process\":\"{process}\",\"kind\":\"{kind}\",\"detail\":\"{detail}\"}}\n",
                t0 + ms * 1_000_000
            );
        }
        std::fs::write(dir.join("events.jsonl"), events).unwrap();
        let plan = [
            parse_fault_flag("plant:stop@1.5s,for=0.02s").unwrap(),
            parse_fault_flag("plant:actuator-hard-over@1.54s,surface=elevator,limit=min,for=0.2s").unwrap(),
        ];
        let r = fault_records(&plan, &dir, 0.01);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(r[0].detected_by.as_deref(), Some("controller (plant-stale)"));
        assert_eq!(r[1].detected_by, None);
        assert_eq!(r[1].injected_at_s, Some(1.54));
        assert!((r[1].injected_at_wall_s.unwrap() - 2.54).abs() < 1e-9, "{:?}", r[1].injected_at_wall_s);
    }

    #[test]
    fn a_peer_detects_before_the_faulted_process_does() {
        // The stopped plant overran once just as the SIGSTOP landed; the controller saw it go silent.
        let fault = parse_fault_flag("plant:stop@1s,for=0.5s").unwrap();
        let dir = run_with(
            "peer",
            &[
                (1000, "launcher", "fault-injected", "plant stop at 1 s, for 0.5 s (SIGSTOP to pid 7)"),
                (1001, "plant", "overrun", "late"),
                (1050, "controller", "plant-stale", "no sample for 50 ms"),
                (1500, "launcher", "fault-ended", "SIGCONT to plant (pid 7)"),
            ],
        );
        let r = &fault_records(&[fault], &dir, 0.01)[0];
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(r.detected_by.as_deref(), Some("controller (plant-stale)"));
    }

    #[test]
    fn a_restarted_process_is_timed_from_its_restart_to_its_join_and_from_its_join_to_the_closed_loop() {
        // A Python controller taking 0.82 s to start: its start-up is the join, not the loop's recovery.
        let fault = parse_fault_flag("controller:kill@1s,restart_after=0.5s").unwrap();
        let dir = run_with(
            "rejoin",
            &[
                (1000, "launcher", "fault-injected", "controller kill at 1 s, restart after 0.5 s (SIGKILL)"),
                (1060, "plant", "controller-stale", "no command for 59 ms"),
                (1510, "launcher", "process-restarted", "plant as pid 9 (restart 1)"),
                (1520, "launcher", "process-restarted", "controller as pid 8 (restart 1)"),
                (2340, "controller", "controller-joined", "plant already at tick 234"),
                (2355, "plant", "controller-recovered", "failsafe released, commands resumed"),
            ],
        );
        let r = &fault_records(&[fault], &dir, 0.01)[0];
        let never = parse_fault_flag("controller:term@1s,restart_after=0.5s").unwrap();
        let never_dir = run_with(
            "rejoin-never",
            &[
                (1000, "launcher", "fault-injected", "controller term at 1 s, restart after 0.5 s"),
                (1500, "launcher", "process-restarted", "controller as pid 8 (restart 1)"),
            ],
        );
        let silent = &fault_records(&[never], &never_dir, 0.01)[0];
        std::fs::remove_dir_all(&never_dir).unwrap();
        let stop = parse_fault_flag("controller:stop@1s,for=0.5s").unwrap();
        let stopped = &fault_records(&[stop], &dir, 0.01)[0];
        std::fs::remove_dir_all(&dir).unwrap();
        let j = r.rejoin.expect("a restart");
        assert!((j.restarted_at_wall_s - 1.52).abs() < 1e-9, "the controller's restart, not the plant's: {j:?}");
        assert!((j.joined_at_wall_s.unwrap() - 2.34).abs() < 1e-9, "{j:?}");
        assert!((j.closed_at_wall_s.unwrap() - 2.355).abs() < 1e-9, "{j:?}");
        let j = silent.rejoin.expect("a restart");
        assert_eq!((j.joined_at_wall_s, j.closed_at_wall_s), (None, None));
        assert_eq!(stopped.rejoin, None, "a stopped process is continued, not restarted");
    }
}
