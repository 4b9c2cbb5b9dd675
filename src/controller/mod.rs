//! Finite-state controllers (FSCs): the paper's `C_* = (G_*, mu_*)` with
//! `mu_*(g', u | g, o)`, a distribution over (next node, action) for each
//! (node, observation) pair, and an initial node distribution.
//!
//! [`Fsc`] holds a controller's probabilities on its support (the paper's
//! indicator `I_*(g', u | g, o)`); [`file`](mod@file) reads and writes `*.fsc.json`
//! (formats.md section 2) and the `uniform:K` shorthand.

pub mod file;
mod mixture;
mod support;

pub(crate) use mixture::Mixture;
pub use support::{Probabilities, Support};

use crate::game::{ModelError, Player, Posg, check_total, rescale_by};

/// Which player a controller belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// The maximising player.
    Defender,
    /// The minimising player.
    Adversary,
}

impl Role {
    /// The other player.
    pub fn other(self) -> Self {
        match self {
            Self::Defender => Self::Adversary,
            Self::Adversary => Self::Defender,
        }
    }

    /// The game's player of this role: its actions, observations and
    /// observation distributions `O_*(o | s)`.
    pub fn player(self, game: &Posg) -> &Player {
        match self {
            Self::Defender => game.defender(),
            Self::Adversary => game.adversary(),
        }
    }

    /// `defender` or `adversary`, as the role is written in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Defender => "defender",
            Self::Adversary => "adversary",
        }
    }
}

/// One supported choice `(g', u)` of a (node, observation) block with its
/// probability `mu(g', u | g, o) > 0` and, optionally, the softmax logit it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice {
    /// `g'`, the next node.
    pub next: usize,
    /// `u`, the action (index into the player's actions).
    pub action: usize,
    /// `mu(g', u | g, o)`.
    pub probability: f64,
    /// The softmax parameter `phi_{g',u|g,o}`, if recorded.
    pub logit: Option<f64>,
}

/// A finite-state controller for one player of a game with `num_observations`
/// observations: blocks `(g, o)` in order `g * num_observations + o`, each a
/// non-empty list of [`Choice`]s with distinct `(next, action)` whose
/// probabilities sum to 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Fsc {
    pub(crate) role: Role,
    pub(crate) num_nodes: usize,
    pub(crate) num_observations: usize,
    pub(crate) num_actions: usize,
    pub(crate) initial: Vec<f64>,
    pub(crate) blocks: Vec<Vec<Choice>>,
}

impl Fsc {
    /// Builds a controller after checking that every block is a distribution
    /// over valid `(next, action)` pairs; `blocks[g * num_observations + o]`.
    /// The initial distribution and each block must sum to 1 within
    /// [`crate::game::DISTRIBUTION_TOLERANCE`] (an error names the node, the
    /// observation and the sum) and are then rescaled to sum to 1.
    pub fn new(
        role: Role,
        num_nodes: usize,
        num_observations: usize,
        num_actions: usize,
        initial: Vec<f64>,
        blocks: Vec<Vec<Choice>>,
    ) -> Result<Self, ModelError> {
        let mut fsc = Self {
            role,
            num_nodes,
            num_observations,
            num_actions,
            initial,
            blocks,
        };
        fsc.check()?;
        fsc.rescale();
        Ok(fsc)
    }

    /// Divides the initial distribution and every block by their sums, which
    /// [`Self::check`] found within [`crate::game::DISTRIBUTION_TOLERANCE`]
    /// of 1, so that each sums to 1 exactly (formats.md section 1).
    fn rescale(&mut self) {
        if let Some(total) = rescale_by(self.initial.iter().sum(), self.initial.len()) {
            self.initial.iter_mut().for_each(|p| *p /= total);
        }
        for block in &mut self.blocks {
            let total = block.iter().map(|c| c.probability).sum();
            if let Some(total) = rescale_by(total, block.len()) {
                block.iter_mut().for_each(|c| c.probability /= total);
            }
        }
    }

    /// The controller with `num_nodes` nodes that starts in node 0 and is
    /// uniform over all `(next node, action)` pairs in every block (`uniform:K`).
    /// Check the size first with [`Fsc::check_uniform_size`]: `num_nodes`
    /// must be at least 1.
    pub fn uniform(
        role: Role,
        num_nodes: usize,
        num_observations: usize,
        num_actions: usize,
    ) -> Self {
        let pairs = num_nodes * num_actions;
        let block: Vec<Choice> = (0..num_nodes)
            .flat_map(|next| {
                (0..num_actions).map(move |action| Choice {
                    next,
                    action,
                    probability: 1.0 / pairs as f64,
                    logit: None,
                })
            })
            .collect();
        let mut initial = vec![0.0; num_nodes];
        initial[0] = 1.0;
        Self {
            role,
            num_nodes,
            num_observations,
            num_actions,
            initial,
            blocks: vec![block; num_nodes * num_observations],
        }
    }

