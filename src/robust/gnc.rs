//! Graduated non-convexity (GNC; Yang, Antonante, Tzoumas and Carlone, "Graduated Non-Convexity
//! for Robust Spatial Perception: From Non-Minimal Solvers to Global Outlier Rejection", RA-L
//! 2020) with pgo's certified solver as the non-minimal solver, following the schedule and the
//! stopping rules of GTSAM's `GncOptimizer`.
//!
//! The robust problem is min_x Σ_e ρ(r_e(x)) over the edges e, with the edge's residual
//!
//! ```text
//! r_e²(x) = ½ (τ_e |p_j − p_i − r_i Δ_e|² + ½ κ_e |r_j − r_i R_e|²)
//! ```
//!
//! with the weights τ_e, κ_e of `--weights`: under the isotropic weights (τ = 2/tr(Ω_tt⁻¹),
//! κ = 2Ω_θθ) and |r_j − r_i R_e|² = 2 − 2cos e_θ ≈ e_θ², this is GTSAM's error ½ eᵀΩe of an
//! isotropic Ω to first order, the quantity GTSAM's threshold is a chi-square quantile of (f's
//! own edge term counts the rotation twice: SE-Sync's κ). ρ is the truncated least squares
//! ρ(r) = min(r², c̄²) (TLS) or Geman-McClure ρ(r) = c̄² r² / (c̄² + r²) (GM). GNC replaces ρ by
//! a surrogate ρ_μ (paper eq. (8) for GM, eq. (10) for TLS) and, by the Black-Rangarajan duality
//! (paper Sec. III-A, eq. (5)), alternates
//!
//! 1. the weighted problem min_x Σ_e w_e r_e²(x) (the variable update of the paper's
//!    Algorithm 1): pgo's f with the weights w_e τ_e and w_e κ_e / 2, solved by
//!    [`crate::solve::solve`] (certified for those weights, where the relaxation is exact, only
//!    with [`RobustOptions::certify_inner`]: GNC uses the estimate);
//! 2. the weights in closed form (paper eq. (12) for GM, eq. (14) for TLS):
//!    GM: w_e = (μc̄² / (r_e² + μc̄²))²;
//!    TLS: w_e = 1 if r_e² ≤ μ/(μ+1) c̄², 0 if r_e² ≥ (μ+1)/μ c̄², else c̄ √(μ(μ+1)) / r_e − μ;
//!
//! then steps μ towards the original loss: TLS starts convex at μ₀ = c̄² / (2 r²_max − c̄²)
//! (paper Remark 5) and multiplies μ by the step (1.4) each iteration, GM starts at
//! μ₀ = 2 r²_max / c̄² and divides it by the step down to 1. r²_max is the largest residual of an
//! uncertain edge at the least-squares estimate (every weight 1), the estimate the first weights
//! are computed from; if 2 r²_max ≤ c̄² (TLS) every edge is an inlier and GNC stops there
//! (GTSAM's rule). GTSAM's `initializeMu` takes r²_max at its initial values instead (here: the
//! file's vertices), a larger value and a smaller μ₀. Tried on intel.g2o with Vertigo's random
//! outliers, that rule found 10 of 10 outliers at seed 2 (this one: 9), 499 of 500 at seed 1
//! (496), 983 of 1000 at seed 1 (992), in 3-4 times the iterations. It stops when the weights are binary within 10⁻⁴ (TLS),
//! when μ reaches 1 (GM), when the weighted cost Σ w_e r_e² changes by less than 10⁻⁵ relative
//! from one iteration to the next, or after 100 iterations (GTSAM's defaults).
//!
//! The threshold c̄² is GTSAM's rule `0.5 * chi2inv(0.99, 3)` by default: an edge whose noise is
//! as its (isotropic) information says stays below it with probability 99%.
//! Odometry edges (between consecutive ids) are known inliers with weight 1 unless told
//! otherwise (GTSAM's `knownInliers`).
//!
//! The answer: edges of final weight ≥ ½ are the inliers (TLS weights end binary); the graph of
//! the inliers alone is solved once more under the weights τ_e, κ_e of `--weights` (pgo's f, not
//! the κ/2 of the residual) and certified. That certificate proves the estimate optimal for the
//! inlier set, which GNC chose: it says nothing of the TLS problem's global optimum.
//!
//! The inner problems are solved without the Riemannian staircase by default (its budget above
//! rank 1 is [`RobustOptions::inner_staircase_budget`], 0): GNC needs their estimates,
//! not their certificates, and the early ones, with outliers still weighted, are the problems
//! whose relaxation is not exact, where the staircase spends its whole budget in vain (on
//! manhattan + 100 outliers: 16 s of CPU with a budget of 100 Newton steps, 1.7 s without, the
//! same inliers found). The final inlier-set problem gets the full budget of `solve`.
//!
//! Warm starts ([`RobustOptions::warm_start`], off by default): the paper's variable update (its
//! Algorithm 1: the weighted problem above with the weights of eq. (12) or (14) fixed) needs a
//! minimizer of the weighted problem, from any start. With warm starts each inner problem after
//! the first, and the inlier set's problem, start from the previous iteration's estimate
//! ([`crate::solve::solve_from`]: Riemannian Newton from its headings); without, from the chordal
//! initialization of the new weights ([`crate::solve::solve`]). The certificate proves whichever
//! point Newton reaches, either way. The chordal start wins: in the early iterations, with the
//! outliers still weighted, the relaxation is not exact and the weighted problem has several
//! minima; the previous estimate, an optimum for more outlier weight, keeps Newton in a basin
//! the chordal initialization of the new weights leaves, and GNC then settles on other inlier
//! sets. In the late iterations the chordal start is near the optimum already and Newton needs
//! 3-4 steps from either start. Measured (whole process, `pgo-solve --robust tls` against
//! `--warm-start`, interleaved, medians of per-run ratios; README, "Outliers"): on CSAIL, intel
//! and M3500 with 100 random outliers (seeds 1-3) the warm start took 1.91x the time and
//! rejected 317 true edges in all (the chordal start 8); with 1000 outliers 0.88x the time on
//! CSAIL and intel and 0.92x on M3500, where it stopped early at worse inlier sets (565 and 890
//! true edges rejected, against 14 and 30); on city10000 with 100 outliers 2.84x the time and
//! 1050 true edges rejected, against none.

