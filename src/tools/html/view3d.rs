//! The flight in 3-D on the run's page: the vehicle flying its trace in a small WebGL view with a time slider
//! (`view3d.js`, our own script), played from the trace's columns embedded in the page, no network.
//!
//! What it draws comes from the plant's announced signals, never from its name: a position (`north_`, `east_`,
//! `alt_` in m or ft) and an attitude (`phi_`, `theta_`, `psi_` in rad or deg), as Foxglove's 3-D channels read them
//! ([`BodySignals`]). A plant that announces four rotor speeds (`omega1_radps` .. `omega4_radps`) is drawn as an X
//! quadrotor in Betaflight's motor order (the built-in quadrotor's, `silrig_model::quad::rotors`), each rotor's disc
//! coloured by its speed; any other is drawn as the aircraft Foxglove's 3D panel shows, its surfaces deflected when
//! announced. Frames: world east-north-up, body forward-left-up.

use silrig_flight::signals::{OutputSignal, PlantSignals};
use silrig_flight::trace::Trace;
use silrig_recording::foxglove::{BodySignals, aircraft_model, quadrotor_model, rotor_arm_m};
use silrig_recording::reader::RecordedRun;
use std::fmt::Write as _;
use std::path::Path;

/// The view's script.
pub const SCRIPT: &str = include_str!("view3d.js");

/// Frames embedded at most: a long run is thinned evenly (a 10 s run keeps 50 a second).
const MAX_FRAMES: usize = 1500;
/// Frames a second kept at most.
const MAX_RATE_HZ: f64 = 50.0;
/// Recordings read for the view at most: a longer run's is left to Foxglove (reading it whole would hold every
/// sample in memory), and the view flies `trace.csv`'s columns.
const MAX_RECORDING_BYTES: u64 = 256 << 20;

/// The trace thinned to the frames the view plays, in the view's units.
#[derive(Debug, Clone, PartialEq)]
pub struct Frames {
    /// Time of each frame, s.
    pub t_s: Vec<f64>,
    /// Position east, north, up, m.
    pub enu_m: Vec<[f64; 3]>,
    /// Rotation world <- body, (x, y, z, w).
    pub rotation: Vec<[f64; 4]>,
    /// Aileron, elevator, rudder, rad, when the plant announces any.
    pub surfaces_rad: Option<Vec<[f64; 3]>>,
    /// Rotor speeds as fractions of the run's highest, when the plant announces four.
    pub rotors: Option<Vec<[f64; 4]>>,
}

/// The trace's frames, or why the view cannot be drawn.
pub fn frames(trace: &Trace) -> Result<Frames, String> {
    let plant = PlantSignals {
        plant: "trace".into(),
        outputs: trace
            .columns
            .iter()
            .map(|name| OutputSignal { name: name.clone(), unit: String::new(), in_trace: true })
            .collect(),
        inputs: Vec::new(),
    };
    let body = BodySignals::resolve(&plant).ok_or(
        "the plant announces no position (north_, east_, alt_ in m or ft) or no attitude (phi_, theta_, psi_ in rad \
         or deg), so there is nothing to place in 3-D",
    )?;
    let (Some(t_col), Some(first), Some(last)) = (trace.index("t_s"), trace.rows.first(), trace.rows.last()) else {
        return Err("the trace has no rows".into());
    };
    let span_s = last[t_col] - first[t_col];
    let keep = MAX_FRAMES.min((span_s * MAX_RATE_HZ) as usize + 1).max(2);
    let stride = trace.rows.len().div_ceil(keep).max(1);
    let mut rows: Vec<&Vec<f64>> = trace.rows.iter().step_by(stride).collect();
    if rows.last() != Some(&last) {
        rows.push(last);
    }
    let rotors = body.rotorcraft().then(|| {
        let speeds: Vec<[f64; 4]> =
            rows.iter().map(|r| body.rotor_speeds_radps(r).unwrap_or_default().map(f64::abs)).collect();
        let top = speeds.iter().flatten().copied().fold(0.0, f64::max);
        let scale = if top > 0.0 { 1.0 / top } else { 0.0 };
        speeds.into_iter().map(|s| s.map(|v| (v * scale).clamp(0.0, 1.0))).collect()
    });
    Ok(Frames {
        t_s: rows.iter().map(|r| r[t_col]).collect(),
        enu_m: rows.iter().map(|r| body.translation_m(r)).collect(),
        rotation: rows.iter().map(|r| body.rotation(r)).collect(),
        surfaces_rad: body.has_surfaces().then(|| rows.iter().map(|r| body.surfaces_rad(r)).collect()),
        rotors,
    })
}

