//! The belief bound of a one-player game (method.md section 6, "the
//! belief bound"): an upper bound on `P(phi)` for every observation-based
//! defender, of any memory, where the adversary has a single action (a
//! POMDP), far below the fully informed bound where observations hide what
//! matters.
//!
//! On the product MDP of the game and an automaton for `phi` (the upper
//! bound's, module documentation of [`super`]), a run that satisfies `phi`
//! ends in an accepting end component, so `P(phi) <= P(reach A)` for every
//! strategy, `A` the states of the accepting MECs. The defender's belief
//! `b` (a distribution over product states given what it observed) evolves
//! by Bayes' rule: playing `u` in belief `b` after observation `o`, the
//! product moves to `nu(m') = sum_m b(m) P(m' | m, u)`; the mass `nu(A)`
//! has reached `A`; the rest is split by the next observation `o'` into
//! the beliefs `b' = nu O(o' | .) / w` of weight `w = (nu O(o' | .))(S)`.
//! The beliefs reachable from `p0` form an MDP whose maximal probability of
//! reaching `A` is the best any observation-based defender achieves:
//! explored breadth first up to a budget, each belief not expanded leaves
//! with the fully informed bound `sum_m b(m) x*(m)` (its optimality
//! certificate's proved side, module documentation of [`super`]), which
//! bounds what any defender achieves from it. The beliefs are exact
//! rationals (so a belief met again is recognised, and the exploration of
//! a finite belief MDP completes); the MDP's probabilities are those
//! rationals rounded to the nearest double, and its maximal reachability
//! is proved by the optimality certificate (method.md section 8).

use std::collections::hash_map::Entry;

use num_bigint::{BigInt, BigUint};
use num_integer::Integer;
use num_rational::BigRational;
use num_traits::{One, ToPrimitive, Zero};
use rustc_hash::FxHashMap;
use serde::Serialize;

use super::{Analysis, CertifyError, analyse};
use crate::automaton::Dra;
use crate::controller::{Fsc, Role};
use crate::game::Posg;
use crate::mdp::{MdpBuilder, max_reachability};
use crate::solver::SolverSettings;

/// How far the belief exploration goes: beliefs beyond these counts are
/// not expanded (they leave with their fully informed bound).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeliefBudget {
    /// The most beliefs expanded.
    pub beliefs: usize,
    /// The most belief entries (product states with positive belief,
    /// summed over the beliefs met) before the exploration stops expanding.
    pub entries: usize,
    /// The most bits of those entries' integer weights, summed (what the
    /// exact arithmetic costs), before the exploration stops expanding.
    pub bits: u64,
    /// A belief with a weight of more bits than this is not expanded (its
    /// successors' weights would grow further).
    pub weight_bits: u64,
}

impl Default for BeliefBudget {
    /// 20,000 beliefs, 100,000 entries, a million bits, 256-bit weights.
    fn default() -> Self {
        Self {
            beliefs: 20_000,
            entries: 100_000,
            bits: 1_000_000,
            weight_bits: 256,
        }
    }
}

/// The belief bound and how it was found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BeliefBound {
    /// No observation-based defender satisfies `phi` with a higher
    /// probability.
    pub value: f64,
    /// The beliefs met.
    pub beliefs: usize,
    /// Whether every belief met was expanded: the bound is then the
    /// optimum over all observation-based defenders of the probability of
    /// reaching `A` (which for a reachability objective with absorbing
    /// goals is the POMDP's optimum).
    pub complete: bool,
}

