//! # pgo-io: pose graphs exactly as read
//!
//! The file layer of pgo, without any of its numerics. It owns:
//! - [`graph3`]: 3D pose graphs ([`Graph3`]: poses in SE(3), 6x6 information matrices, FIX ids),
//!   read from g2o's `VERTEX_SE3:QUAT`/`EDGE_SE3:QUAT` or TORO's `VERTEX3`/`EDGE3` lines and
//!   written back bit for bit ([`read_any_path`] returns a planar or a 3D graph);
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
pub mod graph3;
pub mod io;
pub mod stats;
pub mod vertigo;

pub use error::{Error, Location, ParseError, ParseErrorKind, Result, Warning};
pub use graph::{
    Edge, LandmarkForm, Landmarks, NoiseKind, Observation, Pose2, PoseGraph, SymMat2, SymMat3,
    VertexId,
};
pub use graph3::{Edge3, Form3, Graph3, Pose3, Rotation3, SymMat6};
pub use io::{
    AnyGraph, Dialect, Format, ReadOptions, ReadReport, WriteOptions, read, read_any,
    read_any_path, read_path, read3, write, write_path, write3, write3_path,
};
pub use stats::{GraphStats, GraphStats3};

/// The README's example, compiled and run by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
