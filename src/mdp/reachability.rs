//! Maximum reachability probabilities, exactly, by policy iteration.
//!
//! For a target set `B`, `x*(s) = sup_sigma P^sigma_s(reach B)`. It is the
//! *least* fixed point in `[0, 1]^S` of the Bellman operator
//! `(F x)(s) = 1` on `B`, `max_a sum_t P(t | s, a) x(t)` elsewhere (Baier and
//! Katoen, Section 10.6), and memoryless deterministic strategies attain it.
//!
//! The algorithm:
//!
//! 1. **Qualitative step.** `S_0`, the states that cannot reach `B` in the
//!    graph of all actions, have `x* = 0` under every strategy; `S_1`, the
//!    states from which some strategy reaches `B` almost surely (Baier and
//!    Katoen, Section 10.6), have `x* = 1` exactly. The rest,
//!    `M = S \ (S_1 u S_0)`, are the "maybe" states; below, `B` stands for
//!    `S_1` (which contains it).
//! 2. **Proper start.** A backward search from `B` gives every state of `M`
//!    an action with an edge to a state found earlier, so under this policy
//!    every state of `M` reaches `B` with positive probability: the chain
//!    restricted to `M` is transient and `I - Q` is nonsingular, even when
//!    `M` contains end components (where an arbitrary policy could stay
//!    forever and make the system singular). A cold start usually improves
//!    on it first ([`PolicySystems::greedy_start`]): greedy for a few
//!    sweeps of value iteration, with the proper actions back wherever
//!    that greedy policy would no longer reach `B`. On PAYNT's dodge-8
//!    with a uniform 3-node defender (23,814 maybe states) policy
//!    iteration then took 1.3 s instead of 13 s: the proper start mixes so
//!    slowly that BiCGSTAB stalls on it, and each of its 8 evaluations
//!    fell to a sparse LU.
//! 3. **Evaluation.** `(I - Q_sigma) x = b_sigma` on `M`, with `Q_sigma =
//!    P_sigma` restricted to `M x M` and `b_sigma(s) = P_sigma(B | s)`, by
//!    sparse LU or BiCGSTAB warm-started from the previous policy's values,
//!    as [`crate::solver::LinearSolver`] chooses (with `auto`: LU unless
//!    its analysis predicts a costly factorisation, where a short BiCGSTAB
//!    trial decides, and BiCGSTAB above [`crate::solver::DEFAULT_LU_LIMIT`]
//!    unknowns; residual checked, error bounded).
//!    The policies passed through are evaluated in double precision and
//!    their bound may exceed the tolerance (it raises the improvement
//!    threshold of step 4); the policy whose values are returned must meet
//!    it, in rationals where double precision cannot prove it
//!    ([`crate::solver::exact`]), so a trial evaluation that would end the
//!    loop unproved is repeated with proof before the loop ends.
//!    The diagonal of `I - Q_sigma` is the probability of leaving `s`,
//!    `sum_{t != s} P_sigma(t | s)`, never `1 - P_sigma(s | s)` (method.md
//!    section 8): a lazy action keeps every digit.
//! 4. **Improvement.** In each state of `M` switch to an action with the
//!    largest *self-loop-free* expectation `E'_a x = sum_{t != s} P(t | s, a)
//!    x(t) / sum_{t != s} P(t | s, a)` (the expectation on leaving `s`; an
//!    action that never leaves `s` scores 0) only if it beats the current
//!    action's by more than the threshold, the larger of
//!    [`IMPROVEMENT_THRESHOLD`] and four times the evaluation's error bound;
//!    keep the current action on ties. Removing self-loops and renormalising
//!    changes neither the reachability probabilities nor the optimal
//!    strategies, and `E'_a x - x(s)` has the sign of `E_a x - x(s)` without
//!    losing the digits of a lazy action to the `P(s | s)` near 1.
//!    The new policy is again proper: a closed class `C` inside `M` under the
//!    new policy with no switched state would be closed under the old one,
//!    which is proper; with a switched state, its stationary distribution
//!    `pi > 0` would give `pi P x > pi x = pi P x`. Values never decrease and
//!    strictly increase somewhere, so no policy repeats and the loop ends.
//!
//! **What the result proves.** The final `x` is the value of a policy, so
//! `x <= x*` (within its error bound). It is a fixed point of `F` only up
//! to the improvement threshold per state, and that gap adds up over the
//! expected number of steps (2.2e-8 from a per-state 6.5e-12 over 33,000
//! steps on a 6x6 grid), so `x >= x*` is not implied: the optimality
//! certificate (`src/mdp/optimality.rs`) proves `x* <= upper` in floating
//! point, and `upper` is what a reported bound uses. The proper start keeps
//! every evaluation nonsingular.

use crate::graph::backward_reachable;
use crate::solver::{LinearSolver, SolverSettings, SparsePattern};

use super::optimality::Certificate;
use super::pattern::{Slot, union_pattern};
use super::{Mdp, MdpError, Predecessors};

/// Policy iteration switches an action only if it improves the expected
/// value by more than this (values are probabilities in `[0, 1]`).
pub const IMPROVEMENT_THRESHOLD: f64 = 1e-12;

/// The most Gauss-Seidel sweeps of value iteration that
/// [`PolicySystems::greedy_start`] runs before policy iteration. Measured
/// (one run each, 2 cores): on PAYNT's dodge-8 with a uniform 3-node
/// defender, one lower bound took 13 s from the proper start, 1.4 s after
/// 0 sweeps (the greedy step alone), 1.3 s after 10 and 1.1 s after 100;
/// but 100 sweeps made `solve` on PAYNT's attacker-one-defender and
/// grid-walls (many small products, whose policy iteration is cheap) 20-30%
/// slower, and 10 sweeps cost nothing there.
pub const START_SWEEPS: usize = 10;

