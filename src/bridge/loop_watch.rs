//! The bridge's own loop, watched from a thread beside it: a loop that has not turned for [`STALL_AFTER`] is said
//! on stderr and in the events (`bridge-stalled`, with the step it is in: a Zenoh put that blocks, an iceoryx2
//! call), and again when it turns (`bridge-resumed`, with how long it stood). Without it a stuck bridge looks from
//! both hosts like a lost network: the plant side loses its peer, the controller waits for samples, and nobody
//! says that the bridge itself stood still, nor where.

use silrig_rig::events::EventLog;
use silrig_wire::clock::monotonic_ns;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::Duration;

/// A loop quieter than this is stalled: ten hello periods, and ten times the longest wait of a turning loop.
pub const STALL_AFTER: Duration = Duration::from_secs(1);

/// How often the watcher looks.
const LOOK_EVERY: Duration = Duration::from_millis(100);

/// Where in its loop a bridge is, as said when it stalls there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Waiting for the network or the local streams (bounded by the next hello).
    Waiting,
    /// Taking what came from the network: samples or commands into the local streams, hellos.
    Arrivals,
    /// Sending what the local streams hold onto the network.
    Sending,
    /// Saying hello, and looking at the peer.
    Hello,
}

impl Step {
    const ALL: [Step; 4] = [Step::Waiting, Step::Arrivals, Step::Sending, Step::Hello];

    fn words(self) -> &'static str {
        match self {
            Step::Waiting => "waiting for the network or the local streams",
            Step::Arrivals => "passing what came from the network into this host's streams",
            Step::Sending => "sending this host's samples onto the network",
            Step::Hello => "saying hello to the other bridge",
        }
    }
}

struct Shared {
    turned_ns: AtomicU64,
    step: AtomicUsize,
    done: AtomicBool,
}

/// The loop's side: [`LoopWatch::at`] at each step; the watcher ends when this is dropped.
pub struct LoopWatch {
    shared: Arc<Shared>,
}

impl LoopWatch {
    /// Start watching a loop that begins now.
    pub fn start(events: EventLog) -> Self {
        let shared = Arc::new(Shared {
            turned_ns: AtomicU64::new(monotonic_ns()),
            step: AtomicUsize::new(0),
            done: AtomicBool::new(false),
        });
        let watched = shared.clone();
        let spawned = std::thread::Builder::new().name("loop-watch".into()).spawn(move || watch(&watched, &events));
        if let Err(e) = spawned {
            eprintln!("silrig-bridge: warning: its loop goes unwatched (no thread: {e})");
        }
        Self { shared }
    }

    /// The loop is at `step`, now.
    pub fn at(&self, step: Step) {
        self.shared.step.store(step as usize, Ordering::Relaxed);
        self.shared.turned_ns.store(monotonic_ns(), Ordering::Release);
    }
}

impl Drop for LoopWatch {
    fn drop(&mut self) {
        self.shared.done.store(true, Ordering::Release);
    }
}

/// What the watcher says, given the loop's last turn and step and whether it has said the stall already.
fn look(now_ns: u64, turned_ns: u64, step: Step, stalled_since: &mut Option<u64>) -> Option<(&'static str, String)> {
    let quiet_ns = now_ns.saturating_sub(turned_ns);
    match *stalled_since {
        None if quiet_ns >= STALL_AFTER.as_nanos() as u64 => {
            *stalled_since = Some(turned_ns);
            let text = format!(
                "its loop has not turned for {:.1} s, stuck {}: nothing crosses meanwhile",
                quiet_ns as f64 / 1e9,
                step.words()
            );
            Some(("bridge-stalled", text))
        }
        Some(since) if turned_ns > since => {
            *stalled_since = None;
            let text = format!("its loop turns again, after standing {:.1} s", (turned_ns - since) as f64 / 1e9);
            Some(("bridge-resumed", text))
        }
        _ => None,
    }
}

fn watch(shared: &Shared, events: &EventLog) {
    let mut stalled_since = None;
    while !shared.done.load(Ordering::Acquire) {
        std::thread::sleep(LOOK_EVERY);
        let turned_ns = shared.turned_ns.load(Ordering::Acquire);
        let step = Step::ALL[shared.step.load(Ordering::Relaxed).min(Step::ALL.len() - 1)];
        if let Some((kind, text)) = look(monotonic_ns(), turned_ns, step, &mut stalled_since) {
            eprintln!("silrig-bridge: {text}");
            events.emit(None, kind, text);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: u64 = 1_000_000_000;

    #[test]
    fn a_loop_quiet_for_a_second_is_said_once_with_its_step_and_again_when_it_turns() {
        let mut since = None;
        assert_eq!(look(10 * S + S / 2, 10 * S, Step::Sending, &mut since), None);
        let (kind, text) = look(11 * S, 10 * S, Step::Sending, &mut since).unwrap();
        assert_eq!(kind, "bridge-stalled");
        assert!(text.contains("1.0 s") && text.contains("sending this host's samples"), "{text}");
        assert_eq!(look(12 * S, 10 * S, Step::Sending, &mut since), None, "said once");
        let (kind, text) = look(13 * S, 12 * S + S / 2, Step::Waiting, &mut since).unwrap();
        assert_eq!(kind, "bridge-resumed");
        assert!(text.contains("2.5 s"), "{text}");
        assert_eq!(look(13 * S, 12 * S + S / 2, Step::Waiting, &mut since), None);
    }

    #[test]
    fn the_watcher_sees_a_real_stall_and_its_step() {
        let dir = std::env::temp_dir().join(format!("silrig-loop-watch-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let watch = LoopWatch::start(EventLog::new(&dir, "bridge"));
        watch.at(Step::Arrivals);
        std::thread::sleep(STALL_AFTER + 3 * LOOK_EVERY);
        watch.at(Step::Waiting);
        std::thread::sleep(3 * LOOK_EVERY);
        drop(watch);
        let events = std::fs::read_to_string(dir.join("events.jsonl")).unwrap();
        assert!(events.contains("bridge-stalled") && events.contains("passing what came"), "{events}");
        assert!(events.contains("bridge-resumed"), "{events}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
