//! The lazy engine: counterexample-guided search over supports.
//!
//! The SAT solver sees only the support variables, the edge literals and
//! the lemmas learnt so far. Each support it proposes is judged exactly by
//! the certification analysis of method.md section 6 ([`crate::certify`]:
//! the adversary's maximum probability of `!phi` on the product with an
//! automaton for `!phi`, the defender uniform on the support). A losing
//! support yields a lemma: a clause over edge literals that is false for it
//! and for every support sharing the adversary's counterexample, so the
//! lemma excludes only losing supports.
//!
//! * **Almost-sure mode** loses when some initial state reaches an accepting
//!   end component `C` of the adversary. The counterexample: a path of
//!   present edges from that state to a state `k` of `C` in `K_j`, and the
//!   closed class `B` of `k` under a memoryless strategy inside `C` that
//!   moves towards `k`. Every support with those path edges, edges spanning
//!   `B` (a tree into `k` and one out of it), and no edge leaving `B` under
//!   the strategy's actions keeps `B` an end component that avoids `L_j` and
//!   meets `K_j`, reachable from the initial state.
//! * **Positive mode** loses when every initial state lies in the
//!   adversary's almost-sure region. The counterexample: the states `Y` its
//!   memoryless strategy reaches from the initial states, the bottom
//!   classes of that chain (each accepting for the adversary), edges
//!   spanning each class, one edge from each other state of `Y` towards the
//!   classes, and no edge leaving `Y` or a class under the strategy. Every
//!   support with those keeps the same classes as the only closed classes
//!   reachable, so the adversary still wins almost surely.
//!
//! Each lemma is false for the support that produced it, so the search
//! never proposes a support twice and ends; since the judge is exact, an
//! unsatisfiable formula proves that no support wins, whatever the number of
//! Rabin pairs.

use rustc_hash::{FxHashMap, FxHashSet};

use super::cnf::{Answer, Cnf, Lit, Solver};
use super::graph::{CellGraph, Moves};
use super::variables::SupportVariables;
use super::{Mode, SynthesisError, defender_on};
use crate::automaton::{Dra, Letter};
use crate::certify::{Analysis, analyse_qualitative};
use crate::controller::Role;
use crate::game::Posg;
use crate::graph::{Digraph, bottom_components, strongly_connected_components};
use crate::mdp::QualitativeReachability;

/// The exact judge of supports and the source of lemmas.
pub struct Oracle<'a> {
    game: &'a Posg,
    dra_not_phi: &'a Dra,
    moves: &'a Moves,
    nodes: usize,
    mode: Mode,
    letters: Vec<Letter>,
    /// The cells `(s, q)` of the game and the automaton for `!phi` from which
    /// every path is accepted ([`CellGraph::surely_accepting`]): reaching
    /// one wins for the adversary whatever the support.
    sure: FxHashSet<(usize, usize)>,
    /// Lemmas learnt so far.
    pub lemmas: usize,
    /// Supports judged so far.
    pub judged: usize,
}

impl<'a> Oracle<'a> {
    /// A judge for `mode` with an automaton for `!phi`.
    pub fn new(
        game: &'a Posg,
        dra_not_phi: &'a Dra,
        moves: &'a Moves,
        nodes: usize,
        mode: Mode,
    ) -> Self {
        let letters = dra_not_phi.state_letters(game);
        let cells = CellGraph::build(game, dra_not_phi, moves);
        let sure = cells
            .surely_accepting(dra_not_phi.pairs())
            .into_iter()
            .zip(&cells.cells)
            .filter(|&(sure, _)| sure)
            .map(|(_, &cell)| cell)
            .collect();
        Self {
            game,
            dra_not_phi,
            moves,
            nodes,
            mode,
            letters,
            sure,
            lemmas: 0,
            judged: 0,
        }
    }

    /// A winning support that satisfies `assumptions` and the formula, or
    /// `None` when there is none: proposes, judges and learns until the
    /// solver runs out of proposals.
    pub fn find(
        &mut self,
        cnf: &mut Cnf,
        vars: &mut SupportVariables,
        solver: &mut Solver,
        assumptions: &[Lit],
    ) -> Result<Option<Vec<bool>>, SynthesisError> {
        loop {
            solver.load(cnf);
            if solver.solve(assumptions)? == Answer::Unsatisfiable {
                return Ok(None);
            }
            let support: Vec<bool> = vars.support.iter().map(|&x| solver.value(x)).collect();
            match self.judge(cnf, vars, &support)? {
                None => return Ok(Some(support)),
                Some(lemma) => {
                    cnf.clause(lemma)?;
                    self.lemmas += 1;
                }
            }
        }
    }

