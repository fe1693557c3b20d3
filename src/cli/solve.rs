//! `pgo-solve`: the globally optimal estimate of a pose graph and the bound that proves it.

use super::common::{
    InputArgs, RerunArgs, WeightArgs, check_dense_size, num, to_json_line, write_stdout,
};
use crate::algorithm1::{ComponentSolution, Rounding, SdpSolver, solve_connected};
use crate::error::Error;
use crate::graph::{Pose2, PoseGraph};
use crate::io::{self, Format, WriteOptions};
use crate::staircase::{StaircaseOptions, StaircaseSolution, solve_graph};
use crate::weights::{Weights, edge_weights};
use clap::Parser;
use serde::Serialize;
use std::process::ExitCode;
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  pgo-solve datasets/paper_toy.g2o --weights unit -o toy-solved.g2o
  pgo-solve MIT.g2o --json -o MIT-opt.g2o | jq '{cost, lower_bound, certified}'
  pgo-solve ais2klinik.g2o -o ais2klinik-opt.g2o && pgo-certify ais2klinik.g2o --estimate ais2klinik-opt.g2o
  pgo-simulate -n 20 --seed 3 | pgo-solve - --weights unit --json -o /dev/null";

/// Solve a planar pose graph to global optimality and prove it.
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
#[derive(Debug, Parser)]
#[command(name = "pgo-solve", version, after_help = EXAMPLES)]
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

    /// Solution method [auto: sdp for components of at most 100 poses, else staircase]
    #[arg(long, value_enum, default_value = "auto")]
    pub method: Method,

    /// SDP solver for the dual
    #[arg(long, value_enum, default_value = "ipm")]
    pub solver: SdpSolver,

    /// Relative suboptimality bound under which the result is called certified
    #[arg(long, default_value = "1e-6", value_name = "REL", value_parser = super::common::parse_tolerance)]
    pub tol: f64,

    /// Refine the certified estimate by Levenberg-Marquardt under the file's full information
    /// matrices (g2o's chi2) before writing it; the report's cost and bound stay those of the
    /// certified estimate, and chi2 before and after is added
    #[arg(long)]
    pub refine: bool,

    /// Print the report as one JSON object on stdout (the graph then goes only to -o)
    #[arg(long)]
    pub json: bool,

    /// Leave the timings out of the report (for byte-identical output)
    #[arg(long)]
    pub no_timings: bool,

    #[command(flatten)]
    pub rerun: RerunArgs,
}

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

/// Components up to this size go to the SDP under --method auto.
pub const AUTO_SDP_MAX_POSES: usize = 100;

/// The report of one connected component.
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
    /// With --refine: g2o's chi2 of the certified estimate, and after refinement.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certified_chi2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refined_chi2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refine_iterations: Option<usize>,
}

#[derive(Debug, Serialize)]
pub struct Timings {
    pub read_s: f64,
    pub solve_s: f64,
    pub write_s: f64,
}

/// The report `--json` prints. Totals are sums over the components.
#[derive(Debug, Serialize)]
pub struct Report {
    pub method: Method,
    pub solver: SdpSolver,
    pub weights: Weights,
    pub poses: usize,
    pub edges: usize,
    /// f at the estimate.
    pub cost: f64,
    /// Proven lower bound on the optimum f*.
    pub lower_bound: f64,
    /// cost − lower_bound: the estimate is at most this far from optimal.
    pub suboptimality_bound: f64,
    /// With --refine: g2o's chi2 of the written (refined) estimate, summed over components.
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
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings: Option<Timings>,
}

/// Entry point of the `pgo-solve` binary.
pub fn main() -> ExitCode {
    let args = Args::parse();
    crate::cli::run_tool("pgo-solve", || run(&args))
}