/// The belief bound of `game` for `phi` (automaton `dra_phi`): `None`
/// where the adversary has more than one action (a game, not a POMDP),
/// where the defender observes the state (the fully informed bound is
/// then exact), or where a product or the belief MDP mixes too slowly to
/// prove its optimum.
pub fn belief_upper_bound(
    game: &Posg,
    dra_phi: &Dra,
    budget: &BeliefBudget,
    settings: &SolverSettings,
) -> Result<Option<BeliefBound>, CertifyError> {
    if game.adversary().num_actions() != 1 || game.defender().observes_fully() {
        return Ok(None);
    }
    let adversary = Fsc::uniform_enabled(Role::Adversary, 1, game.adversary());
    let analysis = match analyse(game, dra_phi, &adversary, Role::Adversary, settings) {
        Ok(analysis) => analysis,
        Err(error) if error.is_numerical() => return Ok(None),
        Err(error) => return Err(error),
    };
    let explored = Exploration::new(game, &analysis, *budget).explore();
    let mdp = explored.mdp()?;
    match max_reachability(&mdp, &explored.target(), settings) {
        Ok(result) => {
            let value = result.upper[ROOT] * (1.0 + 4.0 * f64::EPSILON);
            Ok(Some(BeliefBound {
                value: value.min(1.0),
                beliefs: explored.beliefs.len(),
                complete: explored.frontier.iter().all(|&f| !f),
            }))
        }
        Err(error) if CertifyError::from(error.clone()).is_numerical() => Ok(None),
        Err(error) => Err(error.into()),
    }
}

/// The belief MDP's state where `A` has been reached.
const WON: usize = 0;
/// The belief MDP's state from which `A` cannot be reached.
const LOST: usize = 1;
/// The belief MDP's state before the first observation.
const ROOT: usize = 2;

/// A belief after an observation: the observation and the product states
/// with positive probability (increasing), each with a positive integer
/// weight, the weights without a common factor: the belief is the weights
/// over their sum, and equal beliefs have equal weights.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct Belief {
    observation: usize,
    entries: Vec<(usize, BigUint)>,
}

/// A belief MDP action: the probability of reaching `A` at once, of
/// losing, and of each successor belief (by index).
struct Move {
    won: f64,
    lost: f64,
    next: Vec<(usize, f64)>,
}

/// A double `mantissa * 2^exponent`, exactly.
#[derive(Debug, Clone, Copy)]
struct Dyadic {
    mantissa: u64,
    exponent: i64,
}

impl Dyadic {
    /// The nonnegative finite double `x`, exactly (0 for 0).
    fn of(x: f64) -> Self {
        let bits = x.to_bits();
        let biased = ((bits >> 52) & 0x7ff) as i64;
        let fraction = bits & ((1 << 52) - 1);
        if biased == 0 {
            Self {
                mantissa: fraction,
                exponent: -1074,
            }
        } else {
            Self {
                mantissa: fraction | (1 << 52),
                exponent: biased - 1075,
            }
        }
    }
}

/// A measure on product states as integer weights `w(m)` times
/// `2^exponent` over `scale`, before it is split into beliefs.
struct Measure {
    weights: Vec<(usize, BigUint)>,
    exponent: i64,
    scale: BigUint,
}

impl Measure {
    /// `(weight * 2^exponent) / scale` rounded to the nearest double.
    fn probability(&self, weight: &BigUint) -> f64 {
        if weight.is_zero() {
            return 0.0;
        }
        let (numer, denom) = if self.exponent >= 0 {
            (weight << self.exponent as usize, self.scale.clone())
        } else {
            (weight.clone(), &self.scale << (-self.exponent) as usize)
        };
        BigRational::new(BigInt::from(numer), BigInt::from(denom))
            .to_f64()
            .unwrap_or(0.0)
    }
}

/// `terms` as integers: each `weight * mantissa * 2^(exponent - least)`,
/// summed per product state, and the least exponent `least`.
fn integer_terms(terms: &[(usize, &BigUint, Dyadic)]) -> (Vec<(usize, BigUint)>, i64) {
    let least = terms.iter().map(|t| t.2.exponent).min().unwrap_or(0);
    let mut summed: FxHashMap<usize, BigUint> = FxHashMap::default();
    for &(m, weight, d) in terms {
        let term = (weight * d.mantissa) << (d.exponent - least) as usize;
        *summed.entry(m).or_insert_with(BigUint::zero) += term;
    }
    let mut summed: Vec<(usize, BigUint)> = summed.into_iter().collect();
    summed.sort_unstable_by_key(|&(m, _)| m);
    (summed, least)
}

