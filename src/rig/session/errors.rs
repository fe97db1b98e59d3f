//! What a session's calls can end in: [`SessionError`], each phrased for the person running the controller, and
//! [`Status`], the codes the C ABI of `libsilrig_client.so` returns for them (and `silrig contract` writes into the C
//! header and the Python module); [`check_client_layout`] refuses a client built against another contract.

use silrig_wire::ipc::IpcError;
use silrig_wire::wire::{CommandSample, PlantSample};

/// What can go wrong in a session, each phrased for the person running the controller.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The run's arguments, environment or scenario are not usable.
    #[error("{0}")]
    Setup(String),
    /// The client was built against another contract than this library.
    #[error("{0}")]
    Layout(String),
    /// No plant announced itself, or sent a sample, in time after opening.
    #[error(
        "no plant on run `{run}` within {waited_s} s: is the rig running with this run id? (start it first, \
         e.g. `silrig run --controller external`, and give the controller the SILRIG_* variables it prints)"
    )]
    NoRig {
        /// Run id.
        run: String,
        /// How long it waited, s.
        waited_s: f64,
    },
    /// The run has a controller already.
    #[error("refusing to start a second controller: run `{run}` has one already")]
    SecondController {
        /// Run id.
        run: String,
    },
    /// The command was refused and not sent; the plant holds the last valid command for this tick.
    #[error("tick {tick}: command refused, not sent ({reason}); the plant holds the last valid command")]
    CommandRefused {
        /// The tick it answered.
        tick: u64,
        /// What is wrong with it.
        reason: String,
    },
    /// The API was used out of order or with wrong sizes.
    #[error("{0}")]
    Usage(String),
    /// The plant's announcement does not fit: unreadable, a signal the controller asks for is missing, or a
    /// restarted plant announced other signals.
    #[error("{0}")]
    Plant(String),
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] IpcError),
}

/// Every outcome of a session call as the C ABI of `libsilrig_client.so` returns it: 0 and positive values are not
/// errors, negative ones are (the reason is in `silrig_last_error()`). `silrig contract` writes them into the C
/// header and the Python module, so a client never types them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub enum Status {
    /// The call did what it says.
    Ok = 0,
    /// SIGTERM or SIGINT arrived: close the session (its report is written) and exit.
    Stopped = 1,
    /// The plant has flown the whole scenario: close the session and exit.
    RunEnded = 2,
    /// The scenario gives no value of that name (`silrig_plant_parameter`): the model keeps its own.
    NotGiven = 3,
    /// The API was used wrongly (a NULL pointer, a command without a sample, a count that does not match).
    ErrUsage = -1,
    /// The client was built against another contract (layout version or sample sizes differ).
    ErrLayout = -2,
    /// The run's variables or scenario are unusable, or the diagnostics do not fit a command.
    ErrSetup = -3,
    /// No plant sample arrived within twice the startup timeout: no rig runs with this run id.
    ErrNoRig = -4,
    /// The run has a controller already.
    ErrSecondController = -5,
    /// The command was refused (NaN, infinity, out of range) and not sent; the plant holds the last valid one.
    ErrCommandRefused = -6,
    /// The transport failed.
    ErrTransport = -7,
    /// A bug in the library (a panic was caught at the boundary).
    ErrInternal = -8,
    /// The plant's signals do not fit: a name the controller asks for is missing, or a restarted plant announced
    /// other signals.
    ErrPlant = -9,
}

impl Status {
    /// Every status, in code order of appearance.
    pub const ALL: [Status; 13] = [
        Status::Ok,
        Status::Stopped,
        Status::RunEnded,
        Status::NotGiven,
        Status::ErrUsage,
        Status::ErrLayout,
        Status::ErrSetup,
        Status::ErrNoRig,
        Status::ErrSecondController,
        Status::ErrCommandRefused,
        Status::ErrTransport,
        Status::ErrInternal,
        Status::ErrPlant,
    ];