use super::outliers::is_odometry;
use crate::error::Error;
use crate::graph::{Edge, NoiseKind, Pose2, PoseGraph, SymMat3};
use crate::problem::matrix::edge_cost;
use crate::problem::weights::{EdgeWeight, Weights, edge_weights};
use crate::solve::{Solution, SolveOptions, solve, solve_from};
use serde::Serialize;

/// The robust loss ρ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Loss {
    /// Truncated least squares: rho(r) = min(r^2, c^2)
    Tls,
    /// Geman-McClure: rho(r) = c^2 r^2 / (c^2 + r^2)
    Gm,
}

impl Loss {
    pub fn name(self) -> &'static str {
        match self {
            Loss::Tls => "tls",
            Loss::Gm => "gm",
        }
    }
}

/// The 0.99 quantile of the chi-square distribution with 3 degrees of freedom,
/// chi2inv(0.99, 3).
pub const CHI2_99_3: f64 = 11.344_866_730_144_373;

/// GTSAM's default inlier threshold c̄² = ½ chi2inv(0.99, 3).
pub const DEFAULT_INLIER_THRESHOLD: f64 = 0.5 * CHI2_99_3;

/// The Newton steps at rank 1 of each inner weighted problem, whatever their work (its
/// [`crate::SolveOptions::min_descent_steps`]; the budget of the inner problems is 0). More than
/// a clean solve's [`crate::staircase::MIN_DESCENT_STEPS`]: the early inner problems, with the
/// outliers still weighted, converge slowly, and GNC's next weights need their minimizer. With 12
/// steps in place of 50 intel + 1000 random outliers lost 24 more true loop closures (37 of 785
/// against 13), though city10000 + 1000 took 16 s in place of 26.
pub const INNER_NEWTON_STEPS: usize = 50;

