//! `posg-fsc translate`: an LTL formula's deterministic Rabin automaton.

use std::fmt::Write;

use anyhow::Context;
use clap::Args;
use posg_fsc::automaton::{Dra, Letter};
use posg_fsc::ltl;

/// Arguments of `translate`.
#[derive(Debug, Args)]
pub struct TranslateArgs {
    /// The LTL formula, in Spot's syntax (e.g. 'GF goal & G !unsafe').
    formula: String,
    /// Print the automaton in the HOA format instead of a table.
    #[arg(long)]
    hoa: bool,
}

/// Parses and translates the formula and prints its automaton.
pub fn run(args: TranslateArgs) -> anyhow::Result<()> {
    let formula = ltl::parse(&args.formula).context("cannot parse the formula")?;
    let dra = ltl::translate(&formula).context("cannot translate the formula")?;
    let text = if args.hoa {
        posg_fsc::automaton::write_hoa(&dra, Some(&formula.to_string()))
    } else {
        table(&formula, &dra)
    };
    super::common::print_text(&text)
}

/// The letter as the set of propositions holding in it, e.g. `{a, c}`.
fn letter_name(dra: &Dra, letter: Letter) -> String {
    let holding: Vec<&str> = dra
        .propositions()
        .iter()
        .enumerate()
        .filter(|(bit, _)| (letter >> bit) & 1 == 1)
        .map(|(_, p)| p.as_str())
        .collect();
    format!("{{{}}}", holding.join(", "))
}

/// A readable description: states with their Rabin pair memberships and
/// their transitions grouped by target.
fn table(formula: &ltl::Formula, dra: &Dra) -> String {
    let mut out = String::new();
    let letters = 1u32 << dra.propositions().len();
    let _ = writeln!(out, "formula: {formula}");
    let _ = writeln!(out, "propositions: [{}]", dra.propositions().join(", "));
    let _ = writeln!(
        out,
        "{} states, initial state {}, {} Rabin pairs (L_i visited finitely often, K_i infinitely often)",
        dra.num_states(),
        dra.initial(),
        dra.pairs().len()
    );
    for q in 0..dra.num_states() {
        let member = |pick: fn(&posg_fsc::automaton::RabinPair) -> &Vec<bool>, name: &str| {
            dra.pairs()
                .iter()
                .enumerate()
                .filter(|(_, pair)| pick(pair)[q])
                .map(|(i, _)| format!("{name}{i}"))
                .collect::<Vec<_>>()
        };
        let mut labels = member(|p| &p.fin, "L");
        labels.extend(member(|p| &p.inf, "K"));
        let _ = writeln!(out, "state {q} [{}]", labels.join(" "));
        let mut targets: Vec<usize> = (0..letters).map(|a| dra.successor(q, a)).collect();
        targets.sort_unstable();
        targets.dedup();
        for target in targets {
            let on: Vec<String> = (0..letters)
                .filter(|&a| dra.successor(q, a) == target)
                .map(|a| letter_name(dra, a))
                .collect();
            let _ = writeln!(out, "  -> {target} on {}", on.join(" "));
        }
    }
    out
}