/// Numbers as JSON text with `digits` decimals, flattened.
fn flat<const N: usize>(rows: &[[f64; N]], digits: usize) -> String {
    let mut out = String::from("[");
    for (k, v) in rows.iter().flatten().enumerate() {
        let sep = if k == 0 { "" } else { "," };
        let v = if v.is_finite() { *v } else { 0.0 };
        let _ = write!(out, "{sep}{v:.digits$}");
    }
    out + "]"
}

/// Every output the plant announced, a row per recorded tick, from the run's recording (trace.csv leaves some out:
/// the F-16's position); `trace.csv` when the recording cannot be read or is too long.
fn flight_table(dir: &Path) -> Option<Trace> {
    let recording_fits = std::fs::metadata(dir.join("recording.mcap")).is_ok_and(|m| m.len() <= MAX_RECORDING_BYTES);
    let recorded = recording_fits.then(|| RecordedRun::read(dir).ok()).flatten();
    if let Some((run, plant)) = recorded.and_then(|r| r.plant_signals().ok().map(|p| (r, p))) {
        let mut columns = vec!["t_s".to_string()];
        columns.extend(plant.outputs.iter().map(|o| o.name.clone()));
        let mut table = Trace::new(columns);
        table.rows = run
            .plant
            .iter()
            .map(|s| std::iter::once(s.t_sim_s).chain(s.outputs[..plant.outputs.len()].iter().copied()).collect())
            .collect();
        if !table.rows.is_empty() {
            return Some(table);
        }
    }
    Trace::load(&dir.join("trace.csv")).ok()
}

