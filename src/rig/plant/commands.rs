//! The plant's commands, tick by tick: gathering the controller's answer to the tick just published (polling,
//! then blocking, up to the budget), checking and timing each command, choosing the one this tick applies (same-tick
//! or next-tick), and the watchdog that holds the last command and then flies the failsafe while the controller is
//! silent.

use super::{
    IPC_CONTROLLER_TO_PLANT, LOCKSTEP_PEER_TIMEOUT, PUBLISH_STAMPS, PlantLoop, PlantPorts, SENSE_TO_ACTUATE,
    SENSE_TO_ACTUATE_STEADY,
};
use crate::signals;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::Received;
use silrig_wire::wire::{self, CommandSample};

impl PlantLoop {
    /// Wait for the answer to this tick whichever timing applies: next-tick applies it one tick later, but
    /// receiving it now measures the transport honestly, and lockstep never runs ahead of the controller.
    /// Realtime: poll for `spin_ns`, then block, up to the budget; lockstep: up to the peer timeout.
    pub(super) fn gather_commands(&mut self, ports: &PlantPorts, t_send_ns: u64) -> anyhow::Result<()> {
        let wait_until =
            t_send_ns + if self.realtime { self.budget_ns } else { LOCKSTEP_PEER_TIMEOUT.as_nanos() as u64 };
        // Wake-ups are consumed only after a blocking wait: consuming them while a notification lands can lose the
        // wake-up for good (iceoryx2 0.10), and the next blocking wait would then sleep to its timeout.
        let mut woken = false;
        loop {
            self.take_commands(ports, woken)?;
            if self.received.iter().any(|c| c.answers_tick == self.sim_tick) || signals::termination_requested() {
                return Ok(());
            }
            let now = monotonic_ns();
            if now < t_send_ns + self.spin_ns.min(self.budget_ns) {
                match self.realtime {
                    true => std::hint::spin_loop(),
                    // Two vCPUs for three processes: a look that yields lets the logger have its turn.
                    false => std::thread::yield_now(),
                }
                continue;
            }
            if now >= wait_until {
                anyhow::ensure!(
                    self.realtime,
                    "lockstep: no command for tick {} within {LOCKSTEP_PEER_TIMEOUT:?}",
                    self.sim_tick
                );
                return Ok(());
            }
            // EINTR (SIGSTOP/SIGCONT, SIGTERM) just ends this wait early; the loop looks again.
            ports.commands.wait_readable_until(wait_until);
            woken = true;
        }
    }

    /// Drain the command queue, and its wake-ups with `consume_wakeups`: count, time and keep the newest valid
    /// commands.
    fn take_commands(&mut self, ports: &PlantPorts, consume_wakeups: bool) -> anyhow::Result<()> {
        let tick = self.sim_tick;
        let steady_from = silrig_wire::timing::WARM_UP_NS / self.scenario.timing.period_ns();
        let on_command = |r: &Received<CommandSample>| {
            let invalid = match &r.invalid {
                Some(e) => Some(e.to_string()),
                None if r.sample.flags & wire::FLAG_COMMAND_REFUSED != 0 => None,
                None => wire::check_command(&self.signals, &r.sample).err(),
            };
            if let Some(why) = invalid {
                if self.rec.counters.get("commands_invalid").is_none_or(|n| *n == 0) {
                    self.events.emit(Some(tick), "command-invalid", format!("{why}; the plant holds its last command"));
                }
                self.rec.count("commands_invalid", 1);
                return;
            }
            self.rec.count("commands_received", 1);
            let epoch = r.sample.header.epoch;
            if self.command_epoch.is_some_and(|e| e != epoch) {
                self.events.emit(Some(tick), "controller-restarted", "commands from a new controller epoch");
            }
            self.command_epoch = Some(epoch);
            self.rec.record(IPC_CONTROLLER_TO_PLANT, r.age_ns() as i64);
            let answers = r.sample.answers_tick;
            if answers <= tick && tick - answers < PUBLISH_STAMPS as u64 {
                let sent = self.publish_ns[(answers % PUBLISH_STAMPS as u64) as usize];
                self.rec.record(SENSE_TO_ACTUATE, r.t_recv_ns as i64 - sent as i64);
                if answers >= steady_from {
                    self.rec.record(SENSE_TO_ACTUATE_STEADY, r.t_recv_ns as i64 - sent as i64);
                }
            }
            if self.received.len() == 8 {
                self.received.pop_front();
            }
            self.received.push_back(r.sample);
        };
        ports.commands.take(consume_wakeups, on_command)?;
        Ok(())
    }

    /// Apply the command this tick wants (the answer to this tick, same-tick, or to the previous one, next-tick);
    /// returns true when it is missing and the last command is held (a miss).
    pub(super) fn choose_command(&mut self) -> bool {
        let target = self.sim_tick.checked_sub(self.scenario.timing.command_delay_ticks());
        let Some(target) = target else { return false };
        let Some(fresh) = self.received.iter().find(|c| c.answers_tick == target).copied() else {
            self.rec.count("command_misses", 1);
            return true;
        };
        if fresh.flags & wire::FLAG_COMMAND_REFUSED != 0 {
            // The controller's session refused its command (its event says why): hold, as for a missing one.
            self.rec.count("command_misses", 1);
            self.rec.count("commands_refused_held", 1);
            return true;
        }
        self.applied.copy_from_slice(fresh.inputs());
        self.applied_answers = Some(target);
        let w = &mut self.watchdog;
        w.last_fresh_ns = monotonic_ns();
        w.last_fresh_tick = self.sim_tick;
        if w.stale || w.in_failsafe {
            let how = if w.in_failsafe { "failsafe released, " } else { "" };
            self.events.emit(Some(self.sim_tick), "controller-recovered", format!("{how}commands resumed"));
            w.stale = false;
            w.in_failsafe = false;
        }
        false
    }

    /// A held command: the controller is stale after a few periods without a fresh command, and after the hold
    /// the plant flies the failsafe (its announced hold values) until commands return.
    pub(super) fn watch_controller(&mut self) {
        let tick = self.sim_tick;
        let w = &mut self.watchdog;
        let silent_ns = monotonic_ns().saturating_sub(w.last_fresh_ns);
        if !w.stale && silent_ns >= w.stale_after_ns {
            w.stale = true;
            self.events.emit(Some(tick), "controller-stale", format!("no command for {} ms", silent_ns / 1_000_000));
        }
        if !w.in_failsafe && silent_ns >= w.hold_ns {
            w.in_failsafe = true;
            let hold: Vec<String> = (self.signals.inputs.iter().zip(&w.failsafe))
                .map(|(i, v)| format!("{} {v:.3} {}", i.name, i.unit))
                .collect();
            let detail =
                format!("{} ticks after the last fresh command; holding {}", tick - w.last_fresh_tick, hold.join(", "));
            self.events.emit(Some(tick), "failsafe-engaged", detail);
        }
        if w.in_failsafe {
            self.applied.copy_from_slice(&w.failsafe);
            self.rec.count("failsafe_ticks", 1);
        }
    }
}
