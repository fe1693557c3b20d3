//! The best estimate where the relaxation is not exact: every rounding of the relaxed solutions
//! polished by the local solver under f, the lowest kept.
//!
//! Where the SZEP fails, X* of the SDP relaxation (37) (or the staircase's rank-p factor) has
//! rank above one, and no rounding of it is known to reach f*. The candidates, each polished by
//! rank-1 Riemannian Newton under the full objective f (eq. (8), positions optimal for the
//! rotations, eq. (24)) as the paper's Fig. 7 polishes its roundings with Gauss-Newton:
//! - the paper's own roundings: the null-space method (46), the eigenvector method (Eig) and
//!   rank-1 rounding of X* (Sec. 5.2, Sec. 6);
//! - randomized rounding of X*: ξ ~ CN(0, X*), r_i = ξ_i / |ξ_i|, the complex analogue of
//!   Goemans-Williamson's hyperplane rounding for the complex max-cut SDP that (37) is (So, Zhang
//!   and Ye, "On approximating complex quadratic optimization problems via semidefinite
//!   programming relaxations", Math. Program. 2007), with a seeded generator;
//! - the staircase's estimate: its rank-p point rounded by the top eigenvector of YᴴY, polished
//!   (Rosen et al., SE-Sync, IJRR 2019, Sec. 4.2, with ℂ in place of ℝ²).
//!
//! None of this changes the bound, which is proven on its own ([`crate::certify`]): the estimate
//! only gets closer to it.

use crate::dual::algorithm1::{ComponentSolution, comparison_estimate};
use crate::dual::rounding::{Rounding, estimate_from_rotations};
use crate::graph::{Pose2, PoseGraph};
use crate::linalg::eigen::hermitian_eigen;
use crate::linalg::rng::Rng;
use crate::problem::matrix::cost;
use crate::problem::weights::EdgeWeight;
use crate::staircase::init::OptimalPositions;
use crate::staircase::{Anchored, StaircaseOptions, optimize};
use faer::c64;

/// Randomized roundings of X* per component.
pub const RANDOM_ROUNDINGS: usize = 12;

/// An estimate and f there.
#[derive(Debug, Clone)]
pub struct Candidate {
    pub poses: Vec<Pose2>,
    pub cost: f64,
    /// How the relaxed solution was rounded (`None`: the staircase's estimate).
    pub rounding: Option<Rounding>,
}

/// Rank-1 Riemannian Newton under f from `poses` (positions optimal for the rotations);
/// `poses` themselves if that does not lower f.
pub fn polish(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    poses: Vec<Pose2>,
    options: &StaircaseOptions,
) -> (Vec<Pose2>, f64) {
    let before = cost(graph, weights, &poses);
    if graph.num_poses() < 2 {
        return (poses, before);
    }
    let anchored = Anchored::centered(graph, weights, &poses);
    let problem = &anchored.problem;
    let mut positions = OptimalPositions::new(problem);
    let start = anchored.point(&poses);
    let local = optimize(problem, positions.as_mut(), start, options, &mut |_| {});
    let polished = anchored.poses(&local.point, graph.poses[0]);
    let after = cost(graph, weights, &polished);
    if after < before {
        (polished, after)
    } else {
        (poses, before)
    }
}

/// The roundings of Algorithm 1's relaxed solution, polished (see the module docs), in a fixed
/// order: the one Algorithm 1 chose first.
pub fn sdp_candidates(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    solution: &ComponentSolution,
    options: &StaircaseOptions,
) -> Vec<Candidate> {
    let anchor = graph.poses[0];
    let mut rounded = vec![(solution.poses.clone(), solution.rounding)];
    for r in [Rounding::Eigenvector, Rounding::SdpRank1] {
        if r != solution.rounding {
            rounded.push((comparison_estimate(solution, r, anchor), r));
        }
    }
    // ξ = V diag(√σ) g with X* = V diag(σ) Vᴴ and g standard complex Gaussian: ξ ~ CN(0, X*).
    let x = &solution.dual.x;
    let n = x.nrows();
    if n > 1 && x.ncols() == n {
        let (values, vectors) = hermitian_eigen(x);
        let roots: Vec<f64> = values.iter().map(|v| v.max(0.0).sqrt()).collect();
        let mut rng = Rng::new(0x726f_756e_6469_6e67 ^ n as u64);
        for _ in 0..RANDOM_ROUNDINGS {
            let g: Vec<c64> = (0..n)
                .map(|_| c64::new(rng.normal(), rng.normal()) * std::f64::consts::FRAC_1_SQRT_2)
                .collect();
            let r: Vec<c64> = (0..n)
                .map(|i| (0..n).map(|k| vectors[(i, k)] * (roots[k] * g[k])).sum())
                .collect();
            rounded.push((
                estimate_from_rotations(&solution.matrix, &r, anchor),
                Rounding::Randomized,
            ));
        }
    }
    rounded
        .into_iter()
        .map(|(poses, rounding)| {
            let (poses, cost) = polish(graph, weights, poses, options);
            Candidate {
                poses,
                cost,
                rounding: Some(rounding),
            }
        })
        .collect()
}

/// The index of the lowest f (the first of equals).
pub fn lowest(candidates: &[Candidate]) -> usize {
    let mut best = 0;
    for (k, c) in candidates.iter().enumerate() {
        if c.cost < candidates[best].cost {
            best = k;
        }
    }
    best
}
