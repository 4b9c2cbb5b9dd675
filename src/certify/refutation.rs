//! Refuting a one-block change of the defender without solving its product
//! (method.md section 6, "Local search on the supports"): a proof, from
//! the analysis of the defender before the change alone, that the
//! all-seeing adversary wins at least as much against the changed
//! defender, whose lower bound is then no higher.
//!
//! Let `V` be the adversary's optimal values of the analysed product
//! (the probability of reaching its accepting end components, [`Analysis`])
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
//! and the first condition is checked up to [`SLACK`] per state, so a
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
use crate::graph::{Digraph, backward_reachable, strongly_connected_components};
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
pub(crate) struct Refuter<'a> {
    game: &'a Posg,
    dra: &'a Dra,
    letters: Vec<Letter>,
    analysis: Analysis,
    /// The index of each product state `(s, q, node)`.
    index: FxHashMap<(usize, usize, usize), usize>,
    /// The product states of each defender node.
    by_node: Vec<Vec<usize>>,
}

impl<'a> Refuter<'a> {
    /// Analyses `defender`'s product with the automaton of `!phi`,
    /// `dra_not_phi`, by `settings`.
    pub(crate) fn new(
        game: &'a Posg,
        dra_not_phi: &'a Dra,
        defender: &Fsc,
        settings: &SolverSettings,
    ) -> Result<Self, CertifyError> {
        let analysis = analyse(game, dra_not_phi, defender, Role::Defender, settings)?;
        let index = (analysis.states.iter().copied())
            .enumerate()
            .map(|(m, key)| (key, m))
            .collect();
        let mut by_node = vec![Vec::new(); defender.num_nodes()];
        for (m, &(_, _, g)) in analysis.states.iter().enumerate() {
            by_node[g].push(m);
        }
        Ok(Self {
            game,
            dra: dra_not_phi,
            letters: dra_not_phi.state_letters(game),
            analysis,
            index,
            by_node,
        })
    }

    /// Whether the module's proof shows that `changed`, the analysed
    /// defender with only block `block` (`g |O| + o`) changed, lets the
    /// adversary win at least as much (its lower bound no higher, up to
    /// the errors of the module documentation). `false` says nothing: the
    /// change must be solved.
    pub(crate) fn refutes(&self, changed: &Fsc, block: usize) -> bool {
        let observations = changed.num_observations();
        let (node, observation) = (block / observations, block % observations);
        let result = &self.analysis.result;
        let mut rows: FxHashMap<usize, Row> = FxHashMap::default();
        // The changed states where condition 1 fails.
        let mut falling_short = Vec::new();
        for &m in &self.by_node[node] {
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
        let mut initial = vec![false; self.analysis.states.len()];
        for &(m, _) in &self.analysis.initial {
            initial[m] = result.possible[m];
        }
        // The chain's states reached from the initial states through states
        // with `W > 0`: a backward search on the chain's reverse, given the
        // chain itself, searches forwards.
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
                    let next = self.index.get(&key).copied().unwrap_or(UNKNOWN);
                    row.push((next, probability));
                }
            }
        }
        row
    }

    /// Whether the product states `members`, visited forever, meet some
    /// Rabin pair of the automaton.
    fn accepting(&self, members: &[usize]) -> bool {
        let q = |v: usize| self.analysis.states[v].1;
        self.dra.pairs().iter().any(|pair| {
            members.iter().all(|&v| !pair.fin[q(v)]) && members.iter().any(|&v| pair.inf[q(v)])
        })
    }
}

/// The Markov chain of [`Refuter::bottom_components_accept`], as a graph on
/// the product's states with `W > 0`.
struct Chain<'r, 'a> {
    refuter: &'r Refuter<'a>,
    rows: &'r FxHashMap<usize, Row>,
}

