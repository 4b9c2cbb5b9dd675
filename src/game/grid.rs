//! The seed paper's grid family: a defender moves a robot on a `W x H` grid
//! while an adversary may attack (degrade) its actuators; both see the robot's
//! cell through noisy sensors.
//!
//! [`GridSpec`] describes an instance ([`GridSpec::default`] is the paper's
//! 3 x 2 example) and [`GridSpec::build`] writes the [`Posg`] directly into
//! its arrays in `O(W H)` time, so 512 x 512 grids are cheap.
//!
//! The model, for cell `i = x + W y` named `s{i}` and `N(s)` its
//! 4-neighbourhood inside the grid:
//!
//! * defender actions `R` (x + 1), `L` (x - 1), `U` (y - 1), `D` (y + 1);
//!   adversary actions `A` (attack) and `NA` (no attack);
//! * `T(s' | s, u, v)`: let `t` be the cell `u` moves to. If `t` is outside
//!   the grid, `s' = s` with probability 1. Otherwise `s' = t` with
//!   probability `p_v` (`p_NA`, `p_A`) and every cell of
//!   `({s} ∪ N(s)) \ {t}` (there are `|N(s)|` of them) gets
//!   `(1 - p_v) / |N(s)|`. On a 1 x 1 grid `N(s)` is empty, so every move
//!   leaves the grid and the robot stays put: no division by `|N(s)|` happens;
//! * observations ([`ObservationModel`]): a player with sensor accuracy
//!   `p_obs` sees either a cell name (the true cell with probability `p_obs`,
//!   otherwise a uniformly random cell of `N(s)`; with `N(s)` empty the true
//!   cell with probability 1) or the paper's literal two symbols
//!   `correct` / `wrong` with `O(correct | s) = p_obs`;
//! * labels `unsafe` and `goal` on the given cells plus any extra labels, and
//!   the initial distribution puts probability 1 on the initial cell.
//!
//! Zero probabilities (e.g. `p_v = 1`) are dropped, as in every [`Posg`].

use rand::SeedableRng;
use rand::seq::index::sample;
use rand_chacha::ChaCha8Rng;

use super::reading::is_valid_proposition;
use super::{Distribution, ModelError, Player, Posg};

/// What the players observe of the robot's cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ObservationModel {
    /// Observations are cell names: the true cell with probability `p_obs`,
    /// otherwise a uniformly random cell of `N(s)`.
    #[default]
    Neighbourhood,
    /// The paper's literal model: two observations, `correct` with
    /// probability `p_obs` and `wrong` otherwise, whatever the cell.
    Blind,
}

/// Unsafe cells placed at random, reproducibly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RandomUnsafe {
    /// How many cells to add to the unsafe set.
    pub count: usize,
    /// The seed of the `ChaCha8Rng` that picks them.
    pub seed: u64,
}

/// One grid instance. Cells are indices `x + width * y`.
#[derive(Debug, Clone, PartialEq)]
pub struct GridSpec {
    /// `W`, the number of columns (at least 1).
    pub width: usize,
    /// `H`, the number of rows (at least 1).
    pub height: usize,
    /// Cells labelled `unsafe`.
    pub unsafe_cells: Vec<usize>,
    /// Cells labelled `goal`.
    pub goal_cells: Vec<usize>,
    /// More labels: `(proposition, cells)`; propositions match
    /// `[a-z_][a-z0-9_]*` and differ from `unsafe`, `goal` and each other.
    pub extra_labels: Vec<(String, Vec<usize>)>,
    /// The initial cell (probability 1).
    pub initial: usize,
    /// `p_NA`: the probability that a move succeeds when not attacked.
    pub p_na: f64,
    /// `p_A`: the probability that a move succeeds under attack.
    pub p_a: f64,
    /// The defender's sensor accuracy `p_obs`.
    pub defender_p_obs: f64,
    /// The adversary's sensor accuracy `p_obs`.
    pub adversary_p_obs: f64,
    /// What both players observe.
    pub observation: ObservationModel,
    /// Unsafe cells added at random, never on the initial cell, a goal cell
    /// or an already unsafe cell.
    pub random_unsafe: Option<RandomUnsafe>,
}

impl Default for GridSpec {
    /// The paper's instance: 3 x 2, unsafe `s4`, goal `s5`, start `s0`,
    /// `p_NA = 0.8`, `p_A = 0.6`, `p_obs` 0.8 (defender) and 0.6 (adversary).
    fn default() -> Self {
        Self {
            width: 3,
            height: 2,
            unsafe_cells: vec![4],
            goal_cells: vec![5],
            extra_labels: Vec::new(),
            initial: 0,
            p_na: 0.8,
            p_a: 0.6,
            defender_p_obs: 0.8,
            adversary_p_obs: 0.6,
            observation: ObservationModel::Neighbourhood,
            random_unsafe: None,
        }
    }
}

/// Defender actions and their moves `(dx, dy)`.
const MOVES: [(&str, isize, isize); 4] = [("R", 1, 0), ("L", -1, 0), ("U", 0, -1), ("D", 0, 1)];

