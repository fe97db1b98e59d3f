//! What the F-16 reports each tick and what it takes, as plain tables: the snapshot ([`PlantSnapshot`]), its outputs
//! in the announced order with names and units ([`output_signals`], [`f16_outputs`]), and its inputs with their
//! units and ranges ([`INPUTS`], [`input_range`]). `silrig_flight::f16_signals` builds the rig's announcement from
//! them and the FMU of `silrig-fmu-f16` its model description, so both announce the same signals and the same bits.
//! Its traced outputs are the trace's plant columns of old; the 13 states in book units follow untraced.

use crate::actuator::SURFACE_CMD_LIMIT_DEG;
use crate::plant::{F16State, STATE_LEN, STATE_NAMES};
use crate::units::{M_PER_FT, rad_to_deg};

/// What the plant reports each tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantSnapshot {
    /// Tick index.
    pub tick: u64,
    /// Simulated time, s.
    pub t_s: f64,
    /// The 13 states as measured: the true state plus any active sensor fault (`PlantRunner::true_state` in
    /// `silrig_flight::sim` is the one without).
    pub state: F16State,
    /// Surface positions the actuators hold now: aileron, elevator, rudder, deg. Taken when a tick begins, that is
    /// the deflection held over the step that ended at t_s (the initial position at tick 0); after
    /// [`crate::vehicle::F16Vehicle::actuate`], the one for the step that starts at t_s.
    pub surfaces_deg: [f64; 3],
    /// Throttle position, 0..1 (as the surfaces).
    pub throttle: f64,
    /// Normal load factor at the accelerometer, g, of the true state with these surface positions
    /// ([`crate::plant::ModelOutputs::nz_g`]).
    pub nz_g: f64,
    /// Lateral load factor at the accelerometer, g ([`crate::plant::ModelOutputs::ny_g`]).
    pub ny_g: f64,
}

/// What the plant measured at t_k, as the trace shows it (`phi_deg` to `ny_g` of the trace's loop columns): also
/// the F-16's first outputs on the wire ([`f16_outputs`]), so both give the same bits.
pub fn measured_columns(snap: &PlantSnapshot) -> [f64; 12] {
    let x = &snap.state;
    [
        rad_to_deg(x.phi_rad),
        rad_to_deg(x.theta_rad),
        rad_to_deg(x.psi_rad),
        rad_to_deg(x.alpha_rad),
        rad_to_deg(x.beta_rad),
        rad_to_deg(x.p_radps),
        rad_to_deg(x.q_radps),
        rad_to_deg(x.r_radps),
        x.vt_fps * M_PER_FT,
        x.alt_ft,
        snap.nz_g,
        snap.ny_g,
    ]
}

/// The F-16's plant name.
pub const PLANT_NAME: &str = "f16";

/// Outputs that `trace.csv` shows, in its order: measured at t_k, then the actuators' positions.
const TRACED: [(&str, &str); 16] = [
    ("phi_deg", "deg"),
    ("theta_deg", "deg"),
    ("psi_deg", "deg"),
    ("alpha_deg", "deg"),
    ("beta_deg", "deg"),
    ("p_dps", "deg/s"),
    ("q_dps", "deg/s"),
    ("r_dps", "deg/s"),
    ("vt_mps", "m/s"),
    ("alt_ft", "ft"),
    ("nz_g", "g"),
    ("ny_g", "g"),
    ("aileron_deg", "deg"),
    ("elevator_deg", "deg"),
    ("rudder_deg", "deg"),
    ("throttle", "1"),
];

/// Units of the states, in [`STATE_NAMES`] order.
const STATE_UNITS: [&str; STATE_LEN] =
    ["ft/s", "rad", "rad", "rad", "rad", "rad", "rad/s", "rad/s", "rad/s", "ft", "ft", "ft", "%"];

/// The state `alt_ft` is the traced output of that name already.
const ALT_STATE: usize = 11;

/// Outputs of the F-16: the traced ones, then the states but altitude.
pub const OUTPUTS_LEN: usize = TRACED.len() + STATE_LEN - 1;

/// The inputs: the three surfaces, deg (refused beyond the wire's +-[`SURFACE_CMD_LIMIT_DEG`]; the actuators
/// clamp to each surface's travel), and the throttle, 0..1.
pub const INPUTS: [(&str, &str); 4] = [("aileron", "deg"), ("elevator", "deg"), ("rudder", "deg"), ("throttle", "1")];

/// The output that reports each input's actuator position.
pub const HELD_OUTPUT: [usize; 4] = [12, 13, 14, 15];

/// The range a command of input `k` (in [`INPUTS`] order) may take: +-[`SURFACE_CMD_LIMIT_DEG`] for the surfaces,
/// 0..1 for the throttle.
pub fn input_range(k: usize) -> (f64, f64) {
    if k < 3 { (-SURFACE_CMD_LIMIT_DEG, SURFACE_CMD_LIMIT_DEG) } else { (0.0, 1.0) }
}

/// The outputs in announced order: (name, unit, shown in `trace.csv`).
pub fn output_signals() -> [(&'static str, &'static str, bool); OUTPUTS_LEN] {
    let states = (0..STATE_LEN).filter(|k| *k != ALT_STATE);
    let mut out = [("", "", false); OUTPUTS_LEN];
    for (slot, (name, unit)) in out.iter_mut().zip(TRACED) {
        *slot = (name, unit, true);
    }
    for (slot, k) in out[TRACED.len()..].iter_mut().zip(states) {
        *slot = (STATE_NAMES[k], STATE_UNITS[k], false);
    }
    out
}

/// A snapshot's outputs in the order of [`output_signals`]: the measured ones as the single-process loop's trace
/// row computes its columns ([`measured_columns`]), then the actuators' positions and the states.
pub fn f16_outputs(snap: &PlantSnapshot) -> [f64; OUTPUTS_LEN] {
    let mut out = [0.0; OUTPUTS_LEN];
    let measured = measured_columns(snap);
    out[..measured.len()].copy_from_slice(&measured);
    out[measured.len()..TRACED.len()].copy_from_slice(&[
        snap.surfaces_deg[0],
        snap.surfaces_deg[1],
        snap.surfaces_deg[2],
        snap.throttle,
    ]);
    let states = snap.state.to_array();
    for (slot, k) in out[TRACED.len()..].iter_mut().zip((0..STATE_LEN).filter(|k| *k != ALT_STATE)) {
        *slot = states[k];
    }
    out
}
