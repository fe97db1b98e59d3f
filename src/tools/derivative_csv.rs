//! `silrig plant derivative`: state and control rows in, state-derivative rows out, for engineers who cross-check
//! their own F-16 implementation against this one. Every value is printed so that it parses back to the same f64;
//! a row the model cannot take (outside [`silrig_model::plant::envelope`]) stops the run naming its line and column, so
//! no NaN is ever printed.

use silrig_model::plant::{
    ControlInputs, ExternalForcing, F16Model, F16State, STATE_DOT_NAMES, STATE_LEN, STATE_NAMES, aero, envelope,
};
use std::io::{BufRead, Write};

/// Input columns besides the 13 states.
pub const CONTROL_COLUMNS: [&str; 4] = ["throttle", "elevator_deg", "aileron_deg", "rudder_deg"];
/// The optional CG column (default 0.35).
pub const XCG_COLUMN: &str = "xcg";

/// A problem with the input, naming where it is.
#[derive(Debug, thiserror::Error)]
pub enum DerivativeCsvError {
    /// The input has no header line.
    #[error("line 1: empty input, expected a header naming the columns {}", required_columns().join(","))]
    MissingHeader,
    /// A required column is not in the header.
    #[error("line 1: the header has no column `{column}`")]
    MissingColumn {
        /// The missing column.
        column: &'static str,
    },
    /// A data row lacks a cell.
    #[error("line {line}, column `{column}`: missing value (the row has {cells} cells)")]
    MissingValue {
        /// 1-based line number.
        line: usize,
        /// Column name.
        column: &'static str,
        /// Cells in the row.
        cells: usize,
    },
    /// A cell is not a number, or is NaN or infinite.
    #[error("line {line}, column `{column}`: {problem}: {text:?}")]
    BadValue {
        /// 1-based line number.
        line: usize,
        /// Column name.
        column: &'static str,
        /// What is wrong.
        problem: &'static str,
        /// The cell text.
        text: String,
    },
    /// A row whose state lies outside the model's envelope ([`envelope::check`]).
    #[error("line {line}, column `{column}`: outside the model's envelope: {problem}")]
    OutsideEnvelope {
        /// 1-based line number.
        line: usize,
        /// The state column at fault.
        column: &'static str,
        /// What is wrong, with the value.
        problem: String,
    },
    /// The model gave a non-finite derivative for a row inside the envelope (a state the envelope does not yet
    /// know to refuse): refused rather than printed.
    #[error("line {line}: the model gives a non-finite `{derivative}` for this row")]
    NonFinite {
        /// 1-based line number.
        line: usize,
        /// The derivative column.
        derivative: &'static str,
    },
    /// Reading or writing failed.
    #[error("i/o: {0}")]
    Io(#[from] std::io::Error),
}

fn required_columns() -> Vec<&'static str> {
    STATE_NAMES.iter().chain(CONTROL_COLUMNS.iter()).copied().collect()
}

/// Read rows from `input`, write one derivative row per input row to `output`. Rows already written stay written
/// when a later row is bad. Returns the number of rows processed.
pub fn run(input: impl BufRead, mut output: impl Write) -> Result<usize, DerivativeCsvError> {
    let mut lines = input.lines().enumerate();
    let header = loop {
        match lines.next() {
            Some((_, line)) => {
                let line = line?;
                if !line.trim().is_empty() {
                    break line;
                }
            }
            None => return Err(DerivativeCsvError::MissingHeader),
        }
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let position = |c: &str| names.iter().position(|n| *n == c);
    let mut columns: Vec<(&'static str, usize)> = Vec::with_capacity(STATE_LEN + 5);
    for c in required_columns() {
        columns.push((c, position(c).ok_or(DerivativeCsvError::MissingColumn { column: c })?));
    }
    let xcg_index = position(XCG_COLUMN);

    writeln!(output, "{}", STATE_DOT_NAMES.join(","))?;
    let mut rows = 0;
    let mut values = [0.0; STATE_LEN + 4];
    for (index, line) in lines {
        let line = line?;
        let line_no = index + 1;
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let parse = |column: &'static str, i: usize| -> Result<f64, DerivativeCsvError> {
            let text =
                cells.get(i).ok_or(DerivativeCsvError::MissingValue { line: line_no, column, cells: cells.len() })?;
            if text.is_empty() {
                return Err(DerivativeCsvError::MissingValue { line: line_no, column, cells: cells.len() });
            }
            let bad = |problem| DerivativeCsvError::BadValue { line: line_no, column, problem, text: text.to_string() };
            let v: f64 = text.parse().map_err(|_| bad("not a number"))?;
            if v.is_nan() {
                return Err(bad("NaN"));
            }
            if v.is_infinite() {
                return Err(bad("infinite"));
            }
            Ok(v)
        };
        for (k, (column, i)) in columns.iter().enumerate() {
            values[k] = parse(column, *i)?;
        }
        let xcg = match xcg_index {
            Some(i) => parse(XCG_COLUMN, i)?,
            None => aero::XCG_REF,
        };
        let state = F16State::from_array(values[..STATE_LEN].try_into().expect("13 states"));
        let controls = ControlInputs {
            throttle: values[13],
            elevator_deg: values[14],
            aileron_deg: values[15],
            rudder_deg: values[16],
        };
        envelope::check(&state).map_err(|e| DerivativeCsvError::OutsideEnvelope {
            line: line_no,
            column: e.state,
            problem: format!("{} = {}: {}", e.state, e.value, e.problem),
        })?;
        let d = F16Model::new(xcg).derivative(&state, &controls, &ExternalForcing::default());
        if let Some(i) = d.iter().position(|v| !v.is_finite()) {
            return Err(DerivativeCsvError::NonFinite { line: line_no, derivative: STATE_DOT_NAMES[i] });
        }
        let row: Vec<String> = d.iter().map(|v| format!("{v:?}")).collect();
        writeln!(output, "{}", row.join(","))?;
        rows += 1;
    }
    output.flush()?;
    Ok(rows)
}
