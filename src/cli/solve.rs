//! `pgo-solve`: the globally optimal estimate of a pose graph and the bound that proves it.

use super::common::{InputArgs, WeightArgs, check_dense_size, num, to_json_line, write_stdout};
use crate::algorithm1::{ComponentSolution, Rounding, SdpSolver, solve_connected};
use crate::error::Error;
use crate::io::{self, Format, WriteOptions};
use crate::weights::{Weights, edge_weights};
use clap::Parser;
use serde::Serialize;
use std::process::ExitCode;
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  pgo-solve datasets/paper_toy.g2o --weights unit -o toy-solved.g2o
  pgo-solve MIT.g2o --json -o MIT-opt.g2o | jq '{cost, lower_bound, certified}'
  pgo-simulate -n 20 --seed 3 | pgo-solve - --weights unit --json -o /dev/null";

/// Solve a planar pose graph to global optimality and prove it.
///
/// Runs the paper's Algorithm 1: solves the dual SDP (31), checks the single zero eigenvalue
/// property (SZEP) of the penalized pose graph matrix W(lambda*), and scales its null vector
/// (Sec. 5.1); when the SZEP fails it falls back to the null-space method (46) (Sec. 5.2). The
/// report gives the cost of the estimate, a lower bound on the optimum proven by the dual
/// solution (floating-point errors of the eigenvalue computation accounted for), and their
/// difference, which bounds the suboptimality. "certified" means the SZEP holds and that bound
/// is within --tol. Each connected component is solved on its own.
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

    /// Solution method: sdp (the paper's Algorithm 1, for graphs up to 2000 poses)
    #[arg(long, value_enum, default_value = "sdp")]
    pub method: Method,

    /// SDP solver for the dual
    #[arg(long, value_enum, default_value = "ipm")]
    pub solver: SdpSolver,

    /// Relative suboptimality bound under which the result is called certified
    #[arg(long, default_value = "1e-6", value_name = "REL")]
    pub tol: f64,

    /// Print the report as one JSON object on stdout (the graph then goes only to -o)
    #[arg(long)]
    pub json: bool,

    /// Leave the timings out of the report (for byte-identical output)
    #[arg(long)]
    pub no_timings: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Algorithm 1: dual SDP, SZEP, eigenvector scaling or null-space method
    Sdp,
}

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
    pub rounding: Rounding,
    /// The smallest eigenvalues of W(lambda*), ascending (at most 4).
    pub penalized_eigenvalues: Vec<f64>,
    pub sdp_iterations: usize,
    /// Whether the SDP solver reached its tolerance (if not, the bound is proven all the same,
    /// from the dual feasible multipliers it reached, and only weaker).
    pub sdp_converged: bool,
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
    if !(args.tol >= 0.0 && args.tol.is_finite()) {
        return Err(Error::Invalid("--tol must be a finite number >= 0".into()));
    }
    let t0 = Instant::now();
    let (mut graph, read_report) = args.input.read()?;
    let read_s = t0.elapsed().as_secs_f64();
    check_dense_size(&graph, "pgo-solve")?;
    let policy = args.weights.weights;
    let t1 = Instant::now();
    let mut components = Vec::new();
    let mut solutions: Vec<(ComponentSolution, Vec<usize>)> = Vec::new();
    for (part, members, _) in graph.components() {
        let weights = edge_weights(&part, policy)?;
        let solution = solve_connected(&part, &weights, args.solver)?;
        components.push(component_report(&part, &solution, args.tol));
        solutions.push((solution, members));
    }
    let solve_s = t1.elapsed().as_secs_f64();
    for (solution, members) in &solutions {
        for (pose, &k) in solution.poses.iter().zip(members) {
            graph.poses[k] = *pose;
        }
    }
    graph.vertices_declared = true;

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
        relative_suboptimality_bound: suboptimality_bound / cost.abs().max(1.0),
        certified: components.iter().all(|c| c.certified),
        szep: components.iter().all(|c| c.szep),
        near_zero_eigenvalues: components.iter().map(|c| c.near_zero_eigenvalues).sum(),
        sdp_converged: components.iter().all(|c| c.sdp_converged),
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
        rounding: s.rounding,
        penalized_eigenvalues: s.eigenvalues.iter().take(4).copied().collect(),
        sdp_iterations: s.dual.iterations,
        sdp_converged: s.dual.converged,
    }
}

fn text_report(input: &str, r: &Report) -> String {
    let mut out = format!(
        "pgo-solve: {}: {} pose{}, {} edge{}, {} component{}; weights {}; method sdp (solver {})\n",
        if input == "-" { "<stdin>" } else { input },
        r.poses,
        if r.poses == 1 { "" } else { "s" },
        r.edges,
        if r.edges == 1 { "" } else { "s" },
        r.components.len(),
        if r.components.len() == 1 { "" } else { "s" },
        r.weights.name(),
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
        } else if r.szep {
            "NOT certified: the SZEP holds but the bound exceeds --tol".to_string()
        } else {
            let used = |k| r.components.iter().any(|c| c.rounding == k);
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
