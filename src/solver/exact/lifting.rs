//! Dixon's p-adic lifting for an integer system `A x = b` (`A`
//! nonsingular): one LU of `A mod p`, then digit after digit
//! `x = sum_t d_t p^t` with an exact integer residual, rational
//! reconstruction of a common denominator and the numerators, and an exact
//! check `A N = D b` in integers that proves the result.

use num_bigint::{BigInt, BigUint, Sign};
use num_integer::Integer;
use num_traits::{One, Signed, ToPrimitive, Zero};

use super::modular::{ModLu, ModLuFailure, Modulus, primes};

/// An integer system: row `i` is `rows[i]` (`(column, a_ij)`, the diagonal
/// included), with right-hand side `b[i]`.
pub(super) struct IntegerSystem {
    pub rows: Vec<Vec<(usize, BigInt)>>,
    pub b: Vec<BigInt>,
}

/// The proved solution `x = numerators / denominator`.
pub(super) struct RationalSolution {
    pub numerators: Vec<BigInt>,
    pub denominator: BigUint,
}

/// Why the lifting stopped without a solution.
pub(super) enum LiftFailure {
    /// `A mod p` was singular for every prime tried: `A` is (almost surely)
    /// singular, at this row of the elimination.
    Singular(usize),
    /// `L` and `U` modulo `p` would hold more entries than the budget.
    TooMuchFill,
    /// The work budget ran out; the modulus had this many bits.
    TooMuchWork(u64),
}

/// The bits of slack asked of a reconstruction `N / D` from `x mod M`
/// (`|N| D 2^MARGIN < M`): a wrong candidate passes with a probability of
/// about `2^-MARGIN`, and then only costs the exact check, which refuses it.
const MARGIN: u64 = 24;

/// How many primes are tried before `A` is called singular.
const PRIMES: usize = 4;

/// Solves `system` exactly within `entry_limit` entries of the LU modulo
/// `p` and about `work_limit` word operations.
pub(super) fn solve(
    system: &IntegerSystem,
    entry_limit: usize,
    work_limit: u64,
) -> Result<RationalSolution, LiftFailure> {
    let mut last_zero_pivot = 0;
    for p in primes(PRIMES) {
        let modulus = Modulus::new(p);
        let reduced: Vec<Vec<(usize, u64)>> = system
            .rows
            .iter()
            .map(|row| row.iter().map(|(j, a)| (*j, residue(a, p))).collect())
            .collect();
        match ModLu::factorize(&reduced, modulus, entry_limit) {
            Ok(lu) => return Lifting::new(system, lu, modulus).run(work_limit),
            Err(ModLuFailure::TooMuchFill) => return Err(LiftFailure::TooMuchFill),
            Err(ModLuFailure::ZeroPivot(row)) => last_zero_pivot = row,
        }
    }
    Err(LiftFailure::Singular(last_zero_pivot))
}

/// `a mod p` in `[0, p)`.
fn residue(a: &BigInt, p: u64) -> u64 {
    let r = (a.magnitude() % p).to_u64().unwrap_or(0);
    if a.is_negative() && r != 0 { p - r } else { r }
}

/// The state of the lifting: `A` in fixed-width limbs, the residual
/// `r = (b - A sum_{s<t} d_s p^s) / p^t` of every row in `width` limbs
/// (two's complement), and the digits so far.
struct Lifting<'a> {
    system: &'a IntegerSystem,
    lu: ModLu,
    modulus: Modulus,
    /// Per row: `(column, negative, offset into magnitudes)`.
    entries: Vec<Vec<(usize, bool, usize)>>,
    magnitudes: Vec<u64>,
    entry_width: usize,
    width: usize,
    residual: Vec<u64>,
    /// `2^(64 width) mod p`.
    wrap: u64,
    /// `2^(64 j) mod p` in Montgomery form, for each limb `j`.
    limb_weights: Vec<u64>,
    /// Digit `t` of row `i` at `t n + i`.
    digits: Vec<u64>,
    /// `sum_i c_i d_{t,i}` for the random weights `c`: the digits of the
    /// combination `c . x` whose denominator is (almost surely) that of `x`.
    combined: Vec<u128>,
    weights: Vec<u64>,
}

