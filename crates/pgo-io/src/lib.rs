//! # pgo-io: planar pose graphs exactly as read
//!
//! The file layer of pgo, without any of its numerics. It owns:
//! - [`graph`]: the pose graph exactly as read ([`PoseGraph`]: poses, relative-pose
//!   measurements, noise matrices and FIX ids, every value with its bits, edges in input order),
//!   with the dense index the solvers work on;
//! - [`io`]: lossless g2o and TORO readers and writers and their dialects (which order the six
//!   noise values are in, information or covariance), with `PATH:LINE:COL` errors and warnings
//!   ([`error`]);
//! - [`stats`]: the statistics of a graph file (what `pgo-convert --stats` prints);
//! - [`vertigo`]: Vertigo's switchable and max-mixture lines, kept beside the graph.
//!
//! Cargo feature `clap` (off by default): `clap::ValueEnum` on [`io::Format`] and
//! [`io::Dialect`], for command-line flags. An example is in the README.

pub mod error;
pub mod graph;
pub mod io;
pub mod stats;
pub mod vertigo;

pub use error::{Error, Location, ParseError, ParseErrorKind, Result, Warning};
pub use graph::{
    Edge, LandmarkForm, Landmarks, NoiseKind, Observation, Pose2, PoseGraph, SymMat2, SymMat3,
    VertexId,
};
pub use io::{
    Dialect, Format, ReadOptions, ReadReport, WriteOptions, read, read_path, write, write_path,
};
pub use stats::GraphStats;

/// The README's example, compiled and run by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
