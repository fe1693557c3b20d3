//! The whole jobs as library calls, what the tools run and what a Rust program, the Python
//! package or an outer loop (robust estimation) calls: [`solve`] a pose graph to a certified
//! optimum (component by component, the method chosen per component, optionally refined under the
//! full information matrices), and [`certify_estimate`] for any estimate. The graph's spectrum is
//! [`crate::spectrum::spectrum`].
//!
//! May use: every room below it ([`crate::staircase`], [`crate::se3`], [`crate::dual`], [`crate::certify`],
//! [`crate::refine`], [`crate::problem`], [`crate::progress`]); nothing of `viz` or `cli`.

mod best;
mod estimate;
mod spatial;
mod tree;

pub use estimate::{CertifyOptions, EstimateComponent, EstimateReport, certify_estimate};
pub use spatial::{Solution3, certify_estimate3, chi2_3, solve3};

use crate::dual::algorithm1::{self, ComponentSolution, check_dense_size};
use crate::dual::rounding::Rounding;
use crate::dual::solver::SdpSolver;
use crate::error::Error;
use crate::graph::{Pose2, PoseGraph};
use crate::problem::checks::{check_edge_terms, check_not_empty};
use crate::problem::gauge::move_pose_to;
use crate::problem::matrix::cost;
use crate::problem::weights::{EdgeWeight, Weights, edge_weights};
use crate::simulate::wrap_angle;
use crate::staircase::{Iteration, StaircaseOptions, StaircaseSolution, solve_graph_from_estimate};
use serde::Serialize;

/// How each connected component is solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// sdp for components of at most 100 poses, staircase beyond; a tree composed (Prop. 1)
    #[default]
    Auto,
    /// Algorithm 1: dual SDP, SZEP, eigenvector scaling or null-space method (dense; up to 2000 poses)
    Sdp,
    /// The scalable solver: Riemannian Newton, sparse certificate, Riemannian staircase
    Staircase,
    /// A tree (no loop closure), under auto: its measurements composed, f* = 0 (Props. 1, 11).
    /// Not a flag's value; asked for in [`SolveOptions`], trees so and the other components by
    /// the staircase.
    #[value(skip)]
    Tree,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::Sdp => "sdp",
            Method::Staircase => "staircase",
            Method::Tree => "tree",
        }
    }
}

/// Components up to this size go to the SDP under [`Method::Auto`].
pub const AUTO_SDP_MAX_POSES: usize = 100;

/// Under [`Method::Auto`], a component of more than [`AUTO_SDP_MAX_POSES`] poses that the
/// staircase does not certify also takes Algorithm 1 up to this size (the dense SDP's time grows
/// as n³).
pub const AUTO_SECOND_SDP_MAX_POSES: usize = 200;

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
    /// The staircase's largest rank ([`StaircaseOptions::max_rank`], default 6).
    pub max_rank: usize,
    /// The staircase's work at most, in real multiply-adds of its factorizations
    /// ([`StaircaseOptions::staircase_budget`], default [`crate::staircase::STAIRCASE_BUDGET`]).
    pub staircase_budget: f64,
    /// The Newton steps the staircase's first descent may always take, past the budget
    /// ([`StaircaseOptions::min_descent_steps`], default [`crate::staircase::MIN_DESCENT_STEPS`]).
    pub min_descent_steps: usize,
    /// Whether the staircase proves its estimate ([`StaircaseOptions::certify`], default true).
    /// Off, a component the staircase solves gets Riemannian Newton's rank-1 estimate with no
    /// bound (lower bound 0, not certified) and no second method under auto.
    pub certify: bool,
    /// Whether the staircase refines noisy chordal rotations
    /// ([`StaircaseOptions::refine_rotations`], default true).
    pub refine_rotations: bool,
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions {
            method: Method::Auto,
            solver: SdpSolver::Ipm,
            weights: Weights::Isotropic,
            tolerance: 1e-6,
            refine: false,
            max_rank: StaircaseOptions::default().max_rank,
            staircase_budget: StaircaseOptions::default().staircase_budget,
            min_descent_steps: StaircaseOptions::default().min_descent_steps,
            certify: true,
            refine_rotations: true,
        }
    }
}

