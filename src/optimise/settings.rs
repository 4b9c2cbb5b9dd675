//! [`Settings`]: every number the optimiser uses, with its default, checked
//! once by [`Settings::validate`] and recorded verbatim in `summary.json`.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::{OptimiseError, StructureSource};
use crate::seconds;
use crate::solver::{DEFAULT_LU_LIMIT, SolverMethod, SolverSettings};

/// How a player turns its logit gradient into a step (docs/method.md section 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum UpdateRule {
    /// `phi <- phi +/- eta * grad`.
    Plain,
    /// Adam (Kingma and Ba, 2015) with `beta1 = 0.9`, `beta2 = 0.999`,
    /// `epsilon = 1e-8`: `phi <- phi +/- eta * m_hat / (sqrt(v_hat) + epsilon)`,
    /// the update Storm's gradient descent uses by default.
    Adam,
}

/// The optimiser's settings. Every field has a default ([`Settings::default`]).
///
/// With the feature `cli`, they are also the command-line options of
/// `solve` and `sweep` (clap's `Args`): each field's documentation is its
/// help text, its name
/// the option (`max_iterations` is `--max-iterations`), its default the
/// option's; the linear solver's fields come from the options `--solver`,
/// `--lu-limit` and `--tolerance`, shared with `eval`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// Seed of every random choice (initial logits, best-response restarts).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().seed))]
    pub seed: u64,
    /// Logit bound `c_max`: every logit stays in `[-c_max, c_max]`, so every
    /// supported entry keeps probability at least `exp(-2 c_max) / |block|`
    /// (docs/method.md section 3): the support, hence the GMC graph, never changes.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().logit_bound))]
    pub logit_bound: f64,
    /// The max-min run's first logit bound `c_0 <= c_max`: without the
    /// guarantee ascent the bound doubles (up to `logit_bound`) whenever
    /// progress stalls while some logit sits on it, so determinism is
    /// capped only by `c_max`; the single-player ascent uses `c_max` from
    /// the start and the guarantee ascent `min(2 c_0, c_max)`, and with the
    /// guarantee ascent the loop keeps `c_0` and stops on a stall.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().initial_logit_bound))]
    pub initial_logit_bound: f64,
    /// Initial logits are drawn uniformly from `[-spread, spread]` (0: uniform controllers).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().initial_spread))]
    pub initial_spread: f64,
    /// Also optimise the initial node distributions (softmax over the initial support).
    #[cfg_attr(feature = "cli", arg(long))]
    pub optimise_initial: bool,
    /// Outer iterations (one defender step, or one quasi-Newton step of the
    /// single-player ascent) at most: a cap; runs normally stop on the
    /// certified gap or on stalled progress.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().max_iterations))]
    pub max_iterations: usize,
    /// The most work one start's max-min loop spends, in GMC states
    /// solved: every evaluation of the value (and its gradients) on the
    /// structure's GMC counts its reachable states, the gradient steps'
    /// and the best responses' alike (0: no limit); each guarantee ascent
    /// may spend a further quarter of it, counted in its product MDP's
    /// states per policy evaluation. A cap like
    /// `max_iterations` in units that grow with the chain, so that a run on
    /// a large game ends in bounded time, at the same iteration on every
    /// machine.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().max_work))]
    pub max_work: f64,
    /// Independent starts of the optimiser per structure, run in parallel
    /// (rayon), each with its own seeded random stream; the best by
    /// certified lower bound (by worst-case estimate without an automaton
    /// for !phi) is kept. A grown defender's sizes from 2 nodes up race
    /// one more, from the size before.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().starts))]
    pub starts: usize,
    /// Wall-clock budget in seconds for one structure (0: none).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().time_budget, value_parser = crate::seconds::parse))]
    pub time_budget: f64,
    /// Adversary descent steps per defender ascent step (the fast time scale).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().adversary_steps))]
    pub adversary_steps: usize,
    /// Defender step size `eta_def` at iteration 0.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().defender_step))]
    pub defender_step: f64,
    /// Adversary step size `eta_adv` (constant).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().adversary_step))]
    pub adversary_step: f64,
    /// Defender step decay `d`: `eta_def(t) = eta_def / sqrt(1 + d t)`.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().defender_decay))]
    pub defender_decay: f64,
    /// The max-min loop's starts are a portfolio: odd-numbered starts take
    /// defender steps this many times larger, without decay (bold steps
    /// reach near-deterministic optima in few iterations; the even starts'
    /// small decaying steps settle on mixed saddle points, where bold play
    /// cycles). The best certified start is kept. 1: every start alike.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().bold_step_factor))]
    pub bold_step_factor: f64,
    /// The update rule of both players.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Settings::default().update))]
    pub update: UpdateRule,
    /// Optimism `o` of both players' updates: each step moves along
    /// `d_t + o (d_t - d_{t-1})` (0: plain alternating play; 1: the
    /// optimistic gradient method, which converges to mixed saddle points
    /// where plain play cycles).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().optimism))]
    pub optimism: f64,
    /// A best-response check every this many outer iterations (and at the end).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().check_every))]
    pub check_every: usize,
    /// With a certified lower bound (an automaton for !phi), every this
    /// many checks is deep: the current defender also gets an L-BFGS best
    /// response, warm-started from the current adversary and the last best
    /// response, which tightens the game upper bound (the other checks
    /// certify only: one MDP solve per candidate). Without one, every check
    /// is deep.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().best_response_every))]
    pub best_response_every: usize,
    /// Random restarts of the final best-response minimisation of the
    /// returned defender (besides its warm starts; of every start's best
    /// defender without an automaton for `!phi`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().restarts))]
    pub restarts: usize,
    /// L-BFGS iterations per best-response start (fewer in a final best
    /// response on a GMC so large that its starts would spend more than
    /// `max_work`: [`Settings::final_best_response_iterations`]).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().best_response_iterations))]
    pub best_response_iterations: u64,
    /// L-BFGS memory `m`.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().lbfgs_memory))]
    pub lbfgs_memory: usize,
    /// The max-min loop's stall rule applies once this many checks ran
    /// since the logit bound last widened (0: never): it stops (or widens
    /// the bound) when the best score (certified lower bound, or worst-case
    /// estimate without an automaton for !phi) gained at most `stall_gain`
    /// times its magnitude (at least 1e-3) over the second half of those
    /// checks.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().stall_checks))]
    pub stall_checks: usize,
    /// The relative gain below which the max-min loop counts as stalled
    /// (see `stall_checks`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().stall_gain))]
    pub stall_gain: f64,
    /// The guarantee ascent's stall window: it stops when the certified
    /// lower bound has gained at most `stall_tolerance` times itself over
    /// this many steps (0: never).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().ascent_stall_iterations))]
    pub ascent_stall_iterations: usize,
    /// The relative gain below which the guarantee ascent counts as
    /// stalled (see `ascent_stall_iterations`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().stall_tolerance))]
    pub stall_tolerance: f64,
    /// Stop when the certified gap, the game upper bound minus the best
    /// certified lower bound (docs/method.md section 6), is at most this: the
    /// defender is then optimal within it against every adversary.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().gap_tolerance))]
    pub gap_tolerance: f64,
    /// Single-player games (the adversary has one action) are optimised by
    /// L-BFGS steps on the defender's logits, `max V`, under the same
    /// driver (a check's worst case is the value itself); off
    /// (`--no-single-player-ascent`): gradient play runs on them too.
    #[cfg_attr(feature = "cli", arg(long = "no-single-player-ascent", action = clap::ArgAction::SetFalse))]
    pub single_player_ascent: bool,
    /// A defender of `K > 1` nodes is grown from 1 node: each size is
    /// optimised warm-started from the one before and kept at least as good,
    /// so more memory never certifies less (docs/method.md section 4); off
    /// (`--no-grow`): only size `K` is optimised, from the uniform start.
    #[cfg_attr(feature = "cli", arg(long = "no-grow", action = clap::ArgAction::SetFalse))]
    pub grow_defender: bool,
    /// At the end, also evaluate the argmax-rounded defender and its partial
    /// roundings (entries below a threshold dropped) and keep whichever
    /// scores best (the unrounded one included); off: `--no-round`.
    #[cfg_attr(feature = "cli", arg(long = "no-round", action = clap::ArgAction::SetFalse))]
    pub round: bool,
    /// With rounding and a certified lower bound: change deterministic
    /// supports one block at a time (drop a choice, play one enabled (next
    /// node, action) pair, or send a choice to a copy of its next node and
    /// climb from there) while that raises the certified lower bound
    /// (docs/method.md section 6, local search). On games it climbs before
    /// the max-min race from the argmax rounding of the structure's
    /// defender and `local_search_restarts` random memoryless deterministic
    /// defenders (its bound is the race's floor: the race ends once an
    /// upper bound meets it), and once more after the race from the best
    /// rounded candidate; on one-player models after the ascent, from the
    /// best rounded candidate and the restarts. After the restarts, kicks
    /// climb from the best end point with one in 8 of its blocks in use
    /// redrawn, 4 at a time, until they have spent as much work as the
    /// restarts (iterated local search). The best end point is the
    /// candidate `local-search`. Each climb ends by itself, when it has
    /// spent `local_search_work`, or at the time budget's final deadline.
    /// An expected reward's run (docs/method.md section 9) climbs its
    /// expected reward from its best rounding and from
    /// `local_search_restarts` random deterministic controllers on the
    /// structure's support. Off: `--no-local-search`.
    #[cfg_attr(feature = "cli", arg(long = "no-local-search", action = clap::ArgAction::SetFalse))]
    pub local_search: bool,
    /// How many random memoryless starts the local search climbs from
    /// besides the best candidate, per round (in parallel; seeded from
    /// `seed`; up to 4 rounds where climbs end early; fewer where two
    /// evaluations of the start's product cost more than
    /// `local_search_work`, docs/method.md section 6); 0 also turns its
    /// kicks off.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().local_search_restarts))]
    pub local_search_restarts: usize,
    /// The most work one climb of the local search spends, counted as the
    /// reachable product states of its bound evaluations, summed (a move
    /// that cannot raise the bound, in a block the adversary's best
    /// response does not meet, counts without being solved): 120,000 is
    /// 300 evaluations on a 400-state product, 30 on a 4,000-state one. A
    /// count, not seconds, so a seed gives the same search on every
    /// machine.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().local_search_work))]
    pub local_search_work: usize,
    /// On games with a certified lower bound, wherever the max-min loop's
    /// stall rule is judged (see `stall_checks`) and when the loop stops,
    /// ascend the certified lower bound itself from the best defender
    /// (L-BFGS with its Danskin gradient, docs/method.md section 6) and
    /// keep the result when it certifies higher; the stall rule then judges
    /// these ascended bounds. Off (`--no-guarantee-ascent`): the paper's
    /// loop alone.
    #[cfg_attr(feature = "cli", arg(long = "no-guarantee-ascent", action = clap::ArgAction::SetFalse))]
    pub guarantee_ascent: bool,
    /// Largest residual `max |(I - Q) x - b|` accepted from a linear solve.
    #[cfg_attr(feature = "cli", arg(skip = Settings::default().solver_tolerance))]
    pub solver_tolerance: f64,
    /// How the linear systems are solved (LU, BiCGSTAB, or by size).
    #[cfg_attr(feature = "cli", arg(skip = Settings::default().solver))]
    pub solver: SolverMethod,
    /// With `solver` auto: the most unknowns solved by LU. Recorded in
    /// `summary.json` only when it is not [`crate::value::DEFAULT_LU_LIMIT`].
    #[cfg_attr(feature = "cli", arg(skip = Settings::default().lu_limit))]
    #[serde(skip_serializing_if = "is_default_lu_limit")]
    pub lu_limit: usize,
    /// The sources of the structures to optimise on (in parallel):
    /// the starting structure, support synthesis by SAT (docs/method.md section
    /// 7), the paper's Algorithm 1 (docs/method.md section 5).
    #[cfg_attr(feature = "cli", arg(long, value_enum, value_delimiter = ',', default_values_t = Settings::default().structures))]
    pub structures: Vec<StructureSource>,
    /// Support synthesis for the `sat` source; its `mode` is not used (the
    /// source tries almost-sure winning, then positive winning).
    #[cfg_attr(feature = "cli", command(flatten))]
    pub synthesis: crate::synthesis::Settings,
    /// Algorithm 1's lines 14-16 as printed (remove action `u` under
    /// observation `o` for all nodes) instead of only the offending entries.
    #[cfg_attr(feature = "cli", arg(long))]
    pub prune_paper_literal: bool,
    /// Run Algorithm 1's lines 18-22, which restrict the adversary's support:
    /// the worst-case estimate is then against a restricted adversary.
    #[cfg_attr(feature = "cli", arg(long))]
    pub prune_adversary: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            seed: 0,
            logit_bound: 10.0,
            initial_logit_bound: 4.0,
            initial_spread: 1.0,
            optimise_initial: false,
            max_iterations: 3000,
            max_work: DEFAULT_MAX_WORK,
            starts: 4,
            time_budget: 0.0,
            adversary_steps: 10,
            defender_step: 0.05,
            adversary_step: 0.5,
            defender_decay: 0.05,
            bold_step_factor: 4.0,
            update: UpdateRule::Adam,
            optimism: 0.0,
            check_every: 5,
            best_response_every: 20,
            restarts: 4,
            best_response_iterations: 100,
            lbfgs_memory: 7,
            stall_checks: 40,
            stall_gain: 1e-3,
            ascent_stall_iterations: 100,
            stall_tolerance: 1e-5,
            gap_tolerance: 1e-4,
            single_player_ascent: true,
            grow_defender: true,
            round: true,
            local_search: true,
            local_search_restarts: 16,
            local_search_work: 120_000,
            guarantee_ascent: true,
            solver_tolerance: crate::solver::DEFAULT_TOLERANCE,
            solver: SolverMethod::Auto,
            lu_limit: DEFAULT_LU_LIMIT,
            structures: StructureSource::ALL.to_vec(),
            synthesis: crate::synthesis::Settings::default(),
            prune_paper_literal: false,
            prune_adversary: false,
        }
    }
}

