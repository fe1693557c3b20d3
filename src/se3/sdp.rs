//! SE-Sync's semidefinite relaxation, dense, for small graphs: the reference the certified
//! staircase is checked against (weak duality and the zero duality gap, `tests/se3_sdp.rs`).
//!
//! With the translations eliminated (SE-Sync, IJRR 2019, Problem 4 → the translation-explicit
//! form reduced by the Schur complement, eq. (20)-(22)), the rotations V = [R_1ᵀ; …; R_nᵀ]
//! (3n × 3, the rows of Y at p = 3 in [`super::problem`]'s layout) solve
//!
//! ```text
//! f* = min tr(Vᵀ M V)  over R_i ∈ SO(3),    M = Q_YY − Q_Yt L⁻¹ Q_tY
//! ```
//!
//! (SE-Sync's Problem 5 with its M̃ = Q̃ here: L = Q_tt the τ-weighted, anchored Laplacian, SPD
//! for a connected graph). Its semidefinite relaxation (SE-Sync's Problem 7) and the dual of it
//! (Problem 8, the Lagrangian dual of Problem 6) are
//!
//! ```text
//! p* = min tr(M X)  s.t.  X_ii = I₃ (3x3 diagonal blocks),  X ⪰ 0         (3n × 3n)
//! d* = max Σ_i tr Λ_i  s.t.  M − SymBlockDiag(Λ) ⪰ 0,  Λ_i = Λ_iᵀ ∈ ℝ³ˣ³
//! ```
//!
//! X = I and Λ_i = (λ_min(M) − 1) I are strictly feasible, so p* = d* (Slater), and
//! d* ≤ f* ≤ f(any estimate) (X = V Vᵀ is feasible); every dual-feasible Λ, the certificate's
//! included, has Σ tr Λ_i ≤ d*. SE-Sync's exactness result (zero gap) says f* = d* at low noise.
//!
//! [`reduced_matrix`] is always built (dense, O(n³)); [`solve_relaxation`], with clarabel, needs
//! the cargo feature `clarabel-sdp` (its PSD cone needs BLAS/LAPACK). Nothing in the solver uses
//! this module: it is the library's reference for tests and experiments, beside the planar
//! [`crate::dual::clarabel`] (which `se3` may not import: same floor).

use super::problem::Problem3;
use nalgebra::DMatrix;

/// M = Q_YY − Q_Yt L⁻¹ Q_tY, the 3n × 3n rotation-only data matrix of a connected problem
/// (rows 3i + a: row a of R_iᵀ), symmetrized. `None` if L is not positive definite (a
/// disconnected graph).
pub fn reduced_matrix(problem: &Problem3) -> Option<DMatrix<f64>> {
    let n = problem.n;
    let nt = n - 1;
    let dim = problem.dim();
    let mut q = DMatrix::<f64>::zeros(dim, dim);
    for (r, c, v, _) in problem.upper() {
        q[(r, c)] += v;
        if r != c {
            q[(c, r)] += v;
        }
    }
    let l = q.view((0, 0), (nt, nt)).into_owned();
    let b = q.view((0, nt), (nt, 3 * n)).into_owned();
    let qyy = q.view((nt, nt), (3 * n, 3 * n)).into_owned();
    let m = if nt == 0 {
        qyy
    } else {
        let chol = l.cholesky()?;
        qyy - b.transpose() * chol.solve(&b)
    };
    Some((&m + m.transpose()) * 0.5)
}

/// tr(Vᵀ M V) for rotations R_i (row-major, as [`super::rounding::Rt::r`]; V's block rows
/// R_iᵀ): the cost with the translations at their optimum for these rotations.
pub fn reduced_cost(m: &DMatrix<f64>, rotations: &[[f64; 9]]) -> f64 {
    let n = rotations.len();
    // V[3i + a][c] = (R_iᵀ)[a][c] = R_i[c][a].
    let v = DMatrix::<f64>::from_fn(3 * n, 3, |r, c| rotations[r / 3][c * 3 + r % 3]);
    (v.transpose() * m * v).trace()
}

/// A solution of the relaxation, made exactly feasible (see [`solve_relaxation`]).
#[cfg(feature = "clarabel-sdp")]
#[derive(Debug, Clone)]
pub struct Relaxation3 {
    /// Λ_i, dual feasible: M − SymBlockDiag(Λ) ⪰ 0 (after the shift).
    pub lambda: Vec<[[f64; 3]; 3]>,
    /// X, primal feasible: PSD with identity diagonal blocks (after the rescaling).
    pub x: DMatrix<f64>,
    /// Σ tr Λ_i ≤ d*.
    pub dual_objective: f64,
    /// tr(M X) ≥ p* = d*.
    pub primal_objective: f64,
    /// clarabel's status (`Solved` or `AlmostSolved`).
    pub status: String,
    pub iterations: u32,
}

