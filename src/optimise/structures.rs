//! Where the support structures that `solve` optimises on come from, and
//! the choice among their results.
//!
//! Four sources ([`StructureSource`]):
//!
//! * `full`: every `(g', u)` in every block ([`Structure::full`]), or the
//!   controllers the user started from;
//! * `informed`: the fully informed defender's optimal strategy projected
//!   onto the observations (`informed.rs`, method.md section 4);
//! * `sat`: a defender support found by SAT (method.md section 7,
//!   [`crate::synthesis`]): almost-sure winning when one exists (its value is
//!   then certified to be 1), otherwise positive winning, maximised; the
//!   adversary keeps the full support;
//! * `paper`: every structure the paper's Algorithm 1 keeps (method.md
//!   section 5).
//!
//! Identical structures (the same supports and initial supports for both
//! players) are optimised once. The result with the best certified lower
//! bound wins ([`best_by_certified_lower`]).

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::informed::informed;
use super::{OptimiseError, Settings, Structure, StructureOutcome};
use crate::automaton::Dra;
use crate::certify::almost_sure_win_possible;
use crate::certify::belief::UpperBoundsOnce;
use crate::controller::{Fsc, Support};
use crate::game::Posg;
use crate::prune::{PruneSettings, prune};
use crate::synthesis::{self, Mode, SynthesisError};

/// A source of support structures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum StructureSource {
    /// The starting structure: the full support or the user's controllers.
    Full,
    /// The fully informed defender's strategy projected onto the observations.
    Informed,
    /// Support synthesis by SAT.
    Sat,
    /// The paper's Algorithm 1.
    Paper,
}

impl StructureSource {
    /// Every source, in the order their structures are listed.
    pub const ALL: [Self; 4] = [Self::Full, Self::Informed, Self::Sat, Self::Paper];

    /// The name used in settings and messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Full => "full",
            Self::Informed => "informed",
            Self::Sat => "sat",
            Self::Paper => "paper",
        }
    }

    /// What the source's search does, in words (the progress line's).
    pub fn search(self) -> &'static str {
        match self {
            Self::Full => "the full support",
            Self::Informed => {
                "the informed support (the optimum of the defender that sees the state)"
            }
            Self::Sat => "support synthesis by SAT",
            Self::Paper => "Algorithm 1's pruning",
        }
    }
}

/// What one source contributed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SourceNote {
    /// The source.
    pub source: StructureSource,
    /// The names of the structures it contributed (after de-duplication).
    pub structures: Vec<String>,
    /// What it found, proved or why it gave nothing.
    pub note: String,
    /// The structures it found that an earlier source had found already
    /// (optimised once, under the earlier name).
    pub duplicates: Vec<Duplicate>,
    /// Seconds it took.
    pub seconds: f64,
}

/// A structure found twice: `structure` has the same supports as `same_as`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Duplicate {
    /// The name the later source gave it.
    pub structure: String,
    /// The structure found first, which is optimised.
    pub same_as: String,
}

/// The structures to optimise on and what each source said.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidates {
    /// The structures, without duplicates.
    pub structures: Vec<Structure>,
    /// One note per source asked for.
    pub notes: Vec<SourceNote>,
}