impl Chain<'_, '_> {
    /// Condition 2 of the module documentation: every bottom component
    /// through a changed state `reached` from the initial states accepting.
    fn bottom_components_accept(&self, reached: &[bool]) -> bool {
        let components = strongly_connected_components(self);
        let component = &components.component;
        let mut checked = vec![false; components.count];
        let members = components.members();
        for &m in self.rows.keys().filter(|&&m| reached[m]) {
            let c = component[m] as usize;
            if std::mem::replace(&mut checked[c], true) {
                continue;
            }
            let members = &members[c];
            let bottom = members.iter().all(|&v| {
                self.row(v)
                    .all(|(t, _)| t != UNKNOWN && component[t] as usize == c)
            });
            if bottom && !self.refuter.accepting(members) {
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
        self.refuter.analysis.states.len()
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        let possible = &self.refuter.analysis.result.possible;
        let rows = possible[v].then(|| self.row(v));
        rows.into_iter()
            .flatten()
            .map(|(t, _)| t)
            .filter(|&t| t != UNKNOWN && possible[t])
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use serde_json::{Map, Value, json};

    use super::*;
    use crate::certify::ranked_lower_bound;
    use crate::controller::Choice;
    use crate::game::file::from_json_str;
    use crate::pipeline::Automata;

    fn not_phi(formula: &str) -> Dra {
        Automata::from_ltl(formula).unwrap().not_phi.unwrap()
    }

    fn ranking() -> SolverSettings {
        SolverSettings {
            exact_limit: 0,
            prove_optimum: false,
            ..SolverSettings::default()
        }
    }

    /// The ranked lower bound of `defender` (`crate::certify`), solved.
    fn bound(game: &Posg, not_phi: &Dra, defender: &Fsc) -> f64 {
        ranked_lower_bound(game, not_phi, defender, &ranking())
            .unwrap()
            .value
    }

    /// `defender` with block `b` playing `pair` surely.
    fn playing(defender: &Fsc, b: usize, pair: &Choice) -> Fsc {
        let mut changed = defender.clone();
        changed.blocks[b] = vec![Choice {
            probability: 1.0,
            logit: None,
            ..*pair
        }];
        changed
    }

    /// Two states, `x` (labelled `b`) and `y`, each seen as itself; `x`
    /// always moves to `y`, and `y` goes back to `x` or stays. The
    /// defender wants `F G !b`: going back lets the adversary see `b`
    /// forever, staying wins surely.
    const LEAVE_THE_LOOP: &str = r#"{"posg": 1,
        "states": ["x", "y"], "initial": {"x": 1.0}, "labels": {"x": ["b"]},
        "defender": {"actions": ["go", "stay"], "observations": ["X", "Y"],
                     "observe": {"x": {"X": 1.0}, "y": {"Y": 1.0}}},
        "adversary": {"actions": ["a"], "observe": "full"},
        "transitions": [
            {"state": "x", "defender": "*", "adversary": "*", "next": {"y": 1.0}},
            {"state": "y", "defender": "go", "adversary": "*", "next": {"x": 1.0}},
            {"state": "y", "defender": "stay", "adversary": "*", "next": {"y": 1.0}}]}"#;

    /// The defender that goes back from `y` loses surely. Staying in `y`
    /// keeps every value's one-step average (the adversary wins from `y`
    /// before and `y` is where it stays), yet wins surely: the new bottom
    /// component `{y}` never sees `b`, and the refutation's second
    /// condition keeps the move. A move in `x`'s block changes no
    /// transition and is refuted.
    #[test]
    fn a_move_that_closes_a_losing_loop_is_not_refuted() {
        let game = from_json_str(LEAVE_THE_LOOP, "loop.posg.json").unwrap();
        let not_phi = not_phi("F G !b");
        let universe = Fsc::uniform_enabled(Role::Defender, 1, game.defender());
        let pair = |b: usize, action: usize| universe.blocks[b][action];
        let going = playing(&playing(&universe, 0, &pair(0, 0)), 1, &pair(1, 0));
        assert_eq!(bound(&game, &not_phi, &going), 0.0);
        let refuter = Refuter::new(&game, &not_phi, &going, &ranking()).unwrap();
        let staying = playing(&going, 1, &pair(1, 1));
        assert!((bound(&game, &not_phi, &staying) - 1.0).abs() < 1e-12);
        assert!(!refuter.refutes(&staying, 1));
        let idle = playing(&going, 0, &pair(0, 1));
        assert_eq!(bound(&game, &not_phi, &idle), 0.0);
        assert!(refuter.refutes(&idle, 0));
    }

    /// A distribution over `names` with `support` random positive weights.
    fn random_distribution(rng: &mut ChaCha8Rng, names: &[String], support: usize) -> Value {
        let mut map = Map::new();
        for _ in 0..support {
            let name = &names[rng.random_range(0..names.len())];
            let weight =
                rng.random_range(0.1..1.0) + map.get(name).and_then(Value::as_f64).unwrap_or(0.0);
            map.insert(name.clone(), json!(weight));
        }
        let total: f64 = map.values().filter_map(Value::as_f64).sum();
        for weight in map.values_mut() {
            *weight = json!(weight.as_f64().unwrap() / total);
        }
        Value::Object(map)
    }

    /// A random game of 4-5 states labelled from {goal, unsafe}, two
    /// actions per player, two noisy defender observations, transitions
    /// with 1-2 successors.
    fn random_game(seed: u64) -> Posg {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let states: Vec<String> = (0..rng.random_range(4..=5))
            .map(|i| format!("s{i}"))
            .collect();
        let observations = vec!["o0".to_string(), "o1".to_string()];
        let observe: Map<String, Value> = (states.iter())
            .map(|s| {
                let support = rng.random_range(1..=2);
                (
                    s.clone(),
                    random_distribution(&mut rng, &observations, support),
                )
            })
            .collect();
        let labels: Map<String, Value> = (states.iter())
            .map(|s| {
                let props: Vec<&str> = (["goal", "unsafe"].into_iter())
                    .filter(|_| rng.random_bool(0.3))
                    .collect();
                (s.clone(), json!(props))
            })
            .collect();
        let mut transitions = Vec::new();
        for s in &states {
            for u in ["u0", "u1"] {
                for v in ["v0", "v1"] {
                    let support = rng.random_range(1..=2);
                    let next = random_distribution(&mut rng, &states, support);
                    transitions
                        .push(json!({"state": s, "defender": u, "adversary": v, "next": next}));
                }
            }
        }
        let game = json!({
            "posg": 1, "states": states, "initial": {"s0": 1.0}, "labels": labels,
            "defender": {"actions": ["u0", "u1"], "observations": observations, "observe": observe},
            "adversary": {"actions": ["v0", "v1"], "observe": "full"},
            "transitions": transitions,
        });
        from_json_str(&game.to_string(), "random.posg.json").unwrap()
    }

    /// A random 2-node defender: each block one or two of its enabled
    /// pairs, with random probabilities.
    fn random_defender(game: &Posg, rng: &mut ChaCha8Rng) -> Fsc {
        let mut defender = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        for block in &mut defender.blocks {
            let kept = 1 + rng.random_range(0..2).min(block.len() - 1);
            let mut chosen: Vec<Choice> = (0..kept)
                .map(|_| block[rng.random_range(0..block.len())])
                .collect();
            chosen.dedup_by_key(|c| (c.next, c.action));
            let weights: Vec<f64> = chosen.iter().map(|_| rng.random_range(0.1..1.0)).collect();
            let total: f64 = weights.iter().sum();
            for (choice, weight) in chosen.iter_mut().zip(weights) {
                choice.probability = weight / total;
            }
            *block = chosen;
        }
        defender
    }

    /// On random games, defenders and objectives (reachability, safety,
    /// recurrence and persistence), no refuted move raises the solved
    /// lower bound by more than the rounding of the two solves; the
    /// refutation refutes moves, and leaves moves that raise the bound.
    #[test]
    fn no_refuted_move_raises_the_bound_on_random_games() {
        let formulas = [
            "F goal",
            "!unsafe U goal",
            "GF goal",
            "F G !unsafe",
            "GF goal & G !unsafe",
        ];
        let (mut refuted, mut raising) = (0, 0);
        for seed in 0..40 {
            let game = random_game(seed);
            let not_phi = not_phi(formulas[seed as usize % formulas.len()]);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
            for _ in 0..3 {
                let defender = random_defender(&game, &mut rng);
                let before = bound(&game, &not_phi, &defender);
                let refuter = Refuter::new(&game, &not_phi, &defender, &ranking()).unwrap();
                for (b, pairs) in universe.blocks.iter().enumerate() {
                    for pair in pairs {
                        let changed = playing(&defender, b, pair);
                        let after = bound(&game, &not_phi, &changed);
                        if refuter.refutes(&changed, b) {
                            refuted += 1;
                            assert!(
                                after <= before + 1e-9,
                                "seed {seed}, block {b}: {before} -> {after}"
                            );
                        } else if after > before + 1e-6 {
                            raising += 1;
                        }
                    }
                }
            }
        }
        assert!(
            refuted > 100 && raising > 20,
            "{refuted} refuted, {raising} raising"
        );
    }
}