/// Value and gradient evaluations one L-BFGS iteration of a best response
/// is counted as by [`Settings::final_best_response_iterations`] (its line
/// search takes one or more).
pub const EVALUATIONS_PER_ITERATION: usize = 2;

/// The default [`Settings::max_work`]: 3.5 million GMC states solved per
/// start, about 160 outer iterations of gradient play on a GMC of 2,000
/// states (PAYNT's dodge games with 3 nodes); the gradient steps alone
/// (11 evaluations per iteration) reach it within `max_iterations` only
/// on GMCs of more than 106 states, best responses count too.
pub const DEFAULT_MAX_WORK: f64 = 3.5e6;

/// With a time budget, the share of it that a structure's final best
/// responses get at least, however late they start.
const FINAL_SHARE_OF_BUDGET: f64 = 0.1;

/// With a time budget, the share of it that the local search before a
/// structure's race may spend.
const SEARCH_SHARE_OF_BUDGET: f64 = 0.25;

impl Settings {
    /// With a time budget, when the final best responses of a structure whose
    /// run began at `started` must end: at the end of the budget, or a tenth
    /// of the budget from `now` if that is later (`None` without a budget).
    /// A budget beyond the clock is no budget ([`crate::seconds`]).
    pub fn final_deadline(&self, started: Instant, now: Instant) -> Option<Instant> {
        let end = seconds::deadline(started, self.time_budget)?;
        let share = seconds::after(now, self.time_budget * FINAL_SHARE_OF_BUDGET)?;
        Some(end.max(share))
    }

