//! Trees: a connected component with one edge fewer than its poses (odometry alone, no loop
//! closure), solved and certified without an iteration or a factorization, planar and 3D.
//!
//! - The optimum composes the measurements outward from a root (Prop. 1, Appendix 8.1): every
//!   edge term vanishes, f* = 0.
//! - The certificate: λ = 0 is dual feasible, W̃(0) = W̃ ⪰ 0 as a sum of positive semidefinite edge
//!   terms, exactly and whatever the rounding of any matrix, and d(0) = 0 = f* (Prop. 11): the
//!   lower bound 0, the suboptimality of the estimate its own cost (rounding alone).
//! - The SZEP: W̃ = W̃(λ*) has a single zero eigenvalue (Prop. 6), so the relaxation's solution is
//!   the rank-one one of this estimate.
//! - In 3D (SE-Sync's problem) the same: the composition annihilates every term; Λ = 0 leaves
//!   S = Q ⪰ 0, a sum of edge terms, with d = 0 = f*; and Q, anchored, has exactly 3 zero
//!   eigenvalues: a vector of its kernel annihilates every term, so along the tree its value at
//!   one pose (1×3) fixes every other, and the relaxation's solution is this estimate's.

use super::{ComponentReport, Method, component_report};
use crate::graph::{Pose2, PoseGraph};
use crate::graph3::{Graph3, Pose3};
use crate::problem::gauge::move_to_anchor;
use crate::problem::matrix::cost;
use crate::problem::weights::EdgeWeight;

/// Whether `part`, a connected component, is a tree of poses: n − 1 edges (a connected graph
/// with no cycle, so no loop closure, parallel edge or self-loop) and no landmarks.
pub(super) fn is_tree(part: &PoseGraph) -> bool {
    part.landmarks.is_empty() && part.edges.len() + 1 == part.num_poses()
}

/// The optimum of a tree `part` (Prop. 1): its measurements composed from pose 0, which stays
/// where the input has it; and its report, certified where the cost of that composition, which
/// is all rounding, lies within `tolerance` of the bound 0 (Prop. 11).
pub(super) fn solve_tree(
    part: &PoseGraph,
    weights: &[EdgeWeight],
    tolerance: f64,
) -> (ComponentReport, Vec<Pose2>) {
    crate::progress::phase("tree: the measurements composed (Prop. 1)");
    let mut composed = part.clone();
    composed.initialize_spanning_tree();
    let poses = move_to_anchor(&composed.poses, part.poses[0]);
    let f = cost(part, weights, &poses);
    let report = component_report(part, Method::Tree, f, 0.0, true, true, 1, tolerance);
    (report, poses)
}

/// Whether `part`, a connected 3D component, is a tree: n − 1 edges.
pub(super) fn is_tree3(part: &Graph3) -> bool {
    part.edges.len() + 1 == part.num_poses()
}

