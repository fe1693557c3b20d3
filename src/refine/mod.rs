//! Local refinement of an estimate: Levenberg-Marquardt under the file's full information
//! matrices, g2o's chi2 ([`levenberg_marquardt`], what `pgo-solve --refine` runs), and
//! Gauss-Newton on the paper's isotropic cost f (eq. (8)) as the paper's Fig. 7 polishes its
//! roundings ([`gauss_newton`]); the marginal covariances of the poses at an estimate
//! ([`marginals`], what `pgo-solve --refine --marginals` writes); Levenberg-Marquardt on SE(3)ⁿ
//! under the full 6x6 information matrices of 3D graphs ([`se3`], `pgo-solve --refine` on a 3D
//! graph), sharing the normal equations and the damping schedule with the planar one
//! ([`damped`]). None proves anything: the certificate is of the estimate before refinement.
//!
//! May use: [`crate::problem`], [`crate::linalg`], [`crate::simulate`] (angle wrapping), the file
//! layer ([`crate::graph3`]).

pub mod damped;
pub mod gauss_newton;
pub mod levenberg_marquardt;
pub mod marginals;
pub mod se3;

pub use levenberg_marquardt::*;
pub use marginals::{MarginalsError, marginals};
pub use se3::{Refinement3, chi2_3, refine3};
