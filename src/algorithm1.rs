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

use crate::certify::{DualBound, dual_bound};
use crate::error::Error;
use crate::graph::{Pose2, PoseGraph};
use crate::matrix::{PoseGraphMatrix, cost, rotation};
use crate::sdp::{DualSolution, SdpError};
use crate::spectrum::{hermitian_eigen, near_zero, zero_threshold};
use crate::weights::EdgeWeight;
use faer::{Mat, c64};
use std::time::Instant;

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
                let options = crate::sdp::ipm::IpmOptions {
                    tolerance,
                    ..Default::default()
                };
                let result = crate::sdp::ipm::solve(m.as_ref(), &options);
                if !matches!(result, Err(SdpError::NotConverged { .. })) {
                    return result;
                }
            }
            let options = crate::sdp::ipm::IpmOptions {
                tolerance: 1e-6,
                ..Default::default()
            };
            crate::sdp::ipm::solve_best_effort(m.as_ref(), &options)
        }
        #[cfg(feature = "clarabel-sdp")]
        SdpSolver::Clarabel => crate::sdp::clarabel::solve(m.as_ref()),
        #[cfg(not(feature = "clarabel-sdp"))]
        SdpSolver::Clarabel => Err(SdpError::Solver(
            "this build has no clarabel SDP solver (build with --features clarabel-sdp)".into(),
        )),
    }
}

