//! The certification product (module documentation of [`super`]): the
//! reachable MDP on `(s, q, g)` of a game, an automaton and one player's
//! controller, explored breadth first; and its [`Recipe`], which writes the
//! product of another controller on the same support without exploring
//! again (the guarantee ascent and the race's checks certify thousands of
//! controllers of one support; the exploration's hashing was most of a
//! bound's cost on the 16x16 grid).

use super::CertifyError;
use crate::automaton::{Dra, RabinPair};
use crate::controller::{Fsc, Mixture, Role, Support};
use crate::game::{AdversaryAction, DefenderAction, Player, Posg};
use crate::interner::{Interner, TooManyKeys};
use crate::mdp::{Mdp, MdpBuilder, MdpError};

/// The reachable product MDP of a game, an automaton and one player's controller.
pub(super) struct Product {
    /// The MDP: in the state of `(s, q, node)`, action `a` is the free
    /// player's action `free_actions[s][a]`.
    pub mdp: Mdp,
    /// The number of each `(s, q, node)`: MDP state `m` is `ids[m]`.
    pub ids: Interner<(usize, usize, usize)>,
    /// `p0` as `(MDP state, probability)`.
    pub initial: Vec<(usize, f64)>,
    /// The free player's actions per game state: MDP action `a` in
    /// `(s, q, node)` is the free player's action `free_actions[s][a]`.
    pub free_actions: Vec<Vec<usize>>,
}

/// Where the exploration of a [`Product`] starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Seeds {
    /// The support of `p0` only: the reachable product.
    Initial,
    /// Every node of the controller at each initial state as well (with
    /// `p0` unchanged): the states a change of the controller towards an
    /// unused node would reach are explored too.
    EveryNode,
}

/// How a product's probabilities follow from its controller's: for each
/// MDP entry the terms `A(j) T` summed into it, in the order the
/// exploration summed them, and the initial entries' `(init(s), node)`.
/// A controller with the recipe's support (and so the same product graph)
/// gets its product by [`Recipe::refill`], to the bit what exploring it
/// gives.
pub(super) struct Recipe {
    support: Support,
    /// The player whose controller the product fixes.
    fixed: Role,
    seeds: Seeds,
    mixture: Mixture,
    /// Each term's mixture entry `j` and game probability `T`, entry after
    /// entry.
    terms: Vec<(u32, f64)>,
    /// The terms of MDP entry `e` are `terms[term_ends[e]..term_ends[e + 1]]`.
    term_ends: Vec<usize>,
    /// `(init(s), node)` of each entry of `p0`.
    initial: Vec<(f64, usize)>,
    /// The entries' probabilities of the last refill (kept to reuse the
    /// allocation).
    probabilities: Vec<f64>,
}

impl Product {
    /// Explores the product from `p0` breadth first; the free player's
    /// action `w` in `(s, q, g)`, one of those enabled in `s`, has the
    /// distribution of the module documentation of [`super`] (summed over
    /// duplicate successors).
    pub fn build(
        game: &Posg,
        dra: &Dra,
        controller: &Fsc,
        fixed: Role,
    ) -> Result<Self, CertifyError> {
        Self::explore(game, dra, controller, fixed, Seeds::Initial)
    }

    /// [`Product::build`], its exploration starting from `seeds`.
    pub fn explore(
        game: &Posg,
        dra: &Dra,
        controller: &Fsc,
        fixed: Role,
        seeds: Seeds,
    ) -> Result<Self, CertifyError> {
        Ok(Self::explore_recording(game, dra, controller, fixed, seeds, false)?.0)
    }

    /// [`Product::explore`] with the recipe of the product's probabilities
    /// (none where a term `A(j) T` is 0 in floating point: the graph then
    /// depends on more than the support). Recording it costs a little more
    /// than exploring: worth it where controllers of one support follow.
    pub fn explore_with_recipe(
        game: &Posg,
        dra: &Dra,
        controller: &Fsc,
        fixed: Role,
        seeds: Seeds,
    ) -> Result<(Self, Option<Recipe>), CertifyError> {
        Self::explore_recording(game, dra, controller, fixed, seeds, true)
    }