/// What [`robust_solve`] is asked for.
#[derive(Debug, Clone, Copy)]
pub struct RobustOptions {
    pub loss: Loss,
    /// c̄², compared with r_e² (see the module documentation).
    pub inlier_threshold: f64,
    /// The factor μ grows by (TLS) or shrinks by (GM) each iteration.
    pub mu_step: f64,
    pub max_iterations: usize,
    /// Stop when the weighted cost changes by less than this, relative.
    pub relative_cost_tolerance: f64,
    /// TLS: stop when every weight is within this of 0 or 1.
    pub weights_tolerance: f64,
    /// Odometry edges (consecutive ids) keep weight 1.
    pub odometry_inliers: bool,
    /// The staircase's work budget for the inner weighted problems, in multiply-adds (at most
    /// `solve.staircase_budget`; default 0: Riemannian Newton at rank 1 only, at most
    /// [`INNER_NEWTON_STEPS`] steps, certified where the certificate holds);
    /// the final inlier-set problem gets the full budget.
    pub inner_staircase_budget: f64,
    /// Warm starts: each inner problem after the first (the least-squares one), and the inlier
    /// set's problem, solved from the previous iteration's estimate
    /// ([`crate::solve::solve_from`]) instead of the chordal initialization. Off by default: it
    /// does not pay (module documentation, "Warm starts").
    pub warm_start: bool,
    /// Whether each inner weighted problem's estimate is proven optimal for its weights (off by
    /// default). GNC uses their estimates only. The certificates cost a symbolic analysis and one
    /// or more sparse factorizations each (a search over the shift η where the relaxation is not
    /// exact, as in the early iterations): without them `pgo-solve --robust tls` takes 0.70x the
    /// time on intel + 100 random outliers and 0.77x on M3500 + 1000 (interleaved runs), for the
    /// same estimates. The inlier set's problem is certified either way.
    pub certify_inner: bool,
    /// How the inner problems and the final one are solved (`weights` sets τ_e, κ_e; the inner
    /// problems are never refined, the final one if `refine` is set).
    pub solve: SolveOptions,
}

impl Default for RobustOptions {
    fn default() -> Self {
        RobustOptions {
            loss: Loss::Tls,
            inlier_threshold: DEFAULT_INLIER_THRESHOLD,
            mu_step: 1.4,
            max_iterations: 100,
            relative_cost_tolerance: 1e-5,
            weights_tolerance: 1e-4,
            odometry_inliers: true,
            inner_staircase_budget: 0.0,
            warm_start: false,
            certify_inner: false,
            solve: SolveOptions::default(),
        }
    }
}

/// Why GNC stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StopReason {
    /// Every edge is a known inlier.
    NoUncertainEdges,
    /// Every residual of the least-squares estimate is below the threshold (TLS), or zero (GM).
    AllBelowThreshold,
    /// The TLS weights are binary.
    BinaryWeights,
    /// GM's μ reached 1.
    MuConverged,
    /// The weighted cost changed by less than the tolerance.
    CostConverged,
    IterationLimit,
}

impl StopReason {
    pub fn text(self) -> &'static str {
        match self {
            StopReason::NoUncertainEdges => "every edge is a known inlier",
            StopReason::AllBelowThreshold => {
                "every residual of the least-squares estimate is below the threshold"
            }
            StopReason::BinaryWeights => "the weights are binary",
            StopReason::MuConverged => "mu reached 1",
            StopReason::CostConverged => "the weighted cost converged",
            StopReason::IterationLimit => "iteration limit",
        }
    }
}

