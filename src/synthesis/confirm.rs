//! The second route to a support found by the lazy engine: a certificate
//! constructed for it ([`super::witness`]) on the product with the
//! automaton for phi, checked against the certificate formula with every
//! variable of the support and the certificate fixed.

use rustc_hash::FxHashMap;
use serde::Serialize;

use super::cnf::{Answer, Cnf, Lit, Solver};
use super::encoding::{self, Certificates, Context};
use super::variables::SupportVariables;
use super::witness::{Witness, construct};
use super::{Mode, Settings, SynthesisError};
use crate::automaton::{Dra, RabinPair};
use crate::certify::product_mdp;
use crate::controller::{Fsc, Role};

/// How a support was confirmed by the certificate formula.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Confirmation {
    /// A certificate exists and satisfies the formula.
    Confirmed,
    /// No per-pair certificate covers the claim: possible with several
    /// Rabin pairs (the union of per-pair certificates may miss) or a rank
    /// bound below the levels needed. Certification alone vouches for it.
    NotCovered,
    /// Not asked for.
    Skipped,
}

/// Constructs a certificate for `support` (the defender `defender`) and
/// checks it against the certificate formula. A certificate that the
/// formula rejects, or a missing one where the certificate is complete
/// (one usable pair), is an error.
pub fn confirm(
    context: &Context,
    dra: &Dra,
    pairs: &[&RabinPair],
    defender: &Fsc,
    support: &[bool],
    settings: &Settings,
    rank_bound: usize,
) -> Result<Confirmation, SynthesisError> {
    let (states, mdp, initial) = product_mdp(context.game, dra, defender, Role::Defender)?;
    let closed = settings.mode == Mode::AlmostSure;
    let witnesses: Vec<Witness> = pairs
        .iter()
        .map(|pair| {
            let fin: Vec<bool> = states.iter().map(|&(_, q, _)| pair.fin[q]).collect();
            let inf: Vec<bool> = states.iter().map(|&(_, q, _)| pair.inf[q]).collect();
            construct(&mdp, &fin, &inf, closed)
        })
        .collect();
    let covered = |m: usize| witnesses.iter().any(|w| w.level[m].is_some());
    let claimed = match settings.mode {
        Mode::Positive => initial.iter().any(|&(m, _)| covered(m)),
        Mode::AlmostSure => initial.iter().all(|&(m, _)| covered(m)),
    };
    if !claimed {
        return if pairs.len() == 1 {
            Err(SynthesisError::Internal(format!(
                "certification accepts a {} support for which no certificate exists",
                settings.mode.name()
            )))
        } else {
            Ok(Confirmation::NotCovered)
        };
    }
    let mut cnf = Cnf::new(settings.clause_budget);
    let mut vars = SupportVariables::new(&mut cnf, context.game, context.moves, context.nodes)?;
    let certificates = encoding::certificates(
        context,
        &mut cnf,
        &mut vars,
        pairs,
        settings.mode.claim(),
        settings.rank_encoding,
        rank_bound,
    )?;
    encoding::claim_initial(context, &mut cnf, &certificates, settings.mode.claim())?;
    let mut assumptions: Vec<Lit> = vars
        .support
        .iter()
        .zip(support)
        .map(|(&x, &present)| if present { x } else { -x })
        .collect();
    let cell_of: FxHashMap<(usize, usize), usize> = context
        .graph
        .cells
        .iter()
        .enumerate()
        .map(|(c, &cell)| (cell, c))
        .collect();
    let position = |m: usize| {
        let (s, q, g) = states[m];
        cell_of[&(s, q)] * context.nodes + g
    };
    for (i, witness) in witnesses.iter().enumerate() {
        match fix(&certificates, i, witness, settings, position) {
            Some(fixed) => assumptions.extend(fixed),
            None => return Ok(Confirmation::NotCovered),
        }
    }
    match Solver::new(&cnf, None).solve(&assumptions)? {
        Answer::Satisfiable => Ok(Confirmation::Confirmed),
        Answer::Unsatisfiable => Err(SynthesisError::Internal(format!(
            "the certificate constructed for a {} support violates the certificate formula",
            settings.mode.name()
        ))),
    }
}

/// Assumptions fixing pair `i`'s membership, levels and ranks to the
/// witness (`position` maps product states to the formula's states); `None`
/// when a level or rank does not fit the rank bound.
fn fix(
    certificates: &Certificates,
    i: usize,
    witness: &Witness,
    settings: &Settings,
    position: impl Fn(usize) -> usize,
) -> Option<Vec<Lit>> {
    let member = &certificates.members[i];
    let mut inside = vec![false; member.len()];
    let mut assumptions = Vec::new();
    for (m, level) in witness.level.iter().enumerate() {
        let Some(level) = *level else { continue };
        let at = position(m);
        inside[at] = true;
        if let Some(levels) = &certificates.levels[i] {
            assumptions.extend(levels[at].fixed_to(settings.rank_encoding, level)?);
        }
        if let Some(rank) = &certificates.ranks[i][at] {
            assumptions.extend(rank.fixed_to(settings.rank_encoding, witness.rank[m] - 1)?);
        }
    }
    assumptions.extend(
        member
            .iter()
            .zip(&inside)
            .map(|(&x, &inside)| if inside { x } else { -x }),
    );
    Some(assumptions)
}
