//! Trace columns for the figure families: a column the figure needs but the trace lacks is an error naming the
//! column, the trace and the figure's file.

use std::path::{Path, PathBuf};

use super::PlotError;
use silrig_flight::trace::Trace;

/// Column access that turns a missing column into an error naming it.
pub(super) struct Columns<'a> {
    trace: &'a Trace,
    file: PathBuf,
    who: String,
}

impl<'a> Columns<'a> {
    pub(super) fn new(trace: &'a Trace, file: &Path, who: &str) -> Result<Self, PlotError> {
        if trace.rows.is_empty() {
            return Err(PlotError::NoData { file: file.to_path_buf(), problem: format!("{who} has no rows") });
        }
        Ok(Self { trace, file: file.to_path_buf(), who: who.to_string() })
    }

    pub(super) fn get(&self, column: &str) -> Result<Vec<f64>, PlotError> {
        self.trace.column(column).ok_or_else(|| PlotError::MissingColumn {
            file: self.file.clone(),
            trace: self.who.clone(),
            column: column.to_string(),
        })
    }
}

pub(super) fn zip(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    x.iter().copied().zip(y.iter().copied()).collect()
}
