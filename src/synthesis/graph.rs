//! The game x automaton graph over which supports are synthesised.
//!
//! The certification adversary (method.md section 6) sees `(s, q, g)`. The
//! defender's support decides which nodes `g'` and actions `u` can follow,
//! so the encoding works on every *cell* `(s, q)` reachable from the
//! initial cells in the game x automaton graph under all actions of both
//! players, times every defender node. For a cell and an adversary action
//! `v` the possible next game states are the union over `u` of the supports
//! of `T(. | s, u, v)`; the automaton then moves to `q' = delta(q, L(s'))`.

use rustc_hash::FxHashMap;

use crate::automaton::{Dra, RabinPair};
use crate::game::{AdversaryAction, DefenderAction, Posg};
use crate::graph::{Digraph, strongly_connected_components};

/// The game's transitions `(s, v, s')` that some defender action allows:
/// `T(s' | s, u, v) > 0` for some `u`.
#[derive(Debug, Clone)]
pub struct Moves {
    num_adversary_actions: usize,
    /// Per `(s, v)`: `(s', transition)`, sorted by `s'`.
    successors: Vec<Vec<(usize, usize)>>,
    /// Per transition: the defender actions `u` with `T(s' | s, u, v) > 0`.
    actions: Vec<Vec<usize>>,
}

impl Moves {
    /// Numbers the transitions of `game`.
    pub fn of(game: &Posg) -> Self {
        let (nu, nv) = (
            game.defender().num_actions(),
            game.adversary().num_actions(),
        );
        let mut actions: Vec<Vec<usize>> = Vec::new();
        let mut successors = Vec::with_capacity(game.num_states() * nv);
        for s in 0..game.num_states() {
            for v in 0..nv {
                let mut by_next: Vec<(usize, usize)> = (0..nu)
                    .flat_map(|u| {
                        game.transition(s, DefenderAction(u), AdversaryAction(v))
                            .iter()
                            .map(move |&(t, _)| (t, u))
                    })
                    .collect();
                by_next.sort_unstable();
                let mut list: Vec<(usize, usize)> = Vec::new();
                for (next, u) in by_next {
                    match list.last() {
                        Some(&(last, t)) if last == next => actions[t].push(u),
                        _ => {
                            list.push((next, actions.len()));
                            actions.push(vec![u]);
                        }
                    }
                }
                successors.push(list);
            }
        }
        Self {
            num_adversary_actions: nv,
            successors,
            actions,
        }
    }

    /// The next states `s'` of `s` under adversary action `v`, each with
    /// its transition's number.
    pub fn successors(&self, s: usize, v: usize) -> &[(usize, usize)] {
        &self.successors[s * self.num_adversary_actions + v]
    }

    /// The number of transitions.
    pub fn len(&self) -> usize {
        self.actions.len()
    }

    /// The defender actions `u` of transition `t`.
    pub fn actions(&self, t: usize) -> &[usize] {
        &self.actions[t]
    }
}

/// One possible next cell of a cell under an adversary action.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Step {
    /// The next cell's index.
    pub cell: usize,
    /// The transition `(s, v, s')` it comes from ([`Moves`]).
    pub transition: usize,
}

/// The reachable cells `(s, q)` and, per cell and adversary action, the
/// possible next cells.
#[derive(Debug, Clone)]
pub struct CellGraph {
    /// `(s, q)` of each cell.
    pub cells: Vec<(usize, usize)>,
    /// The cells `(s, delta(q_0, L(s)))` with `initial(s) > 0`.
    pub initial: Vec<usize>,
    num_adversary_actions: usize,
    step_offsets: Vec<usize>,
    steps: Vec<Step>,
}

impl CellGraph {
    /// Explores the cells reachable from the initial ones.
    pub fn build(game: &Posg, dra: &Dra, moves: &Moves) -> Self {
        let letters = dra.state_letters(game);
        let nv = game.adversary().num_actions();
        let mut index: FxHashMap<(usize, usize), usize> = FxHashMap::default();
        let mut cells = Vec::new();
        let mut cell_of = |s: usize, q: usize, cells: &mut Vec<(usize, usize)>| {
            *index.entry((s, q)).or_insert_with(|| {
                cells.push((s, q));
                cells.len() - 1
            })
        };
        let initial: Vec<usize> = game
            .initial()
            .iter()
            .map(|&(s, _)| cell_of(s, dra.successor(dra.initial(), letters[s]), &mut cells))
            .collect();
        let mut step_offsets = vec![0];
        let mut steps = Vec::new();
        let mut explored = 0;
        while explored < cells.len() {
            let (s, q) = cells[explored];
            for v in 0..nv {
                for &(next, transition) in moves.successors(s, v) {
                    let cell = cell_of(next, dra.successor(q, letters[next]), &mut cells);
                    steps.push(Step { cell, transition });
                }
                step_offsets.push(steps.len());
            }
            explored += 1;
        }
        Self {
            cells,
            initial,
            num_adversary_actions: nv,
            step_offsets,
            steps,
        }
    }

