//! Softmax parameters of one controller on a fixed support (method.md section 3).
//!
//! A logit vector `phi` holds one logit per support entry, block after block,
//! followed (when the initial distribution is optimised) by one logit per
//! supported initial node. In each block `(g, o)`
//!
//! ```text
//! mu_k = exp(phi_k) / sum_{j in block} exp(phi_j),
//! dV/dphi_k = mu_k (dV/dmu_k - sum_{j in block} mu_j dV/dmu_j),
//! ```
//!
//! and likewise for the initial distribution. The projection clips every
//! logit to `[-c, c]`, so every supported entry keeps probability at least
//! `exp(-2c) / |block|` and the support never changes.

use crate::controller::{Choice, Fsc, Probabilities, Support};
use crate::game::ModelError;

/// The map from logits to a controller's probabilities on one support.
#[derive(Debug, Clone)]
pub struct Softmax {
    template: Fsc,
    blocks: Vec<std::ops::Range<usize>>,
    num_entries: usize,
    initial_nodes: Option<Vec<usize>>,
}

impl Softmax {
    /// The softmax map on the support of `template` ([`Support::of`]).
    /// With `optimise_initial` the initial distribution is parameterised on
    /// the nodes `template` starts in with positive probability; otherwise it
    /// stays `template`'s.
    pub fn new(template: &Fsc, optimise_initial: bool) -> Self {
        let support = Support::of(template);
        let blocks = (0..support.num_blocks())
            .map(|b| support.block_by_index(b))
            .collect();
        let initial_nodes = optimise_initial.then(|| support.initial_nodes().collect());
        Self {
            template: template.clone(),
            blocks,
            num_entries: support.num_entries(),
            initial_nodes,
        }
    }

    /// The controller whose support and shape this map follows.
    pub fn template(&self) -> &Fsc {
        &self.template
    }

    /// The number of logits.
    pub fn num_parameters(&self) -> usize {
        self.num_entries + self.initial_nodes.as_ref().map_or(0, Vec::len)
    }

    /// The probabilities `mu = softmax(phi)` per block (and initial distribution).
    pub fn probabilities(&self, logits: &[f64]) -> Probabilities {
        let mut entries = vec![0.0; self.num_entries];
        for block in &self.blocks {
            softmax_into(&logits[block.clone()], &mut entries[block.clone()]);
        }
        let initial = match &self.initial_nodes {
            None => self.template.initial().to_vec(),
            Some(nodes) => {
                let mut weights = vec![0.0; nodes.len()];
                softmax_into(&logits[self.num_entries..], &mut weights);
                let mut initial = vec![0.0; self.template.num_nodes()];
                for (&g, w) in nodes.iter().zip(weights) {
                    initial[g] = w;
                }
                initial
            }
        };
        Probabilities { entries, initial }
    }

    /// The logit gradient from the probability gradient by the chain rule
    /// `dV/dphi_k = mu_k (dV/dmu_k - sum_j mu_j dV/dmu_j)` per block;
    /// `d_entries` per support entry, `d_initial` per node.
    pub fn chain_rule(&self, mu: &Probabilities, d_entries: &[f64], d_initial: &[f64]) -> Vec<f64> {
        let mut gradient = vec![0.0; self.num_parameters()];
        for block in &self.blocks {
            chain_rule_into(
                &mu.entries[block.clone()],
                &d_entries[block.clone()],
                &mut gradient[block.clone()],
            );
        }
        if let Some(nodes) = &self.initial_nodes {
            let weights: Vec<f64> = nodes.iter().map(|&g| mu.initial[g]).collect();
            let derivatives: Vec<f64> = nodes.iter().map(|&g| d_initial[g]).collect();
            chain_rule_into(&weights, &derivatives, &mut gradient[self.num_entries..]);
        }
        gradient
    }

    /// The logits of the template's own probabilities: its recorded logits
    /// where every entry of a block has one, else those of [`Softmax::logits_of`].
    pub fn logits_of_template(&self, bound: f64) -> Vec<f64> {
        let t = &self.template;
        let mut logits = self.logits_of(&Support::probabilities_of(t), bound);
        for (b, block) in self.blocks.iter().enumerate() {
            let choices = t.choices(b / t.num_observations(), b % t.num_observations());
            if let Some(recorded) = choices
                .iter()
                .map(|c| c.logit)
                .collect::<Option<Vec<f64>>>()
            {
                logits[block.clone()].copy_from_slice(&recorded);
            }
        }
        clip(&mut logits, bound);
        logits
    }

    /// Logits whose softmax is `mu` where the bound allows: `ln mu` centred
    /// per block (and for the initial distribution), shifted down when the
    /// largest exceeds `c` so that it is `c`, then clipped to `[-c, c]`: the
    /// ratios among the largest entries (those within `exp(2c)` of the
    /// maximum) stay exact, and only the smallest are raised.
    pub fn logits_of(&self, mu: &Probabilities, bound: f64) -> Vec<f64> {
        let mut logits: Vec<f64> = Vec::with_capacity(self.num_parameters());
        for block in &self.blocks {
            logits.extend(bounded_logs(
                mu.entries[block.clone()].iter().copied(),
                bound,
            ));
        }
        if let Some(nodes) = &self.initial_nodes {
            logits.extend(bounded_logs(nodes.iter().map(|&g| mu.initial[g]), bound));
        }
        clip(&mut logits, bound);
        logits
    }

    /// The controller with probabilities `softmax(phi)` and the logits recorded.
    pub fn controller(&self, logits: &[f64]) -> Result<Fsc, ModelError> {
        let mu = self.probabilities(logits);
        let t = &self.template;
        let blocks = self
            .blocks
            .iter()
            .enumerate()
            .map(|(b, range)| {
                let old = t.choices(b / t.num_observations(), b % t.num_observations());
                old.iter()
                    .zip(range.clone())
                    .map(|(c, k)| Choice {
                        probability: mu.entries[k],
                        logit: Some(logits[k]),
                        ..*c
                    })
                    .collect()
            })
            .collect();
        Fsc::new(
            t.role(),
            t.num_nodes(),
            t.num_observations(),
            t.num_actions(),
            mu.initial,
            blocks,
        )
    }
}

/// The projection of method.md section 3: every logit clipped to `[-c, c]`.
pub fn clip(logits: &mut [f64], bound: f64) {
    for phi in logits {
        *phi = phi.clamp(-bound, bound);
    }
}

fn softmax_into(logits: &[f64], out: &mut [f64]) {
    let top = logits.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut total = 0.0;
    for (o, &phi) in out.iter_mut().zip(logits) {
        *o = (phi - top).exp();
        total += *o;
    }
    for o in out {
        *o /= total;
    }
}

fn chain_rule_into(mu: &[f64], d_mu: &[f64], out: &mut [f64]) {
    let mean: f64 = mu.iter().zip(d_mu).map(|(m, d)| m * d).sum();
    for ((o, &m), &d) in out.iter_mut().zip(mu).zip(d_mu) {
        *o = m * (d - mean);
    }
}

/// `ln w` centred, then shifted down so that the largest is at most `bound`.
fn bounded_logs(weights: impl Iterator<Item = f64>, bound: f64) -> Vec<f64> {
    let logs: Vec<f64> = weights.map(f64::ln).collect();
    let mean = logs.iter().sum::<f64>() / logs.len().max(1) as f64;
    let top = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max) - mean;
    let shift = mean + (top - bound).max(0.0);
    logs.into_iter().map(|l| l - shift).collect()
}