impl<'a> Lifting<'a> {
    fn new(system: &'a IntegerSystem, lu: ModLu, modulus: Modulus) -> Self {
        let n = system.rows.len();
        let limbs_of = |bits: u64| bits.div_ceil(64).max(1) as usize;
        let entry_width = system
            .rows
            .iter()
            .flatten()
            .map(|(_, a)| limbs_of(a.bits()))
            .max()
            .unwrap_or(1);
        // |r| <= max(|b|, 2 max_i sum_j |a_ij|) at every step, and before
        // the division by p, |r - A d| <= that plus p sum_j |a_ij|.
        let row_sum = system
            .rows
            .iter()
            .map(|row| row.iter().map(|(_, a)| a.magnitude()).sum::<BigUint>())
            .max()
            .unwrap_or_default();
        let largest_b = system.b.iter().map(|b| b.bits()).max().unwrap_or(0);
        let bits = largest_b.max(row_sum.bits() + 1) + 64 + 2;
        let width = limbs_of(bits) + 1;
        let mut magnitudes = Vec::new();
        let entries = system
            .rows
            .iter()
            .map(|row| {
                row.iter()
                    .filter(|(_, a)| !a.is_zero())
                    .map(|(j, a)| {
                        let offset = magnitudes.len();
                        let mut limbs = a.magnitude().to_u64_digits();
                        limbs.resize(entry_width, 0);
                        magnitudes.extend(limbs);
                        (*j, a.is_negative(), offset)
                    })
                    .collect()
            })
            .collect();
        let residual = system.b.iter().flat_map(|b| limbs(b, width)).collect();
        let wrap = ((BigUint::one() << (64 * width)) % modulus.p)
            .to_u64()
            .unwrap_or(0);
        let limb_weights = (0..width)
            .map(|j| {
                let weight = ((BigUint::one() << (64 * j)) % modulus.p)
                    .to_u64()
                    .unwrap_or(0);
                modulus.to_montgomery(weight)
            })
            .collect();
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let weights = (0..n)
            .map(|_| {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                (seed >> 32) | 1
            })
            .collect();
        Self {
            system,
            lu,
            modulus,
            entries,
            magnitudes,
            entry_width,
            width,
            residual,
            wrap,
            limb_weights,
            digits: Vec::new(),
            combined: Vec::new(),
            weights,
        }
    }

    /// The word operations of one lifting step.
    fn step_work(&self) -> u64 {
        let n = self.system.rows.len() as u64;
        let entries = self.entries.iter().map(Vec::len).sum::<usize>() as u64;
        (2 * self.lu.entries() as u64)
            + entries * (self.entry_width as u64 + 2)
            + 4 * n * self.width as u64
    }

    fn run(mut self, work_limit: u64) -> Result<RationalSolution, LiftFailure> {
        let n = self.system.rows.len();
        let p = self.modulus.p;
        let step_work = self.step_work();
        let mut work = 0u64;
        let mut digit = vec![0u64; n];
        let mut accumulator = vec![0u64; self.width];
        let mut next_check = 1usize;
        let mut steps = 0usize;
        let mut modulus = BigUint::one();
        loop {
            if work.saturating_add(step_work) > work_limit {
                return Err(LiftFailure::TooMuchWork(modulus.bits()));
            }
            work += step_work;
            for (i, d) in digit.iter_mut().enumerate() {
                *d = self.residue_of_row(i);
            }
            self.lu.solve_in_place(&mut digit);
            let w = self.width;
            for (i, row) in self.entries.iter().enumerate() {
                accumulator.copy_from_slice(&self.residual[i * w..(i + 1) * w]);
                for &(j, negative, offset) in row {
                    let a = &self.magnitudes[offset..offset + self.entry_width];
                    multiply_add(&mut accumulator, a, digit[j], negative);
                }
                // p divides r - A d: A d = r mod p by construction.
                divide_exactly(&mut accumulator, p, self.modulus.inverse_mod_word);
                self.residual[i * w..(i + 1) * w].copy_from_slice(&accumulator);
            }
            self.combined.push(
                digit
                    .iter()
                    .zip(&self.weights)
                    .map(|(&d, &c)| u128::from(d) * u128::from(c))
                    .sum(),
            );
            self.digits.extend_from_slice(&digit);
            steps += 1;
            modulus *= p;
            if steps >= next_check {
                next_check = steps + (steps * 2 / 5).max(1);
                let limbs = modulus.bits().div_ceil(64);
                // Conversion and reconstruction of the combination.
                work = work.saturating_add(4 * limbs * limbs + 2 * limbs * 64);
                if let Some(solution) = self.attempt(&modulus, steps, &mut work) {
                    return Ok(solution);
                }
            }
        }
    }

