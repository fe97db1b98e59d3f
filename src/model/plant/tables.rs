//! The F-16 aerodynamic and engine tables (Stevens & Lewis, Appendix A), embedded at compile time from
//! `src/model/plant/data/*.csv`, and the book's lookup rule: linear interpolation on uniform axes, linear extrapolation
//! from the end segment outside them (no clamping), bilinear for two-axis tables (along the row axis first).

use std::sync::LazyLock;

/// A uniformly spaced breakpoint axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axis {
    /// First breakpoint.
    pub first: f64,
    /// Spacing between breakpoints.
    pub step: f64,
    /// Number of breakpoints (at least 2).
    pub len: usize,
}

impl Axis {
    /// Breakpoint `i`.
    pub fn at(&self, i: usize) -> f64 {
        self.first + self.step * i as f64
    }

    /// Index of the lower bracketing breakpoint and the fraction along its segment. Outside the axis the end
    /// segment is used and the fraction goes below 0 or above 1: that is the book's linear extrapolation.
    #[inline(always)]
    pub fn locate(&self, x: f64) -> (usize, f64) {
        let s = (x - self.first) / self.step;
        // `as isize` saturates and maps NaN to 0; the NaN then propagates through the fraction.
        let i = (s.floor() as isize).clamp(0, self.len as isize - 2) as usize;
        (i, s - i as f64)
    }
}

/// A table of one or more columns over one axis (`cz0`, the damping derivatives).
#[derive(Debug, Clone)]
pub struct Table1 {
    /// The row axis.
    pub rows: Axis,
    /// Column names from the CSV header.
    pub columns: Vec<String>,
    /// Row-major values, `rows.len * columns.len()`.
    pub values: Vec<f64>,
}

impl Table1 {
    /// Interpolated value of column `col` at `x`.
    #[inline]
    pub fn lookup(&self, x: f64, col: usize) -> f64 {
        let n = self.columns.len();
        let (i, t) = self.rows.locate(x);
        let a = self.values[i * n + col];
        let b = self.values[(i + 1) * n + col];
        a + t * (b - a)
    }

    /// All columns at `x`, sharing one axis search.
    #[inline]
    pub fn lookup_all<const N: usize>(&self, x: f64) -> [f64; N] {
        debug_assert_eq!(N, self.columns.len());
        let (i, t) = self.rows.locate(x);
        let lo = &self.values[i * N..(i + 1) * N];
        let hi = &self.values[(i + 1) * N..(i + 2) * N];
        std::array::from_fn(|k| lo[k] + t * (hi[k] - lo[k]))
    }
}

/// A two-axis table: rows by columns.
#[derive(Debug, Clone)]
pub struct Table2 {
    /// The row axis (alpha, or altitude for thrust).
    pub rows: Axis,
    /// The column axis (elevator, beta, |beta|, or Mach).
    pub cols: Axis,
    /// Row-major values, `rows.len * cols.len`.
    pub values: Vec<f64>,
}

impl Table2 {
    /// Raw entry at breakpoint indices.
    pub fn entry(&self, row: usize, col: usize) -> f64 {
        self.values[row * self.cols.len + col]
    }

    /// Bilinear lookup: along the row axis in the two bracketing columns, then along the column axis.
    #[inline]
    pub fn lookup(&self, row: f64, col: f64) -> f64 {
        let (i, ti) = self.rows.locate(row);
        let (j, tj) = self.cols.locate(col);
        let n = self.cols.len;
        let v = &self.values;
        let c0 = v[i * n + j] + ti * (v[(i + 1) * n + j] - v[i * n + j]);
        let c1 = v[i * n + j + 1] + ti * (v[(i + 1) * n + j + 1] - v[i * n + j + 1]);
        c0 + tj * (c1 - c0)
    }
}

/// Every table of the model.
#[derive(Debug, Clone)]
pub struct F16Tables {
    /// C_X(alpha_deg, elevator_deg).
    pub cx: Table2,
    /// C_Z0(alpha_deg), one column.
    pub cz: Table1,
    /// C_m(alpha_deg, elevator_deg).
    pub cm: Table2,
    /// C_l(alpha_deg, |beta_deg|).
    pub cl: Table2,
    /// C_n(alpha_deg, |beta_deg|).
    pub cn: Table2,
    /// C_l per (aileron_deg / 20) over (alpha_deg, beta_deg).
    pub dlda: Table2,
    /// C_l per (rudder_deg / 30) over (alpha_deg, beta_deg).
    pub dldr: Table2,
    /// C_n per (aileron_deg / 20) over (alpha_deg, beta_deg).
    pub dnda: Table2,
    /// C_n per (rudder_deg / 30) over (alpha_deg, beta_deg).
    pub dndr: Table2,
    /// Damping derivatives over alpha_deg: CXq CYr CYp CZq Clr Clp Cmq Cnr Cnp.
    pub damping: Table1,
    /// Idle thrust, lbf, over (alt_ft, mach).
    pub thrust_idle: Table2,
    /// Military thrust, lbf, over (alt_ft, mach).
    pub thrust_mil: Table2,
    /// Maximum (afterburner) thrust, lbf, over (alt_ft, mach).
    pub thrust_max: Table2,
}

