//! One chain of a sweep (docs/formats.md section 9): a fixed adversary
//! size, the defender sizes in increasing order, each job warm-started
//! from the best outcome of the size before and kept at least as good
//! ([`Job::warm_started`]), so the chain's results are monotone in the
//! defender's size. The faces run each job their own way (into a
//! directory, with observers) between [`Chain::job`] and [`Chain::row`].

use super::{Automata, Job, Outcome, PipelineError, Sizes};
use crate::game::Posg;
use crate::optimise::{Settings, StructureOutcome};
use crate::output::sweep::SweepRow;

/// A chain in progress: what it optimises and the best outcome of the last
/// size it finished.
#[derive(Debug)]
pub struct Chain<'a> {
    game: &'a Posg,
    automata: &'a Automata,
    settings: &'a Settings,
    adversary: usize,
    previous: Option<StructureOutcome>,
}

impl<'a> Chain<'a> {
    /// The chain of adversary size `adversary` on `game` and `automata`.
    pub fn new(
        game: &'a Posg,
        automata: &'a Automata,
        settings: &'a Settings,
        adversary: usize,
    ) -> Self {
        Self {
            game,
            automata,
            settings,
            adversary,
            previous: None,
        }
    }

    /// The job of `defender` nodes: from the full support, warm-started
    /// from the size before when there is one. Sizes must come in
    /// increasing order.
    pub fn job(&self, defender: usize) -> Result<Job<'_>, PipelineError> {
        let sizes = Sizes {
            defender,
            adversary: self.adversary,
        };
        let job = Job::full(self.game, self.automata, sizes, self.settings)?;
        match &self.previous {
            Some(smaller) => job.warm_started(smaller),
            None => Ok(job),
        }
    }

    /// The row of `sweep.csv` of `defender` nodes, whose job ([`Self::job`])
    /// gave `outcome`; that outcome's best structure warm-starts the next
    /// size.
    pub fn row(&mut self, defender: usize, outcome: &Outcome) -> SweepRow {
        let row = SweepRow::of(defender, self.adversary, outcome, self.previous.as_ref());
        self.previous = Some(outcome.best().clone());
        row
    }
}
