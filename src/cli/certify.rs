//! `pgo-certify`: certify or bound any estimate of a pose graph (e.g. one written by g2o, GTSAM or
//! pgo-solve).

use super::common::{InputArgs, RerunArgs, WeightArgs, num, to_json_line, write_stdout};
use super::progress_bar::ProgressArgs;
use crate::error::Error;
use crate::graph::Pose2;
use crate::io::{self, ReadOptions};
use crate::solve::{CertifyOptions, EstimateReport as Report, certify_estimate};
use clap::Parser;
use serde::Serialize;
use std::process::ExitCode;

const EXAMPLES: &str = "\
Examples:
  pgo-certify M3500.g2o --estimate M3500-g2o-output.g2o
  pgo-solve intel.g2o -o intel-opt.g2o && pgo-certify intel-opt.g2o
  pgo-certify city10000.g2o --estimate gtsam-result.g2o --json | jq .suboptimality_bound

Exit status: 0 certified within --tol, 1 not certified (the bound printed still holds), 2 error.";

/// Certify an estimate of a planar or 3D pose graph, or bound how far it is from optimal.
///
/// The estimate's own Lagrange multipliers lambda (first-order conditions, eq. (33)) are tested:
/// a proof that W(lambda) + eta*blkdiag(0, I) is positive semidefinite (the inertia of one sparse
/// LDL^H factorization isolates the estimate's near-zero eigenvalue and Temple's inequality
/// bounds it, or else a sparse Cholesky factorization succeeds) makes lambda - eta dual feasible,
/// so sum(lambda) - n*eta is a lower bound on the optimum (weak duality (32)) and
/// cost - lower_bound bounds the suboptimality. When that fails (the estimate
/// is not optimal, or not optimal enough for --tol), pgo-certify solves the problem itself and
/// reports the lower bound that solution proves: the bound printed always holds.
///
/// The cost is the paper's objective (8) with isotropic weights per edge, f = sum tau*|p_j - p_i -
/// r_i*Delta_ij|^2 + kappa*|r_j - r_i*R_ij|^2, tau = 2/tr(inv(Omega_tt)) and kappa = 2*Omega_thth
/// from the edge's information matrix Omega (--weights unit: tau = kappa = 1). It is not g2o's
/// chi2, sum e^T*Omega*e under the full information matrices (printed beside it), nor GTSAM's
/// error, which is chi2/2 (to first order in the residuals: GTSAM's residual is the log map of
/// the relative pose error). An optimum of chi2 (from g2o, GTSAM or pgo-solve --refine) is an
/// optimum of another objective, so pgo-certify reports it NOT certified, with a proven bound on
/// how far its cost is above the optimum of f (intel: about 4% relative): that answer is right.
/// The estimate pgo-solve writes without --refine is the one that can be certified.
///
/// 3D graphs: SE-Sync's objective and weights (see pgo-solve --help); the estimate's
/// multipliers Lambda_i = sym((QX)_i X_i^T) and the proof that S + eta*P is positive
/// semidefinite (LDL^T inertia and the Lehmann-Maehly bound for the estimate's three null
/// directions, or a Cholesky factorization) give the bound sum tr(Lambda_i) - 3n*eta.
#[derive(Debug, Parser)]
#[command(name = "pgo-certify", version, after_help = super::after_help(EXAMPLES))]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    /// The estimate: a g2o or TORO file whose vertex lines hold the poses, by id [default: the
    /// graph file's own vertices]
    #[arg(long, value_name = "EST")]
    pub estimate: Option<String>,

    #[command(flatten)]
    pub weights: WeightArgs,

    /// Relative suboptimality bound under which the estimate is called certified
    #[arg(long, default_value = "1e-6", value_name = "REL", value_parser = super::common::parse_tolerance, allow_negative_numbers = true)]
    pub tol: f64,

    /// Print the report as one JSON object on stdout
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub progress: ProgressArgs,

    #[command(flatten)]
    pub rerun: RerunArgs,
}

/// What `--json` prints: the library's report and the reader's warnings (lines skipped, e.g.
/// EQUIV with --ignore-equiv: the bound is for the graph without them).
/// The Python package builds its report with this too.
#[derive(Serialize)]
pub struct JsonReport<'a> {
    #[serde(flatten)]
    pub report: &'a Report,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// Entry point of the `pgo-certify` binary.