/// One GNC iteration: the weights of μ, then the weighted problem solved.
#[derive(Debug, Clone, Serialize)]
pub struct GncIteration {
    pub mu: f64,
    /// Σ_e w_e r_e² at the inner estimate.
    pub weighted_cost: f64,
    /// Edges of weight below ½.
    pub outliers: usize,
    /// Whether the inner problem's solve was certified (for its weights); `None` where it was
    /// not checked ([`RobustOptions::certify_inner`] off).
    pub certified: Option<bool>,
    /// Newton iterations of the inner solve (the scalable solver's, all components together;
    /// components solved by Algorithm 1 count none).
    pub newton_iterations: usize,
    /// Per edge: w_e at this iteration (the viewer draws them; not in the JSON report).
    #[serde(skip)]
    pub weights: Vec<f64>,
}

/// What [`robust_solve`] found.
#[derive(Debug)]
pub struct RobustSolution {
    /// The problem of the inlier set (the graph without the rejected edges) solved: its cost,
    /// bound and certificate are of that problem.
    pub solution: Solution,
    /// Per edge of the input graph, in its order: whether GNC rejected it.
    pub rejected: Vec<bool>,
    /// Per edge: the final GNC weight.
    pub weights: Vec<f64>,
    /// Per edge: r_e² at the final (inlier-set) estimate.
    pub residuals: Vec<f64>,
    /// Per edge: whether it was uncertain (not a known inlier).
    pub uncertain: Vec<bool>,
    pub iterations: Vec<GncIteration>,
    pub stop: StopReason,
    /// The μ of the last iteration (μ₀ where none ran; absent where GNC did not start).
    pub mu: Option<f64>,
}

impl RobustSolution {
    pub fn rejected_count(&self) -> usize {
        self.rejected.iter().filter(|&&r| r).count()
    }
}

/// ½ of each edge's term of f under `base` at `poses`: r_e² when `base` holds (τ_e, κ_e / 2)
/// (see the module documentation).
pub fn residuals(
    graph: &PoseGraph,
    base: &[EdgeWeight],
    poses: &[crate::graph::Pose2],
) -> Vec<f64> {
    graph
        .edges
        .iter()
        .zip(base)
        .map(|(e, &w)| 0.5 * edge_cost(e, w, poses))
        .collect()
}

/// The weights of the residual r_e² (module documentation): τ_e and κ_e / 2.
fn residual_weights(graph: &PoseGraph, weights: Weights) -> crate::Result<Vec<EdgeWeight>> {
    Ok(edge_weights(graph, weights)?
        .into_iter()
        .map(|w| EdgeWeight {
            tau: w.tau,
            kappa: 0.5 * w.kappa,
        })
        .collect())
}

/// Loop closures at an estimate that GNC would start out rejecting: those (every edge but the
/// odometry, as `robust_solve`'s default) whose residual r_e² at `poses` exceeds `threshold`
/// (c̄², [`DEFAULT_INLIER_THRESHOLD`] by default). Returned with the number of loop closures.
/// For a solve that is not certified, a sign of false loop closures, which make the relaxation
/// inexact (issue 14): under the noise model about 1% of true ones exceed c̄² = ½χ²₀.₉₉(3).
///
/// # Errors
///
/// Those of the weights ([`edge_weights`]).
pub fn suspect_loop_closures(
    graph: &PoseGraph,
    weights: Weights,
    poses: &[Pose2],
    threshold: f64,
) -> crate::Result<(usize, usize)> {
    let base = residual_weights(graph, weights)?;
    let r2 = residuals(graph, &base, poses);
    let closures = graph.edges.iter().map(|e| !is_odometry(graph, e));
    Ok(closures
        .zip(&r2)
        .filter(|(closure, _)| *closure)
        .fold((0, 0), |(above, all), (_, &r2)| {
            (above + usize::from(r2 > threshold), all + 1)
        }))
}

/// The GNC weight of an edge of residual `r2` at `mu` (paper eq. (12) and (14)).
pub fn weight(loss: Loss, r2: f64, mu: f64, c2: f64) -> f64 {
    match loss {
        Loss::Gm => {
            let a = mu * c2;
            (a / (r2 + a)).powi(2)
        }
        Loss::Tls => {
            if r2 >= (mu + 1.0) / mu * c2 {
                0.0
            } else if r2 <= mu / (mu + 1.0) * c2 {
                1.0
            } else {
                ((c2 * mu * (mu + 1.0) / r2).sqrt() - mu).clamp(0.0, 1.0)
            }
        }
    }
}

