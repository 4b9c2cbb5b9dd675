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
//! (integer weights without a common factor, over their sum: the game's
//! doubles are dyadic rationals), so a belief met again is recognised and
//! the exploration of a finite belief MDP completes. The MDP is solved
//! with its probabilities rounded up to doubles, its maximal reachability
//! proved by the optimality certificate (method.md section 8), and that
//! proved vector is checked in integers to be excessive for the exact
//! belief MDP (`Exploration::excessive`): it then bounds the exact least
//! fixed point, whatever the rounding.

use std::hash::{Hash, Hasher};
use std::sync::{Mutex, MutexGuard, OnceLock, PoisonError};

use indexmap::{Equivalent, IndexSet};
use num_bigint::BigUint;
use num_integer::Integer;
use num_traits::{One, ToPrimitive, Zero};
use rustc_hash::FxBuildHasher;
use serde::Serialize;

use super::{Analysis, Bound, CertifyError, analyse, check_values_consistent};
use crate::automaton::Dra;
use crate::controller::{Fsc, Role};
use crate::game::Posg;
use crate::mdp::{MdpBuilder, accepting_union, max_reachability};
use crate::solver::SolverSettings;

/// How far the belief exploration goes: beliefs beyond these counts are
/// not expanded (they leave with their fully informed bound).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeliefBudget {
    /// Beliefs after the first this many met are not expanded.
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
    /// 20,000 beliefs, 100,000 entries, 200,000 bits, 256-bit weights: at
    /// most about 50 ms on PRISM's POMDPs (drone-4-1, 4,106 beliefs) and
    /// the grid POMDPs of `experiments/benchmarks` (33 ms), on a 2-core
    /// EPYC.
    fn default() -> Self {
        Self {
            beliefs: 20_000,
            entries: 100_000,
            bits: 200_000,
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
/// then exact), where the product exceeds the resource budget or mixes
/// too slowly to prove its optimum, where the belief MDP cannot be built
/// or solved, or where its proved bound fails the exact check.
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
    // The bound is optional: where the product is too large or too stiff,
    // or the belief MDP cannot be built, there is none.
    let analysis = match analyse(game, dra_phi, &adversary, Role::Adversary, settings) {
        Ok(analysis) => analysis,
        Err(error) if error.is_numerical() || matches!(error, CertifyError::Budget(_)) => {
            return Ok(None);
        }
        Err(error) => return Err(error),
    };
    let explored = Exploration::new(game, &analysis, *budget).explore();
    let Ok(mdp) = explored.mdp() else {
        return Ok(None);
    };
    let Ok(result) = max_reachability(&mdp, &explored.target(), settings) else {
        return Ok(None);
    };
    // `upper` is proved for the MDP of rounded probabilities; checked on
    // the exact ones (rounded up), it bounds the exact belief MDP too.
    if !explored.excessive(&result.upper) {
        return Ok(None);
    }
    Ok(Some(BeliefBound {
        value: result.upper[ROOT].min(1.0),
        beliefs: explored.beliefs.len(),
        complete: explored.complete(),
    }))
}

/// The upper bounds a `solve` run asks for more than once, of one game
/// and automaton for `phi`, each computed when first asked for and then
/// kept:
/// * the belief bound with the default budget: a run asks for it in the
///   SAT source and for each structure's upper bound (method.md section
///   6), and the exploration is most of a small POMDP's run (3,008
///   beliefs, 4 ms on a 2-core EPYC, on PRISM's grid-avoid-4-0);
/// * the game upper bound of an adversary ([`super::upper_bound_within`],
///   the defender that sees the state): the informed source projects its
///   strategy and a single player's race starts below its value, on every
///   structure alike (on PAYNT's drone-2-8-1, 500,094 unknowns, one such
///   MDP took three minutes, and it was solved three times).
pub struct UpperBoundsOnce<'a> {
    game: &'a Posg,
    dra_phi: &'a Dra,
    settings: SolverSettings,
    /// The belief bound, once computed (`None` inside: there is none).
    found: OnceLock<Option<BeliefBound>>,
    /// The game upper bounds computed so far, with their adversaries.
    informed: Mutex<Vec<(Fsc, Bound)>>,
}

impl<'a> UpperBoundsOnce<'a> {
    /// The bounds of `game` for `phi` (automaton `dra_phi`), solved with
    /// `settings`, none computed yet.
    pub fn new(game: &'a Posg, dra_phi: &'a Dra, settings: SolverSettings) -> Self {
        Self {
            game,
            dra_phi,
            settings,
            found: OnceLock::new(),
            informed: Mutex::new(Vec::new()),
        }
    }

    /// Whether these are the bounds of `game` for the automaton `dra_phi`
    /// (the same objects).
    pub fn is_of(&self, game: &Posg, dra_phi: &Dra) -> bool {
        std::ptr::eq(self.game, game) && std::ptr::eq(self.dra_phi, dra_phi)
    }

    /// The belief bound if it has been computed (`Some(None)`: there is
    /// none), without computing it.
    pub fn known(&self) -> Option<Option<BeliefBound>> {
        self.found.get().copied()
    }

    /// [`belief_upper_bound`] with [`BeliefBudget::default`], computed on
    /// the first call and kept; an error is returned, not kept. No lock is
    /// held while it is computed (its solves may run on rayon's threads,
    /// which may meanwhile take up another call): calls at once may each
    /// compute it, and the first to finish keeps it (the same bound).
    pub fn get(&self) -> Result<Option<BeliefBound>, CertifyError> {
        if let Some(&bound) = self.found.get() {
            return Ok(bound);
        }
        let bound = belief_upper_bound(
            self.game,
            self.dra_phi,
            &BeliefBudget::default(),
            &self.settings,
        )?;
        Ok(*self.found.get_or_init(|| bound))
    }

