//! A bad network on demand, for tests: added delay and loss on what a bridge receives, set by environment variables
//! (`SILRIG_BRIDGE_TEST_DELAY_MS`, `SILRIG_BRIDGE_TEST_LOSS`, `SILRIG_BRIDGE_TEST_SEED`); and a peer that says it
//! speaks another wire layout, as a build of another commit would (`SILRIG_BRIDGE_TEST_LAYOUT_VERSION`). This kernel has no
//! `sch_netem` (the usual way to make a link slow or lossy), so the bridge does it to its own arrivals, between
//! Zenoh's callback and the loop's inbox. An environment variable rather than a flag because `silrig run` starts the
//! plant-side bridge itself and passes its environment on: one setting impairs both directions. Never meant for a
//! real bench: a bridge with it on says so at start, on stderr and in the events.

use super::error::BridgeError;
use super::net::{Arrival, Inbox};
use silrig_model::rng::SplitMix64;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Sender, channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Extra one-way delay of every arrival, ms (0..=1000).
pub const DELAY_VAR: &str = "SILRIG_BRIDGE_TEST_DELAY_MS";
/// Probability that a plant sample or a command is lost (0..=1); hellos, announcements and the end are never lost.
pub const LOSS_VAR: &str = "SILRIG_BRIDGE_TEST_LOSS";
/// Seed of the losses (a u64; default 1), so a lossy test run can be flown again.
pub const SEED_VAR: &str = "SILRIG_BRIDGE_TEST_SEED";
/// The wire layout version the bridge says it speaks, standing for a build of another commit.
pub const LAYOUT_VAR: &str = "SILRIG_BRIDGE_TEST_LAYOUT_VERSION";

/// The wire layout version this bridge says it speaks: [`LAYOUT_VAR`] if set (a test's stand-in for a build of
/// another commit: the peer's refusal is then the real one), else its build's.
pub fn layout_version_from_env() -> Result<u32, BridgeError> {
    match std::env::var(LAYOUT_VAR) {
        Err(_) => Ok(silrig_wire::wire::WIRE_LAYOUT_VERSION),
        Ok(text) => text
            .trim()
            .parse::<u32>()
            .map_err(|_| BridgeError::Usage(format!("{LAYOUT_VAR}={text:?}: give an unsigned integer"))),
    }
}

/// What the environment asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpairmentSpec {
    /// Added one-way delay, ms.
    pub delay_ms: f64,
    /// Loss probability of samples and commands.
    pub loss: f64,
    /// Seed of the losses.
    pub seed: u64,
}

impl ImpairmentSpec {
    /// From the environment; `None` when neither delay nor loss is set. A malformed or out-of-range value is an
    /// error naming the variable.
    pub fn from_env() -> Result<Option<Self>, BridgeError> {
        Self::from_vars(|k| std::env::var(k).ok())
    }

    fn from_vars(var: impl Fn(&str) -> Option<String>) -> Result<Option<Self>, BridgeError> {
        let number = |name: &str, lo: f64, hi: f64| -> Result<Option<f64>, BridgeError> {
            let Some(text) = var(name) else { return Ok(None) };
            match text.trim().parse::<f64>() {
                Ok(v) if (lo..=hi).contains(&v) => Ok(Some(v)),
                _ => Err(BridgeError::Usage(format!("{name}={text:?}: give a number in {lo}..={hi}"))),
            }
        };
        let delay_ms = number(DELAY_VAR, 0.0, 1000.0)?;
        let loss = number(LOSS_VAR, 0.0, 1.0)?;
        let seed = match var(SEED_VAR) {
            None => 1,
            Some(text) => text
                .trim()
                .parse::<u64>()
                .map_err(|_| BridgeError::Usage(format!("{SEED_VAR}={text:?}: give an unsigned integer")))?,
        };
        if delay_ms.is_none() && loss.is_none() {
            return Ok(None);
        }
        Ok(Some(Self { delay_ms: delay_ms.unwrap_or(0.0), loss: loss.unwrap_or(0.0), seed }))
    }

    /// How the bridge says it at start.
    pub fn describe(&self) -> String {
        format!(
            "TEST impairment on what this bridge receives: {:.1} ms added delay, loss {} of plant samples and \
             commands (seed {}; {DELAY_VAR}, {LOSS_VAR}): not a real network's figures",
            self.delay_ms, self.loss, self.seed
        )
    }
}

/// Between Zenoh's callbacks and the inbox: drops and delays arrivals as the spec says. Delayed arrivals go through
/// one thread that holds them until due, in order (the delay is the same for all).
pub struct Impairment {
    spec: ImpairmentSpec,
    rng: Mutex<SplitMix64>,
    later: Option<Sender<(Instant, Arrival)>>,
    lost: AtomicU64,
}

