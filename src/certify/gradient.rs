//! The gradient of the certified lower bound with respect to the defender's
//! controller probabilities (method.md section 6, "the lower bound's
//! gradient").
//!
//! The lower bound `L(mu_def) = 1 - max_sigma P^sigma(!phi)` is the value of
//! the defender's controller against an adversary that sees everything
//! ([`super::lower_bound`]). It is the pointwise minimum, over the
//! adversary's memoryless strategies `sigma` of the product MDP, of the
//! smooth functions `1 - P^sigma(!phi)`, so where the optimal `sigma*` is
//! unique its derivative is that of `1 - P^{sigma*}(!phi)` with `sigma*`
//! held fixed (Danskin's theorem); where several strategies are optimal it
//! is the derivative of one of them, a one-sided derivative of `L`. With
//! `x` the optimal values of `!phi` and `y` the expected visits to the
//! undecided states under `sigma*` (`PolicySystems::expected_visits` in
//! `src/mdp/reachability.rs`):
//!
//! ```text
//! dL/d mu_def(g', u | g, o) = - sum_{(s, q, g) undecided} y(s, q, g) O_def(o | s)
//!                             sum_s' T(s' | s, u, sigma*(s, q, g)) x(s', delta(q, L(s')), g'),
//! dL/d init_def(g) = - sum_s init(s) x(s, delta(q_0, L(s)), g).
//! ```
//!
//! The decided states (value 0 or 1 whatever the probabilities inside the
//! supports) contribute nothing: their values do not move while the
//! supports stay fixed.

use super::CertifyError;
use super::product::{Product, Recipe, Seeds};
use crate::automaton::Dra;
use crate::controller::{Fsc, Role, Support};
use crate::game::{AdversaryAction, DefenderAction, Posg};
use crate::mdp::{
    PolicySystems, Reachability, accepting_end_components, accepting_union, max_reachability_with,
    qualitative_reachability,
};
use crate::solver::SolverSettings;

/// The certified lower bound of a defender's controller and its gradient.
#[derive(Debug, Clone, PartialEq)]
pub struct LowerBoundGradient {
    /// `L = 1 - max_sigma P^sigma(!phi)`, within `error_bound` of the exact
    /// bound.
    pub value: f64,
    /// The bound on `|value - L_exact|` (method.md section 8).
    pub error_bound: f64,
    /// `dL/d mu_def` per entry of the controller's [`Support`].
    pub entries: Vec<f64>,
    /// `dL/d init_def(g)` per node.
    pub initial: Vec<f64>,
}

/// The certified lower bound of `defender` (as [`super::lower_bound_within`])
/// and its gradient (module documentation), `dra_not_phi` an automaton for
/// `!phi`.
pub fn lower_bound_gradient(
    game: &Posg,
    dra_not_phi: &Dra,
    defender: &Fsc,
    settings: &SolverSettings,
) -> Result<LowerBoundGradient, CertifyError> {
    LowerBoundGradients::new(game, dra_not_phi, *settings).at(defender)
}

/// [`lower_bound_gradient`] for many controllers, usually of one support:
/// from the fourth controller of one support (and seeds) in a row, the
/// product is the previous one refilled by the recipe recorded while
/// exploring the third, not explored again (`src/certify/product.rs`);
/// where the product MDP has the graph of the previous one
/// (`Mdp::same_graph`), its graph analysis (accepting end components,
/// qualitative reachability) is reused and policy iteration starts from
/// the previous optimal strategy, which is proper on that graph.
pub struct LowerBoundGradients<'a> {
    game: &'a Posg,
    dra_not_phi: &'a Dra,
    settings: SolverSettings,
    last: Option<LastAnalysis>,
    work: f64,
}

/// The last product, the support and seeds it was explored for, how
/// many times in a row a product of them was explored, its recipe (where
/// one was recorded), its graph analysis (in its policies' linear
/// systems: one symbolic analysis for the graph) and its optimal strategy.
struct LastAnalysis {
    product: Product,
    support: Support,
    seeds: Seeds,
    explorations: usize,
    recipe: Option<Recipe>,
    systems: PolicySystems,
    strategy: Vec<usize>,
}

/// The most states of a product that [`LowerBoundGradients::forget_if_large`]
/// keeps between checks (about 25 MB with its analysis).
pub const KEPT_PRODUCT_STATES: usize = 1 << 14;

impl LastAnalysis {
    /// Whether the product of `defender` explored from `seeds` is the last
    /// one refilled (the recipe fits and refilled it).
    fn refilled(
        &mut self,
        game: &Posg,
        defender: &Fsc,
        seeds: Seeds,
    ) -> Result<bool, CertifyError> {
        match &mut self.recipe {
            Some(recipe) if recipe.fits(defender, Role::Defender, seeds) => {
                recipe.refill(game, &mut self.product, defender)
            }
            _ => Ok(false),
        }
    }

