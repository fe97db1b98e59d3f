//! The plant's side as a controller's session sees it: waiting for the plant's announcement and checking a
//! restarted plant's against it, handing out the newest plant sample (looking near the plant's deadline in
//! realtime, for a while before blocking in lockstep; older samples skipped and counted), what each sample says
//! about the plant (a join, a restart, silence), and giving up when no rig answers.

use super::{
    BUMPLESS_BLEND_S, ControllerSession, IPC_PLANT_TO_CONTROLLER, Next, Pending, Resumed, SAMPLE_LOOK_LEAD_NS,
    SessionError, StopReason,
};
use crate::plant::LOCKSTEP_LOOK_NS;
use crate::signals;
use silrig_flight::signals::PlantSignals;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::{self, WaitOutcome};
use silrig_wire::wire::{self, MAX_INPUTS, PlantSample};
use std::time::Duration;

impl ControllerSession {
    /// Block until the next plant sample the controller computes for (the newest one waiting: after a stall,
    /// older ones are skipped and counted), or until the session should stop. A controller slower than the plant
    /// (`timing.controller_every_ticks`) sees only its own ticks: the session answers the plant's ticks between
    /// with the controller's last answer. While the plant is silent the session idles and says so once; with no
    /// sample at all within twice `--startup-timeout-s` of opening, it gives up ([`SessionError::NoRig`]).
    pub fn next_sample(&mut self) -> Result<Next, SessionError> {
        loop {
            let next = self.next_plant_sample()?;
            match &next {
                Next::Sample(sample) if self.repeat_last_answer(sample.header.tick)? => continue,
                _ => return Ok(next),
            }
        }
    }

    /// The next plant sample to answer, whoever computes its answer.
    fn next_plant_sample(&mut self) -> Result<Next, SessionError> {
        if self.pending.take().is_some() {
            self.rec.count("samples_unanswered", 1);
        }
        if !self.wait_for_plant()? {
            return Ok(self.stop(StopReason::TerminationRequested));
        }
        if let Some(deadline_ns) = self.next_deadline_ns.take()
            && let Some(sample) = self.look_near_deadline(deadline_ns)?
        {
            return Ok(Next::Sample(sample));
        }
        if let Some(sample) = self.look_lockstep()? {
            return Ok(Next::Sample(sample));
        }
        // Every sample waiting is taken at each wake-up, so waiting first costs nothing: a sample that came since
        // has left a wake-up behind.
        loop {
            if signals::termination_requested() {
                return Ok(self.stop(StopReason::TerminationRequested));
            }
            if self.samples.stats().finished_notices > 0 || self.plant_ended {
                return Ok(self.stop(StopReason::RunEnded));
            }
            match self.samples.wait(self.stale_after)? {
                WaitOutcome::Notified => {
                    if let Some(sample) = self.take_newest()? {
                        return Ok(Next::Sample(sample));
                    }
                }
                WaitOutcome::Interrupted => self.rec.count("interrupted_waits", 1),
                WaitOutcome::TimedOut => {
                    // A sample that came without its wake-up (a lost notification) is taken here, at the latest a
                    // stale deadline after it, instead of never.
                    if let Some(sample) = self.take_newest()? {
                        if self.rec.counters.get("samples_without_wakeup").is_none_or(|n| *n == 0) {
                            let detail = "a plant sample was waiting without its wake-up; taken at the deadline";
                            self.events.emit(Some(sample.header.tick), "sample-without-wakeup", detail);
                        }
                        self.rec.count("samples_without_wakeup", 1);
                        return Ok(Next::Sample(sample));
                    }
                    self.on_plant_silent()?
                }
            }
        }
    }

    /// Realtime: block until shortly before the plant's next deadline (a sample that comes earlier, after a stall
    /// or a restart, is taken at once), then look for it again and again until `sample_poll_ns` past the deadline.
    /// A controller that blocks until the sample's notification pays an idle vCPU's wake-up on every tick (about
    /// 90 µs p50, 320 µs p99 on this kind of VM); one already awake takes the sample within a few µs. Costs at most
    /// `SAMPLE_LOOK_LEAD_NS` + `sample_poll_ns` of CPU a tick; `None` leaves the rest to the blocking wait.
    fn look_near_deadline(&mut self, deadline_ns: u64) -> Result<Option<PlantSample>, SessionError> {
        let look_from = deadline_ns.saturating_sub(SAMPLE_LOOK_LEAD_NS);
        loop {
            let now = monotonic_ns();
            if now >= look_from || signals::termination_requested() {
                break;
            }
            match self.samples.wait(Duration::from_nanos(look_from - now))? {
                WaitOutcome::Notified => {
                    if let Some(sample) = self.take_newest()? {
                        return Ok(Some(sample));
                    }
                }
                WaitOutcome::Interrupted => return Ok(None),
                WaitOutcome::TimedOut => break,
            }
        }
        self.look_until(deadline_ns + self.sample_poll_ns, false)
    }

