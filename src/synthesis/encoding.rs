//! The SAT encoding of "some `N`-node defender support wins" (method.md
//! section 7), with the certificates of [`super`]'s documentation.
//!
//! Variables:
//!
//! * `x[g, o, g', u]`: the support entry `mu(g', u | g, o) > 0`; at least
//!   one per block `(g, o)`. The initial node is node 0.
//! * `E[s, v, s', g, g']`: an edge from `(s, q, g)` to `(s', q', g')` under
//!   adversary action `v`, `E <-> OR { x[g, o, g', u] : O(o | s) > 0,
//!   T(s' | s, u, v) > 0 }` (Tseitin); it does not depend on `q`.
//! * per Rabin pair `i` and product state `m = (s, q, g)`: membership
//!   `in_i[m]`, a level `lambda_i(m)` and, outside `K_i`, a rank
//!   `rho_i(m)` ([`super::ranks`]). States of `K_i` have rank 0, below every
//!   other rank.
//!
//! For every `m` with `in[m]` and every adversary action `v`, with the
//! edges `m -> m'` under `v` (`E` true):
//!
//! * (level) some edge goes to `m'` in the set with `lambda(m') < lambda(m)`,
//!   or every edge goes to `m'` in the set with `lambda(m') <= lambda(m)`;
//! * (`L_i`) if `q in L_i`: some edge goes to `m'` in the set with
//!   `lambda(m') < lambda(m)`;
//! * (`K_i`) if `q not in K_i`: some edge goes to `m'` in the set with
//!   `lambda(m') < lambda(m)`, or with `lambda(m') <= lambda(m)` and
//!   `rho(m') < rho(m)`;
//! * (closure, almost-sure mode only) every edge goes to `m'` in the set.
//!
//! Almost-sure mode without `L_i` states needs no levels (all equal 0).

use rustc_hash::FxHashMap;

use super::SynthesisError;
use super::cnf::{Cnf, FALSE, Lit, TRUE};
use super::graph::{CellGraph, Moves};
use super::ranks::{Number, RankEncoding, less};
use super::variables::SupportVariables;
use crate::automaton::RabinPair;
use crate::game::Posg;

/// What a certificate proves for the initial product states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Claim {
    /// Some initial state is in a positive certificate.
    Positive,
    /// Every initial state is in an almost-sure (closed) certificate.
    AlmostSure,
}

/// The certificate constraints added to a formula: the membership
/// literals of each pair's certificate, indexed by product state
/// `cell * N + g`.
pub struct Certificates {
    /// Per pair, `in_i[m]`.
    pub members: Vec<Vec<Lit>>,
    /// Per pair, `lambda_i(m)` (none: all levels are 0).
    pub levels: Vec<Option<Vec<Number>>>,
    /// Per pair, `rho_i(m)` outside `K_i`.
    pub ranks: Vec<Vec<Option<Number>>>,
}

/// A certificate given as values (to check it against the constraints):
/// per formula state `m`, membership, level and rank (for a state outside
/// `K`, its number is the rank minus 1).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FixedCertificate {
    /// `in[m]`.
    pub member: Vec<bool>,
    /// `lambda(m)`.
    pub level: Vec<usize>,
    /// The value of `rho(m)`'s number.
    pub rank: Vec<usize>,
}

/// The shared context of the constraints.
pub struct Context<'a> {
    /// The game.
    pub game: &'a Posg,
    /// Its transitions.
    pub moves: &'a Moves,
    /// The cells.
    pub graph: &'a CellGraph,
    /// The defender's number of nodes `N`.
    pub nodes: usize,
}

/// Adds one certificate per pair (module documentation) to `cnf`, with
/// levels and ranks in `0..rank_bound` written as `encoding`; with `fixed`
/// (one per pair, values that fit the bound), the certificates are those
/// constants, and every clause they violate is left empty.
#[allow(clippy::too_many_arguments)]
pub fn certificates(
    context: &Context,
    cnf: &mut Cnf,
    vars: &mut SupportVariables,
    pairs: &[&RabinPair],
    claim: Claim,
    encoding: RankEncoding,
    rank_bound: usize,
    fixed: Option<&[FixedCertificate]>,
) -> Result<Certificates, SynthesisError> {
    let mut certificates = Certificates {
        members: Vec::with_capacity(pairs.len()),
        levels: Vec::with_capacity(pairs.len()),
        ranks: Vec::with_capacity(pairs.len()),
    };
    for (i, pair) in pairs.iter().enumerate() {
        let values = fixed.map(|all| &all[i]);
        let mut certificate =
            Certificate::new(context, cnf, pair, claim, (encoding, rank_bound), values)?;
        certificate.constrain(context, cnf, vars)?;
        certificates.members.push(certificate.member);
        certificates.levels.push(certificate.levels);
        certificates.ranks.push(certificate.ranks);
    }
    Ok(certificates)
}

