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
}
