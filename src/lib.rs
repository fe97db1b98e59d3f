//! silrig: a real-time software-in-the-loop rig for flight control.
//!
//! The library holds all the math (F-16 plant, integrator, actuators), and the binaries in `bins/` are thin shells
//! over it. Pure modules ([`plant`], [`integrator`], [`actuator`], [`control`]) do no I/O, IPC or clock reads.
//! The closed loop: [`scenario`] (TOML scenarios), [`sim`] (the single-process loop), [`summary`] (control-quality
//! figures), [`f_true`] (the true lumped function the RBF networks estimate), [`trace`] and [`outputs`] (files).
//!
//! Transport and timing: [`wire`] (the sample types on the wire), [`ipc`] (iceoryx2 streams, per-run namespaces,
//! WaitSet loop, timerfd ticks, cleanup), [`clock`] (monotonic clock, absolute sleeps, SCHED_FIFO, tick schedule),
//! [`timing`] (latency histograms and the timer baseline).

#![warn(missing_docs)]
// `!(x > 0.0)` is how we reject NaN along with the out-of-range values; keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod actuator;
pub mod bench;
#[cfg(feature = "bridge")]
pub mod bridge;
pub mod campaign;
pub mod check;
pub mod clock;
pub mod contract;
pub mod control;
pub mod criteria;
pub mod dispersion;
pub mod f_true;
pub mod fault;
pub mod integrator;
pub mod ipc;
pub mod judge;
pub mod outputs;
pub mod plant;
pub mod plot;
pub mod recording;
pub mod replay;
pub mod rig;
pub mod rng;
pub mod scenario;
pub mod sim;
pub mod summary;
pub mod timing;
pub mod topology;
pub mod trace;
pub mod units;
pub mod wire;
