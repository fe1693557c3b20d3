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

#[cfg(test)]
mod tests {
    use super::*;

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