/// The breadth-first exploration of the beliefs.
struct Exploration<'a> {
    game: &'a Posg,
    analysis: &'a Analysis,
    budget: BeliefBudget,
    /// Per product state: in `A`, or unable to reach it.
    in_target: Vec<bool>,
    /// The beliefs met, numbered in order of discovery.
    beliefs: Vec<Belief>,
    ids: FxHashMap<Belief, usize>,
    /// The root's move (the initial distribution split by observation).
    root: Move,
    /// Each expanded belief's moves, one per enabled action.
    moves: Vec<Vec<Move>>,
    /// Per belief: not expanded.
    frontier: Vec<bool>,
    /// The entries of the beliefs met.
    entries: usize,
    /// The bits of those entries' weights.
    bits: u64,
}

impl<'a> Exploration<'a> {
    fn new(game: &'a Posg, analysis: &'a Analysis, budget: BeliefBudget) -> Self {
        let mut in_target = vec![false; analysis.mdp.num_states()];
        for component in &analysis.accepting {
            for &m in &component.component.states {
                in_target[m] = true;
            }
        }
        Self {
            game,
            analysis,
            budget,
            in_target,
            beliefs: Vec::new(),
            ids: FxHashMap::default(),
            root: Move {
                won: 0.0,
                lost: 0.0,
                next: Vec::new(),
            },
            moves: Vec::new(),
            frontier: Vec::new(),
            entries: 0,
            bits: 0,
        }
    }

    /// Explores from `p0` until every belief met is expanded or the budget
    /// is spent.
    fn explore(mut self) -> Self {
        let one = BigUint::one();
        let terms: Vec<(usize, &BigUint, Dyadic)> = (self.analysis.initial.iter())
            .map(|&(m, p)| (m, &one, Dyadic::of(p)))
            .collect();
        let (weights, exponent) = integer_terms(&terms);
        self.root = self.split(Measure {
            weights,
            exponent,
            scale: BigUint::one(),
        });
        let mut expanded = 0;
        while expanded < self.beliefs.len() {
            let within = expanded < self.budget.beliefs
                && self.entries <= self.budget.entries
                && self.bits <= self.budget.bits
                && self.small_weights(&self.beliefs[expanded]);
            if within {
                let moves = self.expand(expanded);
                self.moves.push(moves);
                self.frontier.push(false);
            } else {
                self.moves.push(Vec::new());
                self.frontier.push(true);
            }
            expanded += 1;
        }
        self
    }

    /// Whether every weight of `belief` is within the budget's bits.
    fn small_weights(&self, belief: &Belief) -> bool {
        belief
            .entries
            .iter()
            .all(|(_, w)| w.bits() <= self.budget.weight_bits)
    }

    /// The moves of belief `i`: one per action its observation enables.
    fn expand(&mut self, i: usize) -> Vec<Move> {
        let belief = self.beliefs[i].clone();
        let scale: BigUint = belief.entries.iter().map(|(_, w)| w).sum();
        let actions: Vec<usize> = (self.game.defender())
            .enabled_actions(belief.observation)
            .collect();
        actions
            .into_iter()
            .map(|u| {
                let mut terms = Vec::new();
                for (m, weight) in &belief.entries {
                    let s = self.analysis.states[*m].0;
                    let a = self.analysis.free_actions[s]
                        .iter()
                        .position(|&w| w == u)
                        .expect("an action the observation enables is enabled in its states");
                    for &(m2, t) in self.analysis.mdp.distribution(*m, a) {
                        terms.push((m2, weight, Dyadic::of(t)));
                    }
                }
                let (weights, exponent) = integer_terms(&terms);
                self.split(Measure {
                    weights,
                    exponent,
                    scale: scale.clone(),
                })
            })
            .collect()
    }

