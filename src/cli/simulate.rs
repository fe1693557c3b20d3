//! `pgo-simulate`: random planar pose graphs by the paper's simulation model (Sec. 6, eq. (47)).

use super::common::RerunArgs;
use crate::error::Error;
use crate::io::{self, Format, WriteOptions};
use crate::robust::outliers::{OutlierConfig, OutlierModel, add_outliers};
use crate::simulate::space::{SpaceConfig, World3, simulate3};
use crate::simulate::{
    LandmarkConfig, LoopModel, RotationNoise, SimulationConfig, TranslationNoise, add_landmarks,
    simulate,
};
use clap::Parser;
use std::process::ExitCode;

const EXAMPLES: &str = "\
Examples:
  pgo-simulate                                   the paper's setup: 10 poses, P_c = 0.1, sigma 0.1
  pgo-simulate -n 50 --seed 7 -o sim.g2o
  pgo-simulate --rotation-noise uniform --seed 3  uninformative rotations
  pgo-simulate --translation-noise uniform:5      translation noise uniform in [-5, 5]^2
  pgo-simulate --rotation-noise gaussian:0 --translation-noise gaussian:0   a balanced graph
  for s in $(seq 1 100); do pgo-simulate --seed $s -o run$s.g2o; done   100 Monte Carlo runs
  pgo-simulate -n 1000000 --loop-model per-pose --loop-probability 0.05 -o big.g2o
  pgo-simulate -n 100 --loop-probability 0 --landmarks 30 --landmark-range 3 -o slam.g2o
                                                 a pose-landmark world: odometry + landmarks
  pgo-simulate --world sphere -n 2500 --rotation-noise gaussian:0.05 -o sphere.g2o
                                                 an SE(3) world: 50 rings of 50 poses
  pgo-simulate --world grid -n 1000 --loop-probability 0.3 --seed 2 -o grid.g2o
  pgo-simulate --corrupt intel.g2o --outliers 100 --seed 1 -o intel-100.g2o --outlier-list intel-100.txt
  pgo-simulate --corrupt M3500.g2o --outliers 50 --outlier-model local --group 10 -o local.g2o

Size: the paper's model draws a loop closure for every pair of poses, about P_c n^2/2 of them:
-n 100000 would make 5e8 edges (about 45 GB of g2o text). Graphs of more than 10^7 expected
loop closures, or more than 10^10 pairs to draw, are refused with their size unless --force is
given; --loop-model per-pose grows linearly (about P_c n loop closures).

3D worlds (--world sphere|torus|grid): SE(3) poses written as g2o VERTEX_SE3:QUAT (the ground
truth) and EDGE_SE3:QUAT. sphere: ceil(sqrt(N)) poses per ring on rings of latitude of a sphere
of diameter L; torus: rings around the tube of a torus of outer diameter L (radii 3L/8, L/8);
grid: a cube of ceil(cbrt(N))^3 lattice points (spacing L/side points) walked row by row.
Loop closures: to the same place on the previous ring (the torus: also last ring to first) or
to lattice neighbours, each with probability P_c [default 1]. Noise: t = R_i^T (t_j - t_i) +
e_t, e_t as --translation-noise in 3 coordinates; R = R_i^T R_j Exp(w), w ~ N(0, SIGMA^2 I_3)
isotropic Gaussian in the tangent space (gaussian:SIGMA), or a rotation uniform on SO(3)
(uniform). The information matrix is the inverse covariance of the noise drawn, in g2o's
coordinates (x, y, z, qx, qy, qz): translation I/SIGMA^2 (uniform: 3/H^2 I), rotation
6 / (1 - (1 - SIGMA^2) exp(-SIGMA^2/2)) I (about 4/SIGMA^2: qv ~ w/2; uniform: 4 I); a
noiseless part gets the identity.

Outliers (--corrupt GRAPH --outliers N): Vertigo's generator (Suenderhauf and Protzel's robust
SLAM benchmark). N groups, each a pair of poses v1 < v2 (dense indices, never consecutive;
random: both uniform; local: v2 at most 20 after v1) and one measurement x, y ~ N(0, 0.3 m),
theta ~ N(0, 10 deg), appended as G edges (v1+k, v2+k), k = 0..G-1, after the graph's edges,
with the information matrix of the graph's first loop closure (first edge between ids that are
not consecutive). The output holds the graph as read, then the outliers; --outlier-list writes
one line 'LINE I J' per outlier: its line in the output file and its two ids.";

