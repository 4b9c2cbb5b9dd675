//! The fill-reducing ordering of the multifrontal LU: approximate minimum
//! degree (faer's AMD) on the pattern of `A + A^T`, compressed first.
//!
//! States of a GMC that differ only in the controllers' memory nodes often
//! have the same successors and predecessors: in the graph of `A + A^T`
//! their closed neighbourhoods are equal ("indistinguishable" vertices,
//! George and Liu), and eliminating one makes the others' fill identical.
//! Ordering the quotient graph, one vertex per class, and numbering each
//! class's members consecutively gives the minimum degree order of the full
//! graph at a fraction of the cost (about 16 times fewer edges for 2-node
//! controllers).
//!
//! Minimum degree is greedy and local; on grid-like chains of 10^5 states
//! and more, nested dissection (split by a small separator, order both
//! halves first and the separator last, recursively) fills less and, above
//! all, needs fewer operations (at 3.3e5 unknowns, 0.66 times the numeric
//! factorisation time). Both orders are computed on the quotient graph and
//! compared by the cost of eliminating it, which faer's elimination tree
//! and column counts give in near-linear time.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;
use rustc_hash::FxHashMap;

use super::column_counts::column_counts;
use super::{SolverError, SparsePattern};

/// The pattern of `A + A^T` with the diagonal: for each vertex its closed
/// neighbourhood, sorted.
#[derive(Debug)]
pub(crate) struct SymmetricPattern {
    offsets: Vec<usize>,
    indices: Vec<usize>,
}

impl SymmetricPattern {
    /// The pattern of `A + A^T` (with every diagonal entry) of `pattern`.
    #[cfg(test)]
    pub(crate) fn of(pattern: &SparsePattern) -> Self {
        let neighbourhoods = ClosedNeighbourhoods::of(pattern);
        let mut symmetric = Self::empty();
        let mut scratch = Vec::new();
        for vertex in 0..pattern.n {
            symmetric.push(neighbourhoods.of_vertex(vertex, &mut scratch));
        }
        symmetric
    }

    fn empty() -> Self {
        Self {
            offsets: vec![0],
            indices: Vec::new(),
        }
    }

    /// Appends a vertex with the neighbours `neighbours`.
    fn push(&mut self, neighbours: &[usize]) {
        self.indices.extend_from_slice(neighbours);
        self.offsets.push(self.indices.len());
    }

    /// The number of vertices.
    pub(crate) fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The closed neighbourhood of `vertex`, sorted.
    pub(crate) fn neighbours(&self, vertex: usize) -> &[usize] {
        &self.indices[self.offsets[vertex]..self.offsets[vertex + 1]]
    }

    /// The upper triangle (rows at most the column), column-compressed.
    pub(crate) fn upper(&self) -> (Vec<usize>, Vec<usize>) {
        let mut offsets = Vec::with_capacity(self.len() + 1);
        offsets.push(0);
        let mut indices = Vec::with_capacity(self.indices.len() / 2 + self.len());
        for vertex in 0..self.len() {
            indices.extend(self.neighbours(vertex).iter().take_while(|&&i| i <= vertex));
            offsets.push(indices.len());
        }
        (offsets, indices)
    }

    /// The cost of a Cholesky factorisation in `order` (`order[new] =
    /// old`), from the column counts of the factor
    /// ([`column_counts`], near-linear in the graph's size).
    fn elimination(&self, order: &[usize]) -> Elimination {
        let n = self.len();
        let mut inverse = vec![0; n];
        for (new, &old) in order.iter().enumerate() {
            inverse[old] = new;
        }
        let mut permuted = Self {
            offsets: Vec::with_capacity(n + 1),
            indices: Vec::with_capacity(self.indices.len()),
        };
        permuted.offsets.push(0);
        for &old in order {
            permuted
                .indices
                .extend(self.neighbours(old).iter().map(|&w| inverse[w]));
            permuted.offsets.push(permuted.indices.len());
        }
        let counts = column_counts(n, |j| permuted.neighbours(j));
        Elimination {
            multiplications: counts.iter().map(|&c| (c as f64).powi(2)).sum(),
            largest_column: counts.iter().copied().max().unwrap_or(0),
        }
    }