pub fn run(args: &Args) -> crate::Result<ExitCode> {
    let rec = args.rerun.recorder("pgo-solve")?;
    let t0 = Instant::now();
    let (mut graph, read_report) = args.input.read()?;
    let read_s = t0.elapsed().as_secs_f64();
    rec.graph(&graph);
    if args.method == Method::Sdp {
        check_dense_size(&graph, "pgo-solve --method sdp")?;
    }
    let policy = args.weights.weights;
    let t1 = Instant::now();
    let mut components = Vec::new();
    let mut solutions: Vec<(Vec<Pose2>, Vec<usize>)> = Vec::new();
    for (part, members, _) in graph.components() {
        let weights = edge_weights(&part, policy)?;
        let sdp = match args.method {
            Method::Sdp => true,
            Method::Staircase => false,
            Method::Auto => part.num_poses() <= AUTO_SDP_MAX_POSES,
        };
        if sdp {
            let solution = rec.observe(|| solve_connected(&part, &weights, args.solver))?;
            components.push(component_report(&part, &solution, args.tol));
            solutions.push((solution.poses, members));
        } else {
            crate::algorithm1::check_edge_terms(&part, &weights, &weights)?;
            let options = StaircaseOptions {
                tolerance: args.tol,
                ..Default::default()
            };
            // Newton steps on the `iteration` timeline of a rerun recording (crate::progress).
            let mut step = 0u64;
            let mut report = |it: &crate::staircase::Iteration| {
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
            };
            let (solution, poses) = rec
                .observe(|| solve_graph(&part, &weights, &options, &mut report))
                .ok_or_else(|| Error::Invalid("the graph is not connected".into()))?;
            components.push(staircase_report(&part, &solution, args.tol));
            solutions.push((poses, members));
        }
        if args.refine {
            let (poses, _) = solutions.last_mut().expect("pushed above");
            let report = components.last_mut().expect("pushed above");
            let refined = crate::refine::refine(&part, poses, &Default::default())?;
            report.certified_chi2 = Some(refined.initial_chi2);
            report.refined_chi2 = Some(refined.chi2);
            report.refine_iterations = Some(refined.iterations);
            *poses = refined.poses;
        }
    }
    let solve_s = t1.elapsed().as_secs_f64();
    for (poses, members) in &solutions {
        for (pose, &k) in poses.iter().zip(members) {
            graph.poses[k] = *pose;
        }
    }
    graph.vertices_declared = true;
    rec.optimized(&graph, policy);

    let t2 = Instant::now();
    let output = match (&args.output, args.json) {
        (Some(o), _) => Some(o.as_str()),
        (None, false) => Some("-"),
        (None, true) => None,
    };
    if let Some(path) = output {
        let format = args
            .to
            .or_else(|| Format::from_extension(path))
            .unwrap_or(read_report.format);
        // The output holds information matrices, in the format's own order.
        graph
            .convert_noise(crate::graph::NoiseKind::Information)
            .map_err(|_| Error::Invalid("a covariance matrix is singular".into()))?;
        let dialect = format.default_dialect();
        io::write_path(&graph, WriteOptions { format, dialect }, path)?;
    }
    let write_s = t2.elapsed().as_secs_f64();

    // Folded from +0: an empty sum of f64 is -0 in Rust, and a graph without edges costs 0.
    let cost = components.iter().fold(0.0, |a, c| a + c.cost);
    let lower_bound = components.iter().fold(0.0, |a, c| a + c.lower_bound);
    let suboptimality_bound = cost - lower_bound;
    let report = Report {
        method: args.method,
        solver: args.solver,
        weights: policy,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        cost,
        lower_bound,
        suboptimality_bound,
        refined_chi2: args
            .refine
            .then(|| components.iter().filter_map(|c| c.refined_chi2).sum()),
        relative_suboptimality_bound: suboptimality_bound / cost.abs().max(1.0),
        certified: components.iter().all(|c| c.certified),
        szep: components.iter().all(|c| c.szep),
        near_zero_eigenvalues: components.iter().map(|c| c.near_zero_eigenvalues).sum(),
        sdp_converged: components.iter().all(|c| c.sdp_converged != Some(false)),
        components,
        timings: (!args.no_timings).then_some(Timings {
            read_s,
            solve_s,
            write_s,
        }),
    };
    if args.json {
        write_stdout(to_json_line(&report)?.as_bytes())?;
    } else {
        eprint!("{}", text_report(&args.input.input, &report));
    }
    rec.certificate(&crate::viz::Certificate {
        cost: report.cost,
        lower_bound: report.lower_bound,
        certified: report.certified,
        szep: report.szep,
        near_zero: report.near_zero_eigenvalues,
    });
    rec.finish()?;
    Ok(ExitCode::SUCCESS)
}

