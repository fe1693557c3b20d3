//! What the sparse certificates share, whatever the scalar (ℂ in 2D, ℝ in 3D) and the number k of
//! eigenvalues they deflate (1 in 2D, 3 in 3D: the estimate's null directions): the power-of-two
//! equilibration and the ladder of shifts μ that isolates the k smallest eigenvalues of an
//! equilibrated matrix B by the inertia of LDLᴴ factorizations of B − μI (Sylvester's law: with
//! at most k negative pivots, and E the factorization's backward error plus the rounding of B
//! itself, λ_{k+1}(B) ≥ θ = μ − ‖E‖). Used by [`super::sparse::SparseCertifier`] and
//! [`crate::se3::certificate`].

/// D_k = 2^{−⌊log₂(a)/2⌋} for a diagonal entry a > 0: D_k² a lies in [1, 4), and scaling by it is
/// exact.
pub fn power_of_two_scale(a: f64) -> f64 {
    let e = (a.log2() / 2.0).floor();
    2f64.powi(-(e as i32))
}

/// The outcome of [`isolate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ladder {
    /// λ_{k+1}(B) ≥ θ > 0 proven at shift μ, with `negative` ≤ k negative pivots.
    Found {
        theta: f64,
        negative: usize,
        mu: f64,
    },
    /// At most k pivots are negative at μ, but the rounding hides the gap there (the caller may
    /// retry in higher precision).
    Hidden { mu: f64 },
    /// No shift isolates k eigenvalues, or a factorization could not be formed.
    Failed,
}

/// The shift ladder: μ from `start` down by 64 (by 4096 while 100 or more pivots are negative:
/// the count of eigenvalues below μ falls like a power of μ, Weyl's law) while more than k are
/// negative, at most 8 rungs and not below 4·`assembly`; where the rounding hides the gap at the
/// first rung with at most k, three log-scale bisections towards the rung above. `inertia(μ)`
/// factors B − μI: `Some(Some((negative pivots, backward error)))`, `Some(None)` on a zero pivot,
/// `None` when the matrix cannot be formed (then no shift will do). `assembly` bounds the
/// difference between the stored B and the exact one.
pub fn isolate(
    k: usize,
    start: f64,
    assembly: f64,
    mut inertia: impl FnMut(f64) -> Option<Option<(usize, f64)>>,
) -> Ladder {
    let mut mu = start;
    // The last shift with more than k negative pivots, if any.
    let mut above: Option<f64> = None;
    for _ in 0..8 {
        let Some(at) = inertia(mu) else {
            return Ladder::Failed;
        };
        match at {
            Some((negative, error)) if negative <= k => {
                let theta = mu - error - assembly;
                if theta > 0.0 {
                    return Ladder::Found {
                        theta,
                        negative,
                        mu,
                    };
                }
                // The rounding hides the gap at μ; λ_{k+1} may lie well above μ (the shifts step
                // by 64): bisect (in log scale, three times) towards the shift above.
                if let Some(mut hi) = above {
                    for _ in 0..3 {
                        let mid = (mu * hi).sqrt();
                        let Some(at) = inertia(mid) else {
                            return Ladder::Failed;
                        };
                        match at {
                            Some((negative, error)) if negative <= k => {
                                let theta = mid - error - assembly;
                                if theta > 0.0 {
                                    return Ladder::Found {
                                        theta,
                                        negative,
                                        mu: mid,
                                    };
                                }
                                mu = mid;
                            }
                            _ => hi = mid,
                        }
                    }
                }
                return Ladder::Hidden { mu };
            }
            other => {
                above = Some(mu);
                let many = matches!(other, Some((negative, _)) if negative >= 100);
                mu /= if many { 4096.0 } else { 64.0 };
            }
        }
        if mu < 4.0 * assembly {
            break;
        }
    }
    Ladder::Failed
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A diagonal "matrix" with known eigenvalues: the inertia of B − μI counts those below μ.
    fn ladder(eigenvalues: &[f64], k: usize, error: f64) -> (Ladder, Vec<f64>) {
        let mut shifts = Vec::new();
        let l = isolate(k, 1.0 / 16.0, 0.0, |mu| {
            shifts.push(mu);
            Some(Some((
                eigenvalues.iter().filter(|&&e| e < mu).count(),
                error,
            )))
        });
        (l, shifts)
    }

    #[test]
    fn the_ladder_isolates_k_eigenvalues_and_proves_the_next_one() {
        // Three at zero, the fourth at 1e-3: μ = 1/16 sees 5 below, 1/1024 sees 3.
        let eig = [0.0, 0.0, 0.0, 1e-3, 2e-3, 1.0];
        let (l, shifts) = ladder(&eig, 3, 1e-9);
        assert_eq!(shifts, vec![1.0 / 16.0, 1.0 / 1024.0]);
        match l {
            Ladder::Found {
                theta, negative, ..
            } => {
                assert_eq!(negative, 3);
                assert!(theta > 0.0 && theta <= 1e-3, "{theta}");
            }
            other => panic!("{other:?}"),
        }
        // With k = 1 the same matrix never isolates: three are at zero.
        assert_eq!(ladder(&eig, 1, 1e-9).0, Ladder::Failed);
        // An error above the shift: the gap is hidden.
        assert!(matches!(ladder(&eig, 3, 1.0).0, Ladder::Hidden { .. }));
        assert!((power_of_two_scale(10.0).powi(2) * 10.0 - 2.5).abs() < 1e-15);
    }
}
