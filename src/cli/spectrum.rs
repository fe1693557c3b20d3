//! `pgo-spectrum`: eigenvalues of the pose graph matrix W, of the penalized matrix W(lambda*)
//! and of the rotation-only matrix M; the SZEP; the tree and balanced flags of Prop. 6. For 3D
//! graphs, those of SE-Sync's data matrix Q, of the certificate matrix S and of M
//! ([`crate::spectrum::spatial`]).

use super::common::{InputArgs, RerunArgs, WeightArgs, num, to_json_line, write_stdout};
use super::progress_bar::ProgressArgs;
use crate::dual::solver::SdpSolver;
use crate::error::Error;
use crate::io;
use crate::spectrum::{Spectrum as Report, Spectrum3, SpectrumOptions, spectrum, spectrum3};
use clap::Parser;
use serde::Serialize;
use std::process::ExitCode;

const EXAMPLES: &str = "\
Examples:
  pgo-spectrum datasets/paper_toy.g2o --weights unit
  pgo-spectrum MIT.g2o -k 6 --json | jq '.penalized_eigenvalues'
  pgo-spectrum sphere2500.g2o -k 6     # 3D: Q, S, M; 3 zeros of S";

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
/// subspace iteration (M is never formed). With -k K (1 to 100), components of more than 100
/// poses are analysed sparse as well whenever that gives the dense answer: when the certificate
/// proves the estimate optimal with the SZEP (its lambda is then lambda*, the eigenvalues those
/// of the dense path to about 1e-8 relative); otherwise they are analysed dense. -k 0 (all
/// eigenvalues) of components of at most 2000 poses is always dense.
///
/// 3D graphs (g2o VERTEX_SE3:QUAT/EDGE_SE3:QUAT, TORO VERTEX3/EDGE3): each component is solved
/// as by pgo-solve (SE-Sync's problem, the staircase), then the K smallest eigenvalues (10 with
/// -k 0, at most 100) are computed sparse, as above, of SE-Sync's data matrix Q over [t; Y] with
/// one translation anchored (the 3D W), of the certificate matrix S = Q - blkdiag(0, Lambda) at
/// the estimate (the 3D W(lambda*); Lambda_i = sym((QX)_i X_i^T), SE-Sync eq. (48)) and of the
/// rotation-only matrix M = Q_YY - Q_Yt L^-1 Q_tY (the translations eliminated). At a certified
/// optimum S has three eigenvalues at zero (the estimate's three columns): the zero count is the
/// certificate's deflated count (its LDL^T inertia proves the fourth eigenvalue positive), else
/// the computed eigenvalues of S below the zero threshold above with the gap cost - lower bound;
/// szep says the certificate counted exactly three. The JSON adds "dimension": 3 and
/// "certified", and leaves out tree, balanced, lambda and sdp_converged; --solver is not used.
#[derive(Debug, Parser)]
#[command(name = "pgo-spectrum", version, after_help = super::after_help(EXAMPLES))]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    #[command(flatten)]
    pub weights: WeightArgs,

    /// How many of the smallest eigenvalues to print (0: all, but 10 for components of more
    /// than 2000 poses, where at most 100 can be asked for; 1 to 100 are computed sparse for
    /// components of more than 100 poses, see above)
    #[arg(short = 'k', long = "count", default_value = "0", value_name = "K")]
    pub count: usize,

    /// SDP solver for the dual (components of at most 2000 poses)
    #[arg(long, value_enum, default_value = "ipm")]
    pub solver: SdpSolver,

    /// Print one JSON object on stdout
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub progress: ProgressArgs,

    #[command(flatten)]
    pub rerun: RerunArgs,
}

/// What `--json` prints: the library's report and the reader's warnings (lines skipped, e.g.
/// EQUIV with --ignore-equiv: the spectra are of the graph without them).
/// The Python package builds its report with this too.
#[derive(Serialize)]
pub struct JsonReport<'a> {
    #[serde(flatten)]
    pub report: &'a Report,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// Entry point of the `pgo-spectrum` binary.
pub fn main() -> ExitCode {
    let args = Args::parse();
    crate::cli::run_tool("pgo-spectrum", || run(&args))
}

