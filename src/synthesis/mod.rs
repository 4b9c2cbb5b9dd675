//! Support synthesis (method.md section 7): a defender support of `N` nodes
//! that wins **positively** (value > 0) or **almost surely** (value 1)
//! against the certification adversary of method.md section 6, found by SAT
//! and maximised, or a proof that none exists.
//!
//! # What is decided
//!
//! Fix a support (which `(g', u)` may follow `(g, o)`) and let the defender
//! play uniformly on it. The certification adversary sees `(s, q, g)` and
//! remembers everything: it plays an MDP on product states `m = (s, q, g)`
//! whose action `v` leads, with positive probability, along every *edge*
//! `m -> (s', delta(q, L(s')), g')` for which some `o` with `O(o | s) > 0`
//! and some supported `(g', u)` at `(g, o)` have `T(s' | s, u, v) > 0`.
//! Which probabilities the defender puts on the support does not matter
//! for the questions below; only the edges do.
//!
//! # Certificates
//!
//! For one Rabin pair `(L, K)`, a *positive certificate* is a set `P` of
//! product states with a level `lambda` and, outside `K`, a rank `rho >= 1`
//! (rank 0 on `K`), such that for every `m` in `P` and every adversary
//! action `v`:
//!
//! 1. some edge goes to `P` with a lower level, or every edge goes to `P`
//!    with a level no higher;
//! 2. if `m` is in `L`: some edge goes to `P` with a lower level;
//! 3. if `m` is not in `K`: some edge goes to `P` with a lower level, or with
//!    a level no higher and a lower rank.
//!
//! An *almost-sure certificate* is a positive certificate that is closed:
//! every edge from `P` stays in `P`.
//!
//! **Soundness.** Along any play the level never increases while the play
//! stays in `P`, and where condition 1 offers only a lower edge, that edge
//! is taken with probability at least `p_min > 0`; so with probability at
//! least `p_min^R` the play stays in `P` forever (surely, for a closed
//! `P`). The states and actions a play uses infinitely often form, almost
//! surely, an end component `E`. If `E` lies in `P`, its lowest-level
//! states are closed under `E`'s actions (condition 1), so `E` has a single
//! level; then condition 2 excludes `L` from `E` and condition 3 (ranks
//! strictly decrease inside one level) forces a `K` state into `E`: the
//! play satisfies the pair. Hence a positive certificate containing an
//! initial state proves a certified lower bound `> 0`, and a closed one
//! containing every initial state proves 1.
//!
//! **Completeness (one pair).** Whenever the adversary's minimum
//! probability of the pair is positive (or 1) from an initial state, a
//! certificate with levels and ranks below the number of product states
//! exists: take for `P` the states from which the adversary cannot reach
//! the union of its winning end components (those meeting `L` or avoiding
//! `K`) almost surely (for value 1: cannot reach them at all), levels from
//! the attractor layers of that set refined by the maximal end component
//! decomposition (every state outside an end component gets a lower
//! successor under every action), and ranks inside each maximal end
//! component towards `K`. So for one pair, with the default rank bound,
//! "no support" is a proof. method.md's *traps* (closed, no `L` state) are
//! the special case with one level; they alone would miss, for example,
//! `FG a` where the adversary may choose between staying in `a` and a
//! single visit to `!a`, and every positive value reached through an end
//! component the adversary may leave.
//!
//! With several pairs the encoding takes the union of one certificate per
//! pair: sound, but it may miss supports that win only by mixing pairs.
//!
//! # Two engines
//!
//! * [`Engine::Certificate`] (the `encoding` module) puts the support, the edges and
//!   the certificates into one formula: a model is a support with its proof.
//!   "Unsatisfiable" is a proof for one pair with the exact rank bound.
//! * [`Engine::Lazy`] (the `search` module, the default) gives the solver only the
//!   support and the edges; each proposed support is judged by the exact
//!   certification of method.md section 6, and a losing one teaches a lemma
//!   read off the adversary's counterexample. "Unsatisfiable" is then a proof
//!   for any number of pairs. It is much faster: the certificate formula
//!   leaves the solver to discover by search what the judge computes in
//!   linear time (on the paper's grid with two nodes, one satisfiable call
//!   of the certificate formula takes longer than the whole lazy search).
//!
//! Whichever engine finds a support, the other route confirms it: the lazy
//! engine's support is checked against the certificate formula with the
//! support fixed (with one usable pair and the exact rank bound it must
//! have a certificate), and every support is certified by
//! [`crate::certify::lower_bound`] (positive, or exactly 1). A disagreement
//! is an error.
//!
//! # Maximisation
//!
//! A found support is enlarged by incremental SAT under assumptions: each
//! absent entry is assumed present together with all entries kept so far,
//! and kept when the formula stays satisfiable. The result is
//! inclusion-maximal: no single entry can be added. Gradient play then has
//! the most room, and never needs an entry the support excludes.

