//! Translating all 55 Dwyer (DAC) specification patterns, together.

use criterion::{Criterion, criterion_group, criterion_main};
use posg_fsc::ltl;

fn dac_patterns() -> Vec<ltl::Formula> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/ltl/dac-patterns.ltl"
    );
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{path}: {e}"))
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| ltl::parse(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

fn translate_dac_patterns(c: &mut Criterion) {
    let patterns = dac_patterns();
    let states: usize = patterns
        .iter()
        .map(|f| ltl::translate(f).expect("translatable").num_states())
        .sum();
    println!("{} DAC patterns, {states} states in total", patterns.len());
    c.bench_function("translate 55 DAC patterns", |b| {
        b.iter(|| {
            patterns
                .iter()
                .map(|f| ltl::translate(std::hint::black_box(f)).map(|d| d.num_states()))
                .collect::<Vec<_>>()
        })
    });
}

criterion_group!(benches, translate_dac_patterns);
criterion_main!(benches);