    /// The number of adversary actions `v`.
    pub fn num_adversary_actions(&self) -> usize {
        self.num_adversary_actions
    }

    /// The number of cells.
    pub fn num_cells(&self) -> usize {
        self.cells.len()
    }

    /// The possible next cells of `cell` under adversary action `v`.
    pub fn steps(&self, cell: usize, v: usize) -> &[Step] {
        let i = cell * self.num_adversary_actions + v;
        &self.steps[self.step_offsets[i]..self.step_offsets[i + 1]]
    }
}

impl CellGraph {
    /// The cells every path from which satisfies the Rabin condition, under
    /// any actions of both players: the union over pairs `j` of the
    /// greatest set of cells outside `L_j`, closed under every step, in
    /// which every cycle meets `K_j`. Computed by alternately removing
    /// cells with a step out of the set and cells on a cycle that avoids
    /// `K_j`, until neither removes anything.
    pub fn surely_accepting(&self, pairs: &[RabinPair]) -> Vec<bool> {
        let n = self.num_cells();
        let mut predecessors: Vec<Vec<usize>> = vec![Vec::new(); n];
        for cell in 0..n {
            for v in 0..self.num_adversary_actions {
                for step in self.steps(cell, v) {
                    predecessors[step.cell].push(cell);
                }
            }
        }
        let mut sure = vec![false; n];
        for pair in pairs {
            let mut keep: Vec<bool> = self.cells.iter().map(|&(_, q)| !pair.fin[q]).collect();
            loop {
                self.close(&mut keep, &predecessors);
                let avoiding: Vec<bool> = (0..n)
                    .map(|c| keep[c] && !pair.inf[self.cells[c].1])
                    .collect();
                let on_cycle = self.on_cycle(&avoiding);
                if !on_cycle.iter().any(|&c| c) {
                    break;
                }
                for (k, c) in keep.iter_mut().zip(on_cycle) {
                    *k &= !c;
                }
            }
            for (s, k) in sure.iter_mut().zip(keep) {
                *s |= k;
            }
        }
        sure
    }

    /// Removes from `keep` every cell with a step out of it, until closed.
    fn close(&self, keep: &mut [bool], predecessors: &[Vec<usize>]) {
        let leaves = |cell: usize, keep: &[bool]| {
            (0..self.num_adversary_actions)
                .any(|v| self.steps(cell, v).iter().any(|step| !keep[step.cell]))
        };
        let mut queue: Vec<usize> = (0..keep.len())
            .filter(|&c| keep[c] && leaves(c, keep))
            .collect();
        for &c in &queue {
            keep[c] = false;
        }
        while let Some(c) = queue.pop() {
            for &p in &predecessors[c] {
                if keep[p] {
                    keep[p] = false;
                    queue.push(p);
                }
            }
        }
    }

    /// The cells of `within` on a cycle of the graph restricted to `within`.
    pub fn on_cycle(&self, within: &[bool]) -> Vec<bool> {
        let view = Within {
            graph: self,
            within,
        };
        let components = strongly_connected_components(&view);
        let mut size = vec![0usize; components.count];
        for &c in &components.component {
            size[c as usize] += 1;
        }
        (0..self.num_cells())
            .map(|cell| {
                within[cell]
                    && (size[components.component[cell] as usize] > 1
                        || view.successors(cell).any(|next| next == cell))
            })
            .collect()
    }
}

/// A cell graph (all actions) restricted to the cells `within`.
struct Within<'a> {
    graph: &'a CellGraph,
    within: &'a [bool],
}

impl Digraph for Within<'_> {
    fn num_vertices(&self) -> usize {
        self.graph.num_cells()
    }

    fn successors(&self, cell: usize) -> impl Iterator<Item = usize> + '_ {
        let inside = self.within[cell];
        (0..self.graph.num_adversary_actions())
            .flat_map(move |v| self.graph.steps(cell, v))
            .map(|step| step.cell)
            .filter(move |&next| inside && self.within[next])
    }
}
