//! The optimality certificate of policy iteration (method.md section 6):
//! a vector `y` with `x* <= y`, proved in floating point.
//!
//! Policy iteration stops when no action improves on the current one by
//! more than its threshold, so its values `x` are those of a policy, below
//! the optimum `x*` by up to the threshold times the number of steps: on
//! a 6x6 grid with a nearly deterministic 2-node defender (33,000 expected
//! steps) by 2.2e-8, where the evaluation's own error bound was 4e-11.
//! Reporting `x` as `max P` would then put a lower bound `1 - max P` above
//! the truth.
//!
//! The certificate: `x*` is the least fixed point of the Bellman operator
//! `F(y)(s) = max_a sum_u P(u | s, a) y(u)` (with `y = 1` on the target's
//! almost-sure states and `y = 0` where it is unreachable), so every `y`
//! with `F(y) <= y` bounds it from above (Knaster-Tarski). The candidate is
//! `y = x + eps T` on the maybe states, with `x` and `T` levelled on each
//! maximal end component inside them (their maxima there: the optimum is
//! the same throughout an end component, and moves inside it then change
//! neither, exactly). `T >= 0` is a potential that every other move
//! lowers: `T(s) >= 1 + E[T(u) | s, a, leaving s's component]` for every
//! action: the maximum expected number of moves between components (it
//! exists because levelling leaves no end component), by policy iteration
//! on the quotient of the components. For each state `s` and action `a`,
//! `F(y) <= y` then reads
//!
//! ```text
//!     r_a(s) <= eps d_a(s),   r_a(s) = sum_u P(u | s, a) (x(u) - x(s)),
//!                             d_a(s) = sum_u P(u | s, a) (T(s) - T(u)),
//! ```
//!
//! over the `u` outside `s`'s component, where `r_a` is the action's
//! advantage (at most the Bellman gap) and `d_a`, the probability of
//! leaving times at least 1, is positive wherever `r_a` can be. `r_a` and
//! `d_a` are evaluated in double precision and widened by a bound on their
//! rounding, so the check proves `F(y) <= y` for the real numbers
//! `x + eps T`, whatever the errors of `x` and `T` themselves; the smallest
//! admissible `eps` is taken. The maximum is what makes every `d_a >= 0`;
//! a potential of one policy (a round of that policy iteration) serves as
//! well where the actions with `d_a < 0` lose enough, `r_a <= eps d_a`
//! for the `eps` the gaining actions ask. Each round's potential is tried
//! so, and the rounds stop at the first that proves it (on PAYNT's dodge-8
//! with one node, 3 rounds for the lower bound and 1 for the upper, where
//! the maximum took 10 each). Where no potential is found (a chain that
//! leaves its states with probabilities near the precision, so that the
//! potential outgrows it) the certificate fails, as an error, never a
//! number.

use super::{Mdp, MdpError, maximal_end_components};
use crate::solver::{LinearSolver, SolverError, SolverMethod, SolverSettings, SparsePattern};

/// The unit roundoff of `f64`.
const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;

/// BiCGSTAB iterations one potential's solve may take (at most the
/// settings' `max_iterations`) before the certificate turns to LU for it
/// and the rest of its graph's potentials.
const POTENTIAL_KRYLOV_ITERATIONS: usize = 2_000;

/// Under `auto`, quotients with at least this many nodes have their
/// potentials solved by BiCGSTAB first ([`Certificate::potential`]);
/// smaller ones as `auto` chooses (LU there costs little, and BiCGSTAB
/// first made PAYNT's dodge-6-lines-position with 3 nodes end at 0.4880
/// instead of 0.5155, on quotients of at most about 4,000 nodes). The
/// quotients of PAYNT's dodge-8 (7,938 nodes for the upper bound, 23,814
/// for the lower bound with 3 nodes) are above it.
const KRYLOV_FIRST_UNKNOWNS: usize = 5_000;

/// Policy-iteration rounds the potential may take to settle.
const MAX_ROUNDS: usize = 100;

/// The graph-only parts of the certificate for one MDP graph and its maybe
/// states (the end components, the quotient's nodes, moves and pattern,
/// the solver's symbolic analysis), kept beside the policy systems so
/// that the many results of one graph (a run's lower bounds of one
/// support) analyse it once.
pub(super) struct Certificate {
    components: Components,
    quotient: Quotient,
    solver: LinearSolver,
    /// Where BiCGSTAB solves the potentials first: the settings of the LU
    /// that takes over where it fails.
    fallback: Option<SolverSettings>,
    /// While BiCGSTAB solves the potentials: the expected moves (per
    /// quotient node) of the last one, where the next solve starts (a
    /// potential then depends on the ones before it on the graph by at
    /// most the solve's residual, which the check makes harmless).
    last_times: Option<Vec<f64>>,
    /// The potential of the last certificate proved on this graph, tried
    /// first on the next ([`Certificate::upper`]).
    last_potential: Option<Vec<f64>>,
    /// The quotient's policy whose potential proved the last certificate
    /// of this graph, evaluated on the next one's numbers second.
    last_choice: Option<Vec<usize>>,
    /// The most a reused potential or policy may raise a value (the
    /// solver's tolerance, within which the values are known anyway).
    reuse_slack: f64,
    /// The potentials solved so far (each a linear solve on the quotient;
    /// the tests read it to see which way a certificate went).
    solves: usize,
}

