//! Certificates: a dual-feasible λ bounds the optimum from below (weak duality (32)), so
//! `cost − lower_bound` bounds the suboptimality of any estimate. What is printed must be a
//! bound, so the floating-point errors of the eigenvalue computation are accounted for.
//!
//! For a candidate λ (e.g. the SDP's λ*), the smallest eigenvalue μ of W̃(λ) is computed by a
//! backward-stable Hermitian eigensolver: it is exact for W̃(λ) + E with ‖E‖₂ ≤ c·d·u·‖W̃(λ)‖_F
//! (d the dimension, u the unit roundoff; we take c = 4). So W̃(λ) ⪰ −β I with
//! β = max(0, ‖E‖ − μ). A shift of the whole matrix is not a dual move (λ only enters the
//! rotation block), so it is turned into one through the Schur complement of L (eq. (38)):
//! from W̃(λ) + βI ⪰ 0,
//!
//! ```text
//! M − diag(λ) + βI − S̃*(L + βI)⁻¹S̃ ⪰ 0   and   S̃*(L⁻¹ − (L + βI)⁻¹)S̃ ≼ β ‖S̃‖² / λ_min(L)² I,
//! ```
//!
//! so M − diag(λ − t·1) ⪰ 0 for t = β (1 + ‖S̃‖²_F / λ_min(L)²), i.e. λ − t·1 is dual feasible
//! (W̃(λ − t1) ⪰ 0) and `lower_bound = Σλ − n·t` holds. λ_min(L) is itself taken
//! conservatively (its computed value minus its own error allowance). When μ ≥ ‖E‖, t = 0.
//!
//! That t is often pessimistic (‖S̃‖²/λ_min(L)² is large for long chains), so smaller shifts
//! s are tried directly on the equilibrated matrix D W̃(λ − s1) D (D = diag(W̃_kk^(−1/2)), PSD
//! exactly when W̃(λ − s1) is): if its computed smallest eigenvalue is at least its own rounding
//! allowance, W̃(λ − s1) ⪰ 0 and the bound Σλ − n·s holds. The better of the two bounds is
//! reported.
//!
//! Both rest on the eigensolver's backward error taken as c·d·u·‖W̃(λ)‖_F, a model rather than a
//! theorem with these constants: [`crate::dual::algorithm1`] proves the shift found here again,
//! by a factorization whose residual is measured
//! ([`crate::certify::SparseCertifier::prove_shift`]).

use crate::linalg::eigen::{hermitian_eigen, hermitian_eigenvalues};
use crate::problem::matrix::PoseGraphMatrix;
use faer::{Mat, c64};

/// A proven lower bound on f* from a candidate λ.
#[derive(Debug, Clone)]
pub struct DualBound {
    /// Σλ − n·t: a lower bound on the optimal cost f*.
    pub lower_bound: f64,
    /// The shift t applied to every λ_i to make it provably dual feasible.
    pub shift: f64,
    /// Eigenvalues of W̃(λ), ascending.
    pub eigenvalues: Vec<f64>,
    /// Their eigenvectors (columns), in the same order.
    pub eigenvectors: Mat<c64>,
}

/// The allowance c·d·u·‖A‖_F for the eigenvalues of a d x d Hermitian A.
fn eigen_error(a: &Mat<c64>) -> f64 {
    let fro: f64 = (0..a.nrows())
        .flat_map(|r| (0..a.ncols()).map(move |c| (r, c)))
        .map(|(r, c)| a[(r, c)].norm_sqr())
        .sum::<f64>()
        .sqrt();
    4.0 * a.nrows() as f64 * f64::EPSILON * fro
}

