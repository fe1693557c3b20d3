//! The problem of the paper in the complex domain: per-edge weights from the information matrices
//! ([`weights`]), the pose graph matrix W̃ and its blocks L, S̃, Q̃, the rotation-only matrix M and
//! the cost f (eqs. (8), (14), (24), (38): [`matrix`]), the rank-p (Burer-Monteiro) form evaluated
//! edge by edge with rounding enclosures ([`rank_p`]), the gauge ([`gauge`]), and the checks that
//! double precision can evaluate all of it ([`checks`]).
//!
//! May use: the file model (`crate::graph`), [`crate::linalg`].

pub mod checks;
pub mod gauge;
pub mod matrix;
pub mod rank_p;
pub mod weights;
