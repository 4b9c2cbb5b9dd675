//! Structural pruning: the paper's Algorithm 1 ("Generate candidate FSCs")
//! and Algorithm 2 ("Recurrent states to visit in steady state").
//!
//! With softmax parameters every supported probability stays positive, so
//! the supports alone decide which GMC states are recurrent. For a formula
//! such as `G !unsafe` a full support lets the defender step into `unsafe`
//! with probability 1 and the value is 0 for every parameter. Algorithm 1
//! removes support entries (the indicator `I_*(g', u | g, o)`) so that some
//! state that must be visited infinitely often becomes recurrent.
//!
//! [`prune`] runs Algorithm 1 from given initial structures and returns a
//! [`PruneReport`]: one [`Attempt`] per SCC `C` and Rabin pair `i` it worked
//! on, and the distinct kept [`Structure`]s, each a pair of controllers that
//! are uniform on the kept support. [`good_sets`] is Algorithm 2.
//!
//! Where the paper is ambiguous this module follows method.md section 5:
//!
//! * Lines 12-17 remove, by default, exactly the defender entries
//!   `(g', u | g, o)` through which some adversary choice gives an edge from
//!   `C \ Bad_i` into the chosen bad state; [`PruneSettings::paper_literal`]
//!   removes action `u` under observation `o` for all `g, g'`, as the paper's
//!   text says.
//! * Lines 18-23 (adversary pruning) run only with
//!   [`PruneSettings::prune_adversary`]: a max-min guarantee must not restrict
//!   the adversary.
//! * Line 9's guard is checked before every single removal: a removal that
//!   would leave some block `(g, o)` without options is not made, the loop
//!   ends there and the attempt records a [`LastOptionStop`].
//! * Line 11's sources are `C \ Bad_i` with `Bad_i` as first computed
//!   (lines 5-6), fixed for the whole loop: line 24 shrinks `Bad_i` one state
//!   per round, and taking the shrunken set would make the removals depend
//!   on the order in which bad states are handled. Bad states inside `C` are
//!   therefore never sources; the final recurrence check (line 29) is exact
//!   either way.
//! * Line 29 keeps a structure only if a recurrent `Good_i` state lies in a
//!   BSCC that misses `L_i`: "recurrent" alone would keep structures without
//!   a phi-feasible recurrent set when `K_i` meets `L_i` or the loop stopped
//!   early, contradicting the paper's soundness Proposition.

mod algorithm;
mod equations;
mod good;
mod indicator;

pub use algorithm::prune;
pub use good::{GoodSet, good_sets};

use serde::Serialize;
use thiserror::Error;

use crate::controller::{Fsc, Role};
use crate::game::ModelError;
use crate::product::{GmcState, ProductError};

/// The choices Algorithm 1 leaves open (method.md section 5).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct PruneSettings {
    /// Lines 14-16 as printed: when `(g', u | g, o)` gives an edge into the
    /// chosen bad state, set `I_def(g'_*, u | g_*, o) = 0` for **all** nodes
    /// `g_*, g'_*`. Default `false`: remove only the entries that give the edge.
    pub paper_literal: bool,
    /// Run lines 18-23, which remove adversary entries `(g''_adv, v | h, o')`
    /// for which every defender action reaches the chosen good state.
    /// Default `false`: the adversary keeps its full initial support.
    pub prune_adversary: bool,
}

/// Why Algorithm 1 could not run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PruneError {
    /// A controller was given for the wrong player.
    #[error("the {expected:?} structure is a controller of the {found:?}")]
    Role {
        /// The player the argument is for.
        expected: Role,
        /// The player the controller belongs to.
        found: Role,
    },
    /// The GMC of line 1 or line 27 could not be built.
    #[error(transparent)]
    Product(#[from] ProductError),
    /// A kept structure could not be turned into a controller.
    #[error(transparent)]
    Model(#[from] ModelError),
}

/// Line 9's loop ended because a removal would have left block `(node,
/// observation)` of `player` without any `(g', u)` (the paper's condition
/// `sum_{g',u} I(g', u | g, o) > 0`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LastOptionStop {
    /// The bad state `m' = (s', q', g', h')` being processed (line 10).
    pub bad_state: GmcState,
    /// Whose block would have become empty.
    pub player: Role,
    /// `g` of the block.
    pub node: usize,
    /// `o` of the block.
    pub observation: usize,
    /// The last remaining entry `(g', u)` of the block, which was kept.
    pub entry: (usize, usize),
}

/// Algorithm 1's work on one SCC `C` (line 3) and Rabin pair `i` (line 4)
/// whose `Good_i` is non-empty.
#[derive(Debug, Clone, PartialEq)]
pub struct Attempt {
    /// The SCC's number in the initial GMC (reverse topological order: an
    /// edge between SCCs goes from a higher to a lower number).
    pub scc: usize,
    /// `|C|`.
    pub scc_size: usize,
    /// The Rabin pair `i`.
    pub pair: usize,
    /// `|Bad_i|` after lines 5-6: successors outside `C` and `C`'s states in `L_i`.
    pub bad: usize,
    /// `|Good_i|` of line 7: `C`'s states in `K_i`.
    pub good: usize,
    /// Defender entries removed from the initial support (lines 12-17).
    pub removed_defender: usize,
    /// Adversary entries removed from the initial support (lines 18-23).
    pub removed_adversary: usize,
    /// Why the loop of line 9 ended early, if it did.
    pub stop: Option<LastOptionStop>,
    /// The index in [`PruneReport::structures`] of the resulting structure
    /// if line 29 kept it (some `Good_i` state is recurrent).
    pub structure: Option<usize>,
}

/// A kept structure `(I_def, I_adv)` of line 30, as uniform controllers on it.
#[derive(Debug, Clone, PartialEq)]
pub struct Structure {
    /// The defender controller: uniform over the kept entries of every block,
    /// initial distribution of the initial structure.
    pub defender: Fsc,
    /// The adversary controller, likewise.
    pub adversary: Fsc,
    /// A `Good_i` state that lies in a BSCC missing `L_i` under this
    /// structure, for the first attempt that produced it.
    pub witness: GmcState,
    /// The attempts (indices into [`PruneReport::attempts`]) that produced it.
    pub attempts: Vec<usize>,
}

/// What Algorithm 1 returned, and how.
#[derive(Debug, Clone, PartialEq)]
pub struct PruneReport {
    /// The settings used.
    pub settings: PruneSettings,
    /// States of the initial GMC (line 1), reachable from its initial distribution.
    pub gmc_states: usize,
    /// The number of SCCs of the initial GMC (line 3).
    pub sccs: usize,
    /// Pairs `(C, i)` skipped because `Good_i` is empty: line 29 cannot hold.
    pub skipped: usize,
    /// One entry per `(C, i)` with a non-empty `Good_i`, in the order run.
    pub attempts: Vec<Attempt>,
    /// The set `I` of line 30: distinct kept structures.
    pub structures: Vec<Structure>,
}

impl PruneReport {
    /// The attempts whose loop ended at line 9's guard, with their stop.
    pub fn stops(&self) -> impl Iterator<Item = (&Attempt, &LastOptionStop)> {
        self.attempts
            .iter()
            .filter_map(|a| a.stop.as_ref().map(|s| (a, s)))
    }
}
