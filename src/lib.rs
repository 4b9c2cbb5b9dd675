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
//! Data flows one way:
//!
//! * [`game`] and [`controller`]: the model and its files;
//! * [`ltl`] and [`automaton`]: formulas, their translation to deterministic
//!   Rabin automata, and HOA input/output;
//! * [`product`]: the GMC in compressed sparse row form, built once per
//!   support structure and refilled in place for new probabilities;
//! * [`graph`]: strongly connected components, BSCCs, phi-feasibility and the
//!   target sets `B`, `Z`, `T` (method.md section 1);
//! * [`solver`]: sparse LU solves of `(I - Q) x = b` and its transpose;
//! * [`value`]: the exact value and its adjoint gradient (method.md sections 1-2);
//!   [`sensitivity`]: the same gradient by forward sensitivities, one solve
//!   per parameter (a reference for comparison);
//! * [`optimise`]: softmax parameters, alternating projected gradient
//!   ascent-descent and best-response checks (method.md sections 3-4);
//! * [`output`]: observers and plots that write the optimiser's results;
//! * [`limits`]: the resource budget checked before large allocations;
//! * [`mdp`] and [`certify`]: MDP analysis (maximal end components, Rabin
//!   acceptance, maximum reachability) and the two certified bounds of
//!   method.md section 6; [`strategy`]: their strategies as files, read
//!   back and, where the free player observes the state, as controllers;
//! * [`synthesis`]: defender supports that win positively or almost surely
//!   against the certification adversary, found by SAT (method.md section 7).
#![warn(missing_docs)]

pub mod analysis;
pub mod automaton;
pub mod certify;
pub mod controller;
pub mod export;
pub mod game;
pub mod graph;
mod interner;
pub mod limits;
pub mod ltl;
pub mod mdp;
pub mod optimise;
pub mod output;
pub mod product;
pub mod prune;
pub mod sensitivity;
pub mod simulate;
pub mod solver;
pub mod strategy;
pub mod synthesis;
pub mod value;
