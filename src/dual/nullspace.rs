//! The null-space method (46) of Sec. 5.2: an estimate when W̃(λ*) does not have the single zero
//! eigenvalue property (SZEP).
//!
//! By Theorem 1 a primal-feasible x̃ in the null space of W̃(λ*) is optimal. When the zero
//! eigenvalue has multiplicity q > 1, the paper looks for a vector of that null space, x̃ = Ṽ z̃
//! (Ṽ ∈ ℂ^{(2n−1)×q} a basis, z̃ ∈ ℂ^q), that is "close" to the feasible set |x̃_i| = 1 on the
//! rotation entries, by relaxing the unit-modulus constraints to |x̃_i| ≤ 1 and pushing the
//! entries outwards with a linear objective:
//!
//! ```text
//! max_z̃  Σ_{i=1}^{2n−1} Re(Ṽ_i z̃) + Im(Ṽ_i z̃)    s.t.  |Ṽ_i z̃|² ≤ 1,  i a rotation row    (46)
//! ```
//!
//! (Ṽ_i the i-th row of Ṽ; the objective sums over all rows, positions included, as in the paper).
//! With z̃ = a + ib the problem is a second-order-cone program over (a, b) ∈ ℝ^{2q}: Re(Ṽ_i z̃)
//! and Im(Ṽ_i z̃) are linear in (a, b), the objective is Re((1 − i) Σ_i Ṽ_i z̃), and each
//! rotation row gives the 3-dimensional cone (1, Re(Ṽ_i z̃), Im(Ṽ_i z̃)) ∈ SOC. It is solved with
//! clarabel (`SecondOrderConeT`, no BLAS needed). Algorithm 1 then normalizes the rotation
//! entries of x̃ = Ṽ z̃* to unit modulus: that is the caller's job, the estimate is not optimal
//! in general.

use std::ops::Range;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use faer::{MatRef, c64};

/// Why the null-space method failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NullSpaceError {
    #[error("the null-space basis has no columns or no rotation rows")]
    Empty,
    #[error("rotation rows {start}..{end} are out of range for a basis with {rows} rows")]
    RowsOutOfRange {
        start: usize,
        end: usize,
        rows: usize,
    },
    #[error("the null-space basis has a non-finite entry")]
    NotFinite,
    #[error(
        "problem (46) is unbounded: the rotation rows of the basis do not have full column rank"
    )]
    Unbounded,
    #[error("the SOCP solver failed: {0}")]
    Solver(String),
}