    /// The game upper bound of `adversary` ([`super::upper_bound_within`]
    /// with these settings), computed on the first call for an equal
    /// adversary and kept; an error is returned, not kept. As for
    /// [`Self::get`], no lock is held while it is computed.
    pub fn informed(&self, adversary: &Fsc) -> Result<Bound, CertifyError> {
        if let Some(bound) = self.informed_known(adversary) {
            return Ok(bound);
        }
        let bound = super::upper_bound_within(self.game, self.dra_phi, adversary, &self.settings)?;
        let mut kept = lock(&self.informed);
        if !kept.iter().any(|(known, _)| known == adversary) {
            kept.push((adversary.clone(), bound.clone()));
        }
        Ok(bound)
    }

    /// [`Self::informed`]'s value, or the trivial bound 1 where the
    /// product mixes too slowly ([`super::upper_value_or_trivial_within`]).
    pub fn informed_or_trivial(&self, adversary: &Fsc) -> Result<f64, CertifyError> {
        super::value_or_trivial(self.informed(adversary), 1.0)
    }

    fn informed_known(&self, adversary: &Fsc) -> Option<Bound> {
        let kept = lock(&self.informed);
        (kept.iter().find(|(known, _)| known == adversary)).map(|(_, bound)| bound.clone())
    }
}

/// The guarded memo, also after a thread panicked holding it (the memo
/// holds finished bounds only).
fn lock<T>(memo: &Mutex<T>) -> MutexGuard<'_, T> {
    memo.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The belief bound of `game` for `phi` with the default budget, checked
/// to lie above `lower`, a certified lower bound of some defender
/// ([`check_below_belief`]): what `certify` reports beside that bound.
pub fn belief_bound_above(
    game: &Posg,
    dra_phi: &Dra,
    lower: &Bound,
    settings: &SolverSettings,
) -> Result<Option<BeliefBound>, CertifyError> {
    let belief = belief_upper_bound(game, dra_phi, &BeliefBudget::default(), settings)?;
    if let Some(belief) = &belief {
        check_below_belief(lower, belief)?;
    }
    Ok(belief)
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
#[derive(Debug, PartialEq, Eq)]
struct Belief {
    /// The observation the defender has just seen.
    observation: usize,
    /// `(product state, weight)`, the weights coprime.
    entries: Vec<(usize, BigUint)>,
}

impl Belief {
    /// The belief as a borrowed key.
    fn key(&self) -> BeliefKey<'_> {
        BeliefKey {
            observation: self.observation,
            entries: &self.entries,
        }
    }
}

impl Hash for Belief {
    /// The hash of [`Belief::key`], so that a key finds its belief.
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.key().hash(state);
    }
}

/// A [`Belief`] borrowed: a candidate successor is looked up by its
/// entries, and copied only where it is new.
#[derive(Hash)]
struct BeliefKey<'e> {
    /// The observation.
    observation: usize,
    /// `(product state, weight)`, the weights coprime.
    entries: &'e [(usize, BigUint)],
}

impl Equivalent<Belief> for BeliefKey<'_> {
    /// Whether the key is `belief`'s: the same observation and entries.
    fn equivalent(&self, belief: &Belief) -> bool {
        self.observation == belief.observation && self.entries == belief.entries.as_slice()
    }
}

/// A belief MDP action, exactly: the masses that reach `A` at once, that
/// reach a state that cannot reach it, and of each successor belief (by
/// index), with the powers of 2 they read by as probabilities (over the
/// denominator of the belief the move leaves, [`Expansion::Expanded`]).
#[derive(Default)]
struct Move {
    /// The mass that reaches `A`, times `2^exponent`.
    won: BigUint,
    /// The mass that reaches a state that cannot reach `A`, times
    /// `2^exponent`.
    lost: BigUint,
    /// Each successor belief, after its observation, with its mass, times
    /// `2^(exponent + observed_exponent)`.
    next: Vec<(usize, BigUint)>,
    /// The power of 2 of `won` and `lost`.
    exponent: i64,
    /// The power of 2 the observations' probabilities add to `exponent`.
    observed_exponent: i64,
}

impl Move {
    /// How `won` and `lost` read as probabilities over `denominator`.
    fn scale<'d>(&self, denominator: &'d BigUint) -> Scale<'d> {
        Scale {
            exponent: self.exponent,
            denominator,
        }
    }

    /// How the successors' masses read as probabilities over
    /// `denominator`.
    fn observed_scale<'d>(&self, denominator: &'d BigUint) -> Scale<'d> {
        Scale {
            exponent: self.exponent + self.observed_exponent,
            denominator,
        }
    }
}

/// What the exploration did with a belief.
enum Expansion {
    /// Its moves, one per action its observation enables, and the sum of
    /// its weights, which their masses read over.
    Expanded {
        /// The belief's weights summed.
        denominator: BigUint,
        /// One move per action.
        moves: Vec<Move>,
    },
    /// Not expanded: it leaves with its fully informed bound.
    Frontier(f64),
}

/// A double `mantissa * 2^exponent`, exactly, the mantissa odd (or 0):
/// a probability 1 or 1/2 multiplies a weight by 1, so that weights grow
/// only by the bits their probabilities have.
#[derive(Debug, Clone, Copy)]
struct Dyadic {
    /// The integer significand, odd unless the double is 0.
    mantissa: u64,
    /// The power of 2.
    exponent: i64,
}

impl Dyadic {
    /// The positive finite double `x`, exactly (a game's probabilities
    /// are positive: formats.md section 3).
    fn of(x: f64) -> Self {
        debug_assert!(x > 0.0 && x.is_finite(), "{x}");
        Self::of_nonnegative(x)
    }

