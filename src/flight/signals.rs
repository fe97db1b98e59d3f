//! A plant's named signals as data: what a plant announces when it joins (its name, its outputs with units, its
//! inputs with units, ranges and the values a failsafe holds), the checks every announcement passes, lookups by
//! name whose errors list what the plant has, and the rule that turns a plant's signals into `trace.csv`'s columns.
//! The F-16's own table is [`crate::f16_signals`]; the wire carries an announcement as `PlantInfo`.

/// Longest name of a plant, signal or diagnostic, in bytes (the wire keeps one byte for the terminating NUL).
pub const MAX_NAME_LEN: usize = 31;
/// Longest unit, in bytes.
pub const MAX_UNIT_LEN: usize = 15;

/// One value the plant publishes every tick.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSignal {
    /// Name: ASCII letters, digits and '_' (a `trace.csv` column when [`Self::in_trace`]).
    pub name: String,
    /// Unit, free text of printable ASCII (`deg`, `m/s`, `1` for a ratio).
    pub unit: String,
    /// Whether the logger writes it to `trace.csv` (every output is in the recording).
    pub in_trace: bool,
}

/// One value the plant takes from each command.
#[derive(Debug, Clone, PartialEq)]
pub struct InputSignal {
    /// Name: ASCII letters, digits and '_'.
    pub name: String,
    /// Unit, as for outputs.
    pub unit: String,
    /// A command below this is refused (the plant holds its last valid command).
    pub min: f64,
    /// A command above this is refused.
    pub max: f64,
    /// What the plant's failsafe commands while no controller answers (the F-16's: trim), within min..max.
    pub hold: f64,
    /// The output that reports what this input's actuator holds now, if the plant has one: the controller's
    /// session blends from it when joining a flying plant, and the trace shows it after the commands.
    pub held_output: Option<usize>,
    /// Whether the command of this input is a `trace.csv` column ([`PlantSignals::command_column`]).
    pub command_in_trace: bool,
}

/// What a plant announces: its name and its signals in the order of the wire's vectors.
#[derive(Debug, Clone, PartialEq)]
pub struct PlantSignals {
    /// The plant's name (`f16`, `c172x`), ASCII letters, digits and '_'.
    pub plant: String,
    /// The outputs, in the order of every plant sample's `outputs`.
    pub outputs: Vec<OutputSignal>,
    /// The inputs, in the order of every command's `inputs`.
    pub inputs: Vec<InputSignal>,
}

/// Whether `name` is a valid plant, signal or diagnostic name: 1..=31 of ASCII letters, digits and '_'.
pub fn valid_name(name: &str) -> bool {
    (1..=MAX_NAME_LEN).contains(&name.len()) && name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
}

/// Whether `unit` is a valid unit: up to 15 printable ASCII characters, no comma or quote (units go into CSV
/// headers of tools downstream).
pub fn valid_unit(unit: &str) -> bool {
    unit.len() <= MAX_UNIT_LEN && unit.bytes().all(|b| b.is_ascii_graphic() && b != b',' && b != b'"')
}

