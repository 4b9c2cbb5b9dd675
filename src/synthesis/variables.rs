//! The support variables `x[g, o, g', u]` and the edge literals built on
//! them, shared by both engines.
//!
//! An edge from `(s, q, g)` to `(s', q', g')` under adversary action `v`
//! exists iff some observation `o` with `O(o | s) > 0` and some action `u`
//! with `T(s' | s, u, v) > 0` have `x[g, o, g', u]`; the edge literal is
//! that disjunction (Tseitin). It does not depend on `q`, so it is keyed by
//! the transition `(s, v, s')` ([`Moves`]) and the nodes `g -> g'`, and
//! built the first time it is asked for. `x[g, o, g', u]` is the constant
//! false when `o` does not enable `u` (`enabled` actions, docs/formats.md
//! section 6); the certification adversary plays in `s` the actions some
//! observation of `s` enables.

use super::SynthesisError;
use super::cnf::{Cnf, FALSE, Lit, TRUE};
use super::graph::Moves;
use crate::game::Posg;

/// The support variables and the edge literals built so far.
pub struct SupportVariables {
    nodes: usize,
    num_observations: usize,
    num_actions: usize,
    /// `x[g, o, g', u]` at [`SupportVariables::index`].
    pub support: Vec<Lit>,
    /// The edge literal per `(transition, g, g')`, 0 until built.
    edges: Vec<Lit>,
}

impl SupportVariables {
    /// Fresh support variables for `nodes` defender nodes, with "at least
    /// one entry per block `(g, o)`".
    pub fn new(
        cnf: &mut Cnf,
        game: &Posg,
        moves: &Moves,
        nodes: usize,
    ) -> Result<Self, SynthesisError> {
        let player = game.defender();
        let (no, nu) = (player.num_observations(), player.num_actions());
        let product = |factors: &[usize]| {
            factors
                .iter()
                .fold(1u128, |p, &f| p.saturating_mul(f as u128))
        };
        let sizes = [
            (
                "support variables (nodes x observations x nodes x actions)",
                product(&[nodes, no, nodes, nu]),
            ),
            (
                "edge slots (game moves x nodes x nodes)",
                product(&[moves.len(), nodes, nodes]),
            ),
        ];
        let budget = crate::limits::MAX_SAT_SLOTS;
        for (what, size) in sizes {
            if size > budget {
                return Err(SynthesisError::TooLarge {
                    what: format!(
                        "{what} (posg_fsc::limits::MAX_SAT_SLOTS): {nodes} nodes need {size}"
                    ),
                    budget: budget as usize,
                });
            }
        }
        let support: Vec<Lit> = (0..nodes * no * nodes * nu)
            .map(|i| {
                let (o, u) = ((i / (nodes * nu)) % no, i % nu);
                if player.action_enabled(o, u) {
                    cnf.fresh()
                } else {
                    FALSE
                }
            })
            .collect();
        for block in support.chunks(nodes * nu) {
            cnf.clause(block.iter().copied())?;
        }
        Ok(Self {
            nodes,
            num_observations: no,
            num_actions: nu,
            support,
            edges: vec![0; moves.len() * nodes * nodes],
        })
    }

    /// The support fixed to `present` (indexed as
    /// [`SupportVariables::support`]): every support literal is a constant,
    /// so edge literals are constants too.
    pub fn fixed(game: &Posg, moves: &Moves, nodes: usize, present: &[bool]) -> Self {
        let player = game.defender();
        Self {
            nodes,
            num_observations: player.num_observations(),
            num_actions: player.num_actions(),
            support: present
                .iter()
                .map(|&p| if p { TRUE } else { FALSE })
                .collect(),
            edges: vec![0; moves.len() * nodes * nodes],
        }
    }

    /// The position of `x[g, o, g', u]` in [`SupportVariables::support`].
    pub fn index(&self, g: usize, o: usize, next: usize, u: usize) -> usize {
        ((g * self.num_observations + o) * self.nodes + next) * self.num_actions + u
    }

    /// The edge literal for game state `s`, transition `t` (from `s`) and
    /// nodes `(g, next)`.
    pub fn edge(
        &mut self,
        cnf: &mut Cnf,
        game: &Posg,
        moves: &Moves,
        (s, t): (usize, usize),
        (g, next): (usize, usize),
    ) -> Result<Lit, SynthesisError> {
        let key = (t * self.nodes + g) * self.nodes + next;
        if self.edges[key] == 0 {
            let terms: Vec<Lit> = game
                .defender()
                .observation_distribution(s)
                .iter()
                .flat_map(|&(o, _)| moves.actions(t).iter().map(move |&u| (o, u)))
                .map(|(o, u)| self.support[self.index(g, o, next, u)])
                .collect();
            self.edges[key] = cnf.or(&terms)?;
        }
        Ok(self.edges[key])
    }
}
