//! # posg-fsc
//!
//! Secure control under partial observability: tune a defender's finite-state
//! controller (FSC) so that a partially observable stochastic game (POSG)
//! satisfies an LTL formula `phi` with the highest probability against a
//! worst-case adversary FSC,
//!
//! ```text
//!     max over mu_def   min over mu_adv   P(trace |= phi | mu_def, mu_adv).
//! ```
//!
//! The method is that of Ramasubramanian, Clark, Bushnell and Poovendran,
//! "Secure Control under Partial Observability with Temporal Logic
//! Constraints": the game is composed with a deterministic Rabin automaton for
//! `phi` and with both controllers into a finite Markov chain, the global
//! Markov chain (GMC) on `(s, q, g, h)`; the satisfaction probability is the
//! probability of reaching its phi-feasible bottom strongly connected
//! components.
//!
//! # The public face
//!
//! Data flows one way through a handful of modules:
//!
//! * [`game`] and [`controller`]: the model (the POSG, its players, the
//!   built-in grid family) and the controllers (FSCs, their supports), with
//!   their files (formats.md sections 1, 2 and 6);
//! * [`ltl`] and [`automaton`]: formulas, their translation to deterministic
//!   Rabin automata (DRA), and HOA input/output;
//! * [`value`]: the global Markov chain (GMC) of a game, a DRA and two
//!   controllers ([`value::Gmc`]), its recurrence analysis (the sets `B`,
//!   `Z`, `T` of method.md section 1), the exact value and its adjoint
//!   gradient (sections 1-2) on the sparse solver of [`value::SolverSettings`],
//!   and a Monte Carlo estimate as a check ([`value::simulate`]);
//! * [`prune`]: the paper's structural pruning (Algorithm 1, method.md
//!   section 5);
//! * [`synthesis`]: defender supports that win positively or almost surely
//!   against the certification adversary, found by SAT (method.md section 7);
//! * [`optimise`]: softmax parameters, alternating projected gradient
//!   ascent-descent and best-response checks (method.md sections 3-4);
//! * [`pipeline`]: the main job end to end (structures, optimisation, the
//!   best structure, its certified bracket) and its `solve` directory
//!   ([`pipeline::solve`] has the example game -> solve);
//! * [`certify`]: the two certified bounds of method.md section 6 and their
//!   strategies as files ([`certify::strategy`]);
//! * [`output`]: what the tool writes: curves, plots, controller drawings,
//!   sweep shards and Slurm scripts, and the GMC for Storm and PRISM
//!   ([`output::export`]);
//! * [`limits`]: the resource budget checked before large allocations.
//!
//! The graph algorithms, the MDP analysis behind the certificates and the
//! linear solvers' internals are private to the crate.
//!
//! # The value of a controller pair
//!
//! ```
//! use posg_fsc::controller::{Fsc, Role};
//! use posg_fsc::game::grid::GridSpec;
//! use posg_fsc::value::{SolverSettings, evaluate_controllers};
//!
//! // The seed paper's 3x2 grid, and `!unsafe U goal` as a Rabin automaton.
//! let game = GridSpec::default().build()?;
//! let dra = posg_fsc::ltl::translate(&posg_fsc::ltl::parse("!unsafe U goal")?)?;
//! // Uniform one-node controllers for both players.
//! let defender = Fsc::uniform_enabled(Role::Defender, 1, game.defender());
//! let adversary = Fsc::uniform_enabled(Role::Adversary, 1, game.adversary());
//! let (_, evaluation) =
//!     evaluate_controllers(&game, &dra, &defender, &adversary, &SolverSettings::default())?;
//! assert!((0.0..=1.0).contains(&evaluation.value));
//! assert!(evaluation.error_bound <= 1e-9);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

mod analysis;
pub mod automaton;
pub mod certify;
pub mod controller;
pub mod game;
mod graph;
mod interner;
pub mod limits;
pub mod ltl;
mod mdp;
pub mod optimise;
pub mod output;
pub mod pipeline;
mod product;
pub mod prune;
pub mod seconds;
mod sensitivity;
mod simulate;
mod solver;
pub mod synthesis;
pub mod value;