/// Policy iteration gives up (as a numerical failure) after this many
/// evaluations; in exact arithmetic it stops after finitely many.
pub const MAX_ITERATIONS: usize = 10_000;

/// Maximum reachability probabilities and a strategy attaining them.
#[derive(Debug, Clone, PartialEq)]
pub struct Reachability {
    /// The reachability probabilities of `strategy` (within `error_bound`),
    /// at most the optimum `x*(s) = sup_sigma P^sigma_s(reach B)` and at
    /// least `x*` less the policy iteration's optimality gap, which `upper`
    /// bounds.
    pub values: Vec<f64>,
    /// Proved upper bounds on the optimum: `x*(s) <= upper(s)` for every
    /// state (the optimality certificate, `src/mdp/optimality.rs`).
    pub upper: Vec<f64>,
    /// An optimal memoryless deterministic strategy: the local action in each
    /// state. In `B` and in states that cannot reach `B` it is action 0
    /// (every action is optimal there); in the other states of value 1 it
    /// reaches `B` almost surely.
    pub strategy: Vec<usize>,
    /// The larger of the final linear solve's residual
    /// `max_s |((I - Q) x - b)(s)|` and the self-loop-free Bellman gap
    /// `max_s (max_a E'_a x - E'_sigma(s) x)` (below the improvement
    /// threshold at the end).
    pub residual: f64,
    /// A bound on `|values(s) - x_sigma(s)|` for every `s`, `x_sigma` the
    /// exact reachability probabilities of `strategy` (method.md section 8).
    pub error_bound: f64,
    /// The number of policy evaluations.
    pub iterations: usize,
    /// `x*(s) > 0` exactly: `s` can reach the target in the graph of all
    /// actions (decided on the graph, not on the computed `values`).
    pub possible: Vec<bool>,
    /// `x*(s) = 1` exactly: some strategy reaches the target from `s`
    /// almost surely (decided on the graph).
    pub almost_sure: Vec<bool>,
}

/// `sup_sigma P^sigma(reach target)` from every state of `mdp`, with an
/// optimal memoryless deterministic strategy (see the module documentation).
/// Its policy evaluations are solved by `settings` (method.md section 8).
pub fn max_reachability(
    mdp: &Mdp,
    target: &[bool],
    settings: &SolverSettings,
) -> Result<Reachability, MdpError> {
    let qualitative = qualitative_reachability(mdp, target)?;
    let mut systems = PolicySystems::new(mdp, qualitative, settings)?;
    let start = systems.greedy_start(mdp);
    max_reachability_with(mdp, &start, &mut systems)
}

/// [`max_reachability`] on `systems`, built by [`PolicySystems::new`] for
/// an MDP with the same graph ([`Mdp::same_graph`]) with its qualitative
/// step (steps 1 and 2, which depend on the graph alone), so that MDPs of
/// one graph (a controller's products as its probabilities change) share
/// the graph analysis and one symbolic analysis; policy iteration starts
/// from `start` on the maybe states: the qualitative strategy, its
/// [`PolicySystems::greedy_start`], or the strategy of an earlier result
/// on the same graph. Each is proper
/// (every maybe state reaches the target with positive probability under
/// it, a property of the graph), so every evaluation stays nonsingular. On
/// return the systems hold the factorisation of the returned strategy.
pub fn max_reachability_with(
    mdp: &Mdp,
    start: &[usize],
    systems: &mut PolicySystems,
) -> Result<Reachability, MdpError> {
    let n = mdp.num_states();
    if start.len() != n || !systems.fits(mdp) {
        return Err(MdpError::Malformed(format!(
            "a start strategy of {} states, or policy systems of another graph, for an MDP of {n}",
            start.len()
        )));
    }
    let qualitative = &systems.qualitative;
    let positive = qualitative.possible.clone();
    let almost_sure = qualitative.almost_sure.clone();
    let mut strategy = qualitative.strategy.clone();
    for &s in &systems.maybe {
        strategy[s] = start[s];
    }
    let mut previous: Vec<f64> = almost_sure.iter().map(|&t| f64::from(t)).collect();
    let mut proof = Proof::Trial;
    for iterations in 1..=MAX_ITERATIONS {
        let (values, report) = evaluate(mdp, systems, &almost_sure, &strategy, &previous, proof)?;
        let proved = report.error_bound <= systems.settings.tolerance;
        let threshold = if proved {
            IMPROVEMENT_THRESHOLD.max(4.0 * report.error_bound)
        } else {
            IMPROVEMENT_THRESHOLD
        };
        let (switched, gap) = improve(mdp, &values, &systems.maybe, &mut strategy, threshold);
        if !switched && proved {
            let upper = systems.certified_upper(mdp, &values)?;
            return Ok(Reachability {
                values,
                upper,
                strategy,
                residual: report.residual.max(gap),
                error_bound: report.error_bound,
                iterations,
                possible: positive,
                almost_sure,
            });
        }
        // A switch is tried without proof; an unproved end is repeated
        // with proof.
        proof = if switched {
            Proof::Trial
        } else {
            Proof::Required
        };
        previous = values;
    }
    Err(MdpError::NotConverged(MAX_ITERATIONS))
}

/// How a policy evaluation's error bound is treated (module documentation,
/// step 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Proof {
    /// A policy passed through: double precision only, and a bound above
    /// the tolerance is accepted (it only raises the improvement threshold).
    Trial,
    /// The policy whose values are returned: the bound must meet the
    /// tolerance, in rationals if double precision cannot prove it.
    Required,
}

