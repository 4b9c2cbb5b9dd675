//! Graph algorithms on finite directed graphs: strongly connected components
//! (Tarjan 1972, iterative so that graphs with millions of vertices cannot
//! overflow the call stack), bottom components, and backward reachability.
//!
//! All algorithms run in `O(|V| + |E|)` time and take any [`Digraph`]; the
//! global Markov chain implements it on its sparsity structure and MDP
//! analyses implement it on restricted sub-graphs.

/// A directed graph on vertices `0..num_vertices()`.
pub trait Digraph {
    /// The number of vertices.
    fn num_vertices(&self) -> usize;
    /// The successors of `v` (duplicates allowed).
    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_;
}

/// A digraph in compressed sparse row form: the successors of `v` are
/// `targets[offsets[v]..offsets[v + 1]]`.
#[derive(Debug, Clone, Copy)]
pub struct CsrGraph<'a> {
    /// Row offsets, `num_vertices + 1` entries.
    pub offsets: &'a [usize],
    /// Column indices.
    pub targets: &'a [u32],
}

impl Digraph for CsrGraph<'_> {
    fn num_vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        self.targets[self.offsets[v]..self.offsets[v + 1]]
            .iter()
            .map(|&t| t as usize)
    }
}

/// The strongly connected components of a digraph.
///
/// Components are numbered `0..count` in **reverse topological order**: if
/// an edge leads from component `a` to a different component `b`, then
/// `b < a`. In particular component 0 is a bottom component.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Components {
    /// `component[v]`: the component of vertex `v`.
    pub component: Vec<u32>,
    /// The number of components.
    pub count: usize,
}

impl Components {
    /// The vertices of each component, in increasing vertex order.
    pub fn members(&self) -> Vec<Vec<usize>> {
        let mut members = vec![Vec::new(); self.count];
        for (v, &c) in self.component.iter().enumerate() {
            members[c as usize].push(v);
        }
        members
    }

    /// The vertices of each component in one array: those of component `c`
    /// are `vertices[offsets[c]..offsets[c + 1]]`, in increasing order
    /// (a counting sort, `O(|V|)`). Returns `(offsets, vertices)`.
    pub fn grouped(&self) -> (Vec<usize>, Vec<u32>) {
        let mut offsets = vec![0usize; self.count + 1];
        for &c in &self.component {
            offsets[c as usize + 1] += 1;
        }
        for c in 0..self.count {
            offsets[c + 1] += offsets[c];
        }
        let mut fill = offsets.clone();
        let mut vertices = vec![0u32; self.component.len()];
        for (v, &c) in self.component.iter().enumerate() {
            vertices[fill[c as usize]] = v as u32;
            fill[c as usize] += 1;
        }
        (offsets, vertices)
    }
}

const UNVISITED: u32 = u32::MAX;

/// Tarjan's algorithm without recursion: `O(|V| + |E|)` time, `O(|V|)` extra memory.
pub fn strongly_connected_components<G: Digraph>(graph: &G) -> Components {
    let n = graph.num_vertices();
    let mut index = vec![UNVISITED; n];
    let mut lowlink = vec![0u32; n];
    let mut on_stack = vec![false; n];
    let mut component = vec![UNVISITED; n];
    let mut tarjan_stack: Vec<usize> = Vec::new();
    let mut call_stack = Vec::new();
    let mut next_index = 0u32;
    let mut count = 0u32;

    for root in 0..n {
        if index[root] != UNVISITED {
            continue;
        }
        index[root] = next_index;
        lowlink[root] = next_index;
        next_index += 1;
        tarjan_stack.push(root);
        on_stack[root] = true;
        call_stack.push((root, graph.successors(root)));

        while let Some((v, successors)) = call_stack.last_mut() {
            let v = *v;
            if let Some(w) = successors.next() {
                if index[w] == UNVISITED {
                    index[w] = next_index;
                    lowlink[w] = next_index;
                    next_index += 1;
                    tarjan_stack.push(w);
                    on_stack[w] = true;
                    call_stack.push((w, graph.successors(w)));
                } else if on_stack[w] {
                    lowlink[v] = lowlink[v].min(index[w]);
                }
                continue;
            }
            call_stack.pop();
            if let Some((parent, _)) = call_stack.last() {
                lowlink[*parent] = lowlink[*parent].min(lowlink[v]);
            }
            if lowlink[v] == index[v] {
                loop {
                    let w = tarjan_stack.pop().expect("v is on the Tarjan stack");
                    on_stack[w] = false;
                    component[w] = count;
                    if w == v {
                        break;
                    }
                }
                count += 1;
            }
        }
    }
    Components {
        component,
        count: count as usize,
    }
}

/// For each component, whether it is a bottom component (no edge leaves it):
/// in a Markov chain these are exactly the recurrence classes.
pub fn bottom_components<G: Digraph>(graph: &G, components: &Components) -> Vec<bool> {
    let mut bottom = vec![true; components.count];
    for v in 0..graph.num_vertices() {
        let c = components.component[v];
        if graph.successors(v).any(|w| components.component[w] != c) {
            bottom[c as usize] = false;
        }
    }
    bottom
}