    /// The graph with one vertex per class, adjacent when their members
    /// are, from the neighbourhoods of one member per class (`self`).
    fn quotient(&self, class_of: &[usize]) -> SymmetricPattern {
        let count = self.len();
        let mut quotient = Self::empty();
        let mut seen = vec![usize::MAX; count];
        let mut neighbours = Vec::new();
        for class in 0..count {
            neighbours.clear();
            for &neighbour in self.neighbours(class) {
                let other = class_of[neighbour];
                if seen[other] != class {
                    seen[other] = class;
                    neighbours.push(other);
                }
            }
            neighbours.sort_unstable();
            quotient.push(&neighbours);
        }
        quotient
    }
}

/// The closed neighbourhoods in `A + A^T` of the pattern of `A`, each
/// merged on demand from a row of `A` and a row of `A^T`.
struct ClosedNeighbourhoods<'a> {
    pattern: &'a SparsePattern,
    transposed_offsets: Vec<usize>,
    transposed: Vec<usize>,
}

impl<'a> ClosedNeighbourhoods<'a> {
    fn of(pattern: &'a SparsePattern) -> Self {
        let (transposed_offsets, transposed) = transpose(pattern);
        Self {
            pattern,
            transposed_offsets,
            transposed,
        }
    }

    /// The closed neighbourhood of `vertex`, sorted, written to `out`.
    fn of_vertex<'o>(&self, vertex: usize, out: &'o mut Vec<usize>) -> &'o [usize] {
        let row = &self.pattern.columns[self.pattern.row_range(vertex)];
        let column =
            &self.transposed[self.transposed_offsets[vertex]..self.transposed_offsets[vertex + 1]];
        out.clear();
        merge_sorted(row, column, vertex, out);
        out
    }
}

/// The classes of vertices of `A + A^T` with equal closed neighbourhoods,
/// numbered in the order of their first members: each vertex's class, the
/// members of each class, and the neighbourhood of each class. Only one
/// neighbourhood per class is kept, never the whole graph.
fn indistinguishable_classes(pattern: &SparsePattern) -> (Vec<usize>, Classes, SymmetricPattern) {
    let neighbourhoods = ClosedNeighbourhoods::of(pattern);
    let mut class_of = vec![0; pattern.n];
    let mut of_class = SymmetricPattern::empty();
    let mut by_hash: FxHashMap<u64, Vec<usize>> = FxHashMap::default();
    let mut scratch = Vec::new();
    for (vertex, class) in class_of.iter_mut().enumerate() {
        let neighbours = neighbourhoods.of_vertex(vertex, &mut scratch);
        let candidates = by_hash.entry(hash_of(neighbours)).or_default();
        let found = candidates
            .iter()
            .copied()
            .find(|&class| of_class.neighbours(class) == neighbours);
        *class = found.unwrap_or_else(|| {
            of_class.push(neighbours);
            candidates.push(of_class.len() - 1);
            of_class.len() - 1
        });
    }
    let members = Classes::of(&class_of, of_class.len());
    (class_of, members, of_class)
}

/// Below this many classes the quotient graph is ordered by minimum degree
/// alone: nested dissection never eliminated such graphs more cheaply
/// (grid GMCs of 2-node controllers: 1.06 times minimum degree's cost at
/// 4,092 classes, 0.88 at 16,380, 0.67 at 65,532), and computing it and
/// both costs took more time than the factorisation it ordered (a fifth
/// of a local search's time on 500-state products).
const DISSECTION_MIN_VERTICES: usize = 8192;

/// What eliminating a graph in some order costs.
struct Elimination {
    /// The multiplications: the sum of the squared column counts.
    multiplications: f64,
    /// The largest column count of the factor (with the diagonal).
    largest_column: usize,
}

