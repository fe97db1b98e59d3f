//! The device faults of the run's plan (`device:cut`, `device:kill`, [`silrig_flight::fault`]), carried out by the
//! controller process that flies the device, since the device's link and program are its own: a cut packet is not
//! sent during its window (Betaflight's RC: its receiver loses the link, and its own failsafe should engage), a kill
//! is SIGKILL to the device's program (the supervision starts it again when it sees it dead, and the arming arms it
//! again). Each is told as the run's events (`fault-injected`, `fault-ended`) at the tick that reached its time.

use silrig_flight::fault::{Fault, FaultAction, FaultTarget};
use silrig_rig::events::EventLog;

/// One device fault of the plan and its progress.
struct Planned {
    fault: Fault,
    /// cut: the index of the packet (among those sent to the device) it cuts.
    packet: usize,
    injected: bool,
    ended: bool,
}

/// What the device faults ask of this tick.
pub struct DeviceFaults {
    planned: Vec<Planned>,
    /// Per packet sent to the device: whether it is cut this tick.
    cut: Vec<bool>,
    events: EventLog,
}

impl DeviceFaults {
    /// The plan's device faults for device `device`, whose packets to it are named `packets`; a cut naming another
    /// packet, or a kill of a device whose program the rig does not run (`has_program`), is refused naming it.
    pub fn new(
        plan: &[Fault],
        device: &str,
        packets: &[&str],
        has_program: bool,
        events: EventLog,
    ) -> Result<Self, String> {
        let mut planned = Vec::new();
        for f in plan.iter().filter(|f| f.target() == FaultTarget::Device) {
            let packet = match (f.action(), f.packet.as_deref()) {
                (FaultAction::Cut, Some(name)) => packets.iter().position(|p| *p == name).ok_or_else(|| {
                    format!(
                        "the fault `{}` cuts packet `{name}`, which device `{device}` is not sent; its layout sends {}",
                        f.describe(),
                        packets.join(", ")
                    )
                })?,
                (FaultAction::Kill, _) if !has_program => {
                    return Err(format!(
                        "the fault `{}` kills device `{device}`'s program, but the rig does not run it: give the \
                         layout a [process] (how to start it)",
                        f.describe()
                    ));
                }
                _ => 0,
            };
            planned.push(Planned { fault: f.clone(), packet, injected: false, ended: false });
        }
        Ok(Self { planned, cut: vec![false; packets.len()], events })
    }

    /// Move the plan to simulated time `t_s` (tick `tick`): which packets are cut now, each window's start and end
    /// told as an event; whether a kill is due now (its event told, with the program's `pid`).
    pub fn at(&mut self, t_s: f64, tick: u64, pid: Option<u32>) -> bool {
        self.cut.fill(false);
        let mut kill = false;
        for p in &mut self.planned {
            let active = p.fault.active_at(t_s);
            if active && !p.injected {
                p.injected = true;
                let how = match p.fault.action() {
                    FaultAction::Kill => {
                        kill = true;
                        format!(" (SIGKILL to pid {})", pid.unwrap_or(0))
                    }
                    _ => String::new(),
                };
                self.events.emit(Some(tick), "fault-injected", format!("{}{how}", p.fault.describe()));
            }
            let cutting = p.fault.action() == FaultAction::Cut && active;
            self.cut[p.packet] |= cutting;
            if p.injected && !active && !p.ended && p.fault.action() == FaultAction::Cut {
                p.ended = true;
                self.events.emit(Some(tick), "fault-ended", format!("{}: sent again", p.fault.describe()));
            }
        }
        kill
    }

    /// Whether packet `k` (among those sent to the device) is cut this tick.
    pub fn is_cut(&self, k: usize) -> bool {
        self.cut[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_flight::fault::parse_fault_flag;

    fn dir(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("silrig-device-faults-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_cut_covers_its_window_and_a_kill_comes_once() {
        let out = dir("window");
        let plan = [
            parse_fault_flag("device:cut@1s,packet=rc,for=0.5s").unwrap(),
            parse_fault_flag("device:kill@2s").unwrap(),
            parse_fault_flag("controller:kill@3s").unwrap(),
        ];
        let mut f = DeviceFaults::new(&plan, "bf", &["fdm", "rc"], true, EventLog::new(&out, "controller")).unwrap();
        assert!(!f.at(0.999, 999, Some(7)) && !f.is_cut(1));
        assert!(!f.at(1.0, 1000, Some(7)) && f.is_cut(1) && !f.is_cut(0));
        assert!(!f.at(1.499, 1499, Some(7)) && f.is_cut(1));
        assert!(!f.at(1.5, 1500, Some(7)) && !f.is_cut(1));
        assert!(f.at(2.0, 2000, Some(7)));
        assert!(!f.at(2.001, 2001, Some(7)));
        let events = silrig_rig::events::read_events(&out);
        let told: Vec<(&str, &str, Option<u64>)> =
            events.iter().map(|e| (e.kind.as_str(), e.detail.as_str(), e.tick)).collect();
        assert_eq!(
            told,
            [
                ("fault-injected", "device cut at 1 s, for 0.5 s, packet rc", Some(1000)),
                ("fault-ended", "device cut at 1 s, for 0.5 s, packet rc: sent again", Some(1500)),
                ("fault-injected", "device kill at 2 s (SIGKILL to pid 7)", Some(2000)),
            ]
        );
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn an_unknown_packet_or_a_program_the_rig_does_not_run_is_refused() {
        let out = dir("refused");
        let cut = [parse_fault_flag("device:cut@1s,packet=sticks,for=1s").unwrap()];
        let e = DeviceFaults::new(&cut, "bf", &["fdm", "rc"], true, EventLog::new(&out, "controller")).err().unwrap();
        assert!(e.contains("cuts packet `sticks`, which device `bf` is not sent; its layout sends fdm, rc"), "{e}");
        let kill = [parse_fault_flag("device:kill@1s").unwrap()];
        let e = DeviceFaults::new(&kill, "bf", &["fdm"], false, EventLog::new(&out, "controller")).err().unwrap();
        assert!(e.contains("give the layout a [process]"), "{e}");
        std::fs::remove_dir_all(&out).unwrap();
    }
}
