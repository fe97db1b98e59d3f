//! `silrig run --live foxglove`: the logger serves the recording's channels, as it writes them, over the Foxglove
//! WebSocket protocol (the Foxglove SDK's server, cargo feature `live`), so Foxglove or Lichtblick shows the run
//! while it flies. The logger hands each channel and message to a [`RecordingTap`] after the file has it; the
//! SDK's own threads (a tokio runtime it starts in the logger process) send them on. Each connected client has a
//! queue of [`BACKLOG_MESSAGES`]: a client that falls behind loses its oldest queued messages, and neither the
//! logger's loop nor the recording waits for it. The plant and the controller never see the server.
//!
//! The plant's announcement (`/plant_info`) is published once, when the plant starts: the server keeps the last
//! one and sends it to each client that subscribes after it, so a client that joins late still knows the signals'
//! names and units.
//!
//! Without the feature the module still builds: [`AVAILABLE`] is false and [`serve`] refuses with the build
//! command, so `silrig run --live` can say what to do before anything starts.

use silrig_recording::RecordingTap;
use std::net::SocketAddr;

/// Whether this build can serve (`cargo build --release --features live`).
pub const AVAILABLE: bool = cfg!(feature = "live");

/// Why a build without the feature cannot serve, and what to do.
pub const NOT_BUILT: &str = "this silrig was built without the `live` feature (the Foxglove WebSocket server); \
                             rebuild with `cargo build --release --features live`";

/// Messages queued for each client before its oldest are dropped: about 12 s of the seven 100 Hz channels.
pub const BACKLOG_MESSAGES: usize = 8192;

/// How long the logger, at its end, leaves a connected client to receive what is queued for it, ms.
pub const DRAIN_MS: u64 = 300;

/// Start a Foxglove WebSocket server on `addr`, named after the run; what the returned tap is handed goes to the
/// server's clients.
#[cfg(feature = "live")]
pub fn serve(addr: SocketAddr, run_id: &str) -> anyhow::Result<Box<dyn RecordingTap>> {
    let context = foxglove::Context::new();
    let latched = std::sync::Arc::new(server::Latched::default());
    let server = foxglove::WebSocketServer::new()
        .name(format!("silrig run {run_id}"))
        .bind(addr.ip().to_string(), addr.port())
        .message_backlog_size(BACKLOG_MESSAGES)
        .context(&context)
        .listener(latched.clone())
        .start_blocking()
        .map_err(|e| anyhow::anyhow!("--live foxglove={addr}: starting the Foxglove WebSocket server: {e}"))?;
    Ok(Box::new(server::FoxgloveTap { context, server: Some(server), channels: Vec::new(), latched }))
}

/// Refuse: this build has no server ([`NOT_BUILT`]).
#[cfg(not(feature = "live"))]
pub fn serve(addr: SocketAddr, _run_id: &str) -> anyhow::Result<Box<dyn RecordingTap>> {
    anyhow::bail!("--live foxglove={addr}: {NOT_BUILT}")
}

#[cfg(feature = "live")]
mod server {
    use silrig_recording::{RecordingTap, TapChannel, topics};
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex};
    use std::time::Duration;

    /// Channels published once, whose last message a client that subscribes later is sent at once.
    const LATCHED_TOPICS: [&str; 1] = [topics::PLANT_INFO];

    /// The last message of each latched channel (by the server's channel id), with its log time.
    #[derive(Default)]
    pub(super) struct Latched {
        last: Mutex<HashMap<foxglove::ChannelId, (Arc<foxglove::RawChannel>, Option<(Vec<u8>, u64)>)>>,
    }

    impl foxglove::websocket::ServerListener for Latched {
        fn on_subscribe(&self, client: foxglove::websocket::Client, channel: foxglove::websocket::ChannelView) {
            let last = self.last.lock().unwrap_or_else(|e| e.into_inner());
            if let Some((ch, Some((data, log_time_ns)))) = last.get(&channel.id()) {
                ch.log_with_meta_to_sink(
                    data,
                    foxglove::PartialMetadata::with_log_time(*log_time_ns),
                    client.sink_id(),
                );
            }
        }
    }

    /// The server and its channels, by the recording's channel id, each with whether it is latched.
    pub(super) struct FoxgloveTap {
        pub(super) context: Arc<foxglove::Context>,
        pub(super) server: Option<foxglove::WebSocketServerHandle>,
        pub(super) channels: Vec<Option<(Arc<foxglove::RawChannel>, bool)>>,
        pub(super) latched: Arc<Latched>,
    }

    impl RecordingTap for FoxgloveTap {
        fn channel(&mut self, c: &TapChannel) {
            let schema = foxglove::Schema::new(c.schema_name, c.schema_encoding, c.schema_data.to_vec());
            let built = foxglove::ChannelBuilder::new(c.topic)
                .message_encoding(c.message_encoding)
                .schema(schema)
                .metadata(c.metadata.clone())
                .context(&self.context)
                .build_raw();
            let id = usize::from(c.id);
            if self.channels.len() <= id {
                self.channels.resize(id + 1, None);
            }
            match built {
                Ok(channel) => {
                    let latched = LATCHED_TOPICS.contains(&c.topic);
                    if latched {
                        let mut last = self.latched.last.lock().unwrap_or_else(|e| e.into_inner());
                        last.insert(channel.id(), (channel.clone(), None));
                    }
                    self.channels[id] = Some((channel, latched))
                }
                // The recording has the channel whatever the server makes of it.
                Err(e) => eprintln!("logger: --live: channel {} not served: {e}", c.topic),
            }
        }

        fn message(&mut self, id: u16, log_time_ns: u64, data: &[u8]) {
            if let Some(Some((channel, latched))) = self.channels.get(usize::from(id)) {
                // Kept before it is sent: a client subscribing meanwhile gets it once or twice, never not at all. Only
                // the latched channels' messages (one a plant life) take the lock, not the rows of every tick.
                if *latched {
                    let mut last = self.latched.last.lock().unwrap_or_else(|e| e.into_inner());
                    if let Some((_, kept)) = last.get_mut(&channel.id()) {
                        *kept = Some((data.to_vec(), log_time_ns));
                    }
                }
                channel.log_with_meta(data, foxglove::PartialMetadata::with_log_time(log_time_ns));
            }
        }

        fn finish(&mut self) {
            let Some(server) = self.server.take() else { return };
            if server.client_count() > 0 {
                std::thread::sleep(Duration::from_millis(super::DRAIN_MS));
            }
            // Stopping closes each connection; a client that does not answer the close is not waited for long.
            let stopped = server.stop();
            let (done, waited) = std::sync::mpsc::channel();
            std::thread::spawn(move || {
                stopped.wait_blocking();
                let _ = done.send(());
            });
            let _ = waited.recv_timeout(Duration::from_secs(1));
        }
    }
}
