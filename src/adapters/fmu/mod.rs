//! A co-simulation FMU (FMI 2.0 or 3.0, opened by `silrig-fmi`) as the rig's plant or controller: [`plant`] maps
//! its variables to a plant's named signals and flies it through the rig's plant session, [`controller`] maps them
//! to a controller's reads and commands and serves it as one more controller, [`variables`] is what the two share
//! (signal names, parameters, serialized state).

pub mod controller;
pub mod plant;
pub mod variables;