    /// Look at the sample queue again and again until `until_ns`, spinning or (`yield_cpu`) yielding between looks.
    /// The queue only: consuming wake-ups while a notification lands can lose the wake-up for good.
    fn look_until(&mut self, until_ns: u64, yield_cpu: bool) -> Result<Option<PlantSample>, SessionError> {
        while monotonic_ns() < until_ns {
            if signals::termination_requested() || self.plant_ended {
                return Ok(None);
            }
            if let Some(sample) = self.take_newest_from(false)? {
                return Ok(Some(sample));
            }
            match yield_cpu {
                true => std::thread::yield_now(),
                false => std::hint::spin_loop(),
            }
        }
        Ok(None)
    }

    /// Lockstep: look for the next sample again and again, yielding the CPU between looks, for up to
    /// [`LOCKSTEP_LOOK_NS`] before blocking. The plant's step takes a few µs: a controller still on its CPU takes its
    /// sample then, where one asleep pays an idle vCPU's wake-up (tens of µs on this kind of VM) every tick.
    fn look_lockstep(&mut self) -> Result<Option<PlantSample>, SessionError> {
        if !self.lockstep {
            return Ok(None);
        }
        self.look_until(monotonic_ns() + LOCKSTEP_LOOK_NS, true)
    }

    /// The plant's signals as it announced them, waiting for the announcement if it has not come yet (as long as
    /// [`Self::next_sample`] waits for a first sample). A controller looks up the outputs it reads and the inputs it
    /// commands here, by name ([`PlantSignals::output`], [`PlantSignals::input`]).
    pub fn plant(&mut self) -> Result<&PlantSignals, SessionError> {
        if !self.wait_for_plant()? {
            return Err(SessionError::Setup("terminated by signal before the plant announced its signals".into()));
        }
        Ok(self.plant.as_ref().expect("announced"))
    }

    /// Wait until the plant has announced itself; false when a stop request came first.
    fn wait_for_plant(&mut self) -> Result<bool, SessionError> {
        loop {
            self.take_announcements()?;
            if self.plant.is_some() {
                return Ok(true);
            }
            if signals::termination_requested() {
                return Ok(false);
            }
            self.give_up_without_rig()?;
            // The announcement reaches a late subscriber from the stream's history, which wakes no listener.
            let waited_ns = monotonic_ns() - self.opened_ns;
            std::thread::sleep(silrig_wire::clock::join_look_pause(waited_ns, Duration::from_millis(2)));
        }
    }

    /// Take the plant's announcements: the first says what the plant is; a later plant epoch (a restart) must say
    /// the same, since this controller found its signals by name in the first.
    fn take_announcements(&mut self) -> Result<(), SessionError> {
        let mut announced = Vec::new();
        // Nothing waits on this listener, so its wake-ups are left unconsumed: taking them is a `recvfrom` at every
        // look of the lockstep and realtime polls, and a listener left notified costs the plant no `sendto` either.
        self.plant_info.receive_queued(|r| announced.push(*r))?;
        for r in announced {
            let signals = r
                .sample
                .signals()
                .map_err(|e| SessionError::Plant(format!("the plant's announcement is refused: {e}")))?;
            if let Some(e) = r.invalid {
                return Err(SessionError::Plant(format!("the plant's announcement is refused: {e}")));
            }
            match &self.plant {
                None => self.plant = Some(signals),
                Some(known) if *known != signals => {
                    return Err(SessionError::Plant(format!(
                        "a restarted plant (epoch {}) announces plant {} with other signals than plant {} this \
                         controller started with",
                        r.sample.header.epoch, signals.plant, known.plant
                    )));
                }
                Some(_) => {}
            }
        }
        Ok(())
    }

    /// Before any sample: give up after twice the startup timeout (no rig runs with this run id).
    fn give_up_without_rig(&mut self) -> Result<(), SessionError> {
        let waited_s = (monotonic_ns() - self.opened_ns) as f64 / 1e9;
        let limit_s = 2.0 * self.args.options.startup_timeout_s;
        if waited_s > limit_s {
            self.no_rig = true;
            return Err(SessionError::NoRig { run: self.args.run_id.to_string(), waited_s: limit_s });
        }
        Ok(())
    }

    fn stop(&mut self, reason: StopReason) -> Next {
        let ended = match reason {
            StopReason::TerminationRequested => "terminated by signal",
            StopReason::RunEnded => "completed",
        };
        self.ended.get_or_insert_with(|| ended.into());
        Next::Stop(reason)
    }