    /// Whether the certified gap between a lower bound `lower` and an upper
    /// bound `upper` is closed: at most `gap_tolerance` (method.md section
    /// 4's stopping rule; no defender certifies more than `upper`).
    pub fn gap_closed(&self, lower: f64, upper: f64) -> bool {
        upper - lower <= self.gap_tolerance
    }

    /// The L-BFGS iterations of each of a final best response's `starts`
    /// on a GMC of `gmc_states` states: `best_response_iterations`, fewer
    /// where the starts together would spend more than `max_work` (counting
    /// `EVALUATIONS_PER_ITERATION` evaluations per iteration, each of
    /// `gmc_states`), and at least one. So the final estimate costs at most
    /// about one start's loop on a large GMC (PAYNT's dodge-8 with 3 nodes:
    /// 24,384 states: 100 iterations from 6 starts took 40 s; 11 now).
    pub fn final_best_response_iterations(&self, gmc_states: usize, starts: usize) -> u64 {
        if self.max_work <= 0.0 {
            return self.best_response_iterations;
        }
        let per_iteration = (EVALUATIONS_PER_ITERATION * gmc_states.max(1) * starts.max(1)) as f64;
        let within = (self.max_work / per_iteration).floor() as u64;
        within.clamp(1, self.best_response_iterations.max(1))
    }

