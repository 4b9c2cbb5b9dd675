//! Rounded candidates of an optimised defender.
//!
//! The logit bound keeps every supported choice at probability at least
//! `exp(-2c) / |block|`, so an optimised controller that should be
//! deterministic is only nearly so, and the value pays for the residual
//! mixing. The candidates here have smaller supports, so their GMC graphs
//! differ from the structure's and each is evaluated exactly on its own:
//!
//! * `truncated-<d>`: in every block (and the initial distribution) the
//!   entries of probability below `d` are dropped and the rest renormalised
//!   (the largest entry always stays): a partial rounding that makes the
//!   nearly deterministic blocks deterministic and leaves mixed blocks mixed;
//! * `argmax`: every block keeps its most probable entry only (the first
//!   of equals), and the initial distribution its most probable node: the
//!   deterministic rounding.

use crate::controller::{Choice, Fsc, Support};
use crate::game::ModelError;

/// The thresholds `d` of the partial roundings, smallest first.
pub const TRUNCATION_THRESHOLDS: [f64; 4] = [1e-6, 1e-4, 1e-2, 1e-1];

/// The partial roundings of `defender` for [`TRUNCATION_THRESHOLDS`] and
/// its argmax rounding, named as in the module documentation; candidates
/// equal to `defender` or to an earlier candidate are left out.
pub fn rounded_candidates(defender: &Fsc) -> Result<Vec<(String, Fsc)>, ModelError> {
    let mut candidates: Vec<(String, Fsc)> = Vec::new();
    let thresholds = TRUNCATION_THRESHOLDS
        .iter()
        .map(|&d| (format!("truncated-{d:e}"), d))
        .chain(std::iter::once(("argmax".to_string(), f64::INFINITY)));
    for (name, threshold) in thresholds {
        let candidate = truncated(defender, threshold)?;
        if !same_choices(&candidate, defender)
            && candidates.iter().all(|(_, c)| !same_choices(c, &candidate))
        {
            candidates.push((name, candidate));
        }
    }
    Ok(candidates)
}

/// Whether two controllers have the same supports and probabilities
/// (recorded logits aside).
fn same_choices(a: &Fsc, b: &Fsc) -> bool {
    Support::of(a) == Support::of(b) && Support::probabilities_of(a) == Support::probabilities_of(b)
}

/// `fsc` with the entries of probability below `threshold` dropped in every
/// block and in the initial distribution (the largest always kept),
/// renormalised; logits are not recorded.
pub fn truncated(fsc: &Fsc, threshold: f64) -> Result<Fsc, ModelError> {
    let blocks = (0..fsc.num_nodes())
        .flat_map(|g| (0..fsc.num_observations()).map(move |o| (g, o)))
        .map(|(g, o)| {
            let choices = fsc.choices(g, o);
            let keep = kept(choices.iter().map(|c| c.probability), threshold);
            let total: f64 = choices
                .iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(c, _)| c.probability)
                .sum();
            choices
                .iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(c, _)| Choice {
                    probability: c.probability / total,
                    logit: None,
                    ..*c
                })
                .collect()
        })
        .collect();
    let keep = kept(fsc.initial().iter().copied(), threshold);
    let total: f64 = fsc
        .initial()
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(p, _)| p)
        .sum();
    let initial = fsc
        .initial()
        .iter()
        .zip(&keep)
        .map(|(&p, &k)| if k { p / total } else { 0.0 })
        .collect();
    Fsc::new(
        fsc.role(),
        fsc.num_nodes(),
        fsc.num_observations(),
        fsc.num_actions(),
        initial,
        blocks,
    )
}

/// Which entries survive: those at or above `threshold`, and the first
/// largest one always (zero entries never).
fn kept(probabilities: impl Iterator<Item = f64> + Clone, threshold: f64) -> Vec<bool> {
    let top = probabilities
        .clone()
        .enumerate()
        .fold(
            (0, f64::NEG_INFINITY),
            |(i, m), (k, p)| {
                if p > m { (k, p) } else { (i, m) }
            },
        )
        .0;
    probabilities
        .enumerate()
        .map(|(k, p)| k == top || (p > 0.0 && p >= threshold))
        .collect()
}