/// Generate a random planar pose graph by the simulation model of Calafiore, Carlone and Dellaert
/// (Sec. 6, eq. (47)), reproducibly.
///
/// Poses: positions uniform in a square [0, L)^2, headings uniform in (-pi, pi]. Edges: the
/// spanning path (i, i+1) plus a loop closure between every other pair with probability P_c (or,
/// with --loop-model per-pose, for large graphs: one loop closure from each pose j >= 2 to an
/// earlier pose drawn uniformly, with probability P_c).
/// Measurements: Delta_ij = R_i^T (p_j - p_i) + e_Delta, R_ij = R_i^T R_j R(e_R), angles wrapped
/// to (-pi, pi]. Every information matrix is the identity, so unit weights give the paper's cost.
/// The vertex lines hold the ground truth. The same seed and flags give the same file, byte for
/// byte; the ground truth depends only on -n, --side and --seed, the edge set also on
/// --loop-probability. An output file is replaced only once completely written. With --world
/// sphere, torus or grid: an SE(3) graph on that world, its information matrices the inverse
/// covariance of the noise drawn (see 3D worlds below).
#[derive(Debug, Parser)]
#[command(
    name = "pgo-simulate",
    version,
    after_help = super::after_help(EXAMPLES),
    allow_negative_numbers = true
)]
pub struct Args {
    /// The world: planar (the paper's model (47)), or an SE(3) world written as g2o 3D (see 3D
    /// worlds below)
    #[arg(long, value_enum, value_name = "WORLD", default_value = "planar")]
    pub world: World,

    /// Number of poses (ids 0..N-1)
    #[arg(short = 'n', long = "poses", value_name = "N", default_value = "10", value_parser = parse_poses)]
    pub n: usize,

    /// Probability P_c of a loop closure between two poses i < j with j > i + 1, each pair
    /// independently (per pose with --loop-model per-pose; in a 3D world each candidate)
    /// [default: 0.1, 1 in a 3D world]
    #[arg(long, value_name = "P", value_parser = parse_probability)]
    pub loop_probability: Option<f64>,

    /// Which loop closures are drawn (planar) [default: pairs]
    #[arg(long, value_enum, value_name = "MODEL")]
    pub loop_model: Option<LoopModel>,

    /// Generate however many loop closures the pairs model makes (see Size below)
    #[arg(long)]
    pub force: bool,

    /// Rotation noise e_R: gaussian:SIGMA (normal, standard deviation SIGMA radians) or uniform
    /// (uniform in (-pi, pi])
    #[arg(long, value_name = "SPEC", default_value = "gaussian:0.1", value_parser = parse_rotation_noise)]
    pub rotation_noise: RotationNoise,

    /// Translation noise e_Delta: gaussian:SIGMA (normal in each coordinate, standard deviation
    /// SIGMA metres) or uniform:HALFWIDTH (uniform in [-HALFWIDTH, HALFWIDTH]^2)
    #[arg(long, value_name = "SPEC", default_value = "gaussian:0.1", value_parser = parse_translation_noise)]
    pub translation_noise: TranslationNoise,

    /// Seed of the random number generator (any 64-bit unsigned integer)
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,

    /// Side L of the square the positions are drawn from, in metres
    #[arg(long, value_name = "L", default_value = "10", value_parser = parse_side)]
    pub side: f64,

    /// Landmarks M: positions uniform in the square, observed (d = R_i^T (l - p_i) + e, e the
    /// translation noise) from every pose within --landmark-range; written as VERTEX_XY (ids
    /// N, N+1, ..., the landmarks some pose sees) and EDGE_SE2_XY lines
    #[arg(long, value_name = "M", default_value_t = 0)]
    pub landmarks: usize,

    /// A pose observes the landmarks within this distance, in metres
    #[arg(long, value_name = "R", default_value = "3", value_parser = parse_side)]
    pub landmark_range: f64,

    /// Output file, or - for stdout
    #[arg(short, long, value_name = "OUT", default_value = "-")]
    pub output: String,

    /// Output format [default: from the output's extension (.g2o, .graph), else g2o]
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub to: Option<Format>,

    /// Do not print the summary line on stderr
    #[arg(short, long)]
    pub quiet: bool,

    /// Add false loop closures to this graph (- for stdin) instead of generating one (see
    /// Outliers below)
    #[arg(long, value_name = "GRAPH", requires = "outliers", conflicts_with_all = ["world", "n", "loop_probability", "loop_model", "force", "rotation_noise", "translation_noise", "side"])]
    pub corrupt: Option<String>,

