//! The F-16 as one plant among others: what it reports each tick ([`PlantSnapshot`], [`measured_columns`]), its
//! announcement ([`f16_signals`]), the outputs of a snapshot in that order ([`f16_outputs`]) and, for a controller built for the F-16 such as the paper's, the snapshot read back from any
//! plant's outputs by name ([`F16Outputs`]). Its traced outputs are the trace's plant columns of old, so every
//! golden trace keeps its bytes; the 13 states in book units follow untraced, so the paper's controller reads the
//! very numbers the single-process loop hands it.

use crate::signals::{InputSignal, OutputSignal, PlantSignals};
use silrig_model::actuator::SURFACE_CMD_LIMIT_DEG;
use silrig_model::plant::{F16State, STATE_LEN, STATE_NAMES};
use silrig_model::units::{M_PER_FT, rad_to_deg};

/// What the plant reports each tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantSnapshot {
    /// Tick index.
    pub tick: u64,
    /// Simulated time, s.
    pub t_s: f64,
    /// The 13 states as measured: the true state plus any active sensor fault (see [`crate::sim::PlantRunner::true_state`]).
    pub state: F16State,
    /// Surface positions the actuators hold now: aileron, elevator, rudder, deg. Taken when a tick begins, that is
    /// the deflection held over the step that ended at t_s (the initial position at tick 0); after
    /// [`crate::sim::PlantRunner::actuate`], the one for the step that starts at t_s.
    pub surfaces_deg: [f64; 3],
    /// Throttle position, 0..1 (as the surfaces).
    pub throttle: f64,
    /// Normal load factor at the accelerometer, g, of the true state with these surface positions
    /// ([`silrig_model::plant::ModelOutputs::nz_g`]).
    pub nz_g: f64,
    /// Lateral load factor at the accelerometer, g ([`silrig_model::plant::ModelOutputs::ny_g`]).
    pub ny_g: f64,
}

/// What the plant measured at t_k, as the trace shows it (`phi_deg` to `ny_g` of [`crate::trace::LOOP_COLUMNS`]):
/// also the F-16's first outputs on the wire ([`f16_outputs`]), so both give the same bits.
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
const HELD_OUTPUT: [usize; 4] = [12, 13, 14, 15];

/// The F-16's announcement; `hold` is what its failsafe commands (trim surfaces, the held throttle), in input order.
pub fn f16_signals(hold: [f64; 4]) -> PlantSignals {
    let traced =
        TRACED.iter().map(|(name, unit)| OutputSignal { name: (*name).into(), unit: (*unit).into(), in_trace: true });
    let states = (0..STATE_LEN).filter(|k| *k != ALT_STATE).map(|k| OutputSignal {
        name: STATE_NAMES[k].into(),
        unit: STATE_UNITS[k].into(),
        in_trace: false,
    });
    let inputs = INPUTS.iter().enumerate().map(|(k, (name, unit))| {
        let (min, max) = if k < 3 { (-SURFACE_CMD_LIMIT_DEG, SURFACE_CMD_LIMIT_DEG) } else { (0.0, 1.0) };
        InputSignal {
            name: (*name).into(),
            unit: (*unit).into(),
            min,
            max,
            hold: hold[k],
            held_output: Some(HELD_OUTPUT[k]),
            // The throttle command has never been a column: the paper's controller does not command it.
            command_in_trace: k < 3,
        }
    });
    PlantSignals { plant: PLANT_NAME.into(), outputs: traced.chain(states).collect(), inputs: inputs.collect() }
}

/// A snapshot's outputs in the order of [`f16_signals`]: the measured ones as the single-process loop's trace row
/// computes its columns ([`measured_columns`]), then the actuators' positions and the states.
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

/// Where an F-16 controller finds what it reads among a plant's outputs, resolved by name once: any plant that
/// publishes these names can be flown by it.
#[derive(Debug, Clone, PartialEq)]
pub struct F16Outputs {
    state: [usize; STATE_LEN],
    surfaces: [usize; 3],
    throttle: usize,
    nz: usize,
    ny: usize,
}

impl F16Outputs {
    /// The indices of the states, surfaces, throttle and load factors in `plant`'s outputs; the error names the
    /// first one missing and what the plant has.
    pub fn resolve(plant: &PlantSignals) -> Result<Self, String> {
        let mut state = [0; STATE_LEN];
        for (slot, name) in state.iter_mut().zip(STATE_NAMES) {
            *slot = plant.output(name)?;
        }
        Ok(Self {
            state,
            surfaces: [plant.output("aileron_deg")?, plant.output("elevator_deg")?, plant.output("rudder_deg")?],
            throttle: plant.output("throttle")?,
            nz: plant.output("nz_g")?,
            ny: plant.output("ny_g")?,
        })
    }

    /// The snapshot a sample's `outputs` carry.
    pub fn snapshot(&self, tick: u64, t_s: f64, outputs: &[f64]) -> PlantSnapshot {
        PlantSnapshot {
            tick,
            t_s,
            state: F16State::from_array(&self.state.map(|k| outputs[k])),
            surfaces_deg: self.surfaces.map(|k| outputs[k]),
            throttle: outputs[self.throttle],
            nz_g: outputs[self.nz],
            ny_g: outputs[self.ny],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace;

    #[test]
    fn the_f16s_trace_columns_are_the_loop_columns() {
        let signals = f16_signals([0.0, -1.9, 0.0, 0.2]);
        assert_eq!(signals.check(32, 16), Ok(()));
        assert_eq!(signals.outputs.len(), OUTPUTS_LEN);
        let diagnostics = trace::attitude_diagnostic_names(5);
        assert_eq!(signals.trace_columns(&diagnostics), trace::columns(5));
        assert_eq!(signals.hold(), [0.0, -1.9, 0.0, 0.2]);
    }

    #[test]
    fn a_snapshot_survives_its_outputs_bit_for_bit() {
        let state = F16State::from_array(&std::array::from_fn(|k| 0.1 * k as f64 + 0.37));
        let snap = PlantSnapshot {
            tick: 7,
            t_s: 0.07,
            state,
            surfaces_deg: [1.5, -2.25, 0.125],
            throttle: 0.3,
            nz_g: 1.01,
            ny_g: -0.02,
        };
        let outputs = f16_outputs(&snap);
        let read = F16Outputs::resolve(&f16_signals([0.0; 4])).unwrap();
        assert_eq!(read.snapshot(7, 0.07, &outputs), snap);
    }

    #[test]
    fn a_plant_without_a_state_is_named() {
        let mut signals = f16_signals([0.0; 4]);
        signals.outputs.retain(|o| o.name != "q_radps");
        let e = F16Outputs::resolve(&signals).unwrap_err();
        assert!(e.starts_with("plant f16 has no output `q_radps`; its outputs: phi_deg, theta_deg"), "{e}");
    }
}