/// The qualitative step alone (module documentation, steps 1 and 2): which
/// states reach the target with positive probability and which almost
/// surely, by graph search only, with a strategy that stays in the
/// almost-sure region and reaches the target from there with probability
/// 1 (elsewhere: the proper start of step 2). Needs no linear solve, so it
/// answers even where the quantitative systems are too ill-conditioned.
#[derive(Debug, Clone, PartialEq)]
pub struct QualitativeReachability {
    /// Whether some strategy reaches the target with positive probability.
    pub possible: Vec<bool>,
    /// Whether some strategy reaches the target with probability 1.
    pub almost_sure: Vec<bool>,
    /// The strategy described above.
    pub strategy: Vec<usize>,
}

/// [`QualitativeReachability`] of `target`.
pub fn qualitative_reachability(
    mdp: &Mdp,
    target: &[bool],
) -> Result<QualitativeReachability, MdpError> {
    let n = mdp.num_states();
    if target.len() != n {
        return Err(MdpError::Malformed(format!(
            "target set of size {} for {n} states",
            target.len()
        )));
    }
    let predecessors = mdp.predecessors();
    let possible = backward_reachable(&predecessors, target);
    let (almost_sure, sure_strategy) = almost_surely(mdp, &predecessors, target, &possible);
    let mut strategy = attractor(n, &predecessors, &almost_sure);
    for s in (0..n).filter(|&s| almost_sure[s]) {
        strategy[s] = sure_strategy[s];
    }
    Ok(QualitativeReachability {
        possible,
        almost_sure,
        strategy,
    })
}

/// `S_1`, the states from which some strategy reaches `target` almost
/// surely, and such a strategy on them (Baier and Katoen, Section 10.6,
/// "Prob1E"): starting from `U` = `positive`, keep the states that reach
/// `target` using only actions whose successors all lie in `U`, until `U`
/// is stable. On the result, each state outside `target` plays an action
/// that stays in `U` and leads one step closer to `target` in that search,
/// so it never leaves `U` and reaches `target` with probability 1.
fn almost_surely(
    mdp: &Mdp,
    predecessors: &Predecessors,
    target: &[bool],
    positive: &[bool],
) -> (Vec<bool>, Vec<usize>) {
    let n = mdp.num_states();
    let mut within = positive.to_vec();
    let mut strategy = vec![0; n];
    // Whether each (global) action keeps every successor in `U`; as `U`
    // only shrinks, an action that leaves it is found once, from the
    // predecessors of the states that leave it.
    let mut stays: Vec<bool> = (0..mdp.num_state_actions())
        .map(|action| {
            let successors = mdp.global_distribution(action);
            successors.iter().all(|&(u, _)| within[u])
        })
        .collect();
    loop {
        let mut found = target.to_vec();
        let mut frontier: Vec<usize> = (0..n).filter(|&s| target[s]).collect();
        while let Some(t) = frontier.pop() {
            for &(s, a) in predecessors.of(t) {
                if within[s] && !found[s] && stays[mdp.action_offsets[s] + a] {
                    found[s] = true;
                    strategy[s] = a;
                    frontier.push(s);
                }
            }
        }
        if found == within {
            return (within, strategy);
        }
        for u in (0..n).filter(|&u| within[u] && !found[u]) {
            for &(s, a) in predecessors.of(u) {
                stays[mdp.action_offsets[s] + a] = false;
            }
        }
        within = found;
    }
}

/// A policy that gives each state able to reach `target` an action with an
/// edge to a state closer to `target` (backward search); action 0 elsewhere.
fn attractor(n: usize, predecessors: &Predecessors, target: &[bool]) -> Vec<usize> {
    let mut strategy = vec![0; n];
    let mut found = target.to_vec();
    let mut frontier: Vec<usize> = (0..n).filter(|&s| target[s]).collect();
    while let Some(t) = frontier.pop() {
        for &(s, a) in predecessors.of(t) {
            if !found[s] {
                found[s] = true;
                strategy[s] = a;
                frontier.push(s);
            }
        }
    }
    strategy
}

/// The residual and error bound of a policy evaluation.
#[derive(Debug, Clone, Copy)]
struct EvaluationReport {
    residual: f64,
    error_bound: f64,
}

/// The reachability probabilities of the policy: 1 on `target`, the solution
/// of `(I - Q) x = b` on the maybe states (diagonal: the probability of
/// leaving the state), 0 elsewhere; and the solve's residual and error
/// bound. An iterative solver starts from `start` (the previous policy's
/// values).
fn evaluate(
    mdp: &Mdp,
    systems: &mut PolicySystems,
    target: &[bool],
    strategy: &[usize],
    start: &[f64],
    proof: Proof,
) -> Result<(Vec<f64>, EvaluationReport), MdpError> {
    let mut values: Vec<f64> = target.iter().map(|&t| f64::from(t)).collect();
    if systems.maybe.is_empty() {
        let exact = EvaluationReport {
            residual: 0.0,
            error_bound: 0.0,
        };
        return Ok((values, exact));
    }
    let rhs = systems.factorise(mdp, strategy)?;
    let maybe = &systems.maybe;
    let mut solution: Vec<f64> = maybe.iter().map(|&s| start[s]).collect();
    let solver = systems.solver()?;
    let report = match proof {
        Proof::Trial => solver.solve_trial(&rhs, &mut solution)?,
        Proof::Required => solver.solve(&rhs, &mut solution)?,
    };
    for (&s, &x) in systems.maybe.iter().zip(&solution) {
        values[s] = x;
    }
    let report = EvaluationReport {
        residual: report.residual,
        error_bound: report.error_bound.unwrap_or(f64::INFINITY),
    };
    Ok((values, report))
}

