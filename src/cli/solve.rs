//! `pgo-solve`: the globally optimal estimate of a pose graph and the bound that proves it.

use super::common::{
    InputArgs, RerunArgs, WeightArgs, check_dense_size, num, to_json_line, write_stdout,
};
use super::progress_bar::ProgressArgs;
use crate::dual::rounding::Rounding;
use crate::dual::solver::SdpSolver;
use crate::error::Error;
use crate::graph::NoiseKind;
use crate::io::{self, Format, WriteOptions};
use crate::robust::gnc::{DEFAULT_INLIER_THRESHOLD, GncIteration};
use crate::robust::{Loss, RobustOptions, RobustSolution, StopReason, robust_solve};
use crate::solve::{Method, Solution, SolveOptions, solve, solve_offering};
use clap::Parser;
use serde::Serialize;
use std::process::ExitCode;
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  pgo-solve datasets/paper_toy.g2o --weights unit -o toy-solved.g2o
  pgo-solve MIT.g2o --json -o MIT-opt.g2o | jq '{cost, lower_bound, certified}'
  pgo-solve ais2klinik.g2o -o ais2klinik-opt.g2o && pgo-certify ais2klinik.g2o --estimate ais2klinik-opt.g2o
  pgo-simulate -n 20 --seed 3 | pgo-solve - --weights unit --json -o /dev/null
  pgo-solve MIT.g2o --fail-uncertified -o MIT-opt.g2o || echo 'not certified (1) or error (2)'
  pgo-solve intel-100.g2o --robust tls --drop-outliers -o intel-inliers.g2o

Gauge: the estimate is placed in the input's frame: a component's pose named by a FIX line stays
exactly where the input has it (else its smallest id does); the cost does not depend on that
choice. Several FIX poses in one component (known poses) are refused. Headings are written in
(-pi, pi].

Exit status: 0 solved, certified or not (the result line, or \"certified\" in --json, says
which); 1 with --fail-uncertified, solved but not certified within --tol (the estimate is written
all the same and the bound printed holds); 2 an error in the input, the flags or the output, with
a message saying where.

Robust (--robust tls|gm): graduated non-convexity (Yang, Antonante, Tzoumas, Carlone, RA-L 2020)
with GTSAM's schedule: per-edge weights w_e in [0, 1] multiply tau_e and kappa_e, each weighted
problem is solved by pgo's solver, the weights follow in closed form from the residuals
r_e^2 = (tau_e |p_j - p_i - r_i Delta_e|^2 + kappa_e |r_j - r_i R_e|^2 / 2) / 2 (GTSAM's error of an
isotropic information matrix, to first order) against the threshold
c^2 (--inlier-threshold, default 0.5 * chi2inv(0.99, 3) = 5.672), mu steps by 1.4, and it stops
on binary weights or a converged cost. Odometry edges (consecutive ids) are known inliers unless
--all-edges-uncertain. Edges of final weight < 1/2 are rejected; the graph without them is then
solved again: cost, bound and \"certified\" are of that inlier set's problem, not of the TLS
problem. The report lists every rejected edge (line, ids, r^2 at the final estimate). -o writes
every edge as read, --drop-outliers only the inliers.";