mod cnf;
mod confirm;
mod encoding;
mod graph;
mod ranks;
mod search;
mod variables;
mod witness;

pub use confirm::Confirmation;
pub use ranks::RankEncoding;

use std::time::Instant;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::automaton::{Dra, RabinPair};
use crate::certify::{CertifyError, Qualitative, lower_bound_within};
use crate::controller::{Choice, Fsc, Role};
use crate::game::{ModelError, Posg};
use crate::solver::SolverSettings;

use cnf::{Answer, Cnf, FALSE, Lit, Solver};
use encoding::{Claim, Context};
use graph::{CellGraph, Moves};
use search::Oracle;
use variables::SupportVariables;

/// What the support must guarantee against the certification adversary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// A certified lower bound above 0.
    Positive,
    /// A certified lower bound of 1.
    AlmostSure,
}

impl Mode {
    /// The name used in files and messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Positive => "positive",
            Self::AlmostSure => "almost-sure",
        }
    }

    fn phrase(self) -> &'static str {
        match self {
            Self::Positive => "with positive probability",
            Self::AlmostSure => "almost surely",
        }
    }

    fn claim(self) -> Claim {
        match self {
            Self::Positive => Claim::Positive,
            Self::AlmostSure => Claim::AlmostSure,
        }
    }
}

/// How the SAT solver is used (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Engine {
    /// Supports only; exact judgement and counterexample lemmas.
    #[default]
    Lazy,
    /// Support and certificate in one formula.
    Certificate,
}

/// The synthesis settings. Every field has a default ([`Settings::default`]).
///
/// Except `mode` (`support --almost-sure`; the `sat` source of `solve`
/// chooses it itself), with the feature `cli` they are also the command-line
/// options of `support`, `solve` and `sweep` (clap's `Args`): each field's
/// documentation is its help text, its default the option's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// Positive or almost-sure winning.
    #[cfg_attr(feature = "cli", arg(skip = Settings::default().mode))]
    pub mode: Mode,
    /// `lazy`: SAT over supports, each judged by exact certification, losses
    /// learnt as lemmas; `certificate`: supports and their certificates in one
    /// formula (docs/method.md section 7).
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Settings::default().engine))]
    pub engine: Engine,
    /// The bound `R` on the certificates' levels and ranks (default: the
    /// number of product states `(s, q, g)`, the bound that makes the
    /// certificate complete, and "impossible" a proof, for one Rabin pair).
    #[cfg_attr(feature = "cli", arg(long))]
    pub rank_bound: Option<usize>,
    /// How levels and ranks are written in CNF.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Settings::default().rank_encoding))]
    pub rank_encoding: RankEncoding,
    /// Enlarge the support found to an inclusion-maximal one (off with
    /// `--no-maximise`: the first support found).
    #[cfg_attr(feature = "cli", arg(long = "no-maximise", action = clap::ArgAction::SetFalse))]
    pub maximise: bool,
    /// Confirm a support found by the lazy engine with the certificate
    /// formula (docs/method.md section 7; off with `--no-confirm`,
    /// certification still checks it).
    #[cfg_attr(feature = "cli", arg(long = "no-confirm", action = clap::ArgAction::SetFalse))]
    pub confirm_certificate: bool,
    /// Refuse SAT instances with more clauses than this (CaDiCaL needs
    /// roughly 100 bytes per clause of this encoding); larger ones are an
    /// error before they are built.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::default().clause_budget))]
    pub clause_budget: usize,
    /// Seconds the SAT solver (with the lazy engine's judging) may take in
    /// all (0: no limit); running out is an error for `support`; `solve` and
    /// `sweep` give the almost-sure attempt 0.4% of it and the positive one
    /// a tenth, and note a timeout and go on without.
    #[cfg_attr(feature = "cli", arg(
        id = "synthesis_time_budget",
        long = "synthesis-time-budget",
        value_name = "SYNTHESIS_TIME_BUDGET",
        default_value_t = Settings::default().time_budget,
        value_parser = crate::seconds::parse
    ))]
    pub time_budget: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            mode: Mode::Positive,
            engine: Engine::Lazy,
            rank_bound: None,
            rank_encoding: RankEncoding::Binary,
            maximise: true,
            confirm_certificate: true,
            clause_budget: 20_000_000,
            time_budget: 120.0,
        }
    }
}

