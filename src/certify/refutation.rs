//! Refuting a one-block change of the defender without solving its product
//! (method.md section 6, "Local search on the supports"): a proof, from
//! the analysis of the defender before the change alone, that the
//! all-seeing adversary wins at least as much against the changed
//! defender, whose lower bound is then no higher.
//!
//! Let `V` be the adversary's optimal values of the analysed product
//! (the probability of reaching its accepting end components, `Analysis`)
//! and `sigma` its optimal memoryless strategy, which stays in the
//! accepting end components it enters and meets its pair's `inf` states
//! there (`mdp/rabin.rs`). A change of block `(g, o)` changes the rows of
//! the product states `(s, q, g)` where `o` is an observation of `s`, the
//! *changed states*; a state the changed defender reaches that the old
//! product lacks gets `W = 0`, every other state `W = V`. The adversary
//! plays `sigma` except at the changed states with `V > 0`, where it
//! plays the action whose changed row has the largest expected `W`.
//! In the Markov chain this makes of the changed product, stopped where it
//! first meets a state with `W = 0` (a new state, or one from which the
//! adversary could not win), consider the states it reaches from the
//! initial ones through states with `W > 0`. If among them
//!
//! 1. `W <= P W` at every state (only the changed states need checking:
//!    elsewhere the rows are `sigma`'s and `V = P V`), and
//! 2. every bottom strongly connected component is accepting for some
//!    Rabin pair (avoids its `fin` states, meets its `inf` states; only
//!    the components through a changed state need checking: the others
//!    are closed classes of `sigma`'s chain with `V > 0`, which stay in
//!    accepting end components and meet their pair's `inf` states),
//!
//! then `W(X_n)` is a bounded submartingale up to the stopping time, the
//! chain stops or enters a bottom component almost surely, and
//! `W <= P(reach an accepting bottom component)`, a probability of the
//! adversary's winning: at the initial states the adversary wins at least
//! the old value. In doubles, `V = P V` holds to the old solve's residual
//! and the first condition is checked up to `SLACK` (1e-12) per state, so a
//! refuted change raises the bound at most by those errors times the
//! expected visits to the changed states before the chain stops or enters
//! a bottom component, and by the error bounds of the two solves: a few
//! times their tolerance on the products the local search meets, below
//! the `1e-8` by which it counts an improvement (a product that mixes
//! slowly can make the visits many; a wrongly refuted move only changes
//! which defender the search reaches, never a number it certifies).

use rustc_hash::FxHashMap;

use super::{Analysis, CertifyError, analyse};
use crate::automaton::{Dra, Letter};
use crate::controller::{Fsc, Role};
use crate::game::{AdversaryAction, DefenderAction, Posg};
use crate::graph::{Digraph, backward_reachable, bottom_components, strongly_connected_components};
use crate::solver::SolverSettings;

/// How far below `V` the expected `W` of a changed state's row may fall
/// and the change still count as refuted (the values' rounding).
const SLACK: f64 = 1e-12;

/// A successor the analysed product lacks (`W = 0`).
const UNKNOWN: usize = usize::MAX;

/// A changed row: `(successor or UNKNOWN, probability)`.
type Row = Vec<(usize, f64)>;

/// The analysis of one defender against the all-seeing adversary, kept to
/// refute the one-block changes of that defender ([`Refuter::refutes`]).
pub struct Refuter<'a> {
    game: &'a Posg,
    dra: &'a Dra,
    letters: Vec<Letter>,
    analysis: Analysis,
    /// The product states of each defender node (up to the last node of
    /// a product state).
    by_node: Vec<Vec<usize>>,
}

impl<'a> Refuter<'a> {
    /// Analyses `defender`'s product with the automaton of `!phi`,
    /// `dra_not_phi`, by `settings`.
    pub fn new(
        game: &'a Posg,
        dra_not_phi: &'a Dra,
        defender: &Fsc,
        settings: &SolverSettings,
    ) -> Result<Self, CertifyError> {
        let analysis = analyse(game, dra_not_phi, defender, Role::Defender, settings)?;
        Ok(Self::from_analysis(game, dra_not_phi, analysis))
    }

    /// The refuter of the defender whose product with `dra_not_phi` is
    /// `analysis` ([`Self::new`] without the solve).
    pub(crate) fn from_analysis(game: &'a Posg, dra_not_phi: &'a Dra, analysis: Analysis) -> Self {
        let nodes = analysis.states.iter().map(|&(_, _, g)| g + 1).max();
        let mut by_node = vec![Vec::new(); nodes.unwrap_or(0)];
        for (m, &(_, _, g)) in analysis.states.iter().enumerate() {
            by_node[g].push(m);
        }
        Self {
            game,
            dra: dra_not_phi,
            letters: dra_not_phi.state_letters(game),
            analysis,
            by_node,
        }
    }