fn is_zero(v: &usize) -> bool {
    *v == 0
}

/// The result of one connected component (`Default`: the zero report each method fills in).
#[derive(Debug, Default, Serialize)]
pub struct ComponentReport {
    /// Ids of the first (smallest) and last pose of the component.
    pub first_id: u32,
    pub poses: usize,
    pub edges: usize,
    /// Landmarks and their observations in the component (absent from JSON when none).
    #[serde(skip_serializing_if = "is_zero")]
    pub landmarks: usize,
    #[serde(skip_serializing_if = "is_zero")]
    pub observations: usize,
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
    /// g2o's chi2 of the certified estimate (absent where a covariance is singular), and with
    /// refinement after it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certified_chi2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refined_chi2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refine_iterations: Option<usize>,
    /// Why the component is not certified (absent when it is): the SZEP fails, the SDP stalled,
    /// the staircase reached its rank or iteration limit, or the gap exceeds the tolerance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_certified_because: Option<String>,
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
    /// Landmarks and observations (absent from JSON when none).
    #[serde(skip_serializing_if = "is_zero")]
    pub landmarks: usize,
    #[serde(skip_serializing_if = "is_zero")]
    pub observations: usize,
    /// f at the certified estimate.
    pub cost: f64,
    /// g2o's chi2 of the certified estimate: Σ eᵀΩe under the full information matrices (another
    /// objective than f; GTSAM's error is chi2 / 2). `None` (JSON null) where a covariance is
    /// singular.
    pub chi2: Option<f64>,
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
    /// Why not certified (absent when certified): the reasons of the components that are not,
    /// "; "-separated, each prefixed with its first id when there are several components.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_certified_because: Option<String>,
    pub szep: bool,
    pub near_zero_eigenvalues: usize,
    /// Whether the SDP solver reached its tolerance on every component.
    pub sdp_converged: bool,
    pub components: Vec<ComponentReport>,
    /// The estimate, one pose per pose of the graph, in the graph's order, in the input's gauge
    /// (each component's FIX pose, else its first pose, exactly where the input has it), headings
    /// in (-π, π] (a FIX pose's as read).
    #[serde(skip)]
    pub estimate: Vec<Pose2>,
    /// The landmark positions, one per landmark of the graph, in its order, in the same gauge
    /// (landmarks seen by no pose as read).
    #[serde(skip)]
    pub landmark_estimate: Vec<[f64; 2]>,
}

/// Solves every connected component of `graph` to a certified optimum where the relaxation is
/// exact (Algorithm 1 for small components, the scalable solver beyond), and bounds the
/// suboptimality of the estimate where it is not. Iterations are reported through
/// [`crate::progress`].
///
/// # Errors
///
/// Besides the solvers' own: two or more fixed poses (`FIX`) in one connected component, which
/// make a problem with known poses that this does not solve.
pub fn solve(graph: &PoseGraph, options: &SolveOptions) -> crate::Result<Solution> {
    solve_with(graph, None, options, None)
}

/// A taker of a solve's estimate before its certificate ([`solve_offering`]): the poses and
/// landmark positions in the graph's order, as [`Solution::estimate`] and
/// [`Solution::landmark_estimate`] would hold them.
pub type CandidateTaker = Box<dyn FnMut(&[Pose2], &[[f64; 2]])>;

/// As [`solve`], with `candidate` given the estimate that the scalable solver is about to
/// certify, in the form the solution would hold it (the FIX pose where the input has it, headings
/// wrapped), before the certificate is computed: for work that depends only on the estimate
/// (pgo-solve writes its output file on the second core meanwhile). A candidate, not the answer:
/// a polish or the staircase may move the estimate after, so whoever uses it compares it with the
/// solution's, bit for bit. Offered for a graph of one connected component solved by the
/// staircase without `refine`; never otherwise. The solution is the same with or without it.
pub fn solve_offering(
    graph: &PoseGraph,
    options: &SolveOptions,
    candidate: CandidateTaker,
) -> crate::Result<Solution> {
    solve_with(graph, None, options, Some(candidate))
}