    /// The random restarts of a final best response: `restarts`, none where
    /// the certified gap is closed (any response is then within
    /// `gap_tolerance` of the truth, so the warm starts suffice).
    pub fn final_restarts(&self, gap_closed: bool) -> usize {
        if gap_closed { 0 } else { self.restarts }
    }

    /// With a time budget, when the local searches before the structures'
    /// max-min races, the run begun at `started`, must end: after a
    /// quarter of the budget, which the structures' searches share (they
    /// run one after another), so that the races keep the rest (`None`
    /// without a budget).
    pub fn search_deadline(&self, started: Instant) -> Option<Instant> {
        seconds::deadline(started, self.time_budget * SEARCH_SHARE_OF_BUDGET)
    }

    /// The linear solver's settings: [`Self::solver`], [`Self::solver_tolerance`]
    /// and [`Self::lu_limit`].
    pub fn solver_settings(&self) -> SolverSettings {
        SolverSettings {
            method: self.solver,
            tolerance: self.solver_tolerance,
            lu_limit: self.lu_limit,
            ..SolverSettings::default()
        }
    }

    /// The settings start `start` of a structure runs with: odd-numbered
    /// starts take bold defender steps (`bold_step_factor` times larger,
    /// no decay), the others these settings as they are.
    pub fn for_start(&self, start: usize) -> Self {
        if start % 2 == 1 {
            Self {
                defender_step: self.defender_step * self.bold_step_factor,
                defender_decay: 0.0,
                ..self.clone()
            }
        } else {
            self.clone()
        }
    }

