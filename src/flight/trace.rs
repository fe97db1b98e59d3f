//! The closed-loop trace: one row per sample, named columns, written as `trace.csv`. The single-process loop, the
//! logger process and the plots all speak this one format.
//!
//! Row convention: a run of N steps has N + 1 rows, t = 0 to the duration. Row k holds the state (and load factors)
//! at t_k, the command the controller computed from it, and the actuator positions held over [t_k, t_k+1)
//! (zero-order hold): the deflections that acted on the aircraft from that sample on, row 0 included.

use std::io::{BufRead, Write};
use std::path::Path;

/// Columns every closed-loop trace starts with, in order: the plant's state and surfaces and the command, whatever
/// the controller. The controller's diagnostics follow (see [`attitude_diagnostic_names`] for ours).
pub const LOOP_COLUMNS: [&str; 21] = [
    "t_s",
    "phi_deg",
    "theta_deg",
    "psi_deg",
    "alpha_deg",
    "beta_deg",
    "p_dps",
    "q_dps",
    "r_dps",
    "vt_mps",
    "alt_ft",
    "nz_g",
    "ny_g",
    "aileron_cmd_deg",
    "elevator_cmd_deg",
    "rudder_cmd_deg",
    "aileron_deg",
    "elevator_deg",
    "rudder_deg",
    "throttle",
    // 0 until the first flight discontinuity, then one more at each: a restarted plant flew ticks again, and rows
    // from here come from its flight (the rig's logger; `silrig sim` always writes 0).
    "flight_segment",
];

/// Controller channels in column-name form.
pub const CHANNELS: [&str; 3] = ["phi", "theta", "psi"];

/// The diagnostics of the paper's controller with `nodes` RBF nodes per channel, in the order it reports them:
/// the sliding surface `s_<channel>` and the RBF estimate `fhat_<channel>` per channel, then the RBF weights
/// `w_<channel>_<k>`, channel by channel.
pub fn attitude_diagnostic_names(nodes: usize) -> Vec<String> {
    let mut names: Vec<String> = CHANNELS.iter().map(|ch| format!("s_{ch}")).collect();
    names.extend(CHANNELS.iter().map(|ch| format!("fhat_{ch}")));
    for ch in CHANNELS {
        for k in 1..=nodes {
            names.push(format!("w_{ch}_{k}"));
        }
    }
    names
}

/// Column names of a trace of the paper's controller with `nodes` RBF nodes per channel.
pub fn columns(nodes: usize) -> Vec<String> {
    let mut names: Vec<String> = LOOP_COLUMNS.iter().map(|s| s.to_string()).collect();
    names.extend(attitude_diagnostic_names(nodes));
    names
}

/// A table of f64 rows under named columns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trace {
    /// Column names.
    pub columns: Vec<String>,
    /// Rows, each as long as `columns`.
    pub rows: Vec<Vec<f64>>,
}

/// A trace file that cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum TraceReadError {
    /// I/O failure.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The file has no header.
    #[error("empty trace file")]
    Empty,
    /// A cell is not a number.
    #[error("line {line}, column `{column}`: not a number: {text:?}")]
    BadCell {
        /// 1-based line.
        line: usize,
        /// Column name.
        column: String,
        /// Cell text.
        text: String,
    },
    /// A row has the wrong number of cells.
    #[error("line {line}: {cells} cells, the header has {expected}")]
    RowLength {
        /// 1-based line.
        line: usize,
        /// Cells found.
        cells: usize,
        /// Cells expected.
        expected: usize,
    },
}

impl Trace {
    /// An empty trace with these columns.
    pub fn new(columns: Vec<String>) -> Self {
        Self { columns, rows: Vec::new() }
    }

    /// Index of a column.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// A copy of one column.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let i = self.index(name)?;
        Some(self.rows.iter().map(|r| r[i]).collect())
    }

    /// The header line.
    pub fn header_line(&self) -> String {
        self.columns.join(",")
    }

    /// One row as a CSV line; values print so that they parse back to the same f64.
    pub fn format_row(row: &[f64]) -> String {
        let mut line = String::with_capacity(row.len() * 20);
        Self::push_row(&mut line, row);
        line
    }

    /// Append [`Self::format_row`]'s text to `line`, allocating nothing beyond its growth (the logger writes a
    /// row per tick).
    pub fn push_row(line: &mut String, row: &[f64]) {
        use std::fmt::Write as _;
        for (i, v) in row.iter().enumerate() {
            if i > 0 {
                line.push(',');
            }
            let _ = write!(line, "{v:?}");
        }
    }

    /// Write as CSV.
    pub fn write_csv(&self, mut out: impl Write) -> std::io::Result<()> {
        writeln!(out, "{}", self.header_line())?;
        for row in &self.rows {
            writeln!(out, "{}", Self::format_row(row))?;
        }
        out.flush()
    }

    /// Write as CSV to a file.
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        self.write_csv(std::io::BufWriter::new(std::fs::File::create(path)?))
    }

    /// Read a CSV trace. A last line without its newline (a writer killed mid-line) is dropped, not an error.
    pub fn read_csv(input: impl BufRead) -> Result<Self, TraceReadError> {
        let mut text = String::new();
        let mut input = input;
        input.read_to_string(&mut text)?;
        let complete = if text.ends_with('\n') { &text[..] } else { &text[..text.rfind('\n').map_or(0, |i| i + 1)] };
        let mut lines = complete.lines();
        let header = lines.next().ok_or(TraceReadError::Empty)?;
        let columns: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
        let mut rows = Vec::new();
        for (k, line) in lines.enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let line_no = k + 2;
            let cells: Vec<&str> = line.split(',').collect();
            if cells.len() != columns.len() {
                return Err(TraceReadError::RowLength { line: line_no, cells: cells.len(), expected: columns.len() });
            }
            let row = cells
                .iter()
                .zip(&columns)
                .map(|(c, name)| {
                    c.trim().parse::<f64>().map_err(|_| TraceReadError::BadCell {
                        line: line_no,
                        column: name.clone(),
                        text: c.to_string(),
                    })
                })
                .collect::<Result<Vec<f64>, _>>()?;
            rows.push(row);
        }
        Ok(Self { columns, rows })
    }

    /// Read a CSV trace file.
    pub fn load(path: &Path) -> Result<Self, TraceReadError> {
        Self::read_csv(std::io::BufReader::new(std::fs::File::open(path)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trips_bit_for_bit_and_tolerates_a_torn_last_line() {
        let mut t = Trace::new(vec!["t_s".into(), "x".into()]);
        t.rows.push(vec![0.0, 0.1 + 0.2]);
        t.rows.push(vec![0.01, -1e-300]);
        let mut buf = Vec::new();
        t.write_csv(&mut buf).unwrap();
        assert_eq!(Trace::read_csv(&buf[..]).unwrap(), t);
        buf.extend_from_slice(b"0.02,1.2"); // killed mid-line
        assert_eq!(Trace::read_csv(&buf[..]).unwrap(), t);
        assert!(Trace::read_csv(&b"t_s,x\n1,zz\n"[..]).unwrap_err().to_string().contains("line 2, column `x`"));
    }

    #[test]
    fn columns_list_weights_per_channel_and_node() {
        let c = columns(5);
        assert_eq!(c.len(), 27 + 15);
        assert_eq!(c[27], "w_phi_1");
        assert_eq!(c.last().unwrap(), "w_psi_5");
    }
}