/// The claim on the initial product states (node 0): some is in some
/// certificate (positive), or each is in some certificate (almost sure).
pub fn claim_initial(
    context: &Context,
    cnf: &mut Cnf,
    certificates: &Certificates,
    claim: Claim,
) -> Result<(), SynthesisError> {
    let nodes = context.nodes;
    let at_start = |cell: usize| {
        certificates
            .members
            .iter()
            .map(move |member| member[cell * nodes])
    };
    match claim {
        Claim::Positive => {
            let any: Vec<Lit> = context
                .graph
                .initial
                .iter()
                .flat_map(|&c| at_start(c))
                .collect();
            cnf.clause(any)
        }
        Claim::AlmostSure => {
            for &c in &context.graph.initial {
                cnf.clause(at_start(c).collect::<Vec<_>>())?;
            }
            Ok(())
        }
    }
}

/// One Rabin pair's certificate (module documentation).
struct Certificate<'p> {
    pair: &'p RabinPair,
    claim: Claim,
    encoding: RankEncoding,
    member: Vec<Lit>,
    levels: Option<Vec<Number>>,
    ranks: Vec<Option<Number>>,
    /// `(m, m') ->` literal implying `in[m'] & lambda(m') < lambda(m)`.
    strict: FxHashMap<(u32, u32), Lit>,
    /// `(m, m') ->` literal implying `in[m']`, `lambda(m') <= lambda(m)` and
    /// `rho(m') < rho(m)`.
    weak: FxHashMap<(u32, u32), Lit>,
    /// `(m, m') ->` literal implying `lambda(m') <= lambda(m)`.
    level_at_most: FxHashMap<(u32, u32), Lit>,
}

impl<'p> Certificate<'p> {
    fn new(
        context: &Context,
        cnf: &mut Cnf,
        pair: &'p RabinPair,
        claim: Claim,
        (encoding, bound): (RankEncoding, usize),
        fixed: Option<&FixedCertificate>,
    ) -> Result<Self, SynthesisError> {
        let graph = context.graph;
        let n = graph.num_cells() * context.nodes;
        let member = match fixed {
            None => cnf.fresh_many(n),
            Some(values) => values
                .member
                .iter()
                .map(|&inside| if inside { TRUE } else { FALSE })
                .collect(),
        };
        let number = |cnf: &mut Cnf, value: Option<usize>| match value {
            None => encoding.number(cnf, bound),
            Some(value) => encoding.constant(bound, value),
        };
        let has_fin = graph.cells.iter().any(|&(_, q)| pair.fin[q]);
        let levels = if claim == Claim::Positive || has_fin {
            Some(
                (0..n)
                    .map(|m| number(cnf, fixed.map(|f| f.level[m])))
                    .collect::<Result<_, _>>()?,
            )
        } else {
            None
        };
        let ranks = (0..n)
            .map(|m| {
                let (_, q) = graph.cells[m / context.nodes];
                (!pair.inf[q])
                    .then(|| number(cnf, fixed.map(|f| f.rank[m])))
                    .transpose()
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            pair,
            claim,
            encoding,
            member,
            levels,
            ranks,
            strict: FxHashMap::default(),
            weak: FxHashMap::default(),
            level_at_most: FxHashMap::default(),
        })
    }

    /// The constraints of every product state and adversary action.
    fn constrain(
        &mut self,
        context: &Context,
        cnf: &mut Cnf,
        vars: &mut SupportVariables,
    ) -> Result<(), SynthesisError> {
        let (graph, nodes) = (context.graph, context.nodes);
        let adversary = context.game.adversary();
        let nv = adversary.num_actions();
        let mut edges: Vec<(usize, Lit)> = Vec::new();
        for cell in 0..graph.num_cells() {
            let (s, q) = graph.cells[cell];
            for g in 0..nodes {
                let m = cell * nodes + g;
                for v in (0..nv).filter(|&v| adversary.action_enabled_in_state(s, v)) {
                    edges.clear();
                    for step in graph.steps(cell, v) {
                        for next in 0..nodes {
                            let e = vars.edge(
                                cnf,
                                context.game,
                                context.moves,
                                (s, step.transition),
                                (g, next),
                            )?;
                            if e != FALSE {
                                edges.push((step.cell * nodes + next, e));
                            }
                        }
                    }
                    self.constrain_action(cnf, m, q, &edges)?;
                }
            }
        }
        Ok(())
    }

