//! Certified bounds on the max-min value (method.md section 6).
//!
//! Gradient play inside fixed supports cannot see an adversary that puts
//! probability exactly 0 on some action, and such an adversary can change
//! which states are recurrent. These two numbers are exact whatever the
//! optimiser did:
//!
//! * [`lower_bound`]: fix the defender's controller `mu_def` and let the
//!   adversary see `(s, q, g)` and remember everything. That is an MDP on
//!   `(s, q, g)`, with `q` a state of a deterministic Rabin automaton for
//!   `!phi`:
//!
//!   ```text
//!   P((s', q', g') | (s, q, g), v) = sum_u A_def(g', u | s, g) T(s' | s, u, v),  q' = delta(q, L(s')),
//!   A_def(g', u | s, g) = sum_o O_def(o | s) mu_def(g', u | g, o)   (controller::Mixture),
//!   p0(s, delta(q_0, L(s)), g) = init(s) init_def(g).
//!   ```
//!
//!   The bound is `1 - max_sigma P^sigma(!phi)`: no adversary of any size,
//!   observation or memory drives `P(phi)` lower, since the MDP's adversary
//!   sees more and remembers more than any FSC. The optimal memoryless
//!   strategy on this product is exported so a user can see the attack.
//! * [`upper_bound`]: fix the adversary's `mu_adv` and let the defender see
//!   `(s, q, h)` and remember everything (`q` now from an automaton for
//!   `phi`): the MDP maximum of `P(phi)`. For every defender FSC `D`,
//!   `min_adv V(D, adv) <= V(D, mu_adv) <=` this bound, so
//!   `max_def min_adv V` is at most the smallest bound over the adversaries
//!   tried.
//!
//! Both are the maximal Rabin probability of an MDP (end components, then
//! maximal reachability by policy iteration) on the product, so the
//! numbers are exact up to the reported `error_bound` (method.md section 8:
//! every policy evaluation is a cancellation-free system with a bounded
//! error). A lower bound above an upper bound beyond their error bounds is
//! impossible for exact numbers: [`bracket`] and [`check_consistent`]
//! report it as an error, never as a bracket.
//!
//! **Enabled actions** (formats.md section 6). The fixed player's controller
//! must play only actions enabled under its observations. The free player,
//! who sees the state, may play in `s` every action that *some* observation
//! `o` with `O(o | s) > 0` enables ([`crate::game::Player::action_enabled_in_state`]).
//! An FSC that observes `o` plays only actions enabled under `o`, so it has
//! no more options than that, and both bounds stay sound. They are also exact
//! for the free player's enabled sets when all observations of each state
//! enable the same actions (Storm's POMDP semantics, and every imported
//! model); when they differ, the free player of the bound is stronger than any
//! FSC, which only widens the bracket.

use std::time::Instant;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::automaton::{Dra, RabinPair};
use crate::controller::{Fsc, Role};
use crate::game::Posg;
use crate::interner::Interner;
use crate::mdp::{
    AcceptingComponent, Mdp, QualitativeReachability, Reachability, max_rabin_analysis,
    max_rabin_qualitative,
};
use crate::solver::{SolverError, SolverSettings};

pub use crate::mdp::MdpError;
pub use certificate::{BoundSummary, Certificate, CertificateReport, certificate};
pub mod belief;
mod certificate;
pub mod gradient;
mod product;
use product::Product;
pub mod refutation;
pub mod reward;
pub mod strategy;

/// Why a bound could not be computed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CertifyError {
    /// The controller is not for the expected player or does not fit the game.
    #[error("the {role:?} controller does not fit: {problem}")]
    Mismatch {
        /// The player the controller was given for.
        role: Role,
        /// What does not fit.
        problem: String,
    },
    /// The MDP analysis failed.
    #[error(transparent)]
    Mdp(#[from] MdpError),
    /// The product MDP exceeds the resource budget ([`crate::limits`]).
    #[error("{0}")]
    Budget(String),
    /// The certified lower bound exceeds the upper bound by more than their
    /// error bounds: a numerical failure, never a valid bracket.
    #[error(
        "inconsistent bounds: the certified lower bound {lower} exceeds the upper bound {upper} \
         by more than their error bounds ({lower_error:e} and {upper_error:e}); the numbers \
         cannot be trusted"
    )]
    Inconsistent {
        /// The lower bound.
        lower: f64,
        /// The upper bound.
        upper: f64,
        /// The lower bound's error bound.
        lower_error: f64,
        /// The upper bound's error bound.
        upper_error: f64,
    },
}