/// The initial μ (paper Remark 5), `None` when GNC has nothing to do (TLS: every residual below
/// c̄²; GM: every residual zero).
fn initial_mu(loss: Loss, r2_max: f64, c2: f64) -> Option<f64> {
    match loss {
        Loss::Tls => (2.0 * r2_max > c2).then(|| c2 / (2.0 * r2_max - c2)),
        Loss::Gm => (r2_max > 0.0).then(|| (2.0 * r2_max / c2).max(1.0)),
    }
}

/// The graph of the weighted problem: each edge's information replaced by the isotropic one
/// whose weights are w_e τ_e, w_e κ_e (Ω = diag(wτ, wτ, wκ/2), so that `--weights isotropic`
/// gives back exactly τ = wτ, κ = wκ); edges of weight 0 (or whose weighted τ, κ underflow) left
/// out. Returns the graph and the input positions of its edges.
fn weighted_graph(graph: &PoseGraph, base: &[EdgeWeight], w: &[f64]) -> PoseGraph {
    let mut edges = Vec::with_capacity(graph.edges.len());
    for ((e, b), &w) in graph.edges.iter().zip(base).zip(w) {
        let (tau, kappa) = (w * b.tau, w * b.kappa);
        if !(tau.is_normal() && kappa.is_normal() && tau > 0.0 && kappa > 0.0) {
            continue;
        }
        edges.push(Edge {
            noise: SymMat3([tau, 0.0, 0.0, tau, 0.0, 0.5 * kappa]),
            ..*e
        });
    }
    PoseGraph {
        ids: graph.ids.clone(),
        poses: graph.poses.clone(),
        edges,
        fixed: graph.fixed.clone(),
        vertices_declared: graph.vertices_declared,
        noise: NoiseKind::Information,
        landmarks: Default::default(),
    }
}

/// The graph without the edges marked in `drop`.
pub fn without_edges(graph: &PoseGraph, drop: &[bool]) -> PoseGraph {
    PoseGraph {
        edges: graph
            .edges
            .iter()
            .zip(drop)
            .filter(|(_, d)| !**d)
            .map(|(e, _)| *e)
            .collect(),
        ..graph.clone()
    }
}

