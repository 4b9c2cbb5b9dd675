//! Reduced ordered binary decision diagrams, used as canonical forms of
//! propositional combinations of formulas ("propositional equivalence
//! classes" in Esparza, Křetínský and Sickert's construction).
//!
//! Nodes `0` and `1` are the constants false and true; variables are ordered
//! by their index. Two Boolean functions are equal iff their node ids are.

use rustc_hash::FxHashMap;

/// A node id: `FALSE`, `TRUE` or an internal node.
pub(crate) type Node = u32;
/// The constant false.
pub(crate) const FALSE: Node = 0;
/// The constant true.
pub(crate) const TRUE: Node = 1;

/// A store of hash-consed BDD nodes.
#[derive(Debug)]
pub(crate) struct Bdd {
    /// `(variable, low, high)` of every node; the two constants have the
    /// variable `u32::MAX`.
    nodes: Vec<(u32, Node, Node)>,
    unique: FxHashMap<(u32, Node, Node), Node>,
    ite_memo: FxHashMap<(Node, Node, Node), Node>,
}

impl Bdd {
    pub(crate) fn new() -> Self {
        Self {
            nodes: vec![(u32::MAX, FALSE, FALSE), (u32::MAX, TRUE, TRUE)],
            unique: FxHashMap::default(),
            ite_memo: FxHashMap::default(),
        }
    }

    fn make(&mut self, var: u32, low: Node, high: Node) -> Node {
        if low == high {
            return low;
        }
        let next = self.nodes.len() as Node;
        *self.unique.entry((var, low, high)).or_insert_with(|| {
            self.nodes.push((var, low, high));
            next
        })
    }

    /// The function `x_var`.
    pub(crate) fn var(&mut self, var: u32) -> Node {
        self.make(var, FALSE, TRUE)
    }

    fn cofactors(&self, node: Node, var: u32) -> (Node, Node) {
        let (v, low, high) = self.nodes[node as usize];
        if v == var { (low, high) } else { (node, node) }
    }

    /// `if f then g else h`.
    pub(crate) fn ite(&mut self, f: Node, g: Node, h: Node) -> Node {
        if f == TRUE || g == h {
            return g;
        }
        if f == FALSE {
            return h;
        }
        if g == TRUE && h == FALSE {
            return f;
        }
        if let Some(&r) = self.ite_memo.get(&(f, g, h)) {
            return r;
        }
        let var = [f, g, h]
            .iter()
            .map(|&n| self.nodes[n as usize].0)
            .min()
            .unwrap_or(u32::MAX);
        let (f0, f1) = self.cofactors(f, var);
        let (g0, g1) = self.cofactors(g, var);
        let (h0, h1) = self.cofactors(h, var);
        let low = self.ite(f0, g0, h0);
        let high = self.ite(f1, g1, h1);
        let r = self.make(var, low, high);
        self.ite_memo.insert((f, g, h), r);
        r
    }

    pub(crate) fn and(&mut self, f: Node, g: Node) -> Node {
        self.ite(f, g, FALSE)
    }

    pub(crate) fn or(&mut self, f: Node, g: Node) -> Node {
        self.ite(f, TRUE, g)
    }

    pub(crate) fn not(&mut self, f: Node) -> Node {
        self.ite(f, FALSE, TRUE)
    }

    /// The variables `node` depends on, in increasing order.
    pub(crate) fn support(&self, node: Node) -> Vec<u32> {
        let mut seen = vec![node];
        let mut stack = vec![node];
        let mut vars = Vec::new();
        while let Some(n) = stack.pop() {
            if n <= TRUE {
                continue;
            }
            let (var, low, high) = self.nodes[n as usize];
            vars.push(var);
            for child in [low, high] {
                if !seen.contains(&child) {
                    seen.push(child);
                    stack.push(child);
                }
            }
        }
        vars.sort_unstable();
        vars.dedup();
        vars
    }

    /// `node` with every variable `v` replaced by the function
    /// `substitution(v)` (all at once).
    pub(crate) fn compose(&mut self, node: Node, substitution: &FxHashMap<u32, Node>) -> Node {
        let mut memo = FxHashMap::default();
        self.compose_memo(node, substitution, &mut memo)
    }

    fn compose_memo(
        &mut self,
        node: Node,
        substitution: &FxHashMap<u32, Node>,
        memo: &mut FxHashMap<Node, Node>,
    ) -> Node {
        if node <= TRUE {
            return node;
        }
        if let Some(&r) = memo.get(&node) {
            return r;
        }
        let (var, low, high) = self.nodes[node as usize];
        let low = self.compose_memo(low, substitution, memo);
        let high = self.compose_memo(high, substitution, memo);
        let test = match substitution.get(&var) {
            Some(&f) => f,
            None => self.var(var),
        };
        let r = self.ite(test, high, low);
        memo.insert(node, r);
        r
    }

    /// The value of `node` under the assignment `value(v)`.
    pub(crate) fn evaluate(&self, mut node: Node, value: impl Fn(u32) -> bool) -> bool {
        while node > TRUE {
            let (var, low, high) = self.nodes[node as usize];
            node = if value(var) { high } else { low };
        }
        node == TRUE
    }
}