impl Certificate {
    /// The analysis of `mdp`'s graph with the maybe states `maybe`.
    /// The potentials are solved by BiCGSTAB where `settings` choose
    /// `auto` and the quotient has from [`KRYLOV_FIRST_UNKNOWNS`] nodes up
    /// to the LU limit (where `auto` would take LU or try BiCGSTAB first),
    /// with LU where that fails ([`Self::potential`]).
    pub fn new(mdp: &Mdp, maybe: &[usize], settings: &SolverSettings) -> Result<Self, MdpError> {
        let components = Components::of(mdp, maybe);
        let quotient = Quotient::new(&components, mdp, maybe);
        let n = quotient.pattern.n;
        let krylov_first = settings.method == SolverMethod::Auto
            && (KRYLOV_FIRST_UNKNOWNS..=settings.lu_limit).contains(&n);
        let first = if krylov_first {
            SolverSettings {
                method: SolverMethod::Krylov,
                max_iterations: settings.max_iterations.min(POTENTIAL_KRYLOV_ITERATIONS),
                ..*settings
            }
        } else {
            *settings
        };
        let fallback = krylov_first.then_some(SolverSettings {
            method: SolverMethod::Lu,
            ..*settings
        });
        let solver = LinearSolver::new(quotient.pattern.clone(), &first).map_err(unsolved)?;
        Ok(Self {
            components,
            quotient,
            solver,
            fallback,
            last_times: None,
            last_potential: None,
            last_choice: None,
            reuse_slack: settings.tolerance,
            solves: 0,
        })
    }

    /// An upper bound `y >= x*` on the maximum reachability probabilities
    /// of `mdp` (of the analysed graph) from the values `values` of a
    /// policy (1 on the almost-sure states, 0 where the target is
    /// unreachable, exact there): `y = x + eps T` on `maybe`, rounded up,
    /// and `values` elsewhere (module documentation). Each round of the
    /// potential's policy iteration is tried as `T`: the rounds stop at the
    /// first potential that proves `F(y) <= y`. Before them, what proved
    /// the last certificate of this graph is tried: its potential, then the
    /// potential of its policy on `mdp` (one solve). The check `F(y) <= y`
    /// asks nothing of `T` but that it be finite, level on each end
    /// component and 0 outside `maybe` (its nonnegativity follows from the
    /// check on maybe states), so a potential of an MDP of the same graph
    /// with other probabilities proves as well where it passes (a run's
    /// bounds of one support change little between checks); either is kept
    /// only where it raises no value by more than the solver's tolerance,
    /// so that the bound is the rounds' own within it (it depends on the
    /// certificates before it on the graph by at most that much). On
    /// PAYNT's dodge-8 with 1 node this took about 1 potential solve per
    /// certificate instead of 2.6.
    pub fn upper(
        &mut self,
        mdp: &Mdp,
        maybe: &[usize],
        values: &[f64],
    ) -> Result<Vec<f64>, MdpError> {
        let values = self.components.levelled(values);
        if let Some(potential) = self.last_potential.take() {
            if let Some(upper) = self.negligibly_raised(mdp, maybe, &values, &potential) {
                self.last_potential = Some(potential);
                return Ok(upper);
            }
        }
        let moves = self.quotient.moves(mdp);
        if let Some(choice) = self.last_choice.take() {
            // Where its solve fails, the rounds below may still succeed.
            let potential = self.potential(mdp, maybe, &moves, &choice).ok();
            let proved = potential.and_then(|potential| {
                let upper = self.negligibly_raised(mdp, maybe, &values, &potential)?;
                Some((potential, upper))
            });
            if let Some((potential, upper)) = proved {
                self.last_potential = Some(potential);
                self.last_choice = Some(choice);
                return Ok(upper);
            }
        }
        let mut choice = self.quotient.best_moves(&moves, &values);
        for _ in 0..MAX_ROUNDS {
            let potential = self.potential(mdp, maybe, &moves, &choice)?;
            let proving = choice.clone();
            let settled = !self.quotient.improve(&moves, &potential, &mut choice);
            match self.admissible_eps(mdp, maybe, &values, &potential) {
                Ok(eps) => {
                    let upper = raised(values, maybe, eps, &potential);
                    self.last_potential = Some(potential);
                    self.last_choice = Some(proving);
                    return Ok(upper);
                }
                Err(unproved) if settled => return Err(unproved),
                Err(_) => {}
            }
        }
        Err(MdpError::OptimalityUnproved(format!(
            "the potential of the certificate did not settle within {MAX_ROUNDS} rounds"
        )))
    }

