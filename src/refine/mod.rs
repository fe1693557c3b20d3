//! Local refinement of an estimate: Levenberg-Marquardt under the file's full information
//! matrices, g2o's chi2 ([`levenberg_marquardt`], what `pgo-solve --refine` runs), and
//! Gauss-Newton on the paper's isotropic cost f (eq. (8)) as the paper's Fig. 7 polishes its
//! roundings ([`gauss_newton`]); the marginal covariances of the poses at an estimate
//! ([`marginals`], what `pgo-solve --refine --marginals` writes). None proves anything: the
//! certificate is of the estimate before refinement.
//!
//! May use: [`crate::problem`], [`crate::linalg`], [`crate::simulate`] (angle wrapping).

pub mod gauss_newton;
pub mod levenberg_marquardt;
pub mod marginals;

pub use levenberg_marquardt::*;
pub use marginals::{MarginalsError, marginals};