/// The linear systems `(I - Q_sigma) x = b_sigma` of every policy `sigma`
/// on the maybe states `M` of one graph (module documentation, step 3),
/// sharing one sparsity pattern: the union of the edges inside `M` of every
/// action, the diagonal included. The solver's symbolic analysis (fill-
/// reducing ordering, elimination structure, choice of method) is done
/// once, at the first factorisation; each policy then refactorises its
/// numbers only, with structural zeros where its action has no edge. Valid
/// for every MDP with the graph and the qualitative step it was built for
/// ([`Mdp::same_graph`]).
pub struct PolicySystems {
    /// `M`, in the order of the unknowns.
    maybe: Vec<usize>,
    /// Where the probability of each entry of the MDP's distributions goes
    /// (indexed like its entries; entries of states outside `M` are unused).
    slots: Vec<Slot>,
    /// The MDP the systems were built for (its graph is what they fit).
    graph: Mdp,
    /// Its qualitative step (steps 1 and 2).
    qualitative: QualitativeReachability,
    pattern: Option<SparsePattern>,
    solver: Option<LinearSolver>,
    /// The optimality certificate's analysis of the graph (at the first
    /// result).
    certificate: Option<Certificate>,
    settings: SolverSettings,
}

impl PolicySystems {
    /// The systems of `mdp`'s policies on the maybe states of
    /// `qualitative`, `mdp`'s qualitative step (neither 0 nor 1 by the
    /// graph), solved by `settings`.
    pub fn new(
        mdp: &Mdp,
        qualitative: QualitativeReachability,
        settings: &SolverSettings,
    ) -> Result<Self, MdpError> {
        let n = mdp.num_states();
        if qualitative.possible.len() != n || qualitative.almost_sure.len() != n {
            return Err(MdpError::Malformed(format!(
                "a qualitative analysis of {} states for {n}",
                qualitative.possible.len()
            )));
        }
        let maybe: Vec<usize> = (0..n)
            .filter(|&s| qualitative.possible[s] && !qualitative.almost_sure[s])
            .collect();
        let mut index = vec![usize::MAX; n];
        for (i, &s) in maybe.iter().enumerate() {
            index[s] = i;
        }
        let (pattern, slots) =
            union_pattern(mdp, (&maybe, &index), &qualitative.almost_sure, |_| true);
        Ok(Self {
            maybe,
            slots,
            graph: mdp.clone(),
            qualitative,
            pattern: Some(pattern),
            solver: None,
            certificate: None,
            settings: *settings,
        })
    }

    /// Whether these systems were built for `mdp`'s graph
    /// ([`Mdp::same_graph`]).
    pub fn fits(&self, mdp: &Mdp) -> bool {
        self.graph.same_graph(mdp)
    }

    /// The optimality certificate's upper bounds from `values`, a policy's
    /// on `mdp` (of this graph), analysing the graph at the first call;
    /// `values` themselves where the settings do not ask for the proof
    /// ([`SolverSettings::prove_optimum`]).
    fn certified_upper(&mut self, mdp: &Mdp, values: &[f64]) -> Result<Vec<f64>, MdpError> {
        if self.maybe.is_empty() || !self.settings.prove_optimum {
            return Ok(values.to_vec());
        }
        let certificate = match &mut self.certificate {
            Some(certificate) => certificate,
            empty => empty.insert(Certificate::new(mdp, &self.maybe, &self.settings)?),
        };
        certificate.upper(mdp, &self.maybe, values)
    }

    /// A proper strategy for policy iteration to start from, usually
    /// better than the qualitative step's (module documentation, step 2):
    /// greedy for the values of at most [`START_SWEEPS`] Gauss-Seidel
    /// sweeps of value iteration from below, then, in every maybe state
    /// from which that policy no longer reaches the almost-sure set, the
    /// proper start's action again. The repaired policy is proper, by
    /// induction on the order in which the qualitative step's backward
    /// search found the states: a reverted state's action has an edge of
    /// positive probability to a state found earlier, which either reached
    /// the set under the greedy policy (along states that all reach it, so
    /// all kept their actions) or was reverted too. Where the proper start
    /// makes the chain mix slowly, this saves most of the policy
    /// evaluations.
    pub fn greedy_start(&self, mdp: &Mdp) -> Vec<usize> {
        let mut values: Vec<f64> = self
            .qualitative
            .almost_sure
            .iter()
            .map(|&t| f64::from(t))
            .collect();
        for _ in 0..START_SWEEPS {
            let mut change: f64 = 0.0;
            for &s in &self.maybe {
                let best = (0..mdp.num_actions(s))
                    .map(|a| leaving_expectation(mdp, s, a, &values))
                    .fold(0.0, f64::max);
                change = change.max(best - values[s]);
                values[s] = best;
            }
            if change <= IMPROVEMENT_THRESHOLD {
                break;
            }
        }
        let mut strategy = self.qualitative.strategy.clone();
        let threshold = IMPROVEMENT_THRESHOLD;
        let (switched, _) = improve(mdp, &values, &self.maybe, &mut strategy, threshold);
        if switched {
            self.restore_proper(mdp, &mut strategy);
        }
        strategy
    }