    /// The expected moves of the quotient's policy `choice` on `mdp`, per
    /// state of `maybe` (0 elsewhere); an error where the solve does not
    /// give finite, nonnegative times. Under `auto`, on a quotient of at
    /// least [`KRYLOV_FIRST_UNKNOWNS`] nodes, BiCGSTAB solves it from the
    /// last potential's times (elsewhere `auto` chooses), within
    /// [`POTENTIAL_KRYLOV_ITERATIONS`]; where it fails, an LU solves it and
    /// the graph's later potentials. (Not `auto`'s own choice: its trial
    /// from 0 saw no progress in 20 iterations on PAYNT's dodge-8 with 3
    /// nodes and took LU, 1.2 s per potential, where BiCGSTAB converged in
    /// 0.02-0.2 s.)
    fn potential(
        &mut self,
        mdp: &Mdp,
        maybe: &[usize],
        moves: &Moves,
        choice: &[usize],
    ) -> Result<Vec<f64>, MdpError> {
        self.solves += 1;
        let start = self.last_times.take();
        let times = match self.expected_moves(moves, choice, start) {
            Ok(times) => times,
            Err(failed) => {
                let Some(lu) = self.fallback.take() else {
                    return Err(failed);
                };
                self.solver =
                    LinearSolver::new(self.quotient.pattern.clone(), &lu).map_err(unsolved)?;
                self.expected_moves(moves, choice, None).map_err(|error| {
                    MdpError::OptimalityUnproved(format!("{error} (BiCGSTAB before it: {failed})"))
                })?
            }
        };
        let mut potential = vec![0.0; mdp.num_states()];
        for &s in maybe {
            potential[s] = times[self.quotient.node_of[s]];
        }
        if self.fallback.is_some() {
            self.last_times = Some(times);
        }
        Ok(potential)
    }

    /// The quotient's expected moves under `choice` by the solver in use,
    /// an iterative solve starting from `start`; an error where the solve
    /// fails or gives a time that is negative or not finite (the expected
    /// moves are at least 1: such a time is a failed solve, and `raised`
    /// would round a cancelling sum).
    fn expected_moves(
        &mut self,
        moves: &Moves,
        choice: &[usize],
        start: Option<Vec<f64>>,
    ) -> Result<Vec<f64>, MdpError> {
        let times = self
            .quotient
            .evaluate(&mut self.solver, moves, choice, start)
            .map_err(unsolved)?;
        match times.iter().position(|t| !(t.is_finite() && *t >= 0.0)) {
            Some(node) => Err(MdpError::OptimalityUnproved(format!(
                "the potential of the certificate is {} at node {node}",
                times[node]
            ))),
            None => Ok(times),
        }
    }

    /// `y = x + eps T` where `potential` proves `F(y) <= y` and raises no
    /// value by more than the solver's tolerance.
    fn negligibly_raised(
        &self,
        mdp: &Mdp,
        maybe: &[usize],
        values: &[f64],
        potential: &[f64],
    ) -> Option<Vec<f64>> {
        let eps = self.admissible_eps(mdp, maybe, values, potential).ok()?;
        let negligible = maybe
            .iter()
            .all(|&s| eps * potential[s] <= self.reuse_slack);
        negligible.then(|| raised(values.to_vec(), maybe, eps, potential))
    }

    /// The smallest `eps` with `r_a(s) <= eps d_a(s)` for every action of
    /// the maybe states (module documentation), widened by rounding: the
    /// actions that gain (`r > 0`) need `d > 0` and ask `eps >= r / d`;
    /// those that lose need nothing of a potential that no action raises
    /// (the maximum expected moves), and ask `eps <= r / d` where a
    /// potential of one policy rises (`d < 0`). An error where no `eps`
    /// satisfies them all.
    fn admissible_eps(
        &self,
        mdp: &Mdp,
        maybe: &[usize],
        values: &[f64],
        potential: &[f64],
    ) -> Result<f64, MdpError> {
        let (mut least, mut most) = (0.0f64, f64::INFINITY);
        for &s in maybe {
            for a in 0..mdp.num_actions(s) {
                let (advantage, decrease) = self.components.widened(mdp, (s, a), values, potential);
                // A NaN would pass every comparison below unconstrained.
                if !(advantage.is_finite() && decrease.is_finite()) {
                    return Err(MdpError::OptimalityUnproved(format!(
                        "action {a} of state {s}: advantage {advantage:e}, decrease {decrease:e}"
                    )));
                }
                if advantage <= 0.0 {
                    if decrease < 0.0 {
                        most = most.min(round_down(advantage / decrease));
                    }
                    continue;
                }
                if decrease <= 0.0 {
                    return Err(MdpError::OptimalityUnproved(format!(
                        "action {a} of state {s} may gain {advantage:e} without lowering the \
                         potential (by {decrease:e})"
                    )));
                }
                least = least.max(round_up(advantage / decrease));
            }
        }
        if least <= most {
            Ok(least)
        } else {
            Err(MdpError::OptimalityUnproved(format!(
                "the actions that gain need eps >= {least:e}, those that lose eps <= {most:e}"
            )))
        }
    }
}

