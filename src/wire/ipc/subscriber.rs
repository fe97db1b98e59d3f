//! The receiving side of a stream: samples copied out of shared memory with their receive time, loss and restarts
//! detected from `(epoch, seq)` ([`SeqTracker`], pure and unit-tested), invalid samples marked, and running totals.

use super::IpcError;
use crate::clock;
use crate::ipc::StreamEvent;
use crate::wire::{WireError, WireSample};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use std::cell::Cell;

/// Loss and restart detection from `(epoch, seq)`. Pure, so the rules are unit-tested without iceoryx2.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SeqTracker {
    last: Option<(u64, u64)>,
}

/// What one sample's header says about the stream.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SeqObservation {
    /// Samples of this epoch missing just before this one.
    pub lost_before: u64,
    /// First sample of a new publisher epoch (a restart), or the very first sample seen.
    pub new_epoch: bool,
    /// `seq` did not advance within the epoch (duplicate or reordered); not counted as loss.
    pub out_of_order: bool,
}

impl SeqTracker {
    /// Account for a sample with this header.
    pub fn observe(&mut self, epoch: u64, seq: u64) -> SeqObservation {
        let obs = match self.last {
            // The first sample ever: whatever the publisher sent before we subscribed is not loss.
            None => SeqObservation { new_epoch: true, ..Default::default() },
            // A restarted publisher counts from 0 again, and we were connected when it started, so a first seq
            // above 0 means samples were lost.
            Some((last_epoch, _)) if last_epoch != epoch => {
                SeqObservation { lost_before: seq, new_epoch: true, out_of_order: false }
            }
            Some((_, last_seq)) if seq <= last_seq => SeqObservation { out_of_order: true, ..Default::default() },
            Some((_, last_seq)) => SeqObservation { lost_before: seq - last_seq - 1, ..Default::default() },
        };
        if !obs.out_of_order {
            self.last = Some((epoch, seq));
        }
        obs
    }
}

/// Running totals of a subscriber.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SubscriberStats {
    /// Samples received.
    pub received: u64,
    /// Samples missing by `seq` (overwritten by safe overflow or never delivered).
    pub lost: u64,
    /// Publisher epochs seen after the first (restarts).
    pub publisher_restarts: u64,
    /// Samples whose `seq` did not advance.
    pub out_of_order: u64,
    /// Samples that failed [`WireSample::validate`].
    pub invalid: u64,
    /// Dead-publisher events seen (after someone cleaned up its node).
    pub publisher_deaths: u64,
    /// Times the publisher said it had sent its last sample ([`StreamEvent::Finished`]).
    #[serde(default)]
    pub finished_notices: u64,
}

/// How [`StreamSubscriber::wait`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WaitOutcome {
    /// Something was notified (a sample, a death, the end); drain to see what.
    Notified,
    /// Nothing within the timeout.
    TimedOut,
    /// A signal interrupted the wait (SIGCONT after SIGSTOP, SIGTERM under a flag handler): look at the flag.
    Interrupted,
}

/// One received sample with what the transport knows about it.
#[derive(Debug, Clone, Copy)]
pub struct Received<T> {
    /// The sample, copied out of shared memory.
    pub sample: T,
    /// CLOCK_MONOTONIC when it was taken from the queue, ns.
    pub t_recv_ns: u64,
    /// Header bookkeeping.
    pub seq: SeqObservation,
    /// Why the sample must not be used, if so (NaN/inf, foreign layout).
    pub invalid: Option<WireError>,
}

impl<T: WireSample> Received<T> {
    /// Receive time minus send stamp, ns (0 if the clocks disagree, which CLOCK_MONOTONIC on one machine
    /// cannot).
    pub fn age_ns(&self) -> u64 {
        self.t_recv_ns.saturating_sub(self.sample.header().t_send_ns)
    }
}

