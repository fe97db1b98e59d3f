//! The F-16 as one plant among others: what it reports each tick ([`PlantSnapshot`], [`measured_columns`]), its
//! announcement ([`f16_signals`]), the outputs of a snapshot in that order ([`f16_outputs`]) and, for a controller built for the F-16 such as the paper's, the snapshot read back from any
//! plant's outputs by name ([`F16Outputs`]). Its traced outputs are the trace's plant columns of old, so every
//! golden trace keeps its bytes; the 13 states in book units follow untraced, so the paper's controller reads the
//! very numbers the single-process loop hands it.

use crate::signals::{InputSignal, OutputSignal, PlantSignals};
use silrig_model::f16_outputs::{HELD_OUTPUT, input_range, output_signals};
use silrig_model::plant::{F16State, STATE_LEN, STATE_NAMES};

/// The snapshot, its outputs and the F-16's tables: the model's own ([`silrig_model::f16_outputs`]), kept here under
/// their old names.
pub use silrig_model::f16_outputs::{INPUTS, OUTPUTS_LEN, PLANT_NAME, PlantSnapshot, f16_outputs, measured_columns};

/// The F-16's announcement; `hold` is what its failsafe commands (trim surfaces, the held throttle), in input order.
pub fn f16_signals(hold: [f64; 4]) -> PlantSignals {
    let outputs = output_signals().into_iter().map(|(name, unit, in_trace)| OutputSignal {
        name: name.into(),
        unit: unit.into(),
        in_trace,
    });
    let inputs = INPUTS.iter().enumerate().map(|(k, (name, unit))| {
        let (min, max) = input_range(k);
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
    PlantSignals { plant: PLANT_NAME.into(), outputs: outputs.collect(), inputs: inputs.collect() }
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
