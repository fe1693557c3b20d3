//! A primal-dual interior-point method for the reduced dual SDP (31) and its primal (37).
//!
//! With positions eliminated (see the [module docs](super)), the pair of SDPs is the complex
//! analogue of the max-cut SDP, on the n x n Hermitian rotation-only matrix M:
//!
//! ```text
//! s* = min Tr(M X)  s.t.  X_ii = 1 (i = 1..n),  X ⪰ 0 Hermitian       (primal, (36)/(37))
//! d* = max Σ_i y_i  s.t.  Z = M − Diag(y) ⪰ 0,  y ∈ ℝⁿ                  (dual, (31))
//! ```
//!
//! Proposition 8 of the paper: each is the Lagrangian dual of the other and, since both are
//! strictly feasible (X = I; y_i small enough), strong duality holds, s* = d*. For any feasible
//! pair, Tr(M X) − Σ y_i = Tr(Z X) + Σ y_i (X_ii − 1) = Tr(Z X) ≥ 0 (weak duality), and the pair
//! is optimal iff the complementarity Z X = 0 holds. The solver returns λ* = y (the multipliers
//! of (31)) and X* (the solution of (37)).
//!
//! # Method
//!
//! The HRVW/KSH/M ("HKM") search direction of Helmberg, Rendl, Vanderbei and Wolkowicz, with
//! Mehrotra's predictor-corrector, as SDPT3 implements it for max-cut, written here for Hermitian
//! matrices. Every iterate keeps X ≻ 0 and Z = M − Diag(y) ≻ 0 (Z is recomputed from y, so dual
//! feasibility holds exactly; diag(X) = 1 holds from the start X = I up to rounding, which each
//! Newton step corrects), and follows the central path X Z = μ I, μ = Tr(X Z)/n → 0.
//!
//! ## The Newton system
//!
//! Dual feasibility fixes ΔZ = −Diag(Δy) =: −D. Linearizing (X + ΔX)(Z + ΔZ) = σμ I, with the
//! product ΔX ΔZ either dropped (predictor, σ = 0) or replaced by its predicted value
//! ΔX_a ΔZ_a (corrector), and multiplying by G := Z⁻¹ on the right:
//!
//! ```text
//! ΔX̂ = σμ G − X − X ΔZ G − ΔX_a ΔZ_a G = σμ G − X + X D G + ΔX_a D_a G.
//! ```
//!
//! ΔX̂ is not Hermitian; the HKM direction is its Hermitian part ΔX = (ΔX̂ + ΔX̂ᴴ)/2. For
//! Hermitian A, B and real diagonal D, the diagonal of the Hermitian part of A D B is
//!
//! ```text
//! [(A D B + B D A)/2]_ii = Re Σ_k A_ik d_k B_ki = Σ_k Re(A_ik · conj(B_ik)) d_k,
//! ```
//!
//! because B_ki = conj(B_ik) and (B D A)_ii = conj((A D B)_ii). Writing
//! H := Re(G ∘ conj(X)) (∘ the entrywise product; H is real symmetric), the primal feasibility
//! of the new point, diag(X + ΔX) = 1, i.e. diag(ΔX) = 1 − diag(X), reads
//!
//! ```text
//! diag(X) + σμ diag(G) − diag(X) + H Δy + c = 1,   c := Re(ΔX_a ∘ conj(G)) Δy_a,
//! ⇒  H Δy = 1 − σμ diag(G) − c                      (c = 0 in the predictor).
//! ```
//!
//! diag(X) cancels, so the same equation also restores feasibility if rounding moved
//! diag(X) away from 1. H is positive definite: G ∘ conj(X) is Hermitian positive definite by
//! the Schur product theorem (G ≻ 0, conj(X) ≻ 0), and for real v, vᵀ (G ∘ conj X) v =
//! vᵀ H v since the imaginary part is antisymmetric. So Δy comes from one n x n real Cholesky
//! factorization per iteration (shared by predictor and corrector), then
//! ΔX = σμ G − X + herm((X D + ΔX_a D_a) G), ΔZ = −Diag(Δy).
//!
//! ## Step lengths and centering
//!
//! With X = L Lᴴ, X + α ΔX ≻ 0 iff I + α L⁻¹ ΔX L⁻ᴴ ≻ 0, so the largest step is
//! −1/λ_min(L⁻¹ ΔX L⁻ᴴ) (unbounded if λ_min ≥ 0); likewise for Z with its Cholesky factor
//! (Z = L_Z L_Zᴴ, and K := L_Z⁻¹ also gives G = Kᴴ K). The predictor's steps α_a give
//! μ_a = Tr((X + α_a ΔX_a)(Z + α_a ΔZ_a))/n and the centering σ = (μ_a/μ)³; the corrector steps
//! are min(1, γ α_max) with γ = 0.9 + 0.09 min(α_a) as in SDPT3, separately in the primal and
//! the dual.
//!
//! ## Polishing
//!
//! Near the optimum X has eigenvalues of order one (its range, the null space of Z*) and of
//! order μ, and the latter reach rounding level before the gap reaches 1e-10 when |d*| is much
//! smaller than the entries of M (pose graphs with small noise). So once the gap is within
//! 1e5 times the tolerance, or has not halved for 3 iterations, each iteration also tries two
//! rounded points, which are feasible by construction and can only improve the bounds:
//! - primal: X truncated to its dominant eigenvalues (λ_k > τ λ_max, a few τ) and rescaled,
//!   X̂ = D^{-1/2} X_r D^{-1/2} with D = Diag(X_r), which is positive semidefinite with a unit
//!   diagonal;
//! - dual: complementarity Z X̂ = 0 on the diagonal gives y_i = Re((M X̂)_ii) (for rank one,
//!   X̂ = r rᴴ, this is the certificate λ_i = Re(conj(r_i) (M r)_i)), so Σ y = Tr(M X̂); then
//!   y − η 1 with η ≥ −λ_min(M − Diag(y)) is dual feasible (checked by a Cholesky
//!   factorization). To first order n η = Tr(M X̂) − d*, so the bound Σ y − n η falls short
//!   of d* only by a term of second order in the error of X̂.
//!
//! ## Stopping
//!
//! The relative duality gap |p − d| / max(1, |d|) ≤ `tolerance`, where d = Σ y over the best
//! dual feasible y found and p = Tr(M X̂) over the best unit-diagonal X̂ found (the iterate
//! rescaled to diag(X̂) = 1, or a polished point). The returned pair is that one: X* has an
//! exactly unit diagonal, λ* makes M − Diag(λ*) positive definite to a Cholesky factorization,
//! and `primal_objective − dual_objective` is the gap that was certified.
//!
//! ## Accuracy
//!
//! Z and X are stored in double precision, so their small eigenvalues, hence the gap, cannot
//! be resolved much below about 1e-14 max|M_ij| (and M = Q − Sᴴ L⁻¹ S itself carries rounding
//! errors of the size of eps |Q|). With the denominator max(1, |d|), a tolerance of 1e-10 is
//! reachable when max|M_ij| / max(1, |d*|) is below about 1e3-1e4; beyond that (long
//! translations relative to the noise, so d* ≪ max|M_ij|) the iteration stops making
//! progress and [`SdpError::NotConverged`] reports the gap reached, once neither the gap nor μ
//! has halved for 20 iterations (rather than running to `max_iterations`).
//!
//! ## Cost
//!
//! O(n³) per iteration with about a dozen n x n matrices allocated once per solve: Cholesky of
//! Z and of X, the triangular inverse K and G = Kᴴ K, the real Cholesky of H, two products
//! (·)G, and four smallest-eigenvalue computations (one per step length), plus an
//! eigendecomposition per polishing attempt. Typically 10-30 iterations.

