//! The checks the fuzz target `solve` (`fuzz/`) runs on every input, shared with
//! `tests/fuzz_regressions.rs`, which replays the minimized inputs the fuzzers found, so a
//! regression fails plain `cargo test`. The readers' checks (fuzz targets `read_g2o`,
//! `read_toro`, `read_auto`) are those of the file layer, in `crates/pgo-io/tests/oracle/mod.rs`.
//!
//! - [`check_solve`]: on tiny graphs, the solve path of `pgo-solve` (components, weights,
//!   Algorithm 1) never panics, and what it reports is sound: the proven lower bound is below the
//!   cost of the estimate and below the cost of the input's own poses (weak duality holds for any
//!   feasible point), a tree is solved to zero cost, and `certified` agrees with the numbers.
#![allow(dead_code)]

use pgo::PoseGraph;
use pgo::graph::Pose2;
use pgo::io::{self, ReadOptions};

/// Largest graph [`check_solve`] solves (the dense SDP path is cubic).
pub const SOLVE_MAX_POSES: usize = 8;
pub const SOLVE_MAX_EDGES: usize = 24;

/// Reads `data` (format from the tags) and, if it is a graph of at most [`SOLVE_MAX_POSES`]
/// poses, runs the solve path of `pgo-solve` on it with both weight policies.
pub fn check_solve(data: &[u8]) {
    use pgo::dual::algorithm1::solve_connected;
    use pgo::dual::solver::SdpSolver;
    use pgo::problem::weights::{Weights, edge_weights};
    let options = ReadOptions {
        allow_indefinite: true,
        ..Default::default()
    };
    let Ok((graph, _)) = io::read(data, "fuzz.txt", &options) else {
        return;
    };
    if graph.num_poses() > SOLVE_MAX_POSES || graph.edges.len() > SOLVE_MAX_EDGES {
        return;
    }
    for policy in [Weights::Unit, Weights::Isotropic] {
        for (part, _, _) in graph.components() {
            let weights = match edge_weights(&part, policy) {
                Ok(w) => w,
                Err(e) => {
                    assert_eq!(policy, Weights::Isotropic, "unit weights always exist");
                    // Only an information matrix that is not positive definite is called so.
                    let msg = e.to_string();
                    if msg.contains("not positive definite") {
                        assert!(
                            part.edges.iter().any(|e| part
                                .information(e)
                                .is_none_or(|m| m.check_positive_definite().is_err())),
                            "{msg}"
                        );
                    }
                    continue;
                }
            };
            let s = match solve_connected(&part, &weights, SdpSolver::Ipm) {
                Ok(s) => s,
                Err(pgo::Error::Invalid(msg)) => {
                    // Said in the user's terms: `part` is a connected component, and the
                    // solver's internal conditions are not the user's business.
                    assert!(!msg.contains("not connected"), "{msg}");
                    assert!(!msg.contains("not Hermitian"), "{msg}");
                    continue;
                }
                Err(e) => panic!("unexpected error kind: {e}"),
            };
            check_solution(&part, &weights, &s);
        }
    }
}

fn check_solution(
    part: &PoseGraph,
    weights: &[pgo::problem::weights::EdgeWeight],
    s: &pgo::dual::algorithm1::ComponentSolution,
) {
    use pgo::problem::matrix::cost;
    // The estimate: the poses, then the landmarks' positions (as poses of heading 0).
    assert_eq!(s.poses.len(), part.num_poses() + part.landmarks.len());
    assert!(s.cost.is_finite() && s.cost >= 0.0, "cost {}", s.cost);
    assert!(!s.lower_bound.is_nan(), "bound is NaN");
    // Rounding of the cost itself: every term is a sum of a few products.
    let slack = |f: f64| 1e-9 * f.abs().max(1.0);
    assert!(
        s.lower_bound <= s.cost + slack(s.cost),
        "bound {} above the cost {} of the estimate",
        s.lower_bound,
        s.cost
    );
    // Weak duality: the bound is below the cost of every feasible point, e.g. the input's.
    let input: Vec<Pose2> = (part.poses.iter().copied())
        .chain(
            part.landmarks
                .positions
                .iter()
                .map(|&[x, y]| Pose2::new(x, y, 0.0)),
        )
        .collect();
    let input_cost = cost(part, weights, &input);
    if input_cost.is_finite() {
        assert!(
            s.lower_bound <= input_cost + slack(input_cost),
            "bound {} above the cost {input_cost} of the input poses",
            s.lower_bound
        );
    }
    // The cost of the returned poses, recomputed, is the one reported.
    let recomputed = cost(part, weights, &s.poses);
    assert!(
        (recomputed - s.cost).abs() <= slack(s.cost),
        "{recomputed} vs {}",
        s.cost
    );
    // A tree is solved exactly: f* = 0 (Prop. 6).
    if part.is_forest() {
        let scale: f64 = part
            .edges
            .iter()
            .zip(weights)
            .map(|(e, w)| w.tau * (e.measurement.x.powi(2) + e.measurement.y.powi(2)) + w.kappa)
            .chain(
                (part.landmarks.observations.iter())
                    .zip(&weights[part.edges.len()..])
                    .map(|(o, w)| w.tau * (o.d[0].powi(2) + o.d[1].powi(2))),
            )
            .sum();
        if scale.is_finite() {
            assert!(
                s.cost <= 1e-6 * scale.max(1.0),
                "tree solved to cost {} (scale {scale})",
                s.cost
            );
        }
    }
}