/// `y = x + eps T` on `maybe` (`x` the levelled `values`, `T` the
/// `potential`), rounded up and at most 1; `x` elsewhere.
fn raised(mut values: Vec<f64>, maybe: &[usize], eps: f64, potential: &[f64]) -> Vec<f64> {
    for &s in maybe {
        values[s] = round_up(values[s] + eps * potential[s]).min(1.0);
    }
    values
}

/// A solve of the potential that failed, as the certificate's failure.
fn unsolved(error: SolverError) -> MdpError {
    MdpError::OptimalityUnproved(format!("the potential of the certificate: {error}"))
}

/// [`Certificate::upper`] with a fresh analysis of `mdp`'s graph.
#[cfg(test)]
fn certified_upper(
    mdp: &Mdp,
    maybe: &[usize],
    values: &[f64],
    settings: &SolverSettings,
) -> Result<Vec<f64>, MdpError> {
    if maybe.is_empty() {
        return Ok(values.to_vec());
    }
    Certificate::new(mdp, maybe, settings)?.upper(mdp, maybe, values)
}

/// The maximal end components inside the maybe states: each state's
/// component (its own index where it is in none).
struct Components {
    of: Vec<usize>,
    members: Vec<Vec<usize>>,
}

impl Components {
    fn of(mdp: &Mdp, maybe: &[usize]) -> Self {
        let mut within = vec![false; mdp.num_states()];
        for &s in maybe {
            within[s] = true;
        }
        let mut of: Vec<usize> = (0..mdp.num_states()).collect();
        let mut members = Vec::new();
        for component in maximal_end_components(mdp, &within) {
            for &s in &component.states {
                of[s] = component.states[0];
            }
            members.push(component.states);
        }
        Self { of, members }
    }

    /// `x` raised to its maximum on each component.
    fn levelled(&self, x: &[f64]) -> Vec<f64> {
        let mut x = x.to_vec();
        for states in &self.members {
            let highest = states.iter().map(|&s| x[s]).fold(f64::MIN, f64::max);
            for &s in states {
                x[s] = highest;
            }
        }
        x
    }

    /// The advantage `r_a(s)` rounded towards `+inf` and the potential's
    /// decrease `d_a(s)` rounded towards `-inf` (moves inside `s`'s
    /// component add exactly 0 to both and are skipped).
    fn widened(&self, mdp: &Mdp, (s, a): (usize, usize), x: &[f64], t: &[f64]) -> (f64, f64) {
        let home = self.of[s];
        let (mut advantage, mut advantage_mass) = (0.0, 0.0);
        let (mut decrease, mut decrease_mass) = (0.0, 0.0);
        let mut terms = 0;
        for &(u, p) in mdp.distribution(s, a) {
            if self.of[u] == home {
                continue;
            }
            let gain = p * (x[u] - x[s]);
            advantage += gain;
            advantage_mass += gain.abs();
            let lower = p * (t[s] - t[u]);
            decrease += lower;
            decrease_mass += lower.abs();
            terms += 1;
        }
        // Each term (one difference, one product) has a relative error of
        // at most 2u + u^2; the sum of `k` terms adds `(k - 1) u` of their
        // absolute sum: `(k + 2) u` of the computed absolute sum, with room
        // for the rounding of that sum itself. A term of two equal values is
        // exactly 0 and adds nothing.
        let gamma = (terms as f64 + 3.0) * UNIT_ROUNDOFF * 1.01;
        (
            advantage + gamma * advantage_mass,
            decrease - gamma * decrease_mass,
        )
    }
}