/// The receiving side of a stream: a subscriber plus the listener that wakes a WaitSet.
pub struct StreamSubscriber<T: WireSample> {
    stream: &'static str,
    subscriber: Subscriber<ipc::Service, T, ()>,
    listener: Listener<ipc::Service>,
    // Cells, because a WaitSet guard keeps `listener` borrowed while the callback drains: draining must work
    // through `&self`.
    tracker: Cell<SeqTracker>,
    stats: Cell<SubscriberStats>,
}

impl<T: WireSample> std::fmt::Debug for StreamSubscriber<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamSubscriber").field("stream", &self.stream).field("stats", &self.stats.get()).finish()
    }
}

impl<T: WireSample> StreamSubscriber<T> {
    pub(super) fn new(
        stream: &'static str,
        subscriber: Subscriber<ipc::Service, T, ()>,
        listener: Listener<ipc::Service>,
    ) -> Self {
        Self {
            stream,
            subscriber,
            listener,
            tracker: Cell::new(SeqTracker::default()),
            stats: Cell::new(SubscriberStats::default()),
        }
    }

    /// The listener to attach to a WaitSet (`attach_notification` or `attach_deadline`).
    pub fn listener(&self) -> &Listener<ipc::Service> {
        &self.listener
    }

    /// Block until a wake-up is pending or the monotonic clock reaches `deadline_ns`, whichever comes first (a
    /// signal may end it early), without consuming the wake-up: [`Self::drain`] does. The listener's own
    /// `timed_wait` times out in whole kernel ticks (a socket timeout: 4 ms on a 250 Hz kernel), so a 2 ms wait
    /// for a command that never comes lasted 6 to 8 ms and overran the plant's tick; `ppoll` keeps to the
    /// microsecond.
    pub fn wait_readable_until(&self, deadline_ns: u64) {
        self.poll_readable(deadline_ns.saturating_sub(crate::clock::monotonic_ns()));
    }

    /// `ppoll` on the listener's descriptor for up to `timeout_ns`: > 0 readable, 0 timed out, < 0 interrupted.
    fn poll_readable(&self, timeout_ns: u64) -> libc::c_int {
        use iceoryx2::prelude::FileDescriptorBased;
        let timeout = libc::timespec {
            tv_sec: (timeout_ns / 1_000_000_000) as libc::time_t,
            tv_nsec: (timeout_ns % 1_000_000_000) as libc::c_long,
        };
        // SAFETY: the descriptor is only polled, never closed or handed on; the listener owns it and outlives
        // the call.
        let fd = unsafe { self.listener.file_descriptor().native_handle() };
        let mut poll_fd = libc::pollfd { fd, events: libc::POLLIN, revents: 0 };
        // SAFETY: one valid pollfd, a valid timespec, no signal mask change.
        unsafe { libc::ppoll(&mut poll_fd, 1, &timeout, std::ptr::null()) }
    }

    /// Running totals.
    pub fn stats(&self) -> SubscriberStats {
        self.stats.get()
    }

    /// Take every pending sample, oldest first, and hand each to `on_sample`; returns how many. Also consumes the
    /// pending wake-ups, which a WaitSet callback must do or the WaitSet spins. Invalid samples are handed over too,
    /// marked in [`Received::invalid`] (the logger records them; a consumer must skip them).
    pub fn drain(&self, on_sample: impl FnMut(&Received<T>)) -> Result<usize, IpcError> {
        let stream = self.stream;
        self.listener
            .try_wait(|activation| self.note_event(activation.id.as_value()))
            .map_err(|e| IpcError::Transfer { stream, op: "listener wait", detail: super::in_words(&e) })?;
        self.receive_queued(on_sample)
    }

    /// [`Self::drain`] when `consume_wakeups` (a consumer about to block on the listener, or one a WaitSet wakes),
    /// else [`Self::receive_queued`] (one looking between waits, or never waiting on this listener).
    pub fn take(&self, consume_wakeups: bool, on_sample: impl FnMut(&Received<T>)) -> Result<usize, IpcError> {
        if consume_wakeups { self.drain(on_sample) } else { self.receive_queued(on_sample) }
    }