use super::sdp::{DualSolution, SdpError};
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::{factor as llt_factor, solve as llt_solve};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::linalg::matmul::{self, triangular as tri_matmul, triangular::BlockStructure};
use faer::linalg::{triangular_inverse, triangular_solve};
use faer::{Accum, Mat, MatRef, Par, c64};

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IpmOptions {
    /// Stop when the relative duality gap |Tr(M X) − Σ y| / max(1, |Σ y|) is at most this.
    pub tolerance: f64,
    /// Give up ([`SdpError::NotConverged`]) after this many Newton steps.
    pub max_iterations: usize,
}

impl Default for IpmOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 100,
        }
    }
}

/// |M_ij − conj(M_ji)| allowed by the input check, relative to max |M_ij|.
const HERMITIAN_TOLERANCE: f64 = 1e-9;

/// Polishing starts once the gap is below this multiple of the tolerance.
const POLISH_FROM: f64 = 1e5;

/// Polishing is also tried when the gap (below one) has not halved for this many iterations.
const POLISH_WHEN_SLOW: usize = 3;

/// Give up when, with the gap below one, neither the gap nor μ has halved for this many
/// iterations: the gap is then at the rounding floor (see "Accuracy" in the module docs).
const STALL_ITERATIONS: usize = 20;

/// Relative eigenvalue thresholds τ tried when truncating X.
const TRUNCATION_THRESHOLDS: [f64; 3] = [1e-3, 1e-6, 1e-9];

/// Solves the reduced dual SDP (31) and its primal (37) for the Hermitian matrix `m`.
///
/// Returns λ* = y (one multiplier per rotation), X* (unit diagonal, positive semidefinite), and
/// the objectives d* = Σ λ_i and s* = Tr(M X*), which agree to the requested relative gap
/// (strong duality, Prop. 8). Runs sequentially (`Par::Seq`): deterministic, and on the
/// 2-core machine it was measured on, faer's threads did not help even at n = 500 (faer is
/// built without them, Cargo.toml).
///
/// # Errors
///
/// [`SdpError::InvalidInput`] if `m` is not square, not finite, or not Hermitian within
/// rounding (|M_ij − conj(M_ji)| ≤ 1e-9 max |M|; the Hermitian part is what is solved);
/// [`SdpError::NotConverged`] if the gap is not reached in `max_iterations` steps or the
/// iteration stalls (see "Accuracy" in the module docs); [`SdpError::Solver`] if an
/// eigenvalue computation fails or the starting point is not dual feasible (not expected).
pub fn solve(m: MatRef<'_, c64>, options: &IpmOptions) -> Result<DualSolution, SdpError> {
    let n = m.nrows();
    let scale = validate(m)?;
    // Solve for M / scale: the iterates are then of order one. X is unchanged and y scales back
    // linearly.
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let ms = Mat::from_fn(n, n, |i, j| (m[(i, j)] + m[(j, i)].conj()) * (0.5 / scale));
    let mut ipm = Ipm::new(ms);
    let iterations = ipm.run(options, scale)?;
    Ok(ipm.into_solution(m, scale, iterations, true))
}

/// [`solve`], except that when the gap is not reached ([`SdpError::NotConverged`]) the last
/// iterate is returned, with `converged: false`: its y keeps Z = M − Diag(y) ≻ 0 at every step,
/// so it is dual feasible and still proves a lower bound (checked again, rounding included, by
/// [`crate::certify::dual_bound`]); only the gap to the optimum is larger. Badly scaled graphs
/// (translations of 1e6 m against unit rotations) can stall above every tolerance.
pub fn solve_best_effort(
    m: MatRef<'_, c64>,
    options: &IpmOptions,
) -> Result<DualSolution, SdpError> {
    let n = m.nrows();
    let scale = validate(m)?;
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let ms = Mat::from_fn(n, n, |i, j| (m[(i, j)] + m[(j, i)].conj()) * (0.5 / scale));
    let mut ipm = Ipm::new(ms);
    match ipm.run(options, scale) {
        Ok(iterations) => Ok(ipm.into_solution(m, scale, iterations, true)),
        Err(SdpError::NotConverged { iterations, .. }) => {
            Ok(ipm.into_solution(m, scale, iterations, false))
        }
        Err(e) => Err(e),
    }
}

/// Checks that `m` is square, finite and Hermitian within rounding; returns max |M_ij|.
fn validate(m: MatRef<'_, c64>) -> Result<f64, SdpError> {
    let n = m.nrows();
    if m.ncols() != n {
        return Err(SdpError::InvalidInput);
    }
    let mut scale = 0.0_f64;
    for j in 0..n {
        for i in 0..n {
            let v = m[(i, j)];
            if !(v.re.is_finite() && v.im.is_finite()) {
                return Err(SdpError::InvalidInput);
            }
            scale = scale.max(v.norm());
        }
    }
    for j in 0..n {
        for i in j..n {
            if (m[(i, j)] - m[(j, i)].conj()).norm() > HERMITIAN_TOLERANCE * scale {
                return Err(SdpError::InvalidInput);
            }
        }
    }
    Ok(scale)
}

/// The iterates and the workspace of one solve (all n x n unless noted).
struct Ipm {
    n: usize,
    /// M / scale, Hermitian (both triangles).
    m: Mat<c64>,
    /// Primal iterate X ≻ 0, both triangles.
    x: Mat<c64>,
    /// Cholesky factor of X (lower triangle).
    lx: Mat<c64>,
    /// Dual iterate y (Z = M − Diag(y) ≻ 0).
    y: Vec<f64>,
    /// Cholesky factor of Z (lower triangle).
    lz: Mat<c64>,
    /// K = L_Z⁻¹ (lower triangle).
    k: Mat<c64>,
    /// G = Z⁻¹ = Kᴴ K, both triangles.
    g: Mat<c64>,
    /// H = Re(G ∘ conj X), then its Cholesky factor.
    h: Mat<f64>,
    /// Predictor direction ΔX_a, Δy_a.
    dx_a: Mat<c64>,
    dy_a: Vec<f64>,
    /// Corrector direction ΔX, Δy.
    dx: Mat<c64>,
    dy: Vec<f64>,
    /// Temporaries.
    t1: Mat<c64>,
    t2: Mat<c64>,
    rhs: Mat<f64>,
    eigenvalues: Diag<c64>,
    /// The best polished primal point: Tr(M X̂) and X̂ (unit diagonal).
    polished_x: Option<(f64, Mat<c64>)>,
    /// The best polished dual point: Σ y and y.
    polished_y: Option<(f64, Vec<f64>)>,
    mem: MemBuffer,
}

