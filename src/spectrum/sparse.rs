//! Eigenvalues of the pose graph matrices: W̃ (eq. (24)), the penalized matrix W̃(λ*)
//! (Sec. 4.1) and M (eq. (38)), and the count of eigenvalues at zero (the SZEP, Prop. 10).
//! Dense for small graphs (all eigenvalues, [`hermitian_eigenvalues`]); sparse for large ones
//! (the smallest few, [`sparse_spectra`], with λ from the scalable solver,
//! [`scalable_spectrum`]).

use crate::certify::szep::{near_zero, zero_threshold};
use crate::error::Error;
use crate::graph::PoseGraph;
use crate::linalg::subspace::{Pencil, SubspaceOptions, smallest_eigenvalues};
use crate::problem::rank_p::Problem;
use crate::problem::weights::EdgeWeight;
use crate::staircase::{StaircaseOptions, solve_anchored};
use faer::{Mat, c64};

/// The smallest eigenvalues of the three matrices of a connected graph, computed sparse
/// ([`sparse_spectra`]).
#[derive(Debug, Clone)]
pub struct SparseSpectra {
    /// The smallest eigenvalues of W̃ (eq. (24)), ascending.
    pub eigenvalues: Vec<f64>,
    /// The smallest eigenvalues of W̃(λ) = W̃ − blkdiag(0, diag λ) (Sec. 4.1), ascending.
    pub penalized_eigenvalues: Vec<f64>,
    /// The smallest eigenvalues of M = Q̃ − S̃* L⁻¹ S̃ (eq. (38)), ascending.
    pub rotation_eigenvalues: Vec<f64>,
    /// Whether the three subspace iterations converged ([`crate::linalg::subspace`]).
    pub converged: bool,
}

/// The `count` smallest eigenvalues of W̃, of W̃(λ) and of M of a connected graph (W̃ anchored at
/// pose 0 as in [`PoseGraphMatrix::new`]; `lambda` one multiplier per pose in the graph's
/// order), without dense matrices: one sparse factorization per matrix and shift-invert
/// subspace iteration ([`crate::linalg::subspace`]). M is the pencil (W̃, blkdiag(0, I)), never formed.
pub fn sparse_spectra(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    lambda: &[f64],
    count: usize,
) -> Result<SparseSpectra, Error> {
    let problem = Problem::new(graph, weights);
    let n = problem.n;
    let positions = problem.positions();
    assert_eq!(lambda.len(), n, "one multiplier per pose");
    let dim = problem.rows();
    let order = problem.row_order();
    let overflow = || {
        Error::Invalid(
            "the pose graph matrix has entries that overflow a 64-bit float: the weighted squared translations of the edges at one pose add up to more than 1.8e308".into(),
        )
    };
    if lambda.iter().any(|l| !l.is_finite()) {
        return Err(Error::Invalid(
            "the multipliers λ are not all finite".into(),
        ));
    }
    let upper: Vec<(usize, usize, c64)> = problem.matrix.upper_entries().collect();
    let penalized: Vec<(usize, usize, c64)> = upper
        .iter()
        .map(|&(r, c, v)| {
            if r == c && r >= positions {
                (r, c, v - c64::new(lambda[r - positions], 0.0))
            } else {
                (r, c, v)
            }
        })
        .collect();
    let options = SubspaceOptions::default();
    let w_form = |z: &Mat<c64>| edge_form(&problem, None, z);
    let wl_form = |z: &Mat<c64>| edge_form(&problem, Some(lambda), z);
    let pencil = |upper, rows, form| Pencil {
        dim,
        upper,
        rows,
        order: &order,
        form: Some(form),
    };
    let w = smallest_eigenvalues(&pencil(&upper, 0..dim, &w_form), count, &options)
        .map_err(|_| overflow())?;
    let wl = smallest_eigenvalues(&pencil(&penalized, 0..dim, &wl_form), count, &options)
        .map_err(|_| overflow())?;
    let m = smallest_eigenvalues(&pencil(&upper, positions..dim, &w_form), count, &options)
        .map_err(|_| crate::problem::checks::singular_laplacian(graph, weights))?;
    Ok(SparseSpectra {
        converged: w.converged && wl.converged && m.converged,
        eigenvalues: w.values,
        penalized_eigenvalues: wl.values,
        rotation_eigenvalues: m.values,
    })
}

