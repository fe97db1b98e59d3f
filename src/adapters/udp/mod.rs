//! Devices over UDP: a controller (or plant) outside the rig that trades fixed-layout binary packets with it, as
//! flight software in the loop (Betaflight's, ArduPilot's and PX4's SITLs) and HIL benches do. A layout file
//! ([`layout`], `configs/devices/*.toml`) declares each packet's fields, types, byte order, scale, offset, frame
//! ([`frames`]) and the named signal each carries; [`bind`] checks it against a plant's signals before anything
//! flies; [`codec`] writes and reads packets each tick.

pub mod bind;
pub mod codec;
pub mod frames;
pub mod layout;
