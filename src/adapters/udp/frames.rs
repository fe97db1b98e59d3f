//! Frame conversions a device's packet may ask for, each a constant orthogonal linear map on a group of values
//! (a 3-vector or a quaternion), so a packet field stays a linear combination of the rig's signals and the inverse
//! (for what a device sends back) is the transpose.
//!
//! Our frames are the aerospace ones: world north-east-down (NED), body forward-right-down (FRD), quaternions
//! (w, x, y, z) rotating body vectors into the world frame. ROS, Gazebo and many SITLs use east-north-up (ENU) and
//! forward-left-up (FLU) (REP 103); some order quaternions (x, y, z, w).

use serde::{Deserialize, Serialize};

/// A conversion of a group of values, applied before scale and offset when sending (after them, inverted, when
/// receiving).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Frame {
    /// A world vector from NED to ENU: (n, e, d) -> (e, n, -d).
    NedToEnu,
    /// A body vector from FRD to FLU: (f, r, d) -> (f, -r, -d).
    FrdToFlu,
    /// An attitude quaternion (w, x, y, z) rotating FRD into NED, as one rotating FLU into ENU, still (w, x, y, z).
    QuatNedFrdToEnuFlu,
    /// A quaternion (w, x, y, z) reordered (x, y, z, w).
    QuatWxyzToXyzw,
}

impl Frame {
    /// Its name in a layout file.
    pub fn name(self) -> &'static str {
        match self {
            Frame::NedToEnu => "ned_to_enu",
            Frame::FrdToFlu => "frd_to_flu",
            Frame::QuatNedFrdToEnuFlu => "quat_ned_frd_to_enu_flu",
            Frame::QuatWxyzToXyzw => "quat_wxyz_to_xyzw",
        }
    }

    /// How many values the conversion takes and gives.
    pub fn width(self) -> usize {
        match self {
            Frame::NedToEnu | Frame::FrdToFlu => 3,
            Frame::QuatNedFrdToEnuFlu | Frame::QuatWxyzToXyzw => 4,
        }
    }

    /// The map as a matrix, row `i` giving output `i` from the inputs.
    pub fn matrix(self) -> Vec<Vec<f64>> {
        match self {
            Frame::NedToEnu => vec![vec![0.0, 1.0, 0.0], vec![1.0, 0.0, 0.0], vec![0.0, 0.0, -1.0]],
            Frame::FrdToFlu => vec![vec![1.0, 0.0, 0.0], vec![0.0, -1.0, 0.0], vec![0.0, 0.0, -1.0]],
            Frame::QuatWxyzToXyzw => {
                vec![
                    vec![0.0, 1.0, 0.0, 0.0],
                    vec![0.0, 0.0, 1.0, 0.0],
                    vec![0.0, 0.0, 0.0, 1.0],
                    vec![1.0, 0.0, 0.0, 0.0],
                ]
            }
            Frame::QuatNedFrdToEnuFlu => quat_ned_frd_to_enu_flu_matrix(),
        }
    }
}

/// Hamilton product of two (w, x, y, z) quaternions.
fn quat_mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// `q_enu_flu = q_enu_ned (x) q_ned_frd (x) q_frd_flu`, linear in `q_ned_frd`: column `k` is the image of the
/// `k`-th unit quaternion. `q_enu_ned` swaps x and y and flips z (a rotation of pi about (1, 1, 0)/sqrt 2);
/// `q_frd_flu` flips y and z (pi about x).
fn quat_ned_frd_to_enu_flu_matrix() -> Vec<Vec<f64>> {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let enu_from_ned = [0.0, h, h, 0.0];
    let frd_from_flu = [0.0, 1.0, 0.0, 0.0];
    let columns: Vec<[f64; 4]> = (0..4)
        .map(|k| {
            let mut unit = [0.0; 4];
            unit[k] = 1.0;
            quat_mul(quat_mul(enu_from_ned, unit), frd_from_flu)
        })
        .collect();
    (0..4).map(|row| (0..4).map(|col| columns[col][row]).collect()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(frame: Frame, v: &[f64]) -> Vec<f64> {
        frame.matrix().iter().map(|row| row.iter().zip(v).map(|(a, b)| a * b).sum()).collect()
    }

    /// Rotates `v` by the (w, x, y, z) quaternion `q`.
    fn rotate(q: &[f64], v: [f64; 3]) -> [f64; 3] {
        let q = [q[0], q[1], q[2], q[3]];
        let conj = [q[0], -q[1], -q[2], -q[3]];
        let r = quat_mul(quat_mul(q, [0.0, v[0], v[1], v[2]]), conj);
        [r[1], r[2], r[3]]
    }

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn vectors_change_frame_as_rep_103_says() {
        assert_eq!(apply(Frame::NedToEnu, &[1.0, 2.0, 3.0]), [2.0, 1.0, -3.0]);
        assert_eq!(apply(Frame::FrdToFlu, &[1.0, 2.0, 3.0]), [1.0, -2.0, -3.0]);
        assert_eq!(apply(Frame::QuatWxyzToXyzw, &[1.0, 2.0, 3.0, 4.0]), [2.0, 3.0, 4.0, 1.0]);
    }

    #[test]
    fn a_converted_attitude_rotates_converted_vectors_alike() {
        // Heading 30 deg, pitch 10 deg, roll -20 deg as a NED/FRD quaternion (3-2-1).
        let (r, p, y) = (-20f64.to_radians() / 2.0, 10f64.to_radians() / 2.0, 30f64.to_radians() / 2.0);
        let q = [
            r.cos() * p.cos() * y.cos() + r.sin() * p.sin() * y.sin(),
            r.sin() * p.cos() * y.cos() - r.cos() * p.sin() * y.sin(),
            r.cos() * p.sin() * y.cos() + r.sin() * p.cos() * y.sin(),
            r.cos() * p.cos() * y.sin() - r.sin() * p.sin() * y.cos(),
        ];
        let q_enu = apply(Frame::QuatNedFrdToEnuFlu, &q);
        assert!((q_enu.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-12);
        for v in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, -0.5, 2.0]] {
            let ned = rotate(&q, v);
            let enu = rotate(&q_enu, apply(Frame::FrdToFlu, &v).try_into().unwrap());
            assert!(close(&enu, &apply(Frame::NedToEnu, &ned)), "{enu:?} against {ned:?}");
        }
        // Level, facing north: FLU's x points north, which in ENU is a yaw of +90 deg about up.
        let north = apply(Frame::QuatNedFrdToEnuFlu, &[1.0, 0.0, 0.0, 0.0]);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(close(&north, &[h, 0.0, 0.0, h]) || close(&north, &[-h, 0.0, 0.0, -h]), "{north:?}");
    }

    #[test]
    fn every_map_is_orthogonal_so_its_inverse_is_its_transpose() {
        for frame in [Frame::NedToEnu, Frame::FrdToFlu, Frame::QuatNedFrdToEnuFlu, Frame::QuatWxyzToXyzw] {
            let m = frame.matrix();
            let n = frame.width();
            for i in 0..n {
                for j in 0..n {
                    let dot: f64 = (0..n).map(|k| m[i][k] * m[j][k]).sum();
                    assert!((dot - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12, "{frame:?}");
                }
            }
        }
    }
}
