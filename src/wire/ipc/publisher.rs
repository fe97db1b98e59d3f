//! The sending side of a stream: every sample leaves stamped (sequence number, tick, epoch, layout version, send
//! time) and validated, and its subscribers are woken.

use super::IpcError;
use crate::clock;
use crate::wire::WireSample;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::prelude::*;

/// The sending side of a stream: stamps the header, sends, then wakes the listeners.
pub struct StreamPublisher<T: WireSample> {
    stream: &'static str,
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
    epoch: u64,
    next_seq: u64,
}

impl<T: WireSample> std::fmt::Debug for StreamPublisher<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamPublisher")
            .field("stream", &self.stream)
            .field("epoch", &self.epoch)
            .field("next_seq", &self.next_seq)
            .finish()
    }
}

impl<T: WireSample> StreamPublisher<T> {
    pub(super) fn new(
        stream: &'static str,
        publisher: Publisher<ipc::Service, T, ()>,
        notifier: Notifier<ipc::Service>,
        epoch: u64,
    ) -> Self {
        Self { stream, publisher, notifier, epoch, next_seq: 0 }
    }

    /// Send `sample` as belonging to plant `tick`: stamps `seq`, `tick`, `epoch`, `layout_version` and `t_send_ns`
    /// (overwriting what the caller put there), validates, loans, writes, sends, notifies. Returns the number of
    /// subscriber queues it went into (0 is not an error: nobody is listening) and the send stamp. An invalid
    /// sample is refused and not counted.
    pub fn send(&mut self, tick: u64, sample: &T) -> Result<SendReceipt, IpcError> {
        let mut out = *sample;
        {
            let h = out.header_mut();
            h.seq = self.next_seq;
            h.tick = tick;
            h.epoch = self.epoch;
            h.layout_version = crate::wire::WIRE_LAYOUT_VERSION;
            h._pad = 0;
        }
        self.transmit(out)
    }

    /// Send a sample another publisher stamped (a bridge passing the stream on from another host): its `seq`,
    /// `tick` and `epoch` are kept, so readers see the original publisher's losses and restarts; only `t_send_ns`
    /// is stamped anew, because the sender's clock is another machine's.
    pub fn forward(&mut self, sample: &T) -> Result<SendReceipt, IpcError> {
        self.transmit(*sample)
    }

    fn transmit(&mut self, mut out: T) -> Result<SendReceipt, IpcError> {
        out.validate().map_err(|cause| IpcError::InvalidSample { stream: self.stream, cause })?;
        let loan = self.publisher.loan_uninit().map_err(|e| IpcError::Transfer {
            stream: self.stream,
            op: "loan",
            detail: super::in_words(&e),
        })?;
        // Stamped as late as possible, so that data age measured by the receiver excludes our own loan.
        let t_send_ns = clock::monotonic_ns();
        out.header_mut().t_send_ns = t_send_ns;
        let delivered = loan.write_payload(out).send().map_err(|e| IpcError::Transfer {
            stream: self.stream,
            op: "send",
            detail: super::in_words(&e),
        })?;
        self.next_seq += 1;
        self.notifier.notify().map_err(|e| IpcError::Transfer {
            stream: self.stream,
            op: "notify",
            detail: super::in_words(&e),
        })?;
        Ok(SendReceipt { delivered, t_send_ns })
    }

    /// Tell the subscribers this publisher has sent its last sample ([`StreamEvent::Finished`]).
    pub fn announce_finished(&self) -> Result<(), IpcError> {
        let id = EventId::new(super::StreamEvent::Finished.id());
        self.notifier.notify_with_custom_event_id(id).map(|_| ()).map_err(|e| IpcError::Transfer {
            stream: self.stream,
            op: "notify",
            detail: super::in_words(&e),
        })
    }

    /// Hand the last sample sent to subscribers that joined since (the stream's history), without sending: what
    /// keeps a once-per-epoch announcement reaching a reader that started late or restarted.
    pub fn deliver_history(&self) -> Result<(), IpcError> {
        use iceoryx2::port::update_connections::UpdateConnections;
        self.publisher.update_connections().map_err(|e| IpcError::Transfer {
            stream: self.stream,
            op: "update connections",
            detail: super::in_words(&e),
        })
    }

    /// Epoch stamped into every sample.
    pub fn epoch(&self) -> u64 {
        self.epoch
    }

    /// `seq` the next sample will carry (= samples sent so far).
    pub fn next_seq(&self) -> u64 {
        self.next_seq
    }
}

/// What [`StreamPublisher::send`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SendReceipt {
    /// Subscriber queues the sample went into.
    pub delivered: usize,
    /// The `t_send_ns` stamped into the sample, CLOCK_MONOTONIC ns.
    pub t_send_ns: u64,
}
