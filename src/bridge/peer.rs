//! Who is at the other end of the link: the bridge each side serves, joined, lost after a stated silence, back
//! again or replaced by a restarted one; a second bridge of the same side while the first is alive is a rival, not
//! a replacement. Pure (time comes in as ns), so the rules are unit-tested.

use super::frame::Hello;

/// What a hello or the passing of time changed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PeerChange {
    /// A peer is heard from: the first, one back after a loss, or a new epoch (a restarted bridge).
    Joined {
        /// Its epoch.
        epoch: u64,
        /// The epoch of the peer before it, if there was one and it was another.
        replaced: Option<u64>,
    },
    /// The peer was silent for the timeout.
    Lost {
        /// Its epoch.
        epoch: u64,
        /// How long it had been silent, ns.
        silent_ns: u64,
    },
    /// Another bridge of the peer's side, while the peer is alive: it is not served.
    Rival {
        /// The rival's epoch.
        epoch: u64,
    },
}

/// The peer as last heard.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Peer {
    hello: Hello,
    last_heard_ns: u64,
    lost: bool,
}

/// Tracks the one peer a bridge serves.
#[derive(Debug, Clone)]
pub struct PeerWatch {
    timeout_ns: u64,
    peer: Option<Peer>,
}

impl PeerWatch {
    /// A watch that declares the peer lost after `timeout_ns` without a hello.
    pub fn new(timeout_ns: u64) -> Self {
        Self { timeout_ns, peer: None }
    }

    /// A hello from the peer's side arrived at `now_ns`.
    pub fn heard(&mut self, hello: Hello, now_ns: u64) -> Option<PeerChange> {
        let epoch = hello.epoch;
        match &mut self.peer {
            Some(p) if p.hello.epoch == epoch => {
                let back = std::mem::take(&mut p.lost);
                p.hello = hello;
                p.last_heard_ns = now_ns;
                back.then_some(PeerChange::Joined { epoch, replaced: None })
            }
            Some(p) if !p.lost && now_ns.saturating_sub(p.last_heard_ns) < self.timeout_ns => {
                Some(PeerChange::Rival { epoch })
            }
            previous => {
                let replaced = previous.as_ref().map(|p| p.hello.epoch);
                *previous = Some(Peer { hello, last_heard_ns: now_ns, lost: false });
                Some(PeerChange::Joined { epoch, replaced })
            }
        }
    }

    /// At `now_ns`: the peer is lost if silent for the timeout (said once per loss).
    pub fn check(&mut self, now_ns: u64) -> Option<PeerChange> {
        let p = self.peer.as_mut().filter(|p| !p.lost)?;
        let silent_ns = now_ns.saturating_sub(p.last_heard_ns);
        (silent_ns >= self.timeout_ns).then(|| {
            p.lost = true;
            PeerChange::Lost { epoch: p.hello.epoch, silent_ns }
        })
    }

    /// The peer's last hello, while it is not lost.
    pub fn alive(&self) -> Option<&Hello> {
        self.peer.as_ref().filter(|p| !p.lost).map(|p| &p.hello)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Side;

    fn hello(epoch: u64) -> Hello {
        Hello {
            side: Side::Controller,
            run_id: "r".into(),
            layout_version: silrig_wire::wire::WIRE_LAYOUT_VERSION,
            epoch,
            serving: None,
            controller_connected: true,
        }
    }

    #[test]
    fn a_peer_joins_is_lost_once_comes_back_and_is_replaced_by_a_restart() {
        let ms = 1_000_000;
        let mut w = PeerWatch::new(500 * ms);
        assert_eq!(w.check(0), None);
        assert_eq!(w.heard(hello(1), 0), Some(PeerChange::Joined { epoch: 1, replaced: None }));
        assert_eq!(w.heard(hello(1), 100 * ms), None);
        assert_eq!(w.check(599 * ms), None);
        assert_eq!(w.check(600 * ms), Some(PeerChange::Lost { epoch: 1, silent_ns: 500 * ms }));
        assert_eq!(w.check(700 * ms), None, "a loss is said once");
        assert!(w.alive().is_none());
        assert_eq!(w.heard(hello(1), 800 * ms), Some(PeerChange::Joined { epoch: 1, replaced: None }));
        assert_eq!(w.alive().map(|h| h.epoch), Some(1));
        // A restarted bridge (new epoch) replaces a lost or silent one.
        assert_eq!(w.heard(hello(2), 1400 * ms), Some(PeerChange::Joined { epoch: 2, replaced: Some(1) }));
    }

    #[test]
    fn a_second_bridge_while_the_first_is_alive_is_a_rival() {
        let ms = 1_000_000;
        let mut w = PeerWatch::new(500 * ms);
        w.heard(hello(1), 0);
        assert_eq!(w.heard(hello(7), 100 * ms), Some(PeerChange::Rival { epoch: 7 }));
        assert_eq!(w.heard(hello(1), 200 * ms), None);
        assert_eq!(w.heard(hello(7), 300 * ms), Some(PeerChange::Rival { epoch: 7 }));
        assert_eq!(w.alive().map(|h| h.epoch), Some(1));
    }
}