    /// Checks that a full-support controller of `num_nodes` nodes can be
    /// built: at least one node, and at most
    /// [`crate::limits::MAX_CONTROLLER_CHOICES`] choices in all. `input`
    /// names what asked for it (`uniform:K`, `--def-nodes`, a file).
    pub fn check_uniform_size(
        input: &str,
        num_nodes: usize,
        num_observations: usize,
        num_actions: usize,
    ) -> Result<(), ModelError> {
        if num_nodes == 0 {
            return Err(ModelError::new(
                input,
                "a controller needs at least one node, not 0",
            ));
        }
        match crate::limits::uniform_controller(num_nodes, num_observations, num_actions) {
            Some(message) => Err(ModelError::new(input, message)),
            None => Ok(()),
        }
    }

    /// The controller with `num_nodes` nodes for `player` that starts in
    /// node 0 and, in every block `(g, o)`, is uniform over the pairs
    /// `(next node, action)` with the action enabled under `o`
    /// ([`Player::action_enabled`]); [`Fsc::uniform`] when every action is
    /// enabled everywhere.
    pub fn uniform_enabled(role: Role, num_nodes: usize, player: &Player) -> Self {
        let mut fsc = Self::uniform(
            role,
            num_nodes,
            player.num_observations(),
            player.num_actions(),
        );
        if player.restricts_actions() {
            for (b, block) in fsc.blocks.iter_mut().enumerate() {
                let o = b % player.num_observations();
                block.retain(|c| player.action_enabled(o, c.action));
                let probability = 1.0 / block.len() as f64;
                block.iter_mut().for_each(|c| c.probability = probability);
            }
        }
        fsc
    }

    /// Checks that the controller fits `player`: the same numbers of
    /// observations and actions, and positive probability only on actions
    /// enabled under the block's observation (formats.md section 6).
    pub fn check_fits(&self, player: &Player) -> Result<(), String> {
        if self.num_observations != player.num_observations() {
            return Err(format!(
                "it has {} observations, the game's player {}",
                self.num_observations,
                player.num_observations()
            ));
        }
        if self.num_actions != player.num_actions() {
            return Err(format!(
                "it has {} actions, the game's player {}",
                self.num_actions,
                player.num_actions()
            ));
        }
        for (b, block) in self.blocks.iter().enumerate() {
            let (g, o) = (b / self.num_observations, b % self.num_observations);
            if let Some(c) = block.iter().find(|c| !player.action_enabled(o, c.action)) {
                return Err(format!(
                    "node {g}, observation `{}` plays action `{}`, which that observation does not enable",
                    player.observations()[o],
                    player.actions()[c.action]
                ));
            }
        }
        Ok(())
    }

    fn check(&self) -> Result<(), ModelError> {
        let here = |what: String| ModelError::new(format!("{:?} controller", self.role), what);
        if self.num_nodes == 0 {
            return Err(here("a controller needs at least one node".into()));
        }
        if self.initial.len() != self.num_nodes {
            return Err(here(format!(
                "initial has {} entries for {} nodes",
                self.initial.len(),
                self.num_nodes
            )));
        }
        check_distribution(self.initial.iter().copied())
            .map_err(|m| here(format!("initial: {m}")))?;
        if self.blocks.len() != self.num_nodes * self.num_observations {
            return Err(here("one block per (node, observation) is required".into()));
        }
        for (b, block) in self.blocks.iter().enumerate() {
            let (g, o) = (b / self.num_observations, b % self.num_observations);
            let at = |m: String| here(format!("node {g}, observation {o}: {m}"));
            if block.is_empty() {
                return Err(at("no choice has positive probability".into()));
            }
            for (i, c) in block.iter().enumerate() {
                if c.next >= self.num_nodes || c.action >= self.num_actions {
                    return Err(at(format!(
                        "choice ({}, {}) out of range",
                        c.next, c.action
                    )));
                }
                if c.probability.is_nan() || c.probability <= 0.0 {
                    return Err(at(format!(
                        "choice ({}, {}) has probability {}",
                        c.next, c.action, c.probability
                    )));
                }
                if block[..i]
                    .iter()
                    .any(|d| (d.next, d.action) == (c.next, c.action))
                {
                    return Err(at(format!(
                        "choice ({}, {}) listed twice",
                        c.next, c.action
                    )));
                }
            }
            check_distribution(block.iter().map(|c| c.probability)).map_err(at)?;
        }
        Ok(())
    }

    /// The player this controller is for.
    pub fn role(&self) -> Role {
        self.role
    }

    /// `|G_*|`.
    pub fn num_nodes(&self) -> usize {
        self.num_nodes
    }

    /// The number of observations of the player.
    pub fn num_observations(&self) -> usize {
        self.num_observations
    }

    /// The number of actions of the player.
    pub fn num_actions(&self) -> usize {
        self.num_actions
    }

    /// The initial node distribution.
    pub fn initial(&self) -> &[f64] {
        &self.initial
    }

    /// The supported choices of block `(g, o)`: `mu(. | g, o)`.
    pub fn choices(&self, g: usize, o: usize) -> &[Choice] {
        &self.blocks[g * self.num_observations + o]
    }
}

/// Checks that finite, non-negative weights sum to 1 within
/// [`crate::game::DISTRIBUTION_TOLERANCE`] (formats.md section 1).
pub(crate) fn check_distribution(weights: impl Iterator<Item = f64>) -> Result<(), String> {
    let mut total = 0.0;
    for w in weights {
        if !w.is_finite() || !(0.0..=1.0).contains(&w) {
            return Err(format!("probability {w} is not in [0, 1]"));
        }
        total += w;
    }
    check_total(total, total, "probabilities")
}
