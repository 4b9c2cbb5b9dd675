//! The column counts of a Cholesky factor from the graph alone, in
//! near-linear time: the elimination tree (Liu), its postorder, and the
//! counts from the leaves of the row subtrees (Gilbert, Ng and Peyton, as
//! in Davis's CSparse).
//!
//! faer's `prefactorize_symbolic_cholesky` gives the same counts by walking
//! every row subtree, which costs one step per entry of the factor: on a
//! graph whose factor is beyond any memory (PAYNT's drone-2-8-1, a front
//! of 72,740 rows) that walk alone ran for minutes. The fill-reducing
//! order uses these counts to compare orders and to refuse such a factor
//! before it is built.

/// No vertex: the parent of a root, or a mark not yet set.
const NONE: usize = usize::MAX;

/// The number of entries (the diagonal included) in each column of the
/// Cholesky factor of a symmetric matrix whose graph has the closed
/// neighbourhoods `neighbours(j)` (vertices already numbered in
/// elimination order: `j`'s neighbours are all the `i` with `A(i, j) != 0`).
pub(crate) fn column_counts<'a>(n: usize, neighbours: impl Fn(usize) -> &'a [usize]) -> Vec<usize> {
    let parent = elimination_tree(n, &neighbours);
    let post = postorder(&parent);
    let mut first = vec![NONE; n];
    let mut delta = vec![0isize; n];
    for (k, &j) in post.iter().enumerate() {
        delta[j] = isize::from(first[j] == NONE);
        let mut up = j;
        while up != NONE && first[up] == NONE {
            first[up] = k;
            up = parent[up];
        }
    }
    let mut leaves = Leaves {
        first,
        max_first: vec![NONE; n],
        previous_leaf: vec![NONE; n],
        ancestor: (0..n).collect(),
    };
    for &j in &post {
        if parent[j] != NONE {
            delta[parent[j]] -= 1;
        }
        for &i in neighbours(j) {
            match leaves.leaf(i, j) {
                Leaf::Not => {}
                Leaf::First => delta[j] += 1,
                Leaf::Subsequent(q) => {
                    delta[j] += 1;
                    delta[q] -= 1;
                }
            }
        }
        if parent[j] != NONE {
            leaves.ancestor[j] = parent[j];
        }
    }
    for &j in &post {
        if parent[j] != NONE {
            delta[parent[j]] += delta[j];
        }
    }
    delta.into_iter().map(|count| count as usize).collect()
}

/// The elimination tree: `parent[j]` is the first row below the diagonal
/// of column `j` of the factor (`NONE` for a root), found with path
/// compression through `ancestor`.
fn elimination_tree<'a>(n: usize, neighbours: &impl Fn(usize) -> &'a [usize]) -> Vec<usize> {
    let (mut parent, mut ancestor) = (vec![NONE; n], vec![NONE; n]);
    for k in 0..n {
        for &start in neighbours(k).iter().filter(|&&i| i < k) {
            let mut i = start;
            while i != NONE && i < k {
                let next = ancestor[i];
                ancestor[i] = k;
                if next == NONE {
                    parent[i] = k;
                }
                i = next;
            }
        }
    }
    parent
}

/// The vertices of the forest `parent` in postorder (children first,
/// each subtree consecutive).
fn postorder(parent: &[usize]) -> Vec<usize> {
    let n = parent.len();
    let (mut head, mut next) = (vec![NONE; n], vec![NONE; n]);
    for j in (0..n).rev() {
        if parent[j] != NONE {
            next[j] = head[parent[j]];
            head[parent[j]] = j;
        }
    }
    let mut order = Vec::with_capacity(n);
    let mut stack = Vec::new();
    for root in (0..n).filter(|&j| parent[j] == NONE) {
        stack.push(root);
        while let Some(&top) = stack.last() {
            let child = head[top];
            if child == NONE {
                stack.pop();
                order.push(top);
            } else {
                head[top] = next[child];
                stack.push(child);
            }
        }
    }
    order
}

