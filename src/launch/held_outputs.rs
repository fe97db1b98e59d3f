//! A degraded plant seen: the ticks whose outputs the plant refused (NaN, infinity) and held at the last valid
//! ones, as `timing.csv`'s `plant_flags` marks them ([`FLAG_OUTPUTS_HELD`]), are flagged in `trace.csv` too (a last
//! column [`HELD_COLUMN`], written only into a run that held a row, so every other trace stays as it was: the
//! golden traces and the byte-for-byte comparisons), and a run that held more than `[plant]
//! outputs_held_fraction_max` of its ticks fails, saying how many. The figures shade the flagged rows.

use silrig_flight::scenario::Scenario;
use silrig_wire::wire::FLAG_OUTPUTS_HELD;
use std::path::Path;

use silrig_flight::trace::OUTPUTS_HELD_COLUMN as HELD_COLUMN;

/// Whether each row of `timing.csv` (its text) carries held outputs; `None` without a `plant_flags` column. A row
/// whose flags do not read as a number (a torn last line) counts as not held.
pub fn held_rows(timing_csv: &str) -> Option<Vec<bool>> {
    let mut lines = timing_csv.lines();
    let column = lines.next()?.split(',').position(|c| c == "plant_flags")?;
    let held = |line: &str| {
        line.split(',').nth(column).and_then(|f| f.parse::<u32>().ok()).is_some_and(|f| f & FLAG_OUTPUTS_HELD != 0)
    };
    Some(lines.filter(|l| !l.is_empty()).map(held).collect())
}

/// `trace.csv` (its text) with [`HELD_COLUMN`] after its last column, from `held` (one per row, in the order
/// `timing.csv` has them, which the logger writes row for row with `trace.csv`); `None` when the rows do not pair
/// up (a file cut short by a full disk) or the column is there already.
pub fn with_held_column(trace_csv: &str, held: &[bool]) -> Option<String> {
    let mut lines = trace_csv.lines();
    let header = lines.next()?;
    let rows: Vec<&str> = lines.filter(|l| !l.is_empty()).collect();
    if rows.len() != held.len() || header.split(',').any(|c| c == HELD_COLUMN) {
        return None;
    }
    let mut out = String::with_capacity(trace_csv.len() + 2 * rows.len() + HELD_COLUMN.len() + 2);
    out.push_str(header);
    out.push(',');
    out.push_str(HELD_COLUMN);
    out.push('\n');
    for (row, held) in rows.iter().zip(held) {
        out.push_str(row);
        out.push_str(if *held { ",1\n" } else { ",0\n" });
    }
    Some(out)
}

/// The run's failure when more than `fraction_max` of its `ticks` held their outputs, in words.
pub fn judge(held: usize, ticks: usize, fraction_max: f64) -> Option<String> {
    if ticks == 0 || held as f64 <= fraction_max * ticks as f64 {
        return None;
    }
    Some(format!(
        "plant: its outputs were refused (NaN or infinity) and held at the last valid ones on {held} of {ticks} ticks \
         ({:.1} %), more than `plant.outputs_held_fraction_max` = {fraction_max} allows: past them the flight is the \
         rig's stand-in, not the model's. events.jsonl says when it began (`outputs-refused`); fix the model, or \
         raise the key if such ticks are expected",
        100.0 * held as f64 / ticks as f64
    ))
}

/// Flag the held rows of the run in `out` in its `trace.csv` and judge their share against the scenario: the
/// failures to add to the run's report (a held share past the key, a `trace.csv` that cannot be rewritten).
pub fn flag_held_rows(out: &Path, scenario: &Scenario) -> Vec<String> {
    let Some(held) = std::fs::read_to_string(out.join("timing.csv")).ok().as_deref().and_then(held_rows) else {
        return Vec::new();
    };
    let count = held.iter().filter(|h| **h).count();
    if count == 0 {
        return Vec::new();
    }
    let mut failures: Vec<String> =
        judge(count, held.len(), scenario.plant.outputs_held_fraction_max).into_iter().collect();
    let path = out.join("trace.csv");
    let flagged = std::fs::read_to_string(&path).ok().and_then(|text| with_held_column(&text, &held));
    if let Some(text) = flagged
        && let Err(e) = silrig_flight::files::write_atomically(&path, &text)
    {
        failures.push(format!("silrig run: flagging the held rows in {}: {e}", path.display()));
    }
    failures
}

#[cfg(test)]
mod tests {
    use super::*;

    const TIMING: &str = "tick,plant_seq,plant_flags,command_seq\n0,0,0,0\n1,1,64,1\n2,2,66,\n3,3,2,3\n";

    #[test]
    fn held_rows_are_the_ones_with_the_flag_whatever_else_is_set() {
        assert_eq!(held_rows(TIMING).unwrap(), [false, true, true, false]);
        // A torn last line is not held; a file without the column says nothing.
        assert_eq!(held_rows("tick,plant_flags\n0,64\n1,6").unwrap(), [true, false]);
        assert_eq!(held_rows("tick,other\n0,64\n"), None);
    }

    #[test]
    fn the_column_goes_last_on_every_row_and_only_when_the_rows_pair_up() {
        let trace = "t_s,x_m,flight_segment\n0.0,1.5,0\n0.01,1.5,0\n";
        assert_eq!(
            with_held_column(trace, &[false, true]).unwrap(),
            "t_s,x_m,flight_segment,outputs_held\n0.0,1.5,0,0\n0.01,1.5,0,1\n"
        );
        assert_eq!(with_held_column(trace, &[true]), None, "one row short");
        let flagged = with_held_column(trace, &[true, true]).unwrap();
        assert_eq!(with_held_column(&flagged, &[true, true]), None, "flagged twice");
    }

    #[test]
    fn a_share_past_the_key_fails_with_the_count_and_one_at_it_passes() {
        assert_eq!(judge(10, 1000, 0.01), None);
        assert_eq!(judge(0, 0, 0.0), None);
        let said = judge(667, 1001, 0.01).unwrap();
        assert!(
            said.contains("667 of 1001 ticks (66.6 %)") && said.contains("plant.outputs_held_fraction_max"),
            "{said}"
        );
        assert!(judge(1, 1000, 0.0).is_some(), "a key of 0 allows none");
    }
}