    /// [`StreamSubscriber::drain`] without consuming wake-ups: for a consumer that polls its queue between waits.
    /// iceoryx2 0.10's listener can lose its wake-up for good when it consumes its wake-ups while a notifier is
    /// half-way through a notification (it resets its state, a second notification completes, then it empties the
    /// socket of that notification's byte too: the state says notified, no byte is left, and no notifier sends one
    /// again until someone consumes the state without a byte). Polling with [`Self::drain`] at the moment samples
    /// arrive makes that window likely; this leaves the wake-ups to the next wait.
    pub fn receive_queued(&self, mut on_sample: impl FnMut(&Received<T>)) -> Result<usize, IpcError> {
        let stream = self.stream;
        let mut stats = self.stats.get();
        let mut tracker = self.tracker.get();
        let mut n = 0;
        loop {
            let sample = match self.subscriber.receive() {
                Ok(Some(s)) => *s.payload(),
                Ok(None) => break,
                Err(e) => {
                    self.stats.set(stats);
                    self.tracker.set(tracker);
                    return Err(IpcError::Transfer { stream, op: "receive", detail: super::in_words(&e) });
                }
            };
            let t_recv_ns = clock::monotonic_ns();
            let h = *sample.header();
            let seq = tracker.observe(h.epoch, h.seq);
            let invalid = sample.validate().err();
            stats.received += 1;
            stats.lost += seq.lost_before;
            stats.publisher_restarts += u64::from(seq.new_epoch && stats.received > 1);
            stats.out_of_order += u64::from(seq.out_of_order);
            stats.invalid += u64::from(invalid.is_some());
            on_sample(&Received { sample, t_recv_ns, seq, invalid });
            n += 1;
        }
        self.stats.set(stats);
        self.tracker.set(tracker);
        Ok(n)
    }

    /// Block until the publisher notifies something or `timeout` passes, without taking samples or consuming the
    /// wake-up ([`StreamSubscriber::drain`] does both); the loop form of a WaitSet deadline, for a process that
    /// owns its signals. A `ppoll` on the listener's descriptor: the listener's own `timed_wait` costs six system
    /// calls a wait (a socket timeout set, the descriptor switched to blocking and back), which a lockstep loop
    /// pays every tick.
    pub fn wait(&self, timeout: std::time::Duration) -> Result<WaitOutcome, IpcError> {
        Ok(match self.poll_readable(timeout.as_nanos().min(u128::from(u64::MAX)) as u64) {
            0 => WaitOutcome::TimedOut,
            n if n > 0 => WaitOutcome::Notified,
            _ => WaitOutcome::Interrupted,
        })
    }

    fn note_event(&self, id: usize) {
        let mut stats = self.stats.get();
        if id == StreamEvent::PublisherDead.id() {
            stats.publisher_deaths += 1;
        } else if id == StreamEvent::Finished.id() {
            stats.finished_notices += 1;
        }
        self.stats.set(stats);
    }

    /// Drain and keep only the newest valid sample (what a controller acts on).
    pub fn latest(&self) -> Result<Option<Received<T>>, IpcError> {
        let mut newest = None;
        self.drain(|r| {
            if r.invalid.is_none() {
                newest = Some(*r);
            }
        })?;
        Ok(newest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seq_tracker_counts_gaps_restarts_and_reorders() {
        let mut t = SeqTracker::default();
        assert_eq!(t.observe(7, 100), SeqObservation { lost_before: 0, new_epoch: true, out_of_order: false });
        assert_eq!(t.observe(7, 101).lost_before, 0);
        assert_eq!(t.observe(7, 105).lost_before, 3);
        assert!(t.observe(7, 104).out_of_order);
        assert_eq!(t.observe(7, 106).lost_before, 0);
        assert_eq!(t.observe(9, 2), SeqObservation { lost_before: 2, new_epoch: true, out_of_order: false });
        assert_eq!(t.observe(9, 3).lost_before, 0);
    }
}
