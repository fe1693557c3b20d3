//! The reduced dual SDP (31) with clarabel, on the real embedding of the Hermitian PSD cone.
//!
//! clarabel only has the real symmetric PSD cone, so the complex constraint is embedded with
//!
//! ```text
//! E(H) = [ Re H  -Im H ]        H ⪰ 0  ⟺  E(H) ⪰ 0   (E(H) [a; b] = [Re(Hv); Im(Hv)], v = a + ib)
//!        [ Im H   Re H ]
//! ```
//!
//! (2n x 2n, every eigenvalue of H twice, the paper's Prop. 7 for W). In clarabel's standard form
//! `min qᵀx s.t. b − A x ∈ K` the problem is
//!
//! ```text
//! x = λ ∈ ℝⁿ,  q = −1,  b − A λ = svec E(M − diag λ) ∈ PSD(2n)
//! ```
//!
//! with `b = svec E(M)` and the column of λ_i holding 1 at the diagonal entries (i, i) and
//! (n+i, n+i) of the embedding. `svec` is clarabel's `PSDTriangleConeT` layout: the upper triangle
//! by columns, off-diagonal entries times √2, so that svec(P)ᵀ svec(Q) = ⟨P, Q⟩.
//!
//! # Recovering the primal X* from clarabel's dual variable
//!
//! clarabel's dual is `max −bᵀz s.t. Aᵀz = −q = 1, z ∈ PSD(2n)`. With `z = svec Z` and Z split
//! into n x n blocks `Z = [[A, B], [C, D]]` (C = Bᵀ), the constraint reads `A_ii + D_ii = 1` and
//! the objective is `−⟨E(M), Z⟩`. Expanding the inner product block by block,
//!
//! ```text
//! ⟨E(M), Z⟩ = ⟨Re M, A⟩ − ⟨Im M, B⟩ + ⟨Im M, C⟩ + ⟨Re M, D⟩ = ⟨Re M, A + D⟩ + ⟨Im M, C − B⟩,
//! ```
//!
//! and for Hermitian M and X, Tr(M X) = ⟨Re M, Re X⟩ + ⟨Im M, Im X⟩. So the adjoint of the
//! embedding,
//!
//! ```text
//! X = E*(Z) = (A + D) + i (C − B),
//! ```
//!
//! maps clarabel's dual to the primal (37) reduced: X is Hermitian (A + D symmetric, C − B
//! antisymmetric, so Im X_ii = 0), X_ii = A_ii + D_ii = 1 where clarabel's equality holds,
//! Tr(M X) = ⟨E(M), Z⟩ is clarabel's dual objective up to sign, and X ⪰ 0 because
//! v^H X v = ⟨E(v v^H), Z⟩ with E(v v^H) = u uᵀ + w wᵀ ⪰ 0 (u = [a; b], w = [−b; a]). This is
//! twice the "average of the blocks" (A + D)/2 + i (C − B)/2: the embedding doubles every
//! eigenvalue (Tr E(H) = 2 Tr H), and the J-symmetric optimum Z = E(X)/2 has that average as
//! X/2 (a J-symmetric Z has A = D and C = −B, so X = 2A + 2iC).
//!
//! # Feasibility
//!
//! clarabel's λ and X satisfy the constraints to its tolerances only. Before returning, the
//! pair is made exactly feasible, so that both objectives are bounds as for [`super::ipm`]:
//! X is rescaled to a unit diagonal, X ← D^{-1/2} X D^{-1/2} with D = Diag(X) (still ⪰ 0), and
//! λ is shifted by the smallest eigenvalue of M − diag(λ) when that is negative (faer's dense
//! Hermitian eigenvalues, sequential). Then `dual_objective` = Σ λ_i ≤ d* = s* ≤ Tr(M X*) =
//! `primal_objective`, to rounding, and their difference is a certified gap.
//!
//! # Settings and accuracy
//!
//! Measured on random pose-graph matrices (n = 5..40, rotation noise 0.01..1, 2 cores):
//! - M is divided by max |M_ij| before the solve (λ scales back, X does not change). Unscaled,
//!   the faer LDL ended `AlmostSolved` with relative gaps up to 3e-5 on a third of the
//!   problems and once `InsufficientProgress`; scaled, all were `Solved`.
//! - Chordal decomposition off: the embedding always has structural zeros (the diagonal of
//!   Im M), so clarabel decomposes even a dense M into many overlapping cliques (with merging
//!   "none", n = 25 took 22 s, n = 30 failed after 80 s). A reduced M of a connected graph is
//!   dense anyway.
//! - KKT solver "auto", which with clarabel's `faer-sparse` feature (enabled by `clarabel-sdp`)
//!   picks faer's supernodal LDL for these dense KKT systems (a dense block of size n(2n + 1),
//!   the PSD cone's scaling, so O(n⁶) per solve): n = 20 about 0.3 s, 30 about 2.5 s, 40 about
//!   10 s; QDLDL took 2 s, 25-35 s and 200 s. One thread (`max_threads = 1`): the result is
//!   then the same whatever the machine, and two threads gained only about 15 %.
//! - clarabel's default tolerances (1e-8, absolute or relative): d* agreed with [`super::ipm`]
//!   to 1.4e-7 relative, the certified gap above was at most 4e-6 relative, and λ* agreed only
//!   to about 1e-3 of max(1, max |λ_i|): along the optimal face, Σ λ moves only to second
//!   order when λ does, so λ is determined to about the square root of the gap. Tighter
//!   tolerances end `AlmostSolved` without improving this.
//!
//! Accepted statuses are `Solved` and `AlmostSolved` (clarabel's reduced tolerances, which
//! docs/method.md §3.1 notes on embedded complex problems); any other status is an [`SdpError::Solver`].
//! For anything but small graphs, and for accurate λ*, use [`super::ipm`].

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{Mat, MatRef, Par, c64};