impl CertifyError {
    /// Whether the optimality certificate of the best response failed
    /// (method.md section 6): the bound is then unproved, not wrong.
    pub fn is_unproved_optimum(&self) -> bool {
        matches!(self, Self::Mdp(MdpError::OptimalityUnproved(_)))
    }

    /// Whether the bound is unknown for numerical reasons, not wrong: the
    /// product mixes too slowly ([`Self::is_slow_mixing`]) or the optimum
    /// could not be proved ([`Self::is_unproved_optimum`]); the trivial
    /// bound stays sound.
    pub fn is_numerical(&self) -> bool {
        self.is_slow_mixing() || self.is_unproved_optimum()
    }

    /// Whether a policy evaluation could not be solved to the tolerance
    /// because the product mixes too slowly (method.md section 8; BiCGSTAB
    /// not converging within its budget where no LU can be built is the
    /// same): the bound is unknown, not wrong, and the trivial bound stays
    /// sound.
    pub fn is_slow_mixing(&self) -> bool {
        matches!(
            self,
            Self::Mdp(MdpError::Solver(
                SolverError::Unbounded { .. }
                    | SolverError::TooLargeForExact { .. }
                    | SolverError::Inaccurate { .. }
                    | SolverError::NotConverged { .. }
            ))
        )
    }
}

/// A certified bound on `P(trace |= phi)` and the strategy that attains it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Bound {
    /// The bound on `P(phi)`, clamped to `[0, 1]`.
    pub value: f64,
    /// The free player's optimal memoryless strategy on the product MDP.
    pub strategy: Strategy,
    /// The number of reachable product MDP states.
    pub mdp_states: usize,
    /// Wall-clock time to build and solve the MDP.
    pub seconds: f64,
    /// The MDP solution's residual: the larger of the last policy
    /// evaluation's `max_s |((I - Q) x - b)(s)|` and the Bellman gap
    /// `max_s (max_a E'_a x - E'_sigma(s) x)`.
    pub residual: f64,
    /// A bound on the distance from `value` to the true bound: `value` is
    /// the proved side of the free player's optimum (its optimality
    /// certificate, method.md section 6), and the optimum lies between
    /// the strategy's own value (within the linear solves' error, section
    /// 8) and it; plus the rounding of the sums over the initial states.
    pub error_bound: f64,
    /// Whether the bound is exactly 0, exactly 1 or strictly between,
    /// decided on the product's graph (not by comparing `value` with 0 or 1).
    pub qualitative: Qualitative,
}

/// Where a probability lies, decided exactly by graph analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Qualitative {
    /// Exactly 0.
    Zero,
    /// Strictly between 0 and 1.
    Between,
    /// Exactly 1.
    One,
}

impl Qualitative {
    /// The class of `1 - p` for `p` in class `self`.
    pub fn complement(self) -> Self {
        match self {
            Self::Zero => Self::One,
            Self::Between => Self::Between,
            Self::One => Self::Zero,
        }
    }

    /// Whether the probability is positive.
    pub fn is_positive(self) -> bool {
        self != Self::Zero
    }
}

/// A memoryless deterministic strategy of the free player on the product of
/// the game, an automaton and the fixed player's controller
/// ([`crate::certify::strategy`] writes and reads it as a file).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Strategy {
    /// The player who plays it (the adversary for a lower bound).
    pub player: Role,
    /// The free player's value from the initial distribution: the largest
    /// probability of its objective (`!phi` for the adversary, `phi` for
    /// the defender), attained by this strategy.
    pub value: f64,
    /// One rule per reachable product state.
    pub rules: Vec<StrategyRule>,
}

/// The action chosen in one product state `(s, q, node)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrategyRule {
    /// The game state `s`, by name.
    pub state: String,
    /// The automaton state `q`.
    pub automaton_state: usize,
    /// The fixed player's controller node.
    pub node: usize,
    /// The chosen action, by name.
    pub action: String,
    /// The free player's value in this product state: the largest
    /// probability with which it achieves its own objective from here
    /// (`!phi` for the adversary, `phi` for the defender), attained by
    /// this strategy.
    pub free_player_value: f64,
}