    /// Take what waits; hand out the newest valid sample of a tick not handed out yet.
    fn take_newest(&mut self) -> Result<Option<PlantSample>, SessionError> {
        self.take_newest_from(true)
    }

    /// [`Self::take_newest`]; with `consume_wakeups` false the wake-ups are left to the next wait (see
    /// [`silrig_wire::ipc::StreamSubscriber::receive_queued`]).
    fn take_newest_from(&mut self, consume_wakeups: bool) -> Result<Option<PlantSample>, SessionError> {
        self.take_announcements()?;
        let mut newest = None;
        let mut fresh = 0u64;
        let mut invalid = 0u64;
        let mut ended = false;
        let mut on_sample = |r: &ipc::Received<PlantSample>| {
            if r.invalid.is_some() {
                invalid += 1;
            } else if r.sample.flags & wire::FLAG_END_OF_RUN != 0 {
                // The plant's last word: nothing to answer (it repeats a tick already flown).
                ended = true;
            } else {
                fresh += 1;
                newest = Some(*r);
            }
        };
        self.samples.take(consume_wakeups, &mut on_sample)?;
        self.plant_ended |= ended;
        // Counted only when there is something to count: this runs at every look, and a counter is a lookup by name.
        if invalid > 0 {
            self.rec.count("samples_invalid", invalid);
        }
        // After a stall several samples wait; acting on stale ones would only delay the newest.
        if fresh > 1 {
            self.rec.count("samples_skipped", fresh - 1);
        }
        let Some(r) = newest else { return Ok(None) };
        let h = r.sample.header;
        if self.last_tick.is_some_and(|(epoch, tick)| epoch == h.epoch && tick >= h.tick) {
            return Ok(None);
        }
        if self.last_tick.is_none() {
            self.announcer.send(h.tick, &self.info)?;
        }
        self.note_plant(h.epoch, h.tick);
        self.rec.record(IPC_PLANT_TO_CONTROLLER, r.age_ns() as i64);
        let mut held = [f64::NAN; MAX_INPUTS];
        let plant = self.plant.as_ref().expect("announced before any sample is taken");
        for (slot, input) in held.iter_mut().zip(&plant.inputs) {
            *slot = input.held_output.and_then(|o| r.sample.outputs().get(o).copied()).unwrap_or(f64::NAN);
        }
        self.pending = Some(Pending { tick: h.tick, held, delivered_ns: monotonic_ns() });
        if self.sample_poll_ns > 0 {
            // The plant publishes right after it wakes for its tick's deadline: the next deadline is a period after
            // this one, which is the send time less the wake-up's lateness.
            let deadline_ns = h.t_send_ns.saturating_add_signed(-r.sample.wake_lateness_ns);
            self.next_deadline_ns = Some(deadline_ns + self.scenario.timing.period_ns());
        }
        Ok(Some(r.sample))
    }

    /// What this sample says about the plant: a first sample past tick 0 (we joined a flying plant: blend), a new
    /// plant epoch (it restarted), samples back after silence.
    fn note_plant(&mut self, epoch: u64, tick: u64) {
        match self.last_tick {
            None if tick > 0 => {
                self.blend = Some(tick);
                let state = match &self.resumed {
                    Resumed::Fresh => "fresh state".to_string(),
                    Resumed::Checkpoint => "checkpointed state".to_string(),
                    Resumed::Rejected(why) => format!("fresh state (its checkpoint was rejected: {why})"),
                    Resumed::Unconfirmed => {
                        "a checkpoint was offered; the controller did not say whether it used it".to_string()
                    }
                };
                let detail = format!("plant already at tick {tick}: {state}, {BUMPLESS_BLEND_S} s bumpless blend");
                self.events.emit(Some(tick), "controller-joined", detail);
            }
            Some((last_epoch, _)) if last_epoch != epoch => {
                self.events.emit(Some(tick), "plant-restarted", "samples from a new plant epoch");
            }
            _ => {}
        }
        if self.plant_stale {
            self.plant_stale = false;
            self.events.emit(Some(tick), "plant-recovered", "samples resumed");
        }
        self.last_tick = Some((epoch, tick));
    }

    /// No sample within the deadline: before the first sample, give up after the startup timeout; after it, flag
    /// the plant stale once, and clean up its node if it died so a restarted plant can take its place.
    fn on_plant_silent(&mut self) -> Result<(), SessionError> {
        let Some((_, tick)) = self.last_tick else {
            return self.give_up_without_rig();
        };
        self.rec.count("plant_stale_deadlines", 1);
        if !self.plant_stale {
            self.plant_stale = true;
            let detail = format!("no plant sample for {:?}; idling", self.stale_after);
            self.events.emit(Some(tick), "plant-stale", detail);
        }
        let _ = self.plant_stream.try_cleanup_dead_nodes();
        Ok(())
    }
}