    /// Whether the module's proof shows that `changed`, the analysed
    /// defender with only block `block` (`g |O| + o`) changed, lets the
    /// adversary win at least as much (its lower bound no higher, up to
    /// the errors of the module documentation). `false` says nothing: the
    /// change must be solved.
    pub fn refutes(&self, changed: &Fsc, block: usize) -> bool {
        let observations = changed.num_observations();
        let (node, observation) = (block / observations, block % observations);
        let result = &self.analysis.result;
        let mut rows: FxHashMap<usize, Row> = FxHashMap::default();
        // The changed states where condition 1 fails.
        let mut falling_short = Vec::new();
        // A node of no product state changes no row.
        for &m in self.by_node.get(node).into_iter().flatten() {
            let s = self.analysis.states[m].0;
            let observed = self.game.defender().observation_distribution(s);
            if !result.possible[m] || !observed.iter().any(|&(o, _)| o == observation) {
                continue;
            }
            let (row, value) = self.best_row(changed, m);
            if value < result.values[m] - SLACK {
                falling_short.push(m);
            }
            rows.insert(m, row);
        }
        let chain = Chain {
            refuter: self,
            rows: &rows,
        };
        let mut initial = vec![false; chain.num_vertices()];
        for &(m, _) in &self.analysis.initial {
            initial[m] = result.possible[m];
        }
        // The chain's states reached from the initial states through states
        // with `W > 0` (and the first states without): a backward search
        // on the chain's reverse, given the chain itself, searches
        // forwards.
        let reached = backward_reachable(&chain, &initial);
        !falling_short.iter().any(|&m| reached[m]) && chain.bottom_components_accept(&reached)
    }

    /// `W` of a successor (0 where the product lacks it or the adversary
    /// cannot win from it).
    fn w(&self, m: usize) -> f64 {
        if m == UNKNOWN || !self.analysis.result.possible[m] {
            0.0
        } else {
            self.analysis.result.values[m]
        }
    }

    /// The row of changed state `m` under the adversary's action with the
    /// largest expected `W` (its optimal action first, kept on ties), and
    /// that expectation.
    fn best_row(&self, changed: &Fsc, m: usize) -> (Row, f64) {
        let expected = |row: &Row| row.iter().map(|&(t, p)| p * self.w(t)).sum::<f64>();
        let optimal = self.analysis.result.strategy[m];
        let actions = self.analysis.mdp.num_actions(m);
        let mut best = self.changed_row(changed, m, optimal);
        let mut best_value = expected(&best);
        for a in (0..actions).filter(|&a| a != optimal) {
            let row = self.changed_row(changed, m, a);
            let value = expected(&row);
            if value > best_value {
                (best, best_value) = (row, value);
            }
        }
        (best, best_value)
    }

    /// The row of product state `m` under its MDP action `a` with the
    /// defender `changed` (the product's distribution, `crate::certify`'s
    /// module documentation, its successors by index), without the terms
    /// of probability 0, which the product has no edge for.
    fn changed_row(&self, changed: &Fsc, m: usize, a: usize) -> Row {
        let (s, q, g) = self.analysis.states[m];
        let adversary = AdversaryAction(self.analysis.free_actions[s][a]);
        let mut row = Vec::new();
        for &(o, p_o) in self.game.defender().observation_distribution(s) {
            for choice in changed.choices(g, o) {
                let defender = DefenderAction(choice.action);
                for &(t, p) in self.game.transition(s, defender, adversary) {
                    let probability = p_o * choice.probability * p;
                    if probability == 0.0 {
                        continue;
                    }
                    let key = (t, self.dra.successor(q, self.letters[t]), choice.next);
                    let next = self
                        .analysis
                        .states
                        .get(&key)
                        .map_or(UNKNOWN, |m| m as usize);
                    row.push((next, probability));
                }
            }
        }
        row
    }

    /// Whether the product states `members`, visited forever, meet some
    /// Rabin pair of the automaton.
    fn accepting(&self, members: &[u32]) -> bool {
        let q = |v: u32| self.analysis.states[v as usize].1;
        self.dra.pairs().iter().any(|pair| {
            members.iter().all(|&v| !pair.fin[q(v)]) && members.iter().any(|&v| pair.inf[q(v)])
        })
    }
}

/// The Markov chain of [`Refuter::refutes`], as a graph on the product's
/// states and one more vertex, `num_states`, standing for every state the
/// product lacks: a state with `W > 0` has its row's successors, any other
/// vertex none (the stopped chain of the module documentation).
struct Chain<'r, 'a> {
    refuter: &'r Refuter<'a>,
    rows: &'r FxHashMap<usize, Row>,
}

impl Chain<'_, '_> {
    /// Condition 2 of the module documentation: every bottom component
    /// through a changed state `reached` from the initial states accepting.
    fn bottom_components_accept(&self, reached: &[bool]) -> bool {
        let components = strongly_connected_components(self);
        let bottom = bottom_components(self, &components);
        let (offsets, members) = components.grouped();
        let mut checked = vec![false; components.count];
        for &m in self.rows.keys().filter(|&&m| reached[m]) {
            let c = components.component[m] as usize;
            if !std::mem::replace(&mut checked[c], true)
                && bottom[c]
                && !self.refuter.accepting(&members[offsets[c]..offsets[c + 1]])
            {
                return false;
            }
        }
        true
    }

    /// The row of product state `v`: its changed row, or `sigma`'s.
    fn row(&self, v: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let analysis = &self.refuter.analysis;
        let changed = self.rows.get(&v);
        let optimal = changed
            .is_none()
            .then(|| analysis.mdp.distribution(v, analysis.result.strategy[v]));
        changed
            .into_iter()
            .flatten()
            .chain(optimal.into_iter().flatten())
            .copied()
    }
}

impl Digraph for Chain<'_, '_> {
    fn num_vertices(&self) -> usize {
        self.refuter.analysis.states.len() + 1
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        let states = self.refuter.analysis.states.len();
        let possible = &self.refuter.analysis.result.possible;
        let rows = (v < states && possible[v]).then(|| self.row(v));
        rows.into_iter()
            .flatten()
            .map(move |(t, _)| if t == UNKNOWN { states } else { t })
    }
}