/// As [`solve`], warm started from `initial`, an estimate of the graph's poses (one per pose, in
/// the graph's order, in any gauge): the scalable solver starts its Riemannian Newton at rank 1
/// from `initial`'s headings instead of the chordal initialization (its positions are replaced
/// by the ones optimal for those headings, as every rank-1 point's are). What is proven is not
/// affected: the certificate proves whatever point the local solver reaches, and the bound is
/// computed exactly as for a cold start. Components solved by Algorithm 1 (the dual SDP, no
/// starting point) ignore `initial`.
///
/// The use: an outer loop solving a sequence of nearby problems, such as the variable updates of
/// graduated non-convexity (Yang, Antonante, Tzoumas and Carlone, RA-L 2020, Algorithm 1: the
/// weighted least-squares problem min_x Σ w_e r_e²(x) under the weights of eq. (12) or (14), one
/// per iteration; see [`crate::robust::gnc`]), each started from the previous one's estimate.
///
/// # Errors
///
/// Those of [`solve`]; `initial` not of one pose per pose of the graph, or with a coordinate that
/// is not finite.
pub fn solve_from(
    graph: &PoseGraph,
    initial: &[Pose2],
    options: &SolveOptions,
) -> crate::Result<Solution> {
    check_initial(graph, initial)?;
    solve_with(graph, Some(initial), options, None)
}

/// Refuses an initial estimate that is not one finite pose per pose of `graph`.
fn check_initial(graph: &PoseGraph, initial: &[Pose2]) -> crate::Result<()> {
    if initial.len() != graph.num_poses() {
        return Err(Error::Invalid(format!(
            "the initial estimate has {} poses, the graph {}: give one pose per pose of the graph, in its order",
            initial.len(),
            graph.num_poses()
        )));
    }
    if let Some(k) = initial
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite() && p.theta.is_finite()))
    {
        let p = initial[k];
        return Err(Error::Invalid(format!(
            "the initial estimate of vertex {} is not finite ({} {} {})",
            graph.ids[k], p.x, p.y, p.theta
        )));
    }
    Ok(())
}