/// Solve a planar or 3D pose graph to global optimality and prove it.
///
/// Small graphs (--method sdp) run the paper's Algorithm 1: the dual SDP (31), the single zero
/// eigenvalue property (SZEP) of the penalized pose graph matrix W(lambda*), its scaled null
/// vector (Sec. 5.1) or the null-space method (46) (Sec. 5.2). Larger ones (--method staircase)
/// run the scalable solver: chordal initialization, Riemannian Newton on |r_i| = 1, a sparse
/// certificate that W(lambda) + eta*blkdiag(0, I) is positive semidefinite (LDL^H inertia and
/// Temple's inequality, or a Cholesky factorization), and the Riemannian staircase when it
/// fails. The report gives the cost of the estimate, a proven lower bound on the optimum and
/// their difference, which bounds the suboptimality; "certified" means that bound is within
/// --tol. Each connected component is solved on its own.
///
/// 3D graphs (g2o VERTEX_SE3:QUAT/EDGE_SE3:QUAT, TORO VERTEX3/EDGE3) are SE-Sync's problem
/// (Rosen et al. 2019): f = sum kappa*||R_j - R_i*R_ij||_F^2 + tau*||t_j - t_i - R_i*t_ij||^2,
/// tau = 3/tr(inv(Omega_tt)), kappa = 3/(2*tr(inv(Omega_RR))), solved by the staircase on
/// St(3, p)^n from rank 3 (--max-rank P: P - 1 lifts, up to rank P + 2) and certified by the
/// inertia of one sparse LDL^T of S = Q - SymBlockDiag(Lambda) and the Lehmann-Maehly bound for
/// its three null directions. --refine on a 3D g2o graph runs Levenberg-Marquardt on SE(3)^n
/// under the full 6x6 information matrices (g2o's EDGE_SE3:QUAT error, translation and
/// quaternion vector part). --marginals, --robust and --method sdp do not apply to 3D graphs yet
/// (exit status 2), nor --refine to TORO 3D files (information over Euler angles).
#[derive(Debug, Parser)]
#[command(name = "pgo-solve", version, after_help = super::after_help(EXAMPLES))]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    /// Write the optimized graph here (- for stdout); with --json the graph goes only here
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<String>,

    /// Output format [default: from the output's extension, else the input format]
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub to: Option<Format>,

    #[command(flatten)]
    pub weights: WeightArgs,

    /// Solution method [auto: sdp for components of at most 100 poses, else staircase; a tree
    /// (no loop closure) is composed, f* = 0]
    #[arg(long, value_enum, default_value = "auto")]
    pub method: Method,

    /// SDP solver for the dual, on the components the sdp method solves (a warning if none)
    /// [default: ipm]
    #[arg(long, value_enum)]
    pub solver: Option<SdpSolver>,

    /// Relative suboptimality bound under which the result is called certified
    #[arg(long, default_value = "1e-6", value_name = "REL", value_parser = super::common::parse_tolerance, allow_negative_numbers = true)]
    pub tol: f64,

    /// The staircase's largest rank: where the certificate fails at rank 1, the scalable solver
    /// lifts the estimate to ranks 2..P (docs/method.md §3.2); a larger P can find better
    /// estimates and tighter bounds where the relaxation is not exact, at a cost that grows as
    /// P³ per Newton step
    #[arg(long, default_value = "6", value_name = "P", value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_rank: u32,

    /// The staircase's work at most, in 10⁹ multiply-adds of its sparse factorizations (Newton
    /// steps, certificate attempts), counted from the factors' structure and not timed, so the
    /// answer is the same on every machine; about 20 per second on one core. The first descent
    /// at rank 1 may always take 12 Newton steps. Past it the solver reports the best estimate
    /// and bound it reached and why it stopped. Graphs of a few hundred poses never reach the
    /// default; long false loop closures (outliers) fill the factors and reach it in seconds
    /// (try --robust)
    #[arg(long, default_value = "50", value_name = "GMA", value_parser = super::common::parse_budget, allow_negative_numbers = true)]
    pub staircase_budget: f64,

    /// Refine the certified estimate by Levenberg-Marquardt under the file's full information
    /// matrices (g2o's chi2; on SE(3)^n for 3D g2o graphs) before writing it; the report's cost
    /// and bound stay those of the
    /// certified estimate, chi2 before and after is added, and the report says that the written
    /// estimate is the refined one, which is not certified (check it with pgo-certify)
    #[arg(long)]
    pub refine: bool,

    /// Robust estimation against false loop closures by graduated non-convexity with this loss
    /// (tls: truncated least squares, gm: Geman-McClure); see Robust below
    #[arg(long, value_enum, value_name = "LOSS")]
    pub robust: Option<Loss>,

    /// With --robust: the inlier threshold c^2 on r_e^2 [default: 0.5 * chi2inv(0.99, 3) =
    /// 5.672, GTSAM's]
    #[arg(long, value_name = "C2", requires = "robust", value_parser = parse_threshold)]
    pub inlier_threshold: Option<f64>,

    /// With --robust: odometry edges (consecutive ids) may be rejected too (by default they are
    /// known inliers)
    #[arg(long, requires = "robust")]
    pub all_edges_uncertain: bool,

    /// With --robust: start each GNC inner problem after the first, and the inlier set's problem,
    /// from the previous iteration's estimate instead of the chordal initialization (slower, and
    /// worse inlier sets, on the benchmark files: see the README)
    #[arg(long, requires = "robust")]
    pub warm_start: bool,

    /// With --robust: certify each GNC inner problem for its weights too (by default only the
    /// inlier set's problem is certified: GNC uses the inner estimates, not their certificates,
    /// which took 30% of the run on intel.g2o with 100 false loop closures)
    #[arg(long, requires = "robust")]
    pub certify_inner: bool,

    /// With --robust: write the estimate without the rejected edges (by default -o holds every
    /// edge as read)
    #[arg(long, requires = "robust")]
    pub drop_outliers: bool,

    /// With --refine: write each pose's marginal covariance at the refined estimate here, one
    /// line per pose sorted by id, `id c11 c12 c13 c22 c23 c33` (the upper triangle over GTSAM's
    /// Pose2 tangent [x, y, theta], body frame, right Expmap), after a `#` comment line; the
    /// inverse of J^T Omega J over GTSAM's BetweenFactor<Pose2> Jacobians and the files'
    /// information matrices, the held poses (FIX, else each component's first) zero. What GTSAM's
    /// Marginals gives with a tight prior on the held poses. Graphs with landmarks are refused
    #[arg(long, value_name = "OUT", requires = "refine")]
    pub marginals: Option<String>,

    /// Exit with status 1 when the result is not certified within --tol (the estimate is still
    /// written); without it, status 0 either way
    #[arg(long)]
    pub fail_uncertified: bool,

    /// Print the report as one JSON object on stdout (the graph then goes only to -o)
    #[arg(long)]
    pub json: bool,

    /// Leave the timings out of the report (for byte-identical output)
    #[arg(long)]
    pub no_timings: bool,

    #[command(flatten)]
    pub progress: ProgressArgs,

    #[command(flatten)]
    pub rerun: RerunArgs,
}

fn parse_threshold(s: &str) -> Result<f64, String> {
    let t: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if t.is_finite() && t > 0.0 {
        Ok(t)
    } else {
        Err(format!(
            "--inlier-threshold must be a finite number > 0, found {s}"
        ))
    }
}

#[derive(Debug, Serialize)]
pub struct Timings {
    pub read_s: f64,
    pub solve_s: f64,
    pub write_s: f64,
    /// With --marginals: computing and writing them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub marginals_s: Option<f64>,
}

/// The report `--json` prints: the solution's figures, which estimate is written, the reader's
/// warnings (lines skipped, e.g. EQUIV with --ignore-equiv: the solution is for the graph without
/// them) and the timings.
#[derive(Debug, Serialize)]
pub struct Report<'a> {
    #[serde(flatten)]
    pub solution: &'a Solution,
    /// The estimate written to -o: "solved" (the one the cost and bound are of, certified or not)
    /// or "refined" (by LM under the full information, after certification: not certified).
    pub written_estimate: &'static str,
    /// g2o's chi2 of the written estimate.
    pub written_chi2: Option<f64>,
    /// Whether the written estimate is certified within --tol (never for a refined one).
    pub written_certified: bool,
    /// With --robust: what GNC did and rejected (the figures above are then of the inlier
    /// set's problem).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robust: Option<RobustReport>,
    /// Not certified (and without --robust, landmarks): the loop closures --robust would start
    /// out rejecting at the estimate, a sign of false loop closures.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub suspect_loop_closures: Option<SuspectLoopClosures>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings: Option<Timings>,
}

/// Loop closures (every edge but the odometry) whose residual r_e² at the estimate exceeds
/// --robust's inlier threshold ([`crate::robust::gnc::suspect_loop_closures`]).
#[derive(Debug, Serialize)]
pub struct SuspectLoopClosures {
    /// How many exceed it.
    pub above_threshold: usize,
    /// Loop closures in the graph.
    pub loop_closures: usize,
    /// The threshold c̄² (--inlier-threshold's default, 0.5 chi2inv(0.99, 3)).
    pub threshold: f64,
}

