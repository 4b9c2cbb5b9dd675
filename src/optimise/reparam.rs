//! The smooth reparametrisation `phi = c tanh(z)` (method.md section 3),
//! the one home of the coordinates both L-BFGS minimisations run in: the
//! single-player ascent (`ascent.rs`) and the adversary's best response
//! (`best_response.rs`).
//!
//! argmin's quasi-Newton solvers have no box constraints. The map
//! `z -> c tanh(z)` takes `R^n` onto the open box `(-c, c)^n` of the
//! projection's logit bound `c`, so an unconstrained minimisation over `z`
//! never leaves the box, and the support (hence the GMC graph) never
//! changes. The chain rule is `dV/dz = c (1 - tanh(z)^2) dV/dphi`.

/// Logits at or beyond `START_CLAMP * c` in magnitude start at the `z` of
/// that point, where `tanh` still has slope `1 - START_CLAMP^2`
/// (a start on the box's face would have `z` infinite and no gradient).
const START_CLAMP: f64 = 0.99;

/// The coordinates `phi = c tanh(z)` for the logit bound `c` (method.md
/// section 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Reparametrisation {
    bound: f64,
}

impl Reparametrisation {
    /// The reparametrisation onto `(-bound, bound)^n`.
    pub fn new(bound: f64) -> Self {
        Self { bound }
    }

    /// `z = atanh(phi / c)` of a starting point, each `|phi|` first clamped
    /// to `START_CLAMP * c`.
    pub fn to_z(self, phi: &[f64]) -> Vec<f64> {
        phi.iter()
            .map(|&p| (p / self.bound).clamp(-START_CLAMP, START_CLAMP).atanh())
            .collect()
    }

    /// `phi = c tanh(z)`, componentwise.
    pub fn to_phi(self, z: &[f64]) -> Vec<f64> {
        z.iter().map(|&zi| self.bound * zi.tanh()).collect()
    }

    /// The chain rule `dV/dz = c (1 - tanh(z)^2) dV/dphi`, componentwise.
    pub fn chain_rule(self, z: &[f64], phi_gradient: &[f64]) -> Vec<f64> {
        z.iter()
            .zip(phi_gradient)
            .map(|(&zi, &d)| self.bound * (1.0 - zi.tanh().powi(2)) * d)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn z_and_phi_are_inverse_inside_the_clamp_and_clamped_beyond() {
        let map = Reparametrisation::new(4.0);
        let phi = [-3.0, 0.0, 1.5];
        let back = map.to_phi(&map.to_z(&phi));
        for (a, b) in phi.iter().zip(&back) {
            assert!((a - b).abs() < 1e-12, "{phi:?} -> {back:?}");
        }
        let clamped = map.to_phi(&map.to_z(&[4.0, -100.0]));
        assert!((clamped[0] - 0.99 * 4.0).abs() < 1e-12, "{clamped:?}");
        assert!((clamped[1] + 0.99 * 4.0).abs() < 1e-12, "{clamped:?}");
    }

    #[test]
    fn the_chain_rule_matches_a_finite_difference() {
        let map = Reparametrisation::new(2.5);
        // V(phi) = sum_k k phi_k^2, so dV/dphi_k = 2 k phi_k.
        let value = |z: &[f64]| -> f64 {
            map.to_phi(z)
                .iter()
                .enumerate()
                .map(|(k, p)| k as f64 * p * p)
                .sum()
        };
        let z = [0.3, -0.7, 1.2];
        let phi = map.to_phi(&z);
        let phi_gradient: Vec<f64> = phi
            .iter()
            .enumerate()
            .map(|(k, p)| 2.0 * k as f64 * p)
            .collect();
        let gradient = map.chain_rule(&z, &phi_gradient);
        let h = 1e-6;
        for k in 0..z.len() {
            let (mut up, mut down) = (z, z);
            up[k] += h;
            down[k] -= h;
            let difference = (value(&up) - value(&down)) / (2.0 * h);
            assert!(
                (difference - gradient[k]).abs() < 1e-6,
                "coordinate {k}: {difference} vs {}",
                gradient[k]
            );
        }
    }
}