impl Ipm {
    /// The strictly feasible start: X = I and y_i = M_ii − Σ_{j≠i} |M_ij| − 1, so that
    /// Z = M − Diag(y) is strictly diagonally dominant with a unit margin, hence Z ≻ 0
    /// (Gershgorin).
    fn new(m: Mat<c64>) -> Self {
        let n = m.nrows();
        let y = (0..n)
            .map(|i| {
                let off: f64 = (0..n).filter(|&j| j != i).map(|j| m[(i, j)].norm()).sum();
                m[(i, i)].re - off - 1.0
            })
            .collect();
        let stack = StackReq::any_of(&[
            llt_factor::cholesky_in_place_scratch::<c64>(n, Par::Seq, Default::default()),
            llt_factor::cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default()),
            llt_solve::solve_in_place_scratch::<f64>(n, 1, Par::Seq),
            // At least 1: faer 0.24 sizes its Householder scratch by n − 1.
            evd::self_adjoint_evd_scratch::<c64>(
                n.max(1),
                ComputeEigenvectors::Yes,
                Par::Seq,
                Default::default(),
            ),
        ]);
        let zeros = || Mat::<c64>::zeros(n, n);
        Self {
            n,
            m,
            x: Mat::identity(n, n),
            lx: Mat::identity(n, n),
            y,
            lz: zeros(),
            k: zeros(),
            g: zeros(),
            h: Mat::zeros(n, n),
            dx_a: zeros(),
            dy_a: vec![0.0; n],
            dx: zeros(),
            dy: vec![0.0; n],
            t1: zeros(),
            t2: zeros(),
            rhs: Mat::zeros(n, 1),
            eigenvalues: Diag::zeros(n),
            polished_x: None,
            polished_y: None,
            mem: MemBuffer::new(stack),
        }
    }

    /// The best bounds found so far (in units of M / scale): the smallest Tr(M X̂) over
    /// unit-diagonal X̂ and the largest Σ y over dual feasible y.
    fn bounds(&self) -> (f64, f64) {
        let primal = unit_diagonal_objective(self.m.as_ref(), self.x.as_ref());
        let dual: f64 = self.y.iter().sum();
        (
            self.polished_x.as_ref().map_or(primal, |p| p.0.min(primal)),
            self.polished_y.as_ref().map_or(dual, |d| d.0.max(dual)),
        )
    }

    /// Runs the predictor-corrector iteration; returns the number of Newton steps taken.
    fn run(&mut self, options: &IpmOptions, scale: f64) -> Result<usize, SdpError> {
        if !factor_dual(&self.m, &self.y, &mut self.lz, &mut self.mem) {
            return Err(SdpError::Solver(
                "the Gershgorin starting point is not dual feasible".into(),
            ));
        }
        // The relative gap in the original units.
        let relative_gap = |(p, d): (f64, f64)| scale * (p - d).abs() / (scale * d.abs()).max(1.0);
        let mut iteration = 0;
        // Progress once the gap is below one: the best gap and μ, and when one last halved.
        let (mut best_gap, mut best_mu, mut best_iteration) = (f64::INFINITY, f64::INFINITY, 0);
        let gap = loop {
            let mut gap = relative_gap(self.bounds());
            let mu = self.mu();
            if gap < 1.0 && (gap < 0.5 * best_gap || mu < 0.5 * best_mu) {
                (best_gap, best_mu, best_iteration) =
                    (gap.min(best_gap), mu.min(best_mu), iteration);
            }
            let without_progress = if gap < 1.0 {
                iteration - best_iteration
            } else {
                0
            };
            if gap > options.tolerance
                && (gap <= POLISH_FROM * options.tolerance || without_progress >= POLISH_WHEN_SLOW)
            {
                self.polish()?;
                gap = relative_gap(self.bounds());
            }
            if crate::progress::observed() {
                // In the original units: the best primal and dual objectives so far, μ.
                let (p, d) = self.bounds();
                crate::progress::iteration(
                    iteration as u64,
                    &[
                        ("primal_objective", scale * p),
                        ("dual_objective", scale * d),
                        ("relative_gap", gap),
                        ("mu", scale * mu),
                    ],
                );
            }
            if gap <= options.tolerance {
                return Ok(iteration);
            }
            let stalled = without_progress >= STALL_ITERATIONS;
            if stalled || iteration == options.max_iterations || !self.step()? {
                break gap;
            }
            iteration += 1;
        };
        Err(SdpError::NotConverged {
            iterations: iteration,
            gap,
        })
    }

    /// μ = Tr(X Z)/n, with Tr(X Z) = Tr(X M) − Σ y_i X_ii.
    fn mu(&self) -> f64 {
        let n = self.n;
        let xz = inner(self.m.as_ref(), self.x.as_ref())
            - (0..n).map(|i| self.y[i] * self.x[(i, i)].re).sum::<f64>();
        xz / n as f64
    }

    /// One predictor-corrector step. False if the iteration cannot continue (μ not positive or
    /// H not positive definite numerically, or no positive step keeps X and Z definite).
    fn step(&mut self) -> Result<bool, SdpError> {
        let n = self.n;
        let mu = self.mu();
        let xz = mu * n as f64;
        // Tr(X Z) > 0 for X, Z ≻ 0, unless rounding has taken over.
        if !(mu > 0.0 && mu < f64::INFINITY && self.newton_system()) {
            return Ok(false);
        }

        // Predictor (affine scaling): σ = 0, H Δy_a = 1.
        self.rhs.fill(1.0);
        self.solve_h();
        for i in 0..n {
            self.dy_a[i] = self.rhs[(i, 0)];
        }
        self.direction(0.0, false);
        std::mem::swap(&mut self.dx, &mut self.dx_a);
        let alpha_p = self.max_primal_step(true)?.min(1.0);
        let alpha_d = self.max_dual_step(true)?.min(1.0);
        // μ_a = Tr((X + α_p ΔX_a)(Z + α_d ΔZ_a))/n, expanded with ΔZ_a = −Diag(Δy_a).
        let dx_z = inner(self.m.as_ref(), self.dx_a.as_ref())
            - (0..n)
                .map(|i| self.y[i] * self.dx_a[(i, i)].re)
                .sum::<f64>();
        let x_dz = -(0..n)
            .map(|i| self.x[(i, i)].re * self.dy_a[i])
            .sum::<f64>();
        let dx_dz = -(0..n)
            .map(|i| self.dx_a[(i, i)].re * self.dy_a[i])
            .sum::<f64>();
        let mu_a = (xz + alpha_p * dx_z + alpha_d * x_dz + alpha_p * alpha_d * dx_dz) / n as f64;
        let sigma = (mu_a / mu).clamp(0.0, 1.0).powi(3);

        // Corrector: H Δy = 1 − σμ diag(G) − Re(ΔX_a ∘ conj G) Δy_a.
        for i in 0..n {
            let c: f64 = (0..n)
                .map(|k| re_conj(self.dx_a[(i, k)], self.g[(i, k)]) * self.dy_a[k])
                .sum();
            self.rhs[(i, 0)] = 1.0 - sigma * mu * self.g[(i, i)].re - c;
        }
        self.solve_h();
        for i in 0..n {
            self.dy[i] = self.rhs[(i, 0)];
        }
        self.direction(sigma * mu, true);
        let gamma = 0.9 + 0.09 * alpha_p.min(alpha_d);
        let alpha_p = (gamma * self.max_primal_step(false)?).min(1.0);
        let alpha_d = (gamma * self.max_dual_step(false)?).min(1.0);
        Ok(self.take_step(alpha_p, alpha_d))
    }

    /// K = L_Z⁻¹, G = Kᴴ K, and the Cholesky factor of H = Re(G ∘ conj X) in `h`.
    /// False if H is numerically not positive definite.
    fn newton_system(&mut self) -> bool {
        let n = self.n;
        triangular_inverse::invert_lower_triangular(self.k.as_mut(), self.lz.as_ref(), Par::Seq);
        tri_matmul::matmul(
            self.g.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            self.k.adjoint(),
            BlockStructure::TriangularUpper,
            self.k.as_ref(),
            BlockStructure::TriangularLower,
            c64::new(1.0, 0.0),
            Par::Seq,
        );
        for j in 0..n {
            self.g[(j, j)].im = 0.0;
            for i in j + 1..n {
                self.g[(j, i)] = self.g[(i, j)].conj();
            }
        }
        for j in 0..n {
            for i in j..n {
                self.h[(i, j)] = re_conj(self.g[(i, j)], self.x[(i, j)]);
            }
        }
        llt_factor::cholesky_in_place(
            self.h.as_mut(),
            Default::default(),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        )
        .is_ok()
    }

    /// Solves H v = rhs in place (H's Cholesky factor in `h`).
    fn solve_h(&mut self) {
        llt_solve::solve_in_place(
            self.h.as_ref(),
            self.rhs.as_mut(),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
    }

    /// ΔX = σμ G − X + herm((X D + [ΔX_a D_a]) G) into `dx`, with D = Diag(Δy) (`dy` if
    /// `corrector`, else `dy_a`), the bracket only in the corrector.
    fn direction(&mut self, sigma_mu: f64, corrector: bool) {
        let n = self.n;
        let d = if corrector { &self.dy } else { &self.dy_a };
        for (j, (&dj, &dj_a)) in d.iter().zip(&self.dy_a).enumerate() {
            for i in 0..n {
                let mut v = self.x[(i, j)] * dj;
                if corrector {
                    v += self.dx_a[(i, j)] * dj_a;
                }
                self.t1[(i, j)] = v;
            }
        }
        matmul::matmul(
            self.dx.as_mut(),
            Accum::Replace,
            self.t1.as_ref(),
            self.g.as_ref(),
            c64::new(1.0, 0.0),
            Par::Seq,
        );
        let dx = &mut self.dx;
        for j in 0..n {
            for i in j + 1..n {
                let v = self.g[(i, j)] * sigma_mu - self.x[(i, j)]
                    + (dx[(i, j)] + dx[(j, i)].conj()) * 0.5;
                dx[(i, j)] = v;
                dx[(j, i)] = v.conj();
            }
            let v = self.g[(j, j)].re * sigma_mu - self.x[(j, j)].re + dx[(j, j)].re;
            dx[(j, j)] = c64::new(v, 0.0);
        }
    }

    /// Largest α with X + α ΔX ⪰ 0: −1/λ_min(L⁻¹ ΔX L⁻ᴴ), or ∞. The predictor's ΔX_a if
    /// `predictor`, else ΔX.
    fn max_primal_step(&mut self, predictor: bool) -> Result<f64, SdpError> {
        let dx = if predictor { &self.dx_a } else { &self.dx };
        self.t1.copy_from(dx);
        triangular_solve::solve_lower_triangular_in_place(
            self.lx.as_ref(),
            self.t1.as_mut(),
            Par::Seq,
        );
        self.t2.copy_from(self.t1.adjoint());
        triangular_solve::solve_lower_triangular_in_place(
            self.lx.as_ref(),
            self.t2.as_mut(),
            Par::Seq,
        );
        let lambda = min_eigenvalue(self.t2.as_ref(), &mut self.eigenvalues, &mut self.mem)?;
        Ok(step_to_boundary(lambda))
    }

    /// Largest α with Z + α ΔZ ⪰ 0, ΔZ = −Diag(Δy): −1/λ_min(−K Diag(Δy) Kᴴ), or ∞.
    fn max_dual_step(&mut self, predictor: bool) -> Result<f64, SdpError> {
        let n = self.n;
        let dy = if predictor { &self.dy_a } else { &self.dy };
        for (j, &dyj) in dy.iter().enumerate() {
            for i in j..n {
                self.t1[(i, j)] = self.k[(i, j)] * dyj;
            }
        }
        tri_matmul::matmul(
            self.t2.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            self.t1.as_ref(),
            BlockStructure::TriangularLower,
            self.k.adjoint(),
            BlockStructure::TriangularUpper,
            c64::new(-1.0, 0.0),
            Par::Seq,
        );
        let lambda = min_eigenvalue(self.t2.as_ref(), &mut self.eigenvalues, &mut self.mem)?;
        Ok(step_to_boundary(lambda))
    }

    /// X += α_p ΔX, y += α_d Δy, refactoring X and Z; a step that rounding makes indefinite is
    /// shortened. False if no positive step keeps both definite (the iteration stalled).
    fn take_step(&mut self, mut alpha_p: f64, mut alpha_d: f64) -> bool {
        let n = self.n;
        let mut accepted = false;
        for _ in 0..30 {
            for j in 0..n {
                for i in j..n {
                    self.lx[(i, j)] = self.x[(i, j)] + self.dx[(i, j)] * alpha_p;
                }
            }
            if llt_factor::cholesky_in_place(
                self.lx.as_mut(),
                Default::default(),
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .is_ok()
            {
                accepted = true;
                break;
            }
            alpha_p *= 0.8;
        }
        if !accepted {
            return false;
        }
        for j in 0..n {
            for i in j..n {
                let v = self.x[(i, j)] + self.dx[(i, j)] * alpha_p;
                self.x[(i, j)] = v;
                self.x[(j, i)] = v.conj();
            }
        }
        let y_old = self.y.clone();
        for _ in 0..30 {
            for ((y, &y0), &dy) in self.y.iter_mut().zip(&y_old).zip(&self.dy) {
                *y = y0 + alpha_d * dy;
            }
            if factor_dual(&self.m, &self.y, &mut self.lz, &mut self.mem) {
                return true;
            }
            alpha_d *= 0.8;
        }
        self.y = y_old;
        factor_dual(&self.m, &self.y, &mut self.lz, &mut self.mem)
    }

    /// Tries the rounded points of the module docs ("Polishing") and keeps them where they
    /// improve the bounds.
    fn polish(&mut self) -> Result<(), SdpError> {
        let n = self.n;
        if n == 0 {
            return Ok(());
        }
        // X = U Λ Uᴴ: U in t1, Λ ascending in `eigenvalues`.
        evd::self_adjoint_evd(
            self.x.as_ref(),
            self.eigenvalues.as_mut(),
            Some(self.t1.as_mut()),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        )
        .map_err(|e| SdpError::Solver(format!("eigendecomposition of X: {e:?}")))?;
        let lambda: Vec<f64> = self
            .eigenvalues
            .column_vector()
            .iter()
            .map(|v| v.re)
            .collect();
        let top = lambda[n - 1];
        // Primal: the truncation with the smallest objective.
        let mut best: Option<(f64, Mat<c64>)> = None;
        let mut last_rank = 0;
        for tau in TRUNCATION_THRESHOLDS {
            let rank = lambda.iter().filter(|&&l| l > tau * top).count();
            if rank == last_rank {
                continue;
            }
            last_rank = rank;
            let mut x = Mat::<c64>::zeros(n, n);
            for (k, &lambda_k) in lambda.iter().enumerate().skip(n - rank) {
                let u = self.t1.col(k);
                for j in 0..n {
                    let s = u[j].conj() * lambda_k;
                    for i in j..n {
                        x[(i, j)] += u[i] * s;
                    }
                }
            }
            if (0..n).any(|i| x[(i, i)].re <= f64::MIN_POSITIVE) {
                continue;
            }
            let d: Vec<f64> = (0..n).map(|i| 1.0 / x[(i, i)].re.sqrt()).collect();
            for j in 0..n {
                for i in j + 1..n {
                    let v = x[(i, j)] * (d[i] * d[j]);
                    x[(i, j)] = v;
                    x[(j, i)] = v.conj();
                }
                x[(j, j)] = c64::new(1.0, 0.0);
            }
            let objective = inner(self.m.as_ref(), x.as_ref());
            if best.as_ref().is_none_or(|b| objective < b.0) {
                best = Some((objective, x));
            }
        }
        let Some((objective, x)) = best else {
            return Ok(());
        };
        // Dual: y_i = Re((M X̂)_ii), made feasible by the shift η.
        let mut y: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| re_conj(self.m[(i, j)], x[(i, j)])).sum())
            .collect();
        for (j, &yj) in y.iter().enumerate() {
            for i in j..n {
                self.t2[(i, j)] = self.m[(i, j)];
            }
            self.t2[(j, j)] -= yj;
        }
        let lambda_min = min_eigenvalue(self.t2.as_ref(), &mut self.eigenvalues, &mut self.mem)?;
        let mut margin = f64::EPSILON * n as f64;
        for _ in 0..4 {
            let shift = (-lambda_min).max(0.0) + margin;
            let shifted: Vec<f64> = y.iter().map(|v| v - shift).collect();
            if factor_dual(&self.m, &shifted, &mut self.t2, &mut self.mem) {
                y = shifted;
                let dual: f64 = y.iter().sum();
                if self.polished_y.as_ref().is_none_or(|b| dual > b.0) {
                    self.polished_y = Some((dual, y));
                }
                break;
            }
            margin *= 16.0;
        }
        if self.polished_x.as_ref().is_none_or(|b| objective < b.0) {
            self.polished_x = Some((objective, x));
        }
        Ok(())
    }

    /// The best pair found: λ* = scale · y, X* with a unit diagonal, objectives on the original
    /// matrix.
    fn into_solution(
        self,
        m: MatRef<'_, c64>,
        scale: f64,
        iterations: usize,
        converged: bool,
    ) -> DualSolution {
        let n = self.n;
        let plain_primal = unit_diagonal_objective(self.m.as_ref(), self.x.as_ref());
        let mut x = match self.polished_x {
            Some((objective, x)) if objective < plain_primal => x,
            _ => self.x,
        };
        let d: Vec<f64> = (0..n).map(|i| 1.0 / x[(i, i)].re.sqrt()).collect();
        for j in 0..n {
            for i in 0..n {
                x[(i, j)] *= d[i] * d[j];
            }
            x[(j, j)] = c64::new(1.0, 0.0);
        }
        let plain_dual: f64 = self.y.iter().sum();
        let y = match self.polished_y {
            Some((dual, y)) if dual > plain_dual => y,
            _ => self.y,
        };
        let lambda: Vec<f64> = y.iter().map(|&v| v * scale).collect();
        DualSolution {
            dual_objective: lambda.iter().sum(),
            lambda,
            primal_objective: inner(m, x.as_ref()),
            x,
            iterations,
            solver: "ipm",
            converged,
        }
    }
}