fn solve_with(
    graph: &PoseGraph,
    initial: Option<&[Pose2]>,
    options: &SolveOptions,
    mut candidate: Option<CandidateTaker>,
) -> crate::Result<Solution> {
    check_not_empty(graph)?;
    if options.method == Method::Sdp {
        check_dense_size(graph, "--method sdp")?;
    }
    check_fixed(graph)?;
    let mut components = Vec::new();
    let mut estimate = graph.poses.clone();
    let mut landmark_estimate = graph.landmarks.positions.clone();
    let staircase = StaircaseOptions {
        tolerance: options.tolerance,
        max_rank: options.max_rank,
        staircase_budget: options.staircase_budget,
        min_descent_steps: options.min_descent_steps,
        certify: options.certify,
        refine_rotations: options.refine_rotations,
        ..Default::default()
    };
    let components_of = graph.components();
    // A candidate only where one staircase solves the whole graph as it is returned.
    if components_of.len() != 1 || options.refine {
        candidate = None;
    }
    for (part, members, _) in components_of {
        let weights = edge_weights(&part, options.weights)?;
        // Where the part's landmarks are in the graph's.
        let landmark_index: Vec<usize> = part
            .landmarks
            .ids
            .iter()
            .map(|id| {
                graph
                    .landmarks
                    .index_of(*id)
                    .expect("a component's landmarks are the graph's")
            })
            .collect();
        let fixed = part.fixed.first().copied();
        let n = part.num_poses();
        let sdp = match options.method {
            Method::Sdp => true,
            Method::Staircase | Method::Tree => false,
            Method::Auto => n <= AUTO_SDP_MAX_POSES,
        };
        let run_sdp = || algorithm1::solve_connected(&part, &weights, options.solver);
        // The warm start's poses of this component, in its order.
        let start: Option<Vec<Pose2>> = initial.map(|p| members.iter().map(|&k| p[k]).collect());
        let mut run_staircase = || -> crate::Result<(StaircaseSolution, Vec<Pose2>)> {
            check_edge_terms(&part, &weights, &weights)?;
            let run = || {
                solve_graph_from_estimate(
                    &part,
                    &weights,
                    &staircase,
                    start.as_deref(),
                    &mut report_step(),
                )
            };
            let solved = match candidate.take() {
                None => run(),
                Some(mut taker) => {
                    // The staircase's poses as this function places them below.
                    let (np, members, landmark_index) =
                        (part.num_poses(), members.clone(), landmark_index.clone());
                    let fixed_at = fixed.map(|k| (k, part.poses[k]));
                    let (mut estimate, mut landmarks) =
                        (estimate.clone(), landmark_estimate.clone());
                    let placing = Box::new(move |poses: &[Pose2]| {
                        let poses = match fixed_at {
                            Some((k, at)) => move_pose_to(poses, k, at),
                            None => poses.to_vec(),
                        };
                        let at = (np, &members[..], &landmark_index[..]);
                        place(poses, fixed, at, &mut estimate, &mut landmarks);
                        taker(&estimate, &landmarks);
                    });
                    crate::staircase::candidate::offering(placing, run)
                }
            };
            solved.ok_or_else(|| Error::Invalid("the graph is not connected".into()))
        };
        // A tree under auto (or asked for): composed and certified without an iteration or a
        // factorization (Props. 1, 6, 11); where the cost of the composition, all rounding, is not
        // within the tolerance, the solvers as for any graph.
        let tree = (matches!(options.method, Method::Auto | Method::Tree) && tree::is_tree(&part))
            .then(|| -> crate::Result<_> {
                check_edge_terms(&part, &weights, &weights)?;
                Ok(tree::solve_tree(&part, &weights, options.tolerance))
            })
            .transpose()?
            .filter(|(report, _)| report.certified);
        let (mut report, mut poses) = match tree {
            Some(solved) => solved,
            None => {
                // The first method as chosen; where it certifies, its result as it is.
                let mut algorithm1 = None;
                let mut scalable = None;
                if sdp {
                    algorithm1 = Some(run_sdp()?);
                } else {
                    scalable = Some(run_staircase()?);
                }
                let mut first = match (&algorithm1, &scalable) {
                    (Some(a), _) => sdp_report(&part, a, options.tolerance),
                    (_, Some((s, _))) => staircase_report(&part, s, options.tolerance),
                    _ => unreachable!("one method ran"),
                };
                // A staircase estimate left unchecked (`certify` off) is the answer too.
                let unchecked = !options.certify && scalable.is_some();
                if unchecked {
                    first.not_certified_because = Some("not checked (certify off)".to_string());
                }
                if first.certified || unchecked {
                    let poses = match (algorithm1, scalable) {
                        (Some(a), _) => a.poses,
                        (_, Some((_, p))) => p,
                        _ => unreachable!("one method ran"),
                    };
                    (first, poses)
                } else {
                    // Not certified: under auto the other method too (Algorithm 1 up to
                    // AUTO_SECOND_SDP_MAX_POSES poses), every rounding polished, the lowest f kept
                    // and the highest proven bound.
                    if options.method == Method::Auto {
                        if scalable.is_none() {
                            scalable = Some(run_staircase()?);
                        } else if n <= AUTO_SECOND_SDP_MAX_POSES {
                            algorithm1 = Some(run_sdp()?);
                        }
                    }
                    best_of(
                        &part,
                        &weights,
                        first,
                        algorithm1.as_ref(),
                        scalable.as_ref(),
                        options.tolerance,
                        &staircase,
                    )
                }
            }
        };
        // The gauge: a FIX pose stays where the input has it (the solvers place pose 0 there).
        if let Some(k) = fixed {
            poses = move_pose_to(&poses, k, part.poses[k]);
        }
        report.certified_chi2 = Some(crate::refine::chi2(&part, &poses)).filter(|c| c.is_finite());
        if options.refine {
            // Levenberg-Marquardt holds the FIX pose (or pose 0) where it is.
            crate::progress::phase("refinement (Levenberg-Marquardt)");
            let refined = crate::refine::refine(&part, &poses, &Default::default())?;
            report.refined_chi2 = Some(refined.chi2);
            report.refine_iterations = Some(refined.iterations);
            poses = refined.poses;
        }
        let at = (part.num_poses(), &members[..], &landmark_index[..]);
        place(poses, fixed, at, &mut estimate, &mut landmark_estimate);
        report.landmarks = part.landmarks.len();
        report.observations = part.landmarks.observations.len();
        components.push(report);
    }
    // Folded from +0: an empty sum of f64 is -0 in Rust, and a graph without edges costs 0.
    let cost = components.iter().fold(0.0, |a, c| a + c.cost);
    let lower_bound = components.iter().fold(0.0, |a, c| a + c.lower_bound);
    let suboptimality_bound = cost - lower_bound;
    let chi2 = components
        .iter()
        .try_fold(0.0, |a, c| c.certified_chi2.map(|x| a + x));
    Ok(Solution {
        method: options.method,
        solver: options.solver,
        weights: options.weights,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        landmarks: graph.landmarks.len(),
        observations: graph.landmarks.observations.len(),
        cost,
        chi2,
        lower_bound,
        suboptimality_bound,
        refined_chi2: options
            .refine
            .then(|| components.iter().filter_map(|c| c.refined_chi2).sum()),
        relative_suboptimality_bound: suboptimality_bound / cost.abs().max(1.0),
        certified: components.iter().all(|c| c.certified),
        not_certified_because: reasons(&components),
        szep: components.iter().all(|c| c.szep),
        near_zero_eigenvalues: components.iter().map(|c| c.near_zero_eigenvalues).sum(),
        sdp_converged: components.iter().all(|c| c.sdp_converged != Some(false)),
        components,
        estimate,
        landmark_estimate,
    })
}

