//! The device's state as it says it over MSP while it flies (armed, its flight modes, its arming-disable flags):
//! each change is an event of the run (`events.jsonl`, listed in the run's report and `report.html`), and the ones a
//! person must know of (armed, disarmed, its own failsafe engaged or ended) are said on the controller's stderr in
//! words, e.g. "device `betaflight-sitl` disarmed at 12.31 s; flight modes ANGLE FAILSAFE; arming-disable flags
//! FAILSAFE RX_FAILSAFE". The status is read every 100 ms ([`super::msp::StatusWatch`]), so a change is told at most
//! about 100 ms after the device made it; the time said is the simulated time of the tick that saw it.

use super::msp::{BOX_ARM, BOX_FAILSAFE, Latest, Status, flag_names, modes_in_words};
use silrig_rig::events::EventLog;

/// One change of the device's state: the event's kind, its words, and whether it is said on stderr too.
#[derive(Debug, Clone, PartialEq)]
pub struct Change {
    /// `device-armed`, `device-disarmed`, `device-failsafe-engaged`, `device-failsafe-ended`, `device-modes`,
    /// `device-arming-flags` or `device-state` (the first status read).
    pub kind: &'static str,
    /// For a person.
    pub detail: String,
    /// Said on stderr as well.
    pub loud: bool,
}

/// What changed from `before` to `now`, seen at simulated time `t_s` (pure: the events' words, tested alone).
pub fn changes(device: &str, before: Option<&Status>, now: &Status, t_s: f64) -> Vec<Change> {
    let modes = modes_in_words(now.modes & !(1 << BOX_ARM));
    let flags = flag_names(now.arming_disabled);
    let state = format!("flight modes {modes}; arming-disable flags {flags}");
    let change = |kind, what: &str, loud| Change {
        kind,
        detail: format!("device `{device}` {what} at {t_s:.2} s; {state}"),
        loud,
    };
    let Some(before) = before else {
        return vec![change("device-state", "said its state", false)];
    };
    let mut out = Vec::new();
    let (was_armed, armed) = (before.mode(BOX_ARM) || before.armed, now.mode(BOX_ARM) || now.armed);
    if armed != was_armed {
        out.push(if armed {
            change("device-armed", "armed", true)
        } else {
            change("device-disarmed", "disarmed", true)
        });
    }
    match (before.mode(BOX_FAILSAFE), now.mode(BOX_FAILSAFE)) {
        (false, true) => out.push(change("device-failsafe-engaged", "engaged its own failsafe", true)),
        (true, false) => out.push(change("device-failsafe-ended", "ended its failsafe", true)),
        _ => {}
    }
    let others = |s: &Status| s.modes & !((1 << BOX_ARM) | (1 << BOX_FAILSAFE));
    if others(before) != others(now) {
        out.push(change("device-modes", "changed its flight modes", false));
    }
    if before.arming_disabled != now.arming_disabled {
        out.push(change("device-arming-flags", "changed its arming-disable flags", false));
    }
    out
}

/// Watches the statuses read and tells each change.
pub struct StateLog {
    device: String,
    events: EventLog,
    last: Option<Status>,
    last_read_ns: u64,
    disarms: u64,
    failsafes: u64,
}

impl StateLog {
    /// Tell the changes of device `device` to the run's `events`.
    pub fn new(device: &str, events: EventLog) -> Self {
        Self { device: device.to_string(), events, last: None, last_read_ns: 0, disarms: 0, failsafes: 0 }
    }

    /// Look at the newest status read: each change since the last one is an event at the time it was read, at
    /// `tick` (simulated time `t_s`).
    pub fn observe(&mut self, latest: &Latest, tick: u64, t_s: f64) {
        let Some(now) = latest.status else { return };
        if latest.read_ns == self.last_read_ns {
            return;
        }
        self.last_read_ns = latest.read_ns;
        for c in changes(&self.device, self.last.as_ref(), &now, t_s) {
            self.disarms += u64::from(c.kind == "device-disarmed");
            self.failsafes += u64::from(c.kind == "device-failsafe-engaged");
            if c.loud {
                eprintln!("silrig controller: {}", c.detail);
            }
            self.events.emit_at(latest.read_ns, Some(tick), c.kind, c.detail);
        }
        self.last = Some(now);
    }

    /// The device was started again: its next status is its first.
    pub fn restart(&mut self) {
        self.last = None;
    }

    /// Counters for the controller's report: how often the device disarmed and engaged its own failsafe.
    pub fn counters(&self) -> [(String, u64); 2] {
        [("device_disarms".to_string(), self.disarms), ("device_failsafes".to_string(), self.failsafes)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn status(modes: u64, flags: u32) -> Status {
        Status { cycle_us: 125, armed: modes & 1 != 0, arming_disabled: flags, modes }
    }

    #[test]
    fn a_disarm_by_failsafe_is_told_in_words() {
        let flying = status(0b11, 0);
        let cut = status((1 << 1) | (1 << 27), (1 << 1) | (1 << 2));
        let told = changes("bf", Some(&flying), &cut, 12.3149);
        let kinds: Vec<&str> = told.iter().map(|c| c.kind).collect();
        assert_eq!(kinds, ["device-disarmed", "device-failsafe-engaged", "device-arming-flags"]);
        assert_eq!(
            told[0].detail,
            "device `bf` disarmed at 12.31 s; flight modes ANGLE FAILSAFE; arming-disable flags FAILSAFE RX_FAILSAFE"
        );
        assert!(told[0].loud && told[1].loud && !told[2].loud);
        // Back: the failsafe ends, armed again.
        let back = changes("bf", Some(&cut), &flying, 20.0);
        let kinds: Vec<&str> = back.iter().map(|c| c.kind).collect();
        assert_eq!(kinds, ["device-armed", "device-failsafe-ended", "device-arming-flags"]);
    }

    #[test]
    fn the_first_status_is_said_and_no_change_says_nothing() {
        let s = status(0b1011, 0);
        let first = changes("bf", None, &s, 0.0);
        assert_eq!(first.len(), 1);
        assert_eq!(first[0].kind, "device-state");
        assert!(first[0].detail.contains("flight modes ANGLE ALTHOLD"), "{}", first[0].detail);
        assert!(changes("bf", Some(&s), &s, 1.0).is_empty());
        let modes = changes("bf", Some(&s), &status(0b11, 0), 2.0);
        assert_eq!(modes.iter().map(|c| c.kind).collect::<Vec<_>>(), ["device-modes"]);
    }

    #[test]
    fn each_change_is_an_event_once_and_counted() {
        let dir = std::env::temp_dir().join(format!("silrig-device-state-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut log = StateLog::new("bf", EventLog::new(&dir, "controller"));
        let read = |s: Status, read_ns: u64| Latest { status: Some(s), read_ns, problem: None };
        log.observe(&read(status(0b11, 0), 10), 100, 0.1);
        // The same read seen again on the next tick is not a change.
        log.observe(&read(status(0b11, 0), 10), 101, 0.101);
        log.observe(&read(status((1 << 1) | (1 << 27), 1 << 2), 20), 200, 0.2);
        let events = silrig_rig::events::read_events(&dir);
        let kinds: Vec<&str> = events.iter().map(|e| e.kind.as_str()).collect();
        assert_eq!(kinds, ["device-state", "device-disarmed", "device-failsafe-engaged", "device-arming-flags"]);
        assert_eq!((events[1].t_ns, events[1].tick), (20, Some(200)));
        assert_eq!(log.counters()[0].1, 1);
        assert_eq!(log.counters()[1].1, 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
