//! `pgo-convert`: g2o <-> TORO conversion, dialects, statistics.

use super::common::{RerunArgs, to_json_line, write_stdout};
use super::progress_bar::Progress;
use crate::error::Error;
use crate::graph::NoiseKind;
use crate::io::trajectory::{TrajectoryFormat, read_stamps, write_trajectory, write_trajectory3};
use crate::io::{self, Dialect, Format, ReadOptions, WriteOptions};
use crate::stats::GraphStats;
use clap::Parser;
use std::process::ExitCode;
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  pgo-convert MIT.g2o -o MIT.graph              g2o -> TORO (format from the extension)
  pgo-convert w10000.graph --to g2o > w10000.g2o
  pgo-convert --stats CSAIL.g2o                 counts, components, id range, duplicates
  pgo-convert --stats --json city10000.g2o | jq .edges
  cat M3500.g2o | pgo-convert - --reindex --to g2o -o M3500-dense.g2o
  pgo-convert w20000.txt --dialect g2o -o w20000.g2o   EDGE2 tags, g2o-order information
  pgo-convert cityTrees10000.g2o --landmarks g2o -o trees.g2o   LANDMARK2 -> VERTEX_XY/EDGE_SE2_XY
  pgo-convert trees.g2o --landmarks landmark2 --landmark-offset 10000 -o back.g2o   and back
  pgo-convert intel-opt.g2o --to tum -o intel-opt.tum   the poses as a TUM trajectory for evo

  pgo-convert --stats sphere2500.g2o            3D (VERTEX_SE3:QUAT, EDGE_SE3:QUAT): counts, dimension 3
  pgo-convert parking-garage.g2o -o copy.g2o    3D, written back bit for bit";

/// Convert pose graphs between g2o and TORO, losslessly, or report statistics.
///
/// Reads g2o (VERTEX_SE2, EDGE_SE2, FIX) and TORO (VERTEX2/VERTEX, EDGE2/EDGE) files, checks every
/// value, and writes the graph in either format: vertices sorted by id, edges in input order, FIX
/// ids on one line at the end, every number in shortest round-trip form, so converting g2o -> TORO
/// -> g2o gives back every value bit for bit. Files without vertex lines get initial poses
/// composed along a spanning tree from the smallest id. 3D files (g2o VERTEX_SE3:QUAT and
/// EDGE_SE3:QUAT, TORO VERTEX3 and EDGE3) are read and written back in their own form, bit for
/// bit; g2o and TORO 3D are not converted into each other (quaternions against Euler angles: not
/// lossless). Errors are reported as PATH:LINE:COL: message with exit status 2; an output file is
/// replaced only once completely written.
#[derive(Debug, Parser)]
#[command(name = "pgo-convert", version, after_help = super::after_help(EXAMPLES))]
pub struct Args {
    /// Input file, or - for stdin
    #[arg(value_name = "IN")]
    pub input: String,

