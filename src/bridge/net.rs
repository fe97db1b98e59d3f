//! The Zenoh side of a bridge: the session (peer mode on the one endpoint given, scouting off, so bridges of other
//! rigs on the network never join; TLS with mutual authentication when there is a bridge key), the run's keys, and
//! an inbox where Zenoh's threads leave what arrives and wake the bridge's loop through an eventfd. iceoryx2 ports
//! are `!Send`: only the loop touches them, never a Zenoh callback.

use super::error::BridgeError;
use super::frame::Side;
use super::key::BridgeKey;
use std::collections::VecDeque;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::sync::{Arc, Mutex};

/// A Zenoh locator from what the user typed: `IP:PORT` (TCP), `tcp/IP:PORT`, `udp/IP:PORT` or `tls/IP:PORT`.
pub fn endpoint(text: &str) -> Result<String, String> {
    let (proto, addr) = match text.split_once('/') {
        Some((p @ ("tcp" | "udp" | "tls"), addr)) => (p, addr),
        Some((p, _)) => return Err(format!("endpoint {text:?}: transport `{p}` is not tcp, udp or tls")),
        None => ("tcp", text),
    };
    let (host, port) =
        addr.rsplit_once(':').ok_or_else(|| format!("endpoint {text:?}: give HOST:PORT (e.g. 192.168.1.20:7447)"))?;
    let port_ok = port.parse::<u16>().is_ok_and(|p| p > 0);
    if host.is_empty() || !port_ok {
        return Err(format!("endpoint {text:?}: give HOST:PORT with a port in 1..65535 (e.g. 192.168.1.20:7447)"));
    }
    Ok(format!("{proto}/{addr}"))
}

