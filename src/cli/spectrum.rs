//! `pgo-spectrum`: eigenvalues of the pose graph matrix W, of the penalized matrix W(lambda*)
//! and of the rotation-only matrix M; the SZEP; the tree and balanced flags of Prop. 6.

use super::common::{
    InputArgs, RerunArgs, WeightArgs, check_dense_size, num, to_json_line, write_stdout,
};
use crate::algorithm1::{SdpSolver, analyze};
use crate::spectrum::hermitian_eigenvalues;
use crate::weights::{Weights, edge_weights};
use clap::Parser;
use serde::Serialize;
use std::process::ExitCode;

const EXAMPLES: &str = "\
Examples:
  pgo-spectrum datasets/paper_toy.g2o --weights unit
  pgo-spectrum MIT.g2o -k 6 --json | jq '.penalized_eigenvalues'";

/// Eigenvalues of the pose graph matrices and the single zero eigenvalue property (SZEP).
///
/// Prints the smallest K eigenvalues (all of them with -k 0) of the complex anchored pose graph
/// matrix W (eq. (24)), of the penalized matrix W(lambda*) at the solution of the dual SDP
/// (31), and of the rotation-only matrix M = Q - S^H L^-1 S; the number of eigenvalues of
/// W(lambda*) at zero (the SZEP holds when it is one, Prop. 10); and whether the graph is a tree
/// or balanced (Prop. 6: W has a zero eigenvalue exactly then). An eigenvalue of W(lambda*) counts
/// as zero within 1000 times the accuracy of the dual solution (its duality gap, or the rounding
/// of the eigenvalue computation if larger). Components are analysed one by one; the top-level
/// lists merge theirs.
#[derive(Debug, Parser)]
#[command(name = "pgo-spectrum", version, after_help = EXAMPLES)]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    #[command(flatten)]
    pub weights: WeightArgs,

    /// How many of the smallest eigenvalues to print (0: all)
    #[arg(short = 'k', long = "count", default_value = "0", value_name = "K")]
    pub count: usize,

    /// SDP solver for the dual
    #[arg(long, value_enum, default_value = "ipm")]
    pub solver: SdpSolver,

    /// Print one JSON object on stdout
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub rerun: RerunArgs,
}

#[derive(Debug, Serialize)]
pub struct ComponentSpectrum {
    pub first_id: u32,
    pub poses: usize,
    pub edges: usize,
    pub eigenvalues: Vec<f64>,
    pub penalized_eigenvalues: Vec<f64>,
    pub rotation_eigenvalues: Vec<f64>,
    pub near_zero: usize,
    pub szep: bool,
    pub tree: bool,
    pub balanced: bool,
    /// d* = Σλ*.
    pub dual_objective: f64,
    /// λ*, one multiplier per pose of the component, in ascending id order.
    pub lambda: Vec<f64>,
    /// The proven lower bound on f* (see pgo-solve).
    pub lower_bound: f64,
    /// Whether the SDP solver reached its tolerance (see pgo-solve).
    pub sdp_converged: bool,
}

/// What `--json` prints; lists are ascending.
#[derive(Debug, Serialize)]
pub struct Report {
    pub weights: Weights,
    pub poses: usize,
    pub edges: usize,
    /// Eigenvalues of W (all components merged).
    pub eigenvalues: Vec<f64>,
    /// Eigenvalues of W(lambda*).
    pub penalized_eigenvalues: Vec<f64>,
    /// Eigenvalues of M.
    pub rotation_eigenvalues: Vec<f64>,
    /// Eigenvalues of W(lambda*) at zero, summed over components.
    pub near_zero: usize,
    pub szep: bool,
    pub tree: bool,
    pub balanced: bool,
    /// Whether the SDP solver reached its tolerance on every component.
    pub sdp_converged: bool,
    pub components: Vec<ComponentSpectrum>,
}

/// Tolerance of the balanced test (metres and radians), Definition 1.
const BALANCE_TOLERANCE: f64 = 1e-9;