    /// `None` when `support` wins in the oracle's mode, otherwise a lemma
    /// that is false for it and for every support sharing its counterexample.
    fn judge(
        &mut self,
        cnf: &mut Cnf,
        vars: &mut SupportVariables,
        support: &[bool],
    ) -> Result<Option<Vec<Lit>>, SynthesisError> {
        self.judged += 1;
        let defender = defender_on(self.game, self.nodes, vars, support)?;
        let analysis = analyse_qualitative(self.game, self.dra_not_phi, &defender, Role::Defender)?;
        let result = &analysis.result;
        let wins = match self.mode {
            Mode::Positive => analysis
                .initial
                .iter()
                .any(|&(m, _)| !result.almost_sure[m]),
            Mode::AlmostSure => analysis.initial.iter().all(|&(m, _)| !result.possible[m]),
        };
        if wins {
            return Ok(None);
        }
        let mut lemma = LemmaBuilder {
            oracle: self,
            analysis: &analysis,
            index: analysis
                .states
                .iter()
                .enumerate()
                .map(|(m, &key)| (key, m))
                .collect(),
            cnf,
            vars,
            literals: Vec::new(),
        };
        let complete = match self.mode {
            Mode::AlmostSure => lemma.reachable_end_component()?,
            Mode::Positive => lemma.almost_sure_attack()?,
        };
        let mut literals = lemma.literals;
        if !complete {
            literals = block(vars, support);
        }
        Ok(Some(literals))
    }
}

/// The clause that excludes exactly `support`.
fn block(vars: &SupportVariables, support: &[bool]) -> Vec<Lit> {
    vars.support
        .iter()
        .zip(support)
        .map(|(&x, &present)| if present { -x } else { x })
        .collect()
}

/// One edge a support may have from a product state under an adversary
/// action.
#[derive(Debug, Clone, Copy)]
struct PotentialEdge {
    /// The target's index in the analysed product, if it has one.
    target: Option<usize>,
    /// Whether the current support has the edge.
    present: bool,
    /// The game state `s` of the source.
    s: usize,
    /// The transition `(s, v, s')`.
    transition: usize,
    /// The nodes `g -> g'`.
    nodes: (usize, usize),
}

/// Collects a lemma's literals from the analysis of a losing support.
struct LemmaBuilder<'o, 'a, 'c> {
    oracle: &'o Oracle<'a>,
    analysis: &'o Analysis<QualitativeReachability>,
    index: FxHashMap<(usize, usize, usize), usize>,
    cnf: &'c mut Cnf,
    vars: &'c mut SupportVariables,
    literals: Vec<Lit>,
}