impl Settings {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), SynthesisError> {
        if self.rank_bound == Some(0) {
            return Err(SynthesisError::Settings {
                field: "rank_bound",
                problem: "must be at least 1".into(),
            });
        }
        if let Err(problem) = crate::seconds::check(self.time_budget) {
            return Err(SynthesisError::Settings {
                field: "time_budget",
                problem,
            });
        }
        Ok(())
    }
}

/// Why synthesis could not answer.
#[derive(Debug, Error)]
pub enum SynthesisError {
    /// A setting is out of range.
    #[error("setting `{field}` {problem}")]
    Settings {
        /// The field's name.
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// The formula would exceed the clause budget.
    #[error(
        "the SAT encoding would exceed the budget of {budget} {what} (raise the clause budget, \
         or lower the rank bound or the number of nodes)"
    )]
    TooLarge {
        /// What was counted.
        what: String,
        /// The budget.
        budget: usize,
    },
    /// The time budget ran out: no answer either way.
    #[error(
        "support synthesis ran out of its time budget after {calls} SAT calls and {seconds:.1} s: \
         no answer"
    )]
    TimeBudget {
        /// SAT calls made.
        calls: usize,
        /// Seconds since the solver was loaded.
        seconds: f64,
    },
    /// The defender does not fit the game, or the sizes are invalid.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The exact certification failed.
    #[error(transparent)]
    Certify(#[from] CertifyError),
    /// The two routes to the same fact disagree: a bug.
    #[error("internal error: {0}; please report this with the game, the formula and the settings")]
    Internal(String),
}

/// The size of the SAT work and the time spent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SatStatistics {
    /// The engine that searched.
    pub engine: Engine,
    /// Variables of the search formula.
    pub variables: usize,
    /// Clauses of the search formula (lemmas included).
    pub clauses: usize,
    /// Product states `(s, q, g)` of the certificate formula.
    pub product_states: usize,
    /// Rabin pairs with a reachable accepting cycle.
    pub pairs: usize,
    /// The bound on levels and ranks of the certificate formula.
    pub rank_bound: usize,
    /// SAT calls, maximisation included.
    pub calls: usize,
    /// Supports judged by certification (lazy engine).
    pub judged: usize,
    /// Lemmas learnt (lazy engine).
    pub lemmas: usize,
    /// Seconds inside the SAT solver.
    pub solve_seconds: f64,
    /// Seconds to confirm the support with the other route.
    pub confirm_seconds: f64,
    /// Wall-clock seconds in all.
    pub seconds: f64,
}

/// The answer for one size and mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Synthesis {
    /// The mode asked for.
    pub mode: Mode,
    /// The defender's number of nodes `N`.
    pub defender_nodes: usize,
    /// The defender uniform on the (maximised) support, starting in node
    /// 0, when one was found.
    pub defender: Option<Fsc>,
    /// Its certified lower bound (method.md section 6), when found.
    pub certified_lower: Option<f64>,
    /// Whether "not found" is a proof (module documentation).
    pub exact: bool,
    /// A sentence saying what was found or proved.
    pub reason: String,
    /// How the support found was confirmed by the certificate formula.
    pub confirmation: Confirmation,
    /// The SAT work (`None` when no SAT call was needed).
    pub statistics: Option<SatStatistics>,
}

impl Synthesis {
    /// The number of support entries `(g, o, g', u)` of the defender found.
    pub fn support_entries(&self) -> usize {
        self.defender.as_ref().map_or(0, |fsc| {
            (0..fsc.num_nodes())
                .flat_map(|g| (0..fsc.num_observations()).map(move |o| (g, o)))
                .map(|(g, o)| fsc.choices(g, o).len())
                .sum()
        })
    }
}