use super::sdp::{DualSolution, SdpError};

/// Index of entry (row, col), row ≤ col, in clarabel's `PSDTriangleConeT` vector (upper triangle
/// by columns).
fn triangle_index(row: usize, col: usize) -> usize {
    debug_assert!(row <= col);
    col * (col + 1) / 2 + row
}

/// Entry (r, c) of E(H) for the n x n Hermitian H given by `h`.
fn embedded(h: impl Fn(usize, usize) -> c64, n: usize, r: usize, c: usize) -> f64 {
    let v = h(r % n, c % n);
    match (r < n, c < n) {
        (true, true) | (false, false) => v.re,
        (true, false) => -v.im,
        (false, true) => v.im,
    }
}

/// Whether `m` is square, finite and Hermitian to rounding (relative to its largest entry).
fn is_hermitian(m: MatRef<'_, c64>) -> bool {
    let n = m.nrows();
    if m.ncols() != n {
        return false;
    }
    let mut scale = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let v = m[(i, j)];
            if !v.re.is_finite() || !v.im.is_finite() {
                return false;
            }
            scale = scale.max(v.norm());
        }
    }
    let tol = 1e-9 * scale.max(f64::MIN_POSITIVE);
    (0..n).all(|j| (0..=j).all(|i| (m[(i, j)] - m[(j, i)].conj()).norm() <= tol))
}

/// The smallest eigenvalue of the Hermitian `h` (lower triangle), computed sequentially so
/// that the result does not depend on faer's global parallelism.
fn smallest_eigenvalue(h: MatRef<'_, c64>) -> Result<f64, SdpError> {
    let n = h.nrows();
    let mut eigenvalues = Diag::<c64>::zeros(n);
    let scratch = evd::self_adjoint_evd_scratch::<c64>(
        n,
        ComputeEigenvectors::No,
        Par::Seq,
        Default::default(),
    );
    evd::self_adjoint_evd(
        h,
        eigenvalues.as_mut(),
        None,
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|e| SdpError::Solver(format!("eigenvalues of M − diag(λ): {e:?}")))?;
    Ok(eigenvalues
        .column_vector()
        .iter()
        .map(|v| v.re)
        .fold(f64::INFINITY, f64::min))
}

