//! Eigenvalues of the pose graph matrices (dense, for small graphs): W̃, the penalized matrix
//! W̃(λ*) and M, the count of eigenvalues at zero (the SZEP, Prop. 10), and the flags of
//! Prop. 6 (tree, balanced).

use crate::matrix::PoseGraphMatrix;
use faer::{Mat, Side, c64};

/// Relative tolerance of the zero test: an eigenvalue μ of W̃(λ*) counts as zero when
/// μ ≤ ZERO_TOLERANCE · max(1, max_k W̃_kk). The dual is solved to a relative gap of about
/// 1e-10, which leaves the zero eigenvalues at about 1e-9 of the matrix's scale (the paper's
/// toy graph: −4e-9 and 7e-9 against 0.027 for the first nonzero one); 1e-6 sits well between.
pub const ZERO_TOLERANCE: f64 = 1e-6;

/// The absolute zero threshold for a pose graph matrix (see [`ZERO_TOLERANCE`]).
pub fn zero_threshold(matrix: &PoseGraphMatrix) -> f64 {
    let w = matrix.dense();
    let scale = (0..w.nrows()).map(|k| w[(k, k)].re).fold(1.0f64, f64::max);
    ZERO_TOLERANCE * scale
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
