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

/// The last column of the trace of a run whose plant held its outputs on some row (written only then, so every
/// other trace keeps its columns): 1 on a row whose outputs are the last valid ones, held in place of refused ones
/// (NaN, infinity), 0 on a row of the model's own.
pub const OUTPUTS_HELD_COLUMN: &str = "outputs_held";

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
        let mut digits = zmij::Buffer::new();
        for (i, v) in row.iter().enumerate() {
            if i > 0 {
                line.push(',');
            }
            push_f64_debug(line, *v, &mut digits);
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

    /// The columns and the last whole row of a CSV trace (none if it has no row yet), reading only its first line
    /// and its end: a restarted logger needs no more, and parsing a 10-minute run's 40 MB left its heap that
    /// large for the rest of its life.
    pub fn load_last_row(path: &Path) -> Result<Self, TraceReadError> {
        use std::io::{Read, Seek, SeekFrom};
        let mut file = std::fs::File::open(path)?;
        let len = file.seek(SeekFrom::End(0))?;
        let mut header = String::new();
        file.seek(SeekFrom::Start(0))?;
        std::io::BufReader::new(&mut file).read_line(&mut header)?;
        // Enough of the end to hold the last whole row and the newline before it; more until it does.
        let mut tail_len: u64 = 64 * 1024;
        loop {
            let from = len.saturating_sub(tail_len);
            let mut tail = Vec::new();
            file.seek(SeekFrom::Start(from))?;
            (&mut file).take(len - from).read_to_end(&mut tail)?;
            let tail = String::from_utf8_lossy(&tail);
            // Up to the last newline: a torn last line (a writer killed mid-line) is not a row.
            let whole = &tail[..tail.rfind('\n').map_or(0, |i| i + 1)];
            let body = whole.strip_suffix('\n').unwrap_or(whole);
            match (body.rfind('\n'), from) {
                (Some(i), _) => return Self::read_csv(format!("{header}{}", &whole[i + 1..]).as_bytes()),
                // The whole file is one line or none: the header alone, or nothing usable.
                (None, 0) => return Self::read_csv(whole.as_bytes()),
                (None, _) => tail_len *= 4,
            }
        }
    }
}

/// Append `v` exactly as `format!("{v:?}")` writes it (the text trace.csv has always held, which the golden
/// fingerprints pin), about four times faster: the shortest digits that read back to the same bits come from
/// `zmij` (Schubfach, as Rust's own formatter they are the shortest and, among those, the closest), laid out as
/// Rust's `Debug` does: `NaN`, `inf`, `-0.0`; plain decimals with at least one fractional digit for 1e-4 <= |v| <
/// 1e16; otherwise `1.5e-5`, `1e16`.
pub fn push_f64_debug(out: &mut String, v: f64, digits: &mut zmij::Buffer) {
    if !v.is_finite() {
        out.push_str(if v.is_nan() {
            "NaN"
        } else if v > 0.0 {
            "inf"
        } else {
            "-inf"
        });
        return;
    }
    let abs = v.abs();
    if abs == 0.0 {
        out.push_str(if v.is_sign_negative() { "-0.0" } else { "0.0" });
        return;
    }
    // zmij writes 1e-5 <= |v| < 1e16 in plain decimals, as `Debug` does from 1e-4 on; the two pick different
    // digits only at an exact tie, which needs a value of few significant bits. Most numbers of a trace (measured,
    // integrated) are neither, and take zmij's text as it is.
    if (1e-4..1e16).contains(&abs) && !may_tie(abs) {
        out.push_str(digits.format_finite(v));
        return;
    }
    // zmij's text of |v| (`1.234`, `0.0001`, `1e16`, `1.5e-5`, `123.0`): its digits and where the point goes.
    let Digits { mut buf, mut n, mut k } = Digits::of(digits.format_finite(abs).as_bytes());
    match exact_tie(abs, n) {
        Tie::No => {}
        Tie::Unknown => {
            // Too large to tell cheaply (1.7e38 to 1e40): Rust's own formatter.
            use std::fmt::Write as _;
            let _ = write!(out, "{v:?}");
            return;
        }
        // Both neighbours are as close: Rust takes the upper one, zmij the even one.
        Tie::Yes(upper) => {
            let text = upper.to_string();
            if text.len() > n {
                // 9.5 -> 10: one digit more in front.
                k += 1;
            }
            n = text.trim_end_matches('0').len().max(1);
            buf[..n].copy_from_slice(&text.as_bytes()[..n]);
        }
    }
    if v.is_sign_negative() {
        out.push('-');
    }
    lay_out_debug(out, abs, std::str::from_utf8(&buf[..n]).expect("ASCII digits"), k);
}