impl GridSpec {
    /// The `side x side` grid of the paper's family used for scaling: the
    /// unsafe cell `(1, 1)` (`s(side + 1)`), the goal in the far corner, the
    /// start `s0`, the paper's probabilities.
    pub fn square(side: usize) -> Self {
        Self {
            width: side,
            height: side,
            unsafe_cells: vec![side + 1],
            goal_cells: vec![side * side - 1],
            ..Self::default()
        }
    }

    /// The number of cells `W H`.
    pub fn num_cells(&self) -> usize {
        self.width * self.height
    }

    /// Builds the game after checking the spec (sizes, cells in range,
    /// probabilities in [0, 1], label names, room for the random unsafe cells).
    pub fn build(&self) -> Result<Posg, ModelError> {
        self.check()?;
        let cells = self.num_cells();
        let neighbours: Vec<Vec<usize>> = (0..cells).map(|c| self.neighbours(c)).collect();
        let (propositions, labels) = self.labels()?;
        let (transition_offsets, transition_entries) = self.transitions(&neighbours);
        Ok(Posg {
            name: Some(format!("grid-{}x{}", self.width, self.height)),
            states: (0..cells).map(|i| format!("s{i}")).collect(),
            initial: vec![(self.initial, 1.0)],
            propositions,
            labels,
            defender: Player {
                actions: MOVES.iter().map(|m| m.0.to_string()).collect(),
                ..self.player(self.defender_p_obs, &neighbours)
            },
            adversary: Player {
                actions: vec!["A".to_string(), "NA".to_string()],
                ..self.player(self.adversary_p_obs, &neighbours)
            },
            has_adversary: true,
            transition_offsets,
            transition_entries,
            rewards: Vec::new(),
        })
    }

    fn check(&self) -> Result<(), ModelError> {
        let err = |m: String| Err(ModelError::new("grid", m));
        if self.width == 0 || self.height == 0 {
            return err(format!(
                "a {}x{} grid has no cells",
                self.width, self.height
            ));
        }
        if let Some(message) = self.size_exceeded() {
            return err(message);
        }
        let named = [
            ("initial", std::slice::from_ref(&self.initial)),
            ("unsafe", &self.unsafe_cells[..]),
            ("goal", &self.goal_cells[..]),
        ];
        let extra = self.extra_labels.iter().map(|(n, c)| (n.as_str(), &c[..]));
        for (what, cells) in named.into_iter().chain(extra) {
            if let Some(c) = cells.iter().find(|&&c| c >= self.num_cells()) {
                return err(format!(
                    "{what} cell {c} is outside the {} cells",
                    self.num_cells()
                ));
            }
        }
        let probabilities = [
            ("p_na", self.p_na),
            ("p_a", self.p_a),
            ("defender p_obs", self.defender_p_obs),
            ("adversary p_obs", self.adversary_p_obs),
        ];
        for (what, p) in probabilities {
            if !(0.0..=1.0).contains(&p) {
                return err(format!("{what} = {p} is not in [0, 1]"));
            }
        }
        Ok(())
    }

    /// `Some(message)` when the grid is larger than the limits of every
    /// game ([`crate::limits`]): its `W H` cells times 4 defender and 2
    /// adversary actions against the transition triples, and the at most 5
    /// successors of each triple against the transition entries. Checked
    /// before anything of the grid's size is allocated.
    fn size_exceeded(&self) -> Option<String> {
        let cells = (self.width as u128).saturating_mul(self.height as u128);
        let cells = usize::try_from(cells).unwrap_or(usize::MAX);
        let triples = crate::limits::transition_triples(cells, MOVES.len(), 2);
        let entries = || {
            crate::limits::exceeded(
                &format!("{cells} cells"),
                (cells as u128).saturating_mul(MOVES.len() as u128 * 2 * 5),
                crate::limits::MAX_TRANSITION_ENTRIES,
                "transition entries",
                "MAX_TRANSITION_ENTRIES",
            )
        };
        let message = triples.or_else(entries)?;
        Some(format!("a {}x{} grid: {message}", self.width, self.height))
    }

    /// `N(c)`: the cells one step right, left, up and down of `c` inside the grid.
    fn neighbours(&self, c: usize) -> Vec<usize> {
        MOVES
            .iter()
            .filter_map(|&(_, dx, dy)| self.step(c, dx, dy))
            .collect()
    }

    /// The cell `(dx, dy)` away from `c`, if inside the grid.
    fn step(&self, c: usize, dx: isize, dy: isize) -> Option<usize> {
        let x = (c % self.width).checked_add_signed(dx)?;
        let y = (c / self.width).checked_add_signed(dy)?;
        (x < self.width && y < self.height).then_some(x + self.width * y)
    }

