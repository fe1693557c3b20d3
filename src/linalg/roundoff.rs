//! Floating-point error bounds in the notation of Higham, *Accuracy and Stability of Numerical
//! Algorithms* (2nd ed., §3.1-3.6): u = 2⁻⁵³ the unit roundoff and γ_k = k·u / (1 − k·u). A sum
//! of k terms computed in any order is within γ_{k−1}·Σ|terms| of the exact sum, and a complex
//! product within √2·γ₂ of its modulus (Lemma 3.5). The certificates use these bounds so that the
//! bounds they print hold for the exact numbers behind the floating-point ones.

/// The unit roundoff of IEEE double precision (round to nearest).
pub const U: f64 = f64::EPSILON / 2.0;

/// γ_k = k·u/(1 − k·u): the relative error of k successive roundings (∞ when k·u ≥ 1).
pub fn gamma(k: usize) -> f64 {
    gamma_with(U, k)
}

/// γ_k for an arithmetic of unit roundoff `u` (e.g. double-double's).
pub fn gamma_with(u: f64, k: usize) -> f64 {
    let ku = k as f64 * u;
    if ku < 0.5 {
        ku / (1.0 - ku)
    } else {
        f64::INFINITY
    }
}

/// |Re z| + |Im z|: an upper bound on the modulus |z|, within a factor √2 of it, for the error
/// bounds, which need no more. `hypot` (what `c64::norm` calls) took 3% of a landmark solve's
/// CPU in the enclosure of f and W̃x and in Temple's residual, some 20 moduli per edge. Its one
/// rounding can leave it below |z| only where one part is under 2u of the other, and then by a
/// relative 2u² at most (the sum is at least the larger part, a float): less than `hypot`'s own
/// error, of up to an ulp, which the bounds' margins of 4u already cover.
pub fn modulus_bound(z: faer::c64) -> f64 {
    z.re.abs() + z.im.abs()
}

/// The unit roundoff the error bounds take for the double-double arithmetic of faer's `cx128`
/// (its real parts are the `qd` crate's `Quad`), in which the certificate's last-resort LDLᴴ runs:
/// 32u², twice what its operations are proven to need.
///
/// A double-double x = x₀ + x₁ is normalized, |x₁| ≤ ulp(x₀)/2 ≤ u|x₀|. faer adds with qd's
/// `add_estimate` (TwoSum of the high parts, the low parts added in double, then Fast2Sum),
/// multiplies with two FMAs after an exact TwoProd, and divides by a pivot as a product with its
/// reciprocal, qd's three-step long division of 1. Without underflow or overflow (the
/// equilibrated matrices the certificate factors are far from both), each operation satisfies the
/// weak model of floating-point arithmetic (the model of a machine without a guard digit, Higham
/// §2.2), fl(x ± y) = x(1 + α) ± y(1 + β), fl(x·y) = xy(1 + δ), with |α|, |β|, |δ| ≤ 16u²:
/// - x + y: TwoSum gives s₀ + e₁ = x₀ + y₀ exactly, |e₁| ≤ u|x₀ + y₀|; s₁ = fl(x₁ + y₁) and
///   e = fl(e₁ + s₁) err by u|x₁ + y₁| ≤ u²(|x₀| + |y₀|) and u|e₁ + s₁| ≤ u²(2 + u)(|x₀| + |y₀|);
///   Fast2Sum(s₀, e) is exact where |s₀| ≥ |e|, else (cancellation: |s₀| < |e| ≤ 2.01u(|x₀| +
///   |y₀|)) errs by at most u|e| + O(u²)|e|. In all: ≤ 5.02u²(|x| + |y|). Not relative to |x + y|:
///   under cancellation the low parts' rounding stays, which the weak model charges to the
///   operands.
/// - x·y: x₀y₀ = p₀ + e₁ exactly; the two FMAs add x₀y₁ and x₁y₀ (each ≤ u|x₀y₀|) with two
///   roundings, of at most u·(2u + u²) and u·(3u + u²) times |x₀y₀|, and x₁y₁ ≤ u²|x₀y₀| is left
///   out; Fast2Sum is exact (the low part, at most 3.01u|p₀|, is below p₀). In all ≤ 6.01u²|xy|.
/// - 1/d: q₀ = fl(1/d₀) is within 2.01u of 1/d; the computed remainder of 1 − d·q₀ (itself at
///   most 2.01u) errs by at most 6.05u², the product's 6.01u²·|d·q₀| and qd's accurate
///   subtraction's 3u² + 13u³ of the remainder (Joldes, Muller and Popescu 2017, ACM TOMS 44(2),
///   Algorithm 6); the second remainder and the third quotient are O(u²) and O(u³) terms; the
///   final accurate addition adds 3.01u²: ≤ 9.1u²|1/d|, and the product by it ≤ 15.2u²|x/d|.
///
/// The error analyses of sums, inner products and LDLᵀ (Higham, Lemma 8.4 and Theorem 10.3) put
/// one factor (1 + α) per rounding on each term of a sum, which the weak model gives as the
/// standard one does: their bounds γ_k hold with this unit roundoff. The tests check each bound
/// against sums and products computed exactly (error-free transformations), on random operands
/// and on the cancellations that break relative accuracy.
pub const DOUBLE_DOUBLE_U: f64 = 32.0 * U * U;