    /// Gives every maybe state from which `strategy` does not reach the
    /// almost-sure set the proper start's action back (see
    /// [`Self::greedy_start`]): a backward search from the set along the
    /// edges of `strategy`.
    fn restore_proper(&self, mdp: &Mdp, strategy: &mut [usize]) {
        let QualitativeReachability {
            possible,
            almost_sure,
            strategy: proper,
        } = &self.qualitative;
        let predecessors = mdp.predecessors();
        let mut reaches = almost_sure.clone();
        let mut frontier: Vec<usize> = (0..reaches.len()).filter(|&t| reaches[t]).collect();
        while let Some(t) = frontier.pop() {
            for &(s, a) in predecessors.of(t) {
                if possible[s] && !reaches[s] && a == strategy[s] {
                    reaches[s] = true;
                    frontier.push(s);
                }
            }
        }
        for &s in self.maybe.iter().filter(|&&s| !reaches[s]) {
            strategy[s] = proper[s];
        }
    }

    /// The solver, once a system was factorised.
    fn solver(&mut self) -> Result<&mut LinearSolver, MdpError> {
        self.solver.as_mut().ok_or(MdpError::Malformed(
            "no policy system was factorised".into(),
        ))
    }

    /// Factorises the system of `strategy` (its actions on `M`, read with
    /// `mdp`'s probabilities); returns `b_sigma`.
    fn factorise(&mut self, mdp: &Mdp, strategy: &[usize]) -> Result<Vec<f64>, MdpError> {
        if let Some(&s) = self
            .maybe
            .iter()
            .find(|&&s| strategy[s] >= mdp.num_actions(s))
        {
            return Err(MdpError::Malformed(format!(
                "action {} of state {s}, which has {}",
                strategy[s],
                mdp.num_actions(s)
            )));
        }
        if let Some(pattern) = self.pattern.take() {
            self.solver = Some(LinearSolver::new(pattern, &self.settings)?);
        }
        let Self {
            maybe,
            slots,
            solver,
            ..
        } = self;
        let solver = solver.as_mut().ok_or(MdpError::Malformed(
            "the policy systems lost their solver".into(),
        ))?;
        let mut rhs = vec![0.0; maybe.len()];
        solver.factorize_with(|values, exits| {
            values.fill(0.0);
            exits.fill(0.0);
            for (i, &s) in maybe.iter().enumerate() {
                let action = mdp.action_offsets[s] + strategy[s];
                let entries = mdp.entry_offsets[action]..mdp.entry_offsets[action + 1];
                for (slot, &(_, p)) in slots[entries.clone()].iter().zip(&mdp.entries[entries]) {
                    match *slot {
                        Slot::Inside(k) => values[k] = -p,
                        Slot::Leaving { target } => {
                            exits[i] += p;
                            if target {
                                rhs[i] += p;
                            }
                        }
                        Slot::Unused => {}
                    }
                }
            }
        })?;
        Ok(rhs)
    }

    /// The expected number of visits `y(s)` to each state of `M` before
    /// the chain of the strategy last returned by [`max_reachability_with`]
    /// on these systems, started from `initial`, leaves `M`: the solution of
    /// `(I - Q_sigma)^T y = p0` on `M`, 0 elsewhere, with the factorisation
    /// of `sigma` the systems hold (the last policy evaluated is the one
    /// returned). These are the adjoint weights of the policy's
    /// reachability value `sum_s p0(s) x(s)`: its derivative along a change
    /// `dP` of the transition probabilities of the policy's actions is
    /// `sum_{s in M} y(s) sum_t dP(t | s) x(t)` (method.md section 6, "the
    /// lower bound's gradient"). Solved in double precision without an
    /// error bound: it is a search direction, never a reported number.
    pub fn expected_visits(&mut self, initial: &[(usize, f64)]) -> Result<Vec<f64>, MdpError> {
        let mut visits = vec![0.0; self.graph.num_states()];
        if self.maybe.is_empty() {
            return Ok(visits);
        }
        let mut start = vec![0.0; self.maybe.len()];
        for &(s, p) in initial {
            if let Ok(i) = self.maybe.binary_search(&s) {
                start[i] += p;
            }
        }
        let mut solution = vec![0.0; self.maybe.len()];
        self.solver()?.solve_transpose(&start, &mut solution)?;
        for (&s, &y) in self.maybe.iter().zip(&solution) {
            visits[s] = y;
        }
        Ok(visits)
    }
}

/// `E'_a x = sum_{t != s} P(t | s, a) x(t) / sum_{t != s} P(t | s, a)`,
/// the expectation of `x` on leaving `s` by action `a`; 0 for an action
/// that never leaves `s` (it never reaches the target).
fn leaving_expectation(mdp: &Mdp, s: usize, a: usize, x: &[f64]) -> f64 {
    let (mut leaving, mut expectation) = (0.0, 0.0);
    for &(t, p) in mdp.distribution(s, a).iter().filter(|&&(t, _)| t != s) {
        leaving += p;
        expectation += p * x[t];
    }
    if leaving > 0.0 {
        expectation / leaving
    } else {
        0.0
    }
}

/// One greedy improvement step on `maybe` (see the module documentation),
/// switching only for gains above `threshold`. Returns whether some action
/// was switched and the self-loop-free Bellman gap
/// `max_s (max_a E'_a x - E'_sigma(s) x)` before switching.
fn improve(
    mdp: &Mdp,
    values: &[f64],
    maybe: &[usize],
    strategy: &mut [usize],
    threshold: f64,
) -> (bool, f64) {
    let mut switched = false;
    let mut gap: f64 = 0.0;
    for &s in maybe {
        let current = leaving_expectation(mdp, s, strategy[s], values);
        let (best_action, best) = (0..mdp.num_actions(s))
            .map(|a| (a, leaving_expectation(mdp, s, a, values)))
            .fold((strategy[s], current), |best, candidate| {
                if candidate.1 > best.1 {
                    candidate
                } else {
                    best
                }
            });
        gap = gap.max(best - current);
        if best > current + threshold {
            strategy[s] = best_action;
            switched = true;
        }
    }
    (switched, gap)
}

