//! `pgo-eval`: the trajectory error of an estimate against a reference (evo's APE and RPE).

use super::common::{ReadFlags, num, to_json_line, write_stdout};
use crate::error::Error;
use crate::eval::align::Alignment;
use crate::eval::ape::{AbsoluteError, absolute_error};
use crate::eval::rpe::{RelativeError, relative_error};
use crate::eval::spatial::{Alignment3, absolute_error3, match_by_id3, relative_error3};
use crate::eval::{Statistics, match_by_id};
use crate::io::{self, AnyGraph};
use clap::Parser;
use serde::Serialize;
use std::process::ExitCode;

const EXAMPLES: &str = "\
Examples:
  pgo-solve ring.g2o -o ring-opt.g2o && pgo-eval ring-opt.g2o ring_groundtruth.g2o
  pgo-eval intel-opt.g2o intel-gtsam.g2o --delta 10 --json | jq .ape.translation.rmse
  pgo-eval est.g2o gt.g2o --no-align          positions compared as they are";

/// Error of an estimate against a reference: ground truth, or another solver's estimate.
///
/// Poses are matched by vertex id (ids in only one file are left out and counted). The estimate
/// is aligned to the reference by the SE(2) transform (SE(3) for 3D graphs) that minimizes the
/// squared position error (Umeyama's alignment without scale, as evo's --align), then:
/// APE, the absolute pose error per matched pose: the distance between the positions (m) and the
/// heading difference (degrees; in 3D the angle of the rotation error Q^-1 P);
/// RPE, the relative pose error over pairs of matched poses --delta apart in ascending id order:
/// the error of the estimate's relative motion against the reference's, (Q_i^-1 Q_j)^-1 (P_i^-1
/// P_j), its translation norm and rotation angle (alignment does not change it). Pairs (0, d),
/// (d, 2d), ... as evo's default, or every (i, i + d) with --all-pairs.
/// Each is summarized as evo does: rmse, mean, median, std (population), min, max.
#[derive(Debug, Parser)]
#[command(name = "pgo-eval", version, after_help = super::after_help(EXAMPLES))]
pub struct Args {
    /// The estimate: a g2o or TORO file whose vertex lines hold the poses
    #[arg(value_name = "EST")]
    pub estimate: String,

    /// The reference (ground truth): a g2o or TORO file whose vertex lines hold the poses
    #[arg(value_name = "REF")]
    pub reference: String,

    #[command(flatten)]
    pub read: ReadFlags,

    /// RPE: the step between the poses of a pair, in matched poses
    #[arg(long, default_value = "1", value_name = "D", value_parser = clap::value_parser!(u32).range(1..))]
    pub delta: u32,

    /// RPE: every pair (i, i + D), not only (0, D), (D, 2D), ...
    #[arg(long)]
    pub all_pairs: bool,

    /// Compare the positions as they are, without the SE(2) alignment
    #[arg(long)]
    pub no_align: bool,

    /// Print the report as one JSON object on stdout
    #[arg(long)]
    pub json: bool,
}

/// What `--json` prints.
#[derive(Debug, Serialize)]
pub struct Report {
    pub estimate_poses: usize,
    pub reference_poses: usize,
    /// Poses with an id in both files.
    pub matched: usize,
    /// The transform applied to the estimate (absent with --no-align): SE(2) `angle`, `x`, `y`,
    /// or for 3D graphs SE(3) `rotation` (rows) and `translation`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alignment: Option<AnyAlignment>,
    pub ape: AbsoluteError,
    /// Absent when fewer than D + 1 poses are matched.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rpe: Option<RelativeError>,
}

/// The alignment of a planar or a 3D estimate.
#[derive(Debug, Clone, Copy, Serialize)]
#[serde(untagged)]
pub enum AnyAlignment {
    Planar(Alignment),
    Spatial(Alignment3),
}

/// Entry point of the `pgo-eval` binary.
pub fn main() -> ExitCode {
    let args = Args::parse();
    crate::cli::run_tool("pgo-eval", || run(&args))
}

/// Reads a file of poses; a file without vertex lines has none to compare. Its warnings are
/// printed unless `quiet` (the same file read a second time).
fn read_poses(args: &Args, path: &str, quiet: bool) -> crate::Result<AnyGraph> {
    let (graph, report) = io::read_any_path(path, &args.read.options())?;
    if !quiet {
        crate::cli::print_warnings(&report.warnings);
    }
    if let AnyGraph::Planar(g) = &graph
        && !g.vertices_declared
    {
        return Err(Error::Invalid(format!(
            "{path}: the file has no vertex lines, so it holds no poses to compare"
        )));
    }
    Ok(graph)
}

