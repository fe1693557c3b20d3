//! Flags and helpers shared by the tools that read a graph and compute on it.

use crate::cli::progress_bar::Progress;
use crate::error::Error;
use crate::graph::PoseGraph;
use crate::io::{self, Dialect, Format, ReadOptions, ReadReport};
use crate::problem::weights::Weights;
use crate::viz::{self, Recorder};
use clap::Args;

/// How to read the input graph.
#[derive(Debug, Clone, Args)]
pub struct InputArgs {
    /// Input file, or - for stdin
    #[arg(value_name = "IN")]
    pub input: String,

    #[command(flatten)]
    pub read: ReadFlags,
}

/// The reader's flags, shared by every tool that reads graph files.
#[derive(Debug, Clone, Args)]
pub struct ReadFlags {
    /// Input format [default: from the extension (.g2o, .graph), else from the tags]
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub from: Option<Format>,

    /// How to read the six noise values of each edge [default: g2o for EDGE_SE2 tags,
    /// toro-info for EDGE2/EDGE tags]
    #[arg(long, value_enum, value_name = "DIALECT")]
    pub dialect: Option<Dialect>,

    /// Treat unknown tags as errors instead of skipping them with a warning
    #[arg(long)]
    pub strict: bool,

    /// Skip TORO's EQUIV lines (vertex merges, not implemented) with a warning instead of
    /// refusing the file: the graph is then the file's without them
    #[arg(long, conflicts_with = "strict")]
    pub ignore_equiv: bool,

    /// Accept noise matrices that are not positive definite (the solvers take them only with
    /// --weights unit)
    #[arg(long)]
    pub allow_indefinite: bool,
}

impl ReadFlags {
    pub fn options(&self) -> ReadOptions {
        ReadOptions {
            format: self.from,
            dialect: self.dialect,
            strict: self.strict,
            ignore_equiv: self.ignore_equiv,
            allow_indefinite: self.allow_indefinite,
        }
    }
}

impl InputArgs {
    /// Reads the graph, printing the reader's warnings.
    pub fn read(&self) -> crate::Result<(PoseGraph, ReadReport)> {
        self.read_shown(&Progress::off())
    }

    /// [`InputArgs::read`] as a phase of `progress`.
    pub fn read_shown(&self, progress: &Progress) -> crate::Result<(PoseGraph, ReadReport)> {
        progress.phase(&format!("reading {}", display_input(&self.input)));
        let (graph, report) = io::read_path(&self.input, &self.read.options())?;
        progress.suspend(|| crate::cli::print_warnings(&report.warnings));
        Ok((graph, report))
    }
}

impl InputArgs {
    /// Reads a planar or a 3D graph ([`io::read_any_path`]), printing the reader's warnings.
    pub fn read_any_shown(&self, progress: &Progress) -> crate::Result<(io::AnyGraph, ReadReport)> {
        progress.phase(&format!("reading {}", display_input(&self.input)));
        let (graph, report) = io::read_any_path(&self.input, &self.read.options())?;
        progress.suspend(|| crate::cli::print_warnings(&report.warnings));
        Ok((graph, report))
    }
}

/// An input path as messages show it (`<stdin>` for `-`).
pub fn display_input(path: &str) -> &str {
    if path == "-" { "<stdin>" } else { path }
}

/// The `--weights` flag: isotropic weights from the information matrices by default (the
/// objective of SE-Sync and CPL-SLAM), unit weights for the paper's cost.
#[derive(Debug, Clone, Args)]
pub struct WeightArgs {
    /// Edge weights: unit (the paper's cost (5)) or isotropic (tau = 2/tr(inv(Omega_tt)),
    /// kappa = 2 Omega_thth: the SE-Sync/CPL-SLAM objective)
    #[arg(long, value_enum, default_value = "isotropic", value_name = "POLICY")]
    pub weights: Weights,
}

/// The rerun flags of every tool (`src/viz.rs`; README "Viewing in rerun"). They never change
/// the tool's other outputs.
#[derive(Debug, Clone, Args)]
#[command(next_help_heading = "Viewing in rerun")]
pub struct RerunArgs {
    /// Write a rerun recording of the run to this .rrd file (poses, edges, residuals, solver
    /// iterations, eigenvalues, certificate); open it with `rerun PATH.rrd`
    #[arg(long, value_name = "PATH.rrd")]
    pub rerun_save: Option<String>,

    /// Stream the recording to a running rerun viewer, at URL if given
    /// [default: rerun+http://127.0.0.1:9876/proxy]; an unreachable viewer is a warning
    #[arg(
        long,
        value_name = "URL",
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = viz::DEFAULT_CONNECT_URL
    )]
    pub rerun_connect: Option<String>,

    /// Start a rerun viewer (the `rerun` executable on PATH, e.g. from PyPI rerun-sdk==0.36.3)
    /// and stream the recording to it
    #[arg(long)]
    pub rerun_spawn: bool,
}

impl RerunArgs {
    /// Starts the recorder these flags ask for (one that does nothing without them).
    pub fn recorder(&self, tool: &'static str) -> crate::Result<Recorder> {
        Recorder::start(
            tool,
            &viz::Target {
                save: self.rerun_save.clone(),
                connect: self.rerun_connect.clone(),
                spawn: self.rerun_spawn,
            },
        )
    }
}

pub use crate::dual::algorithm1::{DENSE_MAX_POSES, check_dense_size};

/// The value of `--tol` (pgo-solve, pgo-certify): a relative suboptimality, finite and ≥ 0.
pub fn parse_tolerance(s: &str) -> Result<f64, String> {
    let t: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if t.is_finite() && t >= 0.0 {
        Ok(t)
    } else {
        Err(format!("--tol must be a finite number >= 0, found {s}"))
    }
}

/// The value of `--staircase-budget`: a finite number ≥ 0.
pub fn parse_budget(s: &str) -> Result<f64, String> {
    let t: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if t.is_finite() && t >= 0.0 {
        Ok(t)
    } else {
        Err(format!(
            "--staircase-budget must be a finite number >= 0, found {s}"
        ))
    }
}

/// Serializes a report as one line of JSON.
pub fn to_json_line<T: serde::Serialize>(value: &T) -> crate::Result<String> {
    let mut s = serde_json::to_string(value)
        .map_err(|e| Error::Invalid(format!("cannot encode the report: {e}")))?;
    s.push('\n');
    Ok(s)
}

/// Writes to stdout, all or nothing.
pub fn write_stdout(bytes: &[u8]) -> crate::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(bytes)
        .and_then(|_| out.flush())
        .map_err(|e| Error::io("<stdout>", e))
}

/// Formats a float for the human-readable reports: shortest round-trip form.
pub fn num(v: f64) -> String {
    // `format_f64` takes finite values only (zmij printed ∞ as 1.797693134862316e+308).
    if !v.is_finite() {
        return v.to_string();
    }
    let mut out = Vec::new();
    io::format_f64(v, &mut out);
    String::from_utf8(out).expect("ASCII")
}

#[cfg(test)]
mod tests {
    use super::num;

    /// The reports' numbers: the shortest round trip for finite values, and what they are for
    /// the others (an overflowing gradient norm was printed as f64::MAX's digits).
    #[test]
    fn a_report_number_is_the_value_it_stands_for() {
        assert_eq!(num(1.5), "1.5");
        assert_eq!(num(-0.0), "-0");
        assert_eq!(num(1e-7), "1e-7");
        assert_eq!(num(f64::INFINITY), "inf");
        assert_eq!(num(f64::NEG_INFINITY), "-inf");
        assert_eq!(num(f64::NAN), "NaN");
    }
}