#[cfg(test)]
mod tests {
    use super::super::MdpBuilder;
    use super::super::tests::mdp;
    use super::*;
    use proptest::prelude::*;

    /// Target 3, sink 4. State 0 may stay forever (action 0) or gamble
    /// (action 1: 1 or 4, half each); 1 and 2 form an end component through
    /// their actions 1. On paper: x2 = max(0.6, x1), x1 = max(0.3 + 0.7 x0,
    /// x2), x0 = max(x0, 0.5 x1); the least solution is x1 = x2 = 0.6 (1 goes
    /// to 2, which tries for 3), x0 = 0.3, and 0.3 + 0.7 * 0.3 = 0.51 < 0.6.
    fn gamble() -> Mdp {
        mdp(&[
            &[&[(0, 1.0)], &[(1, 0.5), (4, 0.5)]],
            &[&[(3, 0.3), (0, 0.7)], &[(2, 1.0)]],
            &[&[(3, 0.6), (4, 0.4)], &[(1, 1.0)]],
            &[&[(3, 1.0)]],
            &[&[(4, 1.0)]],
        ])
    }

    /// A chain of 1,000 states to the target, each with a safe action
    /// (on with 1 - q, else the sink) and one that gains `g = 5e-13` per
    /// state, below the improvement threshold: policy iteration keeps the
    /// first, 5e-10 short of the optimum in all, hundreds of times its
    /// error bound. The certificate's upper bound covers the optimum.
    #[test]
    fn the_certificate_covers_gains_below_the_improvement_threshold() {
        let (n, q, g) = (1000, 1e-4, 5e-13);
        let (target, sink) = (n, n + 1);
        let mut builder = MdpBuilder::new();
        for i in 0..n {
            builder.add_action([(i + 1, 1.0 - q), (sink, q)]);
            builder.add_action([(i + 1, 1.0 - q + g), (sink, q - g)]);
            builder.end_state();
        }
        for s in [target, sink] {
            builder.add_action([(s, 1.0)]);
            builder.end_state();
        }
        let m = builder.build().unwrap();
        let mut is_target = vec![false; n + 2];
        is_target[target] = true;
        let result = max_reachability(&m, &is_target, &SolverSettings::default()).unwrap();
        let optimum = (1.0 - q + g).powi(n as i32);
        assert!(
            result.values[0] < optimum - 1e-10,
            "policy iteration took the gain: {} against {optimum}",
            result.values[0]
        );
        assert!(result.error_bound < 1e-12, "{}", result.error_bound);
        assert!(
            result.upper[0] >= optimum,
            "{} < {optimum}",
            result.upper[0]
        );
        assert!(result.upper[0] < optimum + 1e-9, "{}", result.upper[0]);
    }

    #[test]
    fn a_policy_too_stiff_to_prove_is_passed_through_and_its_optimum_refused() {
        // Target 2, sink 3. States 0 and 1 swap with probability 0.3 and
        // leave rarely (0 to the target with 1e-25, 1 to the sink with
        // 2e-25): under that policy, which the proper start picks, x is
        // near 1/3 and the chain spends ~1e25 steps in the maybe states,
        // beyond what any double-precision bound proves (and the exact
        // fallback is off). State 0's second action wins 0.6 at once; under
        // it the chain mixes fast: x0 = 0.6, x1 = 0.3 x0 / (0.3 + 2e-25).
        // Policy iteration passes through the stiff policy without proof
        // and ends there, but no double vector certifies that the swap
        // (gaining 4e-26 against the rounded x1 = 0.6 for 1e25 moves) does
        // not beat it: the optimum is refused, not reported.
        let m = mdp(&[
            &[&[(1, 0.3), (2, 1e-25), (0, 0.7)], &[(2, 0.6), (3, 0.4)]],
            &[&[(0, 0.3), (3, 2e-25), (1, 0.7)]],
            &[&[(2, 1.0)]],
            &[&[(3, 1.0)]],
        ]);
        let settings = SolverSettings {
            exact_limit: 0,
            ..SolverSettings::default()
        };
        let error = max_reachability(&m, &[false, false, true, false], &settings).unwrap_err();
        assert!(matches!(error, MdpError::OptimalityUnproved(_)), "{error}");
    }

    /// From the proper start (which policy iteration must improve) and
    /// from the greedy start alike.
    #[test]
    fn values_derived_on_paper_with_end_components_in_the_maybe_states() {
        let target = [false, false, false, true, false];
        let qualitative = qualitative_reachability(&gamble(), &target).unwrap();
        let mut systems =
            PolicySystems::new(&gamble(), qualitative.clone(), &SolverSettings::default()).unwrap();
        let from_proper =
            max_reachability_with(&gamble(), &qualitative.strategy, &mut systems).unwrap();
        assert!(
            from_proper.iterations >= 2,
            "the start policy is not optimal"
        );
        let greedy = max_reachability(&gamble(), &target, &SolverSettings::default()).unwrap();
        let expected = [0.3, 0.6, 0.6, 1.0, 0.0];
        for result in [from_proper, greedy] {
            for (x, e) in result.values.iter().zip(expected) {
                assert!((x - e).abs() < 1e-14, "{:?}", result.values);
            }
            assert_eq!(&result.strategy[..3], &[1, 1, 0]);
            assert!(result.residual < 1e-12);
        }
    }