/// Decides whether some `defender_nodes`-node support wins in
/// `settings.mode` against the certification adversary, for the objective
/// given by `dra` and `dra_not_phi` (deterministic automata for phi and
/// !phi), and returns it maximised and certified (module documentation),
/// the certificate's policy evaluations solved by `linear_solver`.
pub fn synthesise(
    game: &Posg,
    dra: &Dra,
    dra_not_phi: &Dra,
    defender_nodes: usize,
    settings: &Settings,
    linear_solver: &SolverSettings,
) -> Result<Synthesis, SynthesisError> {
    settings.validate()?;
    check_nodes(defender_nodes)?;
    let clock = Instant::now();
    let problem = Problem::new(game, dra, defender_nodes, settings);
    let (moves, pairs, product_states, rank_bound) = (
        &problem.moves,
        problem.pairs(dra),
        problem.product_states,
        problem.rank_bound,
    );
    let context = problem.context(game);
    let certificate_complete = pairs.len() <= 1 && rank_bound >= product_states;
    let mut synthesis = Synthesis {
        mode: settings.mode,
        defender_nodes,
        defender: None,
        certified_lower: None,
        exact: match settings.engine {
            Engine::Lazy => true,
            Engine::Certificate => certificate_complete,
        },
        reason: String::new(),
        confirmation: match settings.engine {
            Engine::Lazy => Confirmation::Skipped,
            Engine::Certificate => Confirmation::Confirmed,
        },
        statistics: None,
    };
    if pairs.is_empty() {
        synthesis.reason = "no run of the game can satisfy the formula: no Rabin pair has a \
                            reachable cycle through K that avoids L"
            .into();
        return Ok(synthesis);
    }
    let deadline = crate::seconds::deadline(clock, settings.time_budget);
    let mut cnf = Cnf::new(settings.clause_budget);
    let mut vars = SupportVariables::new(&mut cnf, game, moves, defender_nodes)?;
    let mut oracle = Oracle::new(game, dra_not_phi, moves, defender_nodes, settings.mode);
    if settings.engine == Engine::Certificate {
        certificate_formula(&context, &mut cnf, &mut vars, &pairs, settings, rank_bound)?;
    }
    let mut solver = Solver::new(&cnf, deadline);
    let mut find = |cnf: &mut Cnf,
                    vars: &mut SupportVariables,
                    solver: &mut Solver,
                    assumptions: &[Lit]|
     -> Result<Option<Vec<bool>>, SynthesisError> {
        match settings.engine {
            Engine::Lazy => oracle.find(cnf, vars, solver, assumptions),
            Engine::Certificate => Ok(match solver.solve(assumptions)? {
                Answer::Unsatisfiable => None,
                Answer::Satisfiable => {
                    Some(vars.support.iter().map(|&x| solver.value(x)).collect())
                }
            }),
        }
    };
    let mut support = find(&mut cnf, &mut vars, &mut solver, &[])?;
    if settings.maximise
        && let Some(found) = support.take()
    {
        let literals = vars.support.clone();
        let grow = |assumptions: &[Lit]| find(&mut cnf, &mut vars, &mut solver, assumptions);
        support = Some(maximise(found, grow, &literals)?);
    }
    let (judged, lemmas) = (oracle.judged, oracle.lemmas);
    let mut confirm_seconds = 0.0;
    if let Some(support) = &support {
        let defender = defender_on(game, defender_nodes, &vars, support)?;
        synthesis.certified_lower = Some(certify(
            game,
            dra_not_phi,
            &defender,
            settings.mode,
            linear_solver,
        )?);
        if settings.engine == Engine::Lazy && settings.confirm_certificate {
            let start = Instant::now();
            synthesis.confirmation = confirm::confirm(
                &context, dra, &pairs, &defender, support, settings, rank_bound,
            )?;
            confirm_seconds = start.elapsed().as_secs_f64();
        }
        synthesis.defender = Some(defender);
        synthesis.reason = format!(
            "found a {defender_nodes}-node support that wins {} against every adversary",
            settings.mode.phrase()
        );
    } else {
        synthesis.confirmation = Confirmation::Skipped;
        let strength = if synthesis.exact {
            "proved"
        } else if pairs.len() > 1 {
            "not found (sound, may miss: the automaton has several Rabin pairs)"
        } else {
            "not found (sound, may miss: the rank bound is below the number of product states)"
        };
        synthesis.reason = format!(
            "no {defender_nodes}-node support wins {} against the certification adversary: {strength}",
            settings.mode.phrase()
        );
    }
    synthesis.statistics = Some(SatStatistics {
        engine: settings.engine,
        variables: cnf.num_vars(),
        clauses: cnf.num_clauses(),
        product_states,
        pairs: pairs.len(),
        rank_bound,
        calls: solver.calls(),
        judged,
        lemmas,
        solve_seconds: solver.seconds(),
        confirm_seconds,
        seconds: clock.elapsed().as_secs_f64(),
    });
    Ok(synthesis)
}