    /// The move of the product-state measure `nu`: its mass in `A` won,
    /// its mass where `A` cannot be reached lost, the rest split by the
    /// observation of its states into beliefs (numbered where new).
    fn split(&mut self, nu: Measure) -> Move {
        let mut won = BigUint::zero();
        let mut lost = BigUint::zero();
        let mut observed = Vec::new();
        for (m, weight) in &nu.weights {
            if self.in_target[*m] {
                won += weight;
            } else if !self.analysis.result.possible[*m] {
                lost += weight;
            } else {
                let s = self.analysis.states[*m].0;
                for &(o, q) in self.game.defender().observation_distribution(s) {
                    observed.push((o, *m, weight, Dyadic::of(q)));
                }
            }
        }
        let mut move_ = Move {
            won: nu.probability(&won),
            lost: nu.probability(&lost),
            next: Vec::new(),
        };
        // Every observation's masses on one scale (the least exponent), so
        // that the observations' weights compare.
        let least = observed.iter().map(|t| t.3.exponent).min().unwrap_or(0);
        let mut by_observation: Vec<(usize, Vec<(usize, BigUint)>)> = Vec::new();
        observed.sort_by_key(|t| (t.0, t.1));
        for (o, m, weight, d) in observed {
            let mass = (weight * d.mantissa) << (d.exponent - least) as usize;
            match by_observation.last_mut() {
                Some((last, entries)) if *last == o => entries.push((m, mass)),
                _ => by_observation.push((o, vec![(m, mass)])),
            }
        }
        let split = Measure {
            weights: Vec::new(),
            exponent: nu.exponent + least,
            scale: nu.scale,
        };
        for (o, entries) in by_observation {
            let total: BigUint = entries.iter().map(|(_, w)| w).sum();
            let weight = split.probability(&total);
            let divisor = entries.iter().fold(BigUint::zero(), |g, (_, w)| g.gcd(w));
            let belief = Belief {
                observation: o,
                entries: entries
                    .into_iter()
                    .map(|(m, w)| (m, w / &divisor))
                    .collect(),
            };
            move_.next.push((self.id(belief), weight));
        }
        move_
    }

    /// The number of `belief`, numbered next where new.
    fn id(&mut self, belief: Belief) -> usize {
        let next = self.beliefs.len();
        match self.ids.entry(belief) {
            Entry::Occupied(entry) => *entry.get(),
            Entry::Vacant(entry) => {
                let entries = &entry.key().entries;
                self.entries += entries.len();
                self.bits += entries.iter().map(|(_, w)| w.bits()).sum::<u64>();
                self.beliefs.push(entry.key().clone());
                entry.insert(next);
                next
            }
        }
    }

    /// The fully informed bound of belief `i`: `sum_m b(m) x*(m)` with the
    /// certificate's proved `x*`, rounded up, at most 1.
    fn informed_bound(&self, i: usize) -> f64 {
        let entries = &self.beliefs[i].entries;
        let belief = Measure {
            weights: Vec::new(),
            exponent: 0,
            scale: entries.iter().map(|(_, w)| w).sum(),
        };
        let sum: f64 = entries
            .iter()
            .map(|(m, w)| belief.probability(w) * self.analysis.result.upper[*m])
            .sum();
        let rounding = 1.0 + 4.0 * (entries.len() as f64 + 2.0) * f64::EPSILON;
        (sum * rounding).min(1.0)
    }

    /// The belief MDP: [`WON`] and [`LOST`] absorbing, [`ROOT`], then the
    /// beliefs; a belief not expanded moves to [`WON`] with its fully
    /// informed bound and to [`LOST`] otherwise.
    fn mdp(&self) -> Result<crate::mdp::Mdp, CertifyError> {
        let mut builder = MdpBuilder::new();
        for absorbing in [WON, LOST] {
            builder.add_action([(absorbing, 1.0)]);
            builder.end_state();
        }
        add_move(&mut builder, &self.root);
        builder.end_state();
        for (i, moves) in self.moves.iter().enumerate() {
            if self.frontier[i] {
                let bound = self.informed_bound(i);
                builder.add_action([(WON, bound), (LOST, 1.0 - bound)]);
            }
            for step in moves {
                add_move(&mut builder, step);
            }
            builder.end_state();
        }
        Ok(builder.build()?)
    }

