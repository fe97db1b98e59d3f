//! Devices over UDP: a controller (or plant) outside the rig that trades fixed-layout binary packets with it, as
//! flight software in the loop (Betaflight's, ArduPilot's and PX4's SITLs) and HIL benches do. A layout file
//! ([`layout`], `configs/devices/*.toml`) declares each packet's fields, types, byte order, scale, offset, frame
//! ([`frames`]) and the named signal each carries; [`bind`] checks it against a plant's signals before anything
//! flies; [`codec`] writes and reads packets each tick. [`device`] flies a device as the rig's controller over a
//! [`link`]'s sockets, starting its program when the layout says how ([`supervise`]) and arming it when it must be
//! ([`arming`], over Betaflight's [`msp`]), telling what it says of its state as events ([`device_state`]), and carrying out the plan's device faults
//! ([`device_faults`]).

pub mod arming;
pub mod bind;
pub mod codec;
pub mod device;
pub mod device_faults;
pub mod device_state;
pub mod frames;
pub mod layout;
pub mod link;
pub mod msp;
pub mod supervise;