/// The vertices from which some vertex with `target[v]` is reachable
/// (including the targets), given the graph's **reverse** (predecessor) graph.
pub fn backward_reachable<G: Digraph>(reverse: &G, target: &[bool]) -> Vec<bool> {
    let mut reached = target.to_vec();
    let mut frontier: Vec<usize> = (0..target.len()).filter(|&v| target[v]).collect();
    while let Some(v) = frontier.pop() {
        for u in reverse.successors(v) {
            if !reached[u] {
                reached[u] = true;
                frontier.push(u);
            }
        }
    }
    reached
}

/// The reverse of a CSR graph, in CSR form: `(offsets, targets)` with the
/// predecessors of each vertex in increasing order.
pub fn reverse_csr(graph: &CsrGraph<'_>) -> (Vec<usize>, Vec<u32>) {
    let n = graph.num_vertices();
    let mut offsets = vec![0usize; n + 1];
    for &t in graph.targets {
        offsets[t as usize + 1] += 1;
    }
    for v in 0..n {
        offsets[v + 1] += offsets[v];
    }
    let mut fill = offsets.clone();
    let mut targets = vec![0u32; graph.targets.len()];
    for v in 0..n {
        for w in graph.successors(v) {
            targets[fill[w]] = v as u32;
            fill[w] += 1;
        }
    }
    (offsets, targets)
}

#[cfg(test)]
// Reachability matrices are read as reach[a][b] and reach[b][a]: index loops are clearer.
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn csr(n: usize, edges: &[(usize, usize)]) -> (Vec<usize>, Vec<u32>) {
        let mut rows = vec![Vec::new(); n];
        for &(a, b) in edges {
            rows[a].push(b as u32);
        }
        let mut offsets = vec![0];
        let mut targets = Vec::new();
        for row in rows {
            targets.extend(row);
            offsets.push(targets.len());
        }
        (offsets, targets)
    }

    fn reaches(n: usize, edges: &[(usize, usize)], from: usize) -> Vec<bool> {
        let mut seen = vec![false; n];
        let mut stack = vec![from];
        seen[from] = true;
        while let Some(v) = stack.pop() {
            for &(a, b) in edges {
                if a == v && !seen[b] {
                    seen[b] = true;
                    stack.push(b);
                }
            }
        }
        seen
    }

    #[test]
    fn two_cycles_and_a_bridge() {
        let edges = [(0, 1), (1, 0), (1, 2), (2, 3), (3, 2), (4, 4)];
        let (offsets, targets) = csr(5, &edges);
        let graph = CsrGraph {
            offsets: &offsets,
            targets: &targets,
        };
        let sccs = strongly_connected_components(&graph);
        assert_eq!(sccs.count, 3);
        assert_eq!(sccs.component[0], sccs.component[1]);
        assert_eq!(sccs.component[2], sccs.component[3]);
        assert!(
            sccs.component[2] < sccs.component[0],
            "reverse topological order"
        );
        let bottom = bottom_components(&graph, &sccs);
        assert!(!bottom[sccs.component[0] as usize]);
        assert!(bottom[sccs.component[2] as usize]);
        assert!(bottom[sccs.component[4] as usize]);
    }

    #[test]
    fn a_long_path_does_not_overflow_the_stack() {
        let n = 1_000_000;
        let edges: Vec<(usize, usize)> = (0..n - 1).map(|v| (v, v + 1)).collect();
        let (offsets, targets) = csr(n, &edges);
        let sccs = strongly_connected_components(&CsrGraph {
            offsets: &offsets,
            targets: &targets,
        });
        assert_eq!(sccs.count, n);
    }

    proptest! {
        #[test]
        fn components_are_mutual_reachability(
            n in 1usize..12,
            raw in proptest::collection::vec((0usize..12, 0usize..12), 0..40),
        ) {
            let edges: Vec<(usize, usize)> = raw.into_iter().map(|(a, b)| (a % n, b % n)).collect();
            let (offsets, targets) = csr(n, &edges);
            let graph = CsrGraph { offsets: &offsets, targets: &targets };
            let sccs = strongly_connected_components(&graph);
            let reach: Vec<Vec<bool>> = (0..n).map(|v| reaches(n, &edges, v)).collect();
            for a in 0..n {
                for b in 0..n {
                    let same = sccs.component[a] == sccs.component[b];
                    prop_assert_eq!(same, reach[a][b] && reach[b][a]);
                    if reach[a][b] && !same {
                        prop_assert!(sccs.component[b] < sccs.component[a]);
                    }
                }
            }
            let (group_offsets, grouped) = sccs.grouped();
            let members = sccs.members();
            for c in 0..sccs.count {
                let group: Vec<usize> = grouped[group_offsets[c]..group_offsets[c + 1]]
                    .iter()
                    .map(|&v| v as usize)
                    .collect();
                prop_assert_eq!(&group, &members[c]);
            }
            let (roffsets, rtargets) = reverse_csr(&graph);
            let target: Vec<bool> = (0..n).map(|v| v == n - 1).collect();
            let back = backward_reachable(&CsrGraph { offsets: &roffsets, targets: &rtargets }, &target);
            for v in 0..n {
                prop_assert_eq!(back[v], reach[v][n - 1]);
            }
        }
    }
}