    /// [`WON`] as the target.
    fn target(&self) -> Vec<bool> {
        let mut target = vec![false; ROOT + 1 + self.beliefs.len()];
        target[WON] = true;
        target
    }
}

/// Adds `step` as an action of the current state (beliefs after [`ROOT`]).
fn add_move(builder: &mut MdpBuilder, step: &Move) {
    let beliefs = step.next.iter().map(|&(j, w)| (ROOT + 1 + j, w));
    builder.add_action(
        [(WON, step.won), (LOST, step.lost)]
            .into_iter()
            .chain(beliefs),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    use crate::game::drn::read;
    use crate::pipeline::Automata;

    /// `tests/data/drn/coin.drn`: a coin puts the defender in one of two
    /// states it cannot tell apart, 1/3 and 2/3; one action wins in each.
    fn coin() -> Posg {
        read(Path::new("tests/data/drn/coin.drn")).unwrap().game
    }

    fn phi(formula: &str) -> Dra {
        Automata::from_ltl(formula).unwrap().phi
    }

    fn bound(game: &Posg, formula: &str, budget: &BeliefBudget) -> BeliefBound {
        belief_upper_bound(game, &phi(formula), budget, &SolverSettings::default())
            .unwrap()
            .expect("a POMDP has a belief bound")
    }

    /// On the coin game the beliefs are the coin's odds: the exploration
    /// completes, and the bound is the POMDP's optimum 2/3, not the fully
    /// informed 1; waiting forever, which keeps the belief, wins nothing
    /// (the least fixed point, not the greatest).
    #[test]
    fn the_bound_of_a_finite_belief_mdp_is_the_pomdps_optimum() {
        let game = coin();
        let found = bound(&game, "F goal", &BeliefBudget::default());
        assert!(found.complete);
        assert!((found.value - 2.0 / 3.0).abs() < 1e-9, "{found:?}");
        assert!(found.value >= 2.0 / 3.0, "an upper bound: {found:?}");
        let adversary = Fsc::uniform_enabled(Role::Adversary, 1, game.adversary());
        let informed = super::super::upper_bound(&game, &phi("F goal"), &adversary).unwrap();
        assert!((informed.value - 1.0).abs() < 1e-9);
    }

    /// A belief the budget does not expand leaves with its fully informed
    /// bound: with none expanded, the coin game's bound is 1, and the
    /// exploration is not complete.
    #[test]
    fn an_unexpanded_belief_leaves_with_its_fully_informed_bound() {
        let budget = BeliefBudget {
            beliefs: 0,
            ..BeliefBudget::default()
        };
        let found = bound(&coin(), "F goal", &budget);
        assert!(!found.complete);
        assert!((found.value - 1.0).abs() < 1e-9, "{found:?}");
    }

    /// The dark corridor of `tests/data/drn` (derived there): its beliefs
    /// are `(1/2, 1/2)`, `(1, 0)` and `(1/5, 4/5)`, and the optimum 3/4
    /// (always `left`) is also what a defender that sees the state gets.
    /// Through the automaton of `!trap U goal` (the same runs win) the
    /// bound is the same.
    #[test]
    fn the_dark_corridors_bound_is_its_optimum() {
        let game = read(Path::new("tests/data/drn/dark-corridor.drn"))
            .unwrap()
            .game;
        for formula in ["F goal", "!trap U goal"] {
            let found = bound(&game, formula, &BeliefBudget::default());
            assert!(found.complete, "{formula}");
            assert_eq!(found.beliefs, 3, "{formula}");
            assert!((found.value - 0.75).abs() < 1e-9, "{formula}: {found:?}");
        }
    }

    /// A game with an adversary that chooses has no belief bound.
    #[test]
    fn a_game_with_a_choosing_adversary_has_none() {
        let game = crate::game::grid::GridSpec::default().build().unwrap();
        let found = belief_upper_bound(
            &game,
            &phi("F goal"),
            &BeliefBudget::default(),
            &SolverSettings::default(),
        );
        assert_eq!(found.unwrap(), None);
    }
}