/// Refuses several fixed poses in one connected component: they are known poses, a constrained
/// problem whose optimum and certificate differ from those of f (one fixed pose per component is
/// only the gauge, which f is invariant to).
fn check_fixed(graph: &PoseGraph) -> crate::Result<()> {
    if graph.fixed.len() < 2 {
        return Ok(());
    }
    let (label, count) = graph.connected_components();
    let mut by_component: Vec<Vec<u32>> = vec![Vec::new(); count];
    for &k in &graph.fixed {
        by_component[label[k]].push(graph.ids[k]);
    }
    match by_component.iter_mut().find(|ids| ids.len() > 1) {
        None => Ok(()),
        Some(ids) => {
            ids.sort_unstable();
            let list: Vec<String> = ids.iter().map(u32::to_string).collect();
            Err(Error::Invalid(format!(
                "FIX lines name vertices {}, which are in one connected component: several fixed \
                 poses in one component are known poses, a constrained problem that pgo does not \
                 solve or certify (one FIX per component only sets the gauge); keep at most one \
                 FIX line per component",
                list.join(", ")
            )))
        }
    }
}

/// Places a component's solved `poses` (its poses, then its landmarks as poses) in the graph's
/// `estimate` and `landmarks`, `at` = (the component's pose count, the graph index of each of its
/// poses, of each of its landmarks): headings in (-π, π] (the same rotations: f and chi2 see only
/// e^{iθ} and wrapped differences), but the `fixed` pose exactly as read.
fn place(
    mut poses: Vec<Pose2>,
    fixed: Option<usize>,
    at: (usize, &[usize], &[usize]),
    estimate: &mut [Pose2],
    landmarks: &mut [[f64; 2]],
) {
    let (np, members, landmark_index) = at;
    for (k, pose) in poses.iter_mut().enumerate() {
        if Some(k) != fixed {
            pose.theta = wrap_angle(pose.theta);
        }
    }
    for (pose, &k) in poses[..np].iter().zip(members) {
        estimate[k] = *pose;
    }
    for (p, &k) in poses[np..].iter().zip(landmark_index) {
        landmarks[k] = [p.x, p.y];
    }
}

/// The staircase's Newton steps, reported through [`crate::progress`] (the `iteration` timeline
/// of a rerun recording).
fn report_step() -> impl FnMut(&Iteration) {
    let mut step = 0u64;
    move |it: &Iteration| {
        step += 1;
        report_iteration(step, it.cost, it.gradient_norm, it.rank, it.damping);
    }
}