    /// Whether `defender` explored from `seeds` has the last product's
    /// graph (the same support and seeds).
    fn repeats(&self, defender: &Fsc, seeds: Seeds) -> bool {
        self.seeds == seeds && self.support.describes(defender)
    }

    /// Whether the next product of this graph is explored with its recipe:
    /// from the third exploration in a row. A check judges two defenders
    /// of one support and then forgets a large product
    /// ([`LowerBoundGradients::forget_if_large`]): a recipe recorded at
    /// the second would never be used (on the 96x96 grid of issue 62,
    /// about 100 MB at the run's peak), while the guarantee ascent's
    /// runs of evaluations on one support refill from the fourth on.
    fn records_next(&self) -> bool {
        self.explorations >= 2
    }
}

impl<'a> LowerBoundGradients<'a> {
    /// No analysis yet; policy evaluations solved by `settings`.
    pub fn new(game: &'a Posg, dra_not_phi: &'a Dra, settings: SolverSettings) -> Self {
        Self {
            game,
            dra_not_phi,
            settings,
            last: None,
            work: 0.0,
        }
    }

    /// The work of the bounds computed so far: the product's states per
    /// linear solve (each policy evaluation, and each gradient's adjoint
    /// solve).
    pub fn work(&self) -> f64 {
        self.work
    }

    /// Drops the last product and its analysis, which the next bound would
    /// otherwise reuse where its graph is the same, if it has more than
    /// [`KEPT_PRODUCT_STATES`] states: between a run's checks, so that the
    /// starts of a race do not each hold a large product between them (on
    /// the 96x96 grid of issue 62, about 150 MB each; the 2-node run's peak
    /// fell from 2.0 to 1.3 GB). A smaller one is kept, so that small games
    /// are solved as before.
    pub fn forget_if_large(&mut self) {
        if self
            .last
            .as_ref()
            .is_some_and(|last| last.product.mdp.num_states() > KEPT_PRODUCT_STATES)
        {
            self.last = None;
        }
    }

    /// The lower bound of `defender` and its gradient.
    pub fn at(&mut self, defender: &Fsc) -> Result<LowerBoundGradient, CertifyError> {
        let support = Support::of(defender);
        self.gradient_over(defender, Seeds::Initial, &support, 0.0)
    }

    /// The lower bound of `defender` and its gradient with respect to every
    /// entry of `universe`, a support over `defender`'s nodes and
    /// observations (usually every enabled pair), including the pairs
    /// `defender` never plays: the first-order gain of moving a block
    /// towards them, by which the local search ranks its moves. The
    /// product is explored from every node at the initial states, so that
    /// the values of the states a move towards an unused node reaches are
    /// mostly known; an entry whose successors were not explored is NaN.
    /// As everywhere here, the decided states contribute nothing: a pair
    /// played from them first-order gains nothing, whatever it would
    /// change there.
    pub fn at_over(
        &mut self,
        defender: &Fsc,
        universe: &Support,
    ) -> Result<LowerBoundGradient, CertifyError> {
        self.gradient_over(defender, Seeds::EveryNode, universe, f64::NAN)
    }

    /// The lower bound of `defender` on its product explored from `seeds`,
    /// and its gradient with respect to the entries of `support` (a
    /// successor outside the product counting as `unexplored`).
    fn gradient_over(
        &mut self,
        defender: &Fsc,
        seeds: Seeds,
        support: &Support,
        unexplored: f64,
    ) -> Result<LowerBoundGradient, CertifyError> {
        let (game, dra) = (self.game, self.dra_not_phi);
        let (product, result, systems) = self.analyse(defender, seeds)?;
        let y = systems.expected_visits(&product.initial)?;
        let states = product.mdp.num_states() as f64;
        let found = gradient(game, dra, support, product, &result, &y, unexplored);
        self.work += states;
        found
    }

    /// The lower bound of `defender` alone, or the trivial bound 0 where
    /// the product mixes too slowly or its optimum cannot be proved (as
    /// [`super::lower_value_or_trivial`]).
    pub fn value_or_trivial(&mut self, defender: &Fsc) -> Result<f64, CertifyError> {
        match self.analyse(defender, Seeds::Initial) {
            Ok((product, result, _)) => Ok(lower_value(product, &result)),
            Err(error) if error.is_numerical() => Ok(0.0),
            Err(error) => Err(error),
        }
    }