    /// Number of outlier groups to add to --corrupt's graph
    #[arg(long, value_name = "N", requires = "corrupt", value_parser = parse_count)]
    pub outliers: Option<usize>,

    /// Which pose pairs outliers join: random (any two poses) or local (at most 20 ids apart)
    #[arg(
        long,
        value_enum,
        value_name = "MODEL",
        default_value = "random",
        requires = "corrupt"
    )]
    pub outlier_model: OutlierModel,

    /// Outliers per group: G consecutive pairs (v1+k, v2+k) sharing one measurement
    #[arg(long, value_name = "G", default_value = "1", value_parser = parse_group, requires = "corrupt")]
    pub group: usize,

    /// Write the list of the added outliers here: one line 'LINE I J' each
    #[arg(long, value_name = "FILE", requires = "corrupt")]
    pub outlier_list: Option<String>,

    #[command(flatten)]
    pub rerun: RerunArgs,
}

/// `--world`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum World {
    /// Planar poses by the paper's model (47)
    Planar,
    /// SE(3) poses on rings of latitude of a sphere (like sphere2500)
    Sphere,
    /// SE(3) poses on rings around a torus (like torus3D)
    Torus,
    /// SE(3) poses walking a cubic lattice (like grid3D)
    Grid,
}

fn parse_count(s: &str) -> Result<usize, String> {
    s.parse()
        .map_err(|_| format!("'{s}' is not a whole number >= 0"))
}

fn parse_group(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(g) if g >= 1 => Ok(g),
        _ => Err(format!(
            "the group size must be a whole number >= 1, found {s}"
        )),
    }
}

fn parse_poses(s: &str) -> Result<usize, String> {
    let max = crate::graph::MAX_VERTEX_ID as i128 + 1;
    let n: i128 = s
        .parse()
        .map_err(|_| format!("'{s}' is not a whole number of poses"))?;
    if n < 1 {
        return Err("the graph needs at least 1 pose".into());
    }
    if n > max {
        return Err(format!("at most {max} poses (ids must fit g2o's int)"));
    }
    usize::try_from(n).map_err(|_| format!("{n} poses do not fit this machine's address space"))
}

fn parse_probability(s: &str) -> Result<f64, String> {
    let p: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if (0.0..=1.0).contains(&p) {
        Ok(p)
    } else {
        Err(format!("a probability must be in [0, 1], found {s}"))
    }
}

fn parse_side(s: &str) -> Result<f64, String> {
    let l: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if l.is_finite() && l > 0.0 {
        Ok(l)
    } else {
        Err(format!("the side must be a finite number > 0, found {s}"))
    }
}

fn parse_rotation_noise(s: &str) -> Result<RotationNoise, String> {
    s.parse()
}

fn parse_translation_noise(s: &str) -> Result<TranslationNoise, String> {
    s.parse()
}

/// Entry point of the `pgo-simulate` binary.
pub fn main() -> ExitCode {
    let args = Args::parse();
    crate::cli::run_tool("pgo-simulate", || run(&args))
}