/// The significant digits of a decimal text, trailing zeros dropped, and its power of ten: the value is
/// `0.d × 10^k`.
struct Digits {
    buf: [u8; 40],
    n: usize,
    k: i32,
}

impl Digits {
    /// In one pass: the significant digits into `buf`, the point's position among them, the exponent after `e`.
    fn of(text: &[u8]) -> Digits {
        let mut buf = [0u8; 40];
        let (mut n, mut point, mut seen_point) = (0, 0i32, false);
        let mut exponent = 0i32;
        let mut bytes = text.iter();
        for &b in bytes.by_ref() {
            match b {
                b'.' => seen_point = true,
                b'e' | b'E' => break,
                b'0' if n == 0 => point -= i32::from(seen_point),
                _ => {
                    buf[n] = b;
                    n += 1;
                    point += i32::from(!seen_point);
                }
            }
        }
        let mut exponent_sign = 1;
        for &b in bytes {
            match b {
                b'-' => exponent_sign = -1,
                b'+' => {}
                _ => exponent = exponent * 10 + i32::from(b - b'0'),
            }
        }
        exponent *= exponent_sign;
        while n > 1 && buf[n - 1] == b'0' {
            n -= 1;
        }
        Digits { buf, n, k: point + exponent }
    }
}

/// The digits `d` of `abs = 0.d × 10^k` laid out as Rust's `Debug` does: plain decimals with at least one
/// fractional digit for 1e-4 <= |v| < 1e16, otherwise `1.5e-5`, `1e16`.
fn lay_out_debug(out: &mut String, abs: f64, d: &str, k: i32) {
    let n = d.len();
    if !(1e-4..1e16).contains(&abs) {
        out.push_str(&d[..1]);
        if n > 1 {
            out.push('.');
            out.push_str(&d[1..]);
        }
        use std::fmt::Write as _;
        let _ = write!(out, "e{}", k - 1);
    } else if k <= 0 {
        out.push_str("0.");
        (0..-k).for_each(|_| out.push('0'));
        out.push_str(d);
    } else if (k as usize) < n {
        out.push_str(&d[..k as usize]);
        out.push('.');
        out.push_str(&d[k as usize..]);
    } else {
        out.push_str(d);
        (0..k as usize - n).for_each(|_| out.push('0'));
        out.push_str(".0");
    }
}

/// Whether the exact value of `abs` lies halfway between two `n`-digit decimals, where shortest-digit algorithms
/// may round either way.
enum Tie {
    No,
    /// The upper of the two, as an integer of `n` digits (`n + 1` after a carry: 9.5 -> 10).
    Yes(u128),
    Unknown,
}

/// `abs` (finite, > 0) as `mantissa × 2^exp2` exactly, the mantissa odd.
fn odd_mantissa(abs: f64) -> (u64, i32) {
    let bits = abs.to_bits();
    let (raw_exp, fraction) = ((bits >> 52) as i32, bits & ((1 << 52) - 1));
    let (mantissa, exp2) = if raw_exp == 0 { (fraction, -1074) } else { (fraction | (1 << 52), raw_exp - 1075) };
    let zeros = mantissa.trailing_zeros();
    (mantissa >> zeros, exp2 + zeros as i32)
}

/// Whether [`exact_tie`] can find a tie: below 2^-31 a value's exact decimal has at least 22 significant digits
/// (5^32 has 23), and no shortest (at most 17 digit) number lies halfway at such a precision.
fn may_tie(abs: f64) -> bool {
    odd_mantissa(abs).1 >= -31
}