impl LemmaBuilder<'_, '_, '_> {
    /// Every edge a support may have from product state `m` under the
    /// free player's MDP action `v` (the game action `free_actions[s][v]`).
    fn potential_edges(&self, m: usize, v: usize) -> Vec<PotentialEdge> {
        let (s, q, g) = self.analysis.states[m];
        let present: Vec<usize> = self
            .analysis
            .mdp
            .distribution(m, v)
            .iter()
            .map(|&(t, _)| t)
            .collect();
        let dra = self.oracle.dra_not_phi;
        let mut edges = Vec::new();
        let action = self.analysis.free_actions[s][v];
        for &(next_state, transition) in self.oracle.moves.successors(s, action) {
            let q_next = dra.successor(q, self.oracle.letters[next_state]);
            for next in 0..self.oracle.nodes {
                let target = self.index.get(&(next_state, q_next, next)).copied();
                edges.push(PotentialEdge {
                    target,
                    present: target.is_some_and(|t| present.contains(&t)),
                    s,
                    transition,
                    nodes: (g, next),
                });
            }
        }
        edges
    }

    fn literal(&mut self, edge: &PotentialEdge) -> Result<Lit, SynthesisError> {
        self.vars.edge(
            self.cnf,
            self.oracle.game,
            self.oracle.moves,
            (edge.s, edge.transition),
            edge.nodes,
        )
    }

    /// The lemma keeps the edge `m -> target` under `v`, which the support has.
    fn keep(&mut self, m: usize, v: usize, target: usize) -> Result<(), SynthesisError> {
        let edge = self
            .potential_edges(m, v)
            .into_iter()
            .find(|e| e.target == Some(target) && e.present);
        match edge {
            Some(edge) => {
                let lit = self.literal(&edge)?;
                self.literals.push(-lit);
                Ok(())
            }
            None => Err(internal("a counterexample edge is not in the product")),
        }
    }

    /// The lemma keeps every edge of `m` under `v` leaving `inside` absent.
    fn seal(&mut self, m: usize, v: usize, inside: &[bool]) -> Result<(), SynthesisError> {
        for edge in self.potential_edges(m, v) {
            if !edge.target.is_some_and(|t| inside[t]) {
                let lit = self.literal(&edge)?;
                self.literals.push(lit);
            }
        }
        Ok(())
    }

    /// Almost-sure mode: a path to an accepting end component and a closed
    /// class inside it (module documentation). Returns whether it was found.
    fn reachable_end_component(&mut self) -> Result<bool, SynthesisError> {
        let analysis = self.analysis;
        let Some(&(start, _)) = analysis
            .initial
            .iter()
            .find(|&&(m, _)| analysis.result.possible[m])
        else {
            return Ok(false);
        };
        let sure = |m: usize| self.is_sure(m);
        if let Some(path) = shortest_path(&analysis.mdp, start, sure) {
            for (m, v, to) in path {
                self.keep(m, v, to)?;
            }
            return Ok(true);
        }
        let n = analysis.states.len();
        let mut in_component = vec![usize::MAX; n];
        for (c, accepting) in analysis.accepting.iter().enumerate() {
            for &m in &accepting.component.states {
                if in_component[m] == usize::MAX {
                    in_component[m] = c;
                }
            }
        }
        let Some(path) = shortest_path(&analysis.mdp, start, |m| in_component[m] != usize::MAX)
        else {
            return Ok(false);
        };
        let entry = path.last().map_or(start, |&(_, _, to)| to);
        let accepting = &analysis.accepting[in_component[entry]];
        let inf = &self.oracle.dra_not_phi.pairs()[accepting.pair].inf;
        let component = &accepting.component;
        let Some(&k) = component
            .states
            .iter()
            .find(|&&m| inf[analysis.states[m].1])
        else {
            return Ok(false);
        };
        let (choice, toward) = attract_within(&analysis.mdp, component, k);
        let (class, discovery) = closure(&analysis.mdp, k, |m| choice[&m]);
        let Some(to_k) = shortest_path(&analysis.mdp, start, |m| m == k) else {
            return Ok(false);
        };
        for (m, v, to) in to_k {
            self.keep(m, v, to)?;
        }
        for (m, v, to) in discovery {
            self.keep(m, v, to)?;
        }
        let mut inside = vec![false; n];
        for &m in &class {
            inside[m] = true;
        }
        for &m in class.iter().filter(|&&m| m != k) {
            self.keep(m, choice[&m], toward[&m])?;
        }
        for &m in &class {
            self.seal(m, choice[&m], &inside)?;
        }
        Ok(true)
    }

    /// Positive mode: the adversary's almost-sure attack from every initial
    /// state (module documentation). Returns whether it was confirmed.
    fn almost_sure_attack(&mut self) -> Result<bool, SynthesisError> {
        let analysis = self.analysis;
        let strategy = &analysis.result.strategy;
        let n = analysis.states.len();
        let mut reached = vec![false; n];
        let mut order = Vec::new();
        for &(m, _) in &analysis.initial {
            if !reached[m] {
                reached[m] = true;
                order.push(m);
            }
        }
        let mut i = 0;
        while i < order.len() {
            let m = order[i];
            i += 1;
            if self.is_sure(m) {
                continue;
            }
            for &(t, _) in analysis.mdp.distribution(m, strategy[m]) {
                if !reached[t] {
                    reached[t] = true;
                    order.push(t);
                }
            }
        }
        let sure: Vec<bool> = (0..n).map(|m| reached[m] && self.is_sure(m)).collect();
        let chain = Chain {
            mdp: &analysis.mdp,
            strategy,
            states: &order,
            local: order.iter().enumerate().map(|(i, &m)| (m, i)).collect(),
            stop: &sure,
        };
        let components = strongly_connected_components(&chain);
        let bottom = bottom_components(&chain, &components);
        let mut class_of = vec![usize::MAX; n];
        let mut classes: Vec<Vec<usize>> = vec![Vec::new(); components.count];
        for (i, &m) in order.iter().enumerate() {
            let c = components.component[i] as usize;
            if bottom[c] && !sure[m] {
                class_of[m] = c;
                classes[c].push(m);
            }
        }
        let classes: Vec<Vec<usize>> = classes.into_iter().filter(|c| !c.is_empty()).collect();
        if !classes
            .iter()
            .all(|class| self.accepting_for_adversary(class))
        {
            return Ok(false);
        }
        for &m in order.iter().filter(|&&m| !sure[m]) {
            self.seal(m, strategy[m], &reached)?;
        }
        for class in &classes {
            let mut inside = vec![false; n];
            for &m in class {
                inside[m] = true;
            }
            let root = class[0];
            let (toward, discovery) = spanning(&analysis.mdp, strategy, class, &inside, root);
            for (m, to) in toward {
                self.keep(m, strategy[m], to)?;
            }
            for (m, v, to) in discovery {
                self.keep(m, v, to)?;
            }
            for &m in class {
                self.seal(m, strategy[m], &inside)?;
            }
        }
        let absorbing: Vec<bool> = (0..n)
            .map(|m| class_of[m] != usize::MAX || sure[m])
            .collect();
        for (m, to) in towards_set(&analysis.mdp, strategy, &order, &absorbing) {
            self.keep(m, strategy[m], to)?;
        }
        Ok(true)
    }

    /// Whether product state `m` lies in a surely accepting cell.
    fn is_sure(&self, m: usize) -> bool {
        let (s, q, _) = self.analysis.states[m];
        self.oracle.sure.contains(&(s, q))
    }

    /// Whether the adversary's Rabin condition holds on a closed class:
    /// some pair's `L` misses it and its `K` meets it.
    fn accepting_for_adversary(&self, class: &[usize]) -> bool {
        self.oracle.dra_not_phi.pairs().iter().any(|pair| {
            let q = |m: usize| self.analysis.states[m].1;
            class.iter().all(|&m| !pair.fin[q(m)]) && class.iter().any(|&m| pair.inf[q(m)])
        })
    }
}

