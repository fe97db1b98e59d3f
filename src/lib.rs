//! silrig: a real-time software-in-the-loop rig for flight control.
//!
//! The library holds all the math (F-16 plant, integrator, actuators), and the binaries in `bins/` are thin shells
//! over it. Pure modules ([`plant`], [`integrator`], [`actuator`]) do no I/O, IPC or clock reads.

#![warn(missing_docs)]
// `!(x > 0.0)` is how we reject NaN along with the out-of-range values; keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod actuator;
pub mod bench;
pub mod integrator;
pub mod plant;
pub mod plot;
pub mod rng;
pub mod trace;
pub mod units;