    /// `r_i mod p`.
    fn residue_of_row(&self, i: usize) -> u64 {
        let w = self.width;
        let limbs = &self.residual[i * w..(i + 1) * w];
        let m = self.modulus;
        let remainder = limbs
            .iter()
            .zip(&self.limb_weights)
            .fold(0, |sum, (&limb, &weight)| {
                m.add(sum, m.mul_montgomery(weight, limb))
            });
        if limbs[w - 1] >> 63 == 1 {
            // The limbs read as unsigned are r + 2^(64 w).
            m.sub(remainder, self.wrap)
        } else {
            remainder
        }
    }

    /// Rational reconstruction from the first `steps` digits (modulo
    /// `modulus = p^steps`), checked exactly.
    fn attempt(&self, modulus: &BigUint, steps: usize, work: &mut u64) -> Option<RationalSolution> {
        let powers = powers(self.modulus.p, steps);
        let combined = from_digits(&self.combined, &powers) % modulus;
        let (combined_numerator, denominator) = reconstruct(&combined, modulus)?;
        // The numerators are sought first modulo a shorter power of p,
        // enough for numerators up to the combination's (its weights are
        // at least 1, so it is the largest when the entries share a sign):
        // about half the digits.
        let bits = combined_numerator.bits() + MARGIN + 2;
        let short = steps.min(bits.div_ceil(61) as usize + 1);
        if short < steps {
            let found = self.numerators(short, &powers, denominator.clone(), false, work);
            if found.is_some() {
                return found;
            }
        }
        self.numerators(steps, &powers, denominator, true, work)
    }

    /// The numerators `N = D x` for the denominator `denominator` from the
    /// first `steps` digits, checked exactly. If `extend`, an entry whose
    /// `D x mod p^steps` is not small has its own denominator
    /// reconstructed and multiplied into `D` (the combination of the
    /// entries may have lost a factor).
    fn numerators(
        &self,
        steps: usize,
        powers: &[BigUint],
        mut denominator: BigUint,
        extend: bool,
        work: &mut u64,
    ) -> Option<RationalSolution> {
        let n = self.system.rows.len();
        let modulus = BigUint::from(self.modulus.p).pow(steps as u32);
        let limbs = modulus.bits().div_ceil(64);
        // Conversions, products and reductions modulo p^steps.
        *work = work.saturating_add(n as u64 * limbs * (steps.ilog2() as u64 + 8 + limbs / 2));
        let values: Vec<BigUint> = (0..n)
            .map(|i| {
                let column: Vec<u128> = (0..steps)
                    .map(|t| u128::from(self.digits[t * n + i]))
                    .collect();
                from_digits(&column, powers)
            })
            .collect();
        let half = &modulus >> 1u32;
        'passes: for _ in 0..4 {
            let mut numerators = Vec::with_capacity(n);
            for value in &values {
                let scaled = (value * &denominator) % &modulus;
                let numerator = if scaled > half {
                    BigInt::from_biguint(Sign::Minus, &modulus - &scaled)
                } else {
                    BigInt::from(scaled)
                };
                let small = if extend {
                    small_enough(&numerator, &denominator, &modulus)
                } else {
                    numerator.bits() + MARGIN < modulus.bits()
                };
                if small {
                    numerators.push(numerator);
                } else if extend {
                    let (_, extra) = reconstruct(&(value * &denominator % &modulus), &modulus)?;
                    denominator *= extra;
                    continue 'passes;
                } else {
                    return None;
                }
            }
            return self
                .verify(&numerators, &denominator)
                .then_some(RationalSolution {
                    numerators,
                    denominator,
                });
        }
        None
    }

    /// `A N == D b` exactly.
    fn verify(&self, numerators: &[BigInt], denominator: &BigUint) -> bool {
        let denominator = BigInt::from(denominator.clone());
        self.system.rows.iter().zip(&self.system.b).all(|(row, b)| {
            let sum: BigInt = row.iter().map(|(j, a)| a * &numerators[*j]).sum();
            sum == &denominator * b
        })
    }
}