/// Tr(M X̂) with X̂ = D^{-1/2} X D^{-1/2}, D = Diag(X): the objective of X rescaled to be
/// exactly primal feasible.
fn unit_diagonal_objective(m: MatRef<'_, c64>, x: MatRef<'_, c64>) -> f64 {
    let n = x.nrows();
    let d: Vec<f64> = (0..n).map(|i| 1.0 / x[(i, i)].re.sqrt()).collect();
    let mut s = 0.0;
    for j in 0..n {
        for i in 0..n {
            s += re_conj(m[(i, j)], x[(i, j)]) * d[i] * d[j];
        }
    }
    s
}

/// Re(a · conj(b)).
#[inline]
fn re_conj(a: c64, b: c64) -> f64 {
    a.re * b.re + a.im * b.im
}

/// Tr(A B) = Σ_ij Re(A_ij conj(B_ij)) for Hermitian A, B (both triangles stored).
fn inner(a: MatRef<'_, c64>, b: MatRef<'_, c64>) -> f64 {
    let mut s = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            s += re_conj(a[(i, j)], b[(i, j)]);
        }
    }
    s
}

/// Writes Z = M − Diag(y) (lower triangle) into `lz` and factors it; false if not Z ≻ 0.
fn factor_dual(m: &Mat<c64>, y: &[f64], lz: &mut Mat<c64>, mem: &mut MemBuffer) -> bool {
    let n = m.nrows();
    for j in 0..n {
        for i in j..n {
            lz[(i, j)] = m[(i, j)];
        }
        lz[(j, j)] = c64::new(m[(j, j)].re - y[j], 0.0);
    }
    llt_factor::cholesky_in_place(
        lz.as_mut(),
        Default::default(),
        Par::Seq,
        MemStack::new(mem),
        Default::default(),
    )
    .is_ok()
}