/// Λ shifted by the smallest eigenvalue of M − SymBlockDiag(Λ) when that is negative (so that
/// M − SymBlockDiag(Λ) ⪰ 0 up to the rounding of the dense eigenvalues), and Σ tr Λ_i.
#[cfg(feature = "clarabel-sdp")]
fn made_feasible(m: &DMatrix<f64>, mut lambda: Vec<[[f64; 3]; 3]>) -> (Vec<[[f64; 3]; 3]>, f64) {
    let mut s = m.clone();
    for (i, l) in lambda.iter().enumerate() {
        for a in 0..3 {
            for b in 0..3 {
                s[(3 * i + a, 3 * i + b)] -= l[a][b];
            }
        }
    }
    let s = (&s + s.transpose()) * 0.5;
    let smallest = s.symmetric_eigenvalues().min();
    if smallest < 0.0 {
        for l in &mut lambda {
            for a in 0..3 {
                l[a][a] += smallest;
            }
        }
    }
    let objective = lambda.iter().map(|l| l[0][0] + l[1][1] + l[2][2]).sum();
    (lambda, objective)
}

/// Solves the dual d* = max Σ tr Λ_i s.t. M − SymBlockDiag(Λ) ⪰ 0 with clarabel, and reads X
/// from clarabel's dual variable.
///
/// clarabel's form is min qᵀx s.t. b − A x ∈ K: x holds the six entries of each Λ_i
/// ((0,0), (1,1), (2,2), (0,1), (0,2), (1,2)), q = −1 on the diagonal entries and 0 off it,
/// b − A x = svec(M − SymBlockDiag(Λ)) in the PSD cone of order 3n (svec: the upper triangle
/// by columns, off-diagonal entries times √2, so svec(P)ᵀsvec(Z) = ⟨P, Z⟩). Its dual is
/// max −bᵀz s.t. Aᵀz = −q, z = svec(Z) ⪰ 0: Aᵀz = −q says Z_(3i+a, 3i+a) = 1 and
/// √2·Z_(3i+a, 3i+b) = 0 for a < b, i.e. Z_ii = I₃, and −bᵀz = −⟨M, Z⟩: Z is the primal X of
/// Problem 7 itself (no embedding, unlike the planar complex case).
///
/// M is divided by max |M_ij| for the solve (Λ scales back, X does not change); tolerances
/// 1e-12 (clarabel's defaults, 1e-8, left relative gaps of 1e-5 at low noise, where f* is small
/// beside M's entries). clarabel meets its constraints to tolerance only, so the pair is then
/// made feasible: X ← D^{-1/2} X D^{-1/2} with D = BlockDiag(X_ii) (still ⪰ 0, now X_ii = I₃),
/// and Λ_i ← Λ_i + μI with μ = min(0, λ_min(M − SymBlockDiag(Λ))) (nalgebra's symmetric
/// eigenvalues), for clarabel's Λ and for the multipliers sym((MX)_ii) of X, the better kept. Then
/// `dual_objective` ≤ d* ≤ `primal_objective` up to the rounding of these dense computations,
/// and their difference bounds how far either is from d*. Deterministic: one thread.
///
/// # Errors
///
/// A message if M is not square of order 3n with finite entries, or clarabel ends with another
/// status than `Solved`/`AlmostSolved`, or X's diagonal blocks are not positive definite.
#[cfg(feature = "clarabel-sdp")]
pub fn solve_relaxation(m: &DMatrix<f64>) -> Result<Relaxation3, String> {
    use clarabel::algebra::CscMatrix;
    use clarabel::solver::{
        DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
    };
    let dim = m.nrows();
    if m.ncols() != dim || !dim.is_multiple_of(3) || m.iter().any(|v| !v.is_finite()) {
        return Err("M must be a finite 3n x 3n matrix".into());
    }
    let n = dim / 3;
    let tri = |r: usize, c: usize| c * (c + 1) / 2 + r;
    let scale = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let sqrt2 = std::f64::consts::SQRT_2;
    let mut b = vec![0.0; dim * (dim + 1) / 2];
    for c in 0..dim {
        for r in 0..=c {
            let f = if r == c { 1.0 } else { sqrt2 };
            b[tri(r, c)] = f * 0.5 * (m[(r, c)] + m[(c, r)]) / scale;
        }
    }
    // The six variables of Λ_i and their entries (a, b), a ≤ b.
    const ENTRIES: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    let nvar = 6 * n;
    let mut q = vec![0.0; nvar];
    // Column k of A: one entry, at svec's position of (3i+a, 3i+b); A x enters as −(b − A x).
    let (mut colptr, mut rowval, mut nzval) = (vec![0usize], Vec::new(), Vec::new());
    for i in 0..n {
        for (k, &(a, bb)) in ENTRIES.iter().enumerate() {
            let (r, c) = (3 * i + a, 3 * i + bb);
            rowval.push(tri(r, c));
            nzval.push(if a == bb { 1.0 } else { sqrt2 });
            colptr.push(rowval.len());
            if a == bb {
                q[6 * i + k] = -1.0;
            }
        }
    }
    let a_mat = CscMatrix::new(b.len(), nvar, colptr, rowval, nzval);
    let p_mat = CscMatrix::<f64>::zeros((nvar, nvar));
    let cones = [SupportedConeT::PSDTriangleConeT(dim)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_threads(1)
        .chordal_decomposition_enable(false)
        .direct_solve_method("auto".to_string())
        .tol_gap_abs(1e-12)
        .tol_gap_rel(1e-12)
        .tol_feas(1e-12)
        .build()
        .map_err(|e| format!("clarabel settings: {e}"))?;
    let mut solver = DefaultSolver::new(&p_mat, &q, &a_mat, &b, &cones, settings)
        .map_err(|e| format!("clarabel: {e}"))?;
    solver.solve();
    let status = solver.solution.status;
    if !matches!(status, SolverStatus::Solved | SolverStatus::AlmostSolved) {
        return Err(format!("clarabel ended {status:?}"));
    }
    let x = &solver.solution.x;
    let mut lambda = vec![[[0.0; 3]; 3]; n];
    for i in 0..n {
        for (k, &(a, bb)) in ENTRIES.iter().enumerate() {
            let v = x[6 * i + k] * scale;
            lambda[i][a][bb] = v;
            lambda[i][bb][a] = v;
        }
    }
    // X = Z, rescaled to identity diagonal blocks.
    let z = &solver.solution.z;
    let mut xm = DMatrix::<f64>::zeros(dim, dim);
    for c in 0..dim {
        for r in 0..=c {
            let v = if r == c {
                z[tri(r, c)]
            } else {
                z[tri(r, c)] / sqrt2
            };
            xm[(r, c)] = v;
            xm[(c, r)] = v;
        }
    }
    let mut scaling = DMatrix::<f64>::zeros(dim, dim);
    for i in 0..n {
        let block = xm.view((3 * i, 3 * i), (3, 3)).into_owned();
        let eig = block.symmetric_eigen();
        if eig.eigenvalues.iter().any(|&v| v.is_nan() || v <= 0.0) {
            return Err(format!("X's diagonal block {i} is not positive definite"));
        }
        let inv_sqrt = &eig.eigenvectors
            * DMatrix::from_diagonal(&eig.eigenvalues.map(|v| 1.0 / v.sqrt()))
            * eig.eigenvectors.transpose();
        scaling
            .view_mut((3 * i, 3 * i), (3, 3))
            .copy_from(&inv_sqrt);
    }
    let xm = &scaling * xm * &scaling;
    let xm = (&xm + xm.transpose()) * 0.5;
    let primal_objective = m.component_mul(&xm).sum();
    // Two dual candidates, each made feasible by the shift: clarabel's Λ, and the multipliers
    // of X's first-order conditions, Λ_i = sym((M X)_ii) (SE-Sync's Λ(Y) with X for YᵀY), which
    // at an exact relaxation are the optimal Λ to the accuracy of X; the better one is kept.
    let mx = m * &xm;
    let from_x: Vec<[[f64; 3]; 3]> = (0..n)
        .map(|i| {
            std::array::from_fn(|a| {
                std::array::from_fn(|bb| {
                    0.5 * (mx[(3 * i + a, 3 * i + bb)] + mx[(3 * i + bb, 3 * i + a)])
                })
            })
        })
        .collect();
    let (lambda, dual_objective) = {
        let a = made_feasible(m, lambda);
        let b = made_feasible(m, from_x);
        if b.1 > a.1 { b } else { a }
    };
    Ok(Relaxation3 {
        lambda,
        x: xm,
        dual_objective,
        primal_objective,
        status: format!("{status:?}"),
        iterations: solver.solution.iterations,
    })
}