/// Whether a locator's host is this machine's loopback (127.0.0.0/8, ::1 or `localhost`): a peer there is a
/// process of this host, so a bridge without a key may listen there.
pub fn is_loopback(locator: &str) -> bool {
    let addr = locator.split_once('/').map_or(locator, |(_, a)| a);
    let host = addr.rsplit_once(':').map_or(addr, |(h, _)| h);
    let host = host.trim_start_matches('[').trim_end_matches(']');
    host == "localhost" || host.parse::<std::net::IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

/// The same locator on TLS (a bridge key needs TCP under it), or why it cannot be.
pub fn on_tls(locator: &str) -> Result<String, String> {
    match locator.split_once('/') {
        Some(("tcp" | "tls", addr)) => Ok(format!("tls/{addr}")),
        _ => Err(format!(
            "{locator}: a bridge key runs the link over TLS, which needs TCP: give IP:PORT (or tcp/IP:PORT)"
        )),
    }
}

/// The run's keys: `silrig/<run id>/...`.
#[derive(Debug, Clone)]
pub struct Keys {
    run: String,
}

impl Keys {
    /// Keys of run `run`.
    pub fn new(run: &str) -> Self {
        Self { run: run.into() }
    }

    /// A stream or message of the run.
    pub fn of(&self, what: &str) -> String {
        format!("silrig/{}/{what}", self.run)
    }

    /// This run's hello from `side`.
    pub fn hello(&self, side: Side) -> String {
        self.of(&format!("hello/{}", side.label()))
    }

    /// Hellos from `side` of any run: a bridge of another run at the other end is named, not ignored.
    pub fn any_hello(side: Side) -> String {
        format!("silrig/*/hello/{}", side.label())
    }
}

/// Open the session: the plant side listens on `endpoint`, the controller side connects to it and keeps retrying
/// in the background (also after the link or the other bridge went away). With `bridge_key`, the link is TLS and
/// each side requires the other's certificate to chain to the key's CA.
pub fn open_session(side: Side, endpoint: &str, bridge_key: Option<&BridgeKey>) -> Result<zenoh::Session, BridgeError> {
    use zenoh::Wait;
    let mut config = zenoh::Config::default();
    let json = |v: &str| v.to_string();
    let endpoints = serde_json::to_string(&[endpoint]).expect("a list of strings");
    let (key, other) = match side {
        Side::Plant => ("listen/endpoints", "connect/endpoints"),
        Side::Controller => ("connect/endpoints", "listen/endpoints"),
    };
    let settings = [
        ("mode", json("\"peer\"")),
        ("scouting/multicast/enabled", json("false")),
        ("scouting/gossip/enabled", json("false")),
        (key, endpoints),
        (other, json("[]")),
        // Reconnect quickly once the link or the other bridge is back (Zenoh's default starts at 1 s).
        ("connect/retry", json("{ period_init_ms: 100, period_max_ms: 500, period_increase_factor: 2 }")),
        // No timestamps, no admin space: nothing we use.
        ("adminspace/enabled", json("false")),
    ];
    let tls = bridge_key.map(BridgeKey::zenoh_settings).unwrap_or_default();
    for (k, v) in settings.into_iter().chain(tls) {
        config.insert_json5(k, &v).map_err(|e| BridgeError::Zenoh(format!("config {k} = {v}: {e}")))?;
    }
    zenoh::open(config).wait().map_err(|e| BridgeError::Zenoh(format!("{} bridge on {endpoint}: {e}", side.label())))
}

/// Something that arrived from the other bridge.
#[derive(Debug, Clone, PartialEq)]
pub enum Arrival {
    /// A sample's bytes on the key `what` (a stream label) with its attachment, if any.
    Sample {
        /// Stream label (`plant`, `command`, `controller-info`).
        what: &'static str,
        /// The contract's bytes.
        bytes: Vec<u8>,
        /// The Zenoh attachment.
        attachment: Option<Vec<u8>>,
    },
    /// The plant has published its last sample.
    Finished,
    /// A hello, with the key it came on.
    Hello {
        /// The key (names the run).
        key: String,
        /// The hello's bytes.
        bytes: Vec<u8>,
    },
    /// A TLS link failed its handshake: Zenoh's log line (see [`super::tls_watch`]).
    LinkRefused {
        /// Zenoh's text.
        text: String,
    },
}

/// Where Zenoh's callbacks leave arrivals for the bridge's loop.
#[derive(Debug)]
pub struct Inbox {
    queue: Mutex<VecDeque<Arrival>>,
    wake: OwnedFd,
}

impl Inbox {
    /// An empty inbox.
    pub fn new() -> std::io::Result<Arc<Self>> {
        // SAFETY: eventfd with valid flags; the descriptor is owned by the OwnedFd from here on.
        let raw = unsafe { libc::eventfd(0, libc::EFD_NONBLOCK | libc::EFD_CLOEXEC) };
        if raw < 0 {
            return Err(std::io::Error::last_os_error());
        }
        // SAFETY: a fresh descriptor nobody else owns.
        let wake = unsafe { OwnedFd::from_raw_fd(raw) };
        Ok(Arc::new(Self { queue: Mutex::new(VecDeque::new()), wake }))
    }

    /// Leave an arrival and wake the loop (called on Zenoh's threads).
    pub fn push(&self, arrival: Arrival) {
        self.queue.lock().unwrap_or_else(|e| e.into_inner()).push_back(arrival);
        let one: u64 = 1;
        // SAFETY: writes 8 bytes from a u64 we own to our eventfd; a full counter (EAGAIN) still leaves it readable.
        unsafe { libc::write(self.wake.as_raw_fd(), (&one as *const u64).cast(), 8) };
    }

    /// Everything that arrived, oldest first; re-arms the wake-up.
    pub fn take(&self) -> VecDeque<Arrival> {
        let mut count: u64 = 0;
        // SAFETY: reads at most 8 bytes into a u64 we own; EAGAIN (nothing pending) is fine.
        unsafe { libc::read(self.wake.as_raw_fd(), (&mut count as *mut u64).cast(), 8) };
        std::mem::take(&mut *self.queue.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// The descriptor that is readable while something waits.
    pub fn fd(&self) -> i32 {
        self.wake.as_raw_fd()
    }
}

/// Block until one of `fds` is readable or the monotonic clock reaches `deadline_ns` (a signal ends it early).
pub fn wait_readable(fds: &[i32], deadline_ns: u64) {
    let remaining_ns = deadline_ns.saturating_sub(silrig_wire::clock::monotonic_ns());
    let timeout = silrig_wire::clock::timespec_from_ns(remaining_ns);
    let mut polls: Vec<libc::pollfd> =
        fds.iter().map(|&fd| libc::pollfd { fd, events: libc::POLLIN, revents: 0 }).collect();
    // SAFETY: valid pollfds and timespec for the duration of the call, no signal mask change.
    unsafe { libc::ppoll(polls.as_mut_ptr(), polls.len() as libc::nfds_t, &timeout, std::ptr::null()) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_default_to_tcp_and_bad_ones_are_named() {
        assert_eq!(endpoint("10.0.0.1:7447").unwrap(), "tcp/10.0.0.1:7447");
        assert_eq!(endpoint("udp/10.0.0.1:7447").unwrap(), "udp/10.0.0.1:7447");
        assert_eq!(endpoint("tcp/[::1]:7447").unwrap(), "tcp/[::1]:7447");
        assert!(endpoint("quic/10.0.0.1:7447").unwrap_err().contains("`quic` is not tcp, udp or tls"));
        assert_eq!(endpoint("tls/10.0.0.1:7447").unwrap(), "tls/10.0.0.1:7447");
        assert!(endpoint("10.0.0.1").unwrap_err().contains("HOST:PORT"));
        assert!(endpoint("10.0.0.1:0").unwrap_err().contains("1..65535"));
        assert!(endpoint(":7447").unwrap_err().contains("HOST:PORT"));
    }

    #[test]
    fn the_loopback_is_told_from_the_network_and_a_key_needs_tcp() {
        for local in ["tcp/127.0.0.1:7447", "udp/127.3.2.1:7447", "tcp/[::1]:7447", "tcp/localhost:7447"] {
            assert!(is_loopback(local), "{local}");
        }
        for remote in ["tcp/0.0.0.0:7447", "tcp/10.0.0.1:7447", "tcp/[::]:7447", "tcp/plant.lab:7447"] {
            assert!(!is_loopback(remote), "{remote}");
        }
        assert_eq!(on_tls("tcp/10.0.0.1:7447").unwrap(), "tls/10.0.0.1:7447");
        assert_eq!(on_tls("tls/10.0.0.1:7447").unwrap(), "tls/10.0.0.1:7447");
        assert!(on_tls("udp/10.0.0.1:7447").unwrap_err().contains("needs TCP"));
    }

    #[test]
    fn the_inbox_wakes_and_hands_over_in_order() {
        let inbox = Inbox::new().unwrap();
        inbox.push(Arrival::Finished);
        inbox.push(Arrival::Hello { key: "k".into(), bytes: vec![1] });
        let t0 = silrig_wire::clock::monotonic_ns();
        wait_readable(&[inbox.fd()], t0 + 5_000_000_000);
        let got: Vec<Arrival> = inbox.take().into();
        assert_eq!(got, [Arrival::Finished, Arrival::Hello { key: "k".into(), bytes: vec![1] }]);
        assert!(inbox.take().is_empty());
    }
}
