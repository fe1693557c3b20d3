//! Certificates: a dual-feasible λ bounds the optimum from below (weak duality (32)), so
//! `cost − lower_bound` bounds the suboptimality of an estimate, with every floating-point error
//! of the computation that proves W̃(λ) ⪰ 0 accounted for. Dense for small graphs ([`dense`]:
//! eigenvalues with a backward-error allowance), sparse for large ones ([`sparse`]: LDLᴴ inertia
//! and Temple's inequality for a deflated rank-1 estimate, a shifted LLᴴ otherwise), and the SZEP
//! zero test that both share ([`szep`]); the equilibration and the shift ladder that the planar
//! and the SE(3) sparse certificates share ([`ladder`]).
//!
//! May use: [`crate::problem`], [`crate::linalg`].

pub mod dense;
pub mod ladder;
pub mod sparse;
pub mod szep;

pub use dense::{DualBound, dual_bound};
pub use sparse::{HiddenGap, SparseBound, SparseCertifier};
