//! Warm starts across controller sizes: a `k`-node FSC embeds into `n >= k`
//! nodes (nodes `k..n` are never entered), so the best `k`-node defender is
//! a starting point of the `n`-node optimisation.

use crate::controller::{Choice, Fsc};
use crate::game::ModelError;

/// The weight of the uniform distribution mixed into an embedded controller
/// so that it has the full support structure ([`embed`]).
pub const WARM_START_MIX: f64 = 1e-6;

/// `fsc` embedded into `nodes` nodes on the full support structure (every
/// `(g', u)` in every block): block `(g, o)` is
/// `(1 - mix) mu(. | g, o) + mix * uniform` for the old nodes `g < k`, and a
/// copy of node 0's for the new nodes, so the new nodes are entered with
/// probability at most `mix` per step and the value moves by `O(mix)`.
/// The initial distribution is `fsc`'s padded with zeros, or, with
/// `mix_initial`, mixed with the uniform one over all nodes like the blocks.
pub fn embed(fsc: &Fsc, nodes: usize, mix: f64, mix_initial: bool) -> Result<Fsc, ModelError> {
    let k = fsc.num_nodes();
    if nodes < k {
        return Err(ModelError::new(
            "warm start",
            format!("a {k}-node controller does not embed into {nodes} nodes"),
        ));
    }
    if !(0.0..1.0).contains(&mix) || (mix == 0.0 && nodes > k) {
        return Err(ModelError::new(
            "warm start",
            format!("the uniform weight must be in (0, 1), got {mix}"),
        ));
    }
    let actions = fsc.num_actions();
    let pairs = (nodes * actions) as f64;
    let blocks = (0..nodes)
        .flat_map(|g| (0..fsc.num_observations()).map(move |o| (g, o)))
        .map(|(g, o)| {
            let old = fsc.choices(if g < k { g } else { 0 }, o);
            (0..nodes)
                .flat_map(|next| (0..actions).map(move |action| (next, action)))
                .map(|(next, action)| {
                    let p = old
                        .iter()
                        .find(|c| (c.next, c.action) == (next, action))
                        .map_or(0.0, |c| c.probability);
                    Choice {
                        next,
                        action,
                        probability: (1.0 - mix) * p + mix / pairs,
                        logit: None,
                    }
                })
                .collect()
        })
        .collect();
    let mut initial: Vec<f64> = (0..nodes)
        .map(|g| fsc.initial().get(g).copied().unwrap_or(0.0))
        .collect();
    if mix_initial {
        for p in &mut initial {
            *p = (1.0 - mix) * *p + mix / nodes as f64;
        }
    }
    Fsc::new(
        fsc.role(),
        nodes,
        fsc.num_observations(),
        actions,
        initial,
        blocks,
    )
}