/// Smallest eigenvalue of the Hermitian matrix whose lower triangle is `a`.
fn min_eigenvalue(
    a: MatRef<'_, c64>,
    s: &mut Diag<c64>,
    mem: &mut MemBuffer,
) -> Result<f64, SdpError> {
    evd::self_adjoint_evd(
        a,
        s.as_mut(),
        None,
        Par::Seq,
        MemStack::new(mem),
        Default::default(),
    )
    .map_err(|e| SdpError::Solver(format!("eigenvalues for the step length: {e:?}")))?;
    Ok(s.column_vector()
        .iter()
        .map(|v| v.re)
        .fold(f64::INFINITY, f64::min))
}

/// The step to the boundary of the cone along a direction whose congruence-scaled matrix has
/// smallest eigenvalue `lambda_min`.
fn step_to_boundary(lambda_min: f64) -> f64 {
    if lambda_min < 0.0 {
        -1.0 / lambda_min
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Side;
    use faer::prelude::*;

    /// SplitMix64: a small seeded generator, so the tests need no extra dependency.
    struct Rng(u64);

    impl Rng {
        fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
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

        /// e^{iθ}, θ uniform.
        fn phase(&mut self) -> c64 {
            let t = std::f64::consts::TAU * self.uniform();
            c64::new(t.cos(), t.sin())
        }
    }

    fn random_hermitian(rng: &mut Rng, n: usize) -> Mat<c64> {
        let a = Mat::from_fn(n, n, |_, _| c64::new(rng.normal(), rng.normal()));
        Mat::from_fn(n, n, |i, j| (a[(i, j)] + a[(j, i)].conj()) * 0.5)
    }

    /// Eigenvalues (ascending) by faer's dense Hermitian solver, independent of the IPM.
    fn eigenvalues(a: MatRef<'_, c64>) -> Vec<f64> {
        a.self_adjoint_eigenvalues(Side::Lower).unwrap()
    }

    fn max_abs(a: MatRef<'_, c64>) -> f64 {
        let mut s = 0.0_f64;
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                s = s.max(a[(i, j)].norm());
            }
        }
        s
    }

    /// x^H M x for a vector x.
    fn quadratic_form(m: MatRef<'_, c64>, x: &[c64]) -> f64 {
        let n = x.len();
        let mut s = c64::new(0.0, 0.0);
        for i in 0..n {
            for j in 0..n {
                s += x[i].conj() * m[(i, j)] * x[j];
            }
        }
        s.re
    }

    /// Is the Hermitian `a` positive definite? (Cholesky succeeds.)
    fn is_positive_definite(a: MatRef<'_, c64>) -> bool {
        a.llt(Side::Lower).is_ok()
    }

    /// M − Diag(y).
    fn penalized(m: MatRef<'_, c64>, y: &[f64]) -> Mat<c64> {
        Mat::from_fn(m.nrows(), m.ncols(), |i, j| {
            if i == j { m[(i, j)] - y[i] } else { m[(i, j)] }
        })
    }

    /// Checks a returned pair against the definitions, with only faer's eigenvalue solver:
    /// y dual feasible (Z ⪰ 0), X primal feasible (unit diagonal, X ⪰ 0), the reported
    /// objectives equal Σ y and Tr(M X), zero gap and complementarity Tr(X Z) = 0. Together
    /// these certify optimality of both (weak duality), whatever the solver did.
    fn assert_optimal_pair(m: MatRef<'_, c64>, s: &DualSolution, tolerance: f64) {
        let n = m.nrows();
        let scale = max_abs(m).max(1e-300);
        assert_eq!(s.solver, "ipm");
        assert_eq!(s.lambda.len(), n);
        assert_eq!((s.x.nrows(), s.x.ncols()), (n, n));
        let dual: f64 = s.lambda.iter().sum();
        assert!((dual - s.dual_objective).abs() <= 1e-12 * dual.abs().max(1.0));
        let primal = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| (m[(i, j)] * s.x[(j, i)]).re)
            .sum::<f64>();
        assert!((primal - s.primal_objective).abs() <= 1e-9 * primal.abs().max(1.0));
        // Recomputed here on M as given (the solver works on a scaled copy): equal to rounding.
        let gap = (primal - dual).abs() / dual.abs().max(1.0);
        assert!(gap <= 1.01 * tolerance, "relative gap {gap:e}");
        let z = penalized(m, &s.lambda);
        let z_min = eigenvalues(z.as_ref())[0];
        assert!(z_min >= -1e-8 * scale, "λ_min(Z) = {z_min:e}");
        for i in 0..n {
            assert!(
                (s.x[(i, i)].re - 1.0).abs() <= 1e-12,
                "X_ii = {}",
                s.x[(i, i)]
            );
            assert!(s.x[(i, i)].im.abs() <= 1e-12);
            for j in 0..n {
                assert!((s.x[(i, j)] - s.x[(j, i)].conj()).norm() <= 1e-12);
            }
        }
        let x_min = eigenvalues(s.x.as_ref())[0];
        assert!(x_min >= -1e-8, "λ_min(X) = {x_min:e}");
        let xz = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| (s.x[(i, j)] * z[(j, i)]).re)
            .sum::<f64>();
        // Tr(X Z) = Tr(M X) − Σ y for unit-diagonal X: the gap, computed another way.
        assert!(
            xz.abs() <= 2.0 * tolerance * dual.abs().max(1.0) + 1e-12 * scale * n as f64,
            "Tr(XZ) = {xz:e}"
        );
    }

    /// The reduced matrix M = Q − Sᴴ L⁻¹ S of a pose graph with unit weights, poses 0..n,
    /// pose 0 anchored (p_0 = 0), built from the definition of the cost
    /// f = Σ |p_j − p_i − r_i Δ|² + |r_j − r_i R|² = xᴴ W x (eq. (8), (24)).
    /// Edges are (i, j, dx, dy, dθ).
    fn reduced_pose_graph_matrix(n: usize, edges: &[(usize, usize, f64, f64, f64)]) -> Mat<c64> {
        // Unknowns: p_1..p_{n-1} at 0..n-1, r_0..r_{n-1} at n-1..2n-1.
        let p = |i: usize| if i == 0 { None } else { Some(i - 1) };
        let r = |i: usize| n - 1 + i;
        let mut w = Mat::<c64>::zeros(2 * n - 1, 2 * n - 1);
        for &(i, j, dx, dy, dt) in edges {
            let delta = c64::new(dx, dy);
            let rot = c64::new(dt.cos(), dt.sin());
            // Translation term |c·x|² with c_pj = 1, c_pi = −1, c_ri = −Δ: W += conj(c) cᵀ.
            let mut c: Vec<(usize, c64)> = vec![(r(i), -delta)];
            if let Some(k) = p(j) {
                c.push((k, c64::new(1.0, 0.0)));
            }
            if let Some(k) = p(i) {
                c.push((k, c64::new(-1.0, 0.0)));
            }
            for &(a, ca) in &c {
                for &(b, cb) in &c {
                    w[(a, b)] += ca.conj() * cb;
                }
            }
            // Rotation term |r_j − r_i R|².
            w[(r(j), r(j))] += 1.0;
            w[(r(i), r(i))] += 1.0;
            w[(r(j), r(i))] -= rot;
            w[(r(i), r(j))] -= rot.conj();
        }
        let np = n - 1;
        let l = w.submatrix(0, 0, np, np).to_owned();
        let s = w.submatrix(0, np, np, n).to_owned();
        let q = w.submatrix(np, np, n, n).to_owned();
        let l_inv_s = l.llt(Side::Lower).unwrap().solve(&s);
        let m = &q - s.adjoint() * &l_inv_s;
        Mat::from_fn(n, n, |i, j| (m[(i, j)] + m[(j, i)].conj()) * 0.5)
    }

    #[test]
    fn diagonal_matrix_has_trace_as_optimum() {
        // Z = M − Diag(y) ⪰ 0 forces y_i ≤ M_ii, so Σ y ≤ Tr(M), attained at y = diag(M)
        // (Z = 0); X = I is primal feasible with Tr(M I) = Tr(M). So d* = s* = Tr(M).
        let diagonal = [3.0, -1.0, 2.5, 0.0, 7.25, -4.0];
        let n = diagonal.len();
        let m = Mat::from_fn(n, n, |i, j| {
            c64::new(if i == j { diagonal[i] } else { 0.0 }, 0.0)
        });
        let s = solve(m.as_ref(), &IpmOptions::default()).unwrap();
        let trace: f64 = diagonal.iter().sum();
        assert!((s.dual_objective - trace).abs() <= 1e-9 * trace.abs());
        assert!((s.primal_objective - trace).abs() <= 1e-9 * trace.abs());
        for (l, d) in s.lambda.iter().zip(diagonal) {
            assert!((l - d).abs() <= 1e-8, "λ = {l}, M_ii = {d}");
        }
        assert_optimal_pair(m.as_ref(), &s, 1e-10);
    }

    #[test]
    fn two_by_two_closed_form() {
        // M = [[a, b], [conj b, c]]. Primal: X = [[1, w], [conj w, 1]], |w| ≤ 1, and
        // Tr(M X) = a + c + 2 Re(b conj w), smallest at w = b/|b|·(−1): s* = a + c − 2|b|.
        // Dual: with u = a − y_1, v = c − y_2, Z ⪰ 0 iff u, v ≥ 0 and u v ≥ |b|², and
        // max y_1 + y_2 = a + c − min(u + v) = a + c − 2|b| at u = v = |b| (AM-GM).
        for &(a, b, c) in &[
            (1.0, c64::new(0.5, 0.0), 2.0),
            (-3.0, c64::new(1.0, -2.0), 4.0),
            (0.0, c64::new(0.0, 1.0), 0.0),
            (10.0, c64::new(-0.3, 0.4), -7.0),
            (2.0, c64::new(1e-3, -2e-3), 2.0),
        ] {
            let m = mat![[c64::new(a, 0.0), b], [b.conj(), c64::new(c, 0.0)]];
            let s = solve(m.as_ref(), &IpmOptions::default()).unwrap();
            let expected = a + c - 2.0 * b.norm();
            assert!(
                (s.dual_objective - expected).abs() <= 1e-9 * expected.abs().max(1.0),
                "{} vs {expected}",
                s.dual_objective
            );
            assert!((s.lambda[0] - (a - b.norm())).abs() <= 1e-8);
            assert!((s.lambda[1] - (c - b.norm())).abs() <= 1e-8);
            assert!(
                (s.x[(0, 1)] + b / b.norm()).norm() <= 1e-6,
                "X_12 = {}",
                s.x[(0, 1)]
            );
            assert_optimal_pair(m.as_ref(), &s, 1e-10);
        }
    }

    #[test]
    fn balanced_graph_has_zero_optimum_and_rank_one_solution() {
        // Rotation-only cost Σ_(i,j) |r_j − r_i R_ij|² = rᴴ M r with gains R_ij = conj(u_i) u_j
        // from unit-modulus u, on a connected graph with cycles: a balanced graph (Prop. 2, 11).
        // M ⪰ 0 and M u = 0, so λ = 0 is dual feasible (d* ≥ 0) and X = u uᴴ is primal feasible
        // with Tr(M X) = uᴴ M u = 0 (s* ≤ 0): d* = s* = 0. Both are unique: a dual optimal y
        // has 0 ≤ uᴴ (M − Diag y) u = −Σ y = 0, so (M − Diag y) u = 0, i.e. y_i u_i = 0; an
        // optimal X has Tr(M X) = 0, so its range is in ker M = span(u).
        let mut rng = Rng(7);
        for n in [3, 6, 12, 25] {
            let u: Vec<c64> = (0..n).map(|_| rng.phase()).collect();
            let mut edges: Vec<(usize, usize)> = (1..n).map(|i| (i - 1, i)).collect();
            for i in 0..n {
                for j in i + 2..n {
                    if rng.uniform() < 0.3 {
                        edges.push((i, j));
                    }
                }
            }
            edges.push((n - 1, 0));
            let mut m = Mat::<c64>::zeros(n, n);
            for &(i, j) in &edges {
                let rot = u[i].conj() * u[j];
                m[(j, j)] += 1.0;
                m[(i, i)] += 1.0;
                m[(j, i)] -= rot;
                m[(i, j)] -= rot.conj();
            }
            assert!(quadratic_form(m.as_ref(), &u).abs() < 1e-12);
            let s = solve(m.as_ref(), &IpmOptions::default()).unwrap();
            assert!(s.dual_objective.abs() <= 1e-9, "d* = {}", s.dual_objective);
            // Near the optimum λ is pinned down only to about sqrt(gap · λ_2(M)): Σ y = −ε and
            // uᴴ(M − Diag y)u ≥ 0 along u + w allow ‖Diag(y) u‖² ≲ ε λ_2(M).
            assert!(s.lambda.iter().all(|l| l.abs() <= 1e-6), "{:?}", s.lambda);
            for i in 0..n {
                for j in 0..n {
                    let e = (s.x[(i, j)] - u[i] * u[j].conj()).norm();
                    assert!(e <= 1e-6, "X - u uᴴ at ({i}, {j}): {e:e}");
                }
            }
            assert_optimal_pair(m.as_ref(), &s, 1e-10);
        }
    }

    #[test]
    fn random_hermitian_strong_duality_and_feasibility() {
        let mut rng = Rng(2024);
        for n in [5, 8, 13, 21, 30, 40] {
            for _ in 0..3 {
                let m = random_hermitian(&mut rng, n);
                let s = solve(m.as_ref(), &IpmOptions::default()).unwrap();
                assert_optimal_pair(m.as_ref(), &s, 1e-10);
                assert!(s.iterations <= 40, "n = {n}: {} iterations", s.iterations);
            }
        }
    }

    #[test]
    fn random_small_bracketed_by_brute_force_bounds() {
        let mut rng = Rng(99);
        for n in 2..=8 {
            for _ in 0..5 {
                let m = random_hermitian(&mut rng, n);
                let d = solve(m.as_ref(), &IpmOptions::default())
                    .unwrap()
                    .dual_objective;
                let slack = 1e-9 * d.abs().max(1.0);
                // Lower bounds, dual feasible points: the best common shift y = t·1, found by
                // bisection on t with a Cholesky test of M − t I, and the Gershgorin point.
                let gershgorin: Vec<f64> = (0..n)
                    .map(|i| {
                        m[(i, i)].re
                            - (0..n)
                                .filter(|&j| j != i)
                                .map(|j| m[(i, j)].norm())
                                .sum::<f64>()
                    })
                    .collect();
                let (mut lo, mut hi) = (
                    gershgorin.iter().copied().fold(f64::INFINITY, f64::min) - 1.0,
                    (0..n).map(|i| m[(i, i)].re).fold(f64::INFINITY, f64::min) + 1.0,
                );
                for _ in 0..100 {
                    let t = 0.5 * (lo + hi);
                    if is_positive_definite(penalized(m.as_ref(), &vec![t; n]).as_ref()) {
                        lo = t;
                    } else {
                        hi = t;
                    }
                }
                assert!(d >= n as f64 * lo - slack, "{d} < {}", n as f64 * lo);
                assert!(d >= gershgorin.iter().sum::<f64>() - slack);
                // Upper bounds (weak duality): d* ≤ xᴴ M x for every unit-modulus x; try random
                // phases, each improved by coordinate descent x_i ← −phase(Σ_{j≠i} M_ij x_j).
                let mut best = f64::INFINITY;
                for _ in 0..200 {
                    let mut x: Vec<c64> = (0..n).map(|_| rng.phase()).collect();
                    assert!(d <= quadratic_form(m.as_ref(), &x) + slack);
                    for _ in 0..20 {
                        for i in 0..n {
                            let g: c64 = (0..n).filter(|&j| j != i).map(|j| m[(i, j)] * x[j]).sum();
                            if g.norm() > 0.0 {
                                x[i] = -g / g.norm();
                            }
                        }
                    }
                    best = best.min(quadratic_form(m.as_ref(), &x));
                }
                assert!(d <= best + slack, "d* = {d} > f(x) = {best}");
                if n == 2 {
                    // Tight here: the rank-one X of the 2 x 2 case.
                    assert!((d - best).abs() <= 1e-8 * best.abs().max(1.0));
                }
            }
        }
    }

    #[test]
    fn paper_toy_graph_appendix_8_8() {
        // The toy graph of Section 6 / Appendix 8.8 (ids 1..5 here 0..4), unit weights. The
        // issue's reference: d* = 5.560697 and W(λ*) has two eigenvalues at zero (no SZEP). The
        // reduced M − Diag(λ*) has the same number of zero eigenvalues (Schur complement with
        // L ≻ 0), not the same nonzero ones.
        let edges = [
            (0, 1, 4.6606, 1.2177, 2.8186),
            (1, 2, -4.4199, 4.8043, 0.1519),
            (2, 3, -4.1169, 4.9322, 0.5638),
            (3, 4, -3.6351, -5.0908, -0.5855),
            (4, 0, 3.4744, 5.9425, 2.5775),
        ];
        let m = reduced_pose_graph_matrix(5, &edges);
        let s = solve(m.as_ref(), &IpmOptions::default()).unwrap();
        assert!(
            (s.dual_objective - 5.560697).abs() <= 1e-5,
            "d* = {}",
            s.dual_objective
        );
        assert_optimal_pair(m.as_ref(), &s, 1e-10);
        let z = eigenvalues(penalized(m.as_ref(), &s.lambda).as_ref());
        assert!(z[0].abs() < 1e-6 && z[1].abs() < 1e-6, "{z:?}");
        assert!(z[2] > 1e-3 && z[2] < 1.0, "{z:?}");
        // X* has rank two (= the multiplicity of the zero eigenvalue, strict complementarity).
        let x = eigenvalues(s.x.as_ref());
        assert!(x[2] < 1e-6 && x[3] > 1e-3, "{x:?}");
    }

    /// A random graph after the paper's model (47): poses uniform in a square of side `side`
    /// (10 m in the paper), a spanning path plus loop closures with probability 0.2,
    /// measurement noise σ on Δ and θ.
    fn random_pose_graph(rng: &mut Rng, n: usize, sigma: f64, side: f64) -> Mat<c64> {
        let p: Vec<(f64, f64, f64)> = (0..n)
            .map(|_| {
                (
                    side * rng.uniform(),
                    side * rng.uniform(),
                    6.0 * rng.uniform(),
                )
            })
            .collect();
        let mut pairs: Vec<(usize, usize)> = (1..n).map(|i| (i - 1, i)).collect();
        for i in 0..n {
            for j in i + 2..n {
                if rng.uniform() < 0.2 {
                    pairs.push((i, j));
                }
            }
        }
        let edges: Vec<_> = pairs
            .into_iter()
            .map(|(i, j)| {
                let (c, s) = (p[i].2.cos(), p[i].2.sin());
                let (dx, dy) = (p[j].0 - p[i].0, p[j].1 - p[i].1);
                (
                    i,
                    j,
                    c * dx + s * dy + sigma * rng.normal(),
                    -s * dx + c * dy + sigma * rng.normal(),
                    p[j].2 - p[i].2 + sigma * rng.normal(),
                )
            })
            .collect();
        reduced_pose_graph_matrix(n, &edges)
    }

    #[test]
    fn random_pose_graphs_are_solved_to_tolerance() {
        // The regime the solver is for, where d* is small next to the entries of M, so that the
        // gap relies on polishing (module docs). The paper's Monte Carlo (Sec. 6) finds the
        // SZEP for σ = 0.1, so X* has rank one there.
        let mut rng = Rng(47);
        for n in [8, 15, 30, 60] {
            for sigma in [0.1, 0.5, 1.0] {
                let m = random_pose_graph(&mut rng, n, sigma, 10.0);
                let s = solve(m.as_ref(), &IpmOptions::default()).unwrap();
                assert_optimal_pair(m.as_ref(), &s, 1e-10);
                assert!(s.iterations <= 40, "n = {n}, σ = {sigma}: {}", s.iterations);
                if sigma == 0.1 {
                    let x = eigenvalues(s.x.as_ref());
                    assert!(
                        x[n - 2] < 1e-6 && (x[n - 1] - n as f64).abs() < 1e-6,
                        "{x:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn badly_scaled_graphs_stop_at_the_rounding_floor() {
        // Translations 100 times longer than in the paper: max |M_ij| ~ 1e6 while d* ~ 1, so a
        // gap of 1e-10 is below what double precision resolves ("Accuracy" in the module docs).
        // The solver either gets there or says how far it got, without running to the
        // iteration limit; a looser tolerance is met.
        let mut rng = Rng(1000);
        for _ in 0..5 {
            let m = random_pose_graph(&mut rng, 20, 0.1, 1000.0);
            match solve(m.as_ref(), &IpmOptions::default()) {
                Ok(s) => assert!(s.iterations < 100),
                Err(SdpError::NotConverged { iterations, gap }) => {
                    assert!(iterations < 100 && gap < 1e-5, "{iterations} {gap:e}");
                }
                Err(e) => panic!("{e}"),
            }
            let loose = IpmOptions {
                tolerance: 1e-6,
                ..IpmOptions::default()
            };
            let s = solve(m.as_ref(), &loose).unwrap();
            assert_optimal_pair(m.as_ref(), &s, loose.tolerance);
        }
    }

    #[test]
    fn scaling_the_matrix_scales_the_optimum() {
        // d*(f M) = f d*(M) (substitute y = f y'), with X* unchanged. The relative gap is
        // measured against max(1, |d*|), so for a tiny matrix ask for a gap in its own scale.
        let mut rng = Rng(5);
        let m = random_hermitian(&mut rng, 12);
        let s = solve(m.as_ref(), &IpmOptions::default()).unwrap();
        for factor in [1e-6, 1e6] {
            let ms = Mat::from_fn(12, 12, |i, j| m[(i, j)] * factor);
            let options = IpmOptions {
                tolerance: 1e-10 * factor.min(1.0),
                ..IpmOptions::default()
            };
            let t = solve(ms.as_ref(), &options).unwrap();
            assert_optimal_pair(ms.as_ref(), &t, options.tolerance);
            let expected = s.dual_objective * factor;
            assert!((t.dual_objective - expected).abs() <= 1e-9 * expected.abs());
        }
    }

    #[test]
    fn tiny_and_degenerate_sizes() {
        let empty = Mat::<c64>::zeros(0, 0);
        let s = solve(empty.as_ref(), &IpmOptions::default()).unwrap();
        assert!(s.lambda.is_empty() && s.dual_objective == 0.0 && s.primal_objective == 0.0);
        let one = mat![[c64::new(-2.5, 0.0)]];
        let s = solve(one.as_ref(), &IpmOptions::default()).unwrap();
        assert!((s.lambda[0] + 2.5).abs() <= 1e-9);
        // M = 0: every X is optimal, d* = 0 at y = 0.
        let zero = Mat::<c64>::zeros(4, 4);
        let s = solve(zero.as_ref(), &IpmOptions::default()).unwrap();
        assert!(s.dual_objective.abs() <= 1e-9 && s.lambda.iter().all(|l| l.abs() <= 1e-9));
    }

    #[test]
    fn invalid_input_is_rejected() {
        let options = IpmOptions::default();
        let rect = Mat::<c64>::zeros(2, 3);
        assert_eq!(
            solve(rect.as_ref(), &options).unwrap_err(),
            SdpError::InvalidInput
        );
        let not_hermitian = mat![
            [c64::new(1.0, 0.0), c64::new(0.5, 0.1)],
            [c64::new(0.5, 0.1), c64::new(1.0, 0.0)]
        ];
        assert_eq!(
            solve(not_hermitian.as_ref(), &options).unwrap_err(),
            SdpError::InvalidInput
        );
        let complex_diagonal = mat![[c64::new(1.0, 0.5)]];
        assert_eq!(
            solve(complex_diagonal.as_ref(), &options).unwrap_err(),
            SdpError::InvalidInput
        );
        for bad in [f64::NAN, f64::INFINITY] {
            let m = mat![
                [c64::new(1.0, 0.0), c64::new(bad, 0.0)],
                [c64::new(bad, 0.0), c64::new(1.0, 0.0)]
            ];
            assert_eq!(
                solve(m.as_ref(), &options).unwrap_err(),
                SdpError::InvalidInput
            );
        }
        // Rounding-level asymmetry is accepted.
        let nearly = mat![
            [c64::new(1.0, 0.0), c64::new(0.5, 0.1)],
            [c64::new(0.5, -0.1 + 1e-15), c64::new(1.0, 1e-16)]
        ];
        assert!(solve(nearly.as_ref(), &options).is_ok());
    }

    #[test]
    fn too_few_iterations_is_reported() {
        let mut rng = Rng(3);
        let m = random_hermitian(&mut rng, 10);
        let options = IpmOptions {
            max_iterations: 2,
            ..IpmOptions::default()
        };
        match solve(m.as_ref(), &options) {
            Err(SdpError::NotConverged { iterations, gap }) => {
                assert_eq!(iterations, 2);
                assert!(gap > options.tolerance);
            }
            other => panic!("{other:?}"),
        }
    }
}