    /// The nonnegative finite double `x`, exactly (0 as `0 * 2^0`).
    fn of_nonnegative(x: f64) -> Self {
        let bits = x.to_bits();
        let biased = ((bits >> 52) & 0x7ff) as i64;
        let fraction = bits & ((1 << 52) - 1);
        let (mantissa, exponent) = if biased == 0 {
            (fraction, -1074)
        } else {
            (fraction | (1 << 52), biased - 1075)
        };
        if mantissa == 0 {
            return Self {
                mantissa: 0,
                exponent: 0,
            };
        }
        let zeros = mantissa.trailing_zeros();
        Self {
            mantissa: mantissa >> zeros,
            exponent: exponent + i64::from(zeros),
        }
    }
}

/// How integer masses read as probabilities: `mass * 2^exponent /
/// denominator`.
#[derive(Debug, Clone, Copy)]
struct Scale<'d> {
    /// The power of 2.
    exponent: i64,
    /// The denominator (the weights' sum of the belief they come from).
    denominator: &'d BigUint,
}

impl Scale<'_> {
    /// The probability of `mass`, rounded to the nearest double.
    fn nearest(&self, mass: &BigUint) -> f64 {
        self.rounded(mass, Rounding::Nearest)
    }

    /// The probability of `mass`, rounded up to a double.
    fn above(&self, mass: &BigUint) -> f64 {
        self.rounded(mass, Rounding::Up)
    }

    /// The probability of `mass` rounded as `rounding` says, from one
    /// integer division: the quotient to 66 or 67 bits, and whether a
    /// remainder is left. Most masses and denominators have a few bits:
    /// those divide in machine integers, without a big one built.
    fn rounded(&self, mass: &BigUint, rounding: Rounding) -> f64 {
        if mass.is_zero() {
            return 0.0;
        }
        match (mass.to_u64(), self.denominator.to_u64()) {
            (Some(mass), Some(denominator)) if denominator < SMALL_DENOMINATOR => {
                rounded_small(mass, denominator, self.exponent, rounding)
            }
            _ => self.rounded_big(mass, rounding),
        }
    }

    /// [`Scale::rounded`] in big integers.
    fn rounded_big(&self, mass: &BigUint, rounding: Rounding) -> f64 {
        let shift = quotient_shift(mass.bits(), self.denominator.bits());
        let (quotient, remainder) = if shift >= 0 {
            (mass << shift as usize).div_rem(self.denominator)
        } else {
            mass.div_rem(&(self.denominator << (-shift) as usize))
        };
        let quotient = quotient
            .to_u128()
            .expect("a quotient below 2^67 fits 128 bits");
        rounded_double(
            quotient,
            remainder.is_zero(),
            self.exponent - shift,
            rounding,
        )
    }
}

/// Denominators below `2^62` divide in machine integers
/// ([`rounded_small`]).
const SMALL_DENOMINATOR: u64 = 1 << 62;

/// The power of 2 that puts `mass 2^shift / denominator` in `[2^65,
/// 2^67)`, from the bits of `mass` and of `denominator`: a quotient of 66
/// or 67 bits, at least 54 ([`rounded_double`]).
fn quotient_shift(mass_bits: u64, denominator_bits: u64) -> i64 {
    66 - (mass_bits as i64 - denominator_bits as i64)
}

/// `mass 2^exponent / denominator` rounded as `rounding` says
/// ([`Scale::rounded`]) in machine integers: `mass` of at most 64 bits,
/// `denominator` positive and below [`SMALL_DENOMINATOR`], so that the
/// shift is at least 3 and the shifted mass has at most `66 + 62` bits.
fn rounded_small(mass: u64, denominator: u64, exponent: i64, rounding: Rounding) -> f64 {
    let bits = |x: u64| u64::from(64 - x.leading_zeros());
    let shift = quotient_shift(bits(mass), bits(denominator));
    let numerator = u128::from(mass) << shift;
    let denominator = u128::from(denominator);
    let (quotient, remainder) = (numerator / denominator, numerator % denominator);
    rounded_double(quotient, remainder == 0, exponent - shift, rounding)
}

/// How an exact number becomes a double.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Rounding {
    /// To the nearest double, ties to an even significand.
    Nearest,
    /// To the least double at least the number.
    Up,
}

/// The positive number `(quotient + f) 2^exponent`, `f` in `[0, 1)` and 0
/// exactly when `exact`, rounded to a double as `rounding` says:
/// `quotient` of at least 54 bits, so that the bits below the double's
/// last one are `quotient`'s low bits and `f`. Numbers of `2^1000` and
/// more (never a probability) read as infinity.
fn rounded_double(quotient: u128, exact: bool, exponent: i64, rounding: Rounding) -> f64 {
    debug_assert!(quotient >> 53 != 0, "{quotient}");
    let bits = i64::from(128 - quotient.leading_zeros());
    if bits + exponent > 1000 {
        return f64::INFINITY;
    }
    // Below half the least subnormal: 0 to the nearest, that one up.
    if bits + exponent < -1074 {
        return match rounding {
            Rounding::Nearest => 0.0,
            Rounding::Up => f64::from_bits(1),
        };
    }
    // The bits dropped: below a normal double's 53, or below 2^-1074.
    let dropped = (bits - 53).max(-1074 - exponent);
    // Every bit dropped only where the number is just below 2^-1074.
    let (kept, rest, half) = if dropped >= bits {
        (0, quotient, 1u128 << (bits - 1))
    } else {
        (
            (quotient >> dropped) as u64,
            quotient & ((1u128 << dropped) - 1),
            1u128 << (dropped - 1),
        )
    };
    let above_half = rest > half || (rest == half && !exact);
    let tie = rest == half && exact;
    let up = match rounding {
        Rounding::Up => rest != 0 || !exact,
        Rounding::Nearest => above_half || (tie && kept & 1 == 1),
    };
    let significand = kept + u64::from(up);
    significand as f64 * power_of_two(exponent + dropped)
}

/// `2^e` for `e` in `[-1074, 1023]`, exactly.
fn power_of_two(e: i64) -> f64 {
    if e >= -1022 {
        f64::from_bits(((e + 1023) as u64) << 52)
    } else {
        f64::from_bits(1 << (e + 1074))
    }
}