/// The fill-reducing order of `A + A^T` for the pattern of `A`:
/// approximate minimum degree or nested dissection, both computed on
/// the quotient graph of indistinguishable vertices, whichever
/// eliminates it more cheaply (the quotient's cost counts classes, not
/// their sizes: a proxy when the classes are of equal size, as with
/// uniform controllers); minimum degree alone below
/// [`DISSECTION_MIN_VERTICES`] classes.
///
/// Nested dissection, near-linear, comes first: where its factor has a
/// column of more than `largest_front` classes, each at least one row of
/// a front, the LU is refused ([`SolverError::LuTooLarge`]) before minimum
/// degree runs. Minimum degree's own cost grows with the fill it makes:
/// on PAYNT's drone-2-8-1 (500,094 unknowns, at most 17 neighbours each)
/// it ran for minutes to find a front of 72,740 rows, beyond 32-bit
/// indices all the same.
pub(crate) fn fill_reducing_order(
    pattern: &SparsePattern,
    largest_front: usize,
) -> Result<ClassOrder, SolverError> {
    let (class_of, members, neighbourhoods) = indistinguishable_classes(pattern);
    let quotient = neighbourhoods.quotient(&class_of);
    let classes = if quotient.len() < DISSECTION_MIN_VERTICES {
        amd_order(&quotient)?
    } else {
        let by_dissection = nested_dissection(&quotient)?;
        let dissected = quotient.elimination(&by_dissection);
        if dissected.largest_column > largest_front {
            return Err(SolverError::LuTooLarge {
                unknowns: pattern.n,
                front: dissected.largest_column,
            });
        }
        let by_degree = amd_order(&quotient)?;
        if dissected.multiplications < quotient.elimination(&by_degree).multiplications {
            by_dissection
        } else {
            by_degree
        }
    };
    let mut starts = Vec::with_capacity(classes.len() + 1);
    starts.push(0);
    let mut permutation = Vec::with_capacity(pattern.n);
    for &class in &classes {
        permutation.extend_from_slice(members.members(class));
        starts.push(permutation.len());
    }
    Ok(ClassOrder {
        quotient,
        classes,
        starts,
        permutation,
    })
}

/// A fill-reducing order of a graph by classes of indistinguishable
/// vertices: the classes are eliminated in the order `classes`, the members
/// of each consecutively. Since members share their closed neighbourhood,
/// they share their column of the Cholesky factor below the class, so the
/// factor's structure is the quotient's with every class expanded to its
/// members ([`ClassOrder::positions`]).
pub(crate) struct ClassOrder {
    /// The graph with one vertex per class.
    pub(crate) quotient: SymmetricPattern,
    /// `classes[new] = class`: the classes in elimination order.
    pub(crate) classes: Vec<usize>,
    /// The members of `classes[new]` are at the positions
    /// `starts[new]..starts[new + 1]` of the full order.
    starts: Vec<usize>,
    /// The full order, `permutation[new] = old`.
    pub(crate) permutation: Vec<usize>,
}

impl ClassOrder {
    /// The positions in the full order of the members of the classes at
    /// positions `classes` of the class order.
    pub(crate) fn positions(&self, classes: std::ops::Range<usize>) -> std::ops::Range<usize> {
        self.starts[classes.start]..self.starts[classes.end]
    }
}

/// The members of each class, grouped.
struct Classes {
    offsets: Vec<usize>,
    members: Vec<usize>,
}

impl Classes {
    fn of(class_of: &[usize], count: usize) -> Self {
        let mut offsets = vec![0; count + 1];
        for &class in class_of {
            offsets[class + 1] += 1;
        }
        for class in 0..count {
            offsets[class + 1] += offsets[class];
        }
        let mut next = offsets.clone();
        let mut members = vec![0; class_of.len()];
        for (vertex, &class) in class_of.iter().enumerate() {
            members[next[class]] = vertex;
            next[class] += 1;
        }
        Self { offsets, members }
    }

    fn members(&self, class: usize) -> &[usize] {
        &self.members[self.offsets[class]..self.offsets[class + 1]]
    }
}