/// Z*W̃Z for a block Z = [P; Y] ((2n−1) x b), edge by edge (Prop. 5: x̃*W̃x̃ = f):
/// Σ_e τ ε_t*ε_t + κ ε_r*ε_r with the residual rows ε_t = P_j − P_i − Δ Y_i and
/// ε_r = Y_j − R Y_i (P_0 = 0, the anchor), less Y* diag(λ) Y for W̃(λ). A sum of positive
/// semidefinite terms for W̃ and M, formed from differences: the small eigenvalues of a long
/// trajectory keep their relative accuracy, where products with the assembled W̃ would lose
/// u·‖W̃‖ to rounding.
fn edge_form(problem: &Problem, lambda: Option<&[f64]>, z: &Mat<c64>) -> Mat<c64> {
    let b = z.ncols();
    let zero = c64::new(0.0, 0.0);
    let mut h = Mat::<c64>::zeros(b, b);
    let (mut et, mut er) = (vec![zero; b], vec![zero; b]);
    for t in &problem.terms {
        let yi = problem.rotation_row(t.i);
        let yj = problem.head_rotation_row(t);
        let (pi, pj) = (problem.position_row(t.i), problem.head_position_row(t));
        for c in 0..b {
            let p = |row: Option<usize>| row.map_or(zero, |r| z[(r, c)]);
            et[c] = p(pj) - p(pi) - t.delta * z[(yi, c)];
            // An observation has no rotation part (κ = 0).
            er[c] = yj.map_or(zero, |yj| z[(yj, c)] - t.rot * z[(yi, c)]);
        }
        for c in 0..b {
            let (tc, rc) = (et[c] * t.tau, er[c] * t.kappa);
            for a in 0..b {
                h[(a, c)] += et[a].conj() * tc + er[a].conj() * rc;
            }
        }
    }
    if let Some(lambda) = lambda {
        for (k, &l) in lambda.iter().enumerate() {
            let row = problem.rotation_row(k);
            for c in 0..b {
                let yc = z[(row, c)] * l;
                for a in 0..b {
                    h[(a, c)] -= z[(row, a)].conj() * yc;
                }
            }
        }
    }
    h
}

/// What `pgo-spectrum` reports of a connected graph too large for the dense SDP: the dual side
/// from the scalable solver ([`crate::staircase`]) in place of the dual SDP (31), and the
/// smallest eigenvalues ([`sparse_spectra`]).
#[derive(Debug, Clone)]
pub struct ScalableSpectrum {
    pub spectra: SparseSpectra,
    /// λ at the solver's rank-1 estimate (the first-order multipliers), one per pose in the
    /// graph's order: λ* when the certificate holds.
    pub lambda: Vec<f64>,
    /// Σλ.
    pub dual_objective: f64,
    /// The proven lower bound on f* ([`crate::staircase::StaircaseSolution::lower_bound`]).
    pub lower_bound: f64,
    /// Whether the certificate proved the estimate optimal within 1e-6 relative.
    pub certified: bool,
    /// The eigenvalues of W̃(λ) at zero: the certificate's count (one, proven, when it isolated
    /// the estimate's eigenvalue; else W̃(λ)'s inertia below its resolution), or, when its LDLᴴ
    /// met a zero pivot, those of the computed ones below the zero threshold of
    /// [`ZERO_FACTOR`] with the certificate's gap cost − lower bound.
    pub near_zero: usize,
    /// The SZEP (Prop. 10): the certificate counted exactly one eigenvalue at zero.
    pub szep: bool,
}

/// [`ScalableSpectrum`] of a connected graph: the staircase with its default options, then the
/// `count` smallest eigenvalues of W̃, W̃(λ) and M.
pub fn scalable_spectrum(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    count: usize,
) -> Result<ScalableSpectrum, Error> {
    crate::problem::checks::check_edge_terms(graph, weights, weights)?;
    let (solution, anchored) =
        solve_anchored(graph, weights, &StaircaseOptions::default(), &mut |_| {})
            .ok_or_else(|| crate::problem::checks::singular_laplacian(graph, weights))?;
    let lambda = anchored.graph_order(&solution.lambda);
    crate::progress::phase("eigenvalues");
    let spectra = sparse_spectra(graph, weights, &lambda, count)?;
    let near_zero = solution.near_zero.unwrap_or_else(|| {
        let gap = (solution.cost - solution.lower_bound).max(0.0);
        let threshold = zero_threshold(&anchored.problem.matrix, gap);
        near_zero(&spectra.penalized_eigenvalues, threshold)
    });
    Ok(ScalableSpectrum {
        szep: solution.near_zero == Some(1),
        dual_objective: lambda.iter().fold(0.0, |a, b| a + b),
        lambda,
        lower_bound: solution.lower_bound,
        certified: solution.certified,
        near_zero,
        spectra,
    })
}