fn internal(what: &str) -> SynthesisError {
    SynthesisError::Internal(what.to_string())
}

/// The Markov chain of an MDP under a memoryless strategy, on `states`,
/// with the states `stop` made absorbing (no successors).
struct Chain<'a> {
    mdp: &'a crate::mdp::Mdp,
    strategy: &'a [usize],
    states: &'a [usize],
    local: FxHashMap<usize, usize>,
    stop: &'a [bool],
}

impl Digraph for Chain<'_> {
    fn num_vertices(&self) -> usize {
        self.states.len()
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        let m = self.states[v];
        let successors = if self.stop[m] {
            &[][..]
        } else {
            self.mdp.distribution(m, self.strategy[m])
        };
        successors.iter().map(|(t, _)| self.local[t])
    }
}

/// A shortest path of edges `(m, v, m')` (any action) from `start` to a
/// state satisfying `goal` (empty when `start` does).
fn shortest_path(
    mdp: &crate::mdp::Mdp,
    start: usize,
    goal: impl Fn(usize) -> bool,
) -> Option<Vec<(usize, usize, usize)>> {
    let mut parent: FxHashMap<usize, (usize, usize)> = FxHashMap::default();
    let mut queue = std::collections::VecDeque::from([start]);
    let mut seen = rustc_hash::FxHashSet::from_iter([start]);
    while let Some(m) = queue.pop_front() {
        if goal(m) {
            let mut path = Vec::new();
            let mut at = m;
            while let Some(&(from, v)) = parent.get(&at) {
                path.push((from, v, at));
                at = from;
            }
            path.reverse();
            return Some(path);
        }
        for v in 0..mdp.num_actions(m) {
            for &(t, _) in mdp.distribution(m, v) {
                if seen.insert(t) {
                    parent.insert(t, (m, v));
                    queue.push_back(t);
                }
            }
        }
    }
    None
}

