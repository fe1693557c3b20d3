//! Robust estimation: graphs with false loop closures (outliers). [`gnc`] runs graduated
//! non-convexity (Yang, Antonante, Tzoumas and Carlone, RA-L 2020) over per-edge weights, each
//! inner weighted problem solved by [`crate::solve::solve`] (from the chordal initialization, or
//! warm started by [`crate::solve::solve_from`] on request), and ends with the problem of the
//! inlier set it found solved and certified: the bound proves that estimate optimal for that
//! inlier set, not for the robust (TLS or GM) problem. [`outliers`] plants false loop closures by
//! Vertigo's models, to score it.
//!
//! May use: [`crate::solve`] and every room below it; nothing of `viz` or `cli`.

pub mod gnc;
pub mod outliers;

pub use gnc::{Loss, RobustOptions, RobustSolution, StopReason, robust_solve};