    /// Output file, or - for stdout
    #[arg(
        short,
        long,
        value_name = "OUT",
        default_value = "-",
        conflicts_with = "stats"
    )]
    pub output: String,

    /// Input format [default: from the extension (.g2o, .graph), else from the tags]
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub from: Option<Format>,

    /// Output format [default: from the output's extension, else the input format]; tum and
    /// kitti write the poses only, sorted by id, as trajectory files for evo (TUM: `t x y z qx qy
    /// qz qw` with t the vertex id or --stamps, z = qx = qy = 0 for a planar graph; KITTI: the
    /// rows of [R | t])
    #[arg(long, value_enum, value_name = "FORMAT", conflicts_with = "stats")]
    pub to: Option<Target>,

    /// With --to tum: time stamps of the poses, a file of `id stamp` lines [default: the vertex
    /// id]
    #[arg(long, value_name = "FILE", conflicts_with = "stats")]
    pub stamps: Option<String>,

    /// How to read the six noise values of each edge [default: g2o for EDGE_SE2 tags, toro-info
    /// for EDGE2/EDGE tags]
    #[arg(long, value_enum, value_name = "DIALECT")]
    pub dialect: Option<Dialect>,

    /// How to write the noise values [default: g2o for g2o output, toro-info for TORO output];
    /// covariances and information matrices are inverted into each other when the kinds differ
    #[arg(long, value_enum, value_name = "DIALECT", conflicts_with = "stats")]
    pub to_dialect: Option<Dialect>,

    /// Renumber vertices 0..n-1 in ascending order of their ids (landmarks follow as n..n+m in
    /// g2o's form, 0..m-1 in the LANDMARK2 form)
    #[arg(long)]
    pub reindex: bool,

    /// Write landmarks in this form: g2o (VERTEX_XY, EDGE_SE2_XY; one id space with the poses)
    /// or landmark2 (CPL-SLAM's LANDMARK2, landmark ids of their own; positions on POINT2 lines)
    /// [default: the input's]. To g2o, landmark id k becomes k + OFFSET: --landmark-offset, else
    /// 0 when no landmark id is a pose id, else the largest pose id + 1 (printed on stderr); to
    /// landmark2, k becomes k - OFFSET (default 0), so the same offset converts back
    #[arg(long, value_enum, value_name = "FORM", conflicts_with = "stats")]
    pub landmarks: Option<crate::graph::LandmarkForm>,

    /// With --landmarks: the offset between the two id spaces (see --landmarks)
    #[arg(long, value_name = "OFFSET", requires = "landmarks")]
    pub landmark_offset: Option<u32>,

    /// Treat unknown tags as errors instead of skipping them with a warning
    #[arg(long)]
    pub strict: bool,

    /// Skip TORO's EQUIV lines (vertex merges, not implemented) with a warning instead of
    /// refusing the file: the graph written is the file's without them (--stats always skips
    /// them with a warning)
    #[arg(long, conflicts_with = "strict")]
    pub ignore_equiv: bool,

    /// Accept noise matrices that are not positive definite
    #[arg(long)]
    pub allow_indefinite: bool,

    /// Print statistics (poses, edges, odometry and loop closures, components, ids, duplicates)
    /// instead of converting
    #[arg(long)]
    pub stats: bool,

    /// With --stats: one JSON object on stdout
    #[arg(long, requires = "stats")]
    pub json: bool,

    /// Print the time spent reading and writing on stderr
    #[arg(long)]
    pub timings: bool,

    /// Do not print the summary line on stderr (warnings are still printed), nor the progress
    /// display (shown on stderr only when stderr is a terminal)
    #[arg(short, long)]
    pub quiet: bool,

    /// Show the progress even when stderr is not a terminal, as plain lines (for logs)
    #[arg(long, conflicts_with = "quiet")]
    pub progress: bool,

    #[command(flatten)]
    pub rerun: RerunArgs,
}

/// What `--to` writes: a graph format, or a trajectory of the poses alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Target {
    G2o,
    Toro,
    Tum,
    Kitti,
}

impl Target {
    fn graph_format(self) -> Option<Format> {
        match self {
            Target::G2o => Some(Format::G2o),
            Target::Toro => Some(Format::Toro),
            Target::Tum | Target::Kitti => None,
        }
    }

    fn trajectory_format(self) -> Option<TrajectoryFormat> {
        match self {
            Target::Tum => Some(TrajectoryFormat::Tum),
            Target::Kitti => Some(TrajectoryFormat::Kitti),
            Target::G2o | Target::Toro => None,
        }
    }
}

/// Entry point of the `pgo-convert` binary.
pub fn main() -> ExitCode {
    let args = Args::parse();
    crate::cli::run_tool("pgo-convert", || run(&args))
}