/// What an optimised result guarantees (method.md section 6): the defender's
/// value against every adversary is at least `certified_lower`, and the
/// max-min value over defenders of any size is at most `upper_bound`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bracket {
    /// [`lower_bound`] of the defender.
    pub certified_lower: f64,
    /// The smallest [`upper_bound`] over the adversaries tried.
    pub upper_bound: f64,
}

/// The bracket for `defender` and the adversaries tried against it;
/// `dra_phi` and `dra_not_phi` are deterministic automata for phi and !phi.
/// An adversary whose product mixes too slowly to be solved to the
/// tolerance, or whose best response's optimum cannot be proved
/// ([`CertifyError::is_numerical`]), contributes nothing (its trivial bound
/// 1); the defender's lower bound has no such fallback: it is the number
/// reported, so its trouble is an error.
pub fn bracket<'a>(
    game: &Posg,
    dra_phi: &Dra,
    dra_not_phi: &Dra,
    defender: &Fsc,
    adversaries: impl IntoIterator<Item = &'a Fsc>,
) -> Result<Bracket, CertifyError> {
    let lower = lower_bound(game, dra_not_phi, defender)?;
    let mut upper = 1.0f64;
    for adversary in adversaries {
        match upper_bound(game, dra_phi, adversary) {
            Ok(bound) => {
                check_consistent(&lower, &bound)?;
                upper = upper.min(bound.value);
            }
            Err(error) if error.is_numerical() => {}
            Err(error) => return Err(error),
        }
    }
    Ok(Bracket {
        certified_lower: lower.value,
        upper_bound: upper,
    })
}

/// [`lower_bound`]'s value, or the trivial bound 0 when the product mixes
/// so slowly that its systems cannot be solved to the tolerance or its
/// optimum cannot be proved ([`CertifyError::is_numerical`]). Sound either
/// way; for choosing among
/// candidates, where one candidate's trouble must not stop the search.
pub fn lower_value_or_trivial(
    game: &Posg,
    dra_not_phi: &Dra,
    defender: &Fsc,
) -> Result<f64, CertifyError> {
    lower_value_or_trivial_within(game, dra_not_phi, defender, &SolverSettings::default())
}

/// [`lower_value_or_trivial`] with the policy evaluations solved by
/// `settings` ([`lower_bound_within`]).
pub fn lower_value_or_trivial_within(
    game: &Posg,
    dra_not_phi: &Dra,
    defender: &Fsc,
    settings: &SolverSettings,
) -> Result<f64, CertifyError> {
    value_or_trivial(
        lower_bound_within(game, dra_not_phi, defender, settings),
        0.0,
    )
}

/// [`upper_bound_within`]'s value, or the trivial bound 1 when the
/// product mixes too slowly (as [`lower_value_or_trivial`]).
pub fn upper_value_or_trivial_within(
    game: &Posg,
    dra_phi: &Dra,
    adversary: &Fsc,
    settings: &SolverSettings,
) -> Result<f64, CertifyError> {
    value_or_trivial(upper_bound_within(game, dra_phi, adversary, settings), 1.0)
}

/// A bound's value, or `trivial` (0 below, 1 above) where numerical
/// trouble kept it from being proved ([`CertifyError::is_numerical`]);
/// other errors pass through.
pub(crate) fn value_or_trivial(
    bound: Result<Bound, CertifyError>,
    trivial: f64,
) -> Result<f64, CertifyError> {
    match bound {
        Ok(bound) => Ok(bound.value),
        Err(error) if error.is_numerical() => Ok(trivial),
        Err(error) => Err(error),
    }
}

/// Checks `lower <= upper` up to their error bounds: for any defender and
/// adversary, `lower_bound(defender) <= V(defender, adversary) <=
/// upper_bound(adversary)`, so exact numbers always satisfy it.
pub fn check_consistent(lower: &Bound, upper: &Bound) -> Result<(), CertifyError> {
    check_values_consistent(
        (lower.value, lower.error_bound),
        (upper.value, upper.error_bound),
    )
}