    /// The unsafe cells including the random ones.
    fn all_unsafe_cells(&self) -> Result<Vec<usize>, ModelError> {
        let mut cells = self.unsafe_cells.clone();
        if let Some(random) = self.random_unsafe {
            let mut taken = vec![false; self.num_cells()];
            for &c in cells.iter().chain(&self.goal_cells).chain([&self.initial]) {
                taken[c] = true;
            }
            let candidates: Vec<usize> = (0..self.num_cells()).filter(|&c| !taken[c]).collect();
            if random.count > candidates.len() {
                return Err(ModelError::new(
                    "grid",
                    format!(
                        "{} random unsafe cells requested but only {} cells are free",
                        random.count,
                        candidates.len()
                    ),
                ));
            }
            let mut rng = ChaCha8Rng::seed_from_u64(random.seed);
            cells.extend(
                sample(&mut rng, candidates.len(), random.count)
                    .into_iter()
                    .map(|i| candidates[i]),
            );
        }
        Ok(cells)
    }

    /// The sorted propositions and each cell's label.
    fn labels(&self) -> Result<(Vec<String>, Vec<Vec<usize>>), ModelError> {
        let unsafe_cells = self.all_unsafe_cells()?;
        let mut named: Vec<(&str, &[usize])> = vec![
            ("unsafe", &unsafe_cells[..]),
            ("goal", &self.goal_cells[..]),
        ];
        for (name, cells) in &self.extra_labels {
            if !is_valid_proposition(name) {
                return Err(ModelError::new(
                    "grid",
                    format!("`{name}` is not a valid proposition (expected [a-z_][a-z0-9_]*)"),
                ));
            }
            if named.iter().any(|(n, _)| *n == name.as_str()) {
                return Err(ModelError::new(
                    "grid",
                    format!("label `{name}` is given twice"),
                ));
            }
            named.push((name.as_str(), cells.as_slice()));
        }
        named.retain(|(_, cells)| !cells.is_empty());
        named.sort_by_key(|(n, _)| *n);
        let mut labels = vec![Vec::new(); self.num_cells()];
        for (p, (_, cells)) in named.iter().enumerate() {
            for &c in *cells {
                if labels[c].last() != Some(&p) {
                    labels[c].push(p);
                }
            }
        }
        Ok((named.iter().map(|(n, _)| n.to_string()).collect(), labels))
    }

    /// A player's observations and `O(. | s)`; its actions are filled in by the caller.
    fn player(&self, p_obs: f64, neighbours: &[Vec<usize>]) -> Player {
        let (observations, observe) = match self.observation {
            ObservationModel::Neighbourhood => (
                (0..self.num_cells()).map(|i| format!("s{i}")).collect(),
                neighbours
                    .iter()
                    .enumerate()
                    .map(|(c, n)| spread(c, p_obs, n))
                    .collect(),
            ),
            ObservationModel::Blind => (
                vec!["correct".to_string(), "wrong".to_string()],
                vec![positive(vec![(0, p_obs), (1, 1.0 - p_obs)]); self.num_cells()],
            ),
        };
        Player {
            actions: Vec::new(),
            observations,
            full_observation: false,
            observe,
            enabled: Vec::new(),
            action_labels: Vec::new(),
        }
    }

    /// `T` in the [`Posg`] layout: triples `(s, u, v)` in order, adversary `A` then `NA`.
    fn transitions(&self, neighbours: &[Vec<usize>]) -> (Vec<usize>, Vec<(usize, f64)>) {
        let cells = self.num_cells();
        let mut offsets = Vec::with_capacity(cells * 8 + 1);
        let mut entries = Vec::with_capacity(cells * 8 * 5);
        offsets.push(0);
        for (s, around) in neighbours.iter().enumerate() {
            for &(_, dx, dy) in &MOVES {
                for p_v in [self.p_a, self.p_na] {
                    match self.step(s, dx, dy) {
                        None => entries.push((s, 1.0)),
                        Some(t) => {
                            let mut others = [0; 4];
                            for (o, &c) in others.iter_mut().zip(around) {
                                *o = if c == t { s } else { c };
                            }
                            spread_into(&mut entries, t, p_v, &others[..around.len()]);
                        }
                    }
                    offsets.push(entries.len());
                }
            }
        }
        (offsets, entries)
    }
}

/// `main` with probability `p`, the rest spread evenly over `others` (all of
/// it on `main` when `others` is empty); sorted by cell, zeros dropped.
fn spread(main: usize, p: f64, others: &[usize]) -> Distribution {
    let mut d = Vec::with_capacity(others.len() + 1);
    spread_into(&mut d, main, p, others);
    d
}

/// Appends [`spread`]`(main, p, others)` to `out` without allocating.
fn spread_into(out: &mut Distribution, main: usize, p: f64, others: &[usize]) {
    let start = out.len();
    if others.is_empty() {
        out.push((main, 1.0));
        return;
    }
    let rest = (1.0 - p) / others.len() as f64;
    out.extend(others.iter().map(|&c| (c, rest)));
    out.push((main, p));
    out[start..].sort_unstable_by_key(|&(c, _)| c);
    super::drop_zero_outcomes(out, start);
}

fn positive(d: Distribution) -> Distribution {
    d.into_iter().filter(|&(_, p)| p > 0.0).collect()
}
