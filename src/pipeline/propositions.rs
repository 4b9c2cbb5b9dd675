//! The objective's propositions against the game's labels: a proposition
//! that labels no state is false everywhere (docs/formats.md section 3),
//! which is usually a misspelling. [`check_propositions`] says which ones,
//! with the closest proposition of the game as a hint, and refuses an
//! objective that they make unsatisfiable (every value would be 0). The
//! command line and the Python package both report through it.

use crate::automaton::Dra;
use crate::game::Posg;

/// What the check found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PropositionCheck {
    /// `proposition 'x' labels no state of the game; it is false
    /// everywhere (did you mean y?)`, one per unused proposition.
    pub warnings: Vec<String>,
    /// The error when the unused propositions make the objective
    /// unsatisfiable (every value 0) and that was not allowed.
    pub error: Option<String>,
}

/// Checks the propositions of `dra` against `game`'s labels; `objective`
/// describes the objective in the error, `allow` accepts an objective made
/// unsatisfiable by unused propositions.
pub fn check_propositions(
    dra: &Dra,
    game: &Posg,
    objective: &str,
    allow: bool,
) -> PropositionCheck {
    let consequence = "false everywhere it makes every value 0";
    check_against_labels(dra, game, (objective, consequence), allow)
}

/// [`check_propositions`] for the automaton of an expected reward's `F T`
/// (docs/method.md section 9): a target that is never reached makes every
/// value infinite, which the error says.
pub fn check_target_propositions(
    target: &Dra,
    game: &Posg,
    objective: &str,
    allow: bool,
) -> PropositionCheck {
    let consequence = "the target is never reached: every expected reward is infinite";
    check_against_labels(target, game, (objective, consequence), allow)
}

/// The check, its error saying what an objective that can never hold
/// means (`consequence`).
fn check_against_labels(
    dra: &Dra,
    game: &Posg,
    (objective, consequence): (&str, &str),
    allow: bool,
) -> PropositionCheck {
    let mut unused_mask = 0;
    let mut warnings = Vec::new();
    let mut hints = Vec::new();
    for (bit, name) in dra.propositions().iter().enumerate() {
        if game.propositions().contains(name) {
            continue;
        }
        unused_mask |= 1 << bit;
        let hint = game
            .closest_proposition(name)
            .map(|p| format!(" (did you mean {p}?)"))
            .unwrap_or_default();
        warnings.push(format!(
            "proposition '{name}' labels no state of the game; it is false everywhere{hint}"
        ));
        hints.push(format!("'{name}'{hint}"));
    }
    let never_holds = unused_mask != 0 && !dra.accepts_some_word(|a| a & unused_mask == 0);
    let error = (never_holds && !allow).then(|| {
        format!(
            "the objective {objective} can never hold: {} labels no state of the game, and \
             {consequence}. Fix the name, or allow unused propositions \
             (--allow-unused-propositions; allow_unused_propositions=True in Python) to \
             compute with it anyway",
            hints.join(", ")
        )
    });
    PropositionCheck { warnings, error }
}