    /// `gamble` with other probabilities, the same graph. On paper: x2 =
    /// max(0.2, x1), x1 = max(0.5 + 0.5 x0, x2), x0 = max(x0, 0.5 x1): x0 =
    /// 1/3, x1 = x2 = 2/3 with strategy (1, 0, 1).
    fn gamble_reweighted() -> Mdp {
        mdp(&[
            &[&[(0, 1.0)], &[(1, 0.5), (4, 0.5)]],
            &[&[(3, 0.5), (0, 0.5)], &[(2, 1.0)]],
            &[&[(3, 0.2), (4, 0.8)], &[(1, 1.0)]],
            &[&[(3, 1.0)]],
            &[&[(4, 1.0)]],
        ])
    }

    /// One set of policy systems serves two MDPs of one graph: each gets
    /// its values on paper, and the expected visits of each optimal
    /// strategy from state 0 (on paper: under (1, 1, 0), y = (1, 1/2,
    /// 1/2); under (1, 0, 1), y0 = 1 + y1 / 2 and y1 = y0 / 2, so y = (4/3,
    /// 2/3, 0)).
    #[test]
    fn policy_systems_serve_every_mdp_of_their_graph() {
        let target = [false, false, false, true, false];
        let qualitative = qualitative_reachability(&gamble(), &target).unwrap();
        let settings = SolverSettings::default();
        let mut systems = PolicySystems::new(&gamble(), qualitative.clone(), &settings).unwrap();
        let close =
            |got: &[f64], want: &[f64]| got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-14);
        let first = max_reachability_with(&gamble(), &qualitative.strategy, &mut systems).unwrap();
        assert!(
            close(&first.values, &[0.3, 0.6, 0.6, 1.0, 0.0]),
            "{:?}",
            first.values
        );
        let visits = systems.expected_visits(&[(0, 1.0)]).unwrap();
        assert!(close(&visits, &[1.0, 0.5, 0.5, 0.0, 0.0]), "{visits:?}");
        let reweighted = gamble_reweighted();
        assert!(reweighted.same_graph(&gamble()));
        let second = max_reachability_with(&reweighted, &first.strategy, &mut systems).unwrap();
        let third = 2.0 / 3.0;
        assert!(
            close(&second.values, &[1.0 / 3.0, third, third, 1.0, 0.0]),
            "{:?}",
            second.values
        );
        assert_eq!(&second.strategy[..3], &[1, 0, 1]);
        assert!(second.error_bound <= settings.tolerance);
        let visits = systems.expected_visits(&[(0, 1.0)]).unwrap();
        assert!(
            close(&visits, &[4.0 / 3.0, third, 0.0, 0.0, 0.0]),
            "{visits:?}"
        );
    }

    /// Systems built for another graph are refused, not misread: another
    /// shape, or the same shape with another successor.
    #[test]
    fn policy_systems_of_another_shape_are_an_error() {
        let target = [false, false, false, true, false];
        let qualitative = qualitative_reachability(&gamble(), &target).unwrap();
        let settings = SolverSettings::default();
        let mut systems = PolicySystems::new(&gamble(), qualitative.clone(), &settings).unwrap();
        let smaller = mdp(&[
            &[&[(0, 1.0)], &[(1, 0.5), (4, 0.5)]],
            &[&[(3, 0.3), (0, 0.7)]],
            &[&[(3, 0.6), (4, 0.4)], &[(1, 1.0)]],
            &[&[(3, 1.0)]],
            &[&[(4, 1.0)]],
        ]);
        let found = max_reachability_with(&smaller, &qualitative.strategy, &mut systems);
        assert!(matches!(found, Err(MdpError::Malformed(_))), "{found:?}");
        // The same numbers of states, actions and entries, another successor.
        let rewired = mdp(&[
            &[&[(0, 1.0)], &[(1, 0.5), (4, 0.5)]],
            &[&[(3, 0.3), (0, 0.7)], &[(2, 1.0)]],
            &[&[(3, 0.6), (0, 0.4)], &[(1, 1.0)]],
            &[&[(3, 1.0)]],
            &[&[(4, 1.0)]],
        ]);
        let found = max_reachability_with(&rewired, &qualitative.strategy, &mut systems);
        assert!(matches!(found, Err(MdpError::Malformed(_))), "{found:?}");
    }

    /// Retrying (action 0) reaches 1 almost surely; the one-shot action 1
    /// looks better for one step (0.9) but risks the sink 2.
    #[test]
    fn patience_wins_with_value_exactly_one() {
        let m = mdp(&[
            &[&[(1, 0.5), (0, 0.5)], &[(1, 0.9), (2, 0.1)]],
            &[&[(1, 1.0)]],
            &[&[(2, 1.0)]],
        ]);
        let result =
            max_reachability(&m, &[false, true, false], &SolverSettings::default()).unwrap();
        assert_eq!(result.values, vec![1.0, 1.0, 0.0]);
        assert_eq!(result.strategy[0], 0);
    }

    #[test]
    fn unreachable_target_gives_zero_without_a_solve() {
        let result = max_reachability(&gamble(), &[false; 5], &SolverSettings::default()).unwrap();
        assert_eq!(result.values, vec![0.0; 5]);
        assert_eq!(result.iterations, 1);
    }

    #[test]
    fn a_target_set_of_the_wrong_size_is_an_error() {
        assert!(matches!(
            max_reachability(&gamble(), &[true], &SolverSettings::default()),
            Err(MdpError::Malformed(_))
        ));
    }

    /// State 0 may try for the target 2 directly (action 0: 0.1, else the
    /// sink 3) or move to 1 (action 1), which reaches 2 with 0.9. The
    /// backward search finds 0 through its direct edge to 2, so policy
    /// iteration from the proper start evaluates twice; value iteration
    /// sees 0.9 behind action 1 and the greedy start evaluates once.
    #[test]
    fn the_greedy_start_saves_the_evaluation_of_a_poor_proper_start() {
        let m = mdp(&[
            &[&[(2, 0.1), (3, 0.9)], &[(1, 1.0)]],
            &[&[(2, 0.9), (3, 0.1)]],
            &[&[(2, 1.0)]],
            &[&[(3, 1.0)]],
        ]);
        let target = [false, false, true, false];
        let qualitative = qualitative_reachability(&m, &target).unwrap();
        assert_eq!(qualitative.strategy[0], 0);
        let mut systems =
            PolicySystems::new(&m, qualitative.clone(), &SolverSettings::default()).unwrap();
        let from_proper = max_reachability_with(&m, &qualitative.strategy, &mut systems).unwrap();
        let greedy = max_reachability(&m, &target, &SolverSettings::default()).unwrap();
        assert_eq!((from_proper.iterations, greedy.iterations), (2, 1));
        assert_eq!(greedy.strategy[0], 1);
        assert!((greedy.values[0] - 0.9).abs() < 1e-12);
    }

    /// Whether `strategy` reaches the almost-sure set of `systems` from the
    /// maybe state `s` (a forward search).
    fn proper_from(m: &Mdp, systems: &PolicySystems, strategy: &[usize], s: usize) -> bool {
        let mut seen = vec![false; m.num_states()];
        let mut stack = vec![s];
        while let Some(u) = stack.pop() {
            if systems.qualitative.almost_sure[u] {
                return true;
            }
            if !seen[u] && systems.maybe.contains(&u) {
                seen[u] = true;
                stack.extend(m.distribution(u, strategy[u]).iter().map(|&(t, _)| t));
            }
        }
        false
    }

    /// States 0 and 1 move to each other (0 by action 1, 1 by action 0);
    /// 0 may also try for the target 2 with 0.7, 1 with 0.3 (action 1) or
    /// 0.8 (action 2). The proper start plays 0 -> 2 and 1's action 1; value
    /// iteration gives both 0.8, and the greedy step sends 0 to 1 (0.8 >
    /// 0.7) and 1 to 0 (its first action worth 0.8 > 0.3): a cycle that
    /// never reaches the target, which the repair must undo.
    #[test]
    fn a_greedy_cycle_is_given_the_proper_actions_back() {
        let m = mdp(&[
            &[&[(2, 0.7), (3, 0.3)], &[(1, 1.0)]],
            &[&[(0, 1.0)], &[(2, 0.3), (3, 0.7)], &[(2, 0.8), (3, 0.2)]],
            &[&[(2, 1.0)]],
            &[&[(3, 1.0)]],
        ]);
        let target = [false, false, true, false];
        let qualitative = qualitative_reachability(&m, &target).unwrap();
        let systems = PolicySystems::new(&m, qualitative, &SolverSettings::default()).unwrap();
        let start = systems.greedy_start(&m);
        assert!(proper_from(&m, &systems, &start, 0) && proper_from(&m, &systems, &start, 1));
        let result = max_reachability(&m, &target, &SolverSettings::default()).unwrap();
        assert!(
            (result.values[0] - 0.8).abs() < 1e-12,
            "{:?}",
            result.values
        );
        assert_eq!(&result.strategy[..2], &[1, 2]);
    }

    /// Random MDPs with up to 7 states, 1-3 actions each, and 1-3
    /// successors per action with weights 1-4.
    fn arbitrary_mdp() -> impl Strategy<Value = Mdp> {
        (1usize..8).prop_flat_map(|n| {
            let successor = (0..n, 1u32..5);
            let action = proptest::collection::vec(successor, 1..4);
            proptest::collection::vec(proptest::collection::vec(action, 1..4), n).prop_map(
                |states| {
                    let mut builder = MdpBuilder::new();
                    for actions in states {
                        for successors in actions {
                            let total: u32 = successors.iter().map(|&(_, w)| w).sum();
                            let terms = successors.into_iter();
                            builder.add_action(
                                terms.map(|(t, w)| (t, f64::from(w) / f64::from(total))),
                            );
                        }
                        builder.end_state();
                    }
                    builder.build().unwrap()
                },
            )
        })
    }

    proptest! {
        /// The greedy start is proper (every maybe state reaches the
        /// almost-sure set under it, checked by a forward search), and
        /// policy iteration from it ends at the values it reaches from the
        /// proper start.
        #[test]
        fn the_greedy_start_is_proper_and_changes_no_value(
            (m, target) in arbitrary_mdp().prop_flat_map(|m| {
                let n = m.num_states();
                (Just(m), proptest::collection::vec(any::<bool>(), n))
            })
        ) {
            let qualitative = qualitative_reachability(&m, &target).unwrap();
            let systems =
                PolicySystems::new(&m, qualitative.clone(), &SolverSettings::default()).unwrap();
            let start = systems.greedy_start(&m);
            for &s in &systems.maybe {
                prop_assert!(
                    proper_from(&m, &systems, &start, s),
                    "maybe state {s} does not reach the target under {start:?}"
                );
            }
            let mut from_proper_systems =
                PolicySystems::new(&m, qualitative.clone(), &SolverSettings::default()).unwrap();
            let from_proper =
                max_reachability_with(&m, &qualitative.strategy, &mut from_proper_systems).unwrap();
            let greedy = max_reachability(&m, &target, &SolverSettings::default()).unwrap();
            for (a, b) in greedy.values.iter().zip(&from_proper.values) {
                prop_assert!((a - b).abs() < 1e-9, "{:?} against {:?}", greedy.values, from_proper.values);
            }
        }
    }
}