impl Impairment {
    /// Impair arrivals bound for `inbox`.
    pub fn new(spec: ImpairmentSpec, inbox: Arc<Inbox>) -> Self {
        let later = (spec.delay_ms > 0.0).then(|| {
            let (tx, rx) = channel::<(Instant, Arrival)>();
            std::thread::Builder::new()
                .name("bridge-test-delay".into())
                .spawn(move || {
                    for (due, arrival) in rx {
                        std::thread::sleep(due.saturating_duration_since(Instant::now()));
                        inbox.push(arrival);
                    }
                })
                .expect("a thread for the test delay");
            tx
        });
        Self { spec, rng: Mutex::new(SplitMix64::new(spec.seed)), later, lost: AtomicU64::new(0) }
    }

    /// Deliver `arrival` to `inbox`: dropped, held back, or at once.
    pub fn deliver(&self, inbox: &Inbox, arrival: Arrival) {
        let lossy = matches!(arrival, Arrival::Sample { what: "plant" | "command", .. });
        if lossy && self.spec.loss > 0.0 {
            let draw = self.rng.lock().unwrap_or_else(|e| e.into_inner()).uniform();
            if draw < self.spec.loss {
                self.lost.fetch_add(1, Ordering::Relaxed);
                return;
            }
        }
        match &self.later {
            Some(tx) => {
                let due = Instant::now() + Duration::from_secs_f64(self.spec.delay_ms / 1e3);
                let _ = tx.send((due, arrival));
            }
            None => inbox.push(arrival),
        }
    }

    /// Samples and commands dropped so far.
    pub fn lost(&self) -> u64 {
        self.lost.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(vars: &[(&str, &str)]) -> Result<Option<ImpairmentSpec>, BridgeError> {
        ImpairmentSpec::from_vars(|k| vars.iter().find(|(n, _)| *n == k).map(|(_, v)| v.to_string()))
    }

    #[test]
    fn the_environment_is_read_and_bad_values_are_named() {
        assert_eq!(spec(&[]).unwrap(), None);
        assert_eq!(
            spec(&[(DELAY_VAR, "2.5"), (SEED_VAR, "7")]).unwrap(),
            Some(ImpairmentSpec { delay_ms: 2.5, loss: 0.0, seed: 7 })
        );
        let e = spec(&[(LOSS_VAR, "1.5")]).unwrap_err().to_string();
        assert!(e.contains("SILRIG_BRIDGE_TEST_LOSS=\"1.5\"") && e.contains("0..=1"), "{e}");
        let e = spec(&[(DELAY_VAR, "NaN")]).unwrap_err().to_string();
        assert!(e.contains("SILRIG_BRIDGE_TEST_DELAY_MS"), "{e}");
        let e = spec(&[(LOSS_VAR, "0.1"), (SEED_VAR, "-1")]).unwrap_err().to_string();
        assert!(e.contains("SILRIG_BRIDGE_TEST_SEED"), "{e}");
    }

    fn sample(what: &'static str) -> Arrival {
        Arrival::Sample { what, bytes: vec![1], attachment: None }
    }

    #[test]
    fn losses_hit_only_samples_and_commands_at_about_the_rate_asked() {
        let inbox = Inbox::new().unwrap();
        let imp = Impairment::new(ImpairmentSpec { delay_ms: 0.0, loss: 0.25, seed: 3 }, inbox.clone());
        for _ in 0..4000 {
            imp.deliver(&inbox, sample("plant"));
            imp.deliver(&inbox, Arrival::Finished);
            imp.deliver(&inbox, sample("plant-info"));
        }
        let arrived = inbox.take();
        let count = |f: &dyn Fn(&Arrival) -> bool| arrived.iter().filter(|a| f(a)).count();
        assert_eq!(count(&|a| *a == Arrival::Finished), 4000);
        assert_eq!(count(&|a| *a == sample("plant-info")), 4000);
        let plant = count(&|a| *a == sample("plant"));
        assert_eq!(plant as u64 + imp.lost(), 4000);
        // 1000 expected lost, standard deviation about 27.
        assert!((850..1150).contains(&imp.lost()), "{} lost", imp.lost());
    }

    #[test]
    fn a_delay_holds_each_arrival_back_at_least_that_long_in_order() {
        let inbox = Inbox::new().unwrap();
        let imp = Impairment::new(ImpairmentSpec { delay_ms: 30.0, loss: 0.0, seed: 1 }, inbox.clone());
        let start = Instant::now();
        imp.deliver(&inbox, sample("plant"));
        imp.deliver(&inbox, sample("command"));
        let mut got = Vec::new();
        while got.len() < 2 {
            super::super::net::wait_readable(&[inbox.fd()], silrig_wire::clock::monotonic_ns() + 1_000_000_000);
            got.extend(inbox.take());
        }
        assert!(start.elapsed() >= Duration::from_millis(30));
        assert_eq!(got, [sample("plant"), sample("command")]);
    }
}
