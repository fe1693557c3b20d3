//! The roundings of a relaxed solution to an estimate (Sec. 5): every one yields unit-modulus
//! rotations, and the positions are then the best ones for them, ρ̃ = −L⁻¹S̃r̃ (eq. (24)).

use crate::graph::{Pose2, PoseGraph};
use crate::problem::gauge::{move_to_anchor, place_or_origin};
use crate::problem::matrix::PoseGraphMatrix;
use faer::c64;

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
    /// Randomized rounding of X*: ξ ~ CN(0, X*), r_i = ξ_i/|ξ_i| (So, Zhang and Ye 2007), then
    /// polished under f (`pgo::solve`, where the SZEP fails).
    Randomized,
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
        // Landmarks (as points) follow the poses, as in every estimate of a landmark graph.
        let landmarks = tree
            .landmarks
            .positions
            .iter()
            .map(|&[x, y]| Pose2::new(x, y, 0.0));
        let mut moved: Vec<Pose2> = tree
            .poses
            .iter()
            .copied()
            .chain(landmarks)
            .map(|p| Pose2::from_isometry(&(frame * p.to_isometry())))
            .collect();
        moved[0] = at;
        moved
    };
    place_or_origin(anchor, place)
}
