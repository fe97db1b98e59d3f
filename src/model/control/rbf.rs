//! Gaussian radial-basis-function network with one output, adapted online (paper: h_j = exp(-|x - mu_j|^2 /
//! (2 b_j^2)), f_hat = W^T h, W_dot = Gamma S h).

use serde::{Deserialize, Serialize};

/// Centres and widths of a network over a 2-D input (angle in rad, angle rate in rad/s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RbfLayout {
    /// Node centres (angle_rad, rate_radps).
    pub centres: Vec<[f64; 2]>,
    /// Node widths b_j, one per centre.
    pub widths: Vec<f64>,
}

impl Default for RbfLayout {
    /// The paper's layout as controller.md fixes it: 5 centres on the diagonal of [-1, 1]^2, width 1.
    fn default() -> Self {
        Self { centres: [-1.0, -0.5, 0.0, 0.5, 1.0].map(|c| [c, c]).to_vec(), widths: vec![1.0; 5] }
    }
}

impl RbfLayout {
    /// Number of hidden nodes.
    pub fn nodes(&self) -> usize {
        self.centres.len()
    }

    /// Check the layout; the error names the problem.
    pub fn validate(&self) -> Result<(), String> {
        if self.centres.is_empty() {
            return Err("needs at least one node".into());
        }
        if self.widths.len() != self.centres.len() {
            return Err(format!("{} centres but {} widths", self.centres.len(), self.widths.len()));
        }
        if let Some((j, b)) = self.widths.iter().enumerate().find(|(_, b)| !(**b > 0.0 && b.is_finite())) {
            return Err(format!("width {} must be positive, got {b}", j + 1));
        }
        if let Some(j) = self.centres.iter().position(|c| !c.iter().all(|v| v.is_finite())) {
            return Err(format!("centre {} is not finite", j + 1));
        }
        Ok(())
    }
}

/// One network: layout plus its weights.
#[derive(Debug, Clone, PartialEq)]
pub struct RbfNetwork {
    centres: Vec<[f64; 2]>,
    inv_two_b2: Vec<f64>,
    /// Output weights W, one per node (start at zero, as in the paper).
    pub weights: Vec<f64>,
    activations: Vec<f64>,
}

impl RbfNetwork {
    /// A network with zero weights.
    pub fn new(layout: &RbfLayout) -> Self {
        let n = layout.nodes();
        Self {
            centres: layout.centres.clone(),
            inv_two_b2: layout.widths.iter().map(|b| 1.0 / (2.0 * b * b)).collect(),
            weights: vec![0.0; n],
            activations: vec![0.0; n],
        }
    }

    /// Evaluate h(x) and return f_hat = W^T h; the activations are kept for [`RbfNetwork::adapt`].
    #[inline]
    pub fn evaluate(&mut self, x: [f64; 2]) -> f64 {
        let mut out = 0.0;
        for j in 0..self.centres.len() {
            let (d0, d1) = (x[0] - self.centres[j][0], x[1] - self.centres[j][1]);
            let h = (-(d0 * d0 + d1 * d1) * self.inv_two_b2[j]).exp();
            self.activations[j] = h;
            out += self.weights[j] * h;
        }
        out
    }

    /// Forward-Euler step of W_dot = gamma * S * h over `dt_s`, with h from the last evaluation.
    #[inline]
    pub fn adapt(&mut self, gamma: f64, sliding_surface: f64, dt_s: f64) {
        let k = gamma * sliding_surface * dt_s;
        for (w, h) in self.weights.iter_mut().zip(&self.activations) {
            *w += k * h;
        }
    }

    /// Activations from the last evaluation.
    pub fn activations(&self) -> &[f64] {
        &self.activations
    }

    /// Euclidean norm of the weights.
    pub fn weight_norm(&self) -> f64 {
        self.weights.iter().map(|w| w * w).sum::<f64>().sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_is_one_at_its_centre_and_falls_with_distance() {
        let mut net = RbfNetwork::new(&RbfLayout::default());
        net.weights = vec![0.0, 0.0, 1.0, 0.0, 0.0];
        assert_eq!(net.evaluate([0.0, 0.0]), 1.0);
        // |x - mu|^2 = 2 with b = 1: exp(-1).
        assert!((net.evaluate([1.0, 1.0]) - (-1.0f64).exp()).abs() < 1e-15);
        assert!((net.activations()[4] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn adaptation_moves_weights_along_s_times_h() {
        let mut net = RbfNetwork::new(&RbfLayout::default());
        net.evaluate([0.0, 0.0]);
        net.adapt(0.1, 2.0, 0.01);
        let h = net.activations().to_vec();
        for (w, h) in net.weights.iter().zip(&h) {
            assert!((w - 0.1 * 2.0 * 0.01 * h).abs() < 1e-18);
        }
    }

    #[test]
    fn layout_errors_name_the_problem() {
        let bad = RbfLayout { centres: vec![[0.0, 0.0]], widths: vec![0.0] };
        assert!(bad.validate().unwrap_err().contains("width 1"));
        let bad = RbfLayout { centres: vec![[0.0, 0.0]; 2], widths: vec![1.0] };
        assert!(bad.validate().unwrap_err().contains("2 centres but 1 widths"));
    }
}
