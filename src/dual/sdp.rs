//! The dual SDP (31) in its reduced form: with positions eliminated (Schur complement, L ≻ 0 for
//! a connected graph), W̃(λ) ⪰ 0 iff M − diag(λ) ⪰ 0 with M = Q̃ − S̃* L⁻¹ S̃ (see
//! [`crate::problem::matrix`]), so (31) is
//!
//! ```text
//! d* = max Σ λ_i   s.t.  M − diag(λ) ⪰ 0            (dual, (31) reduced)
//! s* = min Tr(M X) s.t.  X_ii = 1, X ⪰ 0 (Hermitian)  (primal, (37) reduced)
//! ```
//!
//! the complex analogue of the max-cut SDP. Two solvers: a dedicated primal-dual interior-point
//! method on faer ([`crate::dual::ipm`], default build) and clarabel on the real embedding of the Hermitian
//! cone (`clarabel` module, behind the `clarabel-sdp` cargo feature, which needs a system
//! OpenBLAS).

use faer::{Mat, c64};

/// A solution of the reduced dual SDP and its primal.
#[derive(Debug, Clone)]
pub struct DualSolution {
    /// λ*, one multiplier per pose (per unit-modulus constraint).
    pub lambda: Vec<f64>,
    /// X*, the primal (37) solution (n x n Hermitian PSD, unit diagonal).
    pub x: Mat<c64>,
    /// Σ λ_i: the dual objective d*.
    pub dual_objective: f64,
    /// Tr(M X*): the primal objective s*.
    pub primal_objective: f64,
    /// Iterations taken.
    pub iterations: usize,
    /// Which solver produced it ("ipm", "clarabel").
    pub solver: &'static str,
    /// Whether the solver reached its tolerance. A solution that did not (see
    /// [`ipm::solve_best_effort`]) is still dual feasible, so it still proves a bound, only a
    /// weaker one.
    pub converged: bool,
}

/// Why an SDP solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SdpError {
    #[error("the matrix is not Hermitian or not finite")]
    InvalidInput,
    #[error("the SDP solver did not converge in {iterations} iterations (relative gap {gap:e})")]
    NotConverged { iterations: usize, gap: f64 },
    #[error("the SDP solver failed: {0}")]
    Solver(String),
}
