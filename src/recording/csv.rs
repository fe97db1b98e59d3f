//! The CSV sink: `trace.csv` (the same columns and values as `silrig sim`) and `timing.csv` (per-tick stamps,
//! flags and gaps), appended in whole rows, so a kill loses at most the last unflushed batch and a restarted logger
//! continues the same files.

use crate::{LoggedRow, RowSink, TIMING_COLUMNS, timing_values};
use silrig_flight::trace::Trace;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A CSV file the logger appends whole rows to, in batches. A batch the disk does not take whole (a full disk) is
/// cut back out, so the file only ever holds whole rows; the error names the file.
struct RowFile {
    path: PathBuf,
    file: File,
    /// Rows not written yet.
    pending: String,
    /// The file's length at its last whole row, bytes.
    whole_len: u64,
}

impl RowFile {
    /// Open `name` in `dir` for appending; a new file gets `header` first. Appending is what lets a restarted
    /// logger continue a run's log without overwriting anything.
    fn open(dir: &Path, name: &str, header: &str) -> std::io::Result<Self> {
        let path = dir.join(name);
        let named = |e: std::io::Error| std::io::Error::new(e.kind(), format!("{}: {e}", path.display()));
        let fresh = std::fs::metadata(&path).map_or(true, |m| m.len() == 0);
        let mut file = OpenOptions::new().create(true).append(true).open(&path).map_err(named)?;
        if fresh {
            writeln!(file, "{header}").map_err(named)?;
        } else {
            // A writer killed mid-line leaves a torn last line; start ours on a new line so it stays the only damage.
            // Only the last byte is read: reading the whole file (40 MB late in a 10-minute run) left a restarted
            // logger's heap that much larger for the rest of its life (the soak saw 11 MB grow to 47 MB).
            if last_byte(&path).map_err(named)? != Some(b'\n') {
                writeln!(file).map_err(named)?;
            }
        }
        let whole_len = file.metadata().map_err(named)?.len();
        Ok(Self { path, file, pending: String::new(), whole_len })
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let written = self.file.write_all(self.pending.as_bytes());
        let batch_len = self.pending.len() as u64;
        // Cleared, not dropped: the next batch reuses its allocation.
        self.pending.clear();
        match written {
            Ok(()) => {
                self.whole_len += batch_len;
                Ok(())
            }
            Err(e) => {
                let _ = self.file.set_len(self.whole_len);
                Err(std::io::Error::new(e.kind(), format!("writing {}: {e}", self.path.display())))
            }
        }
    }
}

/// The last byte of the file at `path`, `None` when it is empty.
fn last_byte(path: &Path) -> std::io::Result<Option<u8>> {
    use std::io::{Read, Seek, SeekFrom};
    let mut file = File::open(path)?;
    if file.seek(SeekFrom::End(0))? == 0 {
        return Ok(None);
    }
    file.seek(SeekFrom::End(-1))?;
    let mut byte = [0u8; 1];
    file.read_exact(&mut byte)?;
    Ok(Some(byte[0]))
}

/// Append `v` in decimal, as `{v}` writes it, without the formatting machinery (14 numbers a row): `itoa` writes
/// two digits a step and hands them over as text without checking them again, which our digit loop's `from_utf8`
/// did (2 % of a lockstep logger's time).
fn push_i64(out: &mut String, v: i64, digits: &mut itoa::Buffer) {
    out.push_str(digits.format(v));
}

/// `trace.csv` and `timing.csv` in the run's folder.
pub struct CsvSink {
    out_dir: PathBuf,
    /// Opened by [`RowSink::start`], whose columns name the diagnostics; a file a previous logger of the run
    /// started keeps its header.
    trace: Option<RowFile>,
    timing: RowFile,
    /// The digits of the number being written, reused.
    digits: itoa::Buffer,
}

impl CsvSink {
    /// Open `timing.csv` in `out_dir` for appending (`trace.csv` opens with the trace's columns).
    pub fn open(out_dir: &Path) -> std::io::Result<Self> {
        let timing = RowFile::open(out_dir, "timing.csv", &TIMING_COLUMNS.join(","))?;
        Ok(Self { out_dir: out_dir.to_path_buf(), trace: None, timing, digits: itoa::Buffer::new() })
    }
}

impl RowSink for CsvSink {
    fn start(&mut self, trace_columns: &[String]) -> std::io::Result<()> {
        if self.trace.is_none() {
            self.trace = Some(RowFile::open(&self.out_dir, "trace.csv", &trace_columns.join(","))?);
        }
        Ok(())
    }

    fn row(&mut self, row: &LoggedRow) -> std::io::Result<()> {
        let trace = self.trace.as_mut().ok_or_else(|| std::io::Error::other("trace.csv written before its header"))?;
        // Straight into the pending batch: no allocation per row or value.
        Trace::push_row(&mut trace.pending, row.trace);
        trace.pending.push('\n');
        let line = &mut self.timing.pending;
        for (i, v) in timing_values(row).iter().enumerate() {
            if i > 0 {
                line.push(',');
            }
            if let Some(v) = v {
                push_i64(line, *v, &mut self.digits);
            }
        }
        line.push('\n');
        Ok(())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if let Some(trace) = self.trace.as_mut() {
            trace.flush()?;
        }
        self.timing.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_are_written_as_display_writes_them() {
        let mut digits = itoa::Buffer::new();
        for v in [0, 1, -1, 9, 10, -10, 123_456_789, i64::MAX, i64::MIN, 1_764_000_000_123_456_789] {
            let mut out = String::new();
            push_i64(&mut out, v, &mut digits);
            assert_eq!(out, v.to_string());
        }
    }

    #[test]
    fn a_torn_last_line_is_ended_before_the_next_rows_and_a_whole_one_is_left_alone() {
        let dir = std::env::temp_dir().join(format!("silrig-csv-torn-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("torn.csv"), "a,b\n1,2\n3,").unwrap();
        std::fs::write(dir.join("whole.csv"), "a,b\n1,2\n").unwrap();
        assert_eq!(last_byte(&dir.join("torn.csv")).unwrap(), Some(b','));
        for name in ["torn.csv", "whole.csv", "new.csv"] {
            let mut f = RowFile::open(&dir, name, "a,b").unwrap();
            f.pending.push_str("5,6\n");
            f.flush().unwrap();
        }
        let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
        assert_eq!(read("torn.csv"), "a,b\n1,2\n3,\n5,6\n");
        assert_eq!(read("whole.csv"), "a,b\n1,2\n5,6\n");
        assert_eq!(read("new.csv"), "a,b\n5,6\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