    /// [`Product::explore`], with the recipe where `record`.
    fn explore_recording(
        game: &Posg,
        dra: &Dra,
        controller: &Fsc,
        fixed: Role,
        seeds: Seeds,
        record: bool,
    ) -> Result<(Self, Option<Recipe>), CertifyError> {
        check_fits(game, controller, fixed)?;
        let support = Support::of(controller);
        let mut mixture = Mixture::build(fixed.player(game), &support, game.num_states());
        mixture.refill(&Support::probabilities_of(controller).entries);
        let values = mixture.values();
        let mut builder = MdpBuilder::new();
        let mut action: Vec<(usize, u32, f64)> = Vec::new();
        let (mut terms, mut term_ends) = (Vec::new(), vec![0]);
        let mut vanished = false;
        let walked = walk(
            game,
            dra,
            controller,
            fixed,
            seeds,
            &mixture,
            |step| match step {
                Step::Action(found) if !record => {
                    builder.add_action(found.iter().map(|&(m, j, t)| (m, values[j as usize] * t)));
                }
                Step::Action(found) => {
                    // The builder sums repeated successors in the order met
                    // (a stable sort by successor): so does the recipe.
                    action.clear();
                    action.extend_from_slice(found);
                    action.sort_by_key(|&(m, _, _)| m);
                    vanished |= action
                        .iter()
                        .any(|&(_, j, t)| values[j as usize] * t == 0.0);
                    for run in action.chunk_by(|a, b| a.0 == b.0) {
                        terms.extend(run.iter().map(|&(_, j, t)| (j, t)));
                        term_ends.push(terms.len());
                    }
                    builder.add_action(action.iter().map(|&(m, j, t)| (m, values[j as usize] * t)));
                }
                Step::StateEnd => builder.end_state(),
            },
        )?;
        let product = Self {
            mdp: builder.build()?,
            ids: walked.ids,
            initial: walked.initial,
            free_actions: walked.free_actions,
        };
        let recipe = (record && !vanished).then_some(Recipe {
            support,
            fixed,
            seeds,
            mixture,
            terms,
            term_ends,
            initial: walked.initial_terms,
            probabilities: Vec::new(),
        });
        Ok((product, recipe))
    }

    /// The number of states of [`Product::build`]'s product, without
    /// building the MDP: the same count, and the same errors but those of
    /// the probabilities, which it does not form (a state without an action
    /// is an error as there).
    pub fn count_states(
        game: &Posg,
        dra: &Dra,
        controller: &Fsc,
        fixed: Role,
    ) -> Result<usize, CertifyError> {
        check_fits(game, controller, fixed)?;
        let mixture = Mixture::build(
            fixed.player(game),
            &Support::of(controller),
            game.num_states(),
        );
        let walked = walk(
            game,
            dra,
            controller,
            fixed,
            Seeds::Initial,
            &mixture,
            |_| {},
        )?;
        let stuck = walked
            .ids
            .keys()
            .iter()
            .position(|&(s, _, _)| walked.free_actions[s].is_empty());
        match stuck {
            Some(m) => Err(MdpError::no_action(m).into()),
            None => Ok(walked.ids.len()),
        }
    }

    /// `(s, q, node)` of each MDP state, in exploration order.
    pub fn states(&self) -> &[(usize, usize, usize)] {
        self.ids.keys()
    }

    /// The MDP state of `(s, q, node)`, if the exploration reached it.
    pub fn state(&self, key: (usize, usize, usize)) -> Option<usize> {
        self.ids.get(&key).map(|m| m as usize)
    }

    /// The automaton's Rabin pairs read on product states through their `q`.
    pub fn lift(&self, pairs: &[RabinPair]) -> Vec<RabinPair> {
        pairs
            .iter()
            .map(|pair| RabinPair {
                fin: self.states().iter().map(|&(_, q, _)| pair.fin[q]).collect(),
                inf: self.states().iter().map(|&(_, q, _)| pair.inf[q]).collect(),
            })
            .collect()
    }
}

impl Recipe {
    /// Whether the product of `controller` (its choices and initial nodes:
    /// [`Support::of`]), fixing player `fixed` and explored from `seeds`,
    /// has the graph of the recipe's: the same player, support and seeds.
    pub fn fits(&self, controller: &Fsc, fixed: Role, seeds: Seeds) -> bool {
        fixed == self.fixed && seeds == self.seeds && self.support.describes(controller)
    }