    /// Checks every field's range; the optimiser cannot fail on settings afterwards.
    pub fn validate(&self) -> Result<(), OptimiseError> {
        self.synthesis.validate()?;
        if self.structures.is_empty() {
            return Err(invalid(
                "structures",
                "must name at least one source".into(),
            ));
        }
        let positive = [
            ("logit_bound", self.logit_bound),
            ("initial_logit_bound", self.initial_logit_bound),
            ("defender_step", self.defender_step),
            ("adversary_step", self.adversary_step),
            ("solver_tolerance", self.solver_tolerance),
            ("bold_step_factor", self.bold_step_factor),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(invalid(
                    name,
                    format!("must be positive and finite, got {value}"),
                ));
            }
        }
        let non_negative = [
            ("initial_spread", self.initial_spread),
            ("max_work", self.max_work),
            ("defender_decay", self.defender_decay),
            ("stall_tolerance", self.stall_tolerance),
            ("stall_gain", self.stall_gain),
            ("gap_tolerance", self.gap_tolerance),
            ("optimism", self.optimism),
        ];
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(invalid(
                    name,
                    format!("must be non-negative and finite, got {value}"),
                ));
            }
        }
        seconds::check(self.time_budget).map_err(|problem| invalid("time_budget", problem))?;
        if self.initial_spread > self.initial_logit_bound {
            return Err(invalid(
                "initial_spread",
                "must not exceed initial_logit_bound".into(),
            ));
        }
        if self.initial_logit_bound > self.logit_bound {
            return Err(invalid(
                "initial_logit_bound",
                "must not exceed logit_bound".into(),
            ));
        }
        if self.logit_bound > MAX_LOGIT_BOUND {
            return Err(invalid(
                "logit_bound",
                format!(
                    "must be at most {MAX_LOGIT_BOUND} (exp(-2c) must stay far above the \
                     smallest double, or a supported choice would get probability 0)"
                ),
            ));
        }
        let at_least_one = [
            ("max_iterations", self.max_iterations),
            ("starts", self.starts),
            ("adversary_steps", self.adversary_steps),
            ("check_every", self.check_every),
            ("best_response_every", self.best_response_every),
            ("lbfgs_memory", self.lbfgs_memory),
        ];
        for (name, value) in at_least_one {
            if value == 0 {
                return Err(invalid(name, "must be at least 1".into()));
            }
        }
        Ok(())
    }
}