    /// The product of `defender` explored from `seeds` (refilled by the
    /// last product's recipe where it fits) and its optimal values and
    /// strategy for `!phi`, reusing the last graph analysis where the graph
    /// is the same; and the policies' systems, holding the optimal
    /// strategy's factorisation.
    fn analyse(
        &mut self,
        defender: &Fsc,
        seeds: Seeds,
    ) -> Result<(&Product, Reachability, &mut PolicySystems), CertifyError> {
        let (game, dra) = (self.game, self.dra_not_phi);
        let refilled = match &mut self.last {
            Some(last) => last.refilled(game, defender, seeds)?,
            None => false,
        };
        let mut last = match self.last.take() {
            Some(last) if refilled => last,
            last => {
                let support = Support::of(defender);
                let repeats = last.as_ref().is_some_and(|l| l.repeats(defender, seeds));
                let explorations = match &last {
                    Some(last) if repeats => last.explorations + 1,
                    _ => 1,
                };
                let explored = if repeats && last.as_ref().is_some_and(LastAnalysis::records_next) {
                    Product::explore_with_recipe(game, dra, defender, Role::Defender, seeds)
                } else {
                    Product::explore(game, dra, defender, Role::Defender, seeds).map(|p| (p, None))
                };
                let (product, recipe) = match explored {
                    Ok(explored) => explored,
                    Err(error) => {
                        // The last analysis stays for the next controller.
                        self.last = last;
                        return Err(error);
                    }
                };
                match last {
                    Some(last) if last.systems.fits(&product.mdp) => LastAnalysis {
                        product,
                        support,
                        seeds,
                        explorations,
                        recipe,
                        ..last
                    },
                    _ => self.analyse_graph(product, (support, seeds, explorations), recipe)?,
                }
            }
        };
        let result = max_reachability_with(&last.product.mdp, &last.strategy, &mut last.systems);
        if let Ok(result) = &result {
            last.strategy.clone_from(&result.strategy);
            self.work += (last.product.mdp.num_states() * result.iterations) as f64;
        }
        let LastAnalysis {
            product, systems, ..
        } = self.last.insert(last);
        Ok((product, result?, systems))
    }

    /// The graph analysis of a new `product` (explored for `support` and
    /// `seeds`, the `explorations`-th time in a row): its accepting end
    /// components, qualitative reachability and policy systems, starting
    /// from the greedy strategy.
    fn analyse_graph(
        &self,
        product: Product,
        (support, seeds, explorations): (Support, Seeds, usize),
        recipe: Option<Recipe>,
    ) -> Result<LastAnalysis, CertifyError> {
        let pairs = product.lift(self.dra_not_phi.pairs());
        let accepting = accepting_end_components(&product.mdp, &pairs)?;
        let target = accepting_union(&product.mdp, &accepting);
        let qualitative = qualitative_reachability(&product.mdp, &target)?;
        let systems = PolicySystems::new(&product.mdp, qualitative, &self.settings)?;
        Ok(LastAnalysis {
            strategy: systems.greedy_start(&product.mdp),
            systems,
            product,
            support,
            seeds,
            explorations,
            recipe,
        })
    }
}

/// `L = 1 - sum p0 y`, `y >= x*` the proved upper bounds on the optimal
/// values of `!phi` on `product` (the optimality certificate).
fn lower_value(product: &Product, result: &Reachability) -> f64 {
    let not_phi: f64 = product
        .initial
        .iter()
        .map(|&(m, p)| p * result.upper[m])
        .sum();
    let rounding = 2.0 * product.initial.len() as f64 * f64::EPSILON * not_phi;
    (1.0 - not_phi - rounding).clamp(0.0, 1.0)
}

/// The lower bound and its gradient with respect to the entries of
/// `support` from the optimal values and strategy `result` on `product` and
/// the expected visits `y` (module documentation); a successor outside
/// `product` counts with the value `unexplored`.
fn gradient(
    game: &Posg,
    dra_not_phi: &Dra,
    support: &Support,
    product: &Product,
    result: &Reachability,
    y: &[f64],
    unexplored: f64,
) -> Result<LowerBoundGradient, CertifyError> {
    let x = &result.values;
    let value_at = |key: (usize, usize, usize)| product.state(key).map_or(unexplored, |m| x[m]);
    let letters = dra_not_phi.state_letters(game);
    let mut entries = vec![0.0; support.num_entries()];
    for (m, &(s, q, g)) in product.states().iter().enumerate() {
        if y[m] == 0.0 {
            continue;
        }
        let w = product.free_actions[s][result.strategy[m]];
        for &(o, p_o) in game.defender().observation_distribution(s) {
            for k in support.block(g, o) {
                let (next, u) = support.entry(k);
                let expectation: f64 = game
                    .transition(s, DefenderAction(u), AdversaryAction(w))
                    .iter()
                    .map(|&(s2, t)| t * value_at((s2, dra_not_phi.successor(q, letters[s2]), next)))
                    .sum();
                entries[k] -= y[m] * p_o * expectation;
            }
        }
    }
    let mut initial = vec![0.0; support.num_nodes()];
    for &(s, p) in game.initial() {
        let q = dra_not_phi.successor(dra_not_phi.initial(), letters[s]);
        for (g, d) in initial.iter_mut().enumerate() {
            *d -= p * value_at((s, q, g));
        }
    }
    let rounding = 2.0 * product.initial.len() as f64 * f64::EPSILON;
    Ok(LowerBoundGradient {
        value: lower_value(product, result),
        error_bound: result.error_bound + rounding,
        entries,
        initial,
    })
}
