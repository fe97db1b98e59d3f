//! silrig-adapters: what turns a foreign thing into a plant or a controller of the rig. Each adapter is a folder:
//! [`udp`], a device reached over UDP with its packet layouts declared in a file (Betaflight's SITL ships with
//! silrig as `configs/devices/betaflight-sitl.toml`).
//!
//! Layers: above `silrig-flight` (a flight as data); the rig's process bodies do not know which adapter flies.

pub mod udp;
