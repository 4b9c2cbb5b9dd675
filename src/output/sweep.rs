//! The rows of `sweep.csv` (docs/formats.md section 9): one per size pair
//! of a sweep, the best structure's numbers and certified bracket.

use serde::{Deserialize, Serialize};

/// The columns of `sweep.csv` and of each pair's `row.csv`, in order
/// (the fields of [`SweepRow`]; docs/formats.md section 9).
pub const SWEEP_COLUMNS: [&str; 16] = [
    "defender_nodes",
    "adversary_nodes",
    "structure",
    "gmc_states",
    "gmc_transitions",
    "defender_parameters",
    "adversary_parameters",
    "last_value",
    "worst_case",
    "error_bound",
    "certified_lower",
    "upper_bound",
    "iterations",
    "seconds",
    "warm_started",
    "result",
];

/// One row of `sweep.csv`: the best structure's numbers for one size pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    /// The defender controller's size.
    pub defender_nodes: usize,
    /// The adversary controller's size.
    pub adversary_nodes: usize,
    /// The structure whose result is reported.
    pub structure: String,
    /// States of the GMC on (s, g, h).
    pub gmc_states: usize,
    /// Transitions of the GMC.
    pub gmc_transitions: usize,
    /// Free parameters of the defender.
    pub defender_parameters: usize,
    /// Free parameters of the adversary.
    pub adversary_parameters: usize,
    /// The value of the last iterate.
    pub last_value: f64,
    /// The best worst-case estimate (best response found).
    pub worst_case: f64,
    /// The largest error bound of the values computed (method.md section 8).
    pub error_bound: f64,
    /// The certified lower bound (method.md section 6), if an automaton of
    /// the negated objective was available.
    pub certified_lower: Option<f64>,
    /// The game upper bound (method.md section 6), likewise.
    pub upper_bound: Option<f64>,
    /// Outer iterations run.
    pub iterations: usize,
    /// Wall-clock seconds of the optimisation (a timing column).
    pub seconds: f64,
    /// Whether the run started from the best defender of the next smaller size.
    pub warm_started: bool,
    /// Where the reported defender came from, in words: optimised on
    /// `structure`, or a smaller size's result kept because optimising
    /// found nothing better (then `last_value` is that of a run whose
    /// result was not kept).
    pub result: String,
}

impl SweepRow {
    /// `Err(problem)`, naming the column, unless every probability
    /// (`last_value`, `worst_case`, `certified_lower`, `upper_bound`) is a
    /// finite number in [0, 1], `certified_lower <= upper_bound` where both
    /// are present, and `error_bound` and `seconds` are finite and
    /// non-negative: what `sweep-merge` requires of each shard's row.
    pub fn check(&self) -> Result<(), String> {
        let probabilities = [
            ("last_value", Some(self.last_value)),
            ("worst_case", Some(self.worst_case)),
            ("certified_lower", self.certified_lower),
            ("upper_bound", self.upper_bound),
        ];
        for (column, value) in probabilities {
            if let Some(p) = value.filter(|p| !(0.0..=1.0).contains(p)) {
                return Err(format!(
                    "column `{column}`: {p} is not a probability (a finite number in [0, 1])"
                ));
            }
        }
        for (column, value) in [("error_bound", self.error_bound), ("seconds", self.seconds)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(format!(
                    "column `{column}`: {value} is not a finite non-negative number"
                ));
            }
        }
        match (self.certified_lower, self.upper_bound) {
            (Some(lower), Some(upper)) if lower > upper => Err(format!(
                "column `certified_lower`: {lower} is above `upper_bound` {upper}"
            )),
            _ => Ok(()),
        }
    }

    /// The row of the size pair `(defender_nodes, adversary_nodes)` from the
    /// pipeline's outcome: its best structure's numbers and certified
    /// bracket; `previous` is the smaller size's best outcome the run was
    /// warm-started from, if any.
    pub fn of(
        defender_nodes: usize,
        adversary_nodes: usize,
        outcome: &crate::pipeline::Outcome,
        previous: Option<&crate::optimise::StructureOutcome>,
    ) -> Self {
        let (report, certified) = (&outcome.best().report, outcome.certified);
        Self {
            defender_nodes,
            adversary_nodes,
            structure: report.name.clone(),
            gmc_states: report.gmc.states,
            gmc_transitions: report.gmc.transitions,
            defender_parameters: report.defender_parameters,
            adversary_parameters: report.adversary_parameters,
            last_value: report.last_value,
            worst_case: report.worst_case,
            error_bound: report.error_bound,
            certified_lower: certified.map(|b| b.certified_lower),
            upper_bound: certified.map(|b| b.upper_bound),
            iterations: report.iterations,
            seconds: report.seconds,
            warm_started: previous.is_some(),
            result: result_in_words(report, previous),
        }
    }

    /// The row with its timing column zeroed, for comparing runs.
    pub fn without_timing(&self) -> Self {
        Self {
            seconds: 0.0,
            ..self.clone()
        }
    }
}

/// Where a pair's reported defender came from, for the `result` column of
/// `sweep.csv`.
fn result_in_words(
    report: &crate::optimise::StructureReport,
    previous: Option<&crate::optimise::StructureOutcome>,
) -> String {
    let smaller = previous.map(|p| p.defender.num_nodes());
    match smaller {
        Some(k) if report.name.starts_with("from-") => {
            format!("the {k}-node result, kept: optimising found nothing better")
        }
        Some(k) if report.best_iteration == 0 => format!(
            "the {k}-node result it started from, kept: optimising on {} found nothing better",
            report.name
        ),
        Some(k) => format!(
            "optimised on {}, starting from the {k}-node result",
            report.name
        ),
        None => format!("optimised on {}", report.name),
    }
}

/// `rows` as the text of `sweep.csv` (a header, then one line per row).
pub fn sweep_table(rows: &[SweepRow]) -> Result<Vec<u8>, csv::Error> {
    let mut writer = csv::Writer::from_writer(Vec::new());
    for row in rows {
        writer.serialize(row)?;
    }
    writer.into_inner().map_err(|e| e.into_error().into())
}
