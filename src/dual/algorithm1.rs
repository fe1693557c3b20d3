//! The paper's Algorithm 1 (Sec. 5.3) for small graphs: solve the dual SDP (31), test the single
//! zero eigenvalue property (SZEP, Prop. 10) of the penalized pose graph matrix W̃(λ*), and
//! - SZEP: scale the eigenvector of the zero eigenvalue (Sec. 5.1, Corollary 1): the optimum,
//!   proven by the dual bound;
//! - otherwise: the null-space method (46) (Sec. 5.2), a possibly suboptimal estimate, with the
//!   dual bound still bounding its suboptimality.
//!
//! Also the paper's comparison roundings (Sec. 5.2, Sec. 6): the eigenvector method (Eig) and
//! rank-1 rounding of the SDP relaxation (37) (SDP). Every rounding yields unit-modulus
//! rotations; positions are then the best ones for those rotations, ρ̃ = −L⁻¹S̃r̃ (in the SZEP
//! case they equal the scaled eigenvector's; otherwise this can only lower the cost).
//! A graph with several connected components is solved component by component (the paper's
//! remark after Assumption 1).

use crate::certify::szep::{near_zero, zero_threshold};
use crate::certify::{DualBound, SparseCertifier, dual_bound};
use crate::dual::rounding::{Rounding, estimate_from_rotations, spanning_tree_estimate};
use crate::dual::sdp::DualSolution;
use crate::dual::solver::{SdpSolver, solve_dual};
use crate::error::Error;
use crate::graph::{Pose2, PoseGraph};
use crate::linalg::eigen::hermitian_eigen;
use crate::problem::checks::{matrices, singular_laplacian};
use crate::problem::matrix::{PoseGraphMatrix, cost};
use crate::problem::rank_p::Problem;
use crate::problem::weights::EdgeWeight;
use faer::{Mat, c64};
use std::time::Instant;

/// Largest graph (pgo-solve --method sdp) or component (pgo-spectrum) the dense SDP path of
/// Algorithm 1 takes; pgo-spectrum analyses larger components sparse.
pub const DENSE_MAX_POSES: usize = 2000;

/// Refuses graphs too large for the dense SDP path (`tool` names the tool and the flag that
/// asked for it), with a message saying so and what to use instead.
pub fn check_dense_size(graph: &PoseGraph, tool: &str) -> crate::Result<()> {
    if graph.num_poses() > DENSE_MAX_POSES {
        return Err(Error::Invalid(format!(
            "{tool}: {} poses is more than the {DENSE_MAX_POSES} the dense SDP path handles; --method auto or staircase solves it with the scalable solver",
            graph.num_poses()
        )));
    }
    Ok(())
}

/// Algorithm 1 on one connected graph.
#[derive(Debug, Clone)]
pub struct ComponentSolution {
    /// The estimate, in the input's gauge (pose 0 where the input has it).
    pub poses: Vec<Pose2>,
    /// f at the estimate.
    pub cost: f64,
    /// A proven lower bound on f* (from λ*, see [`crate::certify`]).
    pub lower_bound: f64,
    /// d* = Σλ*, as the solver returned it.
    pub dual_objective: f64,
    pub lambda: Vec<f64>,
    /// Eigenvalues of W̃(λ*), ascending.
    pub eigenvalues: Vec<f64>,
    /// Eigenvalues at zero (see [`crate::certify::szep::ZERO_FACTOR`]).
    pub near_zero: usize,
    pub szep: bool,
    pub rounding: Rounding,
    /// The dual SDP's solution (with X* for SDP rounding).
    pub dual: DualSolution,
    pub sdp_seconds: f64,
    /// The matrix, for further roundings.
    pub matrix: PoseGraphMatrix,
}

