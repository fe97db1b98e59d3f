//! The control quality of a run's trace as tables a reader scans (the printed report's text, `Summary::to_text`,
//! is for the terminal): each output with a set point, each actuator, then the few figures of one line each.

use super::{esc, facts, table};
use silrig_flight::summary::{Response, Summary, seconds};

/// A time in seconds, or "never".
fn at(v: Option<f64>) -> String {
    v.map_or("never".into(), |s| format!("{s:.2}"))
}

/// A figure, or "-" where there is none.
fn figure(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.3}"))
}

/// The set points, the actuators and the other figures of `s`, each a table.
pub fn tables(s: &Summary) -> String {
    let t_end = s.ticks.saturating_sub(1) as f64 * s.dt_s;
    let mut out = format!(
        "<p>{} samples every {} s, t = 0 to {t_end:.2} s; \"late\" is the last {} s.</p>\n",
        s.ticks,
        s.dt_s,
        seconds(s.late_window_s)
    );
    if !s.setpoints.is_empty() {
        let rows: Vec<Vec<String>> = s
            .setpoints
            .iter()
            .map(|p| {
                let (settle, overshoot) = match &p.response {
                    Response::Stepped { settle_within_2pct_s, overshoot } => {
                        (at(*settle_within_2pct_s), format!("{overshoot:.3}"))
                    }
                    Response::Held => ("held".into(), "-".into()),
                };
                let within = p.settle_within_0p5deg.as_ref().map_or("-".into(), |d| at(d.at_s));
                vec![
                    esc(&p.name),
                    esc(&p.unit),
                    format!("{:.3}", p.setpoint),
                    format!("{:.3}", p.initial),
                    format!("{:.3}", p.final_value),
                    format!("{:.3}", p.max_error),
                    settle,
                    within,
                    overshoot,
                ]
            })
            .collect();
        let header = [
            "output",
            "unit",
            "set point",
            "initial",
            "final",
            "largest error",
            "settled within 2 % (s)",
            "within 0.5 deg (s)",
            "overshoot",
        ];
        out += &table(&header, &rows);
    }
    out += &actuators(s);
    out + &facts(&one_liners(s))
}

/// One row per actuator, in its input's unit.
fn actuators(s: &Summary) -> String {
    if s.actuators.is_empty() {
        return String::new();
    }
    let percent = |f: f64| format!("{:.1}", 100.0 * f);
    let rows: Vec<Vec<String>> = s
        .actuators
        .iter()
        .map(|a| {
            vec![
                esc(&a.name),
                esc(&a.unit),
                format!("{:.2}", a.peak),
                percent(a.rate_limit_fraction),
                percent(a.position_limit_fraction),
                format!("{:.2}", a.saturated_s),
                figure(a.rms_rate_per_s),
                figure(a.rms_rate_late_per_s),
                figure(a.rms_command_rate_per_s),
            ]
        })
        .collect();
    let header = [
        "actuator",
        "unit",
        "peak",
        "at rate limit (%)",
        "at position limit (%)",
        "saturated (s)",
        "rms rate (/s)",
        "rms rate, late (/s)",
        "rms command rate (/s)",
    ];
    let mut out = table(&header, &rows);
    let unplaced: Vec<&str> = s.actuators.iter().filter(|a| a.position.is_none()).map(|a| a.name.as_str()).collect();
    if !unplaced.is_empty() {
        out += &format!(
            "<p class=\"hint\">{}: the plant reports no position; the figures are the commands' against the \
             actuators' limits.</p>\n",
            esc(&unplaced.join(", "))
        );
    }
    out
}

/// The figures of one line each: angle of attack, late body rates, flight path, limit cycle, controller channels.
fn one_liners(s: &Summary) -> Vec<(&'static str, String)> {
    let late = seconds(s.late_window_s);
    let mut rows = Vec::new();
    if let Some(a) = &s.alpha {
        rows.push(("angle of attack", format!("final {:.3} deg, peak {:.3} deg", a.final_deg, a.peak_deg)));
    }
    if let Some([p, q, r]) = s.body_rate_max_late_dps {
        rows.push(("largest |p|, |q|, |r| late", format!("{p:.3}, {q:.3}, {r:.3} deg/s in the last {late} s")));
    }
    if let Some(f) = &s.flight_path {
        let hold = if f.speed_hold { " (speed hold)" } else { "" };
        let text = format!(
            "altitude {:+.1} ft, airspeed {:+.2} m/s{hold}, energy height {:+.1} ft",
            f.altitude_change_ft, f.airspeed_change_mps, f.energy_height_change_ft
        );
        rows.push(("flight path", text));
    }
    let found: Vec<String> = s
        .oscillations
        .iter()
        .filter(|o| o.sustained)
        .map(|o| format!("{} ±{:.2} every {:.3} s", o.signal, o.amplitude, o.period_s.unwrap_or(f64::NAN)))
        .collect();
    let cycle = if found.is_empty() { "none".to_string() } else { format!("YES: {}", found.join("; ")) };
    rows.push(("limit cycle, late", cycle));
    for c in &s.channels {
        let mut text = format!("final |S| {:.2e}, max |W| {:.2e}", c.final_abs_s, c.max_abs_w);
        if let Some(e) = c.rms_f_error_radps2 {
            text += &format!(", rms(f_hat - f) {e:.3} rad/s²");
        }
        rows.push(("controller channel", format!("{}: {text}", c.name)));
    }
    rows
}
