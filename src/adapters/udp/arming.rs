//! Arming a device that must be armed before it flies (Betaflight): the arm switch's set point is held low until
//! the device's arming-disable flags clear (read over MSP, [`super::msp`]), then raised to the scenario's value, so
//! the switch goes low to high after the flags clear, as Betaflight requires; the set points it must see low to arm
//! (the throttle) are held at 0 until it reports itself armed. Not armed within `within_s` of its (re)start, the
//! run fails naming the flags that kept it from arming, in words. After a restart of the device, the same again; and
//! after it disarmed itself in flight (Betaflight's failsafe drops it), as a pilot would once the link is back: the
//! switch lowered, the throttle held low, the switch raised once its flags clear, timed from the disarm. A scenario
//! that lowers the switch itself is not armed again, nor failed for it, until it raises it.

use super::msp::{Latest, Status, StatusWatch, flags_in_words};

/// Betaflight's `RX_FAILSAFE` arming-disable flag (bit 2, `runtime_config.h`).
const RX_FAILSAFE: u32 = 1 << 2;

/// How long a (re)started device may go without setting its receiver up before it is started again: a start of
/// Betaflight's SITL whose status stays at `BOOT_GRACE_TIME` alone never sets its receiver up (2 of 3 starts on
/// 2026-11-28, the machine loaded), and it is sent nothing until it does (see [`Arming::ready`]); and some starts
/// never answer over MSP at all (their output stops before the SITL takes its first TCP connection: 2 of 4 starts at
/// a load average of 25 the same day).
const STUCK_START_NS: u64 = 5_000_000_000;

/// Whether a start is stuck: its receiver is not up, and it started more than [`STUCK_START_NS`] ago. (Started
/// again each time, a device that never answers ends the run when its `max_restarts` are spent.)
fn stuck_start(receiver_up: bool, since_start_ns: u64) -> bool {
    !receiver_up && since_start_ns > STUCK_START_NS
}

/// Whether a status shows the receiver set up: `RX_FAILSAFE` (it looked for RC and found none), or armed.
fn receiver_up(status: &Status) -> bool {
    status.arming_disabled & RX_FAILSAFE != 0 || status.armed
}
use serde::Deserialize;
use silrig_flight::scenario::Scenario;
use std::net::SocketAddr;

/// `[arming]` of a layout file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmingOptions {
    /// The set point carrying the arm switch: held at 0 until the device's arming-disable flags clear.
    pub switch: String,
    /// Set points held at 0 until the device reports itself armed (Betaflight refuses to arm with the throttle up).
    #[serde(default)]
    pub low_until_armed: Vec<String>,
    /// The TCP port of the device's MSP (Betaflight's UART1 on 5761), on the layout's `address`.
    pub msp_port: u16,
    /// Armed within this many seconds of the device's (re)start, or the run fails naming its flags.
    pub within_s: f64,
}

/// Where arming stands.
pub struct Arming {
    options: ArmingOptions,
    device: String,
    watch: StatusWatch,
    /// The index into the bound set points of the switch, then of each held set point.
    switch: usize,
    held: Vec<usize>,
    started_ns: Option<u64>,
    /// What the device said over MSP when [`Self::check`] last looked.
    latest: Latest,
    raised: bool,
    /// The scenario's switch is high at the tick [`Self::hold`] last saw: it wants the device armed.
    wanted: bool,
    /// Its receiver is set up: it has said `RX_FAILSAFE` (no RC yet) or that it is armed, since it (re)started.
    receiver_up: bool,
    armed: bool,
    /// How long the device took to arm the last time, ms, and how often it was armed.
    armed_after_ms: Option<u64>,
    armings: u64,
    /// The device's PID loop cycle as it last said it, µs.
    cycle_us: u16,
}

