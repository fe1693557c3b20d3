//! Which solver solves the dual SDP (31), and the call that runs it with the tolerances that
//! double precision can reach.

use super::sdp::{DualSolution, SdpError};
use faer::{Mat, c64};

/// Which SDP solver solves the dual.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SdpSolver {
    /// The dedicated primal-dual interior-point method (default build).
    Ipm,
    /// clarabel on the real embedding of the Hermitian cone (cargo feature `clarabel-sdp`).
    Clarabel,
}

/// Solves the reduced dual SDP of M with the chosen solver.
pub fn solve_dual(m: &Mat<c64>, solver: SdpSolver) -> Result<DualSolution, SdpError> {
    match solver {
        SdpSolver::Ipm => {
            // A relative gap of 1e-10 is out of reach in double precision on badly scaled
            // graphs (d* far below the entries of M); accept 1e-8, then 1e-6 there, and past
            // that the last (dual feasible) iterate, marked not converged. The bound reported
            // is proven for whatever λ is returned (see crate::certify).
            for tolerance in [1e-10, 1e-8] {
                let options = crate::dual::ipm::IpmOptions {
                    tolerance,
                    ..Default::default()
                };
                let result = crate::dual::ipm::solve(m.as_ref(), &options);
                if !matches!(result, Err(SdpError::NotConverged { .. })) {
                    return result;
                }
            }
            let options = crate::dual::ipm::IpmOptions {
                tolerance: 1e-6,
                ..Default::default()
            };
            crate::dual::ipm::solve_best_effort(m.as_ref(), &options)
        }
        #[cfg(feature = "clarabel-sdp")]
        SdpSolver::Clarabel => crate::dual::clarabel::solve(m.as_ref()),
        #[cfg(not(feature = "clarabel-sdp"))]
        SdpSolver::Clarabel => Err(SdpError::Solver(
            "this build has no clarabel SDP solver (build with --features clarabel-sdp)".into(),
        )),
    }
}