/// `terms` `(m, k, d)` as integers: each `weights[k] * d` as `weights[k]
/// * mantissa * 2^(exponent - least)`, summed per product state `m`
/// (increasing) and appended to `summed`; returns the least exponent
/// `least`.
fn integer_terms(
    terms: &mut [(usize, usize, Dyadic)],
    weights: &[(usize, BigUint)],
    summed: &mut Vec<(usize, BigUint)>,
) -> i64 {
    let least = terms.iter().map(|t| t.2.exponent).min().unwrap_or(0);
    terms.sort_unstable_by_key(|t| t.0);
    let start = summed.len();
    for &mut (m, k, d) in terms {
        let term = scaled(&weights[k].1, d.mantissa, d.exponent - least);
        match summed[start..].last_mut() {
            Some((last, sum)) if *last == m => *sum += term,
            _ => summed.push((m, term)),
        }
    }
    least
}

/// `mass * factor * 2^shift` (`shift` nonnegative), without arithmetic
/// where `factor` is 1 and `shift` 0 (a probability 1: most observations).
fn scaled(mass: &BigUint, factor: u64, shift: i64) -> BigUint {
    if factor == 1 && shift == 0 {
        mass.clone()
    } else {
        (mass * factor) << shift as usize
    }
}

/// Divides `weights` by their greatest common divisor (nothing where it
/// is 1, as it mostly is): in machine integers where every weight fits
/// 64 bits, as most do.
fn make_coprime(weights: &mut [(usize, BigUint)]) {
    match small_divisor(weights) {
        Some(0 | 1) => {}
        Some(divisor) => weights.iter_mut().for_each(|(_, w)| *w /= divisor),
        None => {
            let mut divisor = BigUint::zero();
            for (_, w) in weights.iter() {
                divisor = divisor.gcd(w);
                if divisor.is_one() {
                    return;
                }
            }
            weights.iter_mut().for_each(|(_, w)| *w /= &divisor);
        }
    }
}

/// The greatest common divisor of `weights` where each fits 64 bits (1
/// as soon as it is 1), `None` where one does not.
fn small_divisor(weights: &[(usize, BigUint)]) -> Option<u64> {
    let mut divisor = 0u64;
    for (_, w) in weights {
        divisor = divisor.gcd(&w.to_u64()?);
        if divisor == 1 {
            return Some(1);
        }
    }
    Some(divisor)
}

/// Buffers the exploration reuses from move to move (cleared before each
/// use), so that a move allocates only what it keeps.
#[derive(Default)]
struct Scratch {
    /// The terms `(m', entry, probability)` of one action's successors.
    terms: Vec<(usize, usize, Dyadic)>,
    /// The product-state masses of each action of a belief, one after
    /// the other.
    masses: Vec<(usize, BigUint)>,
    /// Per action: where its masses end in `masses`, and their exponent.
    actions: Vec<(usize, i64)>,
    /// The buffers of [`Exploration::split`].
    split: SplitScratch,
}

/// Buffers of [`Exploration::split`].
#[derive(Default)]
struct SplitScratch {
    /// The measure's masses by observation: `(observation, m, mass,
    /// probability)`, `mass` an index into the measure.
    observed: Vec<(usize, usize, usize, Dyadic)>,
    /// The weights of one candidate successor belief.
    entries: Vec<(usize, BigUint)>,
}

/// The breadth-first exploration of the beliefs.
struct Exploration<'a> {
    /// The game: the defender's observations and enabled actions.
    game: &'a Posg,
    /// The product with the automaton for `phi`, the defender free: its
    /// transitions, accepting components and proved optimum `x*`.
    analysis: &'a Analysis,
    /// When to stop expanding.
    budget: BeliefBudget,
    /// Per product state: in `A`, or unable to reach it.
    in_target: Vec<bool>,
    /// The beliefs met, numbered (indexed) in order of discovery.
    beliefs: IndexSet<Belief, FxBuildHasher>,
    /// The root's move (the initial distribution split by observation,
    /// over the denominator 1).
    root: Move,
    /// What became of each belief, in order (the beliefs not yet taken
    /// have none).
    expansions: Vec<Expansion>,
    /// The entries of the beliefs met.
    entries: usize,
    /// The bits of those entries' weights.
    bits: u64,
}

impl<'a> Exploration<'a> {
    /// The exploration of the beliefs of `game` on the product `analysis`
    /// (for `phi`, the defender free), within `budget`, nothing met yet.
    fn new(game: &'a Posg, analysis: &'a Analysis, budget: BeliefBudget) -> Self {
        Self {
            game,
            analysis,
            budget,
            in_target: accepting_union(&analysis.mdp, &analysis.accepting),
            beliefs: IndexSet::default(),
            root: Move::default(),
            expansions: Vec::new(),
            entries: 0,
            bits: 0,
        }
    }

    /// Explores from `p0` until every belief met is expanded or the budget
    /// is spent.
    fn explore(mut self) -> Self {
        let mut scratch = Scratch::default();
        self.root = self.root_move(&mut scratch);
        while self.expansions.len() < self.beliefs.len() {
            let i = self.expansions.len();
            let within = i < self.budget.beliefs
                && self.entries <= self.budget.entries
                && self.bits <= self.budget.bits
                && self.small_weights(&self.beliefs[i]);
            let expansion = if within {
                self.expand(i, &mut scratch)
            } else {
                Expansion::Frontier(self.informed_bound(i))
            };
            self.expansions.push(expansion);
        }
        self
    }

    /// The root's move: the initial distribution `p0` (the terms of one
    /// weight 1) split by observation.
    fn root_move(&mut self, scratch: &mut Scratch) -> Move {
        let one = [(0, BigUint::one())];
        scratch.terms.clear();
        (scratch.terms).extend((self.analysis.initial.iter()).map(|&(m, p)| (m, 0, Dyadic::of(p))));
        scratch.masses.clear();
        let exponent = integer_terms(&mut scratch.terms, &one, &mut scratch.masses);
        self.split(&scratch.masses, exponent, &mut scratch.split)
    }