impl Arming {
    /// Start reading the device's status; the set points are checked against the scenario.
    /// `device`: its name; `address`: its IP address.
    pub fn new(
        options: &ArmingOptions,
        device: &str,
        address: std::net::IpAddr,
        scenario: &Scenario,
    ) -> Result<Self, String> {
        if !(options.within_s > 0.0 && options.within_s <= 3600.0) {
            return Err(format!("device `{device}`: arming within_s must be within 0..3600 s"));
        }
        for name in std::iter::once(&options.switch).chain(&options.low_until_armed) {
            if scenario.setpoint.get(name).is_none() {
                return Err(format!(
                    "device `{device}`: [arming] names the set point `{name}`, which the scenario does not give; add \
                     it under [setpoint]"
                ));
            }
        }
        Ok(Self {
            options: options.clone(),
            device: device.to_string(),
            watch: StatusWatch::start(SocketAddr::new(address, options.msp_port)),
            switch: 0,
            held: Vec::new(),
            started_ns: None,
            latest: Latest::default(),
            raised: false,
            wanted: true,
            receiver_up: false,
            armed: false,
            armed_after_ms: None,
            armings: 0,
            cycle_us: 0,
        })
    }

    /// Find the set points among those the layout was bound against (the scenario's `names`).
    pub fn bind(&mut self, names: &[String]) -> Result<(), String> {
        let find = |name: &String| {
            names.iter().position(|n| n == name).ok_or_else(|| format!("[arming] set point `{name}` not found"))
        };
        self.switch = find(&self.options.switch)?;
        self.held = self.options.low_until_armed.iter().map(find).collect::<Result<_, _>>()?;
        Ok(())
    }

    /// Whether the device's receiver is set up since it (re)started: Betaflight's SITL must not be sent anything
    /// before (an RC packet that comes earlier is taken, then its receiver set-up replaces the SITL's UDP RC link
    /// with the default receiver, and `RX_FAILSAFE` never clears; a SITL sent packets while its status still showed
    /// neither `RX_FAILSAFE` nor `CALIBRATING`, its tasks not yet running, answered once and then fell silent). Its
    /// status says `RX_FAILSAFE` once its receiver task has looked for RC and found none.
    pub fn ready(&self) -> bool {
        self.receiver_up
    }

    /// Whether this start of the device is stuck ([`STUCK_START_NS`]): it should be started again.
    pub fn stuck(&self, now_ns: u64) -> bool {
        let since_start_ns = self.started_ns.map_or(0, |started| now_ns.saturating_sub(started));
        stuck_start(self.receiver_up, since_start_ns)
    }

    /// Hold the switch and the held set points low while they must be; else they keep the values in force (the
    /// scenario's at this tick, `[[setpoint_steps]]` included).
    pub fn hold(&mut self, setpoints: &mut [f64]) {
        self.wanted = setpoints[self.switch] >= 0.5;
        if !self.raised {
            setpoints[self.switch] = 0.0;
        }
        if !self.armed {
            for &index in &self.held {
                setpoints[index] = 0.0;
            }
        }
    }

    /// Raise the switch once the flags clear, note when the device says it is armed (and when it disarmed itself);
    /// an error, naming the flags, when it has not armed in time.
    pub fn check(&mut self, now_ns: u64) -> Result<(), String> {
        // Read once a tick; what the tick's other questions ask of it (stuck, the state's events) read this copy.
        self.latest = self.watch.latest();
        self.judge(now_ns)
    }