/// `|numerator| denominator 2^MARGIN < modulus`.
fn small_enough(numerator: &BigInt, denominator: &BigUint, modulus: &BigUint) -> bool {
    numerator.bits() + denominator.bits() + MARGIN < modulus.bits()
}

/// `N / D` with `N = D x mod M`, `|N|, D < sqrt(M / 2)` and
/// `|N| D 2^MARGIN < M` (the extended Euclidean algorithm stopped at the
/// first remainder below `sqrt(M / 2)`), if there is one.
fn reconstruct(x: &BigUint, modulus: &BigUint) -> Option<(BigInt, BigUint)> {
    let bound = BigInt::from((modulus >> 1u32).sqrt());
    let (mut r0, mut r1) = (BigInt::from(modulus.clone()), BigInt::from(x.clone()));
    let (mut s0, mut s1) = (BigInt::zero(), BigInt::one());
    while r1 >= bound {
        // Far from the bound, Lehmer's steps: the quotients that the
        // leading 63 bits determine, applied at once (Knuth, TAOCP 2,
        // 4.5.2, Algorithm L); near it, or where they determine none, one
        // step in full precision, so that the loop stops at the first
        // remainder below the bound.
        let batch = (r1.bits() > bound.bits() + 130)
            .then(|| lehmer_cofactors(&r0, &r1))
            .flatten();
        match batch {
            Some([a, b, c, d]) => {
                (r0, r1) = (&r0 * a + &r1 * b, &r0 * c + &r1 * d);
                (s0, s1) = (&s0 * a + &s1 * b, &s0 * c + &s1 * d);
            }
            None => {
                let (q, r) = r0.div_rem(&r1);
                (r0, r1) = (r1, r);
                let s = s0 - &q * &s1;
                (s0, s1) = (s1, s);
            }
        }
    }
    if s1.is_zero() {
        return None;
    }
    let (numerator, denominator) = if s1.is_negative() {
        (-r1, -s1)
    } else {
        (r1, s1)
    };
    let denominator = denominator.to_biguint()?;
    (BigInt::from(denominator.clone()) < bound && small_enough(&numerator, &denominator, modulus))
        .then_some((numerator, denominator))
}

/// The cofactors `[a, b, c, d]` of the Euclidean steps on `(r0, r1)`
/// (`r0 > r1 > 0`) that their leading 63 bits determine: the remainders
/// after them are `a r0 + b r1` and `c r0 + d r1`; `None` if they determine
/// no step.
fn lehmer_cofactors(r0: &BigInt, r1: &BigInt) -> Option<[i64; 4]> {
    let shift = r0.bits().saturating_sub(63);
    let leading = |r: &BigInt| (r >> shift).to_i128().unwrap_or(0);
    let (mut x, mut y) = (leading(r0), leading(r1));
    let (mut a, mut b, mut c, mut d) = (1i128, 0i128, 0i128, 1i128);
    while y + c > 0 && y + d > 0 {
        let q = (x + a) / (y + c);
        if q != (x + b) / (y + d) {
            break;
        }
        (a, c) = (c, a - q * c);
        (b, d) = (d, b - q * d);
        (x, y) = (y, x - q * y);
    }
    let fits = |v: i128| i64::try_from(v).ok();
    if b == 0 {
        return None;
    }
    Some([fits(a)?, fits(b)?, fits(c)?, fits(d)?])
}

/// `p^(2^j)` for `2^j <= steps`.
fn powers(p: u64, steps: usize) -> Vec<BigUint> {
    let mut powers = vec![BigUint::from(p)];
    while 1usize << powers.len() <= steps {
        let last = powers.last().expect("one power at least");
        powers.push(last * last);
    }
    powers
}