/// The quotient of the maybe states by their maximal end components: one
/// node per component, and for each node its moves, the actions of its
/// states that leave it (a property of the graph), whose distributions over
/// the other nodes, conditioned on leaving, [`Quotient::moves`] reads from
/// an MDP of the graph (the rest leaves `maybe`).
struct Quotient {
    node_of: Vec<usize>,
    /// Per node, the `(state, action)` of each of its moves.
    sources: Vec<Vec<(usize, usize)>>,
    /// The union of every move's edges, the diagonal included.
    pattern: SparsePattern,
}

/// Per node, its moves: `(other node, conditional probability)` lists.
type Moves = Vec<Vec<Vec<(usize, f64)>>>;

impl Quotient {
    fn new(components: &Components, mdp: &Mdp, maybe: &[usize]) -> Self {
        let mut node_of = vec![usize::MAX; mdp.num_states()];
        let mut nodes = 0;
        for &s in maybe {
            let home = components.of[s];
            if node_of[home] == usize::MAX {
                node_of[home] = nodes;
                nodes += 1;
            }
            node_of[s] = node_of[home];
        }
        let mut sources = vec![Vec::new(); nodes];
        let mut rows = vec![Vec::new(); nodes];
        for &s in maybe {
            let home = node_of[s];
            for a in 0..mdp.num_actions(s) {
                let distribution = mdp.distribution(s, a);
                if distribution.iter().all(|&(u, _)| node_of[u] == home) {
                    continue;
                }
                sources[home].push((s, a));
                rows[home].extend(
                    distribution
                        .iter()
                        .map(|&(u, _)| node_of[u])
                        .filter(|&v| v != home && v != usize::MAX),
                );
            }
        }
        let mut row_offsets = vec![0];
        let mut columns = Vec::new();
        for (node, mut row) in rows.into_iter().enumerate() {
            row.push(node);
            row.sort_unstable();
            row.dedup();
            columns.extend(row);
            row_offsets.push(columns.len());
        }
        let pattern = SparsePattern {
            n: nodes,
            row_offsets,
            columns,
        };
        Self {
            node_of,
            sources,
            pattern,
        }
    }

    /// The moves' distributions over the other nodes in `mdp`, conditioned
    /// on leaving the node.
    fn moves(&self, mdp: &Mdp) -> Moves {
        self.sources
            .iter()
            .enumerate()
            .map(|(home, node_sources)| {
                node_sources
                    .iter()
                    .map(|&(s, a)| self.conditioned(mdp.distribution(s, a), home))
                    .collect()
            })
            .collect()
    }

    /// A distribution over nodes other than `home`, conditioned on leaving
    /// it, sorted by node.
    fn conditioned(&self, distribution: &[(usize, f64)], home: usize) -> Vec<(usize, f64)> {
        let leaving: f64 = distribution
            .iter()
            .filter(|&&(u, _)| self.node_of[u] != home)
            .map(|&(_, p)| p)
            .sum();
        let mut terms: Vec<(usize, f64)> = Vec::new();
        for &(u, p) in distribution {
            let node = self.node_of[u];
            if node != home && node != usize::MAX {
                match terms.iter_mut().find(|(v, _)| *v == node) {
                    Some((_, q)) => *q += p / leaving,
                    None => terms.push((node, p / leaving)),
                }
            }
        }
        terms.sort_unstable_by_key(|&(v, _)| v);
        terms
    }

    /// The values `x` (per state) per node.
    fn at_nodes(&self, x: &[f64]) -> Vec<f64> {
        let mut at_node = vec![0.0; self.sources.len()];
        for (s, &node) in self.node_of.iter().enumerate() {
            if node != usize::MAX {
                at_node[node] = x[s];
            }
        }
        at_node
    }

    /// Per node, the move whose expectation of `x` (per state) is highest.
    fn best_moves(&self, moves: &Moves, x: &[f64]) -> Vec<usize> {
        let at_node = self.at_nodes(x);
        moves
            .iter()
            .map(|node_moves| argmax(node_moves, |terms| expectation(terms, &at_node)))
            .collect()
    }

    /// The expected number of moves of the policy `choice` (one move per
    /// node) before leaving: `(I - Q) T = 1`, solved without an error
    /// bound ([`LinearSolver::solve_unbounded`]): the certificate's check
    /// holds or fails whatever the errors of `T`. An iterative solve starts
    /// from `start` (the last potential's times), else from 0.
    fn evaluate(
        &self,
        solver: &mut LinearSolver,
        moves: &Moves,
        choice: &[usize],
        start: Option<Vec<f64>>,
    ) -> Result<Vec<f64>, SolverError> {
        let pattern = &self.pattern;
        solver.factorize_with(|values, exits| {
            values.fill(0.0);
            for (node, &chosen) in choice.iter().enumerate() {
                let terms = &moves[node][chosen];
                let range = pattern.row_range(node);
                let mut staying = 0.0;
                for &(v, q) in terms {
                    let k = range.start
                        + pattern.columns[range.clone()]
                            .binary_search(&v)
                            .expect("the pattern holds every move");
                    values[k] = -q;
                    staying += q;
                }
                exits[node] = (1.0 - staying).max(0.0);
                let diagonal = range.start
                    + pattern.columns[range.clone()]
                        .binary_search(&node)
                        .expect("the pattern holds the diagonal");
                values[diagonal] = exits[node] + staying;
            }
        })?;
        let ones = vec![1.0; pattern.n];
        let mut times = start.unwrap_or_else(|| vec![0.0; pattern.n]);
        solver.solve_unbounded(&ones, &mut times)?;
        Ok(times)
    }

