//! The resource budget: sizes that are checked *before* memory is allocated
//! for them, so that an input too large for the machine is an error naming
//! the input, never an aborted allocation. Each limit is far above what the
//! method can use in practice (the GMC of the largest inputs measured has
//! about 10^6 states) and well below what would exhaust memory; each is
//! counted in the units named, which take a few dozen bytes each.

/// The most choices a controller may hold: `nodes * observations * nodes *
/// actions` for a uniform (full-support) controller (`uniform:K`, the
/// optimiser's starting structures, a file with `"default": "uniform"`).
/// The optimiser holds a few hundred bytes per choice over its parallel
/// starts and structures (`solve --def-nodes 5` on a game of 10^6
/// observations and 2 actions, 5e7 choices, passed 20 GB), so this keeps
/// it within about 2 GB.
pub const MAX_CONTROLLER_CHOICES: u128 = 5_000_000;

/// The most `(state, defender action, adversary action)` triples a game may
/// have (the transition table has one entry per triple).
pub const MAX_TRANSITION_TRIPLES: u128 = 50_000_000;

/// The most transition entries `T(s' | s, u, v) > 0` a game may have once
/// its `"*"` wildcards are expanded.
pub const MAX_TRANSITION_ENTRIES: u128 = 200_000_000;

/// The most non-zero rewards the reward models of a game may hold together
/// (state rewards and action rewards, JSON wildcards expanded), each about
/// 16 bytes: this keeps them within about 800 MB. It is checked before the
/// rewards are stored.
pub const MAX_REWARD_ENTRIES: u128 = 50_000_000;

/// The most edges (`states * 2^AP`) a deterministic automaton may have,
/// read from HOA or built from a formula.
pub const MAX_AUTOMATON_EDGES: u128 = 1 << 24;

/// The most transitions of a global Markov chain (or of a certification
/// product MDP's state-action distributions).
pub const MAX_CHAIN_TRANSITIONS: u128 = 1_000_000_000;

/// The most transitions of the global Markov chain that `eval`, the
/// optimiser and the other evaluations build: each costs about 16 bytes
/// in the chain and 20 more in its linear system (before the LU's fill),
/// so this budget keeps the chain and its system within about 4 GB. It is
/// checked row by row as the chain is explored, before each row is stored.
pub const MAX_GMC_TRANSITIONS: u128 = 100_000_000;

/// The most states of the global Markov chain that `eval`, the optimiser
/// and the other evaluations build: each costs about 100 bytes while the
/// chain is explored (its key, its index entry, its row), so this keeps the
/// exploration within about 2 GB; the largest GMC measured (the 288 x 288
/// grid with 2-node controllers) has about 10^6. It is checked as each new
/// state is reached, before it is stored.
pub const MAX_GMC_STATES: u128 = 20_000_000;

/// The most terms `O(o | s) mu(g', u | g, o)` of one player's action
/// mixture over all `(s, g)` (about game states x nodes^2 x actions for a
/// full-support controller), from which the GMC's rows are built: each
/// costs about 20 bytes, so this keeps a mixture within about 1 GB. It is
/// checked before the mixture is allocated.
pub const MAX_MIXTURE_TERMS: u128 = 50_000_000;

/// The most support variables (`nodes * observations * nodes * actions`)
/// and edge slots (`game moves * nodes^2`) the SAT encoding of support
/// synthesis may allocate, each a few bytes: checked before allocation.
pub const MAX_SAT_SLOTS: u128 = 100_000_000;

/// The most `(defender size, adversary size)` pairs one `sweep` may run.
pub const MAX_SWEEP_PAIRS: u128 = 10_000;

/// `Some(message)` when `size` exceeds `limit`: "`what` would need `size`
/// `unit`, above the budget of `limit` (`name`)". The caller adds the input.
pub fn exceeded(what: &str, size: u128, limit: u128, unit: &str, name: &str) -> Option<String> {
    (size > limit).then(|| {
        format!(
            "{what} would need {size} {unit}, above the budget of {limit} \
             (posg_fsc::limits::{name}); use a smaller input"
        )
    })
}

/// The product of `sizes`, saturating (never overflows).
fn product(sizes: &[usize]) -> u128 {
    sizes
        .iter()
        .fold(1u128, |product, &n| product.saturating_mul(n as u128))
}

/// `states * defender actions * adversary actions` against
/// [`MAX_TRANSITION_TRIPLES`]: `Some(message)` when too large. Every game
/// reader and generator checks it before it allocates the transition table
/// (or the per-state tables of the same size).
pub fn transition_triples(states: usize, nu: usize, nv: usize) -> Option<String> {
    exceeded(
        &format!("{states} states x {nu} defender actions x {nv} adversary actions"),
        product(&[states, nu, nv]),
        MAX_TRANSITION_TRIPLES,
        "transition triples",
        "MAX_TRANSITION_TRIPLES",
    )
}

/// `nodes * observations * nodes * actions` against
/// [`MAX_CONTROLLER_CHOICES`]: `Some(message)` when too large.
pub fn uniform_controller(nodes: usize, observations: usize, actions: usize) -> Option<String> {
    let choices = product(&[nodes, nodes, observations, actions]);
    exceeded(
        &format!(
            "a full-support controller of {nodes} nodes ({observations} observations, {actions} actions)"
        ),
        choices,
        MAX_CONTROLLER_CHOICES,
        "choices",
        "MAX_CONTROLLER_CHOICES",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_at_the_limit_pass_and_one_more_is_refused_with_the_name() {
        assert_eq!(exceeded("x", 10, 10, "units", "LIMIT"), None);
        let message = exceeded("x", 11, 10, "units", "LIMIT").unwrap();
        assert!(message.contains("11 units") && message.contains("limits::LIMIT"));
        assert!(uniform_controller(100_000, 4, 4).is_some());
        assert!(uniform_controller(10, 4, 4).is_none());
        assert!(uniform_controller(usize::MAX, usize::MAX, usize::MAX).is_some());
        assert!(transition_triples(usize::MAX, 2, 2).is_some());
        assert!(transition_triples(1000, 4, 2).is_none());
    }
}