    /// The code the C ABI returns.
    pub const fn code(self) -> i32 {
        self as i32
    }

    /// The constant's name without the `SILRIG_` prefix (`OK`, `ERR_NO_RIG`).
    pub const fn name(self) -> &'static str {
        match self {
            Status::Ok => "OK",
            Status::Stopped => "STOPPED",
            Status::RunEnded => "RUN_ENDED",
            Status::NotGiven => "NOT_GIVEN",
            Status::ErrUsage => "ERR_USAGE",
            Status::ErrLayout => "ERR_LAYOUT",
            Status::ErrSetup => "ERR_SETUP",
            Status::ErrNoRig => "ERR_NO_RIG",
            Status::ErrSecondController => "ERR_SECOND_CONTROLLER",
            Status::ErrCommandRefused => "ERR_COMMAND_REFUSED",
            Status::ErrTransport => "ERR_TRANSPORT",
            Status::ErrInternal => "ERR_INTERNAL",
            Status::ErrPlant => "ERR_PLANT",
        }
    }

    /// What it means, for the header's comments.
    pub const fn meaning(self) -> &'static str {
        match self {
            Status::Ok => "the call did what it says",
            Status::Stopped => "SIGTERM or SIGINT arrived: close the session and exit",
            Status::RunEnded => "the plant has flown the whole scenario: close the session and exit",
            Status::NotGiven => "the scenario gives no value of that name: the model keeps its own",
            Status::ErrUsage => "API misuse: NULL pointer, command without a sample, wrong count",
            Status::ErrLayout => "built against another contract (layout version or sample sizes)",
            Status::ErrSetup => "SILRIG_* variables, scenario or diagnostics unusable",
            Status::ErrNoRig => "no plant announced itself within twice the startup timeout",
            Status::ErrSecondController => "the run has a controller already",
            Status::ErrCommandRefused => "command refused (NaN, infinity, out of range), not sent; plant holds",
            Status::ErrTransport => "the transport failed",
            Status::ErrInternal => "a bug in the library (a panic caught at the boundary)",
            Status::ErrPlant => "the plant lacks a signal asked for, or a restarted plant announced other signals",
        }
    }
}

impl SessionError {
    /// The status the C ABI returns for this error.
    pub fn status(&self) -> Status {
        match self {
            SessionError::Setup(_) => Status::ErrSetup,
            SessionError::Layout(_) => Status::ErrLayout,
            SessionError::NoRig { .. } => Status::ErrNoRig,
            SessionError::SecondController { .. } => Status::ErrSecondController,
            SessionError::CommandRefused { .. } => Status::ErrCommandRefused,
            SessionError::Usage(_) => Status::ErrUsage,
            SessionError::Plant(_) => Status::ErrPlant,
            SessionError::Transport(_) => Status::ErrTransport,
        }
    }
}

/// Refuse a client built against another contract than this library: another layout version (named both ways)
/// or samples of other sizes (a header edited by hand, or packed by another compiler setting).
pub fn check_client_layout(layout_version: u32, plant_size: usize, command_size: usize) -> Result<(), SessionError> {
    let ours = silrig_wire::wire::WIRE_LAYOUT_VERSION;
    if layout_version != ours {
        return Err(SessionError::Layout(format!(
            "the client was built against wire layout version {layout_version}, this library speaks version {ours}: \
             rebuild the client with the header `silrig contract --c-header` writes for this build"
        )));
    }
    for (what, theirs, ours) in [
        ("plant sample", plant_size, size_of::<PlantSample>()),
        ("command sample", command_size, size_of::<CommandSample>()),
    ] {
        if theirs != ours {
            return Err(SessionError::Layout(format!(
                "the client's {what} is {theirs} bytes, the contract's is {ours} (layout version {layout_version}): \
                 the header was changed or compiled with other packing"
            )));
        }
    }
    Ok(())
}