/// faer's approximate minimum degree order of `graph`, `order[new] = old`.
fn amd_order(graph: &SymmetricPattern) -> Result<Vec<usize>, SolverError> {
    let n = graph.len();
    let matrix = SymbolicSparseColMatRef::new_checked(n, n, &graph.offsets, None, &graph.indices);
    let mut buffer = MemBuffer::try_new(amd::order_scratch::<usize>(n, graph.indices.len()))
        .map_err(|_| SolverError::OutOfMemory)?;
    let (mut order, mut inverse) = (vec![0usize; n], vec![0usize; n]);
    amd::order(
        &mut order,
        &mut inverse,
        matrix,
        amd::Control::default(),
        MemStack::new(&mut buffer),
    )
    .map_err(|_| SolverError::OutOfMemory)?;
    Ok(order)
}

/// Parts with at most this many vertices are ordered by minimum degree.
const DISSECTION_LEAF: usize = 64;

/// What is left to order in [`nested_dissection`].
enum Task {
    Dissect(Vec<usize>),
    Emit(Vec<usize>),
}

/// Nested dissection by level structures (George): each part is split by
/// the middle level of a breadth-first search from a pseudo-peripheral
/// vertex; both halves are ordered first, the separator last; small parts
/// by minimum degree.
fn nested_dissection(graph: &SymmetricPattern) -> Result<Vec<usize>, SolverError> {
    let n = graph.len();
    let mut order = Vec::with_capacity(n);
    let mut part = vec![0usize; n];
    let mut level = vec![usize::MAX; n];
    let mut tasks = vec![Task::Dissect((0..n).collect())];
    let mut next_part = 1;
    while let Some(task) = tasks.pop() {
        match task {
            Task::Emit(vertices) => order.extend(vertices),
            Task::Dissect(vertices) if vertices.len() <= DISSECTION_LEAF => {
                order.extend(leaf_order(graph, &vertices, &mut level)?);
            }
            Task::Dissect(vertices) => {
                for &v in &vertices {
                    part[v] = next_part;
                }
                match bisect(graph, &vertices, &part, next_part, &mut level) {
                    Some((first, separator, second)) => {
                        tasks.push(Task::Emit(separator));
                        tasks.push(Task::Dissect(second));
                        tasks.push(Task::Dissect(first));
                    }
                    None => order.extend(leaf_order(graph, &vertices, &mut level)?),
                }
                next_part += 1;
            }
        }
    }
    Ok(order)
}

/// Breadth-first levels from `start` within `part`: the vertices in the
/// order reached, each one's level in `level`.
fn levels_from(
    graph: &SymmetricPattern,
    start: usize,
    part: &[usize],
    id: usize,
    level: &mut [usize],
    vertices: &[usize],
) -> Vec<usize> {
    for &v in vertices {
        level[v] = usize::MAX;
    }
    let mut queue = vec![start];
    level[start] = 0;
    let mut head = 0;
    while head < queue.len() {
        let v = queue[head];
        head += 1;
        for &w in graph.neighbours(v) {
            if part[w] == id && level[w] == usize::MAX {
                level[w] = level[v] + 1;
                queue.push(w);
            }
        }
    }
    queue
}

/// Splits `vertices` (all in part `id`) into two halves and a separator,
/// or `None` when no level structure separates them.
fn bisect(
    graph: &SymmetricPattern,
    vertices: &[usize],
    part: &[usize],
    id: usize,
    level: &mut [usize],
) -> Option<(Vec<usize>, Vec<usize>, Vec<usize>)> {
    let mut reached = levels_from(graph, vertices[0], part, id, level, vertices);
    for _ in 0..2 {
        let far = *reached.last()?;
        reached = levels_from(graph, far, part, id, level, vertices);
    }
    if reached.len() < vertices.len() {
        let rest = vertices
            .iter()
            .copied()
            .filter(|&v| level[v] == usize::MAX)
            .collect();
        return Some((reached, Vec::new(), rest));
    }
    let middle = level[reached[reached.len() / 2]];
    let deepest = level[*reached.last()?];
    if middle == 0 || middle == deepest {
        return None;
    }
    let (mut first, mut separator, mut second) = (Vec::new(), Vec::new(), Vec::new());
    for &v in &reached {
        match level[v].cmp(&middle) {
            std::cmp::Ordering::Less => first.push(v),
            std::cmp::Ordering::Greater => second.push(v),
            std::cmp::Ordering::Equal => {
                let touches_second = graph
                    .neighbours(v)
                    .iter()
                    .any(|&w| part[w] == id && level[w] == middle + 1);
                if touches_second {
                    separator.push(v);
                } else {
                    first.push(v);
                }
            }
        }
    }
    Some((first, separator, second))
}

