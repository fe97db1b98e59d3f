//! silrig-wire: what crosses between the rig's processes and how: the sample types (the contract), the iceoryx2
//! transport, time and timing statistics. The recording of everything that crossed is `silrig-recording`, above.
//!
//! - [`wire`]: the `#[repr(C)]` sample types, versioned, with their field tables and checks.
//! - [`topology`]: the rig's streams (who publishes, who reads, with which settings); [`ipc`]: the thin iceoryx2
//!   layer (per-run namespaces and cleanup, streams, typed ports, the WaitSet loop and tick timer).
//! - [`clock`]: the monotonic clock, absolute sleeps, SCHED_FIFO, the tick schedule; [`timing`]: HdrHistogram
//!   latency figures.
//!
//! Layers: uses `silrig-model` and `silrig-flight` (a plant's signals, announced on the wire, and the streams' roles);
//! knows nothing of the processes or of the recording.

pub mod clock;
pub mod ipc;
pub mod timing;
pub mod topology;
pub mod wire;
