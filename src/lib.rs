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
//! One call solves a graph and says what it proved:
//!
//! ```
//! let (graph, _) = pgo::io::read_path("datasets/MIT.g2o", &Default::default())?;
//! let solution = pgo::solve(&graph, &pgo::SolveOptions::default())?;
//! assert!(solution.certified);
//! println!("{} <= f* <= {}", solution.lower_bound, solution.cost);
//! # Ok::<(), pgo::Error>(())
//! ```
//!
//! The library behind the command-line tools, in layers; each imports only the layers below it
//! (ARCHITECTURE.md):
//!
//! - [`robust`] (top): graduated non-convexity over [`solve()`] for graphs with false loop
//!   closures;
//! - [`solve`]: the whole jobs as one call each: [`solve()`] a graph to a certified optimum
//!   ([`solve_from()`] warm started from an estimate), [`certify_estimate`] any estimate; [`spectrum::spectrum`] the graph's spectra;
//! - [`spectrum`]: eigenvalues of W̃, W̃(λ*) and M, dense or sparse, and the SZEP;
//! - [`refine`]: local refinement (Levenberg-Marquardt under the full information, g2o's chi2;
//!   Gauss-Newton on f);
//! - [`dual`]: the paper's dual method for small graphs: the dual SDP (31) and its solvers,
//!   Algorithm 1, the null-space method (46), the roundings;
//! - [`staircase`]: the scalable solver: chordal initialization, Riemannian Newton, the
//!   Riemannian staircase;
//! - [`certify`]: proofs that λ is dual feasible (dense and deflated sparse), the SZEP zero test;
//! - [`problem`]: weights, the pose graph matrix W̃ and M, the cost, the rank-p form, the gauge;
//! - [`linalg`]: sparse factorizations, the subspace eigensolver, dense eigendecompositions,
//!   rounding-error constants, the seeded generator;
//! - [`simulate`]: random graphs by the paper's model (47);
//! - [`io`], [`graph`], [`stats`] (the `pgo-io` crate, re-exported): the file model exactly as
//!   read, the g2o and TORO readers and writers with their dialects, statistics;
//! - beside them: [`progress`] (solvers report iterations to whoever watches), [`viz`] (what the
//!   `--rerun-*` flags record, cargo feature `rerun`), [`cli`] (the tools' flags, reports and
//!   entry points; the binaries in `src/bin/` only call them).

pub mod certify;
pub mod cli;
pub mod dual;
pub mod error;
pub mod eval;
pub mod linalg;
pub mod problem;
pub mod progress;
pub mod refine;
pub mod robust;
pub mod se3;
pub mod simulate;
pub mod solve;
pub mod spectrum;
pub mod staircase;
pub mod viz;

/// The file layer (crate `pgo-io`): the pose graph as read, the g2o/TORO readers and writers,
/// statistics.
pub use pgo_io::{graph, graph3, io, stats, vertigo};

pub use error::{Error, Result};
pub use graph::{Edge, NoiseKind, Pose2, PoseGraph, SymMat3, VertexId};
pub use solve::{Solution, SolveOptions, certify_estimate, solve, solve_from};