    /// [`Self::check`] on the status read.
    fn judge(&mut self, now_ns: u64) -> Result<(), String> {
        let started = *self.started_ns.get_or_insert(now_ns);
        let Latest { status, problem, .. } = &self.latest;
        if let Some(status) = status {
            self.cycle_us = status.cycle_us;
            self.receiver_up |= receiver_up(status);
        }
        if self.armed {
            match status {
                // Disarmed in flight (its failsafe dropped it, or it landed): armed again as at its start.
                Some(s) if !s.armed => {
                    self.disarmed(now_ns);
                    return Ok(());
                }
                _ => return Ok(()),
            }
        }
        if let Some(status) = status {
            self.raised |= status.arming_disabled == 0;
            self.armed = status.armed;
        }
        if self.armed {
            self.armed_after_ms = Some(now_ns.saturating_sub(started) / 1_000_000);
            self.armings += 1;
        }
        if self.armed || !self.wanted {
            // Not wanted armed: its time starts when the scenario raises the switch.
            self.started_ns = Some(now_ns);
            return Ok(());
        }
        if now_ns.saturating_sub(started) < (self.options.within_s * 1e9) as u64 {
            return Ok(());
        }
        let why = match (status, problem) {
            (Some(status), _) => format!("its arming-disable flags: {}", flags_in_words(status.arming_disabled)),
            (None, Some(problem)) => format!("its MSP on port {} never answered: {problem}", self.options.msp_port),
            (None, None) => format!("its MSP on port {} never answered", self.options.msp_port),
        };
        Err(format!("device `{}` did not arm within {} s; {why}", self.device, self.options.within_s))
    }

    /// It said it is disarmed after it was armed: lower the switch and hold the set points low again, and time its
    /// arming from now. Its receiver stays set up (it is the same start).
    fn disarmed(&mut self, now_ns: u64) {
        (self.started_ns, self.raised, self.armed) = (Some(now_ns), false, false);
    }

    /// Whether the device has said it is armed since it was (re)started.
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// What the device last said over MSP (read every 100 ms), as [`Self::check`] last read it, for watching its
    /// state beyond arming.
    pub fn latest(&self) -> &Latest {
        &self.latest
    }

    /// The device restarted: lower the switch and the held set points, and arm it again.
    pub fn restart(&mut self, now_ns: u64) {
        self.watch.forget();
        self.latest = Latest::default();
        (self.started_ns, self.raised, self.armed, self.receiver_up) = (Some(now_ns), false, false, false);
    }

