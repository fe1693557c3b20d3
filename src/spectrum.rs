//! Eigenvalues of the pose graph matrices (dense, for small graphs): W̃, the penalized matrix
//! W̃(λ*) and M, the count of eigenvalues at zero (the SZEP, Prop. 10), and the flags of
//! Prop. 6 (tree, balanced).

use crate::matrix::PoseGraphMatrix;
use faer::{Mat, Side, c64};

/// The zero test of the SZEP: an eigenvalue μ of W̃(λ*) counts as zero when it is within
/// ZERO_FACTOR times the accuracy of the dual solution, that is of the larger of its duality gap
/// |Tr(M X*) − Σλ*| and the rounding allowance of the eigenvalue computation (d·u·‖W̃‖_F), and
/// never below 1e-12 of the largest diagonal entry of W̃. The eigenvalues a perturbation δ of λ*
/// moves off zero stay within about δ, while the first nonzero eigenvalue of a graph with the
/// SZEP stays put: the paper's toy graph has its two zeros at 1e-13 against a gap of 1e-10 and
/// its next eigenvalue at 0.027.
pub const ZERO_FACTOR: f64 = 1e3;

/// The absolute zero threshold for the eigenvalues of W̃(λ*) (see [`ZERO_FACTOR`]), given the
/// duality gap the SDP solver reached.
pub fn zero_threshold(matrix: &PoseGraphMatrix, duality_gap: f64) -> f64 {
    let w = matrix.dense();
    let d = w.nrows();
    let mut max_diag = 1.0f64;
    let mut fro2 = 0.0;
    for c in 0..d {
        max_diag = max_diag.max(w[(c, c)].re);
        for r in 0..d {
            fro2 += w[(r, c)].norm_sqr();
        }
    }
    let rounding = d as f64 * f64::EPSILON * fro2.sqrt();
    (ZERO_FACTOR * duality_gap.abs().max(rounding)).max(1e-12 * max_diag)
}

/// Eigenvalues (ascending) and eigenvectors (columns) of a Hermitian matrix.
pub fn hermitian_eigen(m: &Mat<c64>) -> (Vec<f64>, Mat<c64>) {
    let evd = m
        .self_adjoint_eigen(Side::Lower)
        .expect("the Hermitian eigensolver converges on finite matrices");
    let s = evd.S();
    let values = (0..m.nrows()).map(|k| s[k].re).collect();
    (values, evd.U().to_owned())
}

/// Eigenvalues (ascending) of a Hermitian matrix.
pub fn hermitian_eigenvalues(m: &Mat<c64>) -> Vec<f64> {
    m.self_adjoint_eigenvalues(Side::Lower)
        .expect("the Hermitian eigensolver converges on finite matrices")
}

/// How many of the ascending `values` are at most `threshold`.
pub fn near_zero(values: &[f64], threshold: f64) -> usize {
    values.iter().take_while(|&&v| v <= threshold).count()
}