impl PlantSignals {
    /// Every rule an announcement must keep, the first broken one named: a valid plant name, at least one output
    /// and at most `max_outputs`, at most `max_inputs` inputs, valid and unique names (outputs among themselves,
    /// inputs among themselves), valid units, finite ranges with min < max and the hold value inside, a held
    /// output that exists, and no column of the trace named twice.
    pub fn check(&self, max_outputs: usize, max_inputs: usize) -> Result<(), String> {
        let plant = &self.plant;
        if !valid_name(plant) {
            return Err(format!("plant name {plant:?}: use 1..={MAX_NAME_LEN} of ASCII letters, digits and '_'"));
        }
        if self.outputs.is_empty() {
            return Err(format!("plant {plant} announces no outputs: a plant publishes at least one"));
        }
        if self.outputs.len() > max_outputs {
            return Err(format!(
                "plant {plant} announces {} outputs; a sample carries at most {max_outputs}",
                self.outputs.len()
            ));
        }
        if self.inputs.len() > max_inputs {
            return Err(format!(
                "plant {plant} announces {} inputs; a command carries at most {max_inputs}",
                self.inputs.len()
            ));
        }
        let signals = self
            .outputs
            .iter()
            .map(|o| ("output", &o.name, &o.unit))
            .chain(self.inputs.iter().map(|i| ("input", &i.name, &i.unit)));
        for (kind, name, unit) in signals {
            if !valid_name(name) {
                return Err(format!(
                    "plant {plant}: {kind} name {name:?}: use 1..={MAX_NAME_LEN} of ASCII letters, digits and '_'"
                ));
            }
            if !valid_unit(unit) {
                return Err(format!(
                    "plant {plant}: {kind} {name}: unit {unit:?}: use up to {MAX_UNIT_LEN} printable ASCII characters, \
                     no comma or quote"
                ));
            }
        }
        duplicate("output", self.outputs.iter().map(|o| o.name.as_str())).map_err(|e| format!("plant {plant}: {e}"))?;
        duplicate("input", self.inputs.iter().map(|i| i.name.as_str())).map_err(|e| format!("plant {plant}: {e}"))?;
        for i in &self.inputs {
            let name = &i.name;
            if !(i.min.is_finite() && i.max.is_finite() && i.min < i.max) {
                return Err(format!(
                    "plant {plant}: input {name}: range {}..{} is not a finite range with min < max",
                    i.min, i.max
                ));
            }
            if !(i.hold >= i.min && i.hold <= i.max) {
                return Err(format!(
                    "plant {plant}: input {name}: hold value {} outside its range {}..{}",
                    i.hold, i.min, i.max
                ));
            }
            if let Some(k) = i.held_output
                && k >= self.outputs.len()
            {
                return Err(format!(
                    "plant {plant}: input {name}: held output {k} does not exist ({} outputs)",
                    self.outputs.len()
                ));
            }
        }
        duplicate("trace column", self.trace_columns(&[]).iter().map(String::as_str))
            .map_err(|e| format!("plant {plant}: {e}"))
    }

    /// The index of output `name`; the error names the signal, the plant and what it has.
    pub fn output(&self, name: &str) -> Result<usize, String> {
        self.outputs.iter().position(|o| o.name == name).ok_or_else(|| {
            let have: Vec<&str> = self.outputs.iter().map(|o| o.name.as_str()).collect();
            format!("plant {} has no output `{name}`; its outputs: {}", self.plant, have.join(", "))
        })
    }

    /// The index of input `name`; the error names the signal, the plant and what it has.
    pub fn input(&self, name: &str) -> Result<usize, String> {
        self.inputs.iter().position(|i| i.name == name).ok_or_else(|| {
            let have: Vec<&str> = self.inputs.iter().map(|i| i.name.as_str()).collect();
            format!("plant {} has no input `{name}`; its inputs: {}", self.plant, have.join(", "))
        })
    }

    /// The failsafe's command: every input's hold value.
    pub fn hold(&self) -> Vec<f64> {
        self.inputs.iter().map(|i| i.hold).collect()
    }

    /// The trace column of input `k`'s command: `<name>_cmd_<unit>` when the unit is a word (`aileron_cmd_deg`),
    /// `<name>_cmd` otherwise (`throttle_cmd` for a unit of `1` or `m/s`). A name that already ends in its unit
    /// keeps it once, at the end: input `aileron_deg` in deg commands `aileron_cmd_deg`, not `aileron_deg_cmd_deg`.
    pub fn command_column(&self, k: usize) -> String {
        let i = &self.inputs[k];
        let word =
            !i.unit.is_empty() && i.unit != "1" && i.unit.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_');
        if !word {
            return format!("{}_cmd", i.name);
        }
        let stem = i.name.strip_suffix(&format!("_{}", i.unit)).filter(|s| !s.is_empty()).unwrap_or(&i.name);
        format!("{stem}_cmd_{}", i.unit)
    }