/// Minimum degree order of the subgraph induced by `vertices`.
fn leaf_order(
    graph: &SymmetricPattern,
    vertices: &[usize],
    local: &mut [usize],
) -> Result<Vec<usize>, SolverError> {
    for (i, &v) in vertices.iter().enumerate() {
        local[v] = i;
    }
    let member = |w: usize| local[w] < vertices.len() && vertices[local[w]] == w;
    let mut offsets = vec![0];
    let mut indices = Vec::new();
    for &v in vertices {
        let start = indices.len();
        indices.extend(
            graph
                .neighbours(v)
                .iter()
                .filter(|&&w| member(w))
                .map(|&w| local[w]),
        );
        indices[start..].sort_unstable();
        offsets.push(indices.len());
    }
    let induced = SymmetricPattern { offsets, indices };
    Ok(amd_order(&induced)?
        .into_iter()
        .map(|i| vertices[i])
        .collect())
}

fn hash_of(neighbours: &[usize]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut hasher = rustc_hash::FxHasher::default();
    neighbours.hash(&mut hasher);
    hasher.finish()
}

/// The pattern of `A^T` row-wise (that is, `A`'s columns): offsets and
/// sorted indices, by a counting sort.
fn transpose(pattern: &SparsePattern) -> (Vec<usize>, Vec<usize>) {
    let n = pattern.n;
    let mut offsets = vec![0; n + 1];
    for &column in &pattern.columns {
        offsets[column + 1] += 1;
    }
    for j in 0..n {
        offsets[j + 1] += offsets[j];
    }
    let mut next = offsets.clone();
    let mut rows = vec![0; pattern.nnz()];
    for row in 0..n {
        for &column in &pattern.columns[pattern.row_range(row)] {
            rows[next[column]] = row;
            next[column] += 1;
        }
    }
    (offsets, rows)
}

