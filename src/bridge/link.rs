//! What both sides of a bridge share: the Zenoh ends ([`Link`]: the session, the inbox its subscribers fill, the
//! hello and what has been said), the check of a peer's hello against this run ([`read_hello`]), and an iceoryx2
//! listener's descriptor to poll beside the inbox ([`listener_fd`]), and the test-only impairment between the two
//! ([`super::impair`]). Knows neither side, so both build on it.

use super::error::{BridgeError, zenoh_err};
use super::frame::Hello;
use super::impair::{self, Impairment, ImpairmentSpec};
use super::net::{self, Arrival, Inbox, Keys};
use super::options::{HELLO_PERIOD, Plan};
use super::tls_watch;
use silrig_rig::ProcessArgs;
use silrig_rig::events::EventLog;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::{self, StreamSubscriber};
use silrig_wire::wire::{WIRE_LAYOUT_VERSION, WireSample};
use std::collections::BTreeSet;
use std::sync::Arc;
use zenoh::Wait;
use zenoh::qos::{CongestionControl, Priority};

/// The Zenoh ends every bridge has: the session, the inbox its subscribers fill, and the hello.
pub(super) struct Link {
    pub(super) endpoint: String,
    pub(super) run: String,
    pub(super) keys: Keys,
    pub(super) session: zenoh::Session,
    pub(super) inbox: Arc<Inbox>,
    subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
    hello: zenoh::pubsub::Publisher<'static>,
    pub(super) epoch: u64,
    pub(super) next_hello_ns: u64,
    pub(super) events: EventLog,
    /// Messages already said once (a rival, another run), so a hello every 100 ms does not repeat them.
    said: BTreeSet<String>,
    /// The test-only delay and loss of arrivals, when the environment asks for them.
    impairment: Option<Arc<Impairment>>,
    /// The wire layout version this bridge says it speaks: its build's, or a test's stand-in for another build.
    pub(super) layout_version: u32,
    /// The bridge key's fingerprint, when there is one.
    fingerprint: Option<String>,
}

impl Link {
    pub(super) fn open(plan: &Plan, args: &ProcessArgs) -> Result<Self, BridgeError> {
        let (side, endpoint) = (plan.side, plan.endpoint.as_str());
        std::fs::create_dir_all(&args.out).map_err(|e| BridgeError::Io(format!("{}: {e}", args.out.display())))?;
        let spec = ImpairmentSpec::from_env()?;
        let layout_version = impair::layout_version_from_env()?;
        let inbox = Inbox::new().map_err(|e| BridgeError::Io(format!("eventfd: {e}")))?;
        // Before the session, so a handshake that fails at once is caught too.
        if plan.key.is_some() {
            tls_watch::watch(inbox.clone());
        }
        let session = net::open_session(side, endpoint, plan.key.as_ref())?;
        let run = args.run_id.to_string();
        let keys = Keys::new(&run);
        let hello = session
            .declare_publisher(keys.hello(side))
            .congestion_control(CongestionControl::Drop)
            .wait()
            .map_err(zenoh_err("hello publisher"))?;
        let mut link = Self {
            endpoint: endpoint.into(),
            run,
            keys,
            session,
            impairment: spec.map(|spec| Arc::new(Impairment::new(spec, inbox.clone()))),
            layout_version,
            inbox,
            subscribers: Vec::new(),
            hello,
            epoch: ipc::new_epoch(),
            next_hello_ns: 0,
            events: EventLog::new(&args.out, "bridge"),
            said: BTreeSet::new(),
            fingerprint: plan.key.as_ref().map(|k| k.fingerprint()),
        };
        if plan.insecure {
            link.say("bridge-insecure", format!("warning: {}", plan.security()), false);
        }
        if let Some(spec) = spec {
            link.say("bridge-test-impairment", format!("warning: {}", spec.describe()), false);
        }
        if layout_version != WIRE_LAYOUT_VERSION {
            let text = format!(
                "warning: TEST: saying it speaks wire layout version {layout_version}, not this build's \
                 {WIRE_LAYOUT_VERSION} ({}), as a build of another commit would",
                impair::LAYOUT_VAR
            );
            link.say("bridge-test-impairment", text, false);
        }
        Ok(link)
    }