    /// Writes `controller`'s probabilities into `product`, the product this
    /// recipe came with (or one it refilled), where the recipe
    /// [fits](Recipe::fits) `controller`: `Ok(true)`, or the error
    /// exploring would give (`controller` not fitting the game, a
    /// probability not positive and finite, a distribution not summing to
    /// 1). `Ok(false)`, and `product` left as it was, where an entry's terms
    /// sum to 0 in floating point (the graph then differs: explore
    /// instead).
    pub fn refill(
        &mut self,
        game: &Posg,
        product: &mut Product,
        controller: &Fsc,
    ) -> Result<bool, CertifyError> {
        check_fits(game, controller, self.fixed)?;
        self.mixture
            .refill(&Support::probabilities_of(controller).entries);
        let values = self.mixture.values();
        let probabilities = &mut self.probabilities;
        probabilities.clear();
        for ends in self.term_ends.windows(2) {
            // From -0.0, as the builder's sum from the first term is.
            let sum: f64 = self.terms[ends[0]..ends[1]]
                .iter()
                .map(|&(j, t)| values[j as usize] * t)
                .sum();
            if sum == 0.0 {
                return Ok(false);
            }
            probabilities.push(sum);
        }
        product.mdp.set_probabilities(probabilities)?;
        let initial = controller.initial();
        for (entry, &(p, g)) in product.initial.iter_mut().zip(&self.initial) {
            entry.1 = p * initial[g];
        }
        Ok(true)
    }
}

/// One step of a product's breadth-first walk ([`walk`]).
enum Step<'a> {
    /// The next free action of the current state: its terms
    /// `(successor, mixture entry j, T)` in the order met.
    Action(&'a [(usize, u32, f64)]),
    /// The current state has no further action.
    StateEnd,
}

/// What a walk numbered and met: the states, `p0` as `(MDP state,
/// probability)` and as `(init(s), node)` per entry, the free player's
/// actions per game state.
struct Walked {
    ids: Interner<(usize, usize, usize)>,
    initial: Vec<(usize, f64)>,
    initial_terms: Vec<(f64, usize)>,
    free_actions: Vec<Vec<usize>>,
}

