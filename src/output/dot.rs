//! Graphviz pictures of controllers: [`controller_dot`].

use std::fmt::Write as _;

use crate::controller::Fsc;

/// The default of [`controller_dot`]'s `threshold`: choices with a smaller
/// probability are left out of the picture (their count is shown).
pub const DEFAULT_THRESHOLD: f64 = 0.01;

/// A Graphviz `digraph` of `fsc`: one circle per node, an arrow from a start
/// point to each initial node (labelled with its probability), and one edge
/// `g -> g'` per pair of nodes that some choice connects, labelled with one
/// line `observation / action  p` per choice `mu(g', u | g, o) >= threshold`.
/// Choices below the threshold are hidden; the edge says how many (and an
/// edge whose choices are all below it is drawn dashed, without lines).
/// `observations` and `actions` name the player's observations and actions;
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
    let mut lines = Vec::new();
    let mut hidden = 0;
    for (o, name) in observations.iter().enumerate() {
        for c in fsc.choices(g, o).iter().filter(|c| c.next == next) {
            if c.probability >= threshold {
                lines.push(format!(
                    "{} / {}  {}",
                    escape(name),
                    escape(&actions[c.action]),
                    probability(c.probability)
                ));
            } else {
                hidden += 1;
            }
        }
    }
    if lines.is_empty() && hidden == 0 {
        return;
    }
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
