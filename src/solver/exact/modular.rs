//! Arithmetic modulo a word-size prime and the sparse LU of `A mod p` that
//! the p-adic lifting of [`super::lifting`] solves with at every step.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The primes below `2^62`, largest first, that the lifting may use: a
/// second one is tried only if `A mod p` is singular for the first.
pub(super) fn primes(count: usize) -> Vec<u64> {
    let mut found = Vec::with_capacity(count);
    let mut candidate = (1u64 << 62) - 1;
    while found.len() < count {
        if is_prime(candidate) {
            found.push(candidate);
        }
        candidate -= 2;
    }
    found
}

/// Deterministic Miller-Rabin for 64-bit numbers (the seven bases of
/// Jaeschke and Sinclair).
fn is_prime(n: u64) -> bool {
    if n < 2 {
        return false;
    }
    for small in [2u64, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37] {
        if n % small == 0 {
            return n == small;
        }
    }
    let (mut d, mut s) = (n - 1, 0);
    while d % 2 == 0 {
        d /= 2;
        s += 1;
    }
    let m = Modulus::new(n);
    'bases: for base in [2u64, 325, 9375, 28178, 450775, 9780504, 1795265022] {
        let a = base % n;
        if a == 0 {
            continue;
        }
        let mut x = m.pow(a, d);
        if x == 1 || x == n - 1 {
            continue;
        }
        for _ in 1..s {
            x = m.mul(x, x);
            if x == n - 1 {
                continue 'bases;
            }
        }
        return false;
    }
    true
}

/// Residues modulo an odd `p < 2^62`, kept in `[0, p)`, with Montgomery
/// multiplication (`R = 2^64`) for the lifting's inner loops.
#[derive(Debug, Clone, Copy)]
pub(super) struct Modulus {
    /// The modulus.
    pub p: u64,
    /// `p^-1 mod 2^64`.
    pub inverse_mod_word: u64,
    /// `R^2 mod p`.
    r_squared: u64,
}

impl Modulus {
    pub fn new(p: u64) -> Self {
        // Newton's iteration doubles the correct low bits: 3, 6, ..., 96.
        let mut inverse = p;
        for _ in 0..5 {
            inverse = inverse.wrapping_mul(2u64.wrapping_sub(p.wrapping_mul(inverse)));
        }
        let r = (1u128 << 64) % u128::from(p);
        Self {
            p,
            inverse_mod_word: inverse,
            r_squared: ((r * r) % u128::from(p)) as u64,
        }
    }

    pub fn mul(self, a: u64, b: u64) -> u64 {
        ((u128::from(a) * u128::from(b)) % u128::from(self.p)) as u64
    }

    /// `t R^-1 mod p` for `t < p 2^64` (Montgomery's reduction).
    pub fn reduce(self, t: u128) -> u64 {
        let m = (t as u64).wrapping_mul(self.inverse_mod_word.wrapping_neg());
        let sum = (t + u128::from(m) * u128::from(self.p)) >> 64;
        let sum = sum as u64;
        if sum >= self.p { sum - self.p } else { sum }
    }

    /// `a b R^-1 mod p` for `a < 2^64`, `b < p`: with `a` in Montgomery
    /// form (`a = a' R mod p`), the plain product `a' b mod p`.
    pub fn mul_montgomery(self, a: u64, b: u64) -> u64 {
        self.reduce(u128::from(a) * u128::from(b))
    }

    /// `a R mod p`, the Montgomery form of `a < p`.
    pub fn to_montgomery(self, a: u64) -> u64 {
        self.mul_montgomery(a, self.r_squared)
    }

    pub fn sub(self, a: u64, b: u64) -> u64 {
        if a >= b { a - b } else { a + self.p - b }
    }

    pub fn add(self, a: u64, b: u64) -> u64 {
        let sum = a + b;
        if sum >= self.p { sum - self.p } else { sum }
    }

    pub fn pow(self, mut base: u64, mut exponent: u64) -> u64 {
        let mut result = 1 % self.p;
        while exponent > 0 {
            if exponent & 1 == 1 {
                result = self.mul(result, base);
            }
            base = self.mul(base, base);
            exponent >>= 1;
        }
        result
    }

    /// `a^-1` for `a != 0` (Fermat).
    pub fn inverse(self, a: u64) -> u64 {
        self.pow(a, self.p - 2)
    }
}

/// `A = L U` modulo `p`, without pivoting: `L` unit lower triangular and
/// `U` upper triangular, stored by rows without their diagonals (`U`'s
/// inverted diagonal apart).
pub(super) struct ModLu {
    modulus: Modulus,
    lower_offsets: Vec<usize>,
    lower: Vec<(usize, u64)>,
    upper_offsets: Vec<usize>,
    upper: Vec<(usize, u64)>,
    inverse_pivots: Vec<u64>,
}

/// Why [`ModLu::factorize`] stopped.
pub(super) enum ModLuFailure {
    /// A pivot is zero modulo `p` (at this row).
    ZeroPivot(usize),
    /// `L` and `U` would hold more than the budget's entries.
    TooMuchFill,
}