    /// Whether every belief met was expanded.
    fn complete(&self) -> bool {
        (self.expansions.iter()).all(|e| matches!(e, Expansion::Expanded { .. }))
    }

    /// Whether every weight of `belief` is within the budget's bits.
    fn small_weights(&self, belief: &Belief) -> bool {
        belief
            .entries
            .iter()
            .all(|(_, w)| w.bits() <= self.budget.weight_bits)
    }

    /// The moves of belief `i`: one per action its observation enables
    /// (each enabled in every state of the belief: a state is in it only
    /// where it shows that observation).
    fn expand(&mut self, i: usize, scratch: &mut Scratch) -> Expansion {
        let belief = &self.beliefs[i];
        let denominator: BigUint = belief.entries.iter().map(|(_, w)| w).sum();
        scratch.masses.clear();
        scratch.actions.clear();
        for u in self.game.defender().enabled_actions(belief.observation) {
            scratch.terms.clear();
            for (k, (m, _)) in belief.entries.iter().enumerate() {
                let s = self.analysis.states[*m].0;
                let a = self.analysis.free_actions[s]
                    .iter()
                    .position(|&w| w == u)
                    .expect("an action the observation enables is enabled in its states");
                for &(m2, t) in self.analysis.mdp.distribution(*m, a) {
                    scratch.terms.push((m2, k, Dyadic::of(t)));
                }
            }
            let exponent = integer_terms(&mut scratch.terms, &belief.entries, &mut scratch.masses);
            scratch.actions.push((scratch.masses.len(), exponent));
        }
        let mut moves = Vec::with_capacity(scratch.actions.len());
        let mut start = 0;
        for &(end, exponent) in &scratch.actions {
            moves.push(self.split(&scratch.masses[start..end], exponent, &mut scratch.split));
            start = end;
        }
        Expansion::Expanded { denominator, moves }
    }

    /// The move of the product-state measure `masses` (times
    /// `2^exponent`): its mass in `A` won, its mass where `A` cannot be
    /// reached lost, the rest split by the observation of its states into
    /// beliefs (numbered where new).
    fn split(
        &mut self,
        masses: &[(usize, BigUint)],
        exponent: i64,
        scratch: &mut SplitScratch,
    ) -> Move {
        let mut won = BigUint::zero();
        let mut lost = BigUint::zero();
        let observed = &mut scratch.observed;
        observed.clear();
        for (k, (m, mass)) in masses.iter().enumerate() {
            if self.in_target[*m] {
                won += mass;
            } else if !self.analysis.result.possible[*m] {
                lost += mass;
            } else {
                let s = self.analysis.states[*m].0;
                for &(o, q) in self.game.defender().observation_distribution(s) {
                    observed.push((o, *m, k, Dyadic::of(q)));
                }
            }
        }
        // Every observation's masses on one scale (the least exponent), so
        // that their probabilities read alike.
        let least = observed.iter().map(|t| t.3.exponent).min().unwrap_or(0);
        observed.sort_unstable_by_key(|t| (t.0, t.1));
        let mut next = Vec::new();
        for group in observed.chunk_by(|a, b| a.0 == b.0) {
            let entries = &mut scratch.entries;
            entries.clear();
            (entries).extend(
                group
                    .iter()
                    .map(|&(_, m, k, d)| (m, scaled(&masses[k].1, d.mantissa, d.exponent - least))),
            );
            let total: BigUint = entries.iter().map(|(_, w)| w).sum();
            make_coprime(entries);
            next.push((self.id(group[0].0, entries), total));
        }
        Move {
            won,
            lost,
            next,
            exponent,
            observed_exponent: least,
        }
    }

    /// The number of the belief of `observation` and (coprime) `entries`,
    /// numbered next where new (its entries then taken).
    fn id(&mut self, observation: usize, entries: &mut Vec<(usize, BigUint)>) -> usize {
        let key = BeliefKey {
            observation,
            entries,
        };
        if let Some(i) = self.beliefs.get_index_of(&key) {
            return i;
        }
        self.entries += entries.len();
        self.bits += entries.iter().map(|(_, w)| w.bits()).sum::<u64>();
        let belief = Belief {
            observation,
            entries: std::mem::take(entries),
        };
        self.beliefs.insert_full(belief).0
    }