pub fn run(args: &Args) -> crate::Result<ExitCode> {
    let progress = args.progress.start("pgo-spectrum");
    let (graph, read_report) = args.input.read_any_shown(&progress)?;
    let graph = match graph {
        io::AnyGraph::Planar(graph) => graph,
        io::AnyGraph::Spatial(graph) => return run3(args, &graph, &read_report, progress),
    };
    let rec = args.rerun.recorder("pgo-spectrum")?;
    rec.graph(&graph);
    let options = SpectrumOptions {
        weights: args.weights.weights,
        count: args.count,
        solver: args.solver,
    };
    let report = progress.watch(|| spectrum(&graph, &options))?;
    progress.finish();
    for c in report.components.iter().filter(|c| !c.eigen_converged) {
        eprintln!(
            "pgo-spectrum: warning: the eigenvalue iteration of the component of pose {} did not converge; its eigenvalues are upper bounds",
            c.first_id
        );
    }
    let text = if args.json {
        to_json_line(&JsonReport {
            report: &report,
            warnings: read_report.warnings.iter().map(|w| w.to_string()).collect(),
        })?
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

/// What `--json` prints for a 3D graph: [`Spectrum3`] and the reader's warnings.
#[derive(Serialize)]
pub struct JsonReport3<'a> {
    #[serde(flatten)]
    pub report: &'a Spectrum3,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// The rest of [`run`] for a 3D graph: [`spectrum3`] and its report.
fn run3(
    args: &Args,
    graph: &crate::graph3::Graph3,
    read_report: &io::ReadReport,
    progress: super::progress_bar::Progress,
) -> crate::Result<ExitCode> {
    let r = &args.rerun;
    if r.rerun_save.is_some() || r.rerun_connect.is_some() || r.rerun_spawn {
        return Err(Error::Invalid(
            "--rerun-save, --rerun-connect, --rerun-spawn: 3D graphs are not recorded yet".into(),
        ));
    }
    let report = progress.watch(|| spectrum3(graph, args.weights.weights, args.count))?;
    progress.finish();
    for c in report.components.iter().filter(|c| !c.eigen_converged) {
        eprintln!(
            "pgo-spectrum: warning: the eigenvalue iteration of the component of pose {} did not converge; its eigenvalues are upper bounds",
            c.first_id
        );
    }
    let text = if args.json {
        to_json_line(&JsonReport3 {
            report: &report,
            warnings: read_report.warnings.iter().map(|w| w.to_string()).collect(),
        })?
    } else {
        text_report3(&report)
    };
    write_stdout(text.as_bytes())?;
    Ok(ExitCode::SUCCESS)
}

fn text_report3(r: &Spectrum3) -> String {
    let list = |v: &[f64]| v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ");
    let yes = |b: bool| if b { "yes" } else { "no" };
    format!(
        "poses:                 {}\nedges:                 {}\ndimension:             3\nweights:               {}\neigenvalues of Q:      {}\neigenvalues of S:      {}\neigenvalues of M:      {}\nzero eigenvalues:      {} of S\nthree zeros (SZEP):    {}\ncertified:             {}\n",
        r.poses,
        r.edges,
        r.weights.name(),
        list(&r.eigenvalues),
        list(&r.penalized_eigenvalues),
        list(&r.rotation_eigenvalues),
        r.near_zero,
        yes(r.szep),
        yes(r.certified)
    )
}

fn text_report(r: &Report) -> String {
    let list = |v: &[f64]| v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ");
    let yes = |b: bool| if b { "yes" } else { "no" };
    let landmarks = if r.landmarks == 0 {
        String::new()
    } else {
        format!(
            "landmarks:             {} ({} observations)\n",
            r.landmarks, r.observations
        )
    };
    format!(
        "poses:                 {}\nedges:                 {}\n{}weights:               {}\neigenvalues of W:      {}\neigenvalues of W(l*):  {}\neigenvalues of M:      {}\nzero eigenvalues:      {} of W(l*)\nSZEP:                  {}\ntree:                  {}\nbalanced:              {}\n",
        r.poses,
        r.edges,
        landmarks,
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