    /// Whether output `k` reports what an input's actuator holds.
    fn is_held(&self, k: usize) -> bool {
        self.inputs.iter().any(|i| i.held_output == Some(k))
    }

    /// `trace.csv`'s columns for this plant and a controller with `diagnostics`: `t_s`; the traced outputs that
    /// are not an actuator's position (what the plant measured at t_k); the traced commands; the traced actuator
    /// positions (held over [t_k, t_k+1), from the next sample); `flight_segment`; the diagnostics. The F-16's are
    /// [`crate::trace::LOOP_COLUMNS`] exactly.
    pub fn trace_columns(&self, diagnostics: &[String]) -> Vec<String> {
        let mut columns = vec!["t_s".to_string()];
        let traced = |held: bool| {
            self.outputs
                .iter()
                .enumerate()
                .filter(move |(k, o)| o.in_trace && self.is_held(*k) == held)
                .map(|(_, o)| o.name.clone())
        };
        columns.extend(traced(false));
        columns.extend(
            (0..self.inputs.len()).filter(|k| self.inputs[*k].command_in_trace).map(|k| self.command_column(k)),
        );
        columns.extend(traced(true));
        columns.push("flight_segment".into());
        columns.extend(diagnostics.iter().cloned());
        columns
    }

    /// One row of `trace.csv`, into `row` (cleared first, so a writer of one row a tick reuses its allocation), in
    /// the order of [`Self::trace_columns`]: the outputs of tick k, the command answering it (`None`: it never came,
    /// NaN), the outputs of the sample that closes the tick (`None`: never came, NaN), the flight segment and the
    /// diagnostics (padded with NaN to `diagnostics_len`).
    #[allow(clippy::too_many_arguments)]
    pub fn trace_row(
        &self,
        row: &mut Vec<f64>,
        t_s: f64,
        outputs: &[f64],
        command: Option<&[f64]>,
        next_outputs: Option<&[f64]>,
        flight_segment: u32,
        diagnostics: &[f64],
    ) {
        row.clear();
        row.push(t_s);
        let traced = |k: &usize| self.outputs[*k].in_trace;
        row.extend((0..self.outputs.len()).filter(traced).filter(|k| !self.is_held(*k)).map(|k| outputs[k]));
        row.extend(
            (0..self.inputs.len())
                .filter(|k| self.inputs[*k].command_in_trace)
                .map(|k| command.and_then(|c| c.get(k).copied()).unwrap_or(f64::NAN)),
        );
        row.extend(
            (0..self.outputs.len())
                .filter(traced)
                .filter(|k| self.is_held(*k))
                .map(|k| next_outputs.and_then(|n| n.get(k).copied()).unwrap_or(f64::NAN)),
        );
        row.push(f64::from(flight_segment));
        row.extend_from_slice(diagnostics);
    }
}