/// [`check_consistent`] on `(value, error bound)` pairs.
fn check_values_consistent(
    (lower, lower_error): (f64, f64),
    (upper, upper_error): (f64, f64),
) -> Result<(), CertifyError> {
    let slack = lower_error + upper_error + 4.0 * f64::EPSILON;
    if lower <= upper + slack {
        Ok(())
    } else {
        Err(CertifyError::Inconsistent {
            lower,
            upper,
            lower_error,
            upper_error,
        })
    }
}

/// The defender's guaranteed probability of `phi` with controller
/// `defender`, against every adversary: `1 - max P(!phi)` on the product
/// with `dra_not_phi`, an automaton for `!phi` (module documentation).
pub fn lower_bound(game: &Posg, dra_not_phi: &Dra, defender: &Fsc) -> Result<Bound, CertifyError> {
    lower_bound_within(game, dra_not_phi, defender, &SolverSettings::default())
}

/// [`lower_bound`] with its policy evaluations solved by `settings` (the
/// tolerance of their error bounds, method.md section 8).
pub fn lower_bound_within(
    game: &Posg,
    dra_not_phi: &Dra,
    defender: &Fsc,
    settings: &SolverSettings,
) -> Result<Bound, CertifyError> {
    let mut bound = best_response(game, dra_not_phi, defender, Role::Defender, settings)?;
    bound.value = complement(bound.value);
    bound.qualitative = bound.qualitative.complement();
    Ok(bound)
}

/// `1 - p`, clamped to `[0, 1]`: the defender's lower bound from the
/// adversary's proved optimum `p` of `!phi`.
fn complement(p: f64) -> f64 {
    (1.0 - p).clamp(0.0, 1.0)
}

/// [`lower_bound_within`]'s value, without the adversary's strategy as
/// rules, together with the blocks of `defender` that strategy meets and
/// the analysis it came from ([`RankedBound`]): what the local search on
/// the supports ranks a defender by and prunes its moves with (the same
/// bits as [`lower_bound_within`]'s value for the same settings).
pub(crate) fn ranked_lower_bound(
    game: &Posg,
    dra_not_phi: &Dra,
    defender: &Fsc,
    settings: &SolverSettings,
) -> Result<RankedBound, CertifyError> {
    let analysis = analyse(game, dra_not_phi, defender, Role::Defender, settings)?;
    let value = complement(proved_optimum(&analysis).value().clamp(0.0, 1.0));
    Ok(RankedBound {
        value,
        blocks: blocks_met(game, defender, &analysis),
        analysis,
    })
}

/// A defender's certified lower bound (as [`lower_bound_within`] ranks
/// it), the blocks `(g, o)` of the defender that the adversary's best
/// response meets, and the analysis of its product.
pub(crate) struct RankedBound {
    /// The lower bound.
    pub value: f64,
    /// Per block, in the defender's order `g * O + o`, whether the
    /// adversary's optimal strategy meets it ([`blocks_met`]).
    pub blocks: Vec<bool>,
    /// The product MDP analysed for the adversary (its reachable states
    /// are the work of judging the defender; a [`refutation::Refuter`]
    /// of the defender's moves can start from it).
    pub analysis: Analysis,
}

/// The blocks `(g, o)` of `defender` at the product states `(s, q, g)`
/// (`o` each observation of `s`) that the adversary's optimal memoryless
/// strategy of `analysis` (which stays in the accepting end components it
/// enters, `mdp/rabin.rs`) reaches from the initial states, leaving out
/// the states from which it cannot win. A defender that differs in any
/// other block leaves that strategy's play as it is up to the first state
/// left out, from which the adversary wins nothing anyway: it wins at
/// least as much against the changed defender, whose lower bound is then
/// no higher (up to the errors of the two computed values).
fn blocks_met(game: &Posg, defender: &Fsc, analysis: &Analysis) -> Vec<bool> {
    let result = &analysis.result;
    let observations = defender.num_observations();
    let mut blocks = vec![false; defender.blocks.len()];
    let mut seen = vec![false; analysis.states.len()];
    let mut stack: Vec<usize> = analysis.initial.iter().map(|&(m, _)| m).collect();
    while let Some(m) = stack.pop() {
        if std::mem::replace(&mut seen[m], true) || !result.possible[m] {
            continue;
        }
        let (s, _, g) = analysis.states[m];
        for &(o, _) in game.defender().observation_distribution(s) {
            blocks[g * observations + o] = true;
        }
        let moves = analysis.mdp.distribution(m, result.strategy[m]);
        stack.extend(moves.iter().map(|&(next, _)| next));
    }
    blocks
}

