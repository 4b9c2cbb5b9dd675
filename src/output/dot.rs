//! Graphviz pictures of controllers: [`controller_dot`].

use std::fmt::Write as _;

use crate::controller::Fsc;

/// The default of [`controller_dot`]'s `threshold`: choices with a smaller
/// probability are left out of the picture (their count is shown).
pub const DEFAULT_THRESHOLD: f64 = 0.01;

/// A Graphviz `digraph` of `fsc`: one circle per node, an arrow from a start
/// point to each initial node (labelled with its probability), and one edge
/// `g -> g'` per pair of nodes that some choice connects, labelled with one
/// line `observation / action  p` per choice `mu(g', u | g, o) >= threshold`
/// (on an edge of more than [`MAX_EDGE_LINES`] choices, one line per action
/// and probability with the observations that choose it).
/// Choices below the threshold are hidden; the edge says how many (and an
/// edge whose choices are all below it is drawn dashed, without lines).
/// `observations` and `actions` name the player's observations and actions
/// (the labels of an imported model, [`crate::game::Player::action_labels`]);
/// `title` labels the graph.
pub fn controller_dot(
    fsc: &Fsc,
    observations: &[String],
    actions: &[String],
    title: &str,
    threshold: f64,
) -> String {
    let mut out = format!(
        "digraph controller {{\n  label=\"{}\";\n  labelloc=t;\n  rankdir=LR;\n  \
         node [shape=circle, fontname=\"Helvetica\"];\n  edge [fontname=\"Helvetica\", fontsize=10];\n  \
         start [shape=point];\n",
        escape(title)
    );
    for g in 0..fsc.num_nodes() {
        writeln!(out, "  n{g} [label=\"{g}\"];").expect("writing to a String");
    }
    for (g, &p) in fsc.initial().iter().enumerate() {
        if p > 0.0 {
            writeln!(out, "  start -> n{g} [label=\"{}\"];", probability(p))
                .expect("writing to a String");
        }
    }
    for g in 0..fsc.num_nodes() {
        for next in 0..fsc.num_nodes() {
            edge(&mut out, fsc, g, next, observations, actions, threshold);
        }
    }
    out.push_str("}\n");
    out
}

/// The edge `g -> next`, if some choice takes it.
fn edge(
    out: &mut String,
    fsc: &Fsc,
    g: usize,
    next: usize,
    observations: &[String],
    actions: &[String],
    threshold: f64,
) {
    let mut shown = Vec::new();
    let mut hidden = 0;
    for (o, name) in observations.iter().enumerate() {
        for c in fsc.choices(g, o).iter().filter(|c| c.next == next) {
            if c.probability >= threshold {
                let action = escape(&actions[c.action]);
                shown.push((escape(name), action, probability(c.probability)));
            } else {
                hidden += 1;
            }
        }
    }
    if shown.is_empty() && hidden == 0 {
        return;
    }
    // The line counting the hidden choices takes one of the edge's lines.
    let room = MAX_EDGE_LINES - usize::from(hidden > 0);
    let mut lines: Vec<String> = if shown.len() <= room {
        (shown.iter())
            .map(|(observation, action, p)| format!("{observation} / {action}  {p}"))
            .collect()
    } else {
        grouped(&shown, room)
    };
    if hidden > 0 {
        lines.push(format!("({hidden} below {threshold})"));
    }
    let style = if lines.len() == 1 && hidden > 0 {
        ", style=dashed"
    } else {
        ""
    };
    let label: String = lines.iter().map(|l| format!("{l}\\l")).collect();
    writeln!(out, "  n{g} -> n{next} [label=\"{label}\"{style}];").expect("writing to a String");
}

/// An edge with more choices than this shows them grouped by action and
/// probability ([`grouped`]), in at most this many lines.
pub const MAX_EDGE_LINES: usize = 12;

/// A group's line names at most this many observations.
const NAMED_OBSERVATIONS: usize = 4;

/// The lines of an edge with many `(observation, action, probability)`
/// choices: one per action and probability, `U  1: s2, s14, s17, s18 and
/// 54 more`, the groups with most observations first, at most
/// `room` lines (the last saying how many choices the others hold).
fn grouped(shown: &[(String, String, String)], room: usize) -> Vec<String> {
    let mut groups: Vec<((&str, &str), Vec<&str>)> = Vec::new();
    for (observation, action, p) in shown {
        let key = (action.as_str(), p.as_str());
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, members)) => members.push(observation),
            None => groups.push((key, vec![observation])),
        }
    }
    groups.sort_by_key(|(_, members)| std::cmp::Reverse(members.len()));
    let kept = if groups.len() > room {
        room - 1
    } else {
        groups.len()
    };
    let mut lines: Vec<String> = (groups[..kept].iter())
        .map(|((action, p), members)| {
            let named = members[..members.len().min(NAMED_OBSERVATIONS)].join(", ");
            let more = members.len().saturating_sub(NAMED_OBSERVATIONS);
            let more = if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            };
            format!("{action}  {p}: {named}{more}")
        })
        .collect();
    let folded: usize = groups[kept..].iter().map(|(_, m)| m.len()).sum();
    if folded > 0 {
        lines.push(format!("({folded} more choices)"));
    }
    lines
}

/// A probability with at most four decimals, trailing zeros dropped.
fn probability(p: f64) -> String {
    let text = format!("{p:.4}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    text.to_string()
}

/// `text` safe inside a double-quoted Graphviz string.
fn escape(text: &str) -> String {
    text.replace('\\', "\\\\").replace('"', "\\\"")
}