    /// The constraints of product state `m` (automaton state `q`) for one
    /// adversary action whose possible edges are `edges` (`(m', E)`).
    fn constrain_action(
        &mut self,
        cnf: &mut Cnf,
        m: usize,
        q: usize,
        edges: &[(usize, Lit)],
    ) -> Result<(), SynthesisError> {
        let inside = self.member[m];
        if inside == FALSE {
            return Ok(());
        }
        let mut progress = Vec::new();
        if self.levels.is_some() {
            for &(next, e) in edges {
                let witness = self.strict_witness(cnf, m, next)?;
                progress.push(cnf.and_implied(&[e, witness])?);
            }
        }
        if self.claim == Claim::AlmostSure {
            for &(next, e) in edges {
                cnf.clause([-inside, -e, self.member[next]])?;
            }
        }
        if self.pair.fin[q] {
            cnf.clause(std::iter::once(-inside).chain(progress.iter().copied()))?;
        } else if self.levels.is_some() {
            let stay = cnf.fresh();
            for &(next, e) in edges {
                if self.claim == Claim::Positive {
                    cnf.clause([-stay, -e, self.member[next]])?;
                }
                let at_most = self.level_at_most(cnf, m, next)?;
                cnf.clause([-stay, -e, at_most])?;
            }
            cnf.clause([-inside, stay].into_iter().chain(progress.iter().copied()))?;
        }
        if !self.pair.inf[q] {
            let mut towards = progress;
            for &(next, e) in edges {
                let witness = self.weak_witness(cnf, m, next)?;
                towards.push(cnf.and_implied(&[e, witness])?);
            }
            cnf.clause(std::iter::once(-inside).chain(towards))?;
        }
        Ok(())
    }

    /// A literal implying `in[m'] & lambda(m') < lambda(m)` (false without
    /// levels: they are all 0).
    fn strict_witness(
        &mut self,
        cnf: &mut Cnf,
        m: usize,
        next: usize,
    ) -> Result<Lit, SynthesisError> {
        if let Some(&lit) = self.strict.get(&key(m, next)) {
            return Ok(lit);
        }
        let Some(levels) = &self.levels else {
            return Ok(FALSE);
        };
        let below = less(self.encoding, cnf, &levels[next], &levels[m], true)?;
        let lit = cnf.and_implied(&[self.member[next], below])?;
        self.strict.insert(key(m, next), lit);
        Ok(lit)
    }

    /// A literal implying `lambda(m') <= lambda(m)` (true without levels).
    fn level_at_most(
        &mut self,
        cnf: &mut Cnf,
        m: usize,
        next: usize,
    ) -> Result<Lit, SynthesisError> {
        let Some(levels) = &self.levels else {
            return Ok(TRUE);
        };
        if let Some(&lit) = self.level_at_most.get(&key(m, next)) {
            return Ok(lit);
        }
        let lit = less(self.encoding, cnf, &levels[next], &levels[m], false)?;
        self.level_at_most.insert(key(m, next), lit);
        Ok(lit)
    }

    /// A literal implying `in[m']`, `lambda(m') <= lambda(m)` and
    /// `rho(m') < rho(m)`, where states of `K` have rank 0, below all others.
    fn weak_witness(
        &mut self,
        cnf: &mut Cnf,
        m: usize,
        next: usize,
    ) -> Result<Lit, SynthesisError> {
        if let Some(&lit) = self.weak.get(&key(m, next)) {
            return Ok(lit);
        }
        let at_most = self.level_at_most(cnf, m, next)?;
        let lower = match (&self.ranks[next], &self.ranks[m]) {
            (Some(r_next), Some(r_here)) => less(self.encoding, cnf, r_next, r_here, true)?,
            (None, Some(_)) => TRUE,
            (_, None) => FALSE,
        };
        let lit = cnf.and_implied(&[self.member[next], at_most, lower])?;
        self.weak.insert(key(m, next), lit);
        Ok(lit)
    }
}

fn key(m: usize, next: usize) -> (u32, u32) {
    (m as u32, next as u32)
}