pub fn run(args: &Args) -> crate::Result<ExitCode> {
    let options = ReadOptions {
        format: args.from,
        dialect: args.dialect,
        strict: args.strict,
        // Statistics describe the file and solve nothing: EQUIV lines are counted as skipped.
        ignore_equiv: args.ignore_equiv || args.stats,
        allow_indefinite: args.allow_indefinite,
    };
    if !args.stats {
        io::check_output(&args.output)?;
    }
    let trajectory = args.to.and_then(Target::trajectory_format);
    if args.stamps.is_some() && trajectory != Some(TrajectoryFormat::Tum) {
        return Err(Error::Invalid("--stamps is for --to tum".into()));
    }
    if trajectory.is_some() && (args.to_dialect.is_some() || args.landmarks.is_some()) {
        return Err(Error::Invalid(
            "a trajectory (--to tum|kitti) has poses only: no --to-dialect or --landmarks".into(),
        ));
    }
    let stamps = args.stamps.as_deref().map(read_stamps).transpose()?;
    let rec = args.rerun.recorder("pgo-convert")?;
    let progress = Progress::start("pgo-convert", args.quiet, args.progress);
    progress.phase(&format!("reading {}", display_name(&args.input, "<stdin>")));
    let t0 = Instant::now();
    let (graph, report) = io::read_any_path(&args.input, &options)?;
    let read_s = t0.elapsed().as_secs_f64();
    let mut graph = match graph {
        io::AnyGraph::Planar(graph) => graph,
        io::AnyGraph::Spatial(graph) => {
            return run3(args, graph, report, read_s, stamps.as_ref(), progress, rec);
        }
    };
    progress.suspend(|| crate::cli::print_warnings(&report.warnings));
    rec.graph(&graph);

    let input_summary = format!(
        "{}: {} poses{}, {} edges{}; format {} ({}), dialect {} ({})",
        display_name(&args.input, "<stdin>"),
        graph.num_poses(),
        if graph.vertices_declared || graph.num_poses() == 0 {
            ""
        } else {
            " (no vertex lines: composed along a spanning tree)"
        },
        graph.edges.len(),
        if graph.landmarks.is_empty() {
            String::new()
        } else {
            format!(
                ", {} landmarks, {} observations",
                graph.landmarks.len(),
                graph.landmarks.observations.len()
            )
        },
        report.format,
        report.format_reason,
        report.dialect,
        report.dialect_reason
    );

    if args.stats {
        progress.finish();
        let stats = GraphStats::new(&graph, &report);
        let text = if args.json {
            to_json_line(&stats)?
        } else {
            stats_text(&display_name(&args.input, "<stdin>"), &stats, &report)
        };
        write_stdout(text.as_bytes())?;
        if args.timings {
            eprintln!("timings: read_s={read_s:.6} write_s=0");
        }
        rec.finish()?;
        return Ok(ExitCode::SUCCESS);
    }

    if let Some(trajectory) = trajectory {
        if args.reindex {
            graph.reindex();
        }
        let t1 = Instant::now();
        progress.phase(&format!(
            "writing {}",
            display_name(&args.output, "<stdout>")
        ));
        io::write_atomic(&args.output, |out, name| {
            write_trajectory(&graph, trajectory, stamps.as_ref(), out, name)
        })?;
        let write_s = t1.elapsed().as_secs_f64();
        progress.finish();
        if !args.quiet {
            eprintln!(
                "pgo-convert: {input_summary} -> {}: {} trajectory of {} poses sorted by id{}",
                display_name(&args.output, "<stdout>"),
                trajectory.name(),
                graph.num_poses(),
                if graph.edges.is_empty() && graph.landmarks.is_empty() {
                    ""
                } else {
                    " (edges and landmarks left out)"
                }
            );
        }
        if args.timings {
            eprintln!("timings: read_s={read_s:.6} write_s={write_s:.6}");
        }
        rec.finish()?;
        return Ok(ExitCode::SUCCESS);
    }
    let format = args
        .to
        .and_then(Target::graph_format)
        .or_else(|| Format::from_extension(&args.output))
        .unwrap_or(report.format);
    let dialect = args.to_dialect.unwrap_or(format.default_dialect());
    if dialect.toro_order() != (format == Format::Toro) {
        return Err(Error::Invalid(format!(
            "dialect {dialect} does not fit {format} output (g2o files take g2o or g2o-cov, TORO files toro-info or toro-cov)"
        )));
    }
    let converted = graph.noise != dialect.noise();
    graph.convert_noise(dialect.noise()).map_err(|k| {
        Error::Invalid(format!(
            "edge {} -> {} has a singular noise matrix that cannot be inverted for dialect {dialect}",
            graph.ids[graph.edges[k].i], graph.ids[graph.edges[k].j]
        ))
    })?;
    let mut mapping = String::new();
    match args.landmarks {
        Some(crate::graph::LandmarkForm::G2o) => {
            let from = graph.landmarks.form;
            let offset = graph
                .landmarks_to_g2o(args.landmark_offset)
                .map_err(|e| Error::Invalid(format!("--landmarks g2o: {e}")))?;
            if from != crate::graph::LandmarkForm::G2o && !graph.landmarks.is_empty() {
                mapping = format!(
                    "; landmark ids shifted by +{offset} into the poses' id space (LANDMARK2 landmark k is vertex k + {offset}; back with --landmarks landmark2 --landmark-offset {offset})"
                );
            }
        }
        Some(crate::graph::LandmarkForm::Landmark2) => {
            let from = graph.landmarks.form;
            graph
                .landmarks_to_landmark2(args.landmark_offset)
                .map_err(|e| Error::Invalid(format!("--landmarks landmark2: {e}")))?;
            if from != crate::graph::LandmarkForm::Landmark2 && !graph.landmarks.is_empty() {
                let offset = args.landmark_offset.unwrap_or(0);
                mapping = format!(
                    "; landmark ids shifted by -{offset} into their own id space (vertex k is LANDMARK2 landmark k - {offset})"
                );
            }
        }
        None => {}
    }
    if args.reindex {
        if report.vertigo.is_some() {
            return Err(Error::Invalid(
                "--reindex renumbers the poses but not Vertigo's switch variables, whose ids share the poses' id space: convert without --reindex".into(),
            ));
        }
        graph.reindex();
    }
    let t1 = Instant::now();
    progress.phase(&format!(
        "writing {}",
        display_name(&args.output, "<stdout>")
    ));
    io::write_path_with(
        &graph,
        report.vertigo.as_ref(),
        WriteOptions { format, dialect },
        &args.output,
    )?;
    let write_s = t1.elapsed().as_secs_f64();
    progress.finish();
    if !args.quiet {
        let conversion = match (converted, dialect.noise()) {
            (false, _) => "",
            (true, NoiseKind::Information) => " (covariances inverted to information)",
            (true, NoiseKind::Covariance) => " (information inverted to covariances)",
        };
        eprintln!(
            "pgo-convert: {input_summary} -> {}: format {format}, dialect {dialect}{conversion}{mapping}",
            display_name(&args.output, "<stdout>")
        );
    }
    if args.timings {
        eprintln!("timings: read_s={read_s:.6} write_s={write_s:.6}");
    }
    rec.finish()?;
    Ok(ExitCode::SUCCESS)
}