/// `sum_t digits[t] p^t`, halves combined by the powers `p^(2^j)`.
fn from_digits(digits: &[u128], powers: &[BigUint]) -> BigUint {
    match digits.len() {
        0 => BigUint::zero(),
        1..=4 => {
            let p = &powers[0];
            digits
                .iter()
                .rev()
                .fold(BigUint::zero(), |acc, &d| acc * p + BigUint::from(d))
        }
        len => {
            let level = (len - 1).ilog2() as usize;
            let half = 1usize << level;
            from_digits(&digits[..half], powers)
                + from_digits(&digits[half..], powers) * &powers[level]
        }
    }
}

/// `value` in `width` limbs, two's complement.
fn limbs(value: &BigInt, width: usize) -> Vec<u64> {
    let mut limbs = value.magnitude().to_u64_digits();
    limbs.resize(width, 0);
    if value.is_negative() {
        negate(&mut limbs);
    }
    limbs
}

/// `x <- -x` in two's complement.
fn negate(x: &mut [u64]) {
    let mut carry = true;
    for limb in x {
        let (sum, overflow) = (!*limb).overflowing_add(u64::from(carry));
        *limb = sum;
        carry = overflow;
    }
}

/// `acc <- acc + a d` (`add`) or `acc - a d`, modulo `2^(64 len)`.
fn multiply_add(acc: &mut [u64], a: &[u64], d: u64, add: bool) {
    if d == 0 {
        return;
    }
    let mut product_carry = 0u64;
    let mut carry = false;
    for (t, limb) in acc.iter_mut().enumerate() {
        let term = match a.get(t) {
            Some(&a_t) => {
                let product = u128::from(a_t) * u128::from(d) + u128::from(product_carry);
                product_carry = (product >> 64) as u64;
                product as u64
            }
            None => std::mem::take(&mut product_carry),
        };
        if t > a.len() && !carry {
            break;
        }
        if add {
            let (s1, o1) = limb.overflowing_add(term);
            let (s2, o2) = s1.overflowing_add(u64::from(carry));
            *limb = s2;
            carry = o1 || o2;
        } else {
            let (s1, o1) = limb.overflowing_sub(term);
            let (s2, o2) = s1.overflowing_sub(u64::from(carry));
            *limb = s2;
            carry = o1 || o2;
        }
    }
}