/// The certified lower bound of `defender` (solved by `solver`), which
/// must be positive (or exactly 1 in almost-sure mode).
fn certify(
    game: &Posg,
    dra_not_phi: &Dra,
    defender: &Fsc,
    mode: Mode,
    solver: &SolverSettings,
) -> Result<f64, SynthesisError> {
    let bound = lower_bound_within(game, dra_not_phi, defender, solver)?;
    let agrees = match mode {
        Mode::Positive => bound.qualitative.is_positive(),
        Mode::AlmostSure => bound.qualitative == Qualitative::One,
    };
    if !agrees {
        return Err(SynthesisError::Internal(format!(
            "SAT found a {} support, but certification gives the lower bound {} ({:?})",
            mode.name(),
            bound.value,
            bound.qualitative
        )));
    }
    Ok(bound.value)
}

/// Writes the certificate formula (support, edges, certificates, claim) in
/// DIMACS CNF, with the support variables listed in a comment line
/// `c support x_1 x_2 ...` in the order `((g * |O| + o) * N + g') * |U| + u`.
pub fn write_dimacs(
    game: &Posg,
    dra: &Dra,
    defender_nodes: usize,
    settings: &Settings,
    out: &mut impl std::io::Write,
) -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    settings.validate()?;
    check_nodes(defender_nodes)?;
    let problem = Problem::new(game, dra, defender_nodes, settings);
    let (moves, pairs, rank_bound) = (&problem.moves, problem.pairs(dra), problem.rank_bound);
    let context = problem.context(game);
    let mut cnf = Cnf::new(settings.clause_budget);
    let mut vars = SupportVariables::new(&mut cnf, game, moves, defender_nodes)?;
    certificate_formula(&context, &mut cnf, &mut vars, &pairs, settings, rank_bound)?;
    let variables: Vec<String> = vars.support.iter().map(ToString::to_string).collect();
    let comments = vec![
        format!(
            "posg-fsc {} support synthesis, {} nodes, mode {}, rank bound {}",
            env!("CARGO_PKG_VERSION"),
            defender_nodes,
            settings.mode.name(),
            rank_bound
        ),
        format!("support {}", variables.join(" ")),
    ];
    cnf.write_dimacs(out, &comments)?;
    Ok(())
}

fn check_nodes(defender_nodes: usize) -> Result<(), ModelError> {
    if defender_nodes == 0 {
        return Err(ModelError::new(
            "defender nodes",
            "a controller needs at least one node",
        ));
    }
    Ok(())
}

/// The pairs `(L_i, K_i)` with a cycle through a `K_i` cell that avoids
/// Adds the certificate formula to `cnf`: one certificate per pair and the
/// claim on the initial states for `settings.mode` (module documentation).
fn certificate_formula(
    context: &Context,
    cnf: &mut Cnf,
    vars: &mut SupportVariables,
    pairs: &[&RabinPair],
    settings: &Settings,
    rank_bound: usize,
) -> Result<(), SynthesisError> {
    let certificates = encoding::certificates(
        context,
        cnf,
        vars,
        pairs,
        settings.mode.claim(),
        settings.rank_encoding,
        rank_bound,
        None,
    )?;
    encoding::claim_initial(context, cnf, &certificates, settings.mode.claim())
}