/// Solves `graph` robustly by GNC (see the module documentation) and certifies the estimate for
/// the inlier set found. Iterations are reported through [`crate::progress`].
///
/// # Errors
///
/// Those of [`solve`]; an invalid threshold or μ step.
pub fn robust_solve(graph: &PoseGraph, options: &RobustOptions) -> crate::Result<RobustSolution> {
    if !graph.landmarks.is_empty() {
        return Err(Error::Invalid(format!(
            "robust estimation of landmark graphs is not supported yet (this graph has {} landmarks): solve without --robust",
            graph.landmarks.len()
        )));
    }
    let c2 = options.inlier_threshold;
    if !(c2.is_finite() && c2 > 0.0) {
        return Err(Error::Invalid(format!(
            "the inlier threshold must be a finite number > 0, found {c2}"
        )));
    }
    if !(options.mu_step.is_finite() && options.mu_step > 1.0) {
        return Err(Error::Invalid(format!(
            "the mu step must be a finite number > 1, found {}",
            options.mu_step
        )));
    }
    let base = residual_weights(graph, options.solve.weights)?;
    let m = graph.edges.len();
    let uncertain: Vec<bool> = graph
        .edges
        .iter()
        .map(|e| !(options.odometry_inliers && is_odometry(graph, e)))
        .collect();
    let inner_options = SolveOptions {
        weights: Weights::Isotropic,
        refine: false,
        staircase_budget: options
            .inner_staircase_budget
            .min(options.solve.staircase_budget),
        min_descent_steps: INNER_NEWTON_STEPS,
        certify: options.certify_inner,
        // The inlier set's problem, solved after, refines them as any solve does.
        refine_rotations: false,
        ..options.solve
    };
    let inner = |w: &[f64], start: Option<&[Pose2]>| -> crate::Result<Solution> {
        let weighted = weighted_graph(graph, &base, w);
        match start {
            Some(start) if options.warm_start => solve_from(&weighted, start, &inner_options),
            _ => solve(&weighted, &inner_options),
        }
    };
    let weighted_cost = |w: &[f64], r2: &[f64]| w.iter().zip(r2).fold(0.0, |a, (w, r)| a + w * r);

    let mut w = vec![1.0; m];
    // The last inner estimate (GNC's x), the final problem's warm start.
    let mut last: Option<Vec<Pose2>> = None;
    let mut iterations = Vec::new();
    let mut mu = None;
    let stop = 'gnc: {
        if !uncertain.iter().any(|&u| u) {
            break 'gnc StopReason::NoUncertainEdges;
        }
        crate::progress::phase("GNC: least squares (every weight 1)");
        let first = inner(&w, None)?;
        let mut r2 = residuals(graph, &base, &first.estimate);
        let mut estimate = first.estimate;
        let r2_max = r2
            .iter()
            .zip(&uncertain)
            .filter(|(_, u)| **u)
            .fold(0.0f64, |a, (r, _)| a.max(*r));
        let Some(mu0) = initial_mu(options.loss, r2_max, c2) else {
            break 'gnc StopReason::AllBelowThreshold;
        };
        let mut mu_k = mu0;
        let mut previous = weighted_cost(&w, &r2);
        for k in 0..options.max_iterations {
            mu = Some(mu_k);
            for e in 0..m {
                if uncertain[e] {
                    w[e] = weight(options.loss, r2[e], mu_k, c2);
                }
            }
            crate::progress::phase(&format!("GNC iteration {} (mu {mu_k:.4e})", k + 1));
            let s = inner(&w, Some(&estimate))?;
            r2 = residuals(graph, &base, &s.estimate);
            let cost = weighted_cost(&w, &r2);
            let outliers = w.iter().filter(|&&x| x < 0.5).count();
            iterations.push(GncIteration {
                mu: mu_k,
                weighted_cost: cost,
                outliers,
                certified: options.certify_inner.then_some(s.certified),
                newton_iterations: s.components.iter().filter_map(|c| c.iterations).sum(),
                weights: w.clone(),
            });
            estimate = s.estimate;
            last = Some(estimate.clone());
            crate::progress::iteration(
                k as u64 + 1,
                &[
                    ("mu", mu_k),
                    ("weighted_cost", cost),
                    ("outliers", outliers as f64),
                ],
            );
            // GTSAM's checkConvergence: cost, weights, then mu.
            if (cost - previous).abs() / previous.max(1e-7) < options.relative_cost_tolerance {
                break 'gnc StopReason::CostConverged;
            }
            if options.loss == Loss::Tls
                && w.iter()
                    .all(|&x| (x - x.round()).abs() <= options.weights_tolerance)
            {
                break 'gnc StopReason::BinaryWeights;
            }
            if options.loss == Loss::Gm && (mu_k - 1.0).abs() < 1e-9 {
                break 'gnc StopReason::MuConverged;
            }
            mu_k = match options.loss {
                Loss::Tls => mu_k * options.mu_step,
                Loss::Gm => (mu_k / options.mu_step).max(1.0),
            };
            previous = cost;
        }
        StopReason::IterationLimit
    };
    let rejected: Vec<bool> = w
        .iter()
        .zip(&uncertain)
        .map(|(&x, &u)| u && x < 0.5)
        .collect();
    crate::progress::phase("the inlier set's problem");
    let inliers = without_edges(graph, &rejected);
    let solution = match &last {
        Some(start) if options.warm_start => solve_from(&inliers, start, &options.solve)?,
        _ => solve(&inliers, &options.solve)?,
    };
    let residuals = residuals(graph, &base, &solution.estimate);
    Ok(RobustSolution {
        solution,
        rejected,
        weights: w,
        residuals,
        uncertain,
        iterations,
        stop,
        mu,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tls_weights_by_hand() {
        // mu = 1, c² = 1: weight 1 up to r² = ½, 0 from r² = 2, between them √2/r − 1.
        assert_eq!(weight(Loss::Tls, 0.5, 1.0, 1.0), 1.0);
        assert_eq!(weight(Loss::Tls, 2.0, 1.0, 1.0), 0.0);
        let w = weight(Loss::Tls, 1.0, 1.0, 1.0);
        assert!((w - (2f64.sqrt() - 1.0)).abs() < 1e-15);
        // GM at mu = 1, r² = c²: (c² / 2c²)² = ¼.
        assert_eq!(weight(Loss::Gm, 3.0, 1.0, 3.0), 0.25);
    }

    #[test]
    fn initial_mu_of_remark_5() {
        // TLS: c² / (2 r²max − c²) = 1 / (2·5 − 1).
        assert_eq!(initial_mu(Loss::Tls, 5.0, 1.0), Some(1.0 / 9.0));
        assert_eq!(initial_mu(Loss::Tls, 0.5, 1.0), None);
        // GM: 2 r²max / c².
        assert_eq!(initial_mu(Loss::Gm, 5.0, 1.0), Some(10.0));
    }

    #[test]
    fn suspect_loop_closures_by_hand() {
        // Poses on the x axis at 0..4, unit information: τ = 2 / tr(I₂⁻¹) = 1, and no rotation
        // error, so r² = ½ τ |p_j − p_i − t_ij|² (module docs: the weights τ and κ / 2, halved).
        let mut text: String = (0..5)
            .map(|k| format!("VERTEX_SE2 {k} {k} 0 0\n"))
            .collect();
        let info = "1 0 0 1 0 1";
        // Odometry, the last one 5 m off (r² = 12.5): a known inlier, never counted.
        for k in 0..3 {
            text += &format!("EDGE_SE2 {k} {} 1 0 0 {info}\n", k + 1);
        }
        text += &format!("EDGE_SE2 3 4 1 5 0 {info}\n");
        // Loop closures: exact (r² = 0); 3 m off (4.5, below c̄² = 5.672); 3.5 m off (6.125);
        // 10 m off (50).
        text += &format!("EDGE_SE2 0 2 2 0 0 {info}\n");
        text += &format!("EDGE_SE2 0 3 6 0 0 {info}\n");
        text += &format!("EDGE_SE2 1 4 6.5 0 0 {info}\n");
        text += &format!("EDGE_SE2 0 4 4 10 0 {info}\n");
        let (g, _) = crate::io::read(text.as_bytes(), "t.g2o", &Default::default()).expect("reads");
        let count = |threshold| {
            suspect_loop_closures(&g, Weights::Isotropic, &g.poses, threshold).expect("weights")
        };
        assert_eq!(count(DEFAULT_INLIER_THRESHOLD), (2, 4));
        // Between 4.5 and 6.125 the count is 2; just below 4.5, 3; at 50 and above, none.
        assert_eq!(count(4.499), (3, 4));
        assert_eq!(count(50.0), (0, 4));
    }

    #[test]
    fn chi2_quantile() {
        // chi2 with 3 degrees of freedom: CDF(x) = erf(√(x/2)) − √(2x/π) e^{−x/2}; at the
        // quantile it is 0.99. erf by its series (converges for every x).
        let x = CHI2_99_3;
        let z = (x / 2.0).sqrt();
        let mut term = z;
        let mut sum = z;
        for n in 1..200 {
            term *= -z * z / n as f64;
            sum += term / (2 * n + 1) as f64;
        }
        let erf = 2.0 / std::f64::consts::PI.sqrt() * sum;
        let cdf = erf - (2.0 * x / std::f64::consts::PI).sqrt() * (-x / 2.0).exp();
        assert!((cdf - 0.99).abs() < 1e-12, "{cdf}");
    }
}
