//! Certifying any estimate (one written by g2o, GTSAM or pgo itself): its cost f (eq. (8)) and the
//! best lower bound on f* that can be proven, from the estimate's own multipliers where they
//! certify it, else from the optimum's.

use super::within;
use crate::error::Error;
use crate::graph::{Pose2, PoseGraph};
use crate::problem::checks::{check_edge_terms, check_not_empty};
use crate::problem::matrix::cost;
use crate::problem::weights::{Weights, edge_weights};
use crate::staircase::{StaircaseOptions, certify_estimate as certify_component, solve_graph};
use serde::Serialize;

/// What [`certify_estimate`] is asked for.
#[derive(Debug, Clone, Copy)]
pub struct CertifyOptions {
    pub weights: Weights,
    /// Relative suboptimality bound under which the estimate is called certified.
    pub tolerance: f64,
}

impl Default for CertifyOptions {
    fn default() -> Self {
        CertifyOptions {
            weights: Weights::Isotropic,
            tolerance: 1e-6,
        }
    }
}

/// The bound of one connected component.
#[derive(Debug, Serialize)]
pub struct EstimateComponent {
    pub first_id: u32,
    pub poses: usize,
    pub edges: usize,
    pub cost: f64,
    pub lower_bound: f64,
    pub suboptimality_bound: f64,
    pub certified: bool,
    /// "estimate": the estimate's own multipliers proved the bound; "solution": the optimum's.
    pub bound_from: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eta: Option<f64>,
    pub gradient_norm: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub near_zero_eigenvalues: Option<usize>,
}

/// The estimate's cost and the proven bound, per component and summed.
#[derive(Debug, Serialize)]
pub struct EstimateReport {
    pub weights: Weights,
    pub poses: usize,
    pub edges: usize,
    pub cost: f64,
    /// g2o's chi2 of the estimate: Σ eᵀΩe under the full information matrices, another objective
    /// than the cost (GTSAM's error is chi2 / 2). `None` (JSON null) where a covariance is
    /// singular.
    pub chi2: Option<f64>,
    pub lower_bound: f64,
    pub suboptimality_bound: f64,
    pub relative_suboptimality_bound: f64,
    pub certified: bool,
    pub gradient_norm: f64,
    pub components: Vec<EstimateComponent>,
}

/// Bounds the suboptimality of `estimate` (one pose per pose of `graph`, in its order, followed
/// by one per landmark when it has landmarks: their positions, θ unused): the
/// estimate's own multipliers λ from the first-order conditions and the sparse certificate; where
/// they do not certify it within the tolerance, the proven bound of the optimum (the staircase),
/// whichever is higher. `source` names the estimate in messages.
pub fn certify_estimate(
    graph: &PoseGraph,
    estimate: &[Pose2],
    options: &CertifyOptions,
    source: &str,
) -> crate::Result<EstimateReport> {
    check_not_empty(graph)?;
    let tol = options.tolerance;
    let mut components = Vec::new();
    for (part, members, _) in graph.components() {
        let weights = edge_weights(&part, options.weights)?;
        check_edge_terms(&part, &weights, &weights)?;
        // The n poses, then the component's landmarks (as points), as the problem takes them.
        let total = graph.num_poses();
        let poses: Vec<Pose2> = members
            .iter()
            .map(|&k| estimate[k])
            .chain(part.landmarks.ids.iter().map(|id| {
                let k = graph
                    .landmarks
                    .index_of(*id)
                    .expect("a component's landmarks are the graph's");
                estimate[total + k]
            }))
            .collect();
        let n = part.num_poses();
        let cost = cost(&part, &weights, &poses);
        if !cost.is_finite() {
            return Err(Error::Invalid(format!(
                "{source}: the cost of the estimate overflows a 64-bit float (its poses are too far apart for the weights)"
            )));
        }
        let reach = tol * cost.max(1.0) / n as f64;
        let mut own = certify_component(&part, &weights, &poses, reach);
        let own_bound = own.bound.map(|b| b.lower_bound.max(0.0));
        let (lower_bound, bound_from) = match own_bound {
            Some(lb) if within(cost - lb, cost, tol) => (lb, "estimate"),
            _ => {
                // Not certified by its own multipliers: the optimum's proven bound bounds it; a
                // tree's is its optimum, 0 (Props. 1, 11), with nothing to solve.
                let solved = if super::tree::is_tree(&part) {
                    0.0
                } else {
                    let staircase = StaircaseOptions {
                        tolerance: tol,
                        ..Default::default()
                    };
                    solve_graph(&part, &weights, &staircase, &mut |_| {})
                        .map(|(s, _)| s.lower_bound)
                        .unwrap_or(0.0)
                };
                match own_bound {
                    Some(lb) if lb >= solved => (lb, "estimate"),
                    _ => (solved, "solution"),
                }
            }
        };
        let near_zero = own
            .bound
            .and_then(|b| own.certifier.near_zero(Some(&b), &own.lambda));
        let suboptimality_bound = cost - lower_bound;
        components.push(EstimateComponent {
            first_id: part.ids[0],
            poses: n,
            edges: part.edges.len(),
            cost,
            lower_bound,
            suboptimality_bound,
            certified: within(suboptimality_bound, cost, tol),
            bound_from,
            eta: own.bound.map(|b| b.eta),
            gradient_norm: own.gradient_norm,
            near_zero_eigenvalues: near_zero,
        });
    }
    let cost: f64 = components.iter().map(|c| c.cost).sum();
    let lower_bound: f64 = components.iter().map(|c| c.lower_bound).sum();
    let suboptimality_bound = cost - lower_bound;
    let chi2 = Some(crate::refine::chi2(graph, estimate)).filter(|c| c.is_finite());
    Ok(EstimateReport {
        weights: options.weights,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        cost,
        chi2,
        lower_bound,
        suboptimality_bound,
        relative_suboptimality_bound: suboptimality_bound / cost.abs().max(1.0),
        certified: components.iter().all(|c| c.certified),
        gradient_norm: components
            .iter()
            .map(|c| c.gradient_norm * c.gradient_norm)
            .sum::<f64>()
            .sqrt(),
        components,
    })
}