#[cfg(test)]
mod tests {
    use super::*;

    /// modulus_bound(z) against |z|² in double-double (products of doubles exact in it): never
    /// below |z| by more than a relative 2u², never above √2·|z| by more than its rounding, over
    /// parts of every ratio from equal to 2⁻¹⁰⁰ (where the sum rounds to the larger part) and of
    /// both signs.
    #[test]
    fn the_modulus_bound_is_an_upper_bound_within_root_two() {
        use faer::fx128;
        let mut seed = 1u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..100_000 {
            let a = (next() - 0.5) * 2f64.powi((next() * 40.0) as i32 - 20);
            let ratio = 2f64.powi(-((next() * 100.0) as i32)) * next();
            let b = a * ratio * if next() < 0.5 { -1.0 } else { 1.0 };
            for z in [faer::c64::new(a, b), faer::c64::new(b, a)] {
                let m = modulus_bound(z);
                let (re, im, mm) = (
                    fx128::from_f64(z.re),
                    fx128::from_f64(z.im),
                    fx128::from_f64(m),
                );
                let square = re * re + im * im;
                let low = square * (fx128::from_f64(1.0) - fx128::from_f64(4.0 * U * U));
                assert!(mm * mm >= low, "{z:?}: {m} below |z|");
                let high = square * fx128::from_f64(2.0 * (1.0 + 2.0 * U));
                assert!(mm * mm <= high, "{z:?}: {m} above √2|z|");
            }
        }
    }

    #[test]
    fn gamma_bounds_the_error_of_a_long_sum() {
        // Σ fl(0.1) over 10^6 terms: the float sum drifts, but stays within γ_{k−1}·Σ|terms| of
        // the exact sum 10^6·fl(0.1) = 100000.0000000000055511…, which is 10^5 to 6e-12.
        let k = 1_000_000;
        let s: f64 = std::iter::repeat_n(0.1, k).sum();
        let exact = 1e5;
        assert!((s - exact).abs() <= gamma(k - 1) * exact + 6e-12);
        assert!(
            (s - exact).abs() > 0.0,
            "the sum must actually drift for this test to mean something"
        );
        assert_eq!(gamma(0), 0.0);
        assert!(gamma(1 << 53).is_infinite());
    }

    /// Knuth's TwoSum: s + e = a + b exactly (any order, no branch).
    fn two_sum(a: f64, b: f64) -> (f64, f64) {
        let s = a + b;
        let bb = s - a;
        (s, (a - (s - bb)) + (b - bb))
    }

    /// The exact sum of `terms` as a nonoverlapping expansion (Shewchuk's Grow-Expansion, one
    /// term at a time, zeros dropped), returned as its value rounded: its components summed from
    /// the smallest, within a relative 2u of the exact sum.
    fn exact_sum(terms: &[f64]) -> f64 {
        let mut expansion: Vec<f64> = Vec::new();
        for &b in terms {
            let mut q = b;
            let mut next = Vec::with_capacity(expansion.len() + 1);
            for &e in &expansion {
                let (s, h) = two_sum(q, e);
                q = s;
                if h != 0.0 {
                    next.push(h);
                }
            }
            if q != 0.0 {
                next.push(q);
            }
            expansion = next;
        }
        expansion.iter().sum()
    }