/// The free player's optimum of `analysis` at the initial distribution:
/// its proved side, widened by the rounding of the sum over the initial
/// states, and the strategy's own value (method.md section 6).
struct ProvedOptimum {
    /// The optimality certificate's bound at the initial distribution.
    proved: f64,
    /// The strategy's value at the initial distribution.
    attained: f64,
    /// The rounding added to `proved`.
    rounding: f64,
}

/// [`ProvedOptimum`] of `analysis`.
fn proved_optimum(analysis: &Analysis) -> ProvedOptimum {
    let result = &analysis.result;
    let at_initial = |x: &[f64]| -> f64 { analysis.initial.iter().map(|&(m, p)| p * x[m]).sum() };
    // The free player's optimum is proved below `proved` (the optimality
    // certificate) and above the strategy's value `attained` less its
    // error bound: the bound reported is the proved side.
    let (attained, proved) = (at_initial(&result.values), at_initial(&result.upper));
    // The sums of nonnegative terms are exact where every term is 0, and
    // within a relative `n eps` otherwise.
    let rounding = 2.0 * analysis.initial.len() as f64 * f64::EPSILON * proved;
    ProvedOptimum {
        proved,
        attained,
        rounding,
    }
}

impl ProvedOptimum {
    /// The proved side, rounded up (not clamped).
    fn value(&self) -> f64 {
        self.proved + self.rounding
    }
}

/// The best probability of `phi` any defender achieves against `adversary`:
/// `max P(phi)` on the product with `dra_phi`, an automaton for `phi`
/// (module documentation).
pub fn upper_bound(game: &Posg, dra_phi: &Dra, adversary: &Fsc) -> Result<Bound, CertifyError> {
    upper_bound_within(game, dra_phi, adversary, &SolverSettings::default())
}

/// [`upper_bound`] with its policy evaluations solved by `settings`.
pub fn upper_bound_within(
    game: &Posg,
    dra_phi: &Dra,
    adversary: &Fsc,
    settings: &SolverSettings,
) -> Result<Bound, CertifyError> {
    best_response(game, dra_phi, adversary, Role::Adversary, settings)
}

/// Whether a defender that sees the state and remembers everything can
/// win `phi` almost surely against `adversary`: the qualitative part of
/// [`upper_bound`], decided on the graph alone. When it cannot, no defender
/// controller wins almost surely against every adversary.
pub(crate) fn almost_sure_win_possible(
    game: &Posg,
    dra_phi: &Dra,
    adversary: &Fsc,
) -> Result<bool, CertifyError> {
    let analysis = analyse_qualitative(game, dra_phi, adversary, Role::Adversary)?;
    Ok(analysis
        .initial
        .iter()
        .all(|&(m, _)| analysis.result.almost_sure[m]))
}

/// The free player's maximum probability of the automaton's language, with
/// the player `fixed` playing `controller`.
fn best_response(
    game: &Posg,
    dra: &Dra,
    controller: &Fsc,
    fixed: Role,
    settings: &SolverSettings,
) -> Result<Bound, CertifyError> {
    let start = Instant::now();
    let analysis = analyse(game, dra, controller, fixed, settings)?;
    let result = &analysis.result;
    let optimum = proved_optimum(&analysis);
    let value = optimum.value();
    let ProvedOptimum {
        proved,
        attained,
        rounding,
    } = optimum;
    let qualitative = if analysis.initial.iter().all(|&(m, _)| !result.possible[m]) {
        Qualitative::Zero
    } else if analysis.initial.iter().all(|&(m, _)| result.almost_sure[m]) {
        Qualitative::One
    } else {
        Qualitative::Between
    };
    let free = fixed.other().player(game);
    let rules = analysis
        .states
        .iter()
        .enumerate()
        .map(|(m, &(s, q, node))| StrategyRule {
            state: game.states()[s].clone(),
            automaton_state: q,
            node,
            action: free.actions()[analysis.free_actions[s][result.strategy[m]]].clone(),
            free_player_value: result.values[m],
        })
        .collect();
    Ok(Bound {
        value: value.clamp(0.0, 1.0),
        strategy: Strategy {
            player: fixed.other(),
            value: value.clamp(0.0, 1.0),
            rules,
        },
        mdp_states: analysis.states.len(),
        seconds: start.elapsed().as_secs_f64(),
        residual: result.residual,
        error_bound: result.error_bound + (proved - attained).max(0.0) + 2.0 * rounding,
        qualitative,
    })
}