/// The bound proven by λ for the graph of `matrix` (dense computation, for small graphs).
/// `None` if the graph is disconnected (L singular).
pub fn dual_bound(matrix: &PoseGraphMatrix, lambda: &[f64]) -> Option<DualBound> {
    let n = matrix.n;
    let penalized = matrix.penalized_dense(lambda);
    let (eigenvalues, eigenvectors) = hermitian_eigen(&penalized);
    let beta = (eigen_error(&penalized) - eigenvalues[0]).max(0.0);
    let schur_shift = if beta == 0.0 || matrix.positions() == 0 {
        beta
    } else {
        let (l, s, _) = matrix.blocks();
        let lc = Mat::from_fn(l.nrows(), l.ncols(), |a, b| c64::new(l[(a, b)], 0.0));
        let l_min = hermitian_eigenvalues(&lc)[0] - eigen_error(&lc);
        if l_min <= 0.0 {
            return None;
        }
        let s_fro2: f64 = (0..s.nrows())
            .flat_map(|r| (0..s.ncols()).map(move |c| (r, c)))
            .map(|(r, c)| s[(r, c)].norm_sqr())
            .sum();
        beta * (1.0 + s_fro2 / (l_min * l_min))
    };
    // Direct shifts, cheaper than t when they work. They are tested on the equilibrated matrix
    // D W̃(λ − s1) D, D = diag(W̃_kk^(-1/2)), which is PSD exactly when W̃(λ − s1) is: its
    // rounding allowance is relative to entries of order one, so the null vectors of graphs
    // whose positions dwarf their rotations (metres against unit complex numbers) need no
    // large shift.
    let mut shift = schur_shift;
    if beta > 0.0 {
        let w = matrix.dense();
        let scale: Vec<f64> = (0..w.nrows())
            .map(|k| 1.0 / w[(k, k)].re.max(f64::MIN_POSITIVE).sqrt())
            .collect();
        let equilibrated = |s: f64| {
            let moved: Vec<f64> = lambda.iter().map(|l| l - s).collect();
            let a = matrix.penalized_dense(&moved);
            Mat::from_fn(a.nrows(), a.ncols(), |r, c| {
                a[(r, c)] * (scale[r] * scale[c])
            })
        };
        // A shift so large that the equilibrated matrix overflows proves nothing (and the
        // eigensolver would not converge on it).
        let proves = |s: f64| {
            let a = equilibrated(s);
            let error = eigen_error(&a);
            error.is_finite() && hermitian_eigenvalues(&a)[0] >= error
        };
        // The smallest diagonal scale of the rotation block converts an allowance on the
        // equilibrated matrix into a shift of λ.
        let r_min = scale[matrix.positions()..]
            .iter()
            .fold(f64::INFINITY, |m, &v| m.min(v));
        let base = eigen_error(&equilibrated(0.0)) / (r_min * r_min);
        if proves(0.0) {
            shift = 0.0;
        } else {
            for k in 0..=14 {
                let s = base * 10f64.powi(k);
                if s >= shift {
                    break;
                }
                if proves(s) {
                    shift = s;
                    break;
                }
            }
        }
    }
    let lower_bound = lambda.iter().sum::<f64>() - n as f64 * shift;
    Some(DualBound {
        lower_bound,
        shift,
        eigenvalues,
        eigenvectors,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, Pose2, PoseGraph, SymMat3};
    use crate::problem::matrix::cost;
    use crate::problem::weights::{Weights, edge_weights};

    fn cycle(noise: f64) -> PoseGraph {
        let n = 6;
        let step = Pose2::new(1.0, 0.0, std::f64::consts::TAU / n as f64);
        let edges = (0..n)
            .map(|k| {
                let mut m = step;
                m.x += noise * (k as f64 - 2.5);
                Edge {
                    i: k,
                    j: (k + 1) % n,
                    measurement: m,
                    noise: SymMat3::IDENTITY,
                }
            })
            .collect();
        let mut g = PoseGraph::with_edges(vec![Pose2::IDENTITY; n], edges);
        g.initialize_spanning_tree();
        g
    }

    #[test]
    fn lambda_zero_bounds_by_zero_and_infeasible_lambda_is_shifted() {
        // λ = 0 is always dual feasible (W̃ ⪰ 0): the bound is 0, up to the rounding shift.
        let g = cycle(0.2);
        let w = edge_weights(&g, Weights::Unit).unwrap();
        let m = PoseGraphMatrix::new(&g, &w);
        let b = dual_bound(&m, &[0.0; 6]).unwrap();
        assert!(
            b.lower_bound <= 0.0 && b.lower_bound > -1e-9,
            "{}",
            b.lower_bound
        );
        // A λ far outside the feasible set is shifted back until W̃(λ − t1) ⪰ 0; whatever λ,
        // the bound never exceeds a feasible point's cost (weak duality (32)).
        let f = cost(&g, &w, &g.poses);
        for big in [1.0, 10.0, 100.0] {
            let b = dual_bound(&m, &[big; 6]).unwrap();
            assert!(b.lower_bound <= f, "{big}: {} > {f}", b.lower_bound);
            let shifted: Vec<f64> = vec![big - b.shift; 6];
            let ev = crate::linalg::eigen::hermitian_eigenvalues(&m.penalized_dense(&shifted));
            assert!(ev[0] >= -1e-9, "{ev:?}");
        }
    }
}
