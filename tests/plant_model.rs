//! The F-16 plant against published numbers: the textbook check case, every table breakpoint, the book's trim,
//! a trim that leaves no derivative, and a 60 s hands-off flight.

use silrig::integrator::rk4_step;
use silrig::plant::tables::{EMBEDDED_CSV, F16_TABLES, ParsedCsv, Table2};
use silrig::plant::trim::{TrimError, trim_level_flight};
use silrig::plant::{ControlInputs, ExternalForcing, F16Model, F16State, STATE_DOT_NAMES};
use silrig::units::m_to_ft;

fn check_case() -> (F16State, ControlInputs) {
    (
        F16State {
            vt_fps: 500.0,
            alpha_rad: 0.5,
            beta_rad: -0.2,
            phi_rad: -1.0,
            theta_rad: 1.0,
            psi_rad: -1.0,
            p_radps: 0.7,
            q_radps: -0.8,
            r_radps: 0.9,
            north_ft: 1000.0,
            east_ft: 900.0,
            alt_ft: 10_000.0,
            power_pct: 90.0,
        },
        ControlInputs { throttle: 0.9, elevator_deg: 20.0, aileron_deg: -15.0, rudder_deg: -20.0 },
    )
}

#[test]
fn textbook_check_case_matches_all_13_derivatives() {
    // Stevens & Lewis Table 3.5-2, xcg = 0.4.
    let published = [
        -75.23724, -0.8813491, -0.4759990, 2.505734, 0.3250820, 2.145926, 12.62679, 0.9649671, 0.5809759, 342.4439,
        -266.7707, 248.1241, -58.68999,
    ];
    let (x, u) = check_case();
    let d = F16Model::new(0.4).derivative(&x, &u, &ExternalForcing::default());
    for i in 0..13 {
        let rel = ((d[i] - published[i]) / published[i]).abs();
        assert!(rel < 1e-6, "{}: {} vs published {} (rel {rel:.2e})", STATE_DOT_NAMES[i], d[i], published[i]);
    }
}

#[test]
fn check_case_at_the_default_cg_moves_only_the_moment_equations() {
    // src/model/plant/data/README.md: with xcg 0.35, q_dot even changes sign (-0.1457558572); the ten others are
    // unchanged.
    let (x, u) = check_case();
    let at_040 = F16Model::new(0.4).derivative(&x, &u, &ExternalForcing::default());
    let at_035 = F16Model::new(0.35).derivative(&x, &u, &ExternalForcing::default());
    for i in (0..13).filter(|i| ![6, 7, 8].contains(i)) {
        assert_eq!(at_040[i], at_035[i], "{}", STATE_DOT_NAMES[i]);
    }
    for (i, want) in [(6, 12.61559473), (7, -0.1457558572), (8, 0.4728200638)] {
        assert!(((at_035[i] - want) / want).abs() < 1e-8, "{}: {}", STATE_DOT_NAMES[i], at_035[i]);
    }
}

fn independent_csv(name: &str) -> ParsedCsv {
    let path = format!("{}/src/model/plant/data/{name}.csv", env!("CARGO_MANIFEST_DIR"));
    ParsedCsv::parse(&std::fs::read_to_string(&path).unwrap()).unwrap()
}

fn check_table2(name: &str, table: &Table2) {
    let csv = independent_csv(name);
    let cols: Vec<f64> = csv.header.iter().map(|c| c.parse().unwrap()).collect();
    assert_eq!(csv.row_breakpoints.len(), table.rows.len, "{name}");
    assert_eq!(cols.len(), table.cols.len, "{name}");
    for (i, row) in csv.row_breakpoints.iter().enumerate() {
        for (j, col) in cols.iter().enumerate() {
            let want = csv.values[i * cols.len() + j];
            let got = table.lookup(*row, *col);
            assert!((got - want).abs() <= 1e-12 * want.abs().max(1.0), "{name}[{row}, {col}]: {got} vs {want}");
        }
    }
}

#[test]
fn every_table_reproduces_every_breakpoint() {
    let t = &*F16_TABLES;
    for (name, table) in [
        ("cx", &t.cx),
        ("cm", &t.cm),
        ("cl", &t.cl),
        ("cn", &t.cn),
        ("dlda", &t.dlda),
        ("dldr", &t.dldr),
        ("dnda", &t.dnda),
        ("dndr", &t.dndr),
        ("thrust_idle", &t.thrust_idle),
        ("thrust_mil", &t.thrust_mil),
        ("thrust_max", &t.thrust_max),
    ] {
        check_table2(name, table);
    }
    for (name, table) in [("cz", &t.cz), ("damping", &t.damping)] {
        let csv = independent_csv(name);
        let n = csv.header.len();
        for (i, alpha) in csv.row_breakpoints.iter().enumerate() {
            for k in 0..n {
                let want = csv.values[i * n + k];
                assert!((table.lookup(*alpha, k) - want).abs() <= 1e-12 * want.abs().max(1.0), "{name}[{alpha}, {k}]");
            }
        }
    }
    assert_eq!(EMBEDDED_CSV.len(), 13);
}