impl ModLu {
    /// Factorises the matrix whose row `i` is `rows[i]` (`(column, a_ij
    /// mod p)`, any order, the diagonal included) row by row, in the
    /// states' order, holding at most `entry_limit` entries.
    pub fn factorize(
        rows: &[Vec<(usize, u64)>],
        modulus: Modulus,
        entry_limit: usize,
    ) -> Result<Self, ModLuFailure> {
        let n = rows.len();
        let mut lu = Self {
            modulus,
            lower_offsets: vec![0],
            lower: Vec::new(),
            upper_offsets: vec![0],
            upper: Vec::new(),
            inverse_pivots: Vec::with_capacity(n),
        };
        let mut work = vec![0u64; n];
        let mut present = vec![false; n];
        let mut touched: Vec<usize> = Vec::new();
        let mut pending: BinaryHeap<Reverse<usize>> = BinaryHeap::new();
        for (i, row) in rows.iter().enumerate() {
            for &(j, a) in row {
                if !present[j] {
                    present[j] = true;
                    touched.push(j);
                    if j < i {
                        pending.push(Reverse(j));
                    }
                }
                work[j] = (work[j] + a) % modulus.p;
            }
            while let Some(Reverse(k)) = pending.pop() {
                let factor = modulus.mul(work[k], lu.inverse_pivots[k]);
                if factor == 0 {
                    continue;
                }
                lu.lower.push((k, factor));
                for &(j, u_kj) in &lu.upper[lu.upper_offsets[k]..lu.upper_offsets[k + 1]] {
                    if !present[j] {
                        present[j] = true;
                        touched.push(j);
                        if j < i {
                            pending.push(Reverse(j));
                        }
                    }
                    work[j] = modulus.sub(work[j], modulus.mul(factor, u_kj));
                }
            }
            let pivot = work[i];
            if pivot == 0 {
                return Err(ModLuFailure::ZeroPivot(i));
            }
            lu.inverse_pivots.push(modulus.inverse(pivot));
            touched.sort_unstable();
            for &j in &touched {
                if j > i && work[j] != 0 {
                    lu.upper.push((j, work[j]));
                }
                work[j] = 0;
                present[j] = false;
            }
            touched.clear();
            lu.lower_offsets.push(lu.lower.len());
            lu.upper_offsets.push(lu.upper.len());
            if lu.lower.len() + lu.upper.len() + i + 1 > entry_limit {
                return Err(ModLuFailure::TooMuchFill);
            }
        }
        // The solves multiply by Montgomery's reduction.
        for (_, value) in lu.lower.iter_mut().chain(lu.upper.iter_mut()) {
            *value = modulus.to_montgomery(*value);
        }
        for value in &mut lu.inverse_pivots {
            *value = modulus.to_montgomery(*value);
        }
        Ok(lu)
    }

    /// The entries of `L` and `U` (diagonal included).
    pub fn entries(&self) -> usize {
        self.lower.len() + self.upper.len() + self.inverse_pivots.len()
    }

    /// Overwrites `x` (holding `c mod p`) with `A^-1 c mod p`.
    pub fn solve_in_place(&self, x: &mut [u64]) {
        let m = self.modulus;
        for i in 0..x.len() {
            let mut sum = x[i];
            for &(k, l_ik) in &self.lower[self.lower_offsets[i]..self.lower_offsets[i + 1]] {
                sum = m.sub(sum, m.mul_montgomery(l_ik, x[k]));
            }
            x[i] = sum;
        }
        for i in (0..x.len()).rev() {
            let mut sum = x[i];
            for &(j, u_ij) in &self.upper[self.upper_offsets[i]..self.upper_offsets[i + 1]] {
                sum = m.sub(sum, m.mul_montgomery(u_ij, x[j]));
            }
            x[i] = m.mul_montgomery(self.inverse_pivots[i], sum);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_primes_are_prime_and_below_two_to_the_62() {
        let found = primes(3);
        assert!(found.windows(2).all(|w| w[0] > w[1]));
        assert!(found.iter().all(|&p| p < 1 << 62 && p > 1 << 61));
        // 2^62 - 57 is the largest prime below 2^62.
        assert_eq!(found[0], (1 << 62) - 57);
        assert!(!is_prime(561) && !is_prime(3215031751) && is_prime(1_000_000_007));
        let m = Modulus::new(found[0]);
        assert_eq!(m.p.wrapping_mul(m.inverse_mod_word), 1);
        let (a, b) = (found[1], u64::MAX);
        assert_eq!(
            m.mul_montgomery(m.to_montgomery(a % m.p), 12345),
            m.mul(a % m.p, 12345)
        );
        assert_eq!(m.mul_montgomery(b, m.to_montgomery(1)), b % m.p);
    }

    #[test]
    fn a_small_system_is_solved_modulo_p() {
        let m = Modulus::new(1_000_000_007);
        // [[2, 1, 0], [1, 3, 1], [0, 1, 4]] x = (3, 5, 5): x = (1, 1, 1).
        let rows = vec![
            vec![(0, 2), (1, 1)],
            vec![(1, 3), (0, 1), (2, 1)],
            vec![(2, 4), (1, 1)],
        ];
        let Ok(lu) = ModLu::factorize(&rows, m, 100) else {
            panic!("nonsingular")
        };
        let mut x = vec![3, 5, 5];
        lu.solve_in_place(&mut x);
        assert_eq!(x, vec![1, 1, 1]);
        assert!(matches!(
            ModLu::factorize(&rows, m, 4),
            Err(ModLuFailure::TooMuchFill)
        ));
        let singular = vec![vec![(0, 1), (1, 1)], vec![(0, 2), (1, 2)]];
        assert!(matches!(
            ModLu::factorize(&singular, m, 100),
            Err(ModLuFailure::ZeroPivot(1))
        ));
    }
}
