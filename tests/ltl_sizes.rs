//! Sizes of the translated automata against the reference state counts of
//! `tests/data/ltl/reference-sizes.tsv` (state-based deterministic parity
//! automata from a leading translator). Set `POSG_FSC_WRITE_RESULTS=1` to
//! rewrite `results/ltl-sizes.tsv`.

use posg_fsc::ltl;

const REFERENCE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/ltl/reference-sizes.tsv"
);
const RESULTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/results/ltl-sizes.tsv");

/// `(formula, reference states, our states or the translation error)`.
fn sizes() -> Vec<(String, usize, Result<usize, String>)> {
    std::fs::read_to_string(REFERENCE)
        .unwrap_or_else(|e| panic!("{REFERENCE}: {e}"))
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|line| {
            let (text, reference) = line.split_once('\t').expect("formula<TAB>states");
            let formula = ltl::parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
            let ours = ltl::translate(&formula)
                .map(|dra| dra.num_states())
                .map_err(|e| e.to_string());
            (
                text.to_string(),
                reference.trim().parse().expect("a state count"),
                ours,
            )
        })
        .collect()
}

#[test]
fn sizes_against_the_reference() {
    let rows = sizes();
    let mut table = String::from("# formula\treference_states\tour_states\tratio\n");
    for (text, reference, ours) in &rows {
        let (states, ratio) = match ours {
            Ok(n) => (
                n.to_string(),
                format!("{:.2}", *n as f64 / *reference as f64),
            ),
            Err(e) => (format!("error: {e}"), "-".to_string()),
        };
        table.push_str(&format!("{text}\t{reference}\t{states}\t{ratio}\n"));
    }
    print!("{table}");
    if std::env::var_os("POSG_FSC_WRITE_RESULTS").is_some() {
        std::fs::write(RESULTS, &table).unwrap();
    }
    let paper = rows
        .iter()
        .find(|(t, _, _)| t == "GF goal & G !unsafe")
        .unwrap();
    assert_eq!(paper.2, Ok(3), "the paper's formula");
}
