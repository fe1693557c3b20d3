//! The paper's dual method for small graphs (Secs. 4-5): the dual SDP (31) in its reduced form and
//! its solvers ([`sdp`], [`solver`], [`ipm`], [`clarabel`]), Algorithm 1 (Sec. 5.3: [`algorithm1`]), the
//! null-space method (46) ([`nullspace`]), and the roundings of a relaxed solution to an estimate
//! ([`rounding`]).
//!
//! May use: [`crate::certify`], [`crate::problem`], [`crate::linalg`], [`crate::progress`].

pub mod algorithm1;
#[cfg(feature = "clarabel-sdp")]
pub mod clarabel;
pub mod ipm;
pub mod nullspace;
pub mod rounding;
pub mod sdp;
pub mod solver;