/// Solves the reduced dual SDP d* = max Σ λ_i s.t. M − diag(λ) ⪰ 0 (the paper's (31) with the
/// positions eliminated, see [`crate::dual::sdp`]) with clarabel, and recovers the primal (37)
/// X* (Hermitian, PSD, unit diagonal) from clarabel's dual variable; see the module docs for
/// the embedding and the derivation.
///
/// The returned pair is feasible (see "Feasibility" in the module docs): M − diag(λ*) ⪰ 0 and
/// X* ⪰ 0 with a unit diagonal, so `dual_objective` = Σ λ*_i ≤ d* ≤ `primal_objective` =
/// Tr(M X*). Deterministic (one thread).
///
/// # Errors
///
/// [`SdpError::InvalidInput`] if `m` is not square, not finite, or not Hermitian within
/// rounding (|M_ij − conj(M_ji)| ≤ 1e-9 max |M|; the Hermitian part is what is solved);
/// [`SdpError::Solver`] if clarabel ends with a status other than `Solved` or `AlmostSolved`
/// (the message names it) or returns an inconsistent X.
pub fn solve(m: MatRef<'_, c64>) -> Result<DualSolution, SdpError> {
    if !is_hermitian(m) {
        return Err(SdpError::InvalidInput);
    }
    let n = m.nrows();
    if n == 0 {
        return Ok(DualSolution {
            lambda: Vec::new(),
            x: Mat::zeros(0, 0),
            dual_objective: 0.0,
            primal_objective: 0.0,
            iterations: 0,
            solver: "clarabel",
            converged: true,
        });
    }
    let herm = |i: usize, j: usize| (m[(i, j)] + m[(j, i)].conj()) * 0.5;
    // clarabel solves for M / scale (entries of order one; λ scales back linearly, X does not
    // change).
    let scale = (0..n)
        .flat_map(|j| (0..n).map(move |i| m[(i, j)].norm()))
        .fold(0.0, f64::max);
    let scale = if scale > 0.0 { scale } else { 1.0 };

    let dim = 2 * n;
    let sqrt2 = std::f64::consts::SQRT_2;
    let mut b = vec![0.0; dim * (dim + 1) / 2];
    for c in 0..dim {
        for r in 0..=c {
            let svec_factor = if r == c { 1.0 } else { sqrt2 };
            b[triangle_index(r, c)] = svec_factor * embedded(herm, n, r, c) / scale;
        }
    }
    // Column i of A: svec E(e_i e_iᵀ), i.e. 1 at the diagonal entries (i, i) and (n+i, n+i).
    let colptr = (0..=n).map(|i| 2 * i).collect();
    let rowval = (0..n)
        .flat_map(|i| [triangle_index(i, i), triangle_index(n + i, n + i)])
        .collect();
    let a = CscMatrix::new(b.len(), n, colptr, rowval, vec![1.0; 2 * n]);
    let p = CscMatrix::zeros((n, n));
    let q = vec![-1.0; n];
    let cones = [SupportedConeT::PSDTriangleConeT(dim)];

    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .chordal_decomposition_enable(false)
        .direct_solve_method("auto".to_string())
        .max_threads(1)
        .build()
        .map_err(|e| SdpError::Solver(format!("clarabel settings: {e}")))?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
        .map_err(|e| SdpError::Solver(format!("clarabel: {e}")))?;
    solver.solve();
    let solution = &solver.solution;
    match solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        status => return Err(SdpError::Solver(format!("clarabel status {status:?}"))),
    }

    // X = E*(Z) = (A + D) + i (C − B) from z = svec Z, Z = [[A, B], [C, D]].
    let z = &solution.z;
    let zt = |r: usize, c: usize| {
        let (r, c) = if r <= c { (r, c) } else { (c, r) };
        let v = z[triangle_index(r, c)];
        if r == c { v } else { v / sqrt2 }
    };
    let x = Mat::from_fn(n, n, |k, l| {
        c64::new(zt(k, l) + zt(n + k, n + l), zt(n + k, l) - zt(k, n + l))
    });
    // Make the pair exactly feasible (see "Feasibility" in the module docs).
    let d: Vec<f64> = (0..n).map(|i| x[(i, i)].re).collect();
    if d.iter().any(|&di| !(di > 0.5 && di < 2.0)) {
        return Err(SdpError::Solver(format!(
            "clarabel returned diag(X) far from 1: {d:?}"
        )));
    }
    let x = Mat::from_fn(n, n, |k, l| {
        if k == l {
            c64::new(1.0, 0.0)
        } else {
            x[(k, l)] / (d[k] * d[l]).sqrt()
        }
    });
    let mut lambda: Vec<f64> = solution.x.iter().map(|l| l * scale).collect();
    let slack = Mat::from_fn(n, n, |i, j| {
        if i == j {
            herm(i, i) - c64::new(lambda[i], 0.0)
        } else {
            herm(i, j)
        }
    });
    let smallest = smallest_eigenvalue(slack.as_ref())?;
    if smallest < 0.0 {
        lambda.iter_mut().for_each(|l| *l += smallest);
    }

    let dual_objective = lambda.iter().sum();
    let primal_objective = (0..n)
        .flat_map(|k| (0..n).map(move |l| (k, l)))
        .map(|(k, l)| (herm(k, l) * x[(l, k)]).re)
        .sum();
    Ok(DualSolution {
        lambda,
        x,
        dual_objective,
        primal_objective,
        iterations: solution.iterations as usize,
        solver: "clarabel",
        converged: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Side;
    use faer::prelude::Solve;

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
        /// Uniform in [0, 1).
        fn uniform(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
        }
        /// Standard normal (Box-Muller).
        fn normal(&mut self) -> f64 {
            let u = 1.0 - self.uniform();
            let v = self.uniform();
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        }
    }

    fn random_hermitian(n: usize, rng: &mut Rng) -> Mat<c64> {
        let g = Mat::from_fn(n, n, |_, _| c64::new(rng.normal(), rng.normal()));
        Mat::from_fn(n, n, |i, j| (g[(i, j)] + g[(j, i)].conj()) * 0.5)
    }

    /// The rotation matrix M = Q − S^H L⁻¹ S of a random planar pose graph with n poses (a
    /// spanning path plus loop closures, unit weights, noisy measurements; pose 1 anchored).
    fn pose_graph_m(n: usize, sigma: f64, rng: &mut Rng) -> Mat<c64> {
        let theta: Vec<f64> = (0..n)
            .map(|_| std::f64::consts::TAU * rng.uniform())
            .collect();
        let p: Vec<c64> = (0..n)
            .map(|_| c64::new(10.0 * rng.uniform(), 10.0 * rng.uniform()))
            .collect();
        let mut edges: Vec<(usize, usize)> = (1..n).map(|j| (j - 1, j)).collect();
        for i in 0..n {
            for j in i + 2..n {
                if rng.uniform() < 0.2 {
                    edges.push((i, j));
                }
            }
        }
        // Unknowns [p_1..p_n, r_1..r_n]; each residual is a linear form cᵀx, W += conj(c) cᵀ.
        let mut w = Mat::<c64>::zeros(2 * n, 2 * n);
        let mut add = |terms: &[(usize, c64)]| {
            for &(a, ca) in terms {
                for &(b, cb) in terms {
                    w[(a, b)] += ca.conj() * cb;
                }
            }
        };
        for &(i, j) in &edges {
            let ri = c64::cis(theta[i]);
            let delta =
                (p[j] - p[i]) * ri.conj() + c64::new(sigma * rng.normal(), sigma * rng.normal());
            let rot = c64::cis(theta[j] - theta[i] + sigma * rng.normal());
            let one = c64::new(1.0, 0.0);
            add(&[(j, one), (i, -one), (n + i, -delta)]);
            add(&[(n + j, one), (n + i, -rot)]);
        }
        let l = Mat::from_fn(n - 1, n - 1, |a, b| w[(1 + a, 1 + b)]);
        let s = Mat::from_fn(n - 1, n, |a, b| w[(1 + a, n + b)]);
        let q = Mat::from_fn(n, n, |a, b| w[(n + a, n + b)]);
        let linv_s = l
            .llt(Side::Lower)
            .expect("connected graph: L ≻ 0")
            .solve(&s);
        let m = &q - s.adjoint() * &linv_s;
        Mat::from_fn(n, n, |i, j| (m[(i, j)] + m[(j, i)].conj()) * 0.5)
    }

    fn min_eigenvalue(h: &Mat<c64>) -> f64 {
        h.self_adjoint_eigenvalues(Side::Lower).unwrap()[0]
    }

    fn max_abs(h: &Mat<c64>) -> f64 {
        let mut s = 0.0f64;
        for j in 0..h.ncols() {
            for i in 0..h.nrows() {
                s = s.max(h[(i, j)].norm());
            }
        }
        s
    }

    /// Checks that the pair is feasible (M − diag(λ) ⪰ 0, X ⪰ 0 with a unit diagonal, to
    /// rounding) and that the certified gap Tr(M X) − Σ λ is in [0, tol max(1, |d|)].
    fn check(m: &Mat<c64>, sol: &DualSolution, tol: f64) {
        let n = m.nrows();
        let rounding = 1e-12 * max_abs(m).max(1.0) * n as f64;
        let z = Mat::from_fn(n, n, |i, j| {
            let shift = if i == j { sol.lambda[i] } else { 0.0 };
            m[(i, j)] - c64::new(shift, 0.0)
        });
        let z_min = min_eigenvalue(&z);
        assert!(z_min >= -rounding, "M − diag(λ) not PSD: {z_min}");
        for i in 0..n {
            assert_eq!(sol.x[(i, i)], c64::new(1.0, 0.0));
        }
        let x_min = min_eigenvalue(&sol.x);
        assert!(x_min >= -1e-9, "X not PSD: {x_min}");
        let trace_mx: f64 = (0..n)
            .flat_map(|k| (0..n).map(move |l| (k, l)))
            .map(|(k, l)| (m[(k, l)] * sol.x[(l, k)]).re)
            .sum();
        assert!((trace_mx - sol.primal_objective).abs() <= rounding);
        let sum: f64 = sol.lambda.iter().sum();
        assert!((sum - sol.dual_objective).abs() <= rounding);
        let gap = sol.primal_objective - sol.dual_objective;
        let den = sol.dual_objective.abs().max(1.0);
        assert!(gap >= -rounding && gap <= tol * den, "gap {gap}");
        assert_eq!(sol.solver, "clarabel");
    }

    #[test]
    fn diagonal_matrix_gives_its_diagonal() {
        let d = [3.0, -1.5, 0.25, 7.0];
        let m = Mat::from_fn(4, 4, |i, j| c64::new(if i == j { d[i] } else { 0.0 }, 0.0));
        let sol = solve(m.as_ref()).unwrap();
        for (l, d) in sol.lambda.iter().zip(d) {
            assert!((l - d).abs() < 1e-6, "λ = {l}, expected {d}");
        }
        check(&m, &sol, 1e-6);
    }

    #[test]
    fn two_by_two_closed_form() {
        // M = [[a, b], [conj b, c]]: d* = a + c − 2|b| (λ = (a − |b|, c − |b|)).
        for &(a, b, c) in &[
            (2.0, c64::new(0.6, -0.8), 5.0),
            (-1.0, c64::new(0.0, 3.0), 0.5),
        ] {
            let m = Mat::from_fn(2, 2, |i, j| match (i, j) {
                (0, 0) => c64::new(a, 0.0),
                (1, 1) => c64::new(c, 0.0),
                (0, 1) => b,
                _ => b.conj(),
            });
            let sol = solve(m.as_ref()).unwrap();
            let expected = a + c - 2.0 * b.norm();
            assert!(
                (sol.dual_objective - expected).abs() < 1e-6,
                "{} vs {expected}",
                sol.dual_objective
            );
            assert!((sol.lambda[0] - (a - b.norm())).abs() < 1e-5);
            assert!((sol.lambda[1] - (c - b.norm())).abs() < 1e-5);
            check(&m, &sol, 1e-6);
            // X* = [[1, −b/|b|], [−conj b/|b|, 1]]: rank one, Tr(M X*) = a + c − 2|b|.
            assert!(
                (sol.x[(0, 1)] + b / b.norm()).norm() < 1e-4,
                "X_01 = {}",
                sol.x[(0, 1)]
            );
        }
    }

    #[test]
    fn random_hermitian_is_certified() {
        let mut rng = Rng(7);
        for n in [1, 2, 3, 8, 15] {
            let m = random_hermitian(n, &mut rng);
            let sol = solve(m.as_ref()).unwrap();
            check(&m, &sol, 1e-6);
        }
    }

    #[test]
    fn pose_graph_matrix_is_certified() {
        let mut rng = Rng(11);
        for n in [5, 12, 25] {
            let m = pose_graph_m(n, 0.1, &mut rng);
            let sol = solve(m.as_ref()).unwrap();
            check(&m, &sol, 1e-5);
        }
    }

    #[test]
    fn agrees_with_the_interior_point_method() {
        use crate::dual::ipm::{IpmOptions, solve as ipm_solve};
        let mut rng = Rng(23);
        let cases = [
            (5, 0.1),
            (6, 1.0),
            (8, 0.5),
            (10, 0.01),
            (12, 0.05),
            (16, 0.2),
            (20, 0.1),
            (30, 0.1),
        ];
        for (n, sigma) in cases {
            let m = pose_graph_m(n, sigma, &mut rng);
            let ours = solve(m.as_ref()).unwrap();
            let ipm = ipm_solve(m.as_ref(), &IpmOptions::default()).unwrap();
            let d = ipm.dual_objective;
            let den = d.abs().max(1.0);
            assert!(
                (ours.dual_objective - d).abs() <= 1e-6 * den,
                "n = {n}: d* clarabel {} vs ipm {d}",
                ours.dual_objective
            );
            // Both pairs are feasible, so each dual objective bounds the other's primal.
            let rounding = 1e-12 * max_abs(&m).max(1.0) * n as f64;
            assert!(ours.dual_objective <= ipm.primal_objective + rounding);
            assert!(ipm.dual_objective <= ours.primal_objective + rounding);
            // λ* itself only to about the square root of clarabel's gap (module docs,
            // "Settings and accuracy"): ≤ 1.4e-3 of max(1, max |λ_i|) over 40 such problems.
            let lambda_scale = ipm.lambda.iter().fold(1.0f64, |s, l| s.max(l.abs()));
            for (i, (a, b)) in ours.lambda.iter().zip(&ipm.lambda).enumerate() {
                assert!(
                    (a - b).abs() <= 5e-3 * lambda_scale,
                    "n = {n}: λ_{i} {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn rejects_invalid_input() {
        let not_square = Mat::<c64>::zeros(2, 3);
        assert_eq!(
            solve(not_square.as_ref()).unwrap_err(),
            SdpError::InvalidInput
        );
        let mut not_hermitian = Mat::<c64>::identity(2, 2);
        not_hermitian[(0, 1)] = c64::new(1.0, 0.0);
        assert_eq!(
            solve(not_hermitian.as_ref()).unwrap_err(),
            SdpError::InvalidInput
        );
        let mut nan = Mat::<c64>::identity(2, 2);
        nan[(1, 1)] = c64::new(f64::NAN, 0.0);
        assert_eq!(solve(nan.as_ref()).unwrap_err(), SdpError::InvalidInput);
        let empty = solve(Mat::<c64>::zeros(0, 0).as_ref()).unwrap();
        assert!(empty.lambda.is_empty() && empty.dual_objective == 0.0);
    }
}