/// The first name that appears twice, as an error.
fn duplicate<'a>(kind: &str, names: impl Iterator<Item = &'a str>) -> Result<(), String> {
    let mut seen = std::collections::BTreeSet::new();
    for name in names {
        if !seen.insert(name) {
            return Err(format!("{kind} `{name}` named twice"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plant() -> PlantSignals {
        let output = |name: &str, unit: &str| OutputSignal { name: name.into(), unit: unit.into(), in_trace: true };
        PlantSignals {
            plant: "rover".into(),
            outputs: vec![output("x_m", "m"), output("steer_deg", "deg"), output("v_mps", "m/s")],
            inputs: vec![
                InputSignal {
                    name: "steer".into(),
                    unit: "deg".into(),
                    min: -30.0,
                    max: 30.0,
                    hold: 0.0,
                    held_output: Some(1),
                    command_in_trace: true,
                },
                InputSignal {
                    name: "speed".into(),
                    unit: "m/s".into(),
                    min: 0.0,
                    max: 5.0,
                    hold: 0.0,
                    held_output: None,
                    command_in_trace: true,
                },
            ],
        }
    }

    #[test]
    fn trace_columns_put_measurements_then_commands_then_actuator_positions() {
        let p = plant();
        assert_eq!(p.check(32, 16), Ok(()));
        let columns = p.trace_columns(&["e".to_string()]);
        assert_eq!(columns, ["t_s", "x_m", "v_mps", "steer_cmd_deg", "speed_cmd", "steer_deg", "flight_segment", "e"]);
        let mut row = Vec::new();
        p.trace_row(&mut row, 0.5, &[1.0, 2.0, 3.0], Some(&[4.0, 5.0]), Some(&[6.0, 7.0, 8.0]), 0, &[9.0]);
        assert_eq!(row, [0.5, 1.0, 3.0, 4.0, 5.0, 7.0, 0.0, 9.0]);
        p.trace_row(&mut row, 0.5, &[1.0, 2.0, 3.0], None, None, 1, &[]);
        assert!(row[3].is_nan() && row[4].is_nan() && row[5].is_nan() && row[6] == 1.0);
    }

    #[test]
    fn a_command_column_carries_its_unit_once() {
        let mut p = plant();
        // An FMU's inputs often carry their unit in the name already.
        p.inputs[0].name = "steer_deg".into();
        p.inputs[0].held_output = None;
        assert_eq!(p.command_column(0), "steer_cmd_deg");
        p.inputs[0].name = "steer".into();
        assert_eq!(p.command_column(0), "steer_cmd_deg");
        // A name that is only its unit is left whole, and a unit that is no word is never appended.
        p.inputs[0].name = "deg".into();
        assert_eq!(p.command_column(0), "deg_cmd_deg");
        p.inputs[1].name = "speed_mps".into();
        assert_eq!(p.command_column(1), "speed_mps_cmd");
        assert_eq!(p.check(32, 16), Ok(()));
    }

    #[test]
    fn lookups_name_the_signal_and_list_the_plants() {
        let p = plant();
        assert_eq!(p.output("v_mps"), Ok(2));
        assert_eq!(p.input("speed"), Ok(1));
        let e = p.output("theta_deg").unwrap_err();
        assert_eq!(e, "plant rover has no output `theta_deg`; its outputs: x_m, steer_deg, v_mps");
        assert!(p.input("throttle").unwrap_err().contains("its inputs: steer, speed"));
    }

    #[test]
    fn every_broken_rule_is_named() {
        let refused = |edit: &dyn Fn(&mut PlantSignals), needle: &str| {
            let mut p = plant();
            edit(&mut p);
            let e = p.check(32, 16).unwrap_err();
            assert!(e.contains(needle), "{e} should say {needle}");
        };
        refused(&|p| p.outputs.clear(), "announces no outputs");
        refused(&|p| p.outputs[2].name = "x_m".into(), "output `x_m` named twice");
        refused(&|p| p.inputs[1].name = "steer".into(), "input `steer` named twice");
        refused(&|p| p.outputs[0].name = "x".repeat(32), "use 1..=31");
        refused(&|p| p.outputs[0].name = "x m".into(), "output name \"x m\"");
        refused(&|p| p.plant = String::new(), "plant name \"\"");
        refused(&|p| p.inputs[0].unit = "deg,rad".into(), "unit \"deg,rad\"");
        refused(&|p| p.inputs[0].max = f64::NAN, "not a finite range");
        refused(&|p| p.inputs[0].hold = 31.0, "hold value 31 outside");
        refused(&|p| p.inputs[0].held_output = Some(3), "held output 3 does not exist");
        refused(&|p| p.outputs[0].name = "steer_cmd_deg".into(), "trace column `steer_cmd_deg` named twice");
        let mut p = plant();
        p.outputs.push(OutputSignal { name: "y".into(), unit: String::new(), in_trace: false });
        assert!(p.check(3, 16).unwrap_err().contains("4 outputs; a sample carries at most 3"));
    }
}