    /// Plant samples and commands the test impairment dropped (`None`: none asked for).
    pub(super) fn test_losses(&self) -> Option<u64> {
        self.impairment.as_ref().map(|i| i.lost())
    }

    /// Deliver what arrives on `key` to the inbox.
    pub(super) fn subscribe(&mut self, key: String, what: &'static str) -> Result<(), BridgeError> {
        let inbox = self.inbox.clone();
        let impairment = self.impairment.clone();
        let finished = what == "finished";
        let hello = what == "hello";
        let subscriber = self
            .session
            .declare_subscriber(key)
            .callback(move |sample| {
                let bytes = sample.payload().to_bytes().into_owned();
                let arrival = if finished {
                    Arrival::Finished
                } else if hello {
                    Arrival::Hello { key: sample.key_expr().to_string(), bytes }
                } else {
                    let attachment = sample.attachment().map(|a| a.to_bytes().into_owned());
                    Arrival::Sample { what, bytes, attachment }
                };
                match &impairment {
                    Some(i) => i.deliver(&inbox, arrival),
                    None => inbox.push(arrival),
                }
            })
            .wait()
            .map_err(zenoh_err("subscriber"))?;
        self.subscribers.push(subscriber);
        Ok(())
    }

    /// A publisher for a stream: express (no batching) at real-time priority; a full queue drops rather than
    /// blocks, because a late sample is worth nothing to the loop.
    pub(super) fn stream_publisher(
        &self,
        what: &str,
        congestion: CongestionControl,
    ) -> Result<zenoh::pubsub::Publisher<'static>, BridgeError> {
        self.session
            .declare_publisher(self.keys.of(what))
            .congestion_control(congestion)
            .priority(Priority::RealTime)
            .express(true)
            .wait()
            .map_err(zenoh_err("publisher"))
    }

    /// Say hello when it is due; returns the time to wait until at most.
    pub(super) fn say_hello(&mut self, hello: impl FnOnce(u64) -> Hello) -> u64 {
        let now = monotonic_ns();
        if now >= self.next_hello_ns {
            let _ = self.hello.put(hello(self.epoch).to_bytes()).wait();
            self.next_hello_ns = now + HELLO_PERIOD.as_nanos() as u64;
        }
        self.next_hello_ns
    }

    /// On the connecting side: a handshake that failed over a certificate means the hosts hold different keys.
    pub(super) fn wrong_key(&self, text: &str) -> Result<(), BridgeError> {
        match (tls_watch::refusal(text), &self.fingerprint) {
            (Some(r), Some(fingerprint)) if r.certificate => Err(BridgeError::WrongKey {
                endpoint: self.endpoint.clone(),
                detail: r.detail,
                fingerprint: fingerprint.clone(),
            }),
            _ => Ok(()),
        }
    }

    /// Say `text` on stderr and in the events, the first time only when `once`.
    pub(super) fn say(&mut self, kind: &str, text: String, once: bool) {
        if once && !self.said.insert(text.clone()) {
            return;
        }
        eprintln!("silrig-bridge: {text}");
        self.events.emit(None, kind, text);
    }
}

/// A hello from the network, with what is wrong with it for this run (another run, another layout).
pub(super) fn read_hello(bytes: &[u8], run: &str, ours: u32) -> Result<Hello, String> {
    let h = Hello::from_bytes(bytes)?;
    if h.run_id != run {
        return Err(format!(
            "a {} bridge of run `{}` is connected; this one serves run `{run}`",
            h.side.label(),
            h.run_id
        ));
    }
    if h.layout_version != ours {
        return Err(format!(
            "the {} bridge speaks wire layout version {}, this build speaks {ours}: build silrig on both hosts from \
             the same commit",
            h.side.label(),
            h.layout_version
        ));
    }
    Ok(h)
}

/// The listener's descriptor, for polling beside the inbox.
pub(super) fn listener_fd<T: WireSample>(s: &StreamSubscriber<T>) -> i32 {
    use iceoryx2::prelude::FileDescriptorBased;
    // SAFETY: only polled, never closed; the listener owns it and outlives every poll.
    unsafe { s.listener().file_descriptor().native_handle() }
}
