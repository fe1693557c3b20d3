//! The single zero eigenvalue property (SZEP, Prop. 10): how many eigenvalues of the penalized
//! matrix W̃(λ*) count as zero at the accuracy the dual was solved to. One zero (the estimate
//! itself) means the relaxation is exact and the estimate is the rounding of its solution.

use crate::problem::matrix::PoseGraphMatrix;

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
/// ‖W̃‖_F from the stored upper triangle, each entry above the diagonal counted twice.
pub fn zero_threshold(matrix: &PoseGraphMatrix, duality_gap: f64) -> f64 {
    let d = matrix.dim();
    let mut max_diag = 1.0f64;
    let mut fro2 = 0.0;
    for (r, c, v) in matrix.upper_entries() {
        if r == c {
            max_diag = max_diag.max(v.re);
            fro2 += v.norm_sqr();
        } else {
            fro2 += 2.0 * v.norm_sqr();
        }
    }
    let rounding = d as f64 * f64::EPSILON * fro2.sqrt();
    (ZERO_FACTOR * duality_gap.abs().max(rounding)).max(1e-12 * max_diag)
}

/// How many of the ascending `values` are at most `threshold`.
pub fn near_zero(values: &[f64], threshold: f64) -> usize {
    values.iter().take_while(|&&v| v <= threshold).count()
}
