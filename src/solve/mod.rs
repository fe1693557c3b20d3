//! The whole jobs as library calls, what the tools run and what a Rust program, the Python
//! package or an outer loop (robust estimation) calls: [`solve`] a pose graph to a certified
//! optimum (component by component, the method chosen per component, optionally refined under the
//! full information matrices), and [`certify_estimate`] for any estimate. The graph's spectrum is
//! [`crate::spectrum::spectrum`].
//!
//! May use: every room below it ([`crate::staircase`], [`crate::dual`], [`crate::certify`],
//! [`crate::refine`], [`crate::problem`], [`crate::progress`]); nothing of `viz` or `cli`.

mod estimate;

pub use estimate::{CertifyOptions, EstimateComponent, EstimateReport, certify_estimate};

use crate::dual::algorithm1::{self, ComponentSolution, check_dense_size};
use crate::dual::rounding::Rounding;
use crate::dual::solver::SdpSolver;
use crate::error::Error;
use crate::graph::{Pose2, PoseGraph};
use crate::problem::checks::{check_edge_terms, check_not_empty};
use crate::problem::weights::{Weights, edge_weights};
use crate::staircase::{Iteration, StaircaseOptions, StaircaseSolution, solve_graph};
use serde::Serialize;

/// How each connected component is solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// sdp for components of at most 100 poses, staircase beyond
    Auto,
    /// Algorithm 1: dual SDP, SZEP, eigenvector scaling or null-space method (dense; up to 2000 poses)
    Sdp,
    /// The scalable solver: Riemannian Newton, sparse certificate, Riemannian staircase
    Staircase,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::Sdp => "sdp",
            Method::Staircase => "staircase",
        }
    }
}

/// Components up to this size go to the SDP under [`Method::Auto`].
pub const AUTO_SDP_MAX_POSES: usize = 100;

/// What [`solve`] is asked for.
#[derive(Debug, Clone, Copy)]
pub struct SolveOptions {
    pub method: Method,
    /// The SDP solver of Algorithm 1's dual.
    pub solver: SdpSolver,
    /// How the information matrices become the weights τ, κ of eq. (8).
    pub weights: Weights,
    /// Relative suboptimality bound under which a component is called certified.
    pub tolerance: f64,
    /// Levenberg-Marquardt under the full information matrices after the certified solve (the
    /// estimate then differs from the certified one: see [`Solution::refined_chi2`]).
    pub refine: bool,
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions {
            method: Method::Auto,
            solver: SdpSolver::Ipm,
            weights: Weights::Isotropic,
            tolerance: 1e-6,
            refine: false,
        }
    }
}

/// The result of one connected component.
#[derive(Debug, Serialize)]
pub struct ComponentReport {
    /// Ids of the first (smallest) and last pose of the component.
    pub first_id: u32,
    pub poses: usize,
    pub edges: usize,
    pub cost: f64,
    pub lower_bound: f64,
    pub suboptimality_bound: f64,
    pub certified: bool,
    pub szep: bool,
    pub near_zero_eigenvalues: usize,
    /// sdp or staircase.
    pub method: Method,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rounding: Option<Rounding>,
    /// The smallest eigenvalues of W(lambda*), ascending (at most 4; sdp only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub penalized_eigenvalues: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sdp_iterations: Option<usize>,
    /// Whether the SDP solver reached its tolerance (if not, the bound is proven all the same,
    /// from the dual feasible multipliers it reached, and only weaker).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sdp_converged: Option<bool>,
    /// The largest rank the staircase reached (1: no staircase needed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rank: Option<usize>,
    /// Newton iterations, all ranks together.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<usize>,
    /// The certificate's eta: W(lambda) + eta*blkdiag(0, I) was proven PSD.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eta: Option<f64>,
    /// Norm of the Riemannian gradient at the estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gradient_norm: Option<f64>,
    /// With refinement: g2o's chi2 of the certified estimate, and after refinement.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certified_chi2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refined_chi2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refine_iterations: Option<usize>,
}

/// The solved graph: the estimate and, per component and summed, its cost, the proven lower bound
/// on the optimum f* and their difference. Totals are sums over the components.
#[derive(Debug, Serialize)]
pub struct Solution {
    pub method: Method,
    pub solver: SdpSolver,
    pub weights: Weights,
    pub poses: usize,
    pub edges: usize,
    /// f at the certified estimate.
    pub cost: f64,
    /// Proven lower bound on the optimum f*.
    pub lower_bound: f64,
    /// cost − lower_bound: the certified estimate is at most this far from optimal.
    pub suboptimality_bound: f64,
    /// With refinement: g2o's chi2 of the returned (refined) estimate, summed over components.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refined_chi2: Option<f64>,
    /// suboptimality_bound / max(1, |cost|).
    pub relative_suboptimality_bound: f64,
    pub certified: bool,
    pub szep: bool,
    pub near_zero_eigenvalues: usize,
    /// Whether the SDP solver reached its tolerance on every component.
    pub sdp_converged: bool,
    pub components: Vec<ComponentReport>,
    /// The estimate, one pose per pose of the graph, in the graph's order.
    #[serde(skip)]
    pub estimate: Vec<Pose2>,
}

