//! The air's drag on the quadrotor's frame (its body, arms and motors, not the rotors' own, which
//! [`super::rotors`] owns): quadratic in the air speed, each body axis with its own coefficient, as RotorPy models it
//! (`D = -|v| diag(c_Dx, c_Dy, c_Dz) v`). It is what bounds a climb or a fall along the rotors' axis together with the
//! axial inflow, where RotorS's rotor drag acts in the discs' plane alone.

use super::params::QuadParams;

/// The frame's drag, body axes, N, for the body moving at `velocity_b_mps` (body axes) through still air.
pub fn body_drag_n(p: &QuadParams, velocity_b_mps: &[f64; 3]) -> [f64; 3] {
    let [u, v, w] = *velocity_b_mps;
    let speed_mps = (u * u + v * v + w * w).sqrt();
    [-p.body_drag_x_kgpm * speed_mps * u, -p.body_drag_y_kgpm * speed_mps * v, -p.body_drag_z_kgpm * speed_mps * w]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_opposes_the_velocity_and_grows_with_its_square() {
        let p = QuadParams::default();
        for v in [[3.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, 5.0], [1.0, -2.0, 3.0], [-4.0, 0.5, -1.5]] {
            let d = body_drag_n(&p, &v);
            let power_w: f64 = d.iter().zip(v).map(|(f, v)| f * v).sum();
            assert!(power_w < 0.0, "drag {d:?} at {v:?} does work {power_w}");
            for k in 0..3 {
                assert!(d[k] * v[k] <= 0.0, "axis {k}: {d:?} at {v:?}");
            }
            let twice = body_drag_n(&p, &v.map(|c| 2.0 * c));
            for k in 0..3 {
                assert!((twice[k] - 4.0 * d[k]).abs() < 1e-12, "{twice:?} against {d:?}");
            }
        }
        assert_eq!(body_drag_n(&p, &[0.0; 3]), [0.0; 3]);
        // Straight down the rotors' axis at 10 m/s: c_Dz v^2 = 0.01 * 100 = 1 N, upwards (against the motion).
        let d = body_drag_n(&p, &[0.0, 0.0, 10.0]);
        assert!((d[2] + 1.0).abs() < 1e-12 && d[0] == 0.0 && d[1] == 0.0, "{d:?}");
    }
}