/// Whether column `j` is a leaf of row `i`'s subtree.
enum Leaf {
    Not,
    /// The first leaf of the row subtree.
    First,
    /// A later leaf; the least common ancestor of it and the previous one.
    Subsequent(usize),
}

/// The state of the leaf detection over the postorder.
struct Leaves {
    /// The first descendant of each vertex in postorder.
    first: Vec<usize>,
    max_first: Vec<usize>,
    previous_leaf: Vec<usize>,
    /// A disjoint-set forest of the vertices done, for the least common
    /// ancestors.
    ancestor: Vec<usize>,
}

impl Leaves {
    fn leaf(&mut self, i: usize, j: usize) -> Leaf {
        let first_j = self.first[j];
        if i <= j || (self.max_first[i] != NONE && first_j <= self.max_first[i]) {
            return Leaf::Not;
        }
        self.max_first[i] = first_j;
        let previous = std::mem::replace(&mut self.previous_leaf[i], j);
        if previous == NONE {
            return Leaf::First;
        }
        let mut root = previous;
        while root != self.ancestor[root] {
            root = self.ancestor[root];
        }
        let mut s = previous;
        while s != root {
            let up = self.ancestor[s];
            self.ancestor[s] = root;
            s = up;
        }
        Leaf::Subsequent(root)
    }
}

#[cfg(test)]
mod tests {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::SymbolicSparseColMatRef;
    use faer::sparse::linalg::cholesky::simplicial::{
        prefactorize_symbolic_cholesky, prefactorize_symbolic_cholesky_scratch,
    };
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// faer's counts (its row-subtree walk), the independent computation.
    fn faer_counts(neighbourhoods: &[Vec<usize>]) -> Vec<usize> {
        let n = neighbourhoods.len();
        let mut offsets = vec![0];
        let mut indices = Vec::new();
        for (j, neighbours) in neighbourhoods.iter().enumerate() {
            indices.extend(neighbours.iter().filter(|&&i| i <= j));
            offsets.push(indices.len());
        }
        let upper = SymbolicSparseColMatRef::new_checked(n, n, &offsets, None, &indices);
        let (mut etree, mut counts) = (vec![0isize; n], vec![0usize; n]);
        let mut buffer = MemBuffer::new(prefactorize_symbolic_cholesky_scratch::<usize>(
            n,
            indices.len(),
        ));
        prefactorize_symbolic_cholesky(&mut etree, &mut counts, upper, MemStack::new(&mut buffer));
        counts
    }

    /// A random symmetric graph of `n` vertices with about `degree`
    /// neighbours each, closed neighbourhoods sorted.
    fn random_graph(n: usize, degree: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<usize>> {
        let mut neighbourhoods: Vec<Vec<usize>> = (0..n).map(|j| vec![j]).collect();
        for _ in 0..n * degree / 2 {
            let (a, b) = (rng.random_range(0..n), rng.random_range(0..n));
            neighbourhoods[a].push(b);
            neighbourhoods[b].push(a);
        }
        for neighbours in &mut neighbourhoods {
            neighbours.sort_unstable();
            neighbours.dedup();
        }
        neighbourhoods
    }

    #[test]
    fn the_counts_agree_with_the_row_subtree_walk_on_random_graphs() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for case in 0..200 {
            let n = rng.random_range(1..60);
            let degree = rng.random_range(0..6);
            let graph = random_graph(n, degree, &mut rng);
            let counts = column_counts(n, |j| &graph[j]);
            assert_eq!(counts, faer_counts(&graph), "case {case}: {graph:?}");
        }
    }

    /// A path in natural order: every column holds its diagonal and the
    /// next vertex, the last only its diagonal.
    #[test]
    fn a_path_has_two_entries_per_column_but_the_last() {
        let graph: Vec<Vec<usize>> = (0..5)
            .map(|j: usize| (j.saturating_sub(1)..(j + 2).min(5)).collect())
            .collect();
        assert_eq!(column_counts(5, |j| &graph[j]), vec![2, 2, 2, 2, 1]);
    }
}