/// Inside an end component: for each state an action of the component that
/// leads one step closer to `k` (any component action at `k`), and that
/// step's successor.
fn attract_within(
    mdp: &crate::mdp::Mdp,
    component: &crate::mdp::EndComponent,
    k: usize,
) -> (FxHashMap<usize, usize>, FxHashMap<usize, usize>) {
    let position: FxHashMap<usize, usize> = component
        .states
        .iter()
        .enumerate()
        .map(|(i, &m)| (m, i))
        .collect();
    let mut predecessors: Vec<Vec<(usize, usize)>> = vec![Vec::new(); component.states.len()];
    for (i, (&m, actions)) in component.states.iter().zip(&component.actions).enumerate() {
        for &a in actions {
            for &(t, _) in mdp.distribution(m, a) {
                if let Some(&j) = position.get(&t) {
                    predecessors[j].push((i, a));
                }
            }
        }
    }
    let mut choice = FxHashMap::default();
    let mut toward = FxHashMap::default();
    let start = position[&k];
    choice.insert(k, component.actions[start][0]);
    let mut queue = std::collections::VecDeque::from([start]);
    while let Some(j) = queue.pop_front() {
        for &(i, a) in &predecessors[j] {
            let m = component.states[i];
            if let std::collections::hash_map::Entry::Vacant(entry) = choice.entry(m) {
                entry.insert(a);
                toward.insert(m, component.states[j]);
                queue.push_back(i);
            }
        }
    }
    (choice, toward)
}

/// The states reachable from `root` under the memoryless `choice`, and the
/// edges `(m, v, m')` that discovered them.
fn closure(
    mdp: &crate::mdp::Mdp,
    root: usize,
    choice: impl Fn(usize) -> usize,
) -> (Vec<usize>, Vec<(usize, usize, usize)>) {
    let mut states = vec![root];
    let mut seen = rustc_hash::FxHashSet::from_iter([root]);
    let mut discovery = Vec::new();
    let mut i = 0;
    while i < states.len() {
        let m = states[i];
        let v = choice(m);
        for &(t, _) in mdp.distribution(m, v) {
            if seen.insert(t) {
                discovery.push((m, v, t));
                states.push(t);
            }
        }
        i += 1;
    }
    (states, discovery)
}

/// For a closed class of the chain under `strategy` with a `root`: an edge
/// from every other state one step closer to the root, and the edges that
/// discover the class from the root.
#[allow(clippy::type_complexity)]
fn spanning(
    mdp: &crate::mdp::Mdp,
    strategy: &[usize],
    class: &[usize],
    inside: &[bool],
    root: usize,
) -> (Vec<(usize, usize)>, Vec<(usize, usize, usize)>) {
    let target: Vec<bool> = (0..inside.len()).map(|m| m == root).collect();
    let toward = towards_set(mdp, strategy, class, &target);
    let (_, discovery) = closure(mdp, root, |m| strategy[m]);
    debug_assert!(discovery.iter().all(|&(_, _, t)| inside[t]));
    (toward, discovery)
}

/// For each state of `states` outside `target`, an edge under `strategy`
/// to a state one step closer to `target` (backward search).
fn towards_set(
    mdp: &crate::mdp::Mdp,
    strategy: &[usize],
    states: &[usize],
    target: &[bool],
) -> Vec<(usize, usize)> {
    let mut predecessors: FxHashMap<usize, Vec<usize>> = FxHashMap::default();
    for &m in states {
        for &(t, _) in mdp.distribution(m, strategy[m]) {
            predecessors.entry(t).or_default().push(m);
        }
    }
    let mut found: rustc_hash::FxHashSet<usize> =
        states.iter().copied().filter(|&m| target[m]).collect();
    let mut queue: std::collections::VecDeque<usize> = found.iter().copied().collect();
    let mut edges = Vec::new();
    while let Some(t) = queue.pop_front() {
        for &m in predecessors.get(&t).map_or(&[][..], Vec::as_slice) {
            if found.insert(m) {
                edges.push((m, t));
                queue.push_back(m);
            }
        }
    }
    edges
}