/// An edge GNC rejected.
#[derive(Debug, Serialize)]
pub struct RejectedEdge {
    /// Its line in the input.
    pub line: usize,
    /// Its ids as written.
    pub i: u32,
    pub j: u32,
    /// r_e^2 at the final (inlier-set) estimate.
    pub residual_sq: f64,
    /// Its final GNC weight.
    pub weight: f64,
}

/// `--robust`'s part of the report.
#[derive(Debug, Serialize)]
pub struct RobustReport {
    pub loss: Loss,
    pub inlier_threshold: f64,
    pub odometry_known_inliers: bool,
    /// Whether the inner problems after the first were warm started (`--warm-start`).
    pub warm_start: bool,
    /// Edges of the input.
    pub input_edges: usize,
    /// Edges GNC could reject (not known inliers).
    pub uncertain_edges: usize,
    pub inliers: usize,
    pub rejected: usize,
    pub gnc_iterations: usize,
    pub stop: StopReason,
    /// The last mu (absent where GNC did not iterate).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// How many of the inner weighted problems were certified (for their weights); null unless
    /// `--certify-inner` asked for their certificates.
    pub inner_certified: Option<usize>,
    /// The problem the certificate is of.
    pub certificate_of: &'static str,
    pub rejected_edges: Vec<RejectedEdge>,
    /// mu, weighted cost, outliers so far and inner certificate per iteration.
    pub history: Vec<GncIteration>,
}

impl RobustReport {
    fn new(
        r: &RobustSolution,
        graph: &crate::graph::PoseGraph,
        lines: &[usize],
        options: &RobustOptions,
    ) -> Self {
        let rejected_edges = r
            .rejected
            .iter()
            .enumerate()
            .filter(|(_, x)| **x)
            .map(|(k, _)| {
                let e = &graph.edges[k];
                RejectedEdge {
                    line: lines.get(k).copied().unwrap_or(0),
                    i: graph.ids[e.i],
                    j: graph.ids[e.j],
                    residual_sq: r.residuals[k],
                    weight: r.weights[k],
                }
            })
            .collect::<Vec<_>>();
        RobustReport {
            loss: options.loss,
            inlier_threshold: options.inlier_threshold,
            odometry_known_inliers: options.odometry_inliers,
            warm_start: options.warm_start,
            input_edges: graph.edges.len(),
            uncertain_edges: r.uncertain.iter().filter(|&&u| u).count(),
            inliers: graph.edges.len() - rejected_edges.len(),
            rejected: rejected_edges.len(),
            gnc_iterations: r.iterations.len(),
            stop: r.stop,
            mu: r.mu,
            inner_certified: options.certify_inner.then(|| {
                r.iterations
                    .iter()
                    .filter(|i| i.certified == Some(true))
                    .count()
            }),
            certificate_of: "the inlier set (the input without the rejected edges), not the robust problem",
            rejected_edges,
            history: r.iterations.clone(),
        }
    }
}

impl<'a> Report<'a> {
    /// The report of `solution` as `--json` prints it (the Python package's `Solution` is this
    /// report too, built by this function, without robust part and timings).
    pub fn new(
        solution: &'a Solution,
        robust: Option<RobustReport>,
        warnings: Vec<String>,
        timings: Option<Timings>,
    ) -> Self {
        let (written_estimate, written_chi2, written_certified) =
            written(solution.refined_chi2, solution.chi2, solution.certified);
        Report {
            solution,
            written_estimate,
            written_chi2,
            written_certified,
            robust,
            suspect_loop_closures: None,
            warnings,
            timings,
        }
    }

    /// Fills [`Report::suspect_loop_closures`] when the solution is not certified, without
    /// --robust and landmarks: the loop closures of `graph` (the graph solved, under `weights`)
    /// above --robust's default inlier threshold at the estimate.
    ///
    /// # Errors
    ///
    /// Those of the weights.
    pub fn note_suspect_loop_closures(
        &mut self,
        graph: &crate::graph::PoseGraph,
        weights: crate::problem::weights::Weights,
    ) -> crate::Result<()> {
        let s = self.solution;
        if s.certified || self.robust.is_some() || !graph.landmarks.is_empty() {
            return Ok(());
        }
        let threshold = DEFAULT_INLIER_THRESHOLD;
        let (above_threshold, loop_closures) =
            crate::robust::gnc::suspect_loop_closures(graph, weights, &s.estimate, threshold)?;
        self.suspect_loop_closures = Some(SuspectLoopClosures {
            above_threshold,
            loop_closures,
            threshold,
        });
        Ok(())
    }
}

/// Entry point of the `pgo-solve` binary.
pub fn main() -> ExitCode {
    let args = Args::parse();
    crate::cli::run_tool("pgo-solve", || run(&args))
}