#[test]
fn lookups_interpolate_and_extrapolate_linearly_from_the_end_segment() {
    let t = &*F16_TABLES;
    // Midway between alpha 0 and 5 in cz: (-0.1 + -0.416) / 2.
    assert!((t.cz.lookup(2.5, 0) - (-0.258)).abs() < 1e-15);
    // Below the first breakpoint: the line through alpha -10 (0.770) and -5 (0.241) at -15 gives 1.299.
    assert!((t.cz.lookup(-15.0, 0) - 1.299).abs() < 1e-12);
    // cm beyond the elevator data: the last segment (12 -> 24 deg) at alpha 0 is -0.121 -> -0.184; at 25 deg:
    let want = -0.184 + (-0.184 - -0.121) / 12.0;
    assert!((t.cm.lookup(0.0, 25.0) - want).abs() < 1e-12);
    // Bilinear centre of four cx entries (alpha 0..5, elevator 0..12): mean of -0.021, -0.039, -0.004, -0.025.
    assert!((t.cx.lookup(2.5, 6.0) - (-0.021 - 0.039 - 0.004 - 0.025) / 4.0).abs() < 1e-15);
    // Thrust above Mach 1 and 50,000 ft extends the end segments rather than clamping.
    assert_ne!(t.thrust_max.lookup(55_000.0, 1.1), t.thrust_max.lookup(50_000.0, 1.0));
}

#[test]
fn sea_level_trim_at_502_fps_gives_the_textbook_throttle_and_elevator() {
    let trim = trim_level_flight(&F16Model::new(0.35), 502.0, 0.0).unwrap();
    // The book prints throttle 0.1385 and elevator -0.7588 deg (src/model/plant/data/README.md: 0.13853, -0.75878,
    // alpha 2.1148).
    assert_eq!(format!("{:.4}", trim.throttle), "0.1385");
    assert_eq!(format!("{:.4}", trim.elevator_deg), "-0.7588");
    assert_eq!(format!("{:.4}", trim.alpha_deg), "2.1148");
    assert_eq!(trim.state.theta_rad, trim.state.alpha_rad);
}

#[test]
fn trim_at_150_mps_and_25000_ft_leaves_no_derivative() {
    let model = F16Model::default();
    let trim = trim_level_flight(&model, m_to_ft(150.0), 25_000.0).unwrap();
    let d = model.derivative(&trim.state, &trim.controls, &ExternalForcing::default());
    for (i, v) in d.iter().enumerate() {
        if STATE_DOT_NAMES[i] == "north_dot" {
            // Level flight due north: the position rate is the airspeed itself.
            assert!((v - trim.vt_fps).abs() < 1e-9);
        } else {
            assert!(v.abs() < 1e-9, "{} = {v:e}", STATE_DOT_NAMES[i]);
        }
    }
    // controller.md: trim alpha at this condition is 6.79 deg.
    assert!((trim.alpha_deg - 6.79).abs() < 0.01, "{}", trim.alpha_deg);
}

#[test]
fn load_factors_match_the_reference_data_and_level_flight() {
    // The textbook prints no Nz or Ny for its check case; the reference data's README (shared/f16-data, table of
    // the check case) gives AeroBench's at the accelerometer 15 ft ahead of the CG: Nz 4.794348736 (xcg 0.4) and
    // 4.276448778 (0.35), Ny 0.8585245608 and 0.8080944575. AeroBench's Nz is the load factor minus 1 g.
    let (x, u) = check_case();
    for (xcg, nz_aerobench, ny) in [(0.4, 4.794348736, 0.8585245608), (0.35, 4.276448778, 0.8080944575)] {
        let (_, out) = F16Model::new(xcg).derivative_with_outputs(&x, &u, &ExternalForcing::default());
        assert!((out.nz_g - (nz_aerobench + 1.0)).abs() < 1e-8, "xcg {xcg}: nz {}", out.nz_g);
        assert!((out.ny_g - ny).abs() < 1e-8, "xcg {xcg}: ny {}", out.ny_g);
    }
    // Trimmed wings-level flight: the accelerometer reads gravity's body-z share, cos(theta), and nothing sideways.
    let model = F16Model::default();
    let trim = trim_level_flight(&model, m_to_ft(150.0), 25_000.0).unwrap();
    let (_, out) = model.derivative_with_outputs(&trim.state, &trim.controls, &ExternalForcing::default());
    assert!((out.nz_g - trim.state.theta_rad.cos()).abs() < 1e-9, "nz {} theta {}", out.nz_g, trim.state.theta_rad);
    assert!(out.ny_g.abs() < 1e-12, "ny {}", out.ny_g);
}