    /// Counters for the controller's report: how often it armed, how long the last arming took (ms), and the
    /// PID loop's cycle it last said (µs).
    pub fn counters(&self) -> Vec<(String, u64)> {
        let mut counters = vec![("device_armings".to_string(), self.armings)];
        counters.extend(self.armed_after_ms.map(|ms| ("device_armed_after_ms".to_string(), ms)));
        counters.push(("device_pid_cycle_us".to_string(), u64::from(self.cycle_us)));
        counters
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_receiver_is_up_once_it_says_rx_failsafe_or_armed() {
        let status = |armed, flags| Status { cycle_us: 125, armed, arming_disabled: flags, modes: u64::from(armed) };
        // BOOT_GRACE_TIME alone: its tasks have not looked for RC yet (the SITL that then fell silent).
        assert!(!receiver_up(&status(false, 1 << 9)));
        // RX_FAILSAFE ANGLE BOOT_GRACE_TIME CALIBRATING: the first status of a SITL that armed.
        assert!(receiver_up(&status(false, (1 << 2) | (1 << 8) | (1 << 9) | (1 << 12))));
        assert!(receiver_up(&status(true, 0)));
    }

    #[test]
    fn a_start_is_stuck_without_its_receiver_for_five_seconds() {
        let s = 1_000_000_000;
        assert!(stuck_start(false, 5 * s + 1));
        assert!(!stuck_start(false, 5 * s), "not before 5 s");
        assert!(!stuck_start(true, 60 * s), "its receiver is up");
    }

    const S: u64 = 1_000_000_000;

    /// Arming of quad-betaflight's `rc_arm`, holding `rc_throttle`, within 30 s, its MSP on a port nothing answers
    /// (the tests give the statuses by hand); the bound set points are `rc_arm`, `rc_throttle`.
    fn arming() -> Arming {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/quad-betaflight.toml");
        let scenario = Scenario::load(std::path::Path::new(path)).unwrap();
        let options = ArmingOptions {
            switch: "rc_arm".into(),
            low_until_armed: vec!["rc_throttle".into()],
            msp_port: 9,
            within_s: 30.0,
        };
        let mut a = Arming::new(&options, "bf", std::net::Ipv4Addr::LOCALHOST.into(), &scenario).unwrap();
        a.bind(&["rc_arm".into(), "rc_throttle".into()]).unwrap();
        a
    }

    /// Betaflight says `flags`, armed or not, at `t_ns`; the set points the device is sent then.
    fn says(a: &mut Arming, armed: bool, flags: u32, t_ns: u64) -> (Result<(), String>, [f64; 2]) {
        let status = Status { cycle_us: 125, armed, arming_disabled: flags, modes: u64::from(armed) };
        a.latest = Latest { status: Some(status), read_ns: t_ns, problem: None };
        let judged = a.judge(t_ns);
        let mut sent = [1.0, 0.5];
        a.hold(&mut sent);
        (judged, sent)
    }

    #[test]
    fn disarmed_by_its_failsafe_it_is_armed_again_with_the_switch_lowered_first() {
        let mut a = arming();
        // RX_FAILSAFE: the switch and the throttle held low; the flags clear: the switch goes up, the throttle not yet.
        assert_eq!(says(&mut a, false, 1 << 2, 0).1, [0.0, 0.0]);
        assert_eq!(says(&mut a, false, 0, S).1, [1.0, 0.0]);
        assert_eq!(says(&mut a, true, 0, 2 * S).1, [1.0, 0.5]);
        assert_eq!(a.counters()[0], ("device_armings".to_string(), 1));
        // Its failsafe drops it (FAILSAFE RX_FAILSAFE): the switch goes low again and the throttle is held.
        assert_eq!(says(&mut a, false, (1 << 1) | (1 << 2), 10 * S).1, [0.0, 0.0]);
        // The link back, its failsafe ended: ARM_SWITCH until it sees the switch low, then the flags clear.
        assert_eq!(says(&mut a, false, 1 << 28, 14 * S).1, [0.0, 0.0]);
        assert_eq!(says(&mut a, false, 0, 15 * S).1, [1.0, 0.0]);
        let (judged, sent) = says(&mut a, true, 0, 16 * S);
        assert_eq!((judged, sent), (Ok(()), [1.0, 0.5]));
        assert_eq!(a.counters()[0], ("device_armings".to_string(), 2));
        // Timed from the disarm at 10 s.
        assert_eq!(a.counters()[1], ("device_armed_after_ms".to_string(), 6000));
    }

    #[test]
    fn not_armed_again_in_time_after_a_disarm_fails_naming_its_flags_unless_the_switch_is_low() {
        let mut a = arming();
        assert_eq!(says(&mut a, false, 0, 0).0, Ok(()));
        assert_eq!(says(&mut a, true, 0, S).0, Ok(()));
        assert_eq!(says(&mut a, false, 1 << 1, 10 * S).0, Ok(()), "a disarm in flight is no failure yet");
        assert_eq!(says(&mut a, false, 1 << 1, 39 * S).0, Ok(()), "within 30 s of the disarm");
        let e = says(&mut a, false, 1 << 1, 41 * S).0.unwrap_err();
        assert_eq!(e, "device `bf` did not arm within 30 s; its arming-disable flags: FAILSAFE (failsafe is active)");
        // A scenario that lowered the switch itself does not want it armed: no failure, however long.
        let mut a = arming();
        let status = Status { cycle_us: 125, armed: false, arming_disabled: 1 << 28, modes: 0 };
        a.latest = Latest { status: Some(status), read_ns: 1, problem: None };
        let mut low = [0.0, 0.5];
        for t_s in [0, 20, 40, 60] {
            a.hold(&mut low);
            assert_eq!(a.judge(t_s * S), Ok(()), "at {t_s} s");
        }
    }
}