/// The structures of the sources in `settings.structures`, starting from
/// `start` (the full structure or the user's controllers, always kept
/// when it came from files). `negated`, an automaton for !phi, is needed
/// by the `sat` source (which certifies what it finds); `bounds` are the
/// run's upper bounds of `game` for the automaton `dra` of phi (the SAT
/// source's belief bound, the informed source's game upper bound).
/// `announce` hears each source as its search begins.
pub fn candidate_structures(
    game: &Posg,
    (dra, negated): (&Dra, Option<&Dra>),
    start: Structure,
    (settings, bounds): (&Settings, &UpperBoundsOnce<'_>),
    announce: &dyn Fn(StructureSource),
) -> Result<Candidates, OptimiseError> {
    debug_assert!(bounds.is_of(game, dra), "the bounds of another game");
    let mut candidates = Candidates {
        structures: Vec::new(),
        notes: Vec::new(),
    };
    let keep_start = settings.structures.contains(&StructureSource::Full) || start.name != "full";
    for source in StructureSource::ALL {
        let wanted = settings.structures.contains(&source)
            || (source == StructureSource::Full && keep_start);
        if !wanted {
            continue;
        }
        announce(source);
        let clock = Instant::now();
        let (found, note) = match source {
            StructureSource::Full => (vec![start.clone()], format!("the {} structure", start.name)),
            // The informed optimum out of the solver's reach (method.md
            // section 8) leaves the other sources to carry the run.
            StructureSource::Informed => match informed(game, &start, bounds) {
                Err(error) if error.is_numerical() => {
                    (Vec::new(), format!("no informed structure: {error}"))
                }
                found => found?,
            },
            StructureSource::Sat => synthesised(game, (dra, negated), &start, settings, bounds)?,
            StructureSource::Paper => pruned(game, dra, &start, settings)?,
        };
        let mut note = SourceNote {
            source,
            structures: Vec::new(),
            note,
            duplicates: Vec::new(),
            seconds: clock.elapsed().as_secs_f64(),
        };
        for structure in found {
            match candidates
                .structures
                .iter()
                .find(|known| same_supports(known, &structure))
            {
                Some(known) => note.duplicates.push(Duplicate {
                    structure: structure.name.clone(),
                    same_as: known.name.clone(),
                }),
                None => {
                    note.structures.push(structure.name.clone());
                    candidates.structures.push(structure);
                }
            }
        }
        candidates.notes.push(note);
    }
    Ok(candidates)
}

/// The share of the synthesis time budget the SAT source gives the
/// almost-sure question (0.48 s of the default 120): its lemmas can be weak
/// on large POMDPs (the 8x8 grid POMDP with 3 nodes takes over 120 s),
/// while the positive question answers in milliseconds there, so an
/// unanswered almost-sure question must not hold `solve` up (the other
/// structures wait for the sources). On PAYNT's game suite and PRISM's
/// POMDPs every answer came within 0.31 s: a support within 0.04 s (what
/// the question is for: a proof that none exists changes no structure),
/// a proof within 0.31 s; five runs (crypt-4 with 2 and 3 nodes,
/// dodge-6-lines-position with 2 and 3, dodge-6-lines with 3) got no
/// answer, and spent the whole share: a hundredth (1.2 s) was a quarter of
/// crypt-4's wall time with 2 nodes.
pub const ALMOST_SURE_BUDGET_SHARE: f64 = 0.004;

/// The share of the synthesis time budget the SAT source gives the
/// positive question (12 s of the default 120). It answers in milliseconds
/// to seconds where it helps (the games that need memory; at most 5.2 s
/// on PAYNT's suite, dodge-8 with 3 nodes); on PAYNT's attacker-defender
/// game (1,179 states) it gave no answer in 120 s, and `solve` optimises
/// the other structures only after the sources answer, so an unanswered
/// question must not hold it up for the whole budget either.
pub const POSITIVE_BUDGET_SHARE: f64 = 0.1;

/// The SAT source: almost-sure winning if possible (within
/// [`ALMOST_SURE_BUDGET_SHARE`] of the time budget), else positive (within
/// [`POSITIVE_BUDGET_SHARE`]). The almost-sure question is not asked when
/// even a defender that sees the state cannot win almost surely against
/// the structure's starting adversary ([`almost_sure_win_possible`]), nor
/// where the belief bound of a single-player game is below 1: no support
/// can then win almost surely against every adversary.
fn synthesised(
    game: &Posg,
    (dra, negated): (&Dra, Option<&Dra>),
    start: &Structure,
    settings: &Settings,
    belief: &UpperBoundsOnce<'_>,
) -> Result<(Vec<Structure>, String), OptimiseError> {
    let Some(negated) = negated else {
        return Ok((
            Vec::new(),
            "skipped: support synthesis certifies with an automaton for !phi, which an objective \
             given as an automaton lacks"
                .into(),
        ));
    };
    let nodes = start.defender.num_nodes();
    let mut reasons = Vec::new();
    let mut modes = vec![Mode::AlmostSure, Mode::Positive];
    if !almost_sure_win_possible(game, dra, &start.adversary)? {
        modes.remove(0);
        reasons.push(
            "almost-sure synthesis skipped: against the starting adversary even a defender that \
             sees the state wins with probability below 1 (decided on the graph)"
                .to_string(),
        );
    } else if let Some(belief) = belief.get()?.filter(|belief| belief.value < 1.0) {
        modes.remove(0);
        reasons.push(format!(
            "almost-sure synthesis skipped: the belief bound proves that no defender wins with \
             probability above {}",
            belief.value
        ));
    }
    for mode in modes {
        let share = match mode {
            Mode::AlmostSure => ALMOST_SURE_BUDGET_SHARE,
            Mode::Positive => POSITIVE_BUDGET_SHARE,
        };
        let mode_settings = synthesis::Settings {
            mode,
            time_budget: settings.synthesis.time_budget * share,
            ..settings.synthesis.clone()
        };
        match synthesis::synthesise(
            game,
            dra,
            negated,
            nodes,
            &mode_settings,
            &settings.solver_settings(),
        ) {
            Ok(found) => match found.defender.clone() {
                Some(defender) => {
                    reasons.push(format!(
                        "{} (certified lower bound {:.6}, {} support entries, {:.2} s)",
                        found.reason,
                        found.certified_lower.unwrap_or(0.0),
                        found.support_entries(),
                        found.statistics.map_or(0.0, |s| s.seconds)
                    ));
                    let structure = Structure {
                        name: format!("sat-{}", mode.name()),
                        defender,
                        adversary: start.adversary.clone(),
                        warm: None,
                    };
                    return Ok((vec![structure], reasons.join("; ")));
                }
                None => reasons.push(found.reason),
            },
            Err(SynthesisError::TimeBudget { calls, seconds }) => reasons.push(format!(
                "{} synthesis gave no answer within its time budget ({calls} SAT calls, {seconds:.1} s)",
                mode.name()
            )),
            Err(other) => return Err(other.into()),
        }
    }
    Ok((Vec::new(), reasons.join("; ")))
}

/// The paper source: the structures Algorithm 1 keeps from `start`.
fn pruned(
    game: &Posg,
    dra: &Dra,
    start: &Structure,
    settings: &Settings,
) -> Result<(Vec<Structure>, String), OptimiseError> {
    let prune_settings = PruneSettings {
        paper_literal: settings.prune_paper_literal,
        prune_adversary: settings.prune_adversary,
    };
    let kept = prune(
        game,
        dra,
        &start.defender,
        &start.adversary,
        &prune_settings,
    )?
    .structures;
    let note = match kept.len() {
        0 => "Algorithm 1 keeps no structure".to_string(),
        1 => "Algorithm 1 keeps one structure".to_string(),
        k => format!("Algorithm 1 keeps {k} structures"),
    };
    let structures = kept
        .into_iter()
        .enumerate()
        .map(|(k, kept)| Structure {
            name: format!("pruned-{}", k + 1),
            defender: kept.defender,
            adversary: kept.adversary,
            warm: None,
        })
        .collect();
    Ok((structures, note))
}

/// Whether two structures have the same supports and initial supports for
/// both players (then their optimisation problems are the same).
fn same_supports(a: &Structure, b: &Structure) -> bool {
    let same = |x: &Fsc, y: &Fsc| Support::of(x) == Support::of(y);
    same(&a.defender, &b.defender) && same(&a.adversary, &b.adversary)
}

/// The index of the outcome with the best certified lower bound (the
/// worst-case estimate where no bound was computed); the first on ties.
pub fn best_by_certified_lower(outcomes: &[StructureOutcome]) -> Option<usize> {
    let score = |o: &StructureOutcome| o.report.certified_lower.unwrap_or(o.report.worst_case);
    (0..outcomes.len()).reduce(|b, i| {
        if score(&outcomes[i]) > score(&outcomes[b]) {
            i
        } else {
            b
        }
    })
}

/// A structure's name in words: `the full support (full)`, `the SAT
/// support, winning with positive probability (sat-positive)`, ...
pub fn described(name: &str) -> String {
    let words = match name {
        "full" => "the full support".to_string(),
        "informed" => {
            "the informed support (the defender that sees the state, projected)".to_string()
        }
        "from-files" => "the controllers given".to_string(),
        "sat-almost-sure" => "the SAT support, winning almost surely".to_string(),
        "sat-positive" => "the SAT support, winning with positive probability".to_string(),
        _ => match (name.strip_prefix("pruned-"), name.strip_prefix("from-")) {
            (Some(k), _) => format!("Algorithm 1's structure {k}"),
            (_, Some(rest)) => match rest.strip_suffix("-nodes") {
                Some(k) => format!("the result of the {k}-node defender, kept"),
                None => return name.to_string(),
            },
            _ => return name.to_string(),
        },
    };
    format!("{words} ({name})")
}

/// Why each structure other than the winner lost, which structures a
/// source found again (optimised once), what the sources without a
/// structure said, and which structures were dropped for numerical
/// trouble: one plain sentence per line.
pub fn why_others_lost(
    outcomes: &[StructureOutcome],
    best: usize,
    notes: &[SourceNote],
    failed: &[(String, String)],
) -> Vec<String> {
    let score = |o: &StructureOutcome| o.report.certified_lower.unwrap_or(o.report.worst_case);
    let winner = &outcomes[best];
    let mut lines: Vec<String> = outcomes
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != best)
        .map(|(_, o)| {
            let value = score(o);
            let (what, against) = if o.report.certified_lower.is_some() {
                ("certified", "against every adversary")
            } else {
                ("estimated", "against the best responses found")
            };
            let name = described(&o.report.name);
            if value <= 0.0 {
                format!(
                    "Lost: {name}: its best defender is {what} at 0 (some adversary always \
                     defeats it)."
                )
            } else if value == score(winner) {
                format!(
                    "Lost: {name}: {what} at {value:.6} {against}, a tie, and ties go to the \
                     structure tried first."
                )
            } else {
                format!("Lost: {name}: {what} at only {value:.6} {against}.")
            }
        })
        .collect();
    for note in notes {
        for duplicate in &note.duplicates {
            lines.push(format!(
                "Not optimised twice: {} is the same as {}.",
                described(&duplicate.structure),
                described(&duplicate.same_as)
            ));
        }
        if note.structures.is_empty() && note.duplicates.is_empty() {
            lines.push(format!(
                "No structure from {} ({}).",
                source_in_words(note.source),
                note.note
            ));
        }
    }
    lines.extend(failed.iter().map(|(name, error)| {
        format!(
            "Dropped: {}: a linear system could not be solved to the tolerance ({error}).",
            described(name)
        )
    }));
    lines
}

/// A source of structures in words.
fn source_in_words(source: StructureSource) -> &'static str {
    match source {
        StructureSource::Full => "the full support",
        StructureSource::Informed => "the informed projection",
        StructureSource::Sat => "SAT support synthesis",
        StructureSource::Paper => "the paper's Algorithm 1",
    }
}