/// Whether `lu_limit` is the default (then `summary.json` leaves it out,
/// as before the setting existed).
fn is_default_lu_limit(lu_limit: &usize) -> bool {
    *lu_limit == DEFAULT_LU_LIMIT
}

/// The largest accepted `logit_bound`: `exp(-2 * 100)` is about `1e-87`.
pub const MAX_LOGIT_BOUND: f64 = 100.0;

fn invalid(field: &'static str, problem: String) -> OptimiseError {
    OptimiseError::Settings { field, problem }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// Small GMCs keep every iteration; a large one gets what `max_work`
    /// pays for its starts together (3.5e6 / (2 * 24,384 * 6) = 11.96 on
    /// PAYNT's dodge-8 with 3 nodes), never none; without a work cap,
    /// every iteration.
    #[test]
    fn a_final_best_response_on_a_large_gmc_gets_the_iterations_max_work_pays_for() {
        let settings = Settings::default();
        assert_eq!(settings.final_best_response_iterations(500, 6), 100);
        assert_eq!(settings.final_best_response_iterations(24_384, 6), 11);
        assert_eq!(settings.final_best_response_iterations(10_000_000, 6), 1);
        let uncapped = Settings {
            max_work: 0.0,
            ..Settings::default()
        };
        assert_eq!(uncapped.final_best_response_iterations(10_000_000, 6), 100);
    }

    /// Issue 57: `solve --time-budget 1e20` panicked in
    /// `Duration::from_secs_f64`; a budget beyond the clock is no deadline.
    #[test]
    fn a_time_budget_beyond_the_clock_is_valid_and_sets_no_deadline() {
        let now = Instant::now();
        for time_budget in [1e20, 1e308] {
            let settings = Settings {
                time_budget,
                ..Settings::default()
            };
            assert!(settings.validate().is_ok());
            assert_eq!(settings.final_deadline(now, now), None);
            assert_eq!(settings.search_deadline(now), None);
        }
    }

    #[test]
    fn the_final_deadline_is_the_budgets_end_or_a_tenth_of_it_after_a_late_stop() {
        let started = Instant::now();
        let budget = Settings {
            time_budget: 20.0,
            ..Settings::default()
        };
        let early = started + Duration::from_secs(5);
        let late = started + Duration::from_secs(30);
        assert_eq!(
            budget.final_deadline(started, early),
            Some(started + Duration::from_secs(20))
        );
        assert_eq!(
            budget.final_deadline(started, late),
            Some(late + Duration::from_secs(2))
        );
        assert_eq!(Settings::default().final_deadline(started, late), None);
    }

    #[test]
    fn the_search_before_the_race_gets_a_quarter_of_the_budget() {
        let started = Instant::now();
        let budget = Settings {
            time_budget: 20.0,
            ..Settings::default()
        };
        assert_eq!(
            budget.search_deadline(started),
            Some(started + Duration::from_secs(5))
        );
        assert_eq!(Settings::default().search_deadline(started), None);
    }
}