    /// Switches each node to a move whose `1 + E[T]` beats its current one
    /// by more than the rounding; returns whether any switched.
    fn improve(&self, moves: &Moves, potential: &[f64], choice: &mut [usize]) -> bool {
        let at_node = self.at_nodes(potential);
        let mut switched = false;
        for (node, node_moves) in moves.iter().enumerate() {
            let current = expectation(&node_moves[choice[node]], &at_node);
            let best = argmax(node_moves, |terms| expectation(terms, &at_node));
            let gain = expectation(&node_moves[best], &at_node) - current;
            if gain > 1e-9 * (1.0 + current.abs()) {
                choice[node] = best;
                switched = true;
            }
        }
        switched
    }
}

/// `sum_v q(v) x(v)` over a move's terms.
fn expectation(terms: &[(usize, f64)], x: &[f64]) -> f64 {
    terms.iter().map(|&(v, q)| q * x[v]).sum()
}

/// The index of the largest `score` (the first of equals; 0 when empty).
fn argmax<T>(items: &[T], score: impl Fn(&T) -> f64) -> usize {
    let mut best = (0, f64::NEG_INFINITY);
    for (i, item) in items.iter().enumerate() {
        let value = score(item);
        if value > best.1 {
            best = (i, value);
        }
    }
    best.0
}

/// `x` rounded up by a few units in the last place (nonnegative `x`).
fn round_up(x: f64) -> f64 {
    x + 4.0 * UNIT_ROUNDOFF * x.abs() + f64::MIN_POSITIVE
}

