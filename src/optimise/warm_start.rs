//! Warm starts across controller sizes: a `k`-node FSC embeds into `n >= k`
//! nodes (nodes `k..n` are never entered), so the best `k`-node defender is
//! a starting point of the `n`-node optimisation ([`warm_started`]), and
//! the `n`-node result can be made never worse than the `k`-node one
//! ([`keep_better`]): results monotone in size by construction.

use super::{Solution, Structure, StructureOutcome, StructureReport};
use crate::controller::{Choice, Fsc};
use crate::game::ModelError;

/// The weight of the uniform distribution mixed into an embedded controller
/// so that it has the support of the structure it starts on ([`embed`]).
pub const WARM_START_MIX: f64 = 1e-6;

/// `fsc` embedded into the support structure `onto` (its nodes, `n >= k`,
/// and in each block `(g, o)` its pairs `(g', u)`: for the full structure,
/// every node with every action enabled under `o`): block `(g, o)` is
/// `(1 - mix) mu(. | g, o) + mix * uniform` over `onto`'s pairs of that
/// block, for the old nodes `g < k`, and a copy of node 0's for the new
/// nodes, so the new nodes are entered with probability at most `mix` per
/// step and the value moves by `O(mix)`. The initial distribution is
/// `fsc`'s padded with zeros, or, with `mix_initial`, mixed with the
/// uniform one over all nodes like the blocks. An error where `fsc` plays a
/// pair outside `onto`'s block, or has other observations or actions.
pub fn embed(fsc: &Fsc, onto: &Fsc, mix: f64, mix_initial: bool) -> Result<Fsc, ModelError> {
    let (k, nodes) = (fsc.num_nodes(), onto.num_nodes());
    if nodes < k {
        return Err(ModelError::new(
            "warm start",
            format!("a {k}-node controller does not embed into {nodes} nodes"),
        ));
    }
    if (fsc.num_observations(), fsc.num_actions()) != (onto.num_observations(), onto.num_actions())
    {
        return Err(ModelError::new(
            "warm start",
            "the controller and the structure differ in observations or actions",
        ));
    }
    if !(0.0..1.0).contains(&mix) || (mix == 0.0 && nodes > k) {
        return Err(ModelError::new(
            "warm start",
            format!("the uniform weight must be in (0, 1), got {mix}"),
        ));
    }
    let blocks = (0..nodes)
        .flat_map(|g| (0..fsc.num_observations()).map(move |o| (g, o)))
        .map(|(g, o)| {
            mixed_block(
                fsc.choices(if g < k { g } else { 0 }, o),
                onto.choices(g, o),
                mix,
                o,
            )
        })
        .collect::<Result<_, _>>()?;
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
        fsc.num_actions(),
        initial,
        blocks,
    )
}

/// One block of [`embed`]: `old`'s distribution mixed with weight `mix`
/// with the uniform one over the pairs of `support` (the structure's block
/// under observation `o`), which must hold every pair `old` plays.
fn mixed_block(
    old: &[Choice],
    support: &[Choice],
    mix: f64,
    o: usize,
) -> Result<Vec<Choice>, ModelError> {
    // Every choice of a controller has positive probability (`Fsc::new`).
    let in_support = |c: &Choice| {
        support
            .iter()
            .any(|s| (s.next, s.action) == (c.next, c.action))
    };
    if let Some(outside) = old.iter().find(|c| !in_support(c)) {
        return Err(ModelError::new(
            "warm start",
            format!(
                "the controller plays action {} to node {} under observation {o}, outside the structure's support",
                outside.action, outside.next
            ),
        ));
    }
    let pairs = support.len() as f64;
    Ok(support
        .iter()
        .map(|s| {
            let p = old
                .iter()
                .find(|c| (c.next, c.action) == (s.next, s.action))
                .map_or(0.0, |c| c.probability);
            Choice {
                next: s.next,
                action: s.action,
                probability: (1.0 - mix) * p + mix / pairs,
                logit: None,
            }
        })
        .collect())
}

/// `fsc` with `nodes >= k` nodes and the same behaviour: the old nodes keep
/// their blocks, the new ones copy node 0's, and the initial distribution
/// is padded with zeros, so the new nodes are never entered.
pub fn pad(fsc: &Fsc, nodes: usize) -> Result<Fsc, ModelError> {
    let k = fsc.num_nodes();
    if nodes < k {
        return Err(ModelError::new(
            "warm start",
            format!("a {k}-node controller does not embed into {nodes} nodes"),
        ));
    }
    let blocks = (0..nodes)
        .flat_map(|g| (0..fsc.num_observations()).map(move |o| (g, o)))
        .map(|(g, o)| fsc.choices(if g < k { g } else { 0 }, o).to_vec())
        .collect();
    let initial = (0..nodes)
        .map(|g| fsc.initial().get(g).copied().unwrap_or(0.0))
        .collect();
    Fsc::new(
        fsc.role(),
        nodes,
        fsc.num_observations(),
        fsc.num_actions(),
        initial,
        blocks,
    )
}

/// `structure` with `previous` embedded into its defender ([`embed`],
/// uniform weight [`WARM_START_MIX`]) as its [`Structure::warm`] start: the
/// first start of the optimisation of `n` nodes begins from the best
/// smaller defender, on the structure's support, the others where they
/// would without it.
pub fn warm_started(
    mut structure: Structure,
    previous: &Fsc,
    mix_initial: bool,
) -> Result<Structure, ModelError> {
    structure.warm = Some(embed(
        previous,
        &structure.defender,
        WARM_START_MIX,
        mix_initial,
    )?);
    Ok(structure)
}

/// The score structures are compared by: the certified lower bound when
/// there is one, else the worst-case estimate.
pub fn score(report: &StructureReport) -> f64 {
    report.certified_lower.unwrap_or(report.worst_case)
}

/// Makes the result of a larger defender size never worse than `previous`,
/// the best outcome of a smaller size: when `previous` scores higher than
/// `solution`'s best, appends it, its defender padded to `nodes` nodes
/// ([`pad`]: the same behaviour, so the same value and bounds) and named
/// `from-<k>-nodes`, and makes it the best. Returns whether it did.
pub fn keep_better(
    solution: &mut Solution,
    previous: &StructureOutcome,
    nodes: usize,
) -> Result<bool, ModelError> {
    if score(&previous.report) <= score(&solution.best().report) {
        return Ok(false);
    }
    let mut kept = previous.clone();
    kept.report.name = format!("from-{}-nodes", previous.defender.num_nodes());
    kept.defender = pad(&previous.defender, nodes)?;
    solution.structures.push(kept);
    solution.best = solution.structures.len() - 1;
    Ok(true)
}