pub fn run(args: &Args) -> crate::Result<ExitCode> {
    if let Some(input) = &args.corrupt {
        return corrupt(args, input);
    }
    let world = match args.world {
        World::Planar => None,
        World::Sphere => Some(World3::Sphere),
        World::Torus => Some(World3::Torus),
        World::Grid => Some(World3::Grid),
    };
    if let Some(world) = world {
        return run3(args, world);
    }
    let config = SimulationConfig {
        n: args.n,
        side: args.side,
        loop_probability: args.loop_probability.unwrap_or(0.1),
        loop_model: args.loop_model.unwrap_or_default(),
        rotation_noise: args.rotation_noise,
        translation_noise: args.translation_noise,
        seed: args.seed,
    };
    config.validate()?;
    if !args.force {
        check_size(&config)?;
    }
    io::check_output(&args.output)?;
    let rec = args.rerun.recorder("pgo-simulate")?;
    if args.landmarks as u128 + args.n as u128 > crate::graph::MAX_VERTEX_ID as u128 + 1 {
        return Err(Error::Invalid(format!(
            "{} poses and {} landmarks: ids must fit g2o's int",
            args.n, args.landmarks
        )));
    }
    let mut sim = simulate(&config);
    if args.landmarks > 0 {
        let landmarks = LandmarkConfig {
            count: args.landmarks,
            range: args.landmark_range,
        };
        add_landmarks(&mut sim, &config, &landmarks);
    }
    rec.graph(&sim.graph);
    let format = args
        .to
        .or_else(|| Format::from_extension(&args.output))
        .unwrap_or(Format::G2o);
    let dialect = format.default_dialect();
    io::write_path(&sim.graph, WriteOptions { format, dialect }, &args.output)?;
    if !args.quiet {
        let odometry = config.n - 1;
        let loops = sim.graph.edges.len() - odometry;
        eprintln!(
            "pgo-simulate: {} pose{}, {} edge{} ({odometry} odometry, {loops} loop closure{}){}; seed {}, loop probability {}{}, rotation noise {}, translation noise {}, side {} -> {}: format {format}",
            config.n,
            if config.n == 1 { "" } else { "s" },
            sim.graph.edges.len(),
            if sim.graph.edges.len() == 1 { "" } else { "s" },
            if loops == 1 { "" } else { "s" },
            if args.landmarks == 0 {
                String::new()
            } else {
                format!(
                    ", {} landmarks seen of {} ({} observations within {} m)",
                    sim.graph.landmarks.len(),
                    args.landmarks,
                    sim.graph.landmarks.observations.len(),
                    args.landmark_range
                )
            },
            config.seed,
            config.loop_probability,
            match config.loop_model {
                LoopModel::Pairs => String::new(),
                model => format!(" ({})", model.name()),
            },
            config.rotation_noise,
            config.translation_noise,
            config.side,
            if args.output == "-" {
                "<stdout>"
            } else {
                &args.output
            },
        );
    }
    rec.finish()?;
    Ok(ExitCode::SUCCESS)
}

/// `--world sphere|torus|grid`: [`simulate3`], written as g2o 3D.
fn run3(args: &Args, world: World3) -> crate::Result<ExitCode> {
    let refused = [
        (args.loop_model.is_some(), "--loop-model"),
        (args.landmarks > 0, "--landmarks"),
        (args.to == Some(Format::Toro), "--to toro"),
    ];
    if let Some((_, what)) = refused.iter().find(|(given, _)| *given) {
        return Err(Error::Invalid(format!(
            "{what}: not available with --world {} (a 3D world is written as g2o VERTEX_SE3:QUAT/EDGE_SE3:QUAT; its loop closures are the world's candidates, each with --loop-probability)",
            world.name()
        )));
    }
    if args.to.is_none() && Format::from_extension(&args.output) == Some(Format::Toro) {
        return Err(Error::Invalid(format!(
            "{}: a 3D world is written as g2o (quaternions), not TORO; name the output .g2o",
            args.output
        )));
    }
    let config = SpaceConfig {
        world,
        n: args.n,
        side: args.side,
        loop_probability: args.loop_probability.unwrap_or(1.0),
        rotation_noise: args.rotation_noise,
        translation_noise: args.translation_noise,
        seed: args.seed,
    };
    config.validate()?;
    io::check_output(&args.output)?;
    let rec = args.rerun.recorder("pgo-simulate")?;
    let sim = simulate3(&config);
    rec.graph3(&sim.graph);
    io::write3_path(&sim.graph, Format::G2o, &args.output)?;
    if !args.quiet {
        let odometry = config.n - 1;
        let loops = sim.graph.edges.len() - odometry;
        eprintln!(
            "pgo-simulate: {} world, {} pose{}, {} edge{} ({odometry} odometry, {loops} loop closure{}); seed {}, loop probability {}, rotation noise {}, translation noise {}, side {} -> {}: format g2o (3D)",
            world.name(),
            config.n,
            if config.n == 1 { "" } else { "s" },
            sim.graph.edges.len(),
            if sim.graph.edges.len() == 1 { "" } else { "s" },
            if loops == 1 { "" } else { "s" },
            config.seed,
            config.loop_probability,
            config.rotation_noise,
            config.translation_noise,
            config.side,
            if args.output == "-" {
                "<stdout>"
            } else {
                &args.output
            },
        );
    }
    rec.finish()?;
    Ok(ExitCode::SUCCESS)
}

/// Expected loop closures beyond which a graph is refused without --force (about 0.9 GB of g2o
/// text and 1 GB of memory).
pub const MAX_EXPECTED_LOOP_CLOSURES: f64 = 1e7;
/// Pairs beyond which the pairs model's draws are refused without --force (one random number
/// each: minutes).
pub const MAX_LOOP_DRAWS: f64 = 1e10;