pub fn main() -> ExitCode {
    let args = Args::parse();
    crate::cli::run_tool("pgo-certify", || run(&args))
}

pub fn run(args: &Args) -> crate::Result<ExitCode> {
    let rec = args.rerun.recorder("pgo-certify")?;
    let progress = args.progress.start("pgo-certify");
    let (graph, read_report) = args.input.read_any_shown(&progress)?;
    let graph = match graph {
        io::AnyGraph::Planar(graph) => graph,
        io::AnyGraph::Spatial(graph) => return run3(args, &graph, &read_report, progress, rec),
    };
    let poses = match &args.estimate {
        None => {
            if !graph.vertices_declared
                || (!graph.landmarks.is_empty() && !graph.landmarks.declared)
            {
                return Err(Error::Invalid(format!(
                    "{}: the file has no vertex lines{}, so there is no estimate to certify (give one with --estimate)",
                    args.input.input,
                    if graph.vertices_declared {
                        " for its landmarks"
                    } else {
                        ""
                    }
                )));
            }
            let landmarks = graph.landmarks.positions.iter();
            graph
                .poses
                .iter()
                .copied()
                .chain(landmarks.map(|&[x, y]| Pose2::new(x, y, 0.0)))
                .collect()
        }
        Some(path) => {
            progress.phase(&format!("reading {path}"));
            progress.suspend(|| estimate_poses(&graph, path))?
        }
    };
    let options = CertifyOptions {
        weights: args.weights.weights,
        tolerance: args.tol,
    };
    let source = args.estimate.as_deref().unwrap_or(&args.input.input);
    let report = progress.watch(|| certify_estimate(&graph, &poses, &options, source))?;
    progress.finish();
    // The estimate as the graph to view, and the certificate as a text entry.
    let mut estimate = graph.clone();
    let n = graph.num_poses();
    for (at, p) in estimate.landmarks.positions.iter_mut().zip(&poses[n..]) {
        *at = [p.x, p.y];
    }
    estimate.poses = poses[..n].to_vec();
    rec.graph(&estimate);
    if args.json {
        let json = JsonReport {
            report: &report,
            warnings: read_report.warnings.iter().map(|w| w.to_string()).collect(),
        };
        write_stdout(to_json_line(&json)?.as_bytes())?;
    } else {
        eprint!("{}", text_report(args, &report));
    }
    rec.certificate(&crate::viz::Certificate {
        cost: report.cost,
        lower_bound: report.lower_bound,
        certified: report.certified,
        szep: report
            .components
            .iter()
            .all(|c| c.near_zero_eigenvalues.is_some_and(|z| z <= 1)),
        near_zero: report
            .components
            .iter()
            .filter_map(|c| c.near_zero_eigenvalues)
            .sum(),
    });
    rec.finish()?;
    Ok(if report.certified {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The rest of [`run`] for a 3D graph: the estimate (the file's own vertices or --estimate's,
/// by id) certified by [`crate::solve::certify_estimate3`], reported as in 2D.
fn run3(
    args: &Args,
    graph: &crate::graph3::Graph3,
    read_report: &io::ReadReport,
    progress: super::progress_bar::Progress,
    rec: crate::viz::Recorder,
) -> crate::Result<ExitCode> {
    let poses = match &args.estimate {
        None => graph.poses.clone(),
        Some(path) => {
            progress.phase(&format!("reading {path}"));
            let options = ReadOptions {
                ignore_equiv: true,
                ..Default::default()
            };
            let (estimate, report) = io::read_any_path(path, &options)?;
            progress.suspend(|| crate::cli::print_warnings(&report.warnings));
            let io::AnyGraph::Spatial(estimate) = estimate else {
                return Err(Error::Invalid(format!(
                    "{path}: the estimate is a planar graph and the graph a 3D one"
                )));
            };
            if estimate.form != graph.form {
                return Err(Error::Invalid(format!(
                    "{path}: the estimate writes its rotations in another form than the graph (g2o quaternions against TORO Euler angles)"
                )));
            }
            graph
                .ids
                .iter()
                .map(|&id| {
                    estimate
                        .index_of(id)
                        .map(|k| estimate.poses[k])
                        .ok_or_else(|| {
                            Error::Invalid(format!(
                                "{path}: the estimate has no vertex {id}, which the graph has"
                            ))
                        })
                })
                .collect::<crate::Result<Vec<_>>>()?
        }
    };
    let options = CertifyOptions {
        weights: args.weights.weights,
        tolerance: args.tol,
    };
    let source = args.estimate.as_deref().unwrap_or(&args.input.input);
    let report =
        progress.watch(|| crate::solve::certify_estimate3(graph, &poses, &options, source))?;
    progress.finish();
    // The estimate certified, as in 2D.
    rec.graph3(&crate::graph3::Graph3 {
        poses,
        ..graph.clone()
    });
    if args.json {
        let json = JsonReport {
            report: &report,
            warnings: read_report.warnings.iter().map(|w| w.to_string()).collect(),
        };
        write_stdout(to_json_line(&json)?.as_bytes())?;
    } else {
        eprint!("{}", text_report(args, &report));
    }
    rec.certificate(&crate::viz::Certificate {
        cost: report.cost,
        lower_bound: report.lower_bound,
        certified: report.certified,
        // In 3D the kernel of a certified S is 3-dimensional (the estimate's rotations).
        szep: report
            .components
            .iter()
            .all(|c| c.near_zero_eigenvalues == Some(3)),
        near_zero: report
            .components
            .iter()
            .filter_map(|c| c.near_zero_eigenvalues)
            .sum(),
    });
    rec.finish()?;
    Ok(if report.certified {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The poses of `path`'s vertex lines, matched to the graph's poses by id, then its landmark
/// positions matched to the graph's landmarks by id (in the same landmark form).
fn estimate_poses(graph: &crate::graph::PoseGraph, path: &str) -> crate::Result<Vec<Pose2>> {
    // Only the vertex lines of the estimate are used: EQUIV lines there are skipped (warning).
    let options = ReadOptions {
        ignore_equiv: true,
        ..Default::default()
    };
    let (estimate, report) = io::read_path(path, &options)?;
    crate::cli::print_warnings(&report.warnings);
    if !estimate.vertices_declared {
        return Err(Error::Invalid(format!(
            "{path}: the estimate has no vertex lines"
        )));
    }
    let marks = &graph.landmarks;
    if !marks.is_empty() {
        if estimate.landmarks.form != marks.form && !estimate.landmarks.is_empty() {
            return Err(Error::Invalid(format!(
                "{path}: the estimate writes its landmarks in another form than the graph (convert it with pgo-convert --landmarks)"
            )));
        }
        if !estimate.landmarks.declared {
            return Err(Error::Invalid(format!(
                "{path}: the estimate has no landmark vertex lines (VERTEX_XY or POINT2)"
            )));
        }
    }
    let poses = graph.ids.iter().map(|&id| {
        estimate
            .index_of(id)
            .map(|k| estimate.poses[k])
            .ok_or_else(|| {
                Error::Invalid(format!(
                    "{path}: the estimate has no vertex {id}, which the graph has"
                ))
            })
    });
    let landmarks = marks.ids.iter().map(|&id| {
        estimate
            .landmarks
            .index_of(id)
            .map(|k| {
                let [x, y] = estimate.landmarks.positions[k];
                Pose2::new(x, y, 0.0)
            })
            .ok_or_else(|| {
                Error::Invalid(format!(
                    "{path}: the estimate has no landmark {id}, which the graph has"
                ))
            })
    });
    poses.chain(landmarks).collect()
}

fn text_report(args: &Args, r: &Report) -> String {
    let input = &args.input.input;
    let mut out = format!(
        "pgo-certify: {}{}: {} poses, {} edges, {} component{}; weights {}\n",
        if input == "-" { "<stdin>" } else { input },
        args.estimate
            .as_ref()
            .map_or(String::new(), |e| format!(" (estimate {e})")),
        r.poses,
        r.edges,
        r.components.len(),
        if r.components.len() == 1 { "" } else { "s" },
        r.weights.name(),
    );
    let row = |k: &str, v: String| format!("  {k:<21}{v}\n");
    out += &row("cost", num(r.cost));
    out += &row(
        "chi2 (g2o)",
        r.chi2
            .map_or("undefined (a covariance matrix is singular)".into(), num),
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
    out += &row("gradient norm", num(r.gradient_norm));
    out += &row(
        "result",
        if r.certified {
            format!("certified optimal within --tol {}", num(args.tol))
        } else {
            format!(
                "NOT certified within --tol {}; the bound above holds",
                num(args.tol)
            )
        },
    );
    out
}