pub fn run(args: &Args) -> crate::Result<ExitCode> {
    let output = match (&args.output, args.json) {
        (Some(o), _) => Some(o.as_str()),
        (None, false) => Some("-"),
        (None, true) => None,
    };
    // Before the work: a solve of minutes must not end in "directory does not exist".
    if let Some(path) = output {
        io::check_output(path)?;
    }
    if let Some(path) = &args.marginals {
        if path == "-" {
            return Err(Error::Invalid(
                "--marginals needs a file: stdout carries the graph or the report".into(),
            ));
        }
        io::check_output(path)?;
    }
    let rec = args.rerun.recorder("pgo-solve")?;
    let progress = args.progress.start("pgo-solve");
    let t0 = Instant::now();
    super::memory::map_heap_ahead(&args.input.input);
    let (graph, mut read_report) = args.input.read_any_shown(&progress)?;
    let read_s = t0.elapsed().as_secs_f64();
    let graph = match graph {
        io::AnyGraph::Planar(graph) => graph,
        io::AnyGraph::Spatial(graph) => {
            return run3(args, graph, read_report, read_s, output, progress, rec);
        }
    };
    rec.graph(&graph);
    if args.marginals.is_some() && !graph.landmarks.is_empty() {
        return Err(Error::Invalid(
            "--marginals: marginal covariances of graphs with landmarks are not implemented".into(),
        ));
    }
    if args.method == Method::Sdp {
        check_dense_size(&graph, "pgo-solve --method sdp")?;
    }
    let options = SolveOptions {
        method: args.method,
        solver: args.solver.unwrap_or(SdpSolver::Ipm),
        weights: args.weights.weights,
        tolerance: args.tol,
        refine: args.refine,
        max_rank: args.max_rank as usize,
        staircase_budget: args.staircase_budget * 1e9,
        ..Default::default()
    };
    let t1 = Instant::now();
    let out_format = output_format(args, output, read_report.format);
    // The output's edge and observation lines do not depend on the estimate: in a plain solve
    // the second core formats them once the solver lets it (its share of the work built ahead
    // done, and the descent too where the Newton factorizations take both cores), while this
    // thread descends or certifies ([`crate::linalg::parallel::when_idle`]; kitti_00 spent 14%
    // of its time writing).
    let shared = std::sync::Arc::new(graph);
    // Also handed to the output written ahead, below.
    let lines_ahead = std::sync::Arc::new(std::sync::OnceLock::new());
    let lines = match (out_format, args.robust) {
        (Some(format), None)
            if shared.noise == NoiseKind::Information
                && read_report.vertigo.is_none()
                && (crate::linalg::parallel::SHARED_FROM_EDGES..=LINES_AHEAD_MAX)
                    .contains(&(shared.edges.len() + shared.landmarks.observations.len())) =>
        {
            let graph = std::sync::Arc::clone(&shared);
            let options = WriteOptions::of(format);
            let slot = std::sync::Arc::clone(&lines_ahead);
            Some(crate::linalg::parallel::when_idle(move || {
                let lines = std::sync::Arc::new(io::constant_lines(&graph, None, options));
                let _ = slot.set(std::sync::Arc::clone(&lines));
                lines
            }))
        }
        _ => None,
    };
    // The output file written ahead: where the lines are formatted ahead and the output is a
    // regular file, the staircase's estimate is written to the output's temporary file on the
    // second core while the certificate is computed ([`Ahead`]); put in place at the end where
    // the solution's estimate is that one, bit for bit. Not for larger graphs: the write of a
    // 23 MB file beside the certificate slowed it more than it saved (the 10⁵-pose world 1.03 of
    // its time, 12 interleaved pairs; at 10⁶ poses -0.7 to +0.3 s of 14-16 s).
    let ahead = std::rc::Rc::new(std::cell::RefCell::new(None::<Ahead>));
    let taker = match (output, out_format) {
        (Some(path), Some(format)) if lines.is_some() && !args.refine && io::stages(path) => {
            let (graph, slot, path) = (
                std::sync::Arc::clone(&shared),
                std::sync::Arc::clone(&lines_ahead),
                path.to_string(),
            );
            let ahead = std::rc::Rc::clone(&ahead);
            let taker: crate::solve::CandidateTaker = Box::new(move |poses, landmarks| {
                let mut ahead = ahead.borrow_mut();
                if ahead.is_some() {
                    return;
                }
                let estimate = std::sync::Arc::new((poses.to_vec(), landmarks.to_vec()));
                let (graph, slot, path) = (graph.clone(), slot.clone(), path.clone());
                let written = std::sync::Arc::clone(&estimate);
                let file = crate::linalg::parallel::when_idle(move || {
                    let (poses, landmarks) = &*written;
                    let estimate = io::Estimate { poses, landmarks };
                    let lines = slot.get().cloned();
                    let options = WriteOptions::of(format);
                    io::stage_graph(&graph, estimate, None, options, &path, lines.as_deref())
                });
                *ahead = Some(Ahead {
                    estimate,
                    file: Some(file),
                });
            });
            Some(taker)
        }
        _ => None,
    };
    // What `--robust` found, for the viewer once the estimate is known.
    let mut gnc_view = None;
    // The graph without the rejected edges (--drop-outliers).
    let mut dropped = None;
    let (solution, robust) = match args.robust {
        None => (
            progress.watch(|| {
                rec.observe(|| match taker {
                    Some(taker) => solve_offering(&shared, &options, taker),
                    None => solve(&shared, &options),
                })
            })?,
            None,
        ),
        Some(loss) => {
            let robust_options = RobustOptions {
                loss,
                inlier_threshold: args.inlier_threshold.unwrap_or(DEFAULT_INLIER_THRESHOLD),
                odometry_inliers: !args.all_edges_uncertain,
                warm_start: args.warm_start,
                certify_inner: args.certify_inner,
                solve: options,
                ..Default::default()
            };
            let r = progress.watch(|| rec.observe(|| robust_solve(&shared, &robust_options)))?;
            let report = RobustReport::new(&r, &shared, &read_report.edge_lines, &robust_options);
            if rec.is_enabled() {
                gnc_view = Some((
                    (*shared).clone(),
                    r.rejected.clone(),
                    r.residuals.clone(),
                    r.iterations.clone(),
                ));
            }
            if args.drop_outliers {
                dropped = Some(crate::robust::gnc::without_edges(&shared, &r.rejected));
                if let Some(v) = &mut read_report.vertigo {
                    let keep: Vec<bool> = r.rejected.iter().map(|x| !x).collect();
                    v.retain_edges(&keep);
                }
            }
            (r.solution, Some(report))
        }
    };
    let solve_s = t1.elapsed().as_secs_f64();
    // Taken (or waited for) before the graph is: the tasks hold it.
    let lines = lines.and_then(|l| l.take());
    // The output written ahead, if it holds this estimate (else removed here).
    let staged = ahead.borrow_mut().take().and_then(|mut a| {
        // Waited for where it runs: a file not kept is removed before the output is written.
        let file = a.file.take()?.take();
        let (poses, landmarks) = &*a.estimate;
        if !same_bits(poses, landmarks, &solution) {
            return None;
        }
        // A write that failed is done again below, where its error is reported.
        file?.ok()?
    });
    let mut graph = dropped.unwrap_or_else(|| {
        std::sync::Arc::try_unwrap(shared).unwrap_or_else(|graph| (*graph).clone())
    });
    graph.poses.clone_from(&solution.estimate);
    graph.vertices_declared = true;
    graph
        .landmarks
        .positions
        .clone_from(&solution.landmark_estimate);
    graph.landmarks.declared = true;
    rec.optimized(&graph, options.weights);
    if let Some((mut all_edges, rejected, residuals, iterations)) = gnc_view {
        // Every edge as read (also under --drop-outliers), at the estimate.
        all_edges.poses.clone_from(&graph.poses);
        let weights: Vec<&[f64]> = iterations.iter().map(|i| i.weights.as_slice()).collect();
        rec.robust(&all_edges, &rejected, &residuals, &weights);
    }

    let t2 = Instant::now();
    // A write that fails after all (a full disk) is reported after the report, never instead.
    let written = match (output, out_format) {
        (Some(path), Some(format)) => {
            progress.phase(&format!(
                "writing {}",
                if path == "-" { "<stdout>" } else { path }
            ));
            super::memory::release_beside(|| match staged {
                Some(staged) => staged.persist().map_err(Error::from),
                None => write_graph(
                    &mut graph,
                    read_report.vertigo.as_ref(),
                    path,
                    format,
                    lines.as_deref(),
                ),
            })
        }
        _ => Ok(()),
    };
    let write_s = t2.elapsed().as_secs_f64();
    let t3 = Instant::now();
    let marginals = match &args.marginals {
        Some(path) => {
            progress.phase("marginal covariances");
            write_marginals(&graph, path)
        }
        None => Ok(()),
    };
    let marginals_s = args.marginals.is_some().then(|| t3.elapsed().as_secs_f64());
    progress.finish();

    let mut report = Report::new(
        &solution,
        robust,
        read_report.warnings.iter().map(|w| w.to_string()).collect(),
        (!args.no_timings).then_some(Timings {
            read_s,
            solve_s,
            write_s,
            marginals_s,
        }),
    );
    report.note_suspect_loop_closures(&graph, options.weights)?;
    if let Some(solver) = args.solver
        && !solution.components.iter().any(|c| c.method == Method::Sdp)
    {
        eprintln!(
            "pgo-solve: warning: --solver {} had no effect: no component was solved by the SDP (method {})",
            solver_name(solver),
            method_text(&solution)
        );
    }
    if args.json {
        write_stdout(to_json_line(&report)?.as_bytes())?;
    } else {
        eprint!("{}", text_report(&args.input.input, &report));
    }
    rec.certificate(&crate::viz::Certificate {
        cost: solution.cost,
        lower_bound: solution.lower_bound,
        certified: solution.certified,
        szep: solution.szep,
        near_zero: solution.near_zero_eigenvalues,
    });
    rec.finish()?;
    written?;
    marginals?;
    Ok(if args.fail_uncertified && !solution.certified {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

/// The options of `pgo-solve` that do not apply to 3D graphs yet: an error naming the first one
/// given.
fn refuse3(args: &Args) -> crate::Result<()> {
    let refused = [
        (args.marginals.is_some(), "--marginals"),
        (args.robust.is_some(), "--robust (graduated non-convexity)"),
        (
            args.method == Method::Sdp,
            "--method sdp (the dual SDP of Algorithm 1 is planar)",
        ),
    ];
    match refused.iter().find(|(given, _)| *given) {
        Some((_, what)) => Err(Error::Invalid(format!(
            "{what}: not implemented for 3D graphs yet; 3D graphs are solved by the staircase (SE-Sync's problem) with --weights, --tol, --max-rank, --staircase-budget"
        ))),
        None => Ok(()),
    }
}

/// The report `--json` prints for a 3D graph: [`Report`]'s fields that apply.
#[derive(Debug, Serialize)]
pub struct Report3<'a> {
    #[serde(flatten)]
    pub solution: &'a crate::solve::Solution3,
    pub written_estimate: &'static str,
    pub written_chi2: Option<f64>,
    pub written_certified: bool,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings: Option<Timings>,
}

impl<'a> Report3<'a> {
    /// The report of a 3D `solution` as `--json` prints it (the Python package's `Solution` of
    /// a 3D graph is this report too, built by this function, without timings).
    pub fn new(
        solution: &'a crate::solve::Solution3,
        warnings: Vec<String>,
        timings: Option<Timings>,
    ) -> Self {
        let (written_estimate, written_chi2, written_certified) =
            written(solution.refined_chi2, solution.chi2, solution.certified);
        Report3 {
            solution,
            written_estimate,
            written_chi2,
            written_certified,
            warnings,
            timings,
        }
    }
}

/// The rest of [`run`] for a 3D graph: [`crate::solve::solve3`], the report, the estimate
/// written in the graph's own form.
fn run3(
    args: &Args,
    graph: crate::graph3::Graph3,
    read_report: io::ReadReport,
    read_s: f64,
    output: Option<&str>,
    progress: super::progress_bar::Progress,
    rec: crate::viz::Recorder,
) -> crate::Result<ExitCode> {
    refuse3(args)?;
    rec.graph3(&graph);
    let options = SolveOptions {
        method: args.method,
        solver: args.solver.unwrap_or(SdpSolver::Ipm),
        weights: args.weights.weights,
        tolerance: args.tol,
        refine: args.refine,
        max_rank: args.max_rank as usize,
        staircase_budget: args.staircase_budget * 1e9,
        ..Default::default()
    };
    let t1 = Instant::now();
    let out_format = output_format(args, output, read_report.format);
    // The edges' lines of the output, formatted on the second core while it idles, as in 2D
    // ([`run`]); a 3D edge's line is three times a planar one's. Whole process against writing
    // them all at the end (15-41 interleaved pairs, the same bytes): sphere2500 0.965-0.971,
    // torus3D 0.966, cubicle 0.960, parking-garage 0.984-0.989, smallGrid3D 0.992-1.000.
    let shared = std::sync::Arc::new(graph);
    let lines = out_format
        .filter(|_| {
            (crate::linalg::parallel::SHARED_FROM_EDGES..=LINES_AHEAD_MAX / 3)
                .contains(&shared.edges.len())
        })
        .map(|format| {
            let graph = std::sync::Arc::clone(&shared);
            crate::linalg::parallel::when_idle(move || io::constant_lines3(&graph, format))
        });
    let solution = progress.watch(|| rec.observe(|| crate::solve::solve3(&shared, &options)))?;
    let solve_s = t1.elapsed().as_secs_f64();
    // Taken (or waited for) before the graph is: the task holds it.
    let lines = lines.and_then(|l| l.take()).flatten();
    let mut graph = std::sync::Arc::try_unwrap(shared).unwrap_or_else(|graph| (*graph).clone());
    graph.poses.clone_from(&solution.estimate);
    rec.optimized3(
        &graph,
        options.weights == crate::problem::weights::Weights::Unit,
    );
    rec.certificate(&crate::viz::Certificate {
        cost: solution.cost,
        lower_bound: solution.lower_bound,
        certified: solution.certified,
        szep: solution.szep,
        near_zero: solution.near_zero_eigenvalues,
    });
    let t2 = Instant::now();
    let written = match (output, out_format) {
        (Some(path), Some(format)) => {
            progress.phase(&format!(
                "writing {}",
                if path == "-" { "<stdout>" } else { path }
            ));
            super::memory::release_beside(|| {
                io::write3_path_prepared(&graph, format, path, lines.as_ref())
            })
        }
        _ => Ok(()),
    };
    let write_s = t2.elapsed().as_secs_f64();
    progress.finish();
    if args.solver.is_some() {
        eprintln!(
            "pgo-solve: warning: --solver had no effect: 3D graphs are solved by the staircase"
        );
    }
    let report = Report3::new(
        &solution,
        read_report.warnings.iter().map(|w| w.to_string()).collect(),
        (!args.no_timings).then_some(Timings {
            read_s,
            solve_s,
            write_s,
            marginals_s: None,
        }),
    );
    if args.json {
        write_stdout(to_json_line(&report)?.as_bytes())?;
    } else {
        eprint!("{}", text_report3(&args.input.input, &report));
    }
    written?;
    rec.finish()?;
    Ok(if args.fail_uncertified && !solution.certified {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

fn text_report3(input: &str, report: &Report3) -> String {
    let r = report.solution;
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    let trees = r
        .components
        .iter()
        .filter(|c| c.method == Method::Tree)
        .count();
    let staircase = format!(
        "staircase (SE(3): Stiefel manifold, rank {})",
        r.components
            .iter()
            .filter_map(|c| c.rank)
            .max()
            .unwrap_or(3)
    );
    let method = match trees {
        0 => staircase,
        t if t == r.components.len() => "auto: tree".to_string(),
        t => format!("auto: {staircase}, tree on {t} component{}", plural(t)),
    };
    let mut out = format!(
        "pgo-solve: {}: {} pose{}, {} edge{}, 3D, {} component{}; weights {}; method {method}\n",
        if input == "-" { "<stdin>" } else { input },
        r.poses,
        plural(r.poses),
        r.edges,
        plural(r.edges),
        r.components.len(),
        plural(r.components.len()),
        r.weights.name(),
    );
    out += &row("cost", num(r.cost));
    out += &row(
        "chi2 (g2o)",
        r.chi2
            .map_or("undefined (TORO information over Euler angles)".into(), num),
    );
    out += &row("lower bound", num(r.lower_bound));
    out += &row(
        "suboptimality <=",
        format!(
            "{} ({} relative)",
            num(r.suboptimality_bound),
            num(r.relative_suboptimality_bound)
        ),
    );
    out += &row(
        "exact relaxation",
        if r.szep && trees == r.components.len() {
            // Nothing computed: the theory of trees.
            "yes (a tree: Lambda* = 0 and S = Q has exactly 3 eigenvalues at zero)".to_string()
        } else if r.szep {
            "yes (S has exactly 3 eigenvalues at zero, the rest proven positive)".to_string()
        } else {
            "not shown".to_string()
        },
    );
    out += &component_rows(
        &r.components
            .iter()
            .map(|c| (c.poses, c.first_id, c.cost, c.lower_bound, c.certified))
            .collect::<Vec<_>>(),
    );
    out += &row(
        "result",
        if r.certified && r.refined_chi2.is_some() {
            "certified optimal within the bound above (the estimate before refinement)".to_string()
        } else if r.certified {
            "certified optimal within the bound above".to_string()
        } else {
            "NOT certified within --tol; the bound above still holds".to_string()
        },
    );
    if let Some(why) = &r.not_certified_because {
        out += &row("why not certified", why.clone());
    }
    out += &closing_rows(
        r.refined_chi2.map(|chi2| {
            let before = r.components.iter().filter_map(|c| c.certified_chi2).sum();
            (before, chi2)
        }),
        "full 6x6 information matrices",
        report.written_estimate == "refined",
        report.written_chi2.map_or("undefined".into(), num),
        report.timings.as_ref(),
    );
    out
}

/// The last rows of the planar and 3D text reports: the refinement's chi2 (before, after) under
/// `information`, which estimate was written (with its chi2 as text), the timings.
fn closing_rows(
    refined: Option<(f64, f64)>,
    information: &str,
    written_refined: bool,
    written_chi2: String,
    timings: Option<&Timings>,
) -> String {
    let mut out = String::new();
    if let Some((before, after)) = refined {
        out += &row(
            "refined (LM, chi2)",
            format!("{} -> {} ({information})", num(before), num(after)),
        );
    }
    if written_refined {
        out += &row(
            "written estimate",
            format!(
                "refined by LM (chi2 {written_chi2}), not the certified one; certify it with pgo-certify"
            ),
        );
    }
    if let Some(t) = timings {
        out += &row(
            "time",
            format!(
                "read {:.3} s, solve {:.3} s, write {:.3} s{}",
                t.read_s,
                t.solve_s,
                t.write_s,
                t.marginals_s
                    .map(|m| format!(", marginals {m:.3} s"))
                    .unwrap_or_default()
            ),
        );
    }
    out
}

/// Which estimate `-o` holds, its chi2 and whether it is certified: the refined one (never
/// certified) when there is a refinement, else the solved one.
fn written(
    refined_chi2: Option<f64>,
    chi2: Option<f64>,
    certified: bool,
) -> (&'static str, Option<f64>, bool) {
    match refined_chi2 {
        Some(refined) => ("refined", Some(refined), false),
        None => ("solved", chi2, certified),
    }
}

/// A row of the text report: the label in a column of 21, the value.
fn row(label: &str, value: String) -> String {
    format!("  {label:<21}{value}\n")
}

/// One row per connected component (poses, first id, cost, bound, certified), when there are
/// several: the planar and the 3D text reports.
fn component_rows(components: &[(usize, u32, f64, f64, bool)]) -> String {
    let mut out = String::new();
    if components.len() < 2 {
        return out;
    }
    for (k, &(poses, first_id, cost, lower_bound, certified)) in components.iter().enumerate() {
        out += &row(
            &format!("component {}", k + 1),
            format!(
                "{poses} pose{} from id {first_id}: cost {}, bound {}, {}",
                if poses == 1 { "" } else { "s" },
                num(cost),
                num(lower_bound),
                if certified {
                    "certified"
                } else {
                    "not certified"
                }
            ),
        );
    }
    out
}

fn solver_name(solver: SdpSolver) -> &'static str {
    match solver {
        SdpSolver::Ipm => "ipm",
        SdpSolver::Clarabel => "clarabel",
    }
}

/// What ran: `staircase`, `sdp (ipm)`, or per method the number of components it solved;
/// prefixed by `auto: ` when the method was chosen per component.
fn method_text(r: &Solution) -> String {
    let count = |m| r.components.iter().filter(|c| c.method == m).count();
    let sdp_name = format!("sdp ({})", solver_name(r.solver));
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    let ran: Vec<(String, usize)> = [
        (sdp_name, count(Method::Sdp)),
        ("staircase".to_string(), count(Method::Staircase)),
        ("tree".to_string(), count(Method::Tree)),
    ]
    .into_iter()
    .filter(|(_, n)| *n > 0)
    .collect();
    let ran = match &ran[..] {
        [] => return r.method.name().to_string(),
        [(name, _)] => name.clone(),
        [(first, a), rest @ ..] => {
            let rest: Vec<String> = rest
                .iter()
                .map(|(name, b)| format!("{name} on {b}"))
                .collect();
            format!(
                "{first} on {a} component{}, {}",
                plural(*a),
                rest.join(", ")
            )
        }
    };
    match r.method {
        Method::Auto => format!("auto: {ran}"),
        _ => ran,
    }
}

/// Writes the marginal covariances of `graph`'s poses ([`crate::refine::marginals`]) to `path`:
/// a `#` line naming the columns, then per pose in ascending id order `id c11 c12 c13 c22 c23
/// c33`, shortest round-trip decimals.
fn write_marginals(graph: &crate::graph::PoseGraph, path: &str) -> crate::Result<()> {
    let covariances = crate::refine::marginals(graph, &graph.poses)?;
    let mut order: Vec<usize> = (0..graph.num_poses()).collect();
    order.sort_by_key(|&k| graph.ids[k]);
    let mut text = Vec::with_capacity(32 + 64 * order.len());
    text.extend_from_slice(
        b"# id c11 c12 c13 c22 c23 c33: covariance over the body-frame tangent [x, y, theta]\n",
    );
    for k in order {
        text.extend_from_slice(graph.ids[k].to_string().as_bytes());
        for &v in &covariances[k].0 {
            text.push(b' ');
            io::format_f64(v, &mut text);
        }
        text.push(b'\n');
    }
    io::write_bytes_path(&text, path)?;
    Ok(())
}

/// The format of the output `output`, if any: `--to`, else its extension's, else the input's.
fn output_format(args: &Args, output: Option<&str>, input: Format) -> Option<Format> {
    output.map(|path| {
        args.to
            .or_else(|| Format::from_extension(path))
            .unwrap_or(input)
    })
}

/// The most edge and observation lines formatted ahead of the write ([`run`]), about 10 MB,
/// held until the end of the solve beside its peak of memory. The public planar files have up to
/// 25 000; the generated 10⁵-pose world (115 000 edges) gained nothing from it and peaked 19 MiB
/// higher, and at 10⁶ poses the lines would be some 190 MB.
const LINES_AHEAD_MAX: usize = 1 << 16;

/// The output file written ahead of the certificate ([`run`]): the estimate it holds and the
/// second core's task writing it to a temporary file. Dropped unused, it waits for a task
/// running and removes its file: none is left behind when the solve ends elsewhere.
struct Ahead {
    /// The poses and landmark positions offered.
    estimate: std::sync::Arc<(Vec<crate::graph::Pose2>, Vec<[f64; 2]>)>,
    file: Option<crate::linalg::parallel::Idle<pgo_io::Result<Option<io::Staged>>>>,
}

impl Drop for Ahead {
    fn drop(&mut self) {
        if let Some(file) = self.file.take() {
            drop(file.take());
        }
    }
}

/// Whether `poses` and `landmarks` are the solution's estimate, bit for bit.
fn same_bits(poses: &[crate::graph::Pose2], landmarks: &[[f64; 2]], solution: &Solution) -> bool {
    let values = |poses: &[crate::graph::Pose2], landmarks: &[[f64; 2]]| {
        let poses = poses.iter().flat_map(|p| [p.x, p.y, p.theta]);
        let landmarks = landmarks.iter().flatten().copied();
        poses.chain(landmarks).map(f64::to_bits).collect::<Vec<_>>()
    };
    poses.len() == solution.estimate.len()
        && values(poses, landmarks) == values(&solution.estimate, &solution.landmark_estimate)
}

/// Writes the solved graph to `path` in `format`, its edge and observation lines from `lines`
/// where they were formatted ahead.
fn write_graph(
    graph: &mut crate::graph::PoseGraph,
    vertigo: Option<&crate::vertigo::Vertigo>,
    path: &str,
    format: Format,
    lines: Option<&io::ConstantLines>,
) -> crate::Result<()> {
    // The output holds information matrices, in the format's own order.
    graph
        .convert_noise(NoiseKind::Information)
        .map_err(|_| Error::Invalid("a covariance matrix is singular".into()))?;
    io::write_path_prepared(graph, vertigo, WriteOptions::of(format), path, lines)?;
    Ok(())
}

fn text_report(input: &str, report: &Report) -> String {
    let r = report.solution;
    let mut out = format!(
        "pgo-solve: {}: {} pose{}, {} edge{}{}, {} component{}; weights {}; method {}\n",
        if input == "-" { "<stdin>" } else { input },
        r.poses,
        if r.poses == 1 { "" } else { "s" },
        r.edges,
        if r.edges == 1 { "" } else { "s" },
        if r.landmarks == 0 {
            String::new()
        } else {
            format!(
                ", {} landmarks, {} observations",
                r.landmarks, r.observations
            )
        },
        r.components.len(),
        if r.components.len() == 1 { "" } else { "s" },
        r.weights.name(),
        method_text(r),
    );
    if let Some(g) = &report.robust {
        out += &robust_text(g);
    }
    let chi2_text =
        |c: Option<f64>| c.map_or("undefined (a covariance matrix is singular)".into(), num);
    out += &row("cost", num(r.cost));
    out += &row("chi2 (g2o)", chi2_text(r.chi2));
    out += &row("lower bound", num(r.lower_bound));
    out += &row(
        "suboptimality <=",
        format!(
            "{} ({} relative)",
            num(r.suboptimality_bound),
            num(r.relative_suboptimality_bound)
        ),
    );
    out += &row(
        "SZEP",
        if r.szep && r.components.iter().all(|c| c.method == Method::Tree) {
            // Nothing computed: the theory of trees.
            "yes (a tree: lambda* = 0 and W(0) has one zero eigenvalue, Props. 6 and 11)"
                .to_string()
        } else if r.szep {
            "yes".to_string()
        } else if r.near_zero_eigenvalues == 0 {
            // Not counted: no certificate was attempted, or the rounding hid the gap.
            "not established".to_string()
        } else {
            format!(
                "no ({} eigenvalues of W(lambda*) at zero)",
                r.near_zero_eigenvalues
            )
        },
    );
    if !r.sdp_converged {
        out += &row(
            "SDP",
            "did not converge: the bound is that of the dual feasible multipliers reached"
                .to_string(),
        );
    }
    out += &component_rows(
        &r.components
            .iter()
            .map(|c| (c.poses, c.first_id, c.cost, c.lower_bound, c.certified))
            .collect::<Vec<_>>(),
    );
    out += &row(
        "result",
        if r.certified && r.refined_chi2.is_some() {
            "certified optimal within the bound above (the estimate before refinement)".to_string()
        } else if r.certified && report.robust.is_some() {
            "certified optimal within the bound above for the inlier set (the input without the \
             rejected edges); the robust (TLS/GM) problem itself is not certified"
                .to_string()
        } else if r.certified {
            "certified optimal within the bound above".to_string()
        } else if r.components.iter().any(|c| c.method == Method::Staircase) {
            "NOT certified within --tol; the bound above still holds".to_string()
        } else if r.szep {
            "NOT certified: the SZEP holds but the bound exceeds --tol".to_string()
        } else {
            let used = |k| r.components.iter().any(|c| c.rounding == Some(k));
            format!(
                "NOT certified: {}, polished under f; the bound above still holds",
                if used(Rounding::SpanningTree) {
                    "spanning-tree estimate (a forest, f* = 0, whose relaxation rounded above it)"
                } else if used(Rounding::Randomized) {
                    "randomized rounding of X* (So, Zhang and Ye 2007)"
                } else if used(Rounding::SdpRank1) {
                    "rank-1 rounding of X* (Sec. 6)"
                } else if used(Rounding::Eigenvector) {
                    "eigenvector estimate (Eig, Sec. 5.2)"
                } else {
                    "null-space estimate (Sec. 5.2)"
                }
            )
        },
    );
    if let Some(why) = &r.not_certified_because {
        out += &row("why not certified", why.clone());
    }
    if let Some(s) = &report.suspect_loop_closures {
        out += &row(
            "loop closures",
            if s.above_threshold == 0 {
                format!(
                    "none of {} has r^2 above --robust's inlier threshold {} at this estimate",
                    s.loop_closures,
                    num(s.threshold)
                )
            } else {
                format!(
                    "{} of {} have r^2 above --robust's inlier threshold {} at this estimate (about 1% of true ones would); if some are false, try --robust tls",
                    s.above_threshold,
                    s.loop_closures,
                    num(s.threshold)
                )
            },
        );
    }
    out += &closing_rows(
        r.refined_chi2.map(|chi2| {
            let before = r.components.iter().filter_map(|c| c.certified_chi2).sum();
            (before, chi2)
        }),
        "full information matrices",
        report.written_estimate == "refined",
        chi2_text(report.written_chi2),
        report.timings.as_ref(),
    );
    out
}

/// The rows of `--robust`'s text report.
fn robust_text(g: &RobustReport) -> String {
    let mut out = row(
        "robust",
        format!(
            "GNC {}, threshold c^2 {} on r^2; {} iteration{} ({}; mu {}); {} of {} edges uncertain{}",
            g.loss.name(),
            num(g.inlier_threshold),
            g.gnc_iterations,
            if g.gnc_iterations == 1 { "" } else { "s" },
            g.stop.text(),
            g.mu.map_or("-".to_string(), num),
            g.uncertain_edges,
            g.input_edges,
            if g.odometry_known_inliers {
                " (odometry known inliers)"
            } else {
                ""
            },
        ),
    );
    out += &row(
        "inliers",
        format!(
            "{} of {} edges ({} rejected); inner problems certified: {}",
            g.inliers,
            g.input_edges,
            g.rejected,
            match g.inner_certified {
                Some(k) => format!("{k} of {}", g.gnc_iterations),
                None => "not checked (--certify-inner)".to_string(),
            }
        ),
    );
    for e in &g.rejected_edges {
        out += &row(
            "rejected",
            format!(
                "line {}: {} -> {}, r^2 {}",
                e.line,
                e.i,
                e.j,
                num(e.residual_sq)
            ),
        );
    }
    out += "  the figures below are of the inlier set's problem\n";
    out
}