/// Entry point of the `pgo-spectrum` binary.
pub fn main() -> ExitCode {
    let args = Args::parse();
    crate::cli::run_tool("pgo-spectrum", || run(&args))
}

fn smallest(mut v: Vec<f64>, k: usize) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    if k > 0 {
        v.truncate(k);
    }
    v
}

pub fn run(args: &Args) -> crate::Result<ExitCode> {
    let rec = args.rerun.recorder("pgo-spectrum")?;
    let (graph, _) = args.input.read()?;
    rec.graph(&graph);
    check_dense_size(&graph, "pgo-spectrum")?;
    let policy = args.weights.weights;
    let mut components = Vec::new();
    for (part, _, _) in graph.components() {
        let weights = edge_weights(&part, policy)?;
        // In the units of the normalized weights, scaled back (see DualAnalysis).
        let a = analyze(&part, &weights, args.solver)?;
        let scaled = |v: Vec<f64>| -> Vec<f64> { v.into_iter().map(|x| x * a.scale).collect() };
        let zeros = a.near_zero;
        components.push(ComponentSpectrum {
            first_id: part.ids[0],
            poses: part.num_poses(),
            edges: part.edges.len(),
            eigenvalues: smallest(scaled(hermitian_eigenvalues(&a.matrix.dense())), args.count),
            penalized_eigenvalues: smallest(scaled(a.bound.eigenvalues.clone()), args.count),
            rotation_eigenvalues: smallest(scaled(hermitian_eigenvalues(&a.m)), args.count),
            near_zero: zeros,
            szep: zeros <= 1,
            tree: part.is_forest(),
            balanced: part.is_balanced(BALANCE_TOLERANCE),
            dual_objective: a.dual.dual_objective * a.scale,
            lambda: scaled(a.dual.lambda.clone()),
            lower_bound: a.bound.lower_bound * a.scale,
            sdp_converged: a.dual.converged,
        });
    }
    let merge = |f: fn(&ComponentSpectrum) -> &Vec<f64>| {
        smallest(
            components
                .iter()
                .flat_map(|c| f(c).iter().copied())
                .collect(),
            args.count,
        )
    };
    let report = Report {
        weights: policy,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        eigenvalues: merge(|c| &c.eigenvalues),
        penalized_eigenvalues: merge(|c| &c.penalized_eigenvalues),
        rotation_eigenvalues: merge(|c| &c.rotation_eigenvalues),
        near_zero: components.iter().map(|c| c.near_zero).sum(),
        szep: components.iter().all(|c| c.szep),
        tree: components.iter().all(|c| c.tree),
        balanced: components.iter().all(|c| c.balanced),
        sdp_converged: components.iter().all(|c| c.sdp_converged),
        components,
    };
    let text = if args.json {
        to_json_line(&report)?
    } else {
        text_report(&report)
    };
    write_stdout(text.as_bytes())?;
    rec.spectrum(&crate::viz::Spectrum {
        eigenvalues: &report.eigenvalues,
        penalized_eigenvalues: &report.penalized_eigenvalues,
        rotation_eigenvalues: &report.rotation_eigenvalues,
        near_zero: report.near_zero,
        szep: report.szep,
        lower_bound: Some(report.components.iter().map(|c| c.lower_bound).sum()),
    });
    rec.finish()?;
    Ok(ExitCode::SUCCESS)
}

fn text_report(r: &Report) -> String {
    let list = |v: &[f64]| v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ");
    let yes = |b: bool| if b { "yes" } else { "no" };
    format!(
        "poses:                 {}\nedges:                 {}\nweights:               {}\neigenvalues of W:      {}\neigenvalues of W(l*):  {}\neigenvalues of M:      {}\nzero eigenvalues:      {} of W(l*)\nSZEP:                  {}\ntree:                  {}\nbalanced:              {}\n",
        r.poses,
        r.edges,
        r.weights.name(),
        list(&r.eigenvalues),
        list(&r.penalized_eigenvalues),
        list(&r.rotation_eigenvalues),
        r.near_zero,
        yes(r.szep),
        yes(r.tree),
        yes(r.balanced)
    )
}