/// The rest of [`run`] for a 3D graph: statistics, or the graph written back in its own form.
fn run3(
    args: &Args,
    mut graph: crate::graph3::Graph3,
    report: io::ReadReport,
    read_s: f64,
    stamps: Option<&std::collections::HashMap<u32, f64>>,
    progress: Progress,
    rec: crate::viz::Recorder,
) -> crate::Result<ExitCode> {
    progress.suspend(|| crate::cli::print_warnings(&report.warnings));
    rec.graph3(&graph);
    if args.landmarks.is_some() {
        return Err(Error::Invalid(
            "--landmarks: this 3D graph has no landmarks".into(),
        ));
    }
    let input = display_name(&args.input, "<stdin>");
    if args.stats {
        progress.finish();
        let stats = crate::stats::GraphStats3::new(&graph, &report);
        let text = if args.json {
            to_json_line(&stats)?
        } else {
            stats3_text(&input, &stats, &report)
        };
        write_stdout(text.as_bytes())?;
        if args.timings {
            eprintln!("timings: read_s={read_s:.6} write_s=0");
        }
        rec.finish()?;
        return Ok(ExitCode::SUCCESS);
    }
    if let Some(trajectory) = args.to.and_then(Target::trajectory_format) {
        if args.reindex {
            graph.reindex();
        }
        let t1 = Instant::now();
        progress.phase(&format!(
            "writing {}",
            display_name(&args.output, "<stdout>")
        ));
        io::write_atomic(&args.output, |out, name| {
            write_trajectory3(&graph, trajectory, stamps, out, name)
        })?;
        let write_s = t1.elapsed().as_secs_f64();
        progress.finish();
        if !args.quiet {
            eprintln!(
                "pgo-convert: {input}: {} poses, {} edges, 3D -> {}: {} trajectory of {} poses sorted by id{}",
                graph.num_poses(),
                graph.edges.len(),
                display_name(&args.output, "<stdout>"),
                trajectory.name(),
                graph.num_poses(),
                if graph.edges.is_empty() {
                    ""
                } else {
                    " (edges left out)"
                }
            );
        }
        if args.timings {
            eprintln!("timings: read_s={read_s:.6} write_s={write_s:.6}");
        }
        rec.finish()?;
        return Ok(ExitCode::SUCCESS);
    }
    let format = args
        .to
        .and_then(Target::graph_format)
        .or_else(|| Format::from_extension(&args.output))
        .unwrap_or(report.format);
    let dialect = dialect3(format, args.to_dialect, "--to-dialect")?;
    if args.reindex {
        graph.reindex();
    }
    let t1 = Instant::now();
    progress.phase(&format!(
        "writing {}",
        display_name(&args.output, "<stdout>")
    ));
    io::write3_path(&graph, format, &args.output)?;
    let write_s = t1.elapsed().as_secs_f64();
    progress.finish();
    if !args.quiet {
        eprintln!(
            "pgo-convert: {input}: {} poses, {} edges, 3D; format {} ({}), dialect {} ({}) -> {}: format {format}, dialect {dialect}",
            graph.num_poses(),
            graph.edges.len(),
            report.format,
            report.format_reason,
            report.dialect,
            report.dialect_reason,
            display_name(&args.output, "<stdout>")
        );
    }
    if args.timings {
        eprintln!("timings: read_s={read_s:.6} write_s={write_s:.6}");
    }
    rec.finish()?;
    Ok(ExitCode::SUCCESS)
}