/// One Newton step of either staircase (planar or 3D), reported through [`crate::progress`].
fn report_iteration(step: u64, cost: f64, gradient_norm: f64, rank: usize, damping: f64) {
    crate::progress::iteration(
        step,
        &[
            ("cost", cost),
            ("gradient_norm", gradient_norm),
            ("rank", rank as f64),
            ("damping", damping),
        ],
    );
}

/// Whether `suboptimality_bound` is within the relative `tolerance` of `cost`.
fn within(suboptimality_bound: f64, cost: f64, tolerance: f64) -> bool {
    suboptimality_bound <= tolerance * cost.abs().max(1.0)
}

/// What every method reports of a component: its cost and proven bound, certified when `proven`
/// (the method's own condition) holds and the gap is within `tolerance`; the method's own figures
/// left out.
#[allow(clippy::too_many_arguments)]
fn component_report(
    part: &PoseGraph,
    method: Method,
    cost: f64,
    lower_bound: f64,
    proven: bool,
    szep: bool,
    near_zero_eigenvalues: usize,
    tolerance: f64,
) -> ComponentReport {
    let suboptimality_bound = cost - lower_bound;
    ComponentReport {
        first_id: part.ids[0],
        poses: part.num_poses(),
        edges: part.edges.len(),
        landmarks: part.landmarks.len(),
        observations: part.landmarks.observations.len(),
        cost,
        lower_bound,
        suboptimality_bound,
        certified: proven && within(suboptimality_bound, cost, tolerance),
        szep,
        near_zero_eigenvalues,
        method,
        ..Default::default()
    }
}

fn sdp_report(part: &PoseGraph, s: &ComponentSolution, tolerance: f64) -> ComponentReport {
    ComponentReport {
        rounding: Some(s.rounding),
        penalized_eigenvalues: Some(s.eigenvalues.iter().take(4).copied().collect()),
        sdp_iterations: Some(s.dual.iterations),
        sdp_converged: Some(s.dual.converged),
        ..component_report(
            part,
            Method::Sdp,
            s.cost,
            s.lower_bound,
            s.szep,
            s.szep,
            s.near_zero,
            tolerance,
        )
    }
}

fn staircase_report(part: &PoseGraph, s: &StaircaseSolution, tolerance: f64) -> ComponentReport {
    ComponentReport {
        rank: Some(s.rank),
        iterations: Some(s.iterations),
        eta: s.bound.map(|b| b.eta),
        gradient_norm: Some(s.gradient_norm),
        ..component_report(
            part,
            Method::Staircase,
            s.cost,
            s.lower_bound,
            s.bound.is_some(),
            s.near_zero.is_some_and(|z| z <= 1),
            s.near_zero.unwrap_or(0),
            tolerance,
        )
    }
}

/// The components' reasons for not being certified (see [`Solution::not_certified_because`]).
fn reasons(components: &[ComponentReport]) -> Option<String> {
    let several = components.len() > 1;
    let all: Vec<String> = components
        .iter()
        .filter_map(|c| {
            let why = c.not_certified_because.as_ref()?;
            Some(if several {
                format!("component at id {}: {why}", c.first_id)
            } else {
                why.clone()
            })
        })
        .collect();
    (!all.is_empty()).then(|| all.join("; "))
}

/// Why neither method certified: what each one that ran reports.
fn reason(
    algorithm1: Option<&ComponentSolution>,
    scalable: Option<&(StaircaseSolution, Vec<Pose2>)>,
    staircase: &StaircaseOptions,
) -> String {
    let mut why = Vec::new();
    if let Some(a) = algorithm1 {
        if !a.dual.converged {
            why.push("SDP stalled".to_string());
        }
        if !a.szep {
            why.push(format!(
                "SZEP fails: {} near-zero eigenvalues of W(lambda*)",
                a.near_zero
            ));
        }
    }
    if let Some((s, _)) = scalable {
        if algorithm1.is_none()
            && let Some(k) = s.near_zero.filter(|&k| k > 1)
        {
            why.push(format!(
                "SZEP fails: {k} near-zero eigenvalues of W(lambda)"
            ));
        }
        if let Some(h) = &s.hidden_gap {
            why.push(hidden_gap_reason(h));
        } else if s.bound.is_none() {
            why.push(format!("staircase: no certificate up to rank {}", s.rank));
        }
        if s.limit_reached {
            why.push(format!(
                "staircase: work budget reached (--staircase-budget {}: {:e} multiply-adds of its factorizations)",
                staircase.staircase_budget / 1e9,
                staircase.staircase_budget
            ));
        }
        if s.rank >= staircase.max_rank {
            why.push(format!("staircase: rank limit {}", staircase.max_rank));
        }
    }
    if why.is_empty() {
        why.push("the gap to the bound exceeds the tolerance".to_string());
    }
    why.join("; ")
}