#[test]
fn trimmed_aircraft_flies_60_s_hands_off_with_theta_drift_below_0_01_deg() {
    let model = F16Model::default();
    let trim = trim_level_flight(&model, m_to_ft(150.0), 25_000.0).unwrap();
    let forcing = ExternalForcing::default();
    let dt = 0.01;
    let mut x = trim.state.to_array();
    let mut worst_deg: f64 = 0.0;
    for k in 0..6000 {
        x = rk4_step(
            |_, s| model.derivative(&F16State::from_array(s), &trim.controls, &forcing),
            k as f64 * dt,
            &x,
            dt,
        );
        worst_deg = worst_deg.max((x[4] - trim.state.theta_rad).to_degrees().abs());
    }
    assert!(worst_deg < 0.01, "theta drifted {worst_deg} deg");
    assert!((x[11] - 25_000.0).abs() < 1.0, "altitude {}", x[11]);
}

#[test]
fn trim_reports_a_clear_error_when_none_exists() {
    let model = F16Model::default();
    let err = trim_level_flight(&model, m_to_ft(40.0), 25_000.0).unwrap_err();
    assert!(matches!(err, TrimError::Infeasible { what: "alpha_deg", .. } | TrimError::NoConvergence { .. }), "{err}");
    assert!(err.to_string().contains("too low"), "{err}");
    let err = trim_level_flight(&model, -5.0, 0.0).unwrap_err();
    assert!(matches!(err, TrimError::InvalidRequest(_)), "{err}");
    // At 50,000 ft and 150 m/s the engine cannot hold level flight: the throttle would have to pass 1.
    let err = trim_level_flight(&model, m_to_ft(150.0), 50_000.0).unwrap_err();
    assert!(matches!(err, TrimError::Infeasible { what: "throttle", .. }), "{err}");
    assert!(err.to_string().contains("not enough thrust"), "{err}");
}

#[test]
fn speed_hold_freezes_vt_and_leaves_the_other_derivatives() {
    let (x, u) = check_case();
    let model = F16Model::new(0.4);
    let free = model.derivative(&x, &u, &ExternalForcing::default());
    let held = model.derivative(&x, &u, &ExternalForcing { speed_hold: true, ..Default::default() });
    assert_eq!(held[0], 0.0);
    assert_eq!(&free[1..], &held[1..]);
    let no_sideslip = model.derivative(&x, &u, &ExternalForcing { sideslip_hold: true, ..Default::default() });
    assert_eq!(no_sideslip[2], 0.0);
    assert_eq!((&free[..2], &free[3..]), (&no_sideslip[..2], &no_sideslip[3..]));
}

#[test]
fn euler_disturbance_appears_in_the_euler_accelerations() {
    // Finite-difference the Euler rates along the body-rate increment the disturbance adds: it must be d.
    let (x, u) = check_case();
    let model = F16Model::new(0.4);
    let d = [0.1, -0.2, 0.3];
    let base = model.derivative(&x, &u, &ExternalForcing::default());
    let dist = model.derivative(&x, &u, &ExternalForcing { euler_accel_disturbance_radps2: d, ..Default::default() });
    let (dp, dq, dr) = (dist[6] - base[6], dist[7] - base[7], dist[8] - base[8]);
    let (sph, cph) = x.phi_rad.sin_cos();
    let (sth, cth) = x.theta_rad.sin_cos();
    let euler = [dp + sth / cth * (sph * dq + cph * dr), cph * dq - sph * dr, (sph * dq + cph * dr) / cth];
    for k in 0..3 {
        assert!((euler[k] - d[k]).abs() < 1e-12, "{euler:?}");
    }
}

#[test]
fn model_scales_multiply_the_coefficients_and_divide_by_mass_and_inertia() {
    use silrig::plant::ModelScales;
    let (mut x, u) = check_case();
    // No body rates: the rate derivatives are the aerodynamic and engine moments over the inertias alone.
    (x.p_radps, x.q_radps, x.r_radps) = (0.0, 0.0, 0.0);
    let book = F16Model::new(0.4);
    let nominal = book.derivative(&x, &u, &ExternalForcing::default());
    assert_eq!(book.with_scales(ModelScales::default()).derivative(&x, &u, &ExternalForcing::default()), nominal);
    let heavy =
        book.with_scales(ModelScales { aero: [1.0; 6], mass: 2.0 }).derivative(&x, &u, &ExternalForcing::default());
    for i in [6, 7, 8] {
        assert!((heavy[i] - nominal[i] / 2.0).abs() < 1e-12 * nominal[i].abs().max(1.0), "{}", STATE_DOT_NAMES[i]);
    }
    // Cm doubled: q_dot (index 7) doubles, roll and yaw do not move.
    let cm = book.with_scales(ModelScales { aero: [1.0, 1.0, 1.0, 1.0, 2.0, 1.0], mass: 1.0 });
    let d = cm.derivative(&x, &u, &ExternalForcing::default());
    assert!((d[7] - 2.0 * nominal[7]).abs() < 1e-12 * nominal[7].abs());
    assert_eq!((d[6], d[8]), (nominal[6], nominal[8]));
}