/// The dual side of Algorithm 1 on a connected graph, in units of the normalized weights:
/// the weights divided by `scale`, the power of two nearest the lightest weight. W̃, M, λ*, the
/// bound and the eigenvalues are linear in the weights, so multiplying them by `scale` (exactly)
/// gives those of the graph's own weights, the bound still proven; the eigenvectors are the same.
/// The solver's tolerances and the SZEP's zero test are relative with an absolute floor (a graph
/// with f* = 0 has no relative gap), which then stands for the lightest edge: the same on a graph
/// whose information matrices are all 1e-9 or all 1e9 as on one whose are 1, and no edge's share
/// of W̃(λ*) falls below it (with the largest weight as the unit, the eigenvalues of a tree with
/// weights 1 and 2e8 dropped under the zero threshold and it lost the SZEP).
pub struct DualAnalysis {
    /// W̃ of the normalized weights.
    pub matrix: PoseGraphMatrix,
    /// M of the normalized weights.
    pub m: Mat<c64>,
    pub dual: DualSolution,
    pub bound: DualBound,
    /// Eigenvalues of W̃(λ*) at zero.
    pub near_zero: usize,
    pub sdp_seconds: f64,
    pub scale: f64,
}

/// The power of two the weights are divided by (see [`DualAnalysis`]): the one nearest the
/// lightest weight, unless the heaviest would then exceed 2^400 (beyond which squared entries of
/// W̃ overflow for translations of a few metres; such graphs get the heaviest at 2^400 and their
/// lightest edges below the tolerances).
fn normalization(weights: &[EdgeWeight]) -> f64 {
    let (lightest, heaviest) = weights
        .iter()
        .flat_map(|w| [w.tau, w.kappa])
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if heaviest == 0.0 {
        return 1.0;
    }
    let k = (lightest.log2().round() as i32).max(heaviest.log2().ceil() as i32 - 400);
    2f64.powi(k.clamp(-1000, 1000))
}

/// Solves the dual SDP of a connected graph and proves its bound (see [`DualAnalysis`]).
pub fn analyze(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    solver: SdpSolver,
) -> Result<DualAnalysis, Error> {
    let scale = normalization(weights);
    let normalized: Vec<EdgeWeight> = weights
        .iter()
        .map(|w| EdgeWeight {
            tau: w.tau / scale,
            kappa: w.kappa / scale,
        })
        .collect();
    let (matrix, m) = matrices(graph, &normalized, weights)?;
    crate::progress::phase("dual SDP");
    let t = Instant::now();
    let dual = solve_dual(&m, solver).map_err(|e| Error::Invalid(e.to_string()))?;
    let sdp_seconds = t.elapsed().as_secs_f64();
    crate::progress::phase("certificate");
    let bound =
        dual_bound(&matrix, &dual.lambda).ok_or_else(|| singular_laplacian(graph, weights))?;
    let bound = proven(graph, &normalized, &dual.lambda, bound);
    let threshold = zero_threshold(&matrix, dual.primal_objective - dual.dual_objective);
    let near_zero = near_zero(&bound.eigenvalues, threshold);
    Ok(DualAnalysis {
        matrix,
        m,
        dual,
        bound,
        near_zero,
        sdp_seconds,
        scale,
    })
}

/// The dense bound's shift t (found from eigenvalues, under their solver's backward-error model:
/// [`crate::certify::dense`]) proven outright: W̃(λ − t1) ⪰ 0 by the sparse certificate's
/// shifted LLᴴ with its residual measured and W̃'s assembly rounding allowed for
/// ([`SparseCertifier::prove_shift`]), at t or, where that fails, at t doubled (from the
/// eigenvalues' resolution where t is 0), at most 64 times. The bound is then Σλ − n·t less its
/// rounding; with no shift proven, 0 (f ≥ 0 always).
fn proven(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    lambda: &[f64],
    mut bound: DualBound,
) -> DualBound {
    let problem = Problem::new(graph, weights);
    let mut certifier = SparseCertifier::new(&problem.matrix.upper, &problem.row_order());
    let mut shift = bound.shift;
    for _ in 0..64 {
        if let Some(lower) = certifier.prove_shift(&problem, lambda, shift) {
            bound.shift = shift;
            bound.lower_bound = lower;
            return bound;
        }
        shift = if shift > 0.0 {
            2.0 * shift
        } else {
            certifier.eigenvalue_resolution(lambda)
        };
        if !shift.is_finite() {
            break;
        }
    }
    bound.shift = f64::INFINITY;
    bound.lower_bound = 0.0;
    bound
}

