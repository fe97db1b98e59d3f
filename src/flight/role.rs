//! The rig's three processes ([`Role`]), named here, below the transport, because a fault of a scenario targets one
//! of them; the streams between them are `silrig_wire::topology`.

use serde::{Deserialize, Serialize};

/// A process of the rig; also what a fault targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Role {
    /// The plant: the time master.
    Plant,
    /// The controller, ours or a user's.
    Controller,
    /// The logger.
    Logger,
}

impl Role {
    /// Every role, in the order reports list them.
    pub const ALL: [Role; 3] = [Role::Plant, Role::Controller, Role::Logger];

    /// Name in plans, reports, events and node names.
    pub fn label(self) -> &'static str {
        match self {
            Role::Plant => "plant",
            Role::Controller => "controller",
            Role::Logger => "logger",
        }
    }

    /// The binary that runs this role (beside the launcher).
    pub fn binary(self) -> &'static str {
        match self {
            Role::Plant => "silrig-plant",
            Role::Controller => "silrig-controller",
            Role::Logger => "silrig-logger",
        }
    }

    /// SCHED_FIFO priority asked for in realtime mode: the plant, the time master, above the controller, whose
    /// answer it waits for; the logger well below both (nobody waits for it within a tick), but above every
    /// ordinary process: a build beside the rig once kept it from running for 3 s while the plant and controller
    /// flew on, longer than its queue held then (docs/src/measurements/soak.md).
    pub fn fifo_priority(self) -> Option<i32> {
        match self {
            Role::Plant => Some(80),
            Role::Controller => Some(79),
            Role::Logger => Some(70),
        }
    }

    /// Whether a restarted process of this role continues from what its predecessor saved (`--resume`).
    pub fn resumes(self) -> bool {
        matches!(self, Role::Plant | Role::Controller)
    }
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}