    /// The exact products of two double-doubles' parts, as terms (TwoProd by FMA).
    fn product_terms(x: fx128, y: fx128) -> Vec<f64> {
        let mut terms = Vec::with_capacity(8);
        for a in [x.0, x.1] {
            for b in [y.0, y.1] {
                let p = a * b;
                terms.extend([p, a.mul_add(b, -p)]);
            }
        }
        terms
    }

    use faer::fx128;

    /// A normalized double-double of magnitude between 2⁻⁴⁰ and 2⁴¹ and a random low part.
    fn random_dd(rng: &mut crate::linalg::rng::Rng) -> fx128 {
        let e = (rng.uniform() * 80.0) as i32 - 40;
        let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
        let hi = sign * (1.0 + rng.uniform()) * 2f64.powi(e);
        let (s, l) = two_sum(hi, hi * U * (2.0 * rng.uniform() - 1.0));
        fx128 { 0: s, 1: l }
    }

    #[test]
    fn double_double_operations_meet_the_weak_model_with_room_to_spare() {
        let mut rng = crate::linalg::rng::Rng::new(17);
        let uu = U * U;
        let (mut add, mut mul, mut inv, mut div) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let mut cancelled = 0.0f64;
        for k in 0..200_000 {
            let x = random_dd(&mut rng);
            // Every fourth y cancels x's high part, to within a few of its ulps, or exactly.
            let y = if k % 4 == 0 {
                let ulps = ((rng.uniform() * 7.0) as i32 - 3) as f64;
                let y0 = -x.0 + ulps * x.0.abs() * f64::EPSILON;
                let (s, l) = two_sum(y0, y0 * U * (2.0 * rng.uniform() - 1.0));
                fx128 { 0: s, 1: l }
            } else {
                random_dd(&mut rng)
            };
            let magnitude = |v: fx128| (v.0 + v.1).abs();
            // x + y against the exact x₀ + x₁ + y₀ + y₁, relative to |x| + |y|.
            let z = x + y;
            let err = exact_sum(&[z.0, z.1, -x.0, -x.1, -y.0, -y.1]).abs();
            let relative = err / ((magnitude(x) + magnitude(y)) * uu);
            add = add.max(relative);
            if k % 4 == 0 {
                let sum = magnitude(z).max(f64::MIN_POSITIVE);
                cancelled = cancelled.max(err / (sum * uu));
            }
            // x·y against the eight exact partial products.
            let z = x * y;
            let mut terms = vec![z.0, z.1];
            terms.extend(product_terms(x, y).iter().map(|t| -t));
            mul = mul.max(exact_sum(&terms).abs() / (magnitude(x) * magnitude(y) * uu));
            // 1/y: |1 − y·q| / 1 is the relative error of q.
            let q = fx128 { 0: 1.0, 1: 0.0 } / y;
            let mut terms = vec![-1.0];
            terms.extend(product_terms(y, q));
            inv = inv.max(exact_sum(&terms).abs() / uu);
            // x·(1/y), as the LDLᴴ divides by a pivot: |x − y·z| / |x|.
            let z = x * q;
            let mut terms = vec![-x.0, -x.1];
            terms.extend(product_terms(y, z));
            div = div.max(exact_sum(&terms).abs() / (magnitude(x) * uu));
        }
        // The proven constants hold, and 32u² is at least twice the largest of them.
        assert!(add <= 5.02, "addition {add} u²");
        assert!(mul <= 6.01, "multiplication {mul} u²");
        assert!(inv <= 9.1, "reciprocal {inv} u²");
        assert!(div <= 15.2, "product by a reciprocal {div} u²");
        assert!(DOUBLE_DOUBLE_U >= 2.0 * 15.2 * uu);
        // And the cancellations did break relative accuracy: the weak model is the one needed.
        assert!(
            cancelled > 1e3,
            "cancellation {cancelled} u² relative to the sum"
        );
    }
}