/// Appends the sorted union of `a`, `b` and `{extra}` to `out`.
fn merge_sorted(a: &[usize], b: &[usize], extra: usize, out: &mut Vec<usize>) {
    let (mut i, mut j) = (0, 0);
    let mut pending_extra = true;
    loop {
        let next_a = a.get(i).copied().unwrap_or(usize::MAX);
        let next_b = b.get(j).copied().unwrap_or(usize::MAX);
        let next_extra = if pending_extra { extra } else { usize::MAX };
        let smallest = next_a.min(next_b).min(next_extra);
        if smallest == usize::MAX {
            return;
        }
        out.push(smallest);
        i += usize::from(next_a == smallest);
        j += usize::from(next_b == smallest);
        pending_extra &= next_extra != smallest;
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_systems::{grid_walk, random_chain, tridiagonal};
    use super::*;

    #[test]
    fn the_symmetric_pattern_holds_both_triangles_and_the_diagonal() {
        let pattern = SparsePattern {
            n: 3,
            row_offsets: vec![0, 1, 2, 4],
            columns: vec![1, 2, 0, 2],
        };
        let symmetric = SymmetricPattern::of(&pattern);
        assert_eq!(symmetric.neighbours(0), [0, 1, 2]);
        assert_eq!(symmetric.neighbours(1), [0, 1, 2]);
        assert_eq!(symmetric.neighbours(2), [0, 1, 2]);
        assert_eq!(
            symmetric.upper(),
            (vec![0, 1, 3, 6], vec![0, 0, 1, 0, 1, 2])
        );
    }

    #[test]
    fn indistinguishable_vertices_are_numbered_together() {
        // Vertices 0 and 2 both see {0, 1, 2}; 1 sees everything; 3 only 1 and itself.
        let pattern = SparsePattern {
            n: 4,
            row_offsets: vec![0, 2, 4, 6, 7],
            columns: vec![1, 2, 0, 3, 0, 1, 3],
        };
        let (class_of, classes, neighbourhoods) = indistinguishable_classes(&pattern);
        assert_eq!(class_of[0], class_of[2]);
        assert_eq!(neighbourhoods.len(), 3);
        assert_eq!(classes.members(class_of[0]), [0, 2]);
        assert_eq!(neighbourhoods.neighbours(class_of[2]), [0, 1, 2]);
        assert_eq!(neighbourhoods.neighbours(class_of[3]), [1, 3]);
        let order = fill_reducing_order(&pattern, usize::MAX)
            .unwrap()
            .permutation;
        let position = |v: usize| order.iter().position(|&o| o == v).unwrap();
        assert_eq!(position(0).abs_diff(position(2)), 1);
    }

    #[test]
    fn the_order_is_a_permutation() {
        for seed in 0..5 {
            let (pattern, _) = random_chain(300, 3, 0.05, seed);
            let mut order = fill_reducing_order(&pattern, usize::MAX)
                .unwrap()
                .permutation;
            order.sort_unstable();
            assert!(order.iter().enumerate().all(|(i, &o)| i == o));
        }
    }

    fn is_permutation(order: &[usize], n: usize) -> bool {
        let mut sorted = order.to_vec();
        sorted.sort_unstable();
        sorted.len() == n && sorted.iter().enumerate().all(|(i, &o)| i == o)
    }

    /// On a graph large enough for nested dissection, a factor with a
    /// column beyond the front limit is refused before minimum degree runs,
    /// with the column's size; within the limit the order is returned.
    #[test]
    fn a_front_beyond_the_limit_is_refused_from_the_dissection() {
        let (pattern, _) = grid_walk(100);
        let refused = fill_reducing_order(&pattern, 50);
        assert!(
            matches!(
                refused,
                Err(SolverError::LuTooLarge { unknowns: 10_000, front }) if front > 50
            ),
            "{:?}",
            refused.err()
        );
        let order = fill_reducing_order(&pattern, 10_000).unwrap().permutation;
        assert!(is_permutation(&order, 10_000));
    }

    #[test]
    fn nested_dissection_orders_every_vertex_once() {
        for seed in 0..5 {
            let (pattern, _) = random_chain(500, 2, 0.05, seed);
            let graph = SymmetricPattern::of(&pattern);
            assert!(is_permutation(&nested_dissection(&graph).unwrap(), 500));
        }
        let (pattern, _) = grid_walk(40);
        let graph = SymmetricPattern::of(&pattern);
        assert!(is_permutation(&nested_dissection(&graph).unwrap(), 1600));
    }

    #[test]
    fn a_path_is_cut_in_the_middle_last() {
        let (pattern, _) = tridiagonal(201, 0.4);
        let order = nested_dissection(&SymmetricPattern::of(&pattern)).unwrap();
        assert_eq!(order.last(), Some(&100));
    }

    #[test]
    fn the_elimination_of_a_path_is_counted_by_hand() {
        // In natural order every column of the factor of a path has 2
        // entries but the last: 4 (n - 1) + 1. Eliminating the middle
        // vertex 2 first joins its neighbours 1 and 3 (one fill edge):
        // columns {2, 1, 3}, {0, 1}, {1, 3}, {3, 4}, {4}.
        let (pattern, _) = tridiagonal(5, 0.4);
        let graph = SymmetricPattern::of(&pattern);
        let natural = graph.elimination(&[0, 1, 2, 3, 4]);
        assert_eq!((natural.multiplications, natural.largest_column), (17.0, 2));
        let middle_first = graph.elimination(&[2, 0, 1, 3, 4]);
        assert_eq!(
            (middle_first.multiplications, middle_first.largest_column),
            (9.0 + 4.0 + 4.0 + 4.0 + 1.0, 3)
        );
    }
}