/// How an estimate was obtained from the dual solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Rounding {
    /// Sec. 5.1: the scaled eigenvector of the single zero eigenvalue.
    SzepEigenvector,
    /// Sec. 5.2, eq. (46): the null-space method.
    NullSpace,
    /// Sec. 5.2: the eigenvector method, normalized entry by entry (Eig).
    Eigenvector,
    /// Sec. 6: rank-1 rounding of the SDP relaxation's X* (SDP).
    SdpRank1,
    /// A forest's optimum in closed form (f* = 0, Prop. 6): the measurements composed along the
    /// tree. Taken where the rounding of the relaxation ends above it, which happens when the
    /// weights span more than double precision resolves (κ 1e17 next to τ 1).
    SpanningTree,
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
    /// Eigenvalues at zero (see [`crate::spectrum::ZERO_FACTOR`]).
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
    let t = Instant::now();
    let dual = solve_dual(&m, solver).map_err(|e| Error::Invalid(e.to_string()))?;
    let sdp_seconds = t.elapsed().as_secs_f64();
    let bound =
        dual_bound(&matrix, &dual.lambda).ok_or_else(|| singular_laplacian(graph, weights))?;
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
    // The eigenvector of the smallest eigenvalue: the scaled solution with the SZEP (Sec. 5.1);
    // without it, the null-space method (46), or the eigenvector method (Eig, Sec. 5.2) where
    // (46) has no solution (a basis whose rotation rows lack full column rank, as with weights
    // 1 next to 1e200): an estimate all the same, which the proven bound still judges.
    let eigenvector = || (0..n).map(|k| bound.eigenvectors[(n - 1 + k, 0)]).collect();
    let (rotations, rounding): (Vec<c64>, _) = if szep {
        (eigenvector(), Rounding::SzepEigenvector)
    } else {
        let basis = Mat::from_fn(matrix.dim(), zeros, |r, c| bound.eigenvectors[(r, c)]);
        match crate::nullspace::null_space_method(basis.as_ref(), n - 1..2 * n - 1) {
            Ok(x) => (x[n - 1..].to_vec(), Rounding::NullSpace),
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

/// Refuses a graph whose edge terms τ|Δ|² + κ overflow a 64-bit float (the cost cannot be
/// evaluated), naming the edge by its ids; `original` are the weights as the user's graph has
/// them (for the message), `weights` those the matrices are built from.
pub fn check_edge_terms(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    original: &[EdgeWeight],
) -> Result<(), Error> {
    for ((e, w), o) in graph.edges.iter().zip(weights).zip(original) {
        let length = e.measurement.x.hypot(e.measurement.y);
        let term = w.tau * length * length + w.kappa;
        if !term.is_finite() {
            let mut weight = Vec::new();
            crate::io::format_f64(o.tau, &mut weight);
            return Err(Error::Invalid(format!(
                "edge {} -> {}: its translation of {length:e} m, squared and weighted by {}, overflows a 64-bit float, so the cost cannot be evaluated",
                graph.ids[e.i],
                graph.ids[e.j],
                String::from_utf8_lossy(&weight)
            )));
        }
    }
    Ok(())
}

/// W̃ of `graph` with `weights` and its rotation-only matrix M, or why they cannot be computed
/// in double precision: an edge's weighted squared translation τ|Δ|² overflows (named by its
/// ids, with `original`, the weights of the user's graph), or a sum of them does, or L is
/// singular ([`singular_laplacian`]).
pub fn matrices(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    original: &[EdgeWeight],
) -> Result<(PoseGraphMatrix, Mat<c64>), Error> {
    check_edge_terms(graph, weights, original)?;
    let matrix = PoseGraphMatrix::new(graph, weights);
    // The proven bound takes the Frobenius norm of W̃(λ) (crate::certify): its square must be
    // finite, so no entry may reach about 1e154. With the weights normalized to at most about
    // one, only translations that long do that; the longest is named.
    let dense = matrix.dense();
    let fro2: f64 = (0..dense.ncols())
        .flat_map(|c| (0..dense.nrows()).map(move |r| (r, c)))
        .map(|(r, c)| dense[(r, c)].norm_sqr())
        .sum();
    if !fro2.is_finite() {
        let (e, length) = graph
            .edges
            .iter()
            .map(|e| (e, e.measurement.x.hypot(e.measurement.y)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("a graph with entries has edges");
        return Err(Error::Invalid(format!(
            "edge {} -> {}: its translation of {length:e} m makes entries of the pose graph matrix too large for the eigenvalue bounds in double precision (their squares overflow); rescale the translations",
            graph.ids[e.i], graph.ids[e.j]
        )));
    }
    let finite = |m: &Mat<c64>| {
        (0..m.ncols())
            .all(|c| (0..m.nrows()).all(|r| m[(r, c)].re.is_finite() && m[(r, c)].im.is_finite()))
    };
    if !finite(&dense) {
        return Err(Error::Invalid(
            "the pose graph matrix overflows a 64-bit float: the weighted squared translations of the edges at one pose add up to more than 1.8e308".into(),
        ));
    }
    let m = matrix
        .rotation_matrix()
        .ok_or_else(|| singular_laplacian(graph, original))?;
    if !finite(&m) {
        return Err(Error::Invalid(
            "the rotation matrix M = Q - S* L^-1 S of this graph overflows a 64-bit float: its translations are too long for its weights".into(),
        ));
    }
    Ok((matrix, m))
}

/// Why the anchored Laplacian L of `graph` could not be factored: the graph is disconnected, or
/// (connected, so L ≻ 0 in exact arithmetic) its translation weights span a range that double
/// precision cannot resolve, e.g. 1e-9 next to 1e9: light edges then vanish in the rounding of
/// the heavy ones.
pub fn singular_laplacian(graph: &PoseGraph, weights: &[EdgeWeight]) -> Error {
    if graph.connected_components().1 != 1 {
        return Error::Invalid("the graph is not connected".into());
    }
    let (lo, hi) = weights.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), w| {
        (lo.min(w.tau), hi.max(w.tau))
    });
    Error::Invalid(format!(
        "the weighted Laplacian of this connected graph is numerically singular: its translation weights range from {lo:e} to {hi:e}, too wide for double precision (edges that light are lost in the rounding of the heavy ones); rescale the information matrices or use --weights unit"
    ))
}

/// Poses from (unnormalized) rotation entries: each rotation normalized to unit modulus, the
/// positions optimal for them (ρ̃ = −L⁻¹S̃r̃), then the whole estimate moved rigidly so that
/// pose 0 is `anchor` (f is invariant to that). A zero entry becomes the rotation 1.
pub fn estimate_from_rotations(matrix: &PoseGraphMatrix, r: &[c64], anchor: Pose2) -> Vec<Pose2> {
    let unit: Vec<c64> = r
        .iter()
        .map(|z| {
            let m = z.norm();
            if m > 0.0 && m.is_finite() {
                z / m
            } else {
                c64::new(1.0, 0.0)
            }
        })
        .collect();
    let rho = matrix
        .optimal_positions(&unit)
        .expect("the graph is connected");
    let x: Vec<c64> = rho.into_iter().chain(unit).collect();
    move_to_anchor(&matrix.poses(&x), anchor)
}

/// The estimate moved rigidly (f is invariant to that) so that pose 0 is exactly `anchor`.
pub fn move_to_anchor(poses: &[Pose2], anchor: Pose2) -> Vec<Pose2> {
    // Rotate by φ so that θ_0 becomes the anchor's, then translate p_0 to the anchor's. φ is
    // taken from the anchor's angle reduced to [-π, π] (if outside, by the rotation e^{iθ}, whose
    // argument reduction is exact): an anchor angle of 1e30 added to every θ would erase the
    // differences between them.
    let anchor_angle = if anchor.theta.abs() <= std::f64::consts::PI {
        anchor.theta
    } else {
        rotation(anchor.theta).arg()
    };
    let phi = anchor_angle - poses[0].theta;
    let turn = rotation(phi);
    let p0 = c64::new(poses[0].x, poses[0].y);
    let place = |at: Pose2| -> Vec<Pose2> {
        let mut moved: Vec<Pose2> = poses
            .iter()
            .map(|p| {
                let q = turn * (c64::new(p.x, p.y) - p0);
                Pose2::new(at.x + q.re, at.y + q.im, p.theta + phi)
            })
            .collect();
        // Exactly, not up to the rounding of θ_0 + φ.
        moved[0] = at;
        moved
    };
    place_or_origin(anchor, place)
}

/// `place(anchor)`, or, where positions would overflow next to the anchor's (near 1.8e308),
/// `place` with pose 0 at the origin and the anchor's heading (f does not depend on where the
/// estimate is).
fn place_or_origin(anchor: Pose2, place: impl Fn(Pose2) -> Vec<Pose2>) -> Vec<Pose2> {
    let moved = place(anchor);
    if moved.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
        return moved;
    }
    place(Pose2::new(0.0, 0.0, anchor.theta))
}

/// The measurements composed along a spanning tree from pose 0, which keeps the anchor's pose
/// (the others placed from the origin if they would overflow next to it): for a forest, an
/// optimum (f* = 0).
pub fn spanning_tree_estimate(graph: &PoseGraph) -> Vec<Pose2> {
    let mut tree = graph.clone();
    tree.initialize_spanning_tree();
    let anchor = graph.poses[0];
    let place = |at: Pose2| -> Vec<Pose2> {
        // Pose 0 is the root, at the identity: x_k' = at · x_k.
        let frame = Pose2::new(at.x, at.y, at.theta).to_isometry();
        let mut moved: Vec<Pose2> = tree
            .poses
            .iter()
            .map(|p| Pose2::from_isometry(&(frame * p.to_isometry())))
            .collect();
        moved[0] = at;
        moved
    };
    place_or_origin(anchor, place)
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
            (0..n).map(|k| vectors[(n - 1 + k, 0)]).collect()
        }
    };
    estimate_from_rotations(matrix, &rotations, anchor)
}