/// Runs Algorithm 1 on a connected graph (the dual side by [`analyze`]); every number is in
/// the units of `weights`.
pub fn solve_connected(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    solver: SdpSolver,
) -> Result<ComponentSolution, Error> {
    let DualAnalysis {
        matrix,
        dual,
        bound,
        near_zero: zeros,
        sdp_seconds,
        scale,
        ..
    } = analyze(graph, weights, solver)?;
    // Prop. 9: W̃(λ*) always has a zero eigenvalue; the SZEP asks that it be simple.
    let szep = zeros <= 1;
    let n = graph.num_poses();
    let positions = matrix.positions();
    // The eigenvector of the smallest eigenvalue: the scaled solution with the SZEP (Sec. 5.1);
    // without it, the null-space method (46), or the eigenvector method (Eig, Sec. 5.2) where
    // (46) has no solution (a basis whose rotation rows lack full column rank, as with weights
    // 1 next to 1e200): an estimate all the same, which the proven bound still judges.
    let eigenvector = || {
        (0..n)
            .map(|k| bound.eigenvectors[(positions + k, 0)])
            .collect()
    };
    let (rotations, rounding): (Vec<c64>, _) = if szep {
        (eigenvector(), Rounding::SzepEigenvector)
    } else {
        let basis = Mat::from_fn(matrix.dim(), zeros, |r, c| bound.eigenvectors[(r, c)]);
        match crate::dual::nullspace::null_space_method(basis.as_ref(), positions..matrix.dim()) {
            Ok(x) => (x[positions..].to_vec(), Rounding::NullSpace),
            Err(_) => (eigenvector(), Rounding::Eigenvector),
        }
    };
    let mut poses = estimate_from_rotations(&matrix, &rotations, graph.poses[0]);
    let mut rounding = rounding;
    if graph.is_forest() {
        let tree = spanning_tree_estimate(graph);
        if cost(graph, weights, &tree) < cost(graph, weights, &poses) {
            (poses, rounding) = (tree, Rounding::SpanningTree);
        }
    }
    let mut dual = dual;
    dual.lambda.iter_mut().for_each(|l| *l *= scale);
    dual.dual_objective *= scale;
    dual.primal_objective *= scale;
    Ok(ComponentSolution {
        cost: cost(graph, weights, &poses),
        poses,
        lower_bound: bound.lower_bound * scale,
        dual_objective: dual.dual_objective,
        lambda: dual.lambda.clone(),
        eigenvalues: bound.eigenvalues.iter().map(|e| e * scale).collect(),
        near_zero: zeros,
        szep,
        rounding,
        dual,
        sdp_seconds,
        matrix: if scale == 1.0 {
            matrix
        } else {
            PoseGraphMatrix::new(graph, weights)
        },
    })
}

/// The comparison roundings of Sec. 5.2 and Sec. 6 from a solved component: the eigenvector
/// method (Eig) and rank-1 rounding of X* (SDP).
pub fn comparison_estimate(
    solution: &ComponentSolution,
    method: Rounding,
    anchor: Pose2,
) -> Vec<Pose2> {
    let matrix = &solution.matrix;
    let n = matrix.n;
    let rotations: Vec<c64> = match method {
        Rounding::SdpRank1 => {
            // X* ≈ σ₁ u₁u₁*: the rotations are √σ₁ u₁ (positions are re-solved anyway).
            let (values, vectors) = hermitian_eigen(&solution.dual.x);
            let top = values.len() - 1;
            let s = values[top].max(0.0).sqrt();
            (0..n).map(|k| vectors[(k, top)] * s).collect()
        }
        _ => {
            let penalized = matrix.penalized_dense(&solution.lambda);
            let (_, vectors) = hermitian_eigen(&penalized);
            (0..n)
                .map(|k| vectors[(matrix.positions() + k, 0)])
                .collect()
        }
    };
    estimate_from_rotations(matrix, &rotations, anchor)
}
