//! Gauss-Newton refinement of the cost f (eq. (8), with per-edge weights) from a given estimate,
//! as the paper uses it to top off estimates (Sec. 6, Fig. 6-7): a local method, with a
//! Levenberg-Marquardt damping that is only raised when a step would increase f. Dense normal
//! equations: for the small graphs of Algorithm 1.
//!
//! Residuals of an edge (i, j): √τ (p_j − p_i − R(θ_i) Δ) ∈ ℝ² and √κ (e^{iθ_j} − e^{iθ_i} R_ij)
//! ∈ ℂ ≅ ℝ², whose squared norms sum to f. Pose 0 is held fixed (the gauge: f is invariant to a
//! global rotation and translation).

use crate::graph::{Pose2, PoseGraph};
use crate::problem::matrix::cost;
use crate::problem::weights::EdgeWeight;
use faer::prelude::*;
use faer::{Mat, Side};

/// The result of a refinement.
#[derive(Debug, Clone)]
pub struct Refined {
    pub poses: Vec<Pose2>,
    pub cost: f64,
    pub iterations: usize,
}

/// Refines `start` by Gauss-Newton (Levenberg-Marquardt damped) on f until the relative
/// decrease of f falls below 1e-14 or `max_iterations` is reached.
pub fn refine(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    start: &[Pose2],
    max_iterations: usize,
) -> Refined {
    let n = graph.num_poses();
    let mut poses = start.to_vec();
    let mut f = cost(graph, weights, &poses);
    let dim = 3 * (n.saturating_sub(1));
    if dim == 0 {
        return Refined {
            poses,
            cost: f,
            iterations: 0,
        };
    }
    // Variable index of pose k's (x, y, θ): pose 0 is fixed.
    let var = |k: usize| (k > 0).then(|| 3 * (k - 1));
    let mut damping = 1e-9;
    let mut iterations = 0;
    while iterations < max_iterations {
        iterations += 1;
        let mut h = Mat::<f64>::zeros(dim, dim);
        let mut g = Mat::<f64>::zeros(dim, 1);
        for (e, w) in graph.edges.iter().zip(weights) {
            let (a, b) = (poses[e.i], poses[e.j]);
            let (st, sk) = (w.tau.sqrt(), w.kappa.sqrt());
            let (c, s) = (a.theta.cos(), a.theta.sin());
            let (dx, dy) = (e.measurement.x, e.measurement.y);
            let phi = a.theta + e.measurement.theta;
            // Rows: two translation residuals, two rotation residuals; columns: the six
            // variables (x_i, y_i, θ_i, x_j, y_j, θ_j).
            let r = [
                st * (b.x - a.x - (c * dx - s * dy)),
                st * (b.y - a.y - (s * dx + c * dy)),
                sk * (b.theta.cos() - phi.cos()),
                sk * (b.theta.sin() - phi.sin()),
            ];
            let jac = [
                [-st, 0.0, st * (s * dx + c * dy), st, 0.0, 0.0],
                [0.0, -st, -st * (c * dx - s * dy), 0.0, st, 0.0],
                [0.0, 0.0, sk * phi.sin(), 0.0, 0.0, -sk * b.theta.sin()],
                [0.0, 0.0, -sk * phi.cos(), 0.0, 0.0, sk * b.theta.cos()],
            ];
            let cols: [Option<usize>; 6] = [
                var(e.i),
                var(e.i).map(|v| v + 1),
                var(e.i).map(|v| v + 2),
                var(e.j),
                var(e.j).map(|v| v + 1),
                var(e.j).map(|v| v + 2),
            ];
            for (row, res) in jac.iter().zip(r) {
                for (p, cp) in cols.iter().enumerate() {
                    let Some(cp) = cp else { continue };
                    g[(*cp, 0)] += row[p] * res;
                    for (q, cq) in cols.iter().enumerate() {
                        if let Some(cq) = cq {
                            h[(*cp, *cq)] += row[p] * row[q];
                        }
                    }
                }
            }
        }
        let mut improved = false;
        while damping < 1e12 {
            let mut hd = h.clone();
            for k in 0..dim {
                hd[(k, k)] += damping * h[(k, k)].max(1e-12);
            }
            let Ok(llt) = hd.llt(Side::Lower) else {
                damping *= 10.0;
                continue;
            };
            let step = llt.solve(-&g);
            let mut trial = poses.clone();
            for (k, p) in trial.iter_mut().enumerate().skip(1) {
                let v = 3 * (k - 1);
                p.x += step[(v, 0)];
                p.y += step[(v + 1, 0)];
                p.theta += step[(v + 2, 0)];
            }
            let ft = cost(graph, weights, &trial);
            if ft < f {
                let decrease = (f - ft) / f.max(f64::MIN_POSITIVE);
                poses = trial;
                f = ft;
                damping = (damping / 10.0).max(1e-12);
                improved = decrease > 1e-14;
                break;
            }
            damping *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Refined {
        poses,
        cost: f,
        iterations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, NoiseKind, SymMat3};
    use crate::problem::weights::{Weights, edge_weights};

    fn triangle(closing: Pose2) -> PoseGraph {
        let z = |x, y, t| Pose2::new(x, y, t);
        PoseGraph {
            ids: vec![0, 1, 2],
            poses: vec![z(0.0, 0.0, 0.0), z(1.0, 0.0, 0.0), z(1.0, 1.0, 0.0)],
            edges: [
                (0, 1, z(1.0, 0.0, std::f64::consts::FRAC_PI_2)),
                (1, 2, z(1.0, 0.0, std::f64::consts::FRAC_PI_2)),
                (2, 0, closing),
            ]
            .iter()
            .map(|&(i, j, m)| Edge {
                i,
                j,
                measurement: m,
                noise: SymMat3::IDENTITY,
            })
            .collect(),
            fixed: vec![],
            vertices_declared: true,
            noise: NoiseKind::Information,
            landmarks: Default::default(),
        }
    }

    #[test]
    fn balanced_graph_reaches_zero_cost() {
        // Two sides of a unit square turning left, and the diagonal back: consistent (by hand,
        // x2 = (1, 1, π), and x2⁻¹·x0 = (1, 1, -π) in pose 2's frame).
        let g = triangle(Pose2::new(1.0, 1.0, -std::f64::consts::PI));
        let w = edge_weights(&g, Weights::Unit).unwrap();
        assert!(cost(&g, &w, &g.poses) > 1.0);
        let r = refine(&g, &w, &g.poses, 50);
        assert!(r.cost < 1e-20, "{}", r.cost);
        // The gauge: pose 0 untouched.
        assert_eq!(r.poses[0], g.poses[0]);
        assert!((r.poses[2].x - 1.0).abs() < 1e-9 && (r.poses[2].y - 1.0).abs() < 1e-9);
    }

    #[test]
    fn refinement_reaches_a_stationary_point_and_never_increases_cost() {
        let g = triangle(Pose2::new(1.3, 0.8, -2.9));
        let w = edge_weights(&g, Weights::Unit).unwrap();
        let f0 = cost(&g, &w, &g.poses);
        let r = refine(&g, &w, &g.poses, 100);
        assert!(r.cost <= f0);
        // Stationary: moving any variable of poses 1, 2 by ±h raises f (to second order).
        let h = 1e-5;
        for k in 1..3 {
            for v in 0..3 {
                for s in [-h, h] {
                    let mut p = r.poses.clone();
                    match v {
                        0 => p[k].x += s,
                        1 => p[k].y += s,
                        _ => p[k].theta += s,
                    }
                    assert!(cost(&g, &w, &p) >= r.cost - 1e-12, "pose {k} var {v}");
                }
            }
        }
    }
}