/// Solves every connected component of `graph` to a certified optimum where the relaxation is
/// exact (Algorithm 1 for small components, the scalable solver beyond), and bounds the
/// suboptimality of the estimate where it is not. Iterations are reported through
/// [`crate::progress`].
pub fn solve(graph: &PoseGraph, options: &SolveOptions) -> crate::Result<Solution> {
    check_not_empty(graph)?;
    if options.method == Method::Sdp {
        check_dense_size(graph, "--method sdp")?;
    }
    let mut components = Vec::new();
    let mut estimate = graph.poses.clone();
    for (part, members, _) in graph.components() {
        let weights = edge_weights(&part, options.weights)?;
        let sdp = match options.method {
            Method::Sdp => true,
            Method::Staircase => false,
            Method::Auto => part.num_poses() <= AUTO_SDP_MAX_POSES,
        };
        let (mut report, mut poses) = if sdp {
            let solution = algorithm1::solve_connected(&part, &weights, options.solver)?;
            (
                sdp_report(&part, &solution, options.tolerance),
                solution.poses,
            )
        } else {
            check_edge_terms(&part, &weights, &weights)?;
            let staircase = StaircaseOptions {
                tolerance: options.tolerance,
                ..Default::default()
            };
            let (solution, poses) = solve_graph(&part, &weights, &staircase, &mut report_step())
                .ok_or_else(|| Error::Invalid("the graph is not connected".into()))?;
            (staircase_report(&part, &solution, options.tolerance), poses)
        };
        if options.refine {
            crate::progress::phase("refinement (Levenberg-Marquardt)");
            let refined = crate::refine::refine(&part, &poses, &Default::default())?;
            report.certified_chi2 = Some(refined.initial_chi2);
            report.refined_chi2 = Some(refined.chi2);
            report.refine_iterations = Some(refined.iterations);
            poses = refined.poses;
        }
        for (pose, &k) in poses.iter().zip(&members) {
            estimate[k] = *pose;
        }
        components.push(report);
    }
    // Folded from +0: an empty sum of f64 is -0 in Rust, and a graph without edges costs 0.
    let cost = components.iter().fold(0.0, |a, c| a + c.cost);
    let lower_bound = components.iter().fold(0.0, |a, c| a + c.lower_bound);
    let suboptimality_bound = cost - lower_bound;
    Ok(Solution {
        method: options.method,
        solver: options.solver,
        weights: options.weights,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        cost,
        lower_bound,
        suboptimality_bound,
        refined_chi2: options
            .refine
            .then(|| components.iter().filter_map(|c| c.refined_chi2).sum()),
        relative_suboptimality_bound: suboptimality_bound / cost.abs().max(1.0),
        certified: components.iter().all(|c| c.certified),
        szep: components.iter().all(|c| c.szep),
        near_zero_eigenvalues: components.iter().map(|c| c.near_zero_eigenvalues).sum(),
        sdp_converged: components.iter().all(|c| c.sdp_converged != Some(false)),
        components,
        estimate,
    })
}

/// The staircase's Newton steps, reported through [`crate::progress`] (the `iteration` timeline
/// of a rerun recording).
fn report_step() -> impl FnMut(&Iteration) {
    let mut step = 0u64;
    move |it: &Iteration| {
        step += 1;
        crate::progress::iteration(
            step,
            &[
                ("cost", it.cost),
                ("gradient_norm", it.gradient_norm),
                ("rank", it.rank as f64),
                ("damping", it.damping),
            ],
        );
    }
}

/// Whether `suboptimality_bound` is within the relative `tolerance` of `cost`.
fn within(suboptimality_bound: f64, cost: f64, tolerance: f64) -> bool {
    suboptimality_bound <= tolerance * cost.abs().max(1.0)
}

fn sdp_report(part: &PoseGraph, s: &ComponentSolution, tolerance: f64) -> ComponentReport {
    let suboptimality_bound = s.cost - s.lower_bound;
    ComponentReport {
        first_id: part.ids[0],
        poses: part.num_poses(),
        edges: part.edges.len(),
        cost: s.cost,
        lower_bound: s.lower_bound,
        suboptimality_bound,
        certified: s.szep && within(suboptimality_bound, s.cost, tolerance),
        szep: s.szep,
        near_zero_eigenvalues: s.near_zero,
        method: Method::Sdp,
        rounding: Some(s.rounding),
        penalized_eigenvalues: Some(s.eigenvalues.iter().take(4).copied().collect()),
        sdp_iterations: Some(s.dual.iterations),
        sdp_converged: Some(s.dual.converged),
        rank: None,
        iterations: None,
        eta: None,
        gradient_norm: None,
        certified_chi2: None,
        refined_chi2: None,
        refine_iterations: None,
    }
}

fn staircase_report(part: &PoseGraph, s: &StaircaseSolution, tolerance: f64) -> ComponentReport {
    let suboptimality_bound = s.cost - s.lower_bound;
    ComponentReport {
        first_id: part.ids[0],
        poses: part.num_poses(),
        edges: part.edges.len(),
        cost: s.cost,
        lower_bound: s.lower_bound,
        suboptimality_bound,
        certified: s.bound.is_some() && within(suboptimality_bound, s.cost, tolerance),
        szep: s.near_zero.is_some_and(|z| z <= 1),
        near_zero_eigenvalues: s.near_zero.unwrap_or(0),
        method: Method::Staircase,
        rounding: None,
        penalized_eigenvalues: None,
        sdp_iterations: None,
        sdp_converged: None,
        rank: Some(s.rank),
        iterations: Some(s.iterations),
        eta: s.bound.map(|b| b.eta),
        gradient_norm: Some(s.gradient_norm),
        certified_chi2: None,
        refined_chi2: None,
        refine_iterations: None,
    }
}