fn component_report(
    part: &crate::graph::PoseGraph,
    s: &ComponentSolution,
    tol: f64,
) -> ComponentReport {
    let suboptimality_bound = s.cost - s.lower_bound;
    ComponentReport {
        first_id: part.ids[0],
        poses: part.num_poses(),
        edges: part.edges.len(),
        cost: s.cost,
        lower_bound: s.lower_bound,
        suboptimality_bound,
        certified: s.szep && suboptimality_bound <= tol * s.cost.abs().max(1.0),
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

fn staircase_report(part: &PoseGraph, s: &StaircaseSolution, tol: f64) -> ComponentReport {
    let suboptimality_bound = s.cost - s.lower_bound;
    ComponentReport {
        first_id: part.ids[0],
        poses: part.num_poses(),
        edges: part.edges.len(),
        cost: s.cost,
        lower_bound: s.lower_bound,
        suboptimality_bound,
        certified: s.bound.is_some() && suboptimality_bound <= tol * s.cost.abs().max(1.0),
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

fn text_report(input: &str, r: &Report) -> String {
    let mut out = format!(
        "pgo-solve: {}: {} pose{}, {} edge{}, {} component{}; weights {}; method {} (sdp solver {})\n",
        if input == "-" { "<stdin>" } else { input },
        r.poses,
        if r.poses == 1 { "" } else { "s" },
        r.edges,
        if r.edges == 1 { "" } else { "s" },
        r.components.len(),
        if r.components.len() == 1 { "" } else { "s" },
        r.weights.name(),
        match r.method {
            Method::Auto => "auto",
            Method::Sdp => "sdp",
            Method::Staircase => "staircase",
        },
        match r.solver {
            SdpSolver::Ipm => "ipm",
            SdpSolver::Clarabel => "clarabel",
        }
    );
    let row = |k: &str, v: String| format!("  {k:<21}{v}\n");
    out += &row("cost", num(r.cost));
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
        if r.szep {
            "yes".to_string()
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
    for (k, c) in r.components.iter().enumerate() {
        if r.components.len() > 1 {
            out += &row(
                &format!("component {}", k + 1),
                format!(
                    "{} poses from id {}: cost {}, bound {}, {}",
                    c.poses,
                    c.first_id,
                    num(c.cost),
                    num(c.lower_bound),
                    if c.certified {
                        "certified"
                    } else {
                        "not certified"
                    }
                ),
            );
        }
    }
    out += &row(
        "result",
        if r.certified {
            "certified optimal within the bound above".to_string()
        } else if r.components.iter().any(|c| c.method == Method::Staircase) {
            "NOT certified within --tol; the bound above still holds".to_string()
        } else if r.szep {
            "NOT certified: the SZEP holds but the bound exceeds --tol".to_string()
        } else {
            let used = |k| r.components.iter().any(|c| c.rounding == Some(k));
            format!(
                "NOT certified: {}; the bound above still holds",
                if used(Rounding::SpanningTree) {
                    "spanning-tree estimate (a forest, f* = 0, whose relaxation rounded above it)"
                } else if used(Rounding::Eigenvector) {
                    "eigenvector estimate (Sec. 5.2: the null-space method (46) had no solution)"
                } else {
                    "null-space estimate (Sec. 5.2)"
                }
            )
        },
    );
    if let Some(chi2) = r.refined_chi2 {
        let before: f64 = r.components.iter().filter_map(|c| c.certified_chi2).sum();
        out += &row(
            "refined (LM, chi2)",
            format!(
                "{} -> {} (full information matrices)",
                num(before),
                num(chi2)
            ),
        );
    }
    if let Some(t) = &r.timings {
        out += &row(
            "time",
            format!(
                "read {:.3} s, solve {:.3} s, write {:.3} s",
                t.read_s, t.solve_s, t.write_s
            ),
        );
    }
    out
}