/// The section's HTML for the run in `dir`: the view and its data, or a line saying why there is none.
pub fn section(dir: &Path) -> String {
    let Some(trace) = flight_table(dir) else {
        return "<p>No 3-D view: the run left no recording or trace to fly it from.</p>\n".into();
    };
    let frames = match frames(&trace) {
        Ok(f) => f,
        Err(why) => return format!("<p>No 3-D view: {}.</p>\n", super::esc(&why)),
    };
    let model = if frames.rotors.is_some() {
        let scenario = std::fs::read_to_string(dir.join("scenario.toml")).unwrap_or_default();
        quadrotor_model(rotor_arm_m(&scenario))
    } else {
        aircraft_model()
    };
    let length_m = model["length_m"].as_f64().unwrap_or(1.0);
    let lowest_m = frames.enu_m.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    // The ground when the flight comes near it, else a plane below the flight (an aircraft at 10,000 ft).
    let (grid_z_m, grid_name) = if lowest_m < 40.0 * length_m {
        (0.0, "the grid is the ground, 0 m".to_string())
    } else {
        let z = ((lowest_m - 5.0 * length_m) / 100.0).floor() * 100.0;
        (z, format!("the grid is a plane at {z:.0} m, below the flight (not the ground)"))
    };
    let step_m = 10f64.powf((2.0 * length_m).log10().ceil());
    let data = format!(
        "{{\"t\":{},\"p\":{},\"q\":{},\"surfaces\":{},\"rotors\":{},\"model\":{},\"grid_z_m\":{grid_z_m},\
         \"grid_step_m\":{step_m},\"height_name\":\"height\"}}",
        flat(&frames.t_s.iter().map(|t| [*t]).collect::<Vec<_>>(), 3),
        flat(&frames.enu_m, 3),
        flat(&frames.rotation, 5),
        frames.surfaces_rad.as_deref().map_or("[]".into(), |s| flat(s, 4)),
        frames.rotors.as_deref().map_or("[]".into(), |r| flat(r, 3)),
        model,
    );
    let drawn = if frames.rotors.is_some() {
        "an X quadrotor (its rotors orange as they speed up, the red block its nose)"
    } else if frames.surfaces_rad.is_some() {
        "the aircraft, its surfaces deflected as the plant reports them"
    } else {
        "the aircraft (the plant reports no surfaces: drawn neutral)"
    };
    format!(
        "<div id=\"view3d\" class=\"view3d\">\n<canvas width=\"960\" height=\"460\"></canvas>\n\
         <div class=\"view3d-controls\"><button type=\"button\">play</button> <input type=\"range\" min=\"0\" \
         max=\"0\" value=\"0\" aria-label=\"time\"> <select aria-label=\"speed\"><option value=\"0.25\">x0.25</option>\
         <option value=\"1\" selected>x1</option><option value=\"4\">x4</option></select> \
         <span class=\"view3d-status\"></span></div>\n\
         <p class=\"hint\">{} frames of the trace; {drawn}; blue: the path flown, grey: the rest; {grid_name}, lines \
         {step_m} m apart. Drag to turn the camera, the wheel to come nearer.</p>\n\
         <script type=\"application/json\" id=\"view3d-data\">{data}</script>\n<script>{SCRIPT}</script>\n</div>\n",
        frames.t_s.len(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trace(columns: &[&str], rows: Vec<Vec<f64>>) -> Trace {
        let mut t = Trace::new(columns.iter().map(|c| c.to_string()).collect());
        t.rows = rows;
        t
    }

    #[test]
    fn a_quadrotor_is_thinned_to_fifty_frames_a_second_with_its_rotors_relative_to_the_highest() {
        let cols = [
            "t_s",
            "north_m",
            "east_m",
            "alt_m",
            "phi_deg",
            "theta_deg",
            "psi_deg",
            "omega1_radps",
            "omega2_radps",
            "omega3_radps",
            "omega4_radps",
        ];
        let rows = (0..=1000)
            .map(|k| {
                let t = k as f64 * 0.001;
                vec![t, t, 2.0 * t, 1.0 + t, 0.0, 0.0, 90.0, 400.0, 500.0, 600.0, 800.0 * t]
            })
            .collect();
        let f = frames(&trace(&cols, rows)).unwrap();
        assert_eq!(f.t_s.len(), 51, "{:?}", f.t_s);
        assert_eq!(f.t_s.last(), Some(&1.0));
        // East, north, up.
        assert_eq!(f.enu_m[50], [2.0, 1.0, 2.0]);
        let r = f.rotors.unwrap();
        assert_eq!(r[50], [0.5, 0.625, 0.75, 1.0]);
        assert!(f.surfaces_rad.is_none());
        // Heading 90 deg (east): the rotation world <- body turns by pi/2 - psi = 0 about up.
        let q = f.rotation[0];
        assert!(q[3] > 0.999_999, "{q:?}");
    }

    #[test]
    fn a_plant_without_a_position_or_attitude_is_said_in_words() {
        let e = frames(&trace(&["t_s", "alt_m", "phi_deg"], vec![vec![0.0, 1.0, 0.0]])).unwrap_err();
        assert!(e.contains("no position") && e.contains("north_"), "{e}");
        let dir = std::env::temp_dir().join(format!("silrig-view3d-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert!(section(&dir).contains("no recording or trace"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn numbers_are_written_flat_with_their_decimals_and_never_as_nan() {
        assert_eq!(flat(&[[1.0, 2.5], [f64::NAN, -0.126]], 2), "[1.00,2.50,0.00,-0.13]");
    }
}