/// The dialect a 3D graph is written in, `format`'s own (information matrices, the upper
/// triangle row by row): `requested` (given by the option `option`) must be that one. The Python
/// package's `Graph3.write` refuses what pgo-convert refuses through this too.
pub fn dialect3(
    format: Format,
    requested: Option<Dialect>,
    option: &str,
) -> crate::Result<Dialect> {
    let dialect = format.default_dialect();
    match requested {
        Some(d) if d != dialect => Err(Error::Invalid(format!(
            "{option} {d}: a 3D {format} file holds information matrices, the upper triangle row by row (dialect {dialect})"
        ))),
        _ => Ok(dialect),
    }
}

/// The human-readable statistics of a 3D graph, laid out as [`stats_text`]'s.
fn stats3_text(name: &str, s: &crate::stats::GraphStats3, report: &io::ReadReport) -> String {
    let opt = |v: Option<u32>| v.map_or("-".to_string(), |v| v.to_string());
    let fixed = if s.fixed.is_empty() {
        "none".to_string()
    } else {
        s.fixed
            .iter()
            .map(|id| id.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let rotations = match s.rotations {
        crate::graph3::Form3::G2o => "quaternions (qx qy qz qw)",
        crate::graph3::Form3::Toro => "Euler angles (roll pitch yaw)",
    };
    let rows = [
        ("file", name.to_string()),
        ("dimension", "3 (SE(3) poses)".to_string()),
        ("format", format!("{} ({})", s.format, report.format_reason)),
        (
            "dialect",
            format!("{} ({})", s.dialect, report.dialect_reason),
        ),
        ("rotations", rotations.to_string()),
        ("poses", s.poses.to_string()),
        ("edges", s.edges.to_string()),
        (
            "odometry edges",
            format!("{} (j = i + 1)", s.odometry_edges),
        ),
        ("loop closures", s.loop_closures.to_string()),
        ("backward edges", format!("{} (i > j)", s.backward_edges)),
        (
            "duplicate edges",
            format!(
                "{} (same pair as an earlier edge; {} identical in every value)",
                s.duplicate_edges, s.exact_duplicate_edges
            ),
        ),
        ("components", s.components.to_string()),
        ("isolated poses", s.isolated_poses.to_string()),
        (
            "id range",
            format!("{} .. {}", opt(s.id_min), opt(s.id_max)),
        ),
        ("id gaps", s.id_gaps.to_string()),
        ("fixed", fixed),
    ];
    let mut out = String::new();
    for (k, v) in rows {
        out.push_str(&format!("{:<17}{v}\n", format!("{k}:")));
    }
    out
}

fn display_name(path: &str, stdio: &str) -> String {
    match path {
        "-" => stdio.into(),
        p => p.into(),
    }
}

/// The human-readable statistics: one `key: value` per line.
fn stats_text(name: &str, s: &GraphStats, report: &io::ReadReport) -> String {
    let opt = |v: Option<u32>| v.map_or("-".to_string(), |v| v.to_string());
    let fixed = if s.fixed.is_empty() {
        "none".to_string()
    } else {
        s.fixed
            .iter()
            .map(|id| id.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let rows = [
        ("file", name.to_string()),
        ("format", format!("{} ({})", s.format, report.format_reason)),
        (
            "dialect",
            format!("{} ({})", s.dialect, report.dialect_reason),
        ),
        (
            "poses",
            format!(
                "{}{}",
                s.poses,
                if s.vertices_declared || s.poses == 0 {
                    ""
                } else {
                    " (no vertex lines: ids from the edges)"
                }
            ),
        ),
        ("edges", s.edges.to_string()),
        (
            "odometry edges",
            format!("{} (j = i + 1)", s.odometry_edges),
        ),
        ("loop closures", s.loop_closures.to_string()),
        ("backward edges", format!("{} (i > j)", s.backward_edges)),
        (
            "duplicate edges",
            format!(
                "{} (same pair as an earlier edge; {} identical in every value)",
                s.duplicate_edges, s.exact_duplicate_edges
            ),
        ),
        ("components", s.components.to_string()),
        ("isolated poses", s.isolated_poses.to_string()),
        (
            "id range",
            format!("{} .. {}", opt(s.id_min), opt(s.id_max)),
        ),
        ("id gaps", s.id_gaps.to_string()),
        ("fixed", fixed),
    ];
    let mut out = String::new();
    for (k, v) in rows {
        out.push_str(&format!("{:<17}{v}\n", format!("{k}:")));
    }
    if let Some(form) = s.landmark_form {
        let form = match form {
            crate::graph::LandmarkForm::G2o => "g2o: VERTEX_XY, EDGE_SE2_XY, ids shared with poses",
            crate::graph::LandmarkForm::Landmark2 => "LANDMARK2: landmark ids of their own",
        };
        for (k, v) in [
            ("landmarks", format!("{} ({form})", s.landmarks)),
            ("observations", s.observations.to_string()),
            ("seen once", format!("{} landmarks", s.landmarks_seen_once)),
            (
                "seen by no pose",
                format!("{} landmarks", s.landmarks_unseen),
            ),
        ] {
            out.push_str(&format!("{:<17}{v}\n", format!("{k}:")));
        }
    }
    out
}
