//! The process faults of a run's plan (kill, term, stop), carried out by `silrig run` with signals at their
//! simulated time: when the plant has published the tick of that time, read from its tick beacon
//! ([`silrig_rig::tick_beacon`]; a plant that does not use our library has none, and then the time counts on the
//! wall clock from its tick 0, read from its `ticking` event). Their follow-ups: SIGCONT after a stop (its length is
//! wall time: a stopped plant's simulated time stands still), a restart after a kill or term. Loop and plant-model
//! faults are the processes' own business, and so are a device's (its program is the controller process's child).
//! The plant-side bridge of a run across hosts takes process faults too.

use super::child::ChildProcess;
use super::remote::RemoteBridge;
use super::supervision::Supervisor;
use silrig_flight::fault::{Fault, FaultAction};
use silrig_rig::events::EventLog;
use silrig_rig::tick_beacon::TickBeacon;
use silrig_wire::ipc::RunId;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A process fault of the plan and its progress.
struct PlannedFault {
    fault: Fault,
    injected: bool,
    /// When to send SIGCONT (stop faults).
    follow_up: Option<Instant>,
}

/// The plan's process faults, in plan order.
pub(crate) struct FaultSchedule {
    plan: Vec<PlannedFault>,
    out: PathBuf,
    events: EventLog,
    /// CLOCK_MONOTONIC of the plant's tick 0, once it has started ticking.
    t0_ns: Option<u64>,
    run: RunId,
    dt_s: f64,
    /// The plant's newest tick, once it has created the beacon.
    beacon: Option<TickBeacon>,
}

impl FaultSchedule {
    pub(crate) fn new(faults: &[Fault], out: &Path, events: EventLog, run: &RunId, dt_s: f64) -> Self {
        let plan = faults
            .iter()
            .filter(|f| f.target().signalled_by_launcher(f.action()))
            .map(|f| PlannedFault { fault: f.clone(), injected: false, follow_up: None })
            .collect();
        Self { plan, out: out.to_path_buf(), events, t0_ns: None, run: run.clone(), dt_s, beacon: None }
    }

    /// Inject the faults that are due and send the SIGCONTs that are due.
    pub(crate) fn poll(&mut self, sup: &mut Supervisor, mut bridge: Option<&mut RemoteBridge>) -> std::io::Result<()> {
        if self.plan.is_empty() {
            return Ok(());
        }
        if self.t0_ns.is_none() {
            self.t0_ns = super::fault_report::plant_t0_ns(&self.out);
        }
        let Some(t0) = self.t0_ns else { return Ok(()) };
        if self.beacon.is_none() {
            self.beacon = TickBeacon::open(&self.run).ok();
        }
        let now_ns = silrig_wire::clock::monotonic_ns();
        let sim_s = self.beacon.as_ref().map(|b| b.newest().map_or(-1.0, |tick| tick as f64 * self.dt_s));
        for pf in self.plan.iter_mut() {
            let due = match sim_s {
                // The tick at or after the fault's time is out (a time between two ticks acts at the later one).
                Some(sim_s) => sim_s >= pf.fault.at_s - 1e-9 * self.dt_s,
                None => now_ns >= t0 + (pf.fault.at_s * 1e9) as u64,
            };
            if !pf.injected && due {
                pf.injected = true;
                inject(pf, sup, bridge.as_deref_mut(), &self.events)?;
            }
            if let Some(at) = pf.follow_up
                && Instant::now() >= at
            {
                pf.follow_up = None;
                if let Some(p) = target_process(&pf.fault, sup, bridge.as_deref_mut()) {
                    p.signal(libc::SIGCONT);
                    let detail = format!("SIGCONT to {} (pid {})", pf.fault.target(), p.pid());
                    self.events.emit(None, "fault-ended", detail);
                }
            }
        }
        Ok(())
    }

    /// A process left stopped by an interrupted plan must be continued to hear SIGTERM.
    pub(crate) fn release_stopped(&self, sup: &mut Supervisor, mut bridge: Option<&mut RemoteBridge>) {
        for pf in self.plan.iter().filter(|pf| pf.follow_up.is_some()) {
            if let Some(p) = target_process(&pf.fault, sup, bridge.as_deref_mut()) {
                p.signal(libc::SIGCONT);
            }
        }
    }
}

/// The process the fault targets: a rig process, or the plant-side bridge (None in a run without one).
fn target_process<'a>(
    f: &Fault,
    sup: &'a mut Supervisor,
    bridge: Option<&'a mut RemoteBridge>,
) -> Option<&'a mut ChildProcess> {
    match f.target().role() {
        Some(role) => Some(&mut sup.process_mut(role).process),
        None => bridge.map(|b| b.child_mut()),
    }
}

/// Send the fault's signal to its target, or skip it (with a warning and an event) when the target is not running.
fn inject(
    pf: &mut PlannedFault,
    sup: &mut Supervisor,
    mut bridge: Option<&mut RemoteBridge>,
    events: &EventLog,
) -> std::io::Result<()> {
    let f = &pf.fault;
    let target = f.target();
    let running = match target_process(f, sup, bridge.as_deref_mut()) {
        Some(p) => p.poll()?.is_none(),
        None => false,
    };
    if !running {
        eprintln!("silrig run: warning: {} skipped: {target} is not running", f.describe());
        events.emit(None, "fault-skipped", format!("{}: {target} is not running", f.describe()));
        return Ok(());
    }
    let (signal, name) = match f.action() {
        FaultAction::Kill => (libc::SIGKILL, "SIGKILL"),
        FaultAction::Term => (libc::SIGTERM, "SIGTERM"),
        _ => (libc::SIGSTOP, "SIGSTOP"),
    };
    let p = target_process(f, sup, bridge.as_deref_mut()).expect("running");
    events.emit(None, "fault-injected", format!("{} ({name} to pid {})", f.describe(), p.pid()));
    p.signal(signal);
    if f.action() == FaultAction::Stop {
        pf.follow_up = Some(Instant::now() + Duration::from_secs_f64(f.duration_s.unwrap_or(0.0)));
        return Ok(());
    }
    let restart_at = f.restart_after_s.map(|r| Instant::now() + Duration::from_secs_f64(r));
    match (target.role(), bridge) {
        (Some(role), _) => {
            let p = sup.process_mut(role);
            p.planned_exit = true;
            if restart_at.is_some() {
                p.restart_at = restart_at;
            }
        }
        (None, Some(b)) => b.planned_death(restart_at),
        (None, None) => {}
    }
    Ok(())
}