/// `x <- x / p` for a two's complement `x` that `p` (odd) divides: the
/// product `x p^-1` modulo `2^(64 len)`, limb by limb from the lowest
/// (exact division by Hensel's inverse, no remainder computed).
/// `inverse = p^-1 mod 2^64`.
fn divide_exactly(x: &mut [u64], p: u64, inverse: u64) {
    let mut borrow = 0u64;
    for limb in x.iter_mut() {
        let (s, under) = limb.overflowing_sub(borrow);
        let q = s.wrapping_mul(inverse);
        *limb = q;
        // q p = s + (borrow out) 2^64.
        borrow = ((u128::from(q) * u128::from(p)) >> 64) as u64 + u64::from(under);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limb_arithmetic_matches_big_integers() {
        let p = (1u64 << 62) - 57;
        let a = BigInt::from(3u8) << 100u32;
        let r = BigInt::from(-7i8) * (BigInt::from(1u8) << 130u32) + 11;
        let d = 123_456_789_012_345u64;
        let mut acc = limbs(&r, 5);
        multiply_add(&mut acc, &a.magnitude().to_u64_digits(), d, false);
        let expected = &r - &a * d;
        assert_eq!(acc, limbs(&expected, 5));
        multiply_add(&mut acc, &a.magnitude().to_u64_digits(), d, true);
        assert_eq!(acc, limbs(&r, 5));
        let inverse = Modulus::new(p).inverse_mod_word;
        for value in [
            expected.clone(),
            -expected.clone(),
            BigInt::from(-1),
            BigInt::zero(),
        ] {
            let mut multiple = limbs(&(&value * p), 5);
            divide_exactly(&mut multiple, p, inverse);
            assert_eq!(multiple, limbs(&value, 5));
        }
    }

    /// The extended Euclidean algorithm in full precision, stopped at the
    /// first remainder below `bound`: `(r, s)` with `r = s x mod M`.
    fn plain_euclid(x: &BigUint, modulus: &BigUint, bound: &BigInt) -> (BigInt, BigInt) {
        let (mut r0, mut r1) = (BigInt::from(modulus.clone()), BigInt::from(x.clone()));
        let (mut s0, mut s1) = (BigInt::zero(), BigInt::one());
        while &r1 >= bound {
            let (q, r) = r0.div_rem(&r1);
            (r0, r1) = (r1, r);
            let s = s0 - &q * &s1;
            (s0, s1) = (s1, s);
        }
        (r1, s1)
    }

    proptest::proptest! {
        /// Lehmer's steps stop where the plain algorithm stops, and find
        /// what it finds.
        #[test]
        fn reconstruction_with_lehmer_steps_matches_the_plain_algorithm(
            numerator in proptest::collection::vec(proptest::num::u64::ANY, 1..12),
            denominator in proptest::collection::vec(proptest::num::u64::ANY, 1..12),
            extra_digits in 0usize..8,
        ) {
            let p = (1u64 << 62) - 57;
            let numerator = BigUint::new(numerator.iter().flat_map(|&d| [d as u32, (d >> 32) as u32]).collect());
            let denominator = BigUint::new(denominator.iter().flat_map(|&d| [d as u32, (d >> 32) as u32]).collect()) | BigUint::one();
            let steps = ((numerator.bits() + denominator.bits() + MARGIN + 2) / 62 + 1) as u32 + extra_digits as u32;
            let modulus = BigUint::from(p).pow(steps);
            let Some(inverse) = denominator.modinv(&modulus) else {
                return Ok(());
            };
            let x = &numerator * inverse % &modulus;
            let bound = BigInt::from((&modulus >> 1u32).sqrt());
            let (r, s) = plain_euclid(&x, &modulus, &bound);
            let found = reconstruct(&x, &modulus);
            if let Some((n, d)) = &found {
                // The same stop: (r, s) up to the sign.
                let sign = if s.is_negative() { -1 } else { 1 };
                proptest::prop_assert_eq!(n, &(&r * sign));
                proptest::prop_assert_eq!(BigInt::from(d.clone()), &s * sign);
            }
            let fits = BigInt::from(numerator.clone()) < bound && BigInt::from(denominator.clone()) < bound
                && numerator.bits() + denominator.bits() + MARGIN < modulus.bits();
            if fits {
                let g = num_integer::Integer::gcd(&numerator, &denominator);
                proptest::prop_assert_eq!(
                    found,
                    Some((BigInt::from(&numerator / &g), &denominator / &g))
                );
            }
            // Random x: lehmer and plain agree on the stop as well.
            let y = (&x * 3u8 + 12345u32) % &modulus;
            let (r, s) = plain_euclid(&y, &modulus, &bound);
            if let Some((n, d)) = reconstruct(&y, &modulus) {
                let sign = if s.is_negative() { -1 } else { 1 };
                proptest::prop_assert_eq!(n, &r * sign);
                proptest::prop_assert_eq!(BigInt::from(d), &s * sign);
            }
        }
    }

    #[test]
    fn digits_and_reconstruction_recover_a_fraction() {
        let p = 1_000_000_007u64;
        let digits = [5u128, 17, 999, 3, 0, 1, 2];
        let powers = powers(p, digits.len());
        let horner = digits
            .iter()
            .rev()
            .fold(BigUint::zero(), |acc, &d| acc * p + BigUint::from(d));
        assert_eq!(from_digits(&digits, &powers), horner);
        // -22/7 modulo p^4.
        let modulus = BigUint::from(p).pow(4);
        let inverse_of_7 = BigUint::from(7u8).modinv(&modulus).unwrap();
        let x = (&modulus - BigUint::from(22u8)) * inverse_of_7 % &modulus;
        assert_eq!(
            reconstruct(&x, &modulus),
            Some((BigInt::from(-22), BigUint::from(7u8)))
        );
    }
}
