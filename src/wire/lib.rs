//! silrig-wire: what crosses between the rig's processes and how: the sample types (the contract), the iceoryx2
//! transport, time, timing statistics and the recording of everything that crossed.
//!
//! - [`wire`]: the `#[repr(C)]` sample types, versioned, with their field tables and checks.
//! - [`topology`]: the rig's streams (who publishes, who reads, with which settings); [`ipc`]: the thin iceoryx2
//!   layer (per-run namespaces and cleanup, streams, typed ports, the WaitSet loop and tick timer).
//! - [`clock`]: the monotonic clock, absolute sleeps, SCHED_FIFO, the tick schedule; [`timing`]: HdrHistogram
//!   latency figures.
//! - [`recording`]: the logger's sinks (CSV, MCAP) and reading a recording back.
//!
//! Layers: uses `silrig-model` and `silrig-flight` (trace rows for the recording); knows nothing of the processes.

pub mod clock;
pub mod ipc;
pub mod recording;
pub mod timing;
pub mod topology;
pub mod wire;
