//! Fixed-step integrators, kept apart from any equations of motion: they see only `f(t, x) -> x_dot`.

/// One classic fourth-order Runge-Kutta step of `x_dot = f(t, x)` from `t` over `dt`.
#[inline]
pub fn rk4_step<const N: usize>(
    mut f: impl FnMut(f64, &[f64; N]) -> [f64; N],
    t: f64,
    x: &[f64; N],
    dt: f64,
) -> [f64; N] {
    let offset = |k: &[f64; N], h: f64| -> [f64; N] { std::array::from_fn(|i| x[i] + h * k[i]) };
    let k1 = f(t, x);
    let k2 = f(t + 0.5 * dt, &offset(&k1, 0.5 * dt));
    let k3 = f(t + 0.5 * dt, &offset(&k2, 0.5 * dt));
    let k4 = f(t + dt, &offset(&k3, dt));
    std::array::from_fn(|i| x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rk4_is_fourth_order() {
        // x' = x from 1 over 1 s: x(1) = e. Halving dt must cut the error by about 2^4.
        let run = |n: usize| {
            let dt = 1.0 / n as f64;
            let mut x = [1.0];
            for k in 0..n {
                x = rk4_step(|_, s: &[f64; 1]| [s[0]], k as f64 * dt, &x, dt);
            }
            (x[0] - std::f64::consts::E).abs()
        };
        let (e1, e2) = (run(10), run(20));
        assert!(e1 < 3e-6, "{e1}");
        let order = (e1 / e2).log2();
        assert!((order - 4.0).abs() < 0.2, "observed order {order}");
    }

    #[test]
    fn rk4_passes_time_to_each_stage() {
        // x' = t from 0: exact for polynomials of degree <= 4, so x(1) = 0.5 in one step.
        let x = rk4_step(|t, _: &[f64; 1]| [t], 0.0, &[0.0], 1.0);
        assert!((x[0] - 0.5).abs() < 1e-15);
    }
}
