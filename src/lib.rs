//! # pgo: certifiably optimal planar pose graph optimization
//!
//! A pose graph has poses x_i = (p_i, r_i) with position p_i ∈ ℂ and rotation r_i ∈ ℂ, |r_i| = 1,
//! and edges (i, j) carrying a relative-pose measurement (Δ_ij ∈ ℂ, R_ij = e^{iθ_ij}): the pose of
//! j seen from i. Following Calafiore, Carlone and Dellaert, "Pose Graph Optimization in the
//! Complex Domain" (eq. (8), with per-edge weights), pgo minimizes
//!
//! ```text
//! f(p, r) = Σ_(i,j)  τ_ij |p_j - p_i - r_i Δ_ij|² + κ_ij |r_j - r_i R_ij|²
//! ```
//!
//! and certifies the result through the Lagrangian dual (31): a feasible λ whose penalized pose
//! graph matrix W(λ) is positive semidefinite bounds f from below, so `cost - lower_bound` is a
//! proven bound on the suboptimality of the estimate.
//!
//! This crate is the library behind the command-line tools:
//! - [`io`]: lossless g2o and TORO readers and writers, dialects, precise `PATH:LINE:COL` errors;
//! - [`graph`]: the data model, kept exactly as read, with a dense index for the numerics;
//! - [`stats`]: what `pgo-convert --stats` reports (these three are the file layer, the crate
//!   `pgo-io` in `crates/pgo-io`, re-exported here);
//! - [`cli`]: the tools' flags and entry points (the binaries in `src/bin/` only call them);
//! - [`viz`]: what the tools' `--rerun-*` flags record for the rerun viewer (cargo feature
//!   `rerun`, on by default), with solvers' iterations reported through [`progress`].

pub mod algorithm1;
pub mod certify;
pub mod cli;
pub mod error;
pub mod factor;
pub mod gauss_newton;
pub mod init;
pub mod manifold;
pub mod matrix;
pub mod nullspace;
pub mod progress;
pub mod refine;
pub mod rounding;
pub mod sdp;
pub mod simulate;
pub mod spectrum;
pub mod staircase;
pub mod subspace;
pub mod viz;
pub mod weights;

/// The file layer (crate `pgo-io`): the pose graph as read, the g2o/TORO readers and writers,
/// statistics.
pub use pgo_io::{graph, io, stats};

pub use error::{Error, Result};
pub use graph::{Edge, NoiseKind, Pose2, PoseGraph, SymMat3, VertexId};
