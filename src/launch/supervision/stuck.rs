//! A restarted controller or logger that joined the run but never takes a sample of the plant flying beside it:
//! started again. iceoryx2 0.10 sometimes never connects a subscriber that joins a publisher already running
//! (iceoryx2 #129, open: "the ports are sometimes not informed about new participants"; another port joining
//! mends it). Two one-hour soaks saw it in 3 of 137 restarts of a controller or logger: in one, the restarted
//! logger wrote no row and the restarted controller sent no command for 17 s, while the plant flew its failsafe
//! surfaces until it left the model's envelope. A restart's first life is not watched: every first life joins before the plant publishes.
//!
//! Progress is read from the status files every process writes once a second (`silrig top`'s): the restarted
//! process is flowing once its own status names its pid and a tick after the plant's at the restart. It is stuck
//! when it has a node of the run (so a slow start, an interpreter importing its modules, is never taken for one)
//! and the plant has flown [`STUCK_AFTER`] since, without it.

use super::Supervisor;
use crate::joining;
use silrig_flight::role::Role;
use silrig_rig::status::read_statuses;
use std::time::{Duration, Instant};

/// How long the plant must fly beside a restarted process that takes none of its samples before it is started
/// again: past the longest stop or delay the soak's fault plan gives a process (1 s), short of what the failsafe
/// surfaces fly safely.
pub(crate) const STUCK_AFTER: Duration = Duration::from_secs(3);

/// At most this many renewals a role and run: a process that never flows after them is left to the run's verdict.
const MAX_RENEWALS: u32 = 3;

/// How often the status files are read.
const LOOK_EVERY: Duration = Duration::from_millis(250);

/// The restarted processes watched, and the renewals made.
#[derive(Default)]
pub(crate) struct StuckWatch {
    watched: Vec<Watched>,
    renewals: Vec<(Role, u32)>,
    /// A renewal's kill, not yet reaped: its pid (its end is the launcher's, not the fault plan's).
    renewing: Vec<u32>,
    last_look: Option<Instant>,
}

impl StuckWatch {
    /// Whether `pid`'s end, reaped now, was a renewal's kill (said once: the pid may be another process's later).
    pub(super) fn take_renewing(&mut self, pid: u32) -> bool {
        let before = self.renewing.len();
        self.renewing.retain(|&p| p != pid);
        self.renewing.len() < before
    }
}

struct Watched {
    role: Role,
    pid: u32,
    /// The plant's newest tick when it was restarted (from the plant's status).
    plant_tick: Option<u64>,
    /// Since when the plant has flown beside it without it (reset while the plant does not fly).
    since: Instant,
}

impl Supervisor {
    /// Watch a controller or logger just restarted as `pid` until it takes the plant's samples.
    pub(super) fn watch_restart(&mut self, role: Role, pid: u32) {
        if !matches!(role, Role::Controller | Role::Logger) {
            return;
        }
        let plant_tick = read_statuses(&self.args.run_id).iter().find(|s| s.process == "plant").map(|s| s.tick);
        self.stuck.watched.retain(|w| w.role != role);
        self.stuck.watched.push(Watched { role, pid, plant_tick, since: Instant::now() });
    }

    /// Start again a watched process that is stuck ([`StuckWatch`]), saying so in the run's events.
    pub(crate) fn renew_stuck(&mut self) {
        if self.stuck.watched.is_empty() || self.stuck.last_look.is_some_and(|t| t.elapsed() < LOOK_EVERY) {
            return;
        }
        self.stuck.last_look = Some(Instant::now());
        let statuses = read_statuses(&self.args.run_id);
        let tick_of = |name: &str, pid: Option<u32>| {
            statuses.iter().find(|s| s.process == name && pid.is_none_or(|p| s.pid == p)).map(|s| s.tick)
        };
        let plant_now = tick_of("plant", None);
        let nodes = joining::nodes(&self.args.run_id);
        let mut stuck = Vec::new();
        self.stuck.watched.retain_mut(|w| {
            let Some(p) = self.processes.iter().find(|p| p.role == w.role) else { return false };
            if p.process.pid() != w.pid || p.process.has_ended() {
                return false;
            }
            let flowing = tick_of(w.role.label(), Some(w.pid)).is_some_and(|t| w.plant_tick.is_none_or(|p| t > p));
            if flowing {
                return false;
            }
            let plant_flies = plant_now.is_some_and(|now| w.plant_tick.is_none_or(|then| now > then));
            if !plant_flies || !joining::has_joined(&p.process, &nodes) {
                w.since = Instant::now();
                return true;
            }
            if w.since.elapsed() < STUCK_AFTER {
                return true;
            }
            stuck.push((w.role, w.pid, w.plant_tick.unwrap_or(0), plant_now.unwrap_or(0)));
            false
        });
        for (role, pid, from_tick, to_tick) in stuck {
            self.renew(role, pid, from_tick, to_tick);
        }
    }

    fn renew(&mut self, role: Role, pid: u32, from_tick: u64, to_tick: u64) {
        let index = match self.stuck.renewals.iter().position(|(r, _)| *r == role) {
            Some(i) => i,
            None => {
                self.stuck.renewals.push((role, 0));
                self.stuck.renewals.len() - 1
            }
        };
        if self.stuck.renewals[index].1 >= MAX_RENEWALS {
            return;
        }
        self.stuck.renewals[index].1 += 1;
        let detail = format!(
            "{role} pid {pid}, restarted, joined the run but took no sample while the plant flew ticks {from_tick}..\
             {to_tick} ({:.0} s): a subscriber that joins a running publisher is sometimes never connected (iceoryx2 \
             #129); killed and started again",
            STUCK_AFTER.as_secs_f64()
        );
        eprintln!("silrig run: {detail}");
        self.events.emit(None, "process-renewed", detail);
        self.stuck.renewing.push(pid);
        let p = self.process_mut(role);
        p.planned_exit = true;
        p.restart_at = Some(Instant::now());
        p.process.signal(libc::SIGKILL);
    }
}