/// `x` rounded down by a few units in the last place (nonnegative `x`),
/// at least 0.
fn round_down(x: f64) -> f64 {
    (x - 4.0 * UNIT_ROUNDOFF * x.abs() - f64::MIN_POSITIVE).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::super::MdpBuilder;
    use super::super::tests::mdp;
    use super::*;

    /// State 0 chooses between action 0 (to the target 2 with 1/2, else
    /// the sink 3) and action 1 (stay with 0.9, else as action 0 but with
    /// 1e-7 more to the target). The optimum is `win / (win + lose)`, about
    /// 0.500001; the values of the first policy (0.5) are certified only up
    /// to a bound that covers the missing 1e-6, and the optimum's own
    /// values within rounding.
    #[test]
    fn the_certificate_covers_what_a_suboptimal_policy_misses() {
        let (win, lose) = (0.05 + 1e-7, 0.05 - 1e-7);
        let m = mdp(&[
            &[&[(2, 0.5), (3, 0.5)], &[(0, 0.9), (2, win), (3, lose)]],
            &[&[(1, 1.0)]],
            &[&[(2, 1.0)]],
            &[&[(3, 1.0)]],
        ]);
        let maybe = [0];
        let optimum = win / (win + lose);
        let first = [0.5, 0.0, 1.0, 0.0];
        let upper = certified_upper(&m, &maybe, &first, &SolverSettings::default()).unwrap();
        assert!(upper[0] >= optimum, "{upper:?}");
        assert!(upper[0] < optimum + 1e-9, "{upper:?}");
        let best = [optimum, 0.0, 1.0, 0.0];
        let upper = certified_upper(&m, &maybe, &best, &SolverSettings::default()).unwrap();
        assert!(
            upper[0] >= optimum && upper[0] < optimum + 1e-14,
            "{upper:?}"
        );
        assert_eq!(
            &upper[1..],
            &[0.0, 1.0, 0.0],
            "states outside M keep their values"
        );
    }

    /// State 0 goes to the target 2 with 1/2, else the sink 3 (action 0),
    /// or to state 1 (action 1), which goes to the target with `q`.
    fn longer_route(q: f64) -> Mdp {
        mdp(&[
            &[&[(2, 0.5), (3, 0.5)], &[(1, 1.0)]],
            &[&[(2, q), (3, 1.0 - q)]],
            &[&[(2, 1.0)]],
            &[&[(3, 1.0)]],
        ])
    }

    /// A gain along a longer route: state 0 goes to the target with 1/2
    /// (action 0, the policy's) or to state 1 (action 1), which goes there
    /// with 0.6. The policy's times do not fall along action 1, the
    /// potential (2 and 1) does; the certificate covers the missing 0.1
    /// (`eps = 0.1`: 0.7 for both).
    #[test]
    fn a_gain_along_a_longer_route_is_covered() {
        let upper = certified_upper(
            &longer_route(0.6),
            &[0, 1],
            &[0.5, 0.6, 1.0, 0.0],
            &SolverSettings::default(),
        )
        .unwrap();
        for y in &upper[..2] {
            assert!((0.7..0.7 + 1e-12).contains(y), "{upper:?}");
        }
    }

    /// One certificate serves MDPs of one graph in turn (the longer-route
    /// graph above, state 1 reaching the target with `q`), reusing its last
    /// potential: from the optimal values `(q, q)`, from values 3e-10 short
    /// of them at state 0 (a gain the reused potential must cover, with
    /// `eps > 0`) and from the first policy's `(1/2, q)`, every upper bound
    /// covers the optimum `max(1/2, q)` and is within the tolerance of a
    /// fresh certificate's; the near-optimal values reuse the potential
    /// without a solve.
    #[test]
    fn one_certificate_serves_every_mdp_of_its_graph() {
        let settings = SolverSettings::default();
        let maybe = [0, 1];
        let mut reused = Certificate::new(&longer_route(0.6), &maybe, &settings).unwrap();
        for q in [0.6, 0.55, 0.7, 0.52, 0.9, 0.6] {
            let m = longer_route(q);
            for values in [
                [q, q, 1.0, 0.0],
                [q - 3e-10, q, 1.0, 0.0],
                [0.5, q, 1.0, 0.0],
            ] {
                let solves = reused.solves;
                let upper = reused.upper(&m, &maybe, &values).unwrap();
                let fresh = certified_upper(&m, &maybe, &values, &settings).unwrap();
                for s in 0..2 {
                    assert!(upper[s] >= q, "q {q}, values {values:?}: {upper:?}");
                    assert!(
                        upper[s] <= fresh[s] + settings.tolerance,
                        "q {q}, values {values:?}: {upper:?} against {fresh:?}"
                    );
                }
                if values[0] > 0.5 && solves > 0 {
                    assert_eq!(reused.solves, solves, "q {q}, values {values:?}");
                }
            }
        }
    }

    /// Where state 1's return to state 0 (probability `a`) changes, so does
    /// the potential: from values 3e-11 short of the optimum 0.8 at state
    /// 1, the potential of `a = 0.5` no longer proves the bound for
    /// `a = 0.9`, and its policy's potential on the new numbers does (one
    /// solve); the bound covers the optimum.
    #[test]
    fn a_potential_that_no_longer_proves_gives_way_to_its_policy_on_the_new_numbers() {
        let returning = |a: f64| {
            mdp(&[
                &[&[(2, 0.5), (3, 0.5)], &[(1, 1.0)]],
                &[&[(0, a), (2, 0.8 * (1.0 - a)), (3, 0.2 * (1.0 - a))]],
                &[&[(2, 1.0)]],
                &[&[(3, 1.0)]],
            ])
        };
        let settings = SolverSettings::default();
        let maybe = [0, 1];
        let values = [0.8, 0.8 - 3e-11, 1.0, 0.0];
        let mut reused = Certificate::new(&returning(0.5), &maybe, &settings).unwrap();
        let first = reused.upper(&returning(0.5), &maybe, &values).unwrap();
        let solves = reused.solves;
        let stale = reused.last_potential.clone().unwrap();
        let m = returning(0.9);
        assert!(reused.admissible_eps(&m, &maybe, &values, &stale).is_err());
        let upper = reused.upper(&m, &maybe, &values).unwrap();
        assert_eq!(reused.solves, solves + 1);
        for y in first[..2].iter().chain(&upper[..2]) {
            assert!((0.8..0.8 + 1e-9).contains(y), "{first:?} {upper:?}");
        }
    }

    /// A potential that is not finite proves nothing: a NaN would pass
    /// every comparison of the check (state 1's gain of 0.1 against a NaN
    /// decrease).
    #[test]
    fn a_potential_that_is_not_finite_proves_nothing() {
        let m = longer_route(0.6);
        let maybe = [0, 1];
        let certificate = Certificate::new(&m, &maybe, &SolverSettings::default()).unwrap();
        let values = [0.5, 0.6, 1.0, 0.0];
        for potential in [[1.0, f64::NAN, 0.0, 0.0], [f64::INFINITY, 1.0, 0.0, 0.0]] {
            assert!(
                certificate
                    .admissible_eps(&m, &maybe, &values, &potential)
                    .is_err(),
                "{potential:?}"
            );
        }
    }

    /// Moves inside an end component need no `eps`, whatever the policy's
    /// times there: states 0 and 1 swap surely (action 0) or leave to the
    /// target with 1/2 (action 1).
    #[test]
    fn moves_inside_an_end_component_need_no_eps() {
        let m = mdp(&[
            &[&[(1, 1.0)], &[(2, 0.5), (3, 0.5)]],
            &[&[(0, 1.0)], &[(2, 0.5), (3, 0.5)]],
            &[&[(2, 1.0)]],
            &[&[(3, 1.0)]],
        ]);
        let upper = certified_upper(
            &m,
            &[0, 1],
            &[0.5, 0.5, 1.0, 0.0],
            &SolverSettings::default(),
        )
        .unwrap();
        assert!(
            upper[..2].iter().all(|&y| (0.5..0.5 + 1e-15).contains(&y)),
            "{upper:?}"
        );
    }

    /// A walk on 6,000 states that moves up, down, jumps far (0.19) or
    /// dies (0.01), the top reaching the target, with a gamble (0.3) beside
    /// it in every state: a quotient above [`KRYLOV_FIRST_UNKNOWNS`]. Under
    /// `auto` its potentials are solved by BiCGSTAB (for two MDPs of the
    /// graph, the second from the first's potential), and by LU where
    /// BiCGSTAB fails (forced here by allowing it one iteration); either
    /// proves the bounds a fresh LU certificate proves.
    #[test]
    fn a_large_quotient_solves_its_potentials_by_bicgstab_and_by_lu_where_that_fails() {
        let n = 6_000;
        let walk = |up: f64| {
            let mut builder = MdpBuilder::new();
            for i in 0..n {
                let down = if i == 0 { n + 1 } else { i - 1 };
                let jump = i * 7_919 % n;
                let moves = [(i + 1, up), (down, 0.8 - up), (jump, 0.19), (n + 1, 0.01)];
                builder.add_action(moves);
                builder.add_action([(n, 0.3), (n + 1, 0.7)]);
                builder.end_state();
            }
            for absorbing in [n, n + 1] {
                builder.add_action([(absorbing, 1.0)]);
                builder.end_state();
            }
            builder.build().unwrap()
        };
        let walks = [walk(0.5), walk(0.45)];
        let mut target = vec![false; n + 2];
        target[n] = true;
        let lu = SolverSettings {
            method: SolverMethod::Lu,
            ..SolverSettings::default()
        };
        let values: Vec<Vec<f64>> = walks
            .iter()
            .map(|m| {
                super::super::max_reachability(m, &target, &lu)
                    .unwrap()
                    .values
            })
            .collect();
        let maybe: Vec<usize> = (0..n).collect();
        let fresh: Vec<Vec<f64>> = walks
            .iter()
            .zip(&values)
            .map(|(m, x)| certified_upper(m, &maybe, x, &lu).unwrap())
            .collect();
        let stalled = SolverSettings {
            max_iterations: 1,
            ..SolverSettings::default()
        };
        for (settings, falls_back) in [(SolverSettings::default(), false), (stalled, true)] {
            let mut certificate = Certificate::new(&walks[0], &maybe, &settings).unwrap();
            for ((m, x), by_lu) in walks.iter().zip(&values).zip(&fresh) {
                let upper = certificate.upper(m, &maybe, x).unwrap();
                for s in 0..n {
                    assert!(upper[s] >= x[s], "state {s}: {} < {}", upper[s], x[s]);
                    let (y, z) = (upper[s], by_lu[s]);
                    assert!((y - z).abs() < 1e-9, "state {s}: {y} against {z}");
                }
            }
            let method = certificate.solver.method();
            assert_eq!(certificate.fallback.is_none(), falls_back);
            let expected = if falls_back {
                SolverMethod::Lu
            } else {
                SolverMethod::Krylov
            };
            assert_eq!(method, expected);
        }
    }

    /// States 0 and 1 swap and leave with probabilities of 1e-25: no
    /// potential fits in double precision, so the certificate refuses.
    #[test]
    fn a_chain_that_leaves_below_the_precision_is_refused() {
        let m = mdp(&[
            &[&[(1, 0.3), (2, 1e-25), (0, 0.7)], &[(2, 0.6), (3, 0.4)]],
            &[&[(0, 0.3), (3, 2e-25), (1, 0.7)]],
            &[&[(2, 1.0)]],
            &[&[(3, 1.0)]],
        ]);
        let error = certified_upper(
            &m,
            &[0, 1],
            &[0.6, 0.6, 1.0, 0.0],
            &SolverSettings::default(),
        )
        .unwrap_err();
        assert!(matches!(error, MdpError::OptimalityUnproved(_)), "{error}");
    }
}