/// What both the search and the DIMACS export build first: the game's
/// transitions, the cell graph, and the rank bound.
struct Problem {
    moves: Moves,
    graph: CellGraph,
    nodes: usize,
    /// Product states `(s, q, g)` of the certificate formula.
    product_states: usize,
    /// The bound on levels and ranks (the number of product states unless
    /// the settings lower it).
    rank_bound: usize,
}

impl Problem {
    fn new(game: &Posg, dra: &Dra, nodes: usize, settings: &Settings) -> Self {
        let moves = Moves::of(game);
        let graph = CellGraph::build(game, dra, &moves);
        let product_states = graph.num_cells() * nodes;
        let rank_bound = settings
            .rank_bound
            .unwrap_or(product_states)
            .clamp(1, product_states.max(1));
        Self {
            moves,
            graph,
            nodes,
            product_states,
            rank_bound,
        }
    }

    /// The Rabin pairs of `dra` that can hold ([`usable_pairs`]).
    fn pairs<'d>(&self, dra: &'d Dra) -> Vec<&'d RabinPair> {
        usable_pairs(&self.graph, dra.pairs())
    }

    fn context<'a>(&'a self, game: &'a Posg) -> Context<'a> {
        Context {
            game,
            moves: &self.moves,
            graph: &self.graph,
            nodes: self.nodes,
        }
    }
}

/// `L_i` in the cell graph (every cell is reachable): the others can never
/// be satisfied.
fn usable_pairs<'a>(graph: &CellGraph, pairs: &'a [RabinPair]) -> Vec<&'a RabinPair> {
    pairs
        .iter()
        .filter(|pair| {
            let avoiding: Vec<bool> = graph.cells.iter().map(|&(_, q)| !pair.fin[q]).collect();
            graph
                .on_cycle(&avoiding)
                .iter()
                .zip(&graph.cells)
                .any(|(&cycle, &(_, q))| cycle && pair.inf[q])
        })
        .collect()
}

/// Enlarges a winning support to an inclusion-maximal one with `find`
/// (a winning support satisfying the assumptions, if any): first all
/// entries at once, then each absent entry with the kept ones assumed. If
/// `kept + {c}` cannot win, no superset of `kept` with `c` can either
/// (assumptions only restrict), so the result is inclusion-maximal.
/// Entries fixed to [`FALSE`] (actions not enabled) are never candidates.
fn maximise(
    mut kept: Vec<bool>,
    mut find: impl FnMut(&[Lit]) -> Result<Option<Vec<bool>>, SynthesisError>,
    support: &[Lit],
) -> Result<Vec<bool>, SynthesisError> {
    let free: Vec<Lit> = support.iter().copied().filter(|&x| x != FALSE).collect();
    if let Some(all) = find(&free)? {
        return Ok(all);
    }
    for candidate in 0..support.len() {
        if kept[candidate] || support[candidate] == FALSE {
            continue;
        }
        let assumptions: Vec<Lit> = support
            .iter()
            .zip(&kept)
            .filter(|&(_, &k)| k)
            .map(|(&x, _)| x)
            .chain(std::iter::once(support[candidate]))
            .collect();
        if let Some(larger) = find(&assumptions)? {
            kept = larger;
        }
    }
    Ok(kept)
}

/// The defender with `nodes` nodes, uniform on the support `present`
/// (indexed as [`SupportVariables::support`]), starting in node 0.
fn defender_on(
    game: &Posg,
    nodes: usize,
    vars: &SupportVariables,
    present: &[bool],
) -> Result<Fsc, ModelError> {
    let player = game.defender();
    let (no, nu) = (player.num_observations(), player.num_actions());
    let mut blocks = Vec::with_capacity(nodes * no);
    for g in 0..nodes {
        for o in 0..no {
            let entries: Vec<(usize, usize)> = (0..nodes)
                .flat_map(|next| (0..nu).map(move |u| (next, u)))
                .filter(|&(next, u)| present[vars.index(g, o, next, u)])
                .collect();
            let p = 1.0 / entries.len() as f64;
            blocks.push(
                entries
                    .into_iter()
                    .map(|(next, action)| Choice {
                        next,
                        action,
                        probability: p,
                        logit: None,
                    })
                    .collect(),
            );
        }
    }
    let mut initial = vec![0.0; nodes];
    initial[0] = 1.0;
    Fsc::new(Role::Defender, nodes, no, nu, initial, blocks)
}
