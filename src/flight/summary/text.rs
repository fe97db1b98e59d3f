//! The summary as a person reads it (what `silrig sim` and `silrig run` print): a line only for what the plant has.

use super::{ActuatorFigures, Response, SetpointFigures, Summary};

/// A time in seconds, or "never".
fn opt_s(v: Option<f64>) -> String {
    v.map_or("never".to_string(), |s| format!("{s:.2} s"))
}

/// A number of seconds as short as it reads: 3, 2.5, 0.9.
pub fn seconds(v: f64) -> String {
    let text = format!("{v:.2}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// A figure, or "-" where there is none.
fn figure(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.3}"))
}

impl Summary {
    /// Readable report.
    pub fn to_text(&self) -> String {
        let t_end = self.ticks.saturating_sub(1) as f64 * self.dt_s;
        let late = seconds(self.late_window_s);
        let mut out = format!(
            "scenario {}: {} samples every {} s, t = 0 to {t_end:.2} s\n",
            self.scenario, self.ticks, self.dt_s
        );
        out += &setpoints_text(&self.setpoints);
        if let Some(a) = &self.alpha {
            out += &format!("  alpha: final {:.3} deg, peak {:.3} deg\n", a.final_deg, a.peak_deg);
        }
        if let Some([p, q, r]) = self.body_rate_max_late_dps {
            out += &format!("  max |p|, |q|, |r| in the last {late} s: {p:.3}, {q:.3}, {r:.3} deg/s\n");
        }
        if let Some(f) = &self.flight_path {
            out += &format!(
                "  flight path: altitude {:+.1} ft, airspeed {:+.2} m/s{}, energy height {:+.1} ft\n",
                f.altitude_change_ft,
                f.airspeed_change_mps,
                if f.speed_hold { " (speed hold)" } else { "" },
                f.energy_height_change_ft
            );
        }
        out += &actuators_text(&self.actuators, &late);
        let found: Vec<String> = self
            .oscillations
            .iter()
            .filter(|o| o.sustained)
            .map(|o| format!("{} +-{:.2} every {:.3} s", o.signal, o.amplitude, o.period_s.unwrap_or(f64::NAN)))
            .collect();
        out += &format!(
            "  limit cycle (last {late} s): {}\n",
            if found.is_empty() { "none".to_string() } else { format!("YES: {}", found.join("; ")) }
        );
        for c in &self.channels {
            out += &format!("  channel {:<6} final |S| {:.2e}  max |W| {:.2e}", c.name, c.final_abs_s, c.max_abs_w);
            if let Some(e) = c.rms_f_error_radps2 {
                out += &format!("  rms(f_hat - f) {e:.3} rad/s^2");
            }
            out.push('\n');
        }
        out
    }
}

/// One line per output with a set point: a step by its settling and overshoot, a held value by its largest error.
fn setpoints_text(rows: &[SetpointFigures]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let width = rows.iter().map(|s| s.name.len()).max().unwrap_or(0).max(9);
    let mut out =
        format!("  {:<width$} {:>9} {:>9} {:>9}  settle(0.5deg)  response\n", "set point", "set", "initial", "final");
    for s in rows {
        let deg = s.settle_within_0p5deg.as_ref().map_or("-".to_string(), |d| opt_s(d.at_s));
        let response = match &s.response {
            Response::Stepped { settle_within_2pct_s, overshoot } => {
                format!("step: settle(2%) {}, overshoot {overshoot:.3}", opt_s(*settle_within_2pct_s))
            }
            Response::Held => format!("held: largest error {:.3}", s.max_error),
        };
        out += &format!(
            "  {:<width$} {:>9.3} {:>9.3} {:>9.3}  {deg:>14}  {response}\n",
            s.name, s.setpoint, s.initial, s.final_value
        );
    }
    out
}

/// The actuator table, in each input's unit, and a note for those whose figures are their commands'.
fn actuators_text(rows: &[ActuatorFigures], late: &str) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let width = rows.iter().map(|a| a.name.len()).max().unwrap_or(0).max(8);
    let last = format!("last {late} s");
    let mut out = format!(
        "  {:<width$} {:<5} {:>8} {:>10} {:>9} {:>9} {:>10} {last:>10} {:>12}\n",
        "actuator", "unit", "peak", "rate-limit", "pos-limit", "saturated", "rms rate/s", "rms cmd/s"
    );
    for a in rows {
        let percent = |f: f64| format!("{:.1} %", 100.0 * f);
        out += &format!(
            "  {:<width$} {:<5} {:>8.2} {:>10} {:>9} {:>9} {:>10} {:>10} {:>12}\n",
            a.name,
            a.unit,
            a.peak,
            percent(a.rate_limit_fraction),
            percent(a.position_limit_fraction),
            format!("{:.2} s", a.saturated_s),
            figure(a.rms_rate_per_s),
            figure(a.rms_rate_late_per_s),
            figure(a.rms_command_rate_per_s)
        );
    }
    let unplaced: Vec<&str> = rows.iter().filter(|a| a.position.is_none()).map(|a| a.name.as_str()).collect();
    if !unplaced.is_empty() {
        out += &format!(
            "  {}: the plant reports no position; the figures are the commands' against the actuators' limits\n",
            unplaced.join(", ")
        );
    }
    out
}
