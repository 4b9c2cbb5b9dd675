//! The HOA writer: a [`Dra`] as HOA v1 text with state-based `Rabin n`
//! acceptance.
//!
//! Contract: [`write_hoa`] takes any valid [`Dra`] and returns the text; it
//! cannot fail. The output has one edge per distinct successor of a state,
//! labelled with an irredundant sum of cubes over AP indices, so
//! [`super::read_hoa_dra`] reads back an automaton with the same states,
//! transitions and pairs.

use std::fmt::Write as _;

use crate::automaton::{Dra, Letter};

/// Prints `dra` as HOA v1 with state-based acceptance `Rabin n`: pair `i`
/// becomes `Fin(2i) & Inf(2i+1)`, state `q` carries mark `2i` iff it is in
/// `L_i` and mark `2i + 1` iff it is in `K_i`. Each state has one edge per
/// successor, labelled with an irredundant sum of cubes over AP indices
/// (`t` when one successor takes every letter). `name` becomes the `name:`
/// item.
pub fn write_hoa(dra: &Dra, name: Option<&str>) -> String {
    let mut out = String::from("HOA: v1\n");
    if let Some(name) = name {
        writeln!(out, "name: {}", quoted(name)).expect("writing to a String");
    }
    write_header(&mut out, dra);
    out.push_str("--BODY--\n");
    for q in 0..dra.num_states() {
        write_state(&mut out, dra, q);
    }
    out.push_str("--END--\n");
    out
}

/// The `States:` to `properties:` items.
fn write_header(out: &mut String, dra: &Dra) {
    let props = dra.propositions();
    let names: String = props.iter().map(|p| format!(" {}", quoted(p))).collect();
    let n = dra.pairs().len();
    let acceptance = if n == 0 {
        "f".to_string()
    } else {
        (0..n)
            .map(|i| format!("(Fin({})&Inf({}))", 2 * i, 2 * i + 1))
            .collect::<Vec<_>>()
            .join(" | ")
    };
    writeln!(
        out,
        "States: {}\nStart: {}\nAP: {}{names}\nacc-name: Rabin {n}\nAcceptance: {} {acceptance}\n\
         properties: trans-labels explicit-labels state-acc deterministic complete",
        dra.num_states(),
        dra.initial(),
        props.len(),
        2 * n,
    )
    .expect("writing to a String");
}

/// One `State:` line and its edges.
fn write_state(out: &mut String, dra: &Dra, q: usize) {
    let marks: Vec<String> = dra
        .pairs()
        .iter()
        .enumerate()
        .flat_map(|(i, p)| {
            [(p.fin[q], 2 * i), (p.inf[q], 2 * i + 1)]
                .into_iter()
                .filter(|&(member, _)| member)
                .map(|(_, mark)| mark.to_string())
        })
        .collect();
    if marks.is_empty() {
        writeln!(out, "State: {q}").expect("writing to a String");
    } else {
        writeln!(out, "State: {q} {{{}}}", marks.join(" ")).expect("writing to a String");
    }
    let props = dra.propositions().len();
    let letters = 1usize << props;
    let mut targets: Vec<usize> = (0..letters)
        .map(|a| dra.successor(q, a as Letter))
        .collect();
    let table = targets.clone();
    targets.sort_unstable();
    targets.dedup();
    for target in targets {
        let on: Vec<bool> = table.iter().map(|&t| t == target).collect();
        writeln!(out, "[{}] {target}", label_text(&on, props)).expect("writing to a String");
    }
}

/// A HOA string literal.
pub(super) fn quoted(text: &str) -> String {
    let mut out = String::from("\"");
    for c in text.chars() {
        if c == '"' || c == '\\' {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

/// A product of literals: proposition `i` is constrained iff bit `i` of
/// `care` is set, and then must have the value of bit `i` of `value`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Cube {
    care: Letter,
    value: Letter,
}

/// A label for the letters `a` with `on[a]`, as a sum of cubes.
fn label_text(on: &[bool], props: usize) -> String {
    let cubes = isop(on, on, props);
    if cubes.is_empty() {
        return "f".to_string();
    }
    cubes
        .iter()
        .map(|cube| cube_text(*cube, props))
        .collect::<Vec<_>>()
        .join(" | ")
}

/// A cube as `0&!1&...`, or `t` for the empty cube.
fn cube_text(cube: Cube, props: usize) -> String {
    let literals: Vec<String> = (0..props)
        .filter(|i| cube.care >> i & 1 == 1)
        .map(|i| {
            if cube.value >> i & 1 == 1 {
                i.to_string()
            } else {
                format!("!{i}")
            }
        })
        .collect();
    if literals.is_empty() {
        "t".to_string()
    } else {
        literals.join("&")
    }
}

/// An irredundant sum of cubes covering every letter of `lower` and only
/// letters of `upper` (`lower` implies `upper`), over propositions
/// `0..vars`, by the Minato-Morreale recursion on the top proposition.
fn isop(lower: &[bool], upper: &[bool], vars: usize) -> Vec<Cube> {
    if !lower.contains(&true) {
        return Vec::new();
    }
    if !upper.contains(&false) {
        return vec![Cube { care: 0, value: 0 }];
    }
    let half = lower.len() / 2;
    let x = (vars - 1) as u32;
    let (l0, l1) = lower.split_at(half);
    let (u0, u1) = upper.split_at(half);
    let only0: Vec<bool> = l0.iter().zip(u1).map(|(&l, &u)| l && !u).collect();
    let only1: Vec<bool> = l1.iter().zip(u0).map(|(&l, &u)| l && !u).collect();
    let cubes0 = isop(&only0, u0, vars - 1);
    let cubes1 = isop(&only1, u1, vars - 1);
    let covered0 = cover(&cubes0, half);
    let covered1 = cover(&cubes1, half);
    let rest: Vec<bool> = (0..half)
        .map(|a| (l0[a] && !covered0[a]) || (l1[a] && !covered1[a]))
        .collect();
    let both: Vec<bool> = u0.iter().zip(u1).map(|(&a, &b)| a && b).collect();
    let shared = isop(&rest, &both, vars - 1);
    let with = |value: Letter| {
        move |c: Cube| Cube {
            care: c.care | 1 << x,
            value: c.value | value << x,
        }
    };
    cubes0
        .into_iter()
        .map(with(0))
        .chain(cubes1.into_iter().map(with(1)))
        .chain(shared)
        .collect()
}

/// The letters `0..size` covered by some cube.
fn cover(cubes: &[Cube], size: usize) -> Vec<bool> {
    (0..size as Letter)
        .map(|a| cubes.iter().any(|c| a & c.care == c.value))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn label_of(letters: &[usize], props: usize) -> String {
        let on: Vec<bool> = (0..1 << props).map(|a| letters.contains(&a)).collect();
        label_text(&on, props)
    }

    #[test]
    fn labels_are_compact_sums_of_cubes() {
        assert_eq!(label_of(&[0, 1, 2, 3], 2), "t");
        assert_eq!(label_of(&[], 2), "f");
        assert_eq!(label_of(&[1, 3], 2), "0");
        assert_eq!(label_of(&[0, 2], 2), "!0");
        assert_eq!(label_of(&[1, 2], 2), "0&!1 | !0&1");
        assert_eq!(label_of(&[1, 2, 3], 2), "1 | 0");
        assert_eq!(label_of(&[0], 0), "t");
    }
}
