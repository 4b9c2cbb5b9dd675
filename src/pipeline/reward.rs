//! The expected-reward objective of every face (method.md section 9): a
//! property's `R{"r"}min=? [F T]` or `R{"r"}max=? [F T]` made for a game,
//! with its reward model looked up and the automaton of `F T` translated
//! and checked against the game's labels.

use super::{PipelineError, check_target_propositions};
use crate::automaton::Dra;
use crate::controller::{Probabilities, Support};
use crate::game::{ModelError, Posg, RewardModel};
use crate::ltl::{self, props::RewardQuery};
use crate::optimise::ExpectedReward;
use crate::value::{Evaluator, SolverSettings, ValueError};

/// An expected-reward objective for one game: the expected total reward of
/// `rewards` until the first state satisfying the target `T`, which the
/// defender minimises (a cost) or maximises (method.md section 9).
#[derive(Debug, Clone)]
pub struct RewardObjective {
    /// The reward model.
    pub rewards: RewardModel,
    /// The automaton of `F T`, whose accepting states mark the runs that
    /// have reached `T`.
    pub target: Dra,
    /// The automaton of `!F T`, with which the almost-sure support
    /// synthesis certifies a cost's supports (method.md sections 7, 9).
    pub not_target: Dra,
    /// Whether the defender minimises the expected reward (`Rmin`, a cost)
    /// rather than maximises it (`Rmax`).
    pub minimise: bool,
    /// The query in Storm's words, `R{"r"}min=? [F T]`, for reports.
    pub description: String,
}

impl RewardObjective {
    /// The objective of `query` on `game`, minimised or not: its reward
    /// model (by name, or the game's only one), and the automaton of `F T`
    /// translated within `budget` with its propositions checked against the
    /// game's labels as [`super::Automata::for_game`] checks a formula's
    /// (`allow_unused`). Returns the objective and the check's warnings.
    pub fn for_game(
        game: &Posg,
        query: &RewardQuery,
        minimise: bool,
        budget: &ltl::TranslationBudget,
        allow_unused: bool,
    ) -> Result<(Self, Vec<String>), PipelineError> {
        let rewards = reward_model(game, query.model.as_deref())?.clone();
        let reach = query.reach_target();
        let target = ltl::translate_within(&reach, budget)?;
        let not_target = ltl::translate_within(&reach.negate(), budget)?;
        let description = format!(
            "R{{\"{}\"}}{}=? [{reach}]",
            rewards.name(),
            if minimise { "min" } else { "max" }
        );
        let check = check_target_propositions(&target, game, &description, allow_unused);
        if check.error.is_some() {
            return Err(PipelineError::Propositions(check));
        }
        let objective = Self {
            rewards,
            target,
            not_target,
            minimise,
            description,
        };
        Ok((objective, check.warnings))
    }
}

impl RewardObjective {
    /// The objective as the optimiser takes it
    /// ([`crate::optimise::optimise_expected_reward`]).
    pub fn optimised(&self) -> ExpectedReward<'_> {
        ExpectedReward {
            target: &self.target,
            not_target: &self.not_target,
            rewards: &self.rewards,
            minimise: self.minimise,
        }
    }

    /// The probability of reaching the target under the controllers of
    /// `supports` with `probabilities`, which `evaluator` (built for this
    /// objective on those supports) evaluates: 1 where it finds the reward
    /// finite, else computed (it says by how much the target is missed).
    pub fn target_probability(
        &self,
        game: &Posg,
        evaluator: &Evaluator,
        supports: (&Support, &Support),
        probabilities: (&Probabilities, &Probabilities),
        settings: &SolverSettings,
    ) -> Result<f64, ValueError> {
        if !evaluator.is_infinite() {
            return Ok(1.0);
        }
        let mut reach = Evaluator::new(game, &self.target, supports.0, supports.1, settings)?;
        Ok(reach.evaluate(probabilities.0, probabilities.1)?.value)
    }
}

/// The game's reward model `name`, or its only one for `None`.
fn reward_model<'a>(game: &'a Posg, name: Option<&str>) -> Result<&'a RewardModel, ModelError> {
    let names: Vec<&str> = game.reward_model_names().collect();
    let listed = || match names.as_slice() {
        [] => "it has none (DRN files carry them in `@reward_models`, JSON games in \
               `rewards`: docs/formats.md sections 1 and 6)"
            .to_string(),
        names => format!(
            "its reward models: {}",
            names
                .iter()
                .map(|n| format!("\"{n}\""))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    match name {
        Some(name) => game.reward_model(name).ok_or_else(|| {
            ModelError::new(
                format!("R{{\"{name}\"}}"),
                format!("the game has no reward model \"{name}\"; {}", listed()),
            )
        }),
        None => match game.reward_models() {
            [only] => Ok(only),
            _ => Err(ModelError::new(
                "R",
                format!(
                    "a query without a reward model's name needs a game with exactly one; \
                     name one as R{{\"name\"}}: {}",
                    listed()
                ),
            )),
        },
    }
}