/// Refuses a graph of the pairs model whose loop closures would not fit a sensible run, saying
/// how large it would be.
fn check_size(config: &SimulationConfig) -> crate::Result<()> {
    if config.loop_model != LoopModel::Pairs {
        // Linear in n: as large as the user asked for.
        return Ok(());
    }
    let expected = config.expected_loop_closures();
    let draws = config.loop_draws();
    if expected <= MAX_EXPECTED_LOOP_CLOSURES && draws <= MAX_LOOP_DRAWS {
        return Ok(());
    }
    // About 90 bytes of g2o text per edge line, 104 bytes of memory per edge (the edge and its
    // pair).
    let gb = |bytes_per_edge: f64| expected * bytes_per_edge / 1e9;
    let size = if expected > MAX_EXPECTED_LOOP_CLOSURES {
        format!(
            "makes about {expected:.3e} loop closures (P_c (n-1)(n-2)/2 by pairs; about {:.0} GB of g2o text and {:.0} GB of memory)",
            gb(90.0),
            gb(104.0)
        )
    } else {
        format!(
            "draws a random number for each of the {draws:.3e} pairs of poses (for {expected:.3e} loop closures)"
        )
    };
    Err(Error::Invalid(format!(
        "-n {} with --loop-probability {} {size}: use --loop-model per-pose (about P_c n loop closures, linear in n) or a smaller --loop-probability, or pass --force",
        config.n, config.loop_probability
    )))
}

/// `--corrupt`: the graph as read with Vertigo's outliers appended.
fn corrupt(args: &Args, input: &str) -> crate::Result<ExitCode> {
    io::check_output(&args.output)?;
    if let Some(list) = &args.outlier_list {
        io::check_output(list)?;
    }
    let (mut graph, mut report) = io::read_path(input, &Default::default())?;
    crate::cli::print_warnings(&report.warnings);
    let config = OutlierConfig {
        count: args.outliers.unwrap_or(0),
        model: args.outlier_model,
        group: args.group,
        noise: None,
        seed: args.seed,
    };
    let added = add_outliers(&mut graph, &config)?;
    let format = args
        .to
        .or_else(|| Format::from_extension(&args.output))
        .unwrap_or(report.format);
    // Information matrices in the format's own order (a covariance file is inverted).
    graph
        .convert_noise(crate::graph::NoiseKind::Information)
        .map_err(|k| Error::Invalid(format!("edge {k}: its covariance matrix is singular")))?;
    let dialect = format.default_dialect();
    // Plain EDGE_SE2 outliers, as Vertigo's generator writes them without -s or -m.
    if let Some(v) = &mut report.vertigo {
        v.kinds
            .resize(graph.edges.len(), crate::vertigo::EdgeKind::Plain);
    }
    io::write_path_with(
        &graph,
        report.vertigo.as_ref(),
        WriteOptions { format, dialect },
        &args.output,
    )?;
    // The writer puts one vertex line per pose first, then the switch variables, then the edges
    // in order.
    let first_edge_line =
        graph.num_poses() + report.vertigo.as_ref().map_or(0, |v| v.switches.len()) + 1;
    if let Some(list) = &args.outlier_list {
        let mut text = String::from("# line i j: the outliers added, lines of the output file\n");
        for &k in &added {
            let e = &graph.edges[k];
            text += &format!(
                "{} {} {}\n",
                first_edge_line + k,
                graph.ids[e.i],
                graph.ids[e.j]
            );
        }
        write_text(list, &text)?;
    }
    if !args.quiet {
        eprintln!(
            "pgo-simulate: {}: {} pose{}, {} edge{}; added {} outlier{} ({} group{} of {}, model {}, seed {}) after them -> {}: format {format}",
            crate::cli::common::display_input(input),
            graph.num_poses(),
            if graph.num_poses() == 1 { "" } else { "s" },
            graph.edges.len() - added.len(),
            if graph.edges.len() - added.len() == 1 {
                ""
            } else {
                "s"
            },
            added.len(),
            if added.len() == 1 { "" } else { "s" },
            config.count,
            if config.count == 1 { "" } else { "s" },
            config.group,
            config.model.name(),
            config.seed,
            if args.output == "-" {
                "<stdout>"
            } else {
                &args.output
            },
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Writes `text` to `path` (stdout for `-`).
fn write_text(path: &str, text: &str) -> crate::Result<()> {
    if path == "-" {
        return crate::cli::common::write_stdout(text.as_bytes());
    }
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}