/// The optimum of a 3D tree `part`: its measurements composed from pose `root`, which stays
/// exactly where the input has it, each pose in the graph's form (`form_of`).
pub(super) fn compose3(
    part: &Graph3,
    root: usize,
    form_of: impl Fn(&nalgebra::Isometry3<f64>) -> Pose3,
) -> Vec<Pose3> {
    crate::progress::phase("tree: the measurements composed (Prop. 1)");
    let n = part.num_poses();
    let mut incident = vec![Vec::new(); n];
    for (k, e) in part.edges.iter().enumerate() {
        incident[e.i].push(k);
        incident[e.j].push(k);
    }
    let mut at: Vec<Option<nalgebra::Isometry3<f64>>> = vec![None; n];
    at[root] = Some(part.poses[root].to_isometry());
    let mut queue = std::collections::VecDeque::from([root]);
    while let Some(u) = queue.pop_front() {
        let xu = at[u].expect("queued poses are placed");
        for &k in &incident[u] {
            let e = &part.edges[k];
            let v = if e.i == u { e.j } else { e.i };
            if at[v].is_none() {
                let z = e.measurement.to_isometry();
                at[v] = Some(if e.i == u { xu * z } else { xu * z.inverse() });
                queue.push_back(v);
            }
        }
    }
    at.iter()
        .enumerate()
        .map(|(k, x)| {
            let x = x.expect("a connected component's poses are all reached");
            if k == root {
                part.poses[root]
            } else {
                form_of(&x)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, SymMat3};
    use crate::linalg::rng::Rng;
    use crate::problem::weights::{Weights, edge_weights};
    use crate::solve::{SolveOptions, solve};
    use crate::staircase::{StaircaseOptions, solve_graph};

    /// A random tree: pose k > 0 hangs from a random earlier pose by a random measurement and a
    /// random information matrix, the edge reversed now and then (composed by its inverse); the
    /// poses as given (not the composition).
    fn random_tree(n: usize, seed: u64) -> PoseGraph {
        let mut rng = Rng::new(seed);
        let edges = (1..n)
            .map(|k| {
                let parent = (rng.uniform() * k as f64) as usize;
                let (i, j) = if rng.uniform() < 0.3 {
                    (k, parent)
                } else {
                    (parent, k)
                };
                let (a, c) = (1.0 + 50.0 * rng.uniform(), 1.0 + 400.0 * rng.uniform());
                Edge {
                    i,
                    j,
                    measurement: Pose2::new(
                        3.0 * rng.normal(),
                        3.0 * rng.normal(),
                        2.0 * rng.normal(),
                    ),
                    noise: SymMat3([a, 0.3 * (rng.uniform() - 0.5), 0.0, 20.0, 0.0, c]),
                }
            })
            .collect();
        let poses = (0..n)
            .map(|_| Pose2::new(10.0 * rng.normal(), 10.0 * rng.normal(), rng.angle()))
            .collect();
        PoseGraph::with_edges(poses, edges)
    }

    #[test]
    fn a_tree_is_solved_at_zero_cost_where_the_staircase_finds_its_optimum() {
        for (n, seed) in [(2, 1), (3, 2), (40, 3), (300, 4)] {
            let g = random_tree(n, seed);
            assert!(is_tree(&g));
            let w = edge_weights(&g, Weights::Isotropic).unwrap();
            let (report, poses) = solve_tree(&g, &w, 1e-6);
            // Prop. 1: the composition annihilates every term, up to rounding (weights up to a
            // few hundred, measurements of order 1 to 10).
            assert!(report.cost < 1e-20 * n as f64, "{n}: {}", report.cost);
            assert!(report.certified && report.szep && report.lower_bound == 0.0);
            assert_eq!(poses[0], g.poses[0]);
            // The scalable solver, independently: certified at a cost of rounding too, at the
            // same poses up to rounding once in the same gauge.
            let (s, staircase) =
                solve_graph(&g, &w, &StaircaseOptions::default(), &mut |_| {}).unwrap();
            assert!(s.certified && s.cost < 1e-12, "{n}: {}", s.cost);
            let moved = move_to_anchor(&staircase, g.poses[0]);
            for (a, b) in poses.iter().zip(&moved) {
                let turn = (a.theta - b.theta).sin().abs();
                let off = (a.x - b.x).abs() + (a.y - b.y).abs() + turn;
                assert!(off < 1e-9 * n as f64, "{n}: {a:?} {b:?}");
            }
        }
    }

    #[test]
    fn a_trees_estimate_is_bounded_by_its_optimum_zero() {
        // The composition moved off its optimum: its own multipliers do not certify it, and the
        // optimum's bound, 0 for a tree, is what the staircase proves for it to rounding.
        let g = random_tree(60, 9);
        let w = edge_weights(&g, Weights::Isotropic).unwrap();
        let (_, mut poses) = solve_tree(&g, &w, 1e-6);
        for p in poses.iter_mut() {
            p.theta += 0.05;
            p.x += 0.1 * p.y.sin();
        }
        let report = crate::solve::certify_estimate(&g, &poses, &Default::default(), "x").unwrap();
        let c = &report.components[0];
        assert_eq!((c.lower_bound, c.bound_from), (0.0, "solution"));
        assert!(!report.certified && report.suboptimality_bound == report.cost);
        let (s, _) = solve_graph(&g, &w, &StaircaseOptions::default(), &mut |_| {}).unwrap();
        assert!(
            s.certified && s.lower_bound.abs() < 1e-9,
            "{}",
            s.lower_bound
        );
    }

    #[test]
    fn only_trees_take_the_tree_path_under_auto_or_when_asked() {
        let g = random_tree(30, 7);
        let auto = solve(&g, &SolveOptions::default()).unwrap();
        assert_eq!(auto.components[0].method, Method::Tree);
        assert!(auto.certified && auto.szep && auto.lower_bound == 0.0);
        let asked = SolveOptions {
            method: Method::Staircase,
            ..Default::default()
        };
        let staircase = solve(&g, &asked).unwrap();
        assert_eq!(staircase.components[0].method, Method::Staircase);
        assert!(staircase.certified);
        // One loop closure more: a cycle, no longer a tree.
        let mut edges = g.edges.clone();
        let mut closure = edges[0];
        closure.i = 29;
        closure.measurement = Pose2::new(1.0, 2.0, 0.5);
        edges.push(closure);
        let cycle = PoseGraph::with_edges(g.poses.clone(), edges);
        assert!(!is_tree(&cycle));
        let solved = solve(&cycle, &SolveOptions::default()).unwrap();
        assert_ne!(solved.components[0].method, Method::Tree);
        assert!(solved.cost > 1e-3);
        // Asked for (the library's option, no flag): trees so, other components by the staircase.
        let asked = SolveOptions {
            method: Method::Tree,
            ..Default::default()
        };
        assert_eq!(
            solve(&g, &asked).unwrap().components[0].method,
            Method::Tree
        );
        let solved = solve(&cycle, &asked).unwrap();
        assert_eq!(solved.components[0].method, Method::Staircase);
        assert!(solved.certified);
    }
}