/// The tables, parsed once from the embedded CSV files.
pub static F16_TABLES: LazyLock<F16Tables> =
    LazyLock::new(|| F16Tables::from_embedded().unwrap_or_else(|e| panic!("embedded F-16 data is corrupt: {e}")));

macro_rules! embedded {
    ($name:literal) => {
        ($name, include_str!(concat!("data/", $name, ".csv")))
    };
}

/// The embedded CSV files, by name.
pub const EMBEDDED_CSV: [(&str, &str); 13] = [
    embedded!("cx"),
    embedded!("cz"),
    embedded!("cm"),
    embedded!("cl"),
    embedded!("cn"),
    embedded!("dlda"),
    embedded!("dldr"),
    embedded!("dnda"),
    embedded!("dndr"),
    embedded!("damping"),
    embedded!("thrust_idle"),
    embedded!("thrust_mil"),
    embedded!("thrust_max"),
];

impl F16Tables {
    /// Parse every embedded CSV file.
    pub fn from_embedded() -> Result<Self, String> {
        let csv = |name: &str| {
            let text = EMBEDDED_CSV.iter().find(|(n, _)| *n == name).map(|(_, t)| *t).expect("known table");
            ParsedCsv::parse(text).map_err(|e| format!("{name}.csv: {e}"))
        };
        let t2 = |name: &str| csv(name)?.into_table2().map_err(|e| format!("{name}.csv: {e}"));
        let t1 = |name: &str| csv(name)?.into_table1().map_err(|e| format!("{name}.csv: {e}"));
        Ok(Self {
            cx: t2("cx")?,
            cz: t1("cz")?,
            cm: t2("cm")?,
            cl: t2("cl")?,
            cn: t2("cn")?,
            dlda: t2("dlda")?,
            dldr: t2("dldr")?,
            dnda: t2("dnda")?,
            dndr: t2("dndr")?,
            damping: t1("damping")?,
            thrust_idle: t2("thrust_idle")?,
            thrust_mil: t2("thrust_mil")?,
            thrust_max: t2("thrust_max")?,
        })
    }
}

/// One data file: header cells, row breakpoints and row-major values.
#[derive(Debug, Clone)]
pub struct ParsedCsv {
    /// Header cells after the first one (column breakpoints or coefficient names).
    pub header: Vec<String>,
    /// First cell of every data row.
    pub row_breakpoints: Vec<f64>,
    /// Row-major values.
    pub values: Vec<f64>,
}

impl ParsedCsv {
    /// Parse the data folder's CSV format (see `src/model/plant/data/README.md`).
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let header: Vec<String> =
            lines.next().ok_or("empty file")?.split(',').skip(1).map(|c| c.trim().to_string()).collect();
        let (mut row_breakpoints, mut values) = (Vec::new(), Vec::new());
        for (k, line) in lines.enumerate() {
            let cells: Vec<&str> = line.split(',').collect();
            if cells.len() != header.len() + 1 {
                return Err(format!("data row {} has {} cells, expected {}", k + 1, cells.len(), header.len() + 1));
            }
            let num = |c: &str| c.trim().parse::<f64>().map_err(|e| format!("data row {}: {c:?}: {e}", k + 1));
            row_breakpoints.push(num(cells[0])?);
            for c in &cells[1..] {
                values.push(num(c)?);
            }
        }
        Ok(Self { header, row_breakpoints, values })
    }

    fn into_table1(self) -> Result<Table1, String> {
        Ok(Table1 { rows: uniform_axis(&self.row_breakpoints)?, columns: self.header, values: self.values })
    }

    fn into_table2(self) -> Result<Table2, String> {
        let cols: Vec<f64> =
            self.header.iter().map(|c| c.parse::<f64>()).collect::<Result<_, _>>().map_err(|e| e.to_string())?;
        Ok(Table2 { rows: uniform_axis(&self.row_breakpoints)?, cols: uniform_axis(&cols)?, values: self.values })
    }
}

fn uniform_axis(points: &[f64]) -> Result<Axis, String> {
    if points.len() < 2 {
        return Err("an axis needs at least two breakpoints".into());
    }
    let step = points[1] - points[0];
    for (i, p) in points.iter().enumerate() {
        if (p - (points[0] + step * i as f64)).abs() > 1e-9 * step.abs().max(1.0) {
            return Err(format!("axis is not uniform at breakpoint {i} ({p})"));
        }
    }
    Ok(Axis { first: points[0], step, len: points.len() })
}
