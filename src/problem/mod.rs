//! The problem of the paper in the complex domain: per-edge weights from the information matrices
//! ([`weights`]), the pose graph matrix W̃ and its blocks L, S̃, Q̃, the rotation-only matrix M and
//! the cost f (eqs. (8), (14), (24), (38): [`matrix`]), the rank-p (Burer-Monteiro) form evaluated
//! edge by edge with rounding enclosures ([`rank_p`]), the gauge ([`gauge`]), and the checks that
//! double precision can evaluate all of it ([`checks`]).
//!
//! Landmarks (issue 13): a landmark l_k is one more complex position and its observation from
//! pose i one more term ν |l_k − p_i − r_i d_ik|² of f, so the landmark positions join the
//! positions of the poses as free linear variables: W̃, L and S̃ gain their rows, M = Q̃ − S̃* L⁻¹ S̃
//! (eq. (38)) keeps its form and size n x n, and the dual (31), the SZEP (Prop. 10), Algorithm 1
//! and the certificate of Theorem 1 apply as written ([`matrix::PoseGraphMatrix`]); the weights
//! put one ν per observation after the edges' (τ, κ) ([`weights::edge_weights`]).
//!
//! May use: the file model (`crate::graph`), [`crate::linalg`].

pub mod checks;
pub mod gauge;
pub mod matrix;
pub mod rank_p;
pub mod weights;