/// Why a hidden gap ([`crate::certify::HiddenGap`]) leaves the estimate uncertified: the SZEP
/// is neither proven nor refuted at double precision's resolution.
fn hidden_gap_reason(h: &crate::certify::HiddenGap) -> String {
    let precise = match h.precise_limit {
        Some(limit) => format!(
            "the double-double retry is limited to {limit:.0e} factor entries and this factor has {:.1e}",
            h.factor_entries as f64
        ),
        None => "double-double did not resolve it either".to_string(),
    };
    let measured = match h.measured {
        Some(m) => format!(", its residual measured {m:.2e}"),
        None => String::new(),
    };
    format!(
        "SZEP unresolved: the second eigenvalue of W(lambda) is below the rounding of its \
         factorization (equilibrated, its LDL^H shows at most one negative pivot at the shift \
         {:.2e}, but the error bound there is {:.2e}{measured}); {precise}",
        h.shift, h.error
    )
}

/// The lowest-cost estimate of every polished rounding of the methods that ran (see
/// [`best`]), with the highest of their proven bounds (both bound the same f*, of the same
/// weights); certified if that bound proves the estimate returned within `tolerance`.
fn best_of(
    part: &PoseGraph,
    weights: &[EdgeWeight],
    first: ComponentReport,
    algorithm1: Option<&ComponentSolution>,
    scalable: Option<&(StaircaseSolution, Vec<Pose2>)>,
    tolerance: f64,
    staircase: &StaircaseOptions,
) -> (ComponentReport, Vec<Pose2>) {
    let from_staircase = scalable.map(|(_, poses)| best::Candidate {
        poses: poses.clone(),
        cost: cost(part, weights, poses),
        rounding: None,
    });
    let from_sdp = algorithm1
        .map(|a| best::sdp_candidates(part, weights, a, staircase))
        .unwrap_or_default();
    let mut candidates = Vec::new();
    if first.method == Method::Sdp {
        candidates.extend(from_sdp);
        candidates.extend(from_staircase);
    } else {
        candidates.extend(from_staircase);
        candidates.extend(from_sdp);
    }
    let winner = candidates.swap_remove(best::lowest(&candidates));
    let mut report = match (winner.rounding, algorithm1, scalable) {
        (Some(_), Some(a), _) => sdp_report(part, a, tolerance),
        (_, _, Some((s, _))) => staircase_report(part, s, tolerance),
        _ => first,
    };
    if let Some(a) = algorithm1 {
        report.penalized_eigenvalues = Some(a.eigenvalues.iter().take(4).copied().collect());
        report.sdp_iterations = Some(a.dual.iterations);
        report.sdp_converged = Some(a.dual.converged);
        report.szep = a.szep;
        report.near_zero_eigenvalues = a.near_zero;
    }
    if let Some((s, _)) = scalable {
        report.rank = Some(s.rank);
        report.iterations = Some(s.iterations);
        report.eta = s.bound.map(|b| b.eta);
    }
    if winner.rounding.is_some() {
        report.method = Method::Sdp;
        report.rounding = winner.rounding;
        report.gradient_norm = None;
    }
    let lower_bound = algorithm1
        .map(|a| a.lower_bound)
        .into_iter()
        .chain(scalable.map(|(s, _)| s.lower_bound))
        .fold(0.0f64, f64::max);
    report.cost = winner.cost;
    report.lower_bound = lower_bound;
    report.suboptimality_bound = winner.cost - lower_bound;
    report.certified = within(report.suboptimality_bound, winner.cost, tolerance);
    report.not_certified_because =
        (!report.certified).then(|| reason(algorithm1, scalable, staircase));
    (report, winner.poses)
}