    /// The fully informed bound of belief `i`: `sum_m b(m) x*(m)` with the
    /// certificate's proved `x*`, rounded up, at most 1.
    fn informed_bound(&self, i: usize) -> f64 {
        let entries = &self.beliefs[i].entries;
        let denominator = entries.iter().map(|(_, w)| w).sum();
        let scale = Scale {
            exponent: 0,
            denominator: &denominator,
        };
        let sum: f64 = (entries.iter())
            .map(|(m, w)| scale.nearest(w) * self.analysis.result.upper[*m])
            .sum();
        // Each term within a relative eps (the probability's and the
        // product's rounding), the sum within `count` eps.
        let rounding = 1.0 + (2.0 * entries.len() as f64 + 4.0) * f64::EPSILON;
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
        add_move(&mut builder, &self.root, &BigUint::one());
        builder.end_state();
        for expansion in &self.expansions {
            match expansion {
                Expansion::Expanded { denominator, moves } => {
                    for step in moves {
                        add_move(&mut builder, step, denominator);
                    }
                }
                Expansion::Frontier(bound) => {
                    builder.add_action([(WON, *bound), (LOST, 1.0 - bound)]);
                }
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

    /// Whether `y` (on the states of [`Self::mdp`]) is excessive for the
    /// exact belief MDP: `y(WON) = 1`, at least the fully informed bound at
    /// a belief not expanded, and at least every move's expected `y` by
    /// the exact probabilities ([`holds`], in integers). Then `y` bounds
    /// the exact least fixed point, the maximal probability of reaching
    /// `A` (Knaster-Tarski), whatever the rounding of the MDP the
    /// certificate proved `y` on.
    fn excessive(&self, y: &[f64]) -> bool {
        if !y.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return false;
        }
        let belief = |j: usize| ROOT + 1 + j;
        let at_most = |at: usize, step: &Move| holds(step, y[at], y[WON], |j| y[belief(j)]);
        y[WON] == 1.0
            && at_most(ROOT, &self.root)
            && (self.expansions.iter().enumerate()).all(|(i, expansion)| match expansion {
                Expansion::Expanded { moves, .. } => {
                    moves.iter().all(|step| at_most(belief(i), step))
                }
                Expansion::Frontier(bound) => *bound <= y[belief(i)],
            })
    }
}

/// Whether `won * y_won + sum_j next_j y(j) <= y_at` for `step`'s exact
/// probabilities, each mass over the step's exact total (a game's doubles
/// may sum to 1 plus an ulp: the exact belief MDP is the one of the rows
/// normalised). In integers: every double as `mantissa * 2^exponent`, both
/// sides on the least power of 2 (the masses' common denominator
/// cancelled).
fn holds(step: &Move, y_at: f64, y_won: f64, y: impl Fn(usize) -> f64) -> bool {
    let at = Dyadic::of_nonnegative(y_at);
    let sides = |term| both_sides(term, at);
    let least = (step_terms(step, y_won, &y).flat_map(sides))
        .filter(|part| part.1 != 0)
        .map(|part| part.2)
        .min()
        .unwrap_or(0);
    let (mut left, mut right) = (BigUint::zero(), BigUint::zero());
    for [weighted, total] in step_terms(step, y_won, &y).map(sides) {
        for ((mass, mantissa, exponent), side) in [(weighted, &mut left), (total, &mut right)] {
            if mantissa != 0 {
                *side += scaled(mass, mantissa, exponent - least);
            }
        }
    }
    left <= right
}

/// A term `(mass, exponent, value)` of [`step_terms`] as its parts of the
/// two sides of [`holds`], `mass value` and `mass y_at`: `(mass, mantissa,
/// exponent)` each.
fn both_sides(
    (mass, exponent, value): (&BigUint, i64, f64),
    at: Dyadic,
) -> [(&BigUint, u64, i64); 2] {
    let d = Dyadic::of_nonnegative(value);
    [
        (mass, d.mantissa, exponent + d.exponent),
        (mass, at.mantissa, exponent + at.exponent),
    ]
}

/// A move's masses with the value each leads to: `(mass, exponent,
/// value)`, the mass times `2^exponent`, the masses positive.
fn step_terms<'s>(
    step: &'s Move,
    y_won: f64,
    y: &'s impl Fn(usize) -> f64,
) -> impl Iterator<Item = (&'s BigUint, i64, f64)> + 's {
    let observed = step.exponent + step.observed_exponent;
    [
        (&step.won, step.exponent, y_won),
        (&step.lost, step.exponent, 0.0),
    ]
    .into_iter()
    .chain((step.next.iter()).map(move |(j, m)| (m, observed, y(*j))))
    .filter(|t| !t.0.is_zero())
}

/// Checks that the certified lower bound `lower` of some defender is at
/// most the belief bound `belief` (which holds for every defender) up to
/// its error bound: exact numbers always are, so anything else is a
/// numerical failure, never a bracket.
pub fn check_below_belief(lower: &Bound, belief: &BeliefBound) -> Result<(), CertifyError> {
    check_values_consistent((lower.value, lower.error_bound), (belief.value, 0.0))
}

/// Adds `step`, a move of a belief of weights summing to `denominator`,
/// as an action of the current state (beliefs after [`ROOT`]), its
/// probabilities rounded up to doubles but the lost one (rounded to the
/// nearest: it counts nothing where [`WON`] is the target).
fn add_move(builder: &mut MdpBuilder, step: &Move, denominator: &BigUint) {
    let (scale, observed) = (step.scale(denominator), step.observed_scale(denominator));
    let beliefs = (step.next.iter()).map(|(j, mass)| (ROOT + 1 + j, observed.above(mass)));
    let ends = [
        (WON, scale.above(&step.won)),
        (LOST, scale.nearest(&step.lost)),
    ];
    builder.add_action(ends.into_iter().chain(beliefs));
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    use num_bigint::BigInt;
    use num_rational::BigRational;
    use num_traits::{Pow, Signed};

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

    /// A move whose masses are `0.8` and `0.2` as doubles (which sum to 1
    /// plus an ulp) to two beliefs, read over the masses' exact total.
    fn move_of_doubles() -> Move {
        let (a, b) = (Dyadic::of(0.8), Dyadic::of(0.2));
        let least = a.exponent.min(b.exponent);
        let mass = |d: Dyadic| BigUint::from(d.mantissa) << (d.exponent - least) as usize;
        Move {
            next: vec![(0, mass(a)), (1, mass(b))],
            exponent: least,
            ..Move::default()
        }
    }

    /// The excessiveness check is exact on the normalised row: `y` equal
    /// everywhere holds (though `0.8 + 0.2 > 1` in doubles), and a state
    /// an ulp below its successors' average does not.
    #[test]
    fn a_move_holds_exactly_on_its_normalised_row() {
        let step = move_of_doubles();
        let y = [0.75, 0.75];
        assert!(holds(&step, 0.75, 1.0, |j| y[j]));
        let below = f64::from_bits(0.75f64.to_bits() - 1);
        assert!(!holds(&step, below, 1.0, |j| y[j]));
        let uneven = [0.75, 0.5];
        assert!(holds(&step, 0.7001, 1.0, |j| uneven[j]));
        assert!(!holds(&step, 0.6999, 1.0, |j| uneven[j]));
    }

    /// `sum mass value <= y_at sum mass` for `step`, in exact rationals.
    fn holds_exactly(step: &Move, y_at: f64, y_won: f64, y: &[f64]) -> bool {
        let rational = |mass: &BigUint, exponent: i64| {
            let two = BigRational::from_integer(BigInt::from(2));
            BigRational::from_integer(BigInt::from(mass.clone())) * two.pow(exponent as i32)
        };
        let observed = step.exponent + step.observed_exponent;
        let terms: Vec<(BigRational, f64)> = [
            (&step.won, step.exponent, y_won),
            (&step.lost, step.exponent, 0.0),
        ]
        .into_iter()
        .chain(step.next.iter().map(|(j, m)| (m, observed, y[*j])))
        .map(|(m, e, v)| (rational(m, e), v))
        .collect();
        let left: BigRational = terms.iter().map(|(m, v)| m * exact(*v)).sum();
        let right: BigRational = terms.iter().map(|(m, _)| m * exact(y_at)).sum();
        left <= right
    }

    proptest::proptest! {
        /// A move holds exactly where it holds in rationals, on random
        /// masses, powers of 2 and values (0 among them), with `y_at` a few
        /// ulps from the expected value or anywhere (0 among it).
        #[test]
        fn a_move_holds_as_in_rationals(
            won in 0u64..1 << 20,
            lost in 0u64..4,
            next in proptest::collection::vec((1u64.., proptest::prop_oneof![proptest::strategy::Just(0.0), 0.0f64..=1.0]), 1..5),
            exponent in -80i64..10,
            observed_exponent in -70i64..=0,
            y_won in 0.5f64..=1.0,
            ulps in -3i64..=3,
            anywhere in proptest::prop_oneof![proptest::strategy::Just(0.0), 0.0f64..=1.0],
            near in proptest::prelude::any::<bool>(),
        ) {
            let y: Vec<f64> = next.iter().map(|t| t.1).collect();
            let step = Move {
                won: BigUint::from(won),
                lost: BigUint::from(lost),
                next: next.iter().enumerate().map(|(j, t)| (j, BigUint::from(t.0))).collect(),
                exponent,
                observed_exponent,
            };
            // The expected value in doubles, then `ulps` ulps away.
            let (mut weighted, mut total) = (0.0, 0.0);
            for (mass, e, value) in step_terms(&step, y_won, &|j| y[j]) {
                let x = mass.to_f64().unwrap() * 2f64.powi((e - exponent) as i32);
                weighted += x * value;
                total += x;
            }
            let expected = weighted / total;
            let y_at = if near {
                f64::from_bits((expected.to_bits() as i64 + ulps).max(0) as u64)
            } else {
                anywhere
            };
            let truth = holds_exactly(&step, y_at, y_won, &y);
            proptest::prop_assert_eq!(holds(&step, y_at, y_won, |j| y[j]), truth);
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

    /// The bound kept is the bound computed alone, for threads asking at
    /// once; nothing is known before it is asked for, and where there is
    /// none, that is kept; a check against a defender's lower bound above
    /// it is an error.
    #[test]
    fn the_bound_is_kept_once_computed() {
        let game = coin();
        let dra = phi("F goal");
        let alone = bound(&game, "F goal", &BeliefBudget::default());
        let once = UpperBoundsOnce::new(&game, &dra, SolverSettings::default());
        assert_eq!(once.known(), None, "not computed before asked");
        let asked: Vec<_> = std::thread::scope(|scope| {
            let threads: Vec<_> = (0..3).map(|_| scope.spawn(|| once.get())).collect();
            threads.into_iter().map(|t| t.join().unwrap()).collect()
        });
        for found in asked {
            assert_eq!(found.unwrap(), Some(alone));
        }
        assert_eq!(once.known(), Some(Some(alone)));
        let grid = crate::game::grid::GridSpec::default().build().unwrap();
        let none = UpperBoundsOnce::new(&grid, &dra, SolverSettings::default());
        assert_eq!(none.get().unwrap(), None);
        assert_eq!(none.known(), Some(None));
        assert!(once.is_of(&game, &dra) && !none.is_of(&game, &dra));
        let not_phi = Automata::from_ltl("F goal").unwrap().not_phi.unwrap();
        let defender = Fsc::uniform_enabled(Role::Defender, 1, game.defender());
        let certified = super::super::lower_bound(&game, &not_phi, &defender).unwrap();
        let at = |value: f64| Bound {
            value,
            ..certified.clone()
        };
        let settings = SolverSettings::default();
        let below = belief_bound_above(&game, &dra, &at(0.5), &settings).unwrap();
        assert_eq!(below, Some(alone));
        assert!(belief_bound_above(&game, &dra, &at(0.7), &settings).is_err());
    }

    /// The exact value of the finite double `x`.
    fn exact(x: f64) -> BigRational {
        BigRational::from_float(x).expect("finite")
    }

    /// Whether `x` is `ratio` rounded as `rounding` says, by exact
    /// comparison with its neighbouring doubles.
    fn is_rounded(x: f64, ratio: &BigRational, rounding: Rounding) -> bool {
        let below = f64::from_bits(x.to_bits() - 1);
        let above = f64::from_bits(x.to_bits() + 1);
        match rounding {
            Rounding::Up => exact(x) >= *ratio && (x == f64::from_bits(1) || exact(below) < *ratio),
            Rounding::Nearest => {
                let distance = |y: f64| (exact(y) - ratio).abs();
                let (here, left, right) = (distance(x), distance(below), distance(above));
                let even = x.to_bits() & 1 == 0;
                (here < left || (here == left && even)) && (here < right || (here == right && even))
            }
        }
    }

    proptest::proptest! {
        /// A mass over a denominator, times a power of 2, rounds to the
        /// double an exact comparison picks (ties to even), up and to the
        /// nearest, down to subnormals and quotients with many bits.
        #[test]
        fn a_scaled_ratio_rounds_like_the_exact_one(
            mass in proptest::collection::vec(proptest::prelude::any::<u32>(), 1..6),
            denominator in proptest::collection::vec(proptest::prelude::any::<u32>(), 1..6),
            exponent in -1150i64..40,
            halves in 0u32..3,
        ) {
            let mass = BigUint::new(mass) << halves;
            let denominator = BigUint::new(denominator);
            proptest::prop_assume!(!mass.is_zero() && !denominator.is_zero());
            let scale = Scale { exponent, denominator: &denominator };
            let power = BigRational::from_integer(BigInt::from(2)).pow(exponent as i32);
            let ratio = BigRational::new(BigInt::from(mass.clone()), BigInt::from(denominator.clone())) * power;
            for (x, rounding) in [(scale.nearest(&mass), Rounding::Nearest), (scale.above(&mass), Rounding::Up)] {
                if x == 0.0 {
                    proptest::prop_assert!(rounding == Rounding::Nearest);
                    proptest::prop_assert!(ratio < exact(f64::from_bits(1)) / BigInt::from(2));
                } else {
                    proptest::prop_assert!(is_rounded(x, &ratio, rounding), "{x:e} {rounding:?}");
                }
            }
        }
    }

    /// The same rounding of `mass` by `scale` in machine integers and in
    /// big ones, both directions.
    fn assert_small_is_big(scale: &Scale, mass: u64) {
        let denominator = scale.denominator.to_u64().expect("a small denominator");
        for rounding in [Rounding::Nearest, Rounding::Up] {
            let small = rounded_small(mass, denominator, scale.exponent, rounding);
            let big = scale.rounded_big(&BigUint::from(mass), rounding);
            assert_eq!(
                small.to_bits(),
                big.to_bits(),
                "{mass} / {denominator} {rounding:?}"
            );
        }
    }

    proptest::proptest! {
        /// Masses of at most 64 bits over denominators below
        /// [`SMALL_DENOMINATOR`], of every bit length (each drawn shifted
        /// right by a random count), round in machine integers as in big
        /// ones.
        #[test]
        fn a_small_ratio_rounds_as_in_big_integers(
            mass in proptest::prelude::any::<u64>(),
            mass_shift in 0u32..64,
            denominator in 1u64..SMALL_DENOMINATOR,
            denominator_shift in 0u32..62,
            exponent in -1150i64..40,
        ) {
            let mass = (mass >> mass_shift).max(1);
            let denominator = BigUint::from((denominator >> denominator_shift).max(1));
            let scale = Scale { exponent, denominator: &denominator };
            assert_small_is_big(&scale, mass);
        }
    }

    /// The widest machine-integer division: a 64-bit mass over the largest
    /// small denominator and over 1.
    #[test]
    fn the_widest_small_ratios_round_as_in_big_integers() {
        for denominator in [1, 3, SMALL_DENOMINATOR - 1] {
            let denominator = BigUint::from(denominator);
            let scale = Scale {
                exponent: -60,
                denominator: &denominator,
            };
            for mass in [1, 2, u64::MAX, u64::MAX - 1, 1 << 63] {
                assert_small_is_big(&scale, mass);
            }
        }
    }

    /// Exact ties round to an even significand: `1 + 2^-53` down to 1,
    /// `1 + 3 2^-53` up to `1 + 2^-51`; up, each to the double above.
    #[test]
    fn a_tie_rounds_to_even() {
        let one = BigUint::one();
        let scale = Scale {
            exponent: -53,
            denominator: &one,
        };
        let eps = f64::EPSILON;
        for (odd, nearest, up) in [
            (1u32, 1.0, 1.0 + eps),
            (3, 1.0 + 2.0 * eps, 1.0 + 2.0 * eps),
        ] {
            let numerator = (&one << 53) + odd;
            assert_eq!(scale.nearest(&numerator), nearest, "{odd}");
            assert_eq!(scale.above(&numerator), up, "{odd}");
        }
    }

    /// Weights lose their common factor, in machine integers or big ones
    /// (`b = 2^100 + 1`, odd): `(6, 9)` becomes `(2, 3)`, so does `(6 b, 9
    /// b)`, `(6, 9 b)` becomes `(2, 3 b)`, a single weight becomes 1;
    /// coprime weights stay.
    #[test]
    fn weights_lose_their_common_factor() {
        let big = (BigUint::one() << 100usize) + 1u32;
        let weights = |a: BigUint, b: BigUint| vec![(0, a), (1, b)];
        let six = BigUint::from(6u32);
        let nine = BigUint::from(9u32);
        for (mut given, expected) in [
            (
                weights(six.clone(), nine.clone()),
                weights(2u32.into(), 3u32.into()),
            ),
            (
                weights(&six * &big, &nine * &big),
                weights(2u32.into(), 3u32.into()),
            ),
            (
                weights(six.clone(), &nine * &big),
                weights(2u32.into(), 3u32 * &big),
            ),
            (
                weights(5u32.into(), &nine * &big),
                weights(5u32.into(), &nine * &big),
            ),
        ] {
            make_coprime(&mut given);
            assert_eq!(given, expected);
        }
        for single in [six.clone(), &nine * &big] {
            let mut given = vec![(0, single)];
            make_coprime(&mut given);
            assert_eq!(given, vec![(0, BigUint::one())]);
        }
    }

    /// A double's mantissa is odd: 1 is `1 * 2^0`, 0.75 is `3 * 2^-2`.
    #[test]
    fn a_dyadic_has_an_odd_mantissa() {
        for (x, mantissa, exponent) in [
            (1.0, 1, 0),
            (0.75, 3, -2),
            (0.0, 0, 0),
            (f64::from_bits(1), 1, -1074),
        ] {
            let d = Dyadic::of_nonnegative(x);
            assert_eq!((d.mantissa, d.exponent), (mantissa, exponent), "{x}");
        }
    }
}