fn exact_tie(abs: f64, n: usize) -> Tie {
    let (mantissa, exp2) = odd_mantissa(abs);
    // Its exact decimal digits, trailing zeros dropped.
    let mut exact: u128 = if exp2 >= 0 {
        if exp2 > 127 - 53 {
            return Tie::Unknown;
        }
        u128::from(mantissa) << exp2
    } else if !may_tie(abs) {
        return Tie::No;
    } else {
        u128::from(mantissa) * 5u128.pow((-exp2) as u32)
    };
    while exact.is_multiple_of(10) {
        exact /= 10;
    }
    let digits = exact.checked_ilog10().map_or(1, |d| d as usize + 1);
    if digits == n + 1 && exact % 10 == 5 { Tie::Yes(exact / 10 + 1) } else { Tie::No }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_row_is_read_from_the_end_alone() {
        let dir = std::env::temp_dir().join(format!("silrig-trace-last-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("trace.csv");
        // 2,000 rows of about 80 bytes: longer than the first look at the end.
        let mut trace = Trace::new(vec!["t_s".into(), "x".into(), "flight_segment".into()]);
        for k in 0..2000 {
            trace.rows.push(vec![k as f64 * 0.01, (k as f64).sin() * 1e-7, 1.0 + (k / 1000) as f64]);
        }
        trace.save(&path).unwrap();
        let last = Trace::load_last_row(&path).unwrap();
        assert_eq!(last.columns, trace.columns);
        assert_eq!(last.rows, vec![trace.rows[1999].clone()]);
        // A torn last line is not a row.
        let mut text = std::fs::read_to_string(&path).unwrap();
        text.push_str("20.0,0.5");
        std::fs::write(&path, &text).unwrap();
        assert_eq!(Trace::load_last_row(&path).unwrap().rows, vec![trace.rows[1999].clone()]);
        // One row, the header alone, nothing.
        std::fs::write(&path, "t_s,x\n0.5,2.0\n").unwrap();
        assert_eq!(Trace::load_last_row(&path).unwrap().rows, vec![vec![0.5, 2.0]]);
        std::fs::write(&path, "t_s,x\n").unwrap();
        let header_only = Trace::load_last_row(&path).unwrap();
        assert_eq!((header_only.columns.len(), header_only.rows.len()), (2, 0));
        std::fs::write(&path, "t_s,x").unwrap();
        assert!(Trace::load_last_row(&path).is_err());
        // A row long enough to need a second, larger look.
        let wide: Vec<String> = (0..20_000).map(|i| format!("c{i}")).collect();
        let row: Vec<String> = (0..20_000).map(|i| format!("{i}.5")).collect();
        std::fs::write(&path, format!("{}\n{}\n{}\n", wide.join(","), row.join(","), row.join(","))).unwrap();
        let last = Trace::load_last_row(&path).unwrap();
        assert_eq!((last.rows.len(), last.rows[0][19_999]), (1, 19_999.5));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn numbers_are_written_as_debug_writes_them() {
        let mut digits = zmij::Buffer::new();
        let mut check = |v: f64| {
            let mut out = String::new();
            push_f64_debug(&mut out, v, &mut digits);
            assert_eq!(out, format!("{v:?}"), "bits {:#x}", v.to_bits());
        };
        for v in [
            0.0,
            -0.0,
            1.0,
            -1.5,
            0.1,
            1e-4,
            9.999e-5,
            1e-5,
            1e16,
            9.999999999999998e15,
            1e15,
            123456.0,
            1e300,
            -2.5e-310,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            1.0 / 3.0,
            100.0,
            0.000123,
            12345678901234567.0,
        ] {
            check(v);
        }
        // Random bit patterns (every exponent) and random values of the sizes a trace holds.
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            check(f64::from_bits(x));
            check((x >> 11) as f64 / (1u64 << 53) as f64 * 10f64.powi((x % 24) as i32 - 8));
        }
    }

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
