//! `pgo-spectrum`: eigenvalues of the pose graph matrix W, of the penalized matrix W(lambda*)
//! and of the rotation-only matrix M; the SZEP; the tree and balanced flags of Prop. 6.

use super::common::{
    DENSE_MAX_POSES, InputArgs, RerunArgs, WeightArgs, num, to_json_line, write_stdout,
};
use crate::algorithm1::{SdpSolver, analyze};
use crate::error::Error;
use crate::spectrum::{hermitian_eigenvalues, scalable_spectrum};
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
///
/// Components of more than 2000 poses are analysed sparse, without the SDP: lambda* are the
/// multipliers of the scalable solver's estimate (pgo-solve's staircase), the zero count and the
/// SZEP its certificate's (one eigenvalue at zero, proven, when the certificate isolates it),
/// sdp_converged whether the certificate holds, and only the K smallest eigenvalues of each
/// matrix are computed (10 with -k 0), with one sparse factorization per matrix and shift-invert
/// subspace iteration (M is never formed).
#[derive(Debug, Parser)]
#[command(name = "pgo-spectrum", version, after_help = EXAMPLES)]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    #[command(flatten)]
    pub weights: WeightArgs,

    /// How many of the smallest eigenvalues to print (0: all, but 10 for components of more
    /// than 2000 poses, where at most 100 can be asked for)
    #[arg(short = 'k', long = "count", default_value = "0", value_name = "K")]
    pub count: usize,

    /// SDP solver for the dual (components of at most 2000 poses)
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
    /// Whether the SDP solver reached its tolerance (see pgo-solve); for a component analysed
    /// sparse (more than [`DENSE_MAX_POSES`] poses), whether the scalable solver's certificate
    /// proved its estimate optimal (pgo-solve's `certified`).
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

/// How many of the smallest eigenvalues `-k 0` prints for a component of more than
/// [`DENSE_MAX_POSES`] poses, where not all are computed.
pub const SPARSE_DEFAULT_COUNT: usize = 10;

/// The most eigenvalues per matrix computed for a component of more than [`DENSE_MAX_POSES`]
/// poses (each costs two solves per iteration of the subspace iteration).
pub const SPARSE_MAX_COUNT: usize = 100;

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
    let policy = args.weights.weights;
    let parts = graph.components();
    let sparse = |part: &crate::graph::PoseGraph| part.num_poses() > DENSE_MAX_POSES;
    let any_sparse = parts.iter().any(|(part, _, _)| sparse(part));
    let sparse_count = match args.count {
        0 => SPARSE_DEFAULT_COUNT,
        k if k > SPARSE_MAX_COUNT && any_sparse => {
            return Err(Error::Invalid(format!(
                "-k {k} is more than the {SPARSE_MAX_COUNT} smallest eigenvalues computed for components of more than {DENSE_MAX_POSES} poses"
            )));
        }
        k => k,
    };
    let mut components = Vec::new();
    for (part, _, _) in parts {
        let weights = edge_weights(&part, policy)?;
        if sparse(&part) {
            let s = scalable_spectrum(&part, &weights, sparse_count)?;
            if !s.spectra.converged {
                eprintln!(
                    "pgo-spectrum: warning: the eigenvalue iteration of the component of pose {} did not converge; its eigenvalues are upper bounds",
                    part.ids[0]
                );
            }
            components.push(ComponentSpectrum {
                first_id: part.ids[0],
                poses: part.num_poses(),
                edges: part.edges.len(),
                eigenvalues: s.spectra.eigenvalues,
                penalized_eigenvalues: s.spectra.penalized_eigenvalues,
                rotation_eigenvalues: s.spectra.rotation_eigenvalues,
                near_zero: s.near_zero,
                szep: s.szep,
                tree: part.is_forest(),
                balanced: part.is_balanced(BALANCE_TOLERANCE),
                dual_objective: s.dual_objective,
                lambda: s.lambda,
                lower_bound: s.lower_bound,
                sdp_converged: s.certified,
            });
            continue;
        }
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
    // The K smallest of each component hold the K smallest of the graph; with -k 0 and a
    // component analysed sparse, its SPARSE_DEFAULT_COUNT are all the merged lists can hold.
    let merged_count = if any_sparse { sparse_count } else { args.count };
    let merge = |f: fn(&ComponentSpectrum) -> &Vec<f64>| {
        smallest(
            components
                .iter()
                .flat_map(|c| f(c).iter().copied())
                .collect(),
            merged_count,
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