pub fn run(args: &Args) -> crate::Result<ExitCode> {
    let estimate = read_poses(args, &args.estimate, false)?;
    let reference = read_poses(args, &args.reference, args.reference == args.estimate)?;
    let (delta, all_pairs) = (args.delta as usize, args.all_pairs);
    let no_common = || {
        Error::Invalid(format!(
            "{} and {} have no vertex id in common",
            args.estimate, args.reference
        ))
    };
    let report = match (&estimate, &reference) {
        (AnyGraph::Planar(e), AnyGraph::Planar(r)) => {
            let matched = match_by_id(e, r);
            let alignment = (!args.no_align)
                .then(|| Alignment::least_squares(&matched))
                .flatten();
            Report {
                estimate_poses: e.num_poses(),
                reference_poses: r.num_poses(),
                matched: matched.ids.len(),
                ape: absolute_error(&matched, &alignment.unwrap_or(Alignment::IDENTITY))
                    .ok_or_else(no_common)?,
                alignment: alignment.map(AnyAlignment::Planar),
                rpe: relative_error(&matched, delta, all_pairs),
            }
        }
        (AnyGraph::Spatial(e), AnyGraph::Spatial(r)) => {
            let matched = match_by_id3(e, r);
            let alignment = (!args.no_align)
                .then(|| Alignment3::least_squares(&matched))
                .flatten();
            Report {
                estimate_poses: e.num_poses(),
                reference_poses: r.num_poses(),
                matched: matched.ids.len(),
                ape: absolute_error3(&matched, &alignment.unwrap_or(Alignment3::IDENTITY))
                    .ok_or_else(no_common)?,
                alignment: alignment.map(AnyAlignment::Spatial),
                rpe: relative_error3(&matched, delta, all_pairs),
            }
        }
        (e, _) => {
            let dim = |g: &AnyGraph| match g {
                AnyGraph::Planar(_) => "planar",
                AnyGraph::Spatial(_) => "3D",
            };
            return Err(Error::Invalid(format!(
                "{} is {} and {} is {}: both must be planar or both 3D",
                args.estimate,
                dim(e),
                args.reference,
                dim(&reference)
            )));
        }
    };
    if args.json {
        write_stdout(to_json_line(&report)?.as_bytes())?;
    } else {
        eprint!("{}", text_report(args, &report));
    }
    Ok(ExitCode::SUCCESS)
}

fn row(name: &str, s: &Statistics) -> String {
    format!(
        "  {name:<22} rmse {}  mean {}  median {}  std {}  min {}  max {}\n",
        num(s.rmse),
        num(s.mean),
        num(s.median),
        num(s.std),
        num(s.min),
        num(s.max)
    )
}

fn text_report(args: &Args, r: &Report) -> String {
    let mut out = format!(
        "pgo-eval: {} against {}: {} poses matched by id (of {} and {})\n",
        args.estimate, args.reference, r.matched, r.estimate_poses, r.reference_poses
    );
    match &r.alignment {
        Some(AnyAlignment::Planar(a)) => out.push_str(&format!(
            "  aligned by SE(2): rotation {} rad, translation ({}, {})\n",
            num(a.angle),
            num(a.x),
            num(a.y)
        )),
        Some(AnyAlignment::Spatial(a)) => out.push_str(&format!(
            "  aligned by SE(3): rotation of {} rad, translation ({}, {}, {})\n",
            num(a.isometry().rotation.angle()),
            num(a.translation[0]),
            num(a.translation[1]),
            num(a.translation[2])
        )),
        None => out.push_str("  not aligned (--no-align)\n"),
    }
    out.push_str(&row("APE translation (m)", &r.ape.translation));
    out.push_str(&row("APE rotation (deg)", &r.ape.rotation_deg));
    match &r.rpe {
        Some(rpe) => {
            out.push_str(&format!(
                "  RPE over pairs {} apart{}, {} pairs\n",
                rpe.delta,
                if rpe.all_pairs { " (all pairs)" } else { "" },
                rpe.translation.count
            ));
            out.push_str(&row("RPE translation (m)", &rpe.translation));
            out.push_str(&row("RPE rotation (deg)", &rpe.rotation_deg));
        }
        None => out.push_str(&format!(
            "  RPE: no pair of matched poses {} apart\n",
            args.delta
        )),
    }
    out
}