/// The product MDP of a game, an automaton and one player's controller,
/// analysed for the free player's maximum probability of the automaton's
/// language (what [`lower_bound`] and [`upper_bound`] are computed from),
/// or only qualitatively (`R` = [`QualitativeReachability`]: what support
/// synthesis needs).
pub(crate) struct Analysis<R = Reachability> {
    /// `(s, q, node)` of each MDP state (`states[m]`), and the state of
    /// each `(s, q, node)` the product has (`states.get`).
    pub states: Interner<(usize, usize, usize)>,
    /// The MDP: state `m`'s action `w` is the free player's action `w`.
    pub mdp: Mdp,
    /// `p0` as `(MDP state, probability)`.
    pub initial: Vec<(usize, f64)>,
    /// Maximum reachability of the accepting end components.
    pub result: R,
    /// The accepting end components, per Rabin pair of the automaton.
    pub accepting: Vec<AcceptingComponent>,
    /// The free player's actions per game state: MDP action `a` in
    /// `(s, q, node)` is the free player's action `free_actions[s][a]`.
    pub free_actions: Vec<Vec<usize>>,
}

/// The reachable product MDP with `controller` playing for `fixed`, not
/// analysed: `(s, q, node)` per state, the MDP, and `p0`.
pub(crate) type ProductMdp = (Vec<(usize, usize, usize)>, Mdp, Vec<(usize, f64)>);

/// Builds the product with `controller` playing for `fixed`.
pub(crate) fn product_mdp(
    game: &Posg,
    dra: &Dra,
    controller: &Fsc,
    fixed: Role,
) -> Result<ProductMdp, CertifyError> {
    let Product {
        ids, mdp, initial, ..
    } = Product::build(game, dra, controller, fixed)?;
    Ok((ids.into_keys(), mdp, initial))
}

/// The number of states of [`product_mdp`]'s product, and its errors, by
/// walking its graph without building the MDP.
pub(crate) fn product_states(
    game: &Posg,
    dra: &Dra,
    controller: &Fsc,
    fixed: Role,
) -> Result<usize, CertifyError> {
    Product::count_states(game, dra, controller, fixed)
}

/// Builds the product with `controller` playing for `fixed` and decides,
/// by graph search alone, where the free player wins with positive
/// probability and where almost surely.
pub(crate) fn analyse_qualitative(
    game: &Posg,
    dra: &Dra,
    controller: &Fsc,
    fixed: Role,
) -> Result<Analysis<QualitativeReachability>, CertifyError> {
    analyse_with(game, dra, controller, fixed, max_rabin_qualitative)
}

/// Builds the product with `controller` playing for `fixed` and analyses it.
pub(crate) fn analyse(
    game: &Posg,
    dra: &Dra,
    controller: &Fsc,
    fixed: Role,
    settings: &SolverSettings,
) -> Result<Analysis, CertifyError> {
    analyse_with(game, dra, controller, fixed, |mdp, pairs| {
        max_rabin_analysis(mdp, pairs, settings)
    })
}

/// The product with `controller` playing for `fixed`, analysed by `solve`
/// for the automaton's pairs lifted to it.
fn analyse_with<R>(
    game: &Posg,
    dra: &Dra,
    controller: &Fsc,
    fixed: Role,
    solve: impl FnOnce(&Mdp, &[RabinPair]) -> Result<(R, Vec<AcceptingComponent>), MdpError>,
) -> Result<Analysis<R>, CertifyError> {
    let product = Product::build(game, dra, controller, fixed)?;
    let pairs = product.lift(dra.pairs());
    let (result, accepting) = solve(&product.mdp, &pairs)?;
    let Product {
        ids,
        mdp,
        initial,
        free_actions,
    } = product;
    Ok(Analysis {
        states: ids,
        mdp,
        initial,
        result,
        accepting,
        free_actions,
    })
}
