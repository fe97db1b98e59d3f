//! What Zenoh says, only in its log, when a TLS link fails its handshake: the listening side drops the connection
//! and the connecting side retries, and neither tells its application. A bridge must say it in words (a peer
//! without the key knocked; the other host holds another key), so this module installs a `tracing` subscriber that
//! listens to Zenoh's TLS link and connection retries alone (every other log line is switched off at its call
//! site, so it costs nothing) and hands each failure's text to the bridge's loop as an [`Arrival::LinkRefused`].
//! What the text means is read by [`refusal`]; pure, and held to Zenoh's real texts by `tests/bridge.rs`.

use super::net::{Arrival, Inbox};
use std::sync::Arc;
use tracing::field::{Field, Visit};
use tracing::subscriber::Interest;
use tracing::{Event, Metadata, span};

/// Where Zenoh logs the accept loop's handshake failures (the listening side).
const TLS_LINK: &str = "zenoh_link_tls";
/// Where Zenoh logs a failed connection to the configured peer (the connecting side).
const CONNECT_RETRIES: &str = "zenoh::net::runtime::orchestrator";

/// A failed handshake, read from Zenoh's text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    /// What TLS said, without Zenoh's wrapping and hints.
    pub detail: String,
    /// The failure is about a certificate (the peers hold different keys, or one has none), not the network.
    pub certificate: bool,
}

/// Start handing Zenoh's TLS failures to `inbox`; once per process (a second call changes nothing).
pub(super) fn watch(inbox: Arc<Inbox>) {
    let _ = tracing::subscriber::set_global_default(Watch { inbox });
}

/// How Zenoh's accept loop ends its line for any failed accept, a TLS handshake's included.
const ACCEPT_HINT: &str = ". Hint: increase the system open file limit";
/// What Zenoh's connecting side says before TLS's own words.
const CONNECT_FAILED: &str = "Can not create a new TLS link bound to ";

/// The failure in a log line of Zenoh's TLS link or connection retries, if it is one.
pub fn refusal(text: &str) -> Option<Refusal> {
    let detail = if let Some((error, _)) = text.split_once(ACCEPT_HINT) {
        // The listening side: the line is TLS's error, then the hint.
        error
    } else {
        // The connecting side: "... bound to <server name>: <TLS's error>. Retry in ...".
        // "... bound to <server name>: <TLS's error> at <file>:<line>.. Retry in ...": Zenoh's errors say where.
        let (_, after) = text.split_once(CONNECT_FAILED)?;
        let error = after.split_once(": ").map_or(after, |(_, e)| e);
        let error = error.split(". Retry in").next().unwrap_or(error);
        error.find(" at ").filter(|&i| error[i..].contains(".rs:")).map_or(error, |i| &error[..i])
    };
    let detail = detail.trim().trim_end_matches('.').to_string();
    let lower = detail.to_ascii_lowercase();
    let certificate =
        ["certificate", "unknownca", "unknown ca", "unknownissuer", "decrypterror"].iter().any(|w| lower.contains(w));
    Some(Refusal { detail, certificate })
}

struct Watch {
    inbox: Arc<Inbox>,
}

fn wanted(m: &Metadata<'_>) -> bool {
    m.is_event() && (m.target().starts_with(TLS_LINK) || m.target().starts_with(CONNECT_RETRIES))
}

/// An event's `message` field, formatted.
#[derive(Default)]
struct Message(String);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            self.0 = format!("{value:?}");
        }
    }
}

impl tracing::Subscriber for Watch {
    fn register_callsite(&self, m: &'static Metadata<'static>) -> Interest {
        if wanted(m) { Interest::always() } else { Interest::never() }
    }

    fn enabled(&self, m: &Metadata<'_>) -> bool {
        wanted(m)
    }

    fn max_level_hint(&self) -> Option<tracing::level_filters::LevelFilter> {
        // The connecting side's retries are logged at debug.
        Some(tracing::level_filters::LevelFilter::DEBUG)
    }

    fn new_span(&self, _: &span::Attributes<'_>) -> span::Id {
        // Never called: no span is enabled; an id must not be 0.
        span::Id::from_u64(1)
    }

    fn record(&self, _: &span::Id, _: &span::Record<'_>) {}

    fn record_follows_from(&self, _: &span::Id, _: &span::Id) {}

    fn event(&self, event: &Event<'_>) {
        let mut message = Message::default();
        event.record(&mut message);
        if refusal(&message.0).is_some() {
            self.inbox.push(Arrival::LinkRefused { text: message.0 });
        }
    }

    fn enter(&self, _: &span::Id) {}

    fn exit(&self, _: &span::Id) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zenoh_s_lines_are_read_into_tls_s_words() {
        let server = "received fatal alert: UnknownCA. Hint: increase the system open file limit.";
        assert_eq!(
            refusal(server),
            Some(Refusal { detail: "received fatal alert: UnknownCA".into(), certificate: true }),
            "the accept loop's failure, without its hint"
        );
        let client = "Unable to connect to configured peer tls/10.0.0.1:7447! Can not create a new TLS link bound to \
                      IpAddress(V4(Ipv4Addr([10, 0, 0, 1]))): invalid peer certificate: UnknownIssuer at \
                      /src/zenoh-link-tls/src/unicast.rs:378.. Retry in 100ms.";
        assert_eq!(
            refusal(client),
            Some(Refusal { detail: "invalid peer certificate: UnknownIssuer".into(), certificate: true })
        );
        let plain = "received corrupt message of type InvalidContentType. Hint: increase the system open file limit.";
        let r = refusal(plain).unwrap();
        assert!(!r.certificate && r.detail == "received corrupt message of type InvalidContentType", "{r:?}");
        assert_eq!(refusal("Successfully connected to configured peer tls/10.0.0.1:7447"), None);
        assert_eq!(refusal("Unable to connect to configured peer tcp/10.0.0.1:7447! Connection refused"), None);
    }
}