/// Walks the product of `controller` (its mixture `mixture`, on its
/// support; `controller` checked to fit the game) breadth first from
/// `seeds`, numbering states in order of discovery, and hands each state's
/// free actions and their terms to `visit`, then [`Step::StateEnd`].
fn walk(
    game: &Posg,
    dra: &Dra,
    controller: &Fsc,
    fixed: Role,
    seeds: Seeds,
    mixture: &Mixture,
    mut visit: impl FnMut(Step<'_>),
) -> Result<Walked, CertifyError> {
    let free_actions = free_actions(fixed.other().player(game), game.num_states());
    let letters = dra.state_letters(game);
    let transition = |s: usize, f: usize, w: usize| match fixed {
        Role::Defender => game.transition(s, DefenderAction(f), AdversaryAction(w)),
        Role::Adversary => game.transition(s, DefenderAction(w), AdversaryAction(f)),
    };
    let mut ids: Interner<(usize, usize, usize)> = Interner::default();
    let mut initial = Vec::new();
    let mut initial_terms = Vec::new();
    for &(s, p) in game.initial() {
        let q = dra.successor(dra.initial(), letters[s]);
        for (g, &p_node) in controller.initial().iter().enumerate() {
            if p_node > 0.0 {
                initial.push((state_id(&mut ids, (s, q, g))?, p * p_node));
                initial_terms.push((p, g));
            } else if seeds == Seeds::EveryNode {
                state_id(&mut ids, (s, q, g))?;
            }
        }
    }
    let mut found = Vec::new();
    let mut action = Vec::new();
    let mut total_terms = 0u128;
    let mut walked = 0;
    while walked < ids.len() {
        let (s, q, g) = ids.keys()[walked];
        for &w in &free_actions[s] {
            found.clear();
            for j in mixture.at(s, g) {
                let (next, f) = mixture.entry(j);
                for &(s2, t) in transition(s, f as usize, w) {
                    found.push(((s2, dra.successor(q, letters[s2]), next as usize), j, t));
                }
            }
            total_terms += found.len() as u128;
            if let Some(message) = crate::limits::exceeded(
                "the certification product MDP",
                total_terms,
                crate::limits::MAX_CHAIN_TRANSITIONS,
                "transitions or more",
                "MAX_CHAIN_TRANSITIONS",
            ) {
                return Err(CertifyError::Budget(message));
            }
            action.clear();
            for &(key, j, t) in &found {
                action.push((state_id(&mut ids, key)?, j as u32, t));
            }
            visit(Step::Action(&action));
        }
        visit(Step::StateEnd);
        walked += 1;
    }
    Ok(Walked {
        ids,
        initial,
        initial_terms,
        free_actions,
    })
}

/// Checks that `controller` is `role`'s and fits that player of `game`
/// (sizes and enabled actions, [`Fsc::check_fits`]).
fn check_fits(game: &Posg, controller: &Fsc, role: Role) -> Result<(), CertifyError> {
    let problem = if controller.role() != role {
        Err(format!("it is a {:?} controller", controller.role()))
    } else {
        controller.check_fits(role.player(game))
    };
    problem.map_err(|problem| CertifyError::Mismatch { role, problem })
}

/// The free player's actions in each state `s`: those some observation of
/// `s` enables ([`Player::action_enabled_in_state`]), in increasing order.
fn free_actions(player: &Player, num_states: usize) -> Vec<Vec<usize>> {
    (0..num_states)
        .map(|s| {
            (0..player.num_actions())
                .filter(|&w| player.action_enabled_in_state(s, w))
                .collect()
        })
        .collect()
}

/// The index of product state `(s, q, node)`, numbered in order of discovery.
fn state_id(
    ids: &mut Interner<(usize, usize, usize)>,
    key: (usize, usize, usize),
) -> Result<usize, CertifyError> {
    let id = ids.intern(key).map_err(|TooManyKeys| {
        CertifyError::Budget("the certification product MDP exceeds 2^32 - 1 states".into())
    })?;
    Ok(id as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::game::grid::GridSpec;
    use crate::pipeline::Automata;

    /// An automaton for the negation of `formula`.
    fn not_phi(formula: &str) -> Dra {
        Automata::from_ltl(formula).unwrap().not_phi.unwrap()
    }

    /// `fsc` with its choices and its initial nodes reweighted by a
    /// positive pattern varying with `salt` (the support unchanged: an
    /// unused initial node stays unused).
    fn reweighted(fsc: &Fsc, salt: usize) -> Fsc {
        let pattern = |i: usize| ((i * 7919 + salt * 31) % 97 + 1) as f64;
        let normalised = |weights: Vec<f64>| {
            let total: f64 = weights.iter().sum();
            weights.into_iter().map(move |w| w / total)
        };
        let mut other = fsc.clone();
        for block in &mut other.blocks {
            let weights = (0..block.len()).map(pattern).collect();
            for (choice, p) in block.iter_mut().zip(normalised(weights)) {
                choice.probability = p;
            }
        }
        let weights = (other.initial.iter().enumerate())
            .map(|(g, &p)| if p > 0.0 { pattern(g) } else { 0.0 })
            .collect();
        other.initial = normalised(weights).collect();
        other
    }

    /// `fsc` starting in every node.
    fn starting_anywhere(fsc: &Fsc) -> Fsc {
        let mut other = fsc.clone();
        let nodes = other.initial.len() as f64;
        other.initial.iter_mut().for_each(|p| *p = 1.0 / nodes);
        other
    }

    /// On a grid whose defender observes its cell with noise (several
    /// terms per MDP entry), the recipe of one controller's product writes
    /// the product of another on the same support to the bit (transitions
    /// and `p0`), from either seeds, with an unused initial node (so that
    /// the seeds differ) or none; it does not fit another support, other
    /// seeds or the other player.
    #[test]
    fn a_refilled_product_is_the_explored_one() {
        let game = GridSpec::square(5).build().unwrap();
        let not_phi = not_phi("!unsafe U goal");
        let uniform = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        for first in [
            reweighted(&uniform, 1),
            reweighted(&starting_anywhere(&uniform), 1),
        ] {
            for seeds in [Seeds::Initial, Seeds::EveryNode] {
                refills_as_explored(&game, &not_phi, &first, seeds);
            }
        }
    }

    /// The checks of [`a_refilled_product_is_the_explored_one`] from `first`.
    fn refills_as_explored(game: &Posg, not_phi: &Dra, first: &Fsc, seeds: Seeds) {
        let (mut product, recipe) =
            Product::explore_with_recipe(game, not_phi, first, Role::Defender, seeds).unwrap();
        let mut recipe = recipe.expect("no term vanishes");
        let summed = recipe
            .term_ends
            .windows(2)
            .any(|ends| ends[1] - ends[0] > 1);
        assert!(summed, "some entry sums several terms");
        for salt in 2..5 {
            let next = reweighted(first, salt);
            assert!(recipe.fits(&next, Role::Defender, seeds));
            assert!(recipe.refill(game, &mut product, &next).unwrap());
            let explored = Product::explore(game, not_phi, &next, Role::Defender, seeds).unwrap();
            assert_eq!(product.states(), explored.states());
            let bits = |initial: &[(usize, f64)]| -> Vec<(usize, u64)> {
                initial.iter().map(|&(m, p)| (m, p.to_bits())).collect()
            };
            assert_eq!(bits(&product.initial), bits(&explored.initial));
            assert!(product.mdp.same_graph(&explored.mdp));
            for m in 0..explored.mdp.num_states() {
                for a in 0..explored.mdp.num_actions(m) {
                    let bits = |mdp: &Mdp| -> Vec<u64> {
                        mdp.distribution(m, a)
                            .iter()
                            .map(|e| e.1.to_bits())
                            .collect()
                    };
                    assert_eq!(bits(&product.mdp), bits(&explored.mdp), "state {m}");
                }
            }
        }
        let other_seeds = match seeds {
            Seeds::Initial => Seeds::EveryNode,
            Seeds::EveryNode => Seeds::Initial,
        };
        assert!(!recipe.fits(first, Role::Defender, other_seeds));
        assert!(!recipe.fits(first, Role::Adversary, seeds));
        let mut narrower = first.clone();
        let block = narrower.blocks.iter_mut().find(|b| b.len() > 1).unwrap();
        let dropped = block.pop().unwrap();
        block[0].probability += dropped.probability;
        assert!(!recipe.fits(&narrower, Role::Defender, seeds));
    }

    /// A controller made for another game is refused with the player's
    /// mismatch, by exploring, counting and refilling alike.
    #[test]
    fn a_controller_for_another_game_is_a_mismatch_not_a_panic() {
        let game = GridSpec::square(5).build().unwrap();
        let smaller = GridSpec::square(3).build().unwrap();
        let not_phi = not_phi("!unsafe U goal");
        let foreign = Fsc::uniform_enabled(Role::Defender, 2, smaller.defender());
        let mismatch = |error: CertifyError| matches!(error, CertifyError::Mismatch { .. });
        let explored = Product::explore(&game, &not_phi, &foreign, Role::Defender, Seeds::Initial);
        assert!(explored.err().is_some_and(mismatch));
        let counted = Product::count_states(&game, &not_phi, &foreign, Role::Defender);
        assert!(counted.err().is_some_and(mismatch));
        let own = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let (mut product, recipe) =
            Product::explore_with_recipe(&game, &not_phi, &own, Role::Defender, Seeds::Initial)
                .unwrap();
        let refilled = recipe.unwrap().refill(&game, &mut product, &foreign);
        assert!(refilled.err().is_some_and(mismatch));
    }

    /// The states counted without building the MDP are those explored, for
    /// controllers of one to three nodes, starting in node 0 or anywhere.
    #[test]
    fn the_counted_states_are_the_explored_ones() {
        let game = GridSpec::square(5).build().unwrap();
        let not_phi = not_phi("GF goal & G !unsafe");
        for nodes in 1..=3 {
            let uniform = Fsc::uniform_enabled(Role::Defender, nodes, game.defender());
            for fsc in [uniform.clone(), starting_anywhere(&uniform)] {
                let explored =
                    Product::explore(&game, &not_phi, &fsc, Role::Defender, Seeds::Initial)
                        .unwrap();
                let counted = Product::count_states(&game, &not_phi, &fsc, Role::Defender).unwrap();
                assert_eq!(counted, explored.states().len(), "{nodes} nodes");
            }
        }
    }
}
