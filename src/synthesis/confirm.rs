//! The second route to a support found by the lazy engine: a certificate
//! constructed for it ([`super::witness`]) on the product with the
//! automaton for phi, checked against the certificate formula with every
//! variable of the support and the certificate fixed.

use rustc_hash::FxHashMap;
use serde::Serialize;

use super::cnf::{Answer, Cnf, Solver};
use super::encoding::{self, Context, FixedCertificate};
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
    let size = context.graph.num_cells() * context.nodes;
    let fits = |value: usize| settings.rank_encoding.constant(rank_bound, value).is_ok();
    let mut fixed = Vec::with_capacity(witnesses.len());
    for witness in &witnesses {
        let mut values = FixedCertificate {
            member: vec![false; size],
            level: vec![0; size],
            rank: vec![0; size],
        };
        for (m, level) in witness.level.iter().enumerate() {
            let Some(level) = *level else { continue };
            let rank = witness.rank[m].saturating_sub(1);
            if !fits(level) || !fits(rank) {
                return Ok(Confirmation::NotCovered);
            }
            let at = position(m);
            values.member[at] = true;
            values.level[at] = level;
            values.rank[at] = rank;
        }
        fixed.push(values);
    }
    let mut cnf = Cnf::new(settings.clause_budget);
    let mut vars = SupportVariables::fixed(context.game, context.moves, context.nodes, support);
    let certificates = encoding::certificates(
        context,
        &mut cnf,
        &mut vars,
        pairs,
        settings.mode.claim(),
        settings.rank_encoding,
        rank_bound,
        Some(&fixed),
    )?;
    encoding::claim_initial(context, &mut cnf, &certificates, settings.mode.claim())?;
    match Solver::new(&cnf, None).solve(&[])? {
        Answer::Satisfiable => Ok(Confirmation::Confirmed),
        Answer::Unsatisfiable => Err(SynthesisError::Internal(format!(
            "the certificate constructed for a {} support violates the certificate formula",
            settings.mode.name()
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::game::file::from_json_str;
    use crate::synthesis::graph::{CellGraph, Moves};
    use crate::synthesis::{Mode, RankEncoding};

    /// A certificate claiming every state at level 0 on a game where the
    /// defender's only support can step into `bad`: the constant check
    /// must leave an empty clause, and the true (empty) region must not
    /// satisfy the claim either.
    #[test]
    fn a_false_certificate_violates_the_formula() {
        let game = from_json_str(
            r#"{"posg": 1, "states": ["s0", "bad"], "initial": {"s0": 1},
                "labels": {"bad": ["bad"]},
                "defender": {"actions": ["a", "b"], "observe": "full"},
                "transitions": [
                  {"state": "s0", "defender": "a", "next": {"s0": 1}},
                  {"state": "s0", "defender": "b", "next": {"bad": 1}},
                  {"state": "bad", "defender": "*", "next": {"bad": 1}}]}"#,
            "test.posg.json",
        )
        .unwrap();
        let dra = crate::ltl::translate(&crate::ltl::parse("G !bad").unwrap()).unwrap();
        let moves = Moves::of(&game);
        let graph = CellGraph::build(&game, &dra, &moves);
        let context = Context {
            game: &game,
            moves: &moves,
            graph: &graph,
            nodes: 1,
        };
        let size = graph.num_cells();
        let everything = FixedCertificate {
            member: vec![true; size],
            level: vec![0; size],
            rank: vec![0; size],
        };
        let pairs: Vec<&RabinPair> = dra.pairs().iter().collect();
        let support = [true; 4];
        let verdict = |fixed: &FixedCertificate, mode: Mode| {
            let mut cnf = Cnf::new(10_000);
            let mut vars = SupportVariables::fixed(&game, &moves, 1, &support);
            let certificates = encoding::certificates(
                &context,
                &mut cnf,
                &mut vars,
                &pairs,
                mode.claim(),
                RankEncoding::Binary,
                size,
                Some(std::slice::from_ref(fixed)),
            )
            .unwrap();
            encoding::claim_initial(&context, &mut cnf, &certificates, mode.claim()).unwrap();
            Solver::new(&cnf, None).solve(&[]).unwrap()
        };
        for mode in [Mode::Positive, Mode::AlmostSure] {
            assert_eq!(
                verdict(&everything, mode),
                Answer::Unsatisfiable,
                "{mode:?}"
            );
        }
    }
}