/// The null-space method, problem (46) of Sec. 5.2: given a basis `v` = Ṽ ∈ ℂ^{(2n−1)×q} of the
/// null space of W̃(λ*) (one basis vector per column) and the rows of `v` that hold rotations
/// (`rotation_rows`; `n−1..2n−1` in pgo's layout [ρ; r] with positions of poses 2..n first),
/// solves
///
/// ```text
/// z̃* = argmax_z̃ Σ_i Re(Ṽ_i z̃) + Im(Ṽ_i z̃)  s.t.  |Ṽ_i z̃| ≤ 1 for i in rotation_rows
/// ```
///
/// (the sum over all rows) as a second-order-cone program with clarabel, and returns
/// x̃ = Ṽ z̃*, all 2n−1 rows.
///
/// The rotation entries of x̃ have modulus at most 1 (the solution is scaled down by the
/// solver's feasibility error if it exceeds 1, about 1e-10), but are **not normalized**: as in
/// Algorithm 1, the caller divides each rotation entry by its modulus to get a primal-feasible
/// (in general suboptimal) estimate. The problem is bounded iff the rotation rows of Ṽ have full
/// column rank, which holds for a null space of W̃(λ) with a connected graph (a null vector with
/// zero rotations has L ρ = 0, so ρ = 0). In the SZEP case (q = 1, |ṽ_i| equal on the rotation
/// rows) the answer is ṽ / |ṽ_i| times the phase that maximizes the objective.
pub fn null_space_method(
    v: MatRef<'_, c64>,
    rotation_rows: Range<usize>,
) -> Result<Vec<c64>, NullSpaceError> {
    let (rows, q) = (v.nrows(), v.ncols());
    if rotation_rows.start > rotation_rows.end || rotation_rows.end > rows {
        return Err(NullSpaceError::RowsOutOfRange {
            start: rotation_rows.start,
            end: rotation_rows.end,
            rows,
        });
    }
    if q == 0 || rotation_rows.is_empty() {
        return Err(NullSpaceError::Empty);
    }
    if (0..q).any(|k| (0..rows).any(|i| !v[(i, k)].re.is_finite() || !v[(i, k)].im.is_finite())) {
        return Err(NullSpaceError::NotFinite);
    }

    // Variables y = (a, b), z = a + ib. Row i: Re(V_i z) = Σ_k Re V_ik a_k − Im V_ik b_k and
    // Im(V_i z) = Σ_k Im V_ik a_k + Re V_ik b_k; clarabel minimizes, so the cost is minus
    // Σ_i (Re + Im)(V_i z).
    let mut cost = vec![0.0; 2 * q];
    for k in 0..q {
        for i in 0..rows {
            let vik = v[(i, k)];
            cost[k] -= vik.re + vik.im;
            cost[q + k] -= vik.re - vik.im;
        }
    }
    // Cone t (rotation row i): s = b − A y = (1, Re(V_i z), Im(V_i z)) ∈ SOC(3), so rows 3t+1
    // and 3t+2 of A hold minus the coefficients of Re(V_i z) and Im(V_i z).
    let cones_count = rotation_rows.len();
    let mut colptr = Vec::with_capacity(2 * q + 1);
    let mut rowval = Vec::with_capacity(4 * q * cones_count);
    let mut nzval = Vec::with_capacity(4 * q * cones_count);
    colptr.push(0);
    for part in 0..2 {
        for k in 0..q {
            for (t, i) in rotation_rows.clone().enumerate() {
                let vik = v[(i, k)];
                // ∂(Re, Im)(V_i z)/∂a_k = (Re V_ik, Im V_ik); ∂/∂b_k = (−Im V_ik, Re V_ik).
                let (d_re, d_im) = if part == 0 {
                    (vik.re, vik.im)
                } else {
                    (-vik.im, vik.re)
                };
                rowval.extend([3 * t + 1, 3 * t + 2]);
                nzval.extend([-d_re, -d_im]);
            }
            colptr.push(rowval.len());
        }
    }
    let a = CscMatrix::new(3 * cones_count, 2 * q, colptr, rowval, nzval);
    let b: Vec<f64> = (0..3 * cones_count)
        .map(|r| if r % 3 == 0 { 1.0 } else { 0.0 })
        .collect();
    let p = CscMatrix::zeros((2 * q, 2 * q));
    let cones = vec![SupportedConeT::SecondOrderConeT(3); cones_count];

    // Tighter than clarabel's 1e-8: the optimum of a linear objective over this curved set moves
    // like the square root of the gap, so 1e-8 left x about 1e-5 off (1e-10: about 1e-6, still
    // `Solved` in about 11 iterations; 1e-12 ends `AlmostSolved`). QDLDL, sequential: the same
    // result with or without the `clarabel-sdp` feature (which makes faer's LDL available).
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .direct_solve_method("qdldl".to_string())
        .max_threads(1)
        .tol_gap_abs(1e-10)
        .tol_gap_rel(1e-10)
        .tol_feas(1e-10)
        .build()
        .map_err(|e| NullSpaceError::Solver(format!("clarabel settings: {e}")))?;
    let mut solver = DefaultSolver::new(&p, &cost, &a, &b, &cones, settings)
        .map_err(|e| NullSpaceError::Solver(format!("clarabel: {e}")))?;
    solver.solve();
    let solution = &solver.solution;
    match solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => {
            return Err(NullSpaceError::Unbounded);
        }
        status => {
            return Err(NullSpaceError::Solver(format!(
                "clarabel status {status:?}"
            )));
        }
    }

    let y = &solution.x;
    let mut x: Vec<c64> = (0..rows)
        .map(|i| (0..q).map(|k| v[(i, k)] * c64::new(y[k], y[q + k])).sum())
        .collect();
    // Remove the solver's feasibility error so that |x_i| ≤ 1 holds exactly on rotation rows.
    let largest = x[rotation_rows]
        .iter()
        .map(|xi| xi.norm())
        .fold(0.0, f64::max);
    if largest > 1.0 {
        x.iter_mut().for_each(|xi| *xi /= largest);
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    /// SplitMix64: deterministic test data without a dependency.
    struct Rng(u64);

    impl Rng {
        fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        /// Uniform in [−1, 1).
        fn signed(&mut self) -> f64 {
            2.0 * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64) - 1.0
        }
        fn complex(&mut self) -> c64 {
            c64::new(self.signed(), self.signed())
        }
    }

    /// The objective of (46) at x = V z.
    fn objective(x: &[c64]) -> f64 {
        x.iter().map(|xi| xi.re + xi.im).sum()
    }

    fn close(a: c64, b: c64, tol: f64) -> bool {
        (a - b).norm() <= tol
    }

    #[test]
    fn szep_case_scales_the_null_vector() {
        // q = 1, |v_i| = ρ on the rotation rows: x = v e^{iφ}/ρ with the phase maximizing
        // Re((1 − i) e^{iφ} Σ v_i) / ρ, i.e. e^{iφ} = conj(w)/|w|, w = (1 − i) Σ v_i.
        let mut rng = Rng(1);
        for (n, rho) in [(2usize, 0.3), (5, 1.7), (12, 0.05)] {
            let rows = 2 * n - 1;
            let v = Mat::from_fn(rows, 1, |i, _| {
                if i < n - 1 {
                    rng.complex()
                } else {
                    c64::cis(3.0 * rng.signed()) * rho
                }
            });
            let x = null_space_method(v.as_ref(), n - 1..rows).unwrap();
            let w = c64::new(1.0, -1.0) * (0..rows).map(|i| v[(i, 0)]).sum::<c64>();
            let phase = w.conj() / w.norm();
            for i in 0..rows {
                assert!(
                    close(x[i], v[(i, 0)] * phase / rho, 1e-6),
                    "row {i}: {}",
                    x[i]
                );
            }
            for xi in &x[n - 1..] {
                assert!((xi.norm() - 1.0).abs() < 1e-6 && xi.norm() <= 1.0);
            }
        }
    }

    #[test]
    fn two_independent_rotations() {
        // V = [[u0, u1], [e^{iα}, 0], [0, e^{iβ}]], rotation rows 1..3: x_1 = e^{iα} z_0 and
        // x_2 = e^{iβ} z_1 are independent, x_0 = u0 e^{−iα} x_1 + u1 e^{−iβ} x_2, so the
        // objective Re((1 − i)(x_0 + x_1 + x_2)) splits and x_1 = conj(w_1)/|w_1| with
        // w_1 = (1 − i)(1 + u0 e^{−iα}), likewise x_2.
        let (u0, u1) = (c64::new(0.5, 2.0), c64::new(-1.0, 0.25));
        let (alpha, beta) = (0.7, -2.1);
        let v = Mat::from_fn(3, 2, |i, k| match (i, k) {
            (0, 0) => u0,
            (0, 1) => u1,
            (1, 0) => c64::cis(alpha),
            (2, 1) => c64::cis(beta),
            _ => c64::new(0.0, 0.0),
        });
        let x = null_space_method(v.as_ref(), 1..3).unwrap();
        let one_minus_i = c64::new(1.0, -1.0);
        let w1 = one_minus_i * (c64::new(1.0, 0.0) + u0 * c64::cis(-alpha));
        let w2 = one_minus_i * (c64::new(1.0, 0.0) + u1 * c64::cis(-beta));
        let (x1, x2) = (w1.conj() / w1.norm(), w2.conj() / w2.norm());
        assert!(close(x[1], x1, 1e-6), "{} vs {x1}", x[1]);
        assert!(close(x[2], x2, 1e-6), "{} vs {x2}", x[2]);
        let x0 = u0 * c64::cis(-alpha) * x1 + u1 * c64::cis(-beta) * x2;
        assert!(close(x[0], x0, 1e-6), "{} vs {x0}", x[0]);

        // Without position rows and with V = I: each rotation is (1 + i)/√2.
        let x = null_space_method(Mat::<c64>::identity(2, 2).as_ref(), 0..2).unwrap();
        let diag = c64::new(1.0, 1.0) / 2f64.sqrt();
        assert!(close(x[0], diag, 1e-6) && close(x[1], diag, 1e-6), "{x:?}");
    }

    #[test]
    fn random_bases_feasible_optimal_and_basis_independent() {
        let mut rng = Rng(2);
        for (n, q) in [(4usize, 2usize), (10, 2), (10, 3), (25, 4)] {
            let rows = 2 * n - 1;
            let rot = n - 1..rows;
            let v = Mat::from_fn(rows, q, |_, _| rng.complex());
            let x = null_space_method(v.as_ref(), rot.clone()).unwrap();
            let largest = x[rot.clone()]
                .iter()
                .map(|xi| xi.norm())
                .fold(0.0, f64::max);
            assert!(largest <= 1.0 + 1e-7, "constraint violated: {largest}");
            assert!(largest >= 1.0 - 1e-6, "no constraint active: {largest}");
            // Not beaten by random feasible points V z (z scaled onto the feasible set).
            let best = objective(&x);
            for _ in 0..200 {
                let z: Vec<c64> = (0..q).map(|_| rng.complex()).collect();
                let vz: Vec<c64> = (0..rows)
                    .map(|i| (0..q).map(|k| v[(i, k)] * z[k]).sum())
                    .collect();
                let m = vz[rot.clone()]
                    .iter()
                    .map(|xi| xi.norm())
                    .fold(0.0, f64::max);
                let candidate: Vec<c64> = vz.iter().map(|xi| xi / m).collect();
                assert!(objective(&candidate) <= best + 1e-7);
            }
            // x depends on the null space only, not on its basis: V G, G invertible.
            let g = Mat::from_fn(q, q, |i, k| {
                rng.complex() * 0.3
                    + if i == k {
                        c64::new(1.0, 0.0)
                    } else {
                        c64::new(0.0, 0.0)
                    }
            });
            let vg = &v * &g;
            let y = null_space_method(vg.as_ref(), rot.clone()).unwrap();
            for i in 0..rows {
                assert!(close(x[i], y[i], 1e-5), "row {i}: {} vs {}", x[i], y[i]);
            }
        }
    }

    #[test]
    fn errors_and_rotation_row_placement() {
        let v = Mat::<c64>::identity(3, 2);
        assert_eq!(
            null_space_method(v.as_ref(), 1..4),
            Err(NullSpaceError::RowsOutOfRange {
                start: 1,
                end: 4,
                rows: 3
            })
        );
        assert_eq!(
            null_space_method(v.as_ref(), 2..2),
            Err(NullSpaceError::Empty)
        );
        assert_eq!(
            null_space_method(Mat::<c64>::zeros(3, 0).as_ref(), 0..3),
            Err(NullSpaceError::Empty)
        );
        let mut nan = Mat::<c64>::identity(3, 2);
        nan[(0, 1)] = c64::new(0.0, f64::INFINITY);
        assert_eq!(
            null_space_method(nan.as_ref(), 0..3),
            Err(NullSpaceError::NotFinite)
        );
        // The second basis vector only moves row 1, which is not a rotation row.
        let rank_deficient = Mat::<c64>::identity(3, 2);
        assert_eq!(
            null_space_method(rank_deficient.as_ref(), 0..1),
            Err(NullSpaceError::Unbounded)
        );
        // Rotation rows need not be at the end: q = 1 with row 1 the only rotation row.
        let v = Mat::from_fn(3, 1, |i, _| c64::new([2.0, 1.0, 3.0][i], 0.0));
        let x = null_space_method(v.as_ref(), 1..2).unwrap();
        assert!((x[1].norm() - 1.0).abs() < 1e-6);
        assert!(close(x[0], x[1] * 2.0, 1e-9) && close(x[2], x[1] * 3.0, 1e-9));
    }
}
