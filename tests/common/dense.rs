//! Dense matrices and vectors for the reference computations: just what
//! they need (indexing, identity, sums, dot products and an LU solve with
//! partial pivoting), written here so that the tests share no linear
//! algebra with the crate.

use std::ops::{Add, Index, IndexMut};

/// A dense column vector.
pub type DVector = Vec<f64>;

/// `n` zeros.
pub fn zeros(n: usize) -> DVector {
    vec![0.0; n]
}

/// `sum_i a_i b_i`.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A dense square matrix in row-major order.
#[derive(Debug, Clone, PartialEq)]
pub struct DMatrix {
    n: usize,
    entries: Vec<f64>,
}

impl DMatrix {
    /// The `n x n` zero matrix.
    pub fn zeros(n: usize) -> Self {
        Self {
            n,
            entries: vec![0.0; n * n],
        }
    }

    /// The `n x n` identity.
    pub fn identity(n: usize) -> Self {
        Self::from_fn(n, |i, j| f64::from(u8::from(i == j)))
    }

    /// The matrix with entries `f(i, j)`.
    pub fn from_fn(n: usize, f: impl Fn(usize, usize) -> f64) -> Self {
        let entries = (0..n * n).map(|k| f(k / n, k % n)).collect();
        Self { n, entries }
    }

    /// The number of rows (and columns).
    pub fn nrows(&self) -> usize {
        self.n
    }

    /// The solution of `self x = b` by Gaussian elimination with partial
    /// pivoting, or `None` when a pivot vanishes (singular matrix).
    pub fn solve(&self, b: &[f64]) -> Option<DVector> {
        let n = self.n;
        let mut a = self.entries.clone();
        let mut x = b.to_vec();
        for col in 0..n {
            let pivot =
                (col..n).max_by(|&r, &s| a[r * n + col].abs().total_cmp(&a[s * n + col].abs()))?;
            if a[pivot * n + col].abs() < 1e-300 {
                return None;
            }
            for k in 0..n {
                a.swap(col * n + k, pivot * n + k);
            }
            x.swap(col, pivot);
            for row in col + 1..n {
                let factor = a[row * n + col] / a[col * n + col];
                if factor != 0.0 {
                    for k in col..n {
                        a[row * n + k] -= factor * a[col * n + k];
                    }
                    x[row] -= factor * x[col];
                }
            }
        }
        for col in (0..n).rev() {
            let tail: f64 = (col + 1..n).map(|k| a[col * n + k] * x[k]).sum();
            x[col] = (x[col] - tail) / a[col * n + col];
        }
        Some(x)
    }
}

impl Index<(usize, usize)> for DMatrix {
    type Output = f64;

    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        &self.entries[i * self.n + j]
    }
}

impl IndexMut<(usize, usize)> for DMatrix {
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        &mut self.entries[i * self.n + j]
    }
}

impl Add<&DMatrix> for DMatrix {
    type Output = DMatrix;

    fn add(mut self, other: &DMatrix) -> DMatrix {
        for (a, b) in self.entries.iter_mut().zip(&other.entries) {
            *a += b;
        }
        self
    }
}
