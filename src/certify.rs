//! Certificates: a dual-feasible λ bounds the optimum from below (weak duality (32)), so
//! `cost − lower_bound` bounds the suboptimality of any estimate. What is printed must be a
//! bound, so the floating-point errors of the eigenvalue computation are accounted for.
//!
//! For a candidate λ (e.g. the SDP's λ*), the smallest eigenvalue μ of W̃(λ) is computed by a
//! backward-stable Hermitian eigensolver: it is exact for W̃(λ) + E with ‖E‖₂ ≤ c·d·u·‖W̃(λ)‖_F
//! (d the dimension, u the unit roundoff; we take c = 4). So W̃(λ) ⪰ −β I with
//! β = max(0, ‖E‖ − μ). A shift of the whole matrix is not a dual move (λ only enters the
//! rotation block), so it is turned into one through the Schur complement of L (eq. (38)):
//! from W̃(λ) + βI ⪰ 0,
//!
//! ```text
//! M − diag(λ) + βI − S̃*(L + βI)⁻¹S̃ ⪰ 0   and   S̃*(L⁻¹ − (L + βI)⁻¹)S̃ ≼ β ‖S̃‖² / λ_min(L)² I,
//! ```
//!
//! so M − diag(λ − t·1) ⪰ 0 for t = β (1 + ‖S̃‖²_F / λ_min(L)²), i.e. λ − t·1 is dual feasible
//! (W̃(λ − t1) ⪰ 0) and `lower_bound = Σλ − n·t` holds. λ_min(L) is itself taken
//! conservatively (its computed value minus its own error allowance). When μ ≥ ‖E‖, t = 0.
//!
//! That t is often pessimistic (‖S̃‖²/λ_min(L)² is large for long chains), so smaller shifts
//! s are tried directly on the equilibrated matrix D W̃(λ − s1) D (D = diag(W̃_kk^(−1/2)), PSD
//! exactly when W̃(λ − s1) is): if its computed smallest eigenvalue is at least its own rounding
//! allowance, W̃(λ − s1) ⪰ 0 outright and the bound Σλ − n·s holds. The better of the two proven
//! bounds is reported.

use crate::factor::{Assembly, SparseFactor};
use crate::matrix::PoseGraphMatrix;
use crate::spectrum::{hermitian_eigen, hermitian_eigenvalues};
use faer::{Mat, c64};

/// A proven lower bound on f* from a candidate λ.
#[derive(Debug, Clone)]
pub struct DualBound {
    /// Σλ − n·t: a lower bound on the optimal cost f*.
    pub lower_bound: f64,
    /// The shift t applied to every λ_i to make it provably dual feasible.
    pub shift: f64,
    /// Eigenvalues of W̃(λ), ascending.
    pub eigenvalues: Vec<f64>,
    /// Their eigenvectors (columns), in the same order.
    pub eigenvectors: Mat<c64>,
}

/// The allowance c·d·u·‖A‖_F for the eigenvalues of a d x d Hermitian A.
fn eigen_error(a: &Mat<c64>) -> f64 {
    let fro: f64 = (0..a.nrows())
        .flat_map(|r| (0..a.ncols()).map(move |c| (r, c)))
        .map(|(r, c)| a[(r, c)].norm_sqr())
        .sum::<f64>()
        .sqrt();
    4.0 * a.nrows() as f64 * f64::EPSILON * fro
}

/// The bound proven by λ for the graph of `matrix` (dense computation, for small graphs).
/// `None` if the graph is disconnected (L singular).
pub fn dual_bound(matrix: &PoseGraphMatrix, lambda: &[f64]) -> Option<DualBound> {
    let n = matrix.n;
    let penalized = matrix.penalized_dense(lambda);
    let (eigenvalues, eigenvectors) = hermitian_eigen(&penalized);
    let beta = (eigen_error(&penalized) - eigenvalues[0]).max(0.0);
    let schur_shift = if beta == 0.0 || n == 1 {
        beta
    } else {
        let (l, s, _) = matrix.blocks();
        let lc = Mat::from_fn(l.nrows(), l.ncols(), |a, b| c64::new(l[(a, b)], 0.0));
        let l_min = hermitian_eigenvalues(&lc)[0] - eigen_error(&lc);
        if l_min <= 0.0 {
            return None;
        }
        let s_fro2: f64 = (0..s.nrows())
            .flat_map(|r| (0..s.ncols()).map(move |c| (r, c)))
            .map(|(r, c)| s[(r, c)].norm_sqr())
            .sum();
        beta * (1.0 + s_fro2 / (l_min * l_min))
    };
    // Direct shifts, cheaper than t when they work. They are tested on the equilibrated matrix
    // D W̃(λ − s1) D, D = diag(W̃_kk^(-1/2)), which is PSD exactly when W̃(λ − s1) is: its
    // rounding allowance is relative to entries of order one, so the null vectors of graphs
    // whose positions dwarf their rotations (metres against unit complex numbers) need no
    // large shift.
    let mut shift = schur_shift;
    if beta > 0.0 {
        let w = matrix.dense();
        let scale: Vec<f64> = (0..w.nrows())
            .map(|k| 1.0 / w[(k, k)].re.max(f64::MIN_POSITIVE).sqrt())
            .collect();
        let equilibrated = |s: f64| {
            let moved: Vec<f64> = lambda.iter().map(|l| l - s).collect();
            let a = matrix.penalized_dense(&moved);
            Mat::from_fn(a.nrows(), a.ncols(), |r, c| {
                a[(r, c)] * (scale[r] * scale[c])
            })
        };
        // A shift so large that the equilibrated matrix overflows proves nothing (and the
        // eigensolver would not converge on it).
        let proves = |s: f64| {
            let a = equilibrated(s);
            let error = eigen_error(&a);
            error.is_finite() && hermitian_eigenvalues(&a)[0] >= error
        };
        // The smallest diagonal scale of the rotation block converts an allowance on the
        // equilibrated matrix into a shift of λ.
        let r_min = scale[n - 1..].iter().fold(f64::INFINITY, |m, &v| m.min(v));
        let base = eigen_error(&equilibrated(0.0)) / (r_min * r_min);
        if proves(0.0) {
            shift = 0.0;
        } else {
            for k in 0..=14 {
                let s = base * 10f64.powi(k);
                if s >= shift {
                    break;
                }
                if proves(s) {
                    shift = s;
                    break;
                }
            }
        }
    }
    let lower_bound = lambda.iter().sum::<f64>() - n as f64 * shift;
    Some(DualBound {
        lower_bound,
        shift,
        eigenvalues,
        eigenvectors,
    })
}

/// The sparse certificate of the scalable solver (DESIGN.md §3.2): for multipliers λ (from the
/// first-order conditions at an estimate), a successful LLᴴ factorization of
/// W̃(λ) + η·blkdiag(0, I) proves λ − η1 dual feasible (eq. (31)), so
/// `lower_bound = Σλ − n·η ≤ d* ≤ f*` (weak duality (32)).
///
/// Rounding: the factored matrix is B = D(W̃(λ) + ηP)D − αI, D = diag(2^{−e_k}) a power-of-two
/// equilibration (exact; B's diagonal lies in [1, 4)). A floating-point LLᴴ that succeeds is the
/// exact factor of B + ΔB with ‖ΔB‖₂ of the order of dim·u·‖B‖₂ (Higham, Accuracy and Stability of
/// Numerical Algorithms, §10.1: the backward error of Cholesky; u the unit roundoff). pgo takes
/// α = dim·u·‖B‖_∞ (‖B‖₂ ≤ ‖B‖_∞ for Hermitian B, summed exactly) plus the rounding of B's own diagonal, so
/// success proves D(W̃(λ) + ηP)D ⪰ αI − ΔB ⪰ 0 under that backward-error model, i.e.
/// W̃(λ) + ηP ⪰ 0. (The worst-case componentwise bound, γ_k times the fill, would be ~100x
/// larger and the bound it gives too loose to certify at 1e-6; an a-posteriori residual in
/// double-double would make the proof unconditional.)
///
/// η is searched upward by factors of 2 from 1.25·η_res ([`SparseCertifier::resolution`]), the
/// smallest value at which the estimate's own direction x (W̃(λ)x ≈ 0, x*(ηP)x = ηn) clears α in
/// equilibrated coordinates. So η is set by the problem's scale (the diagonal of W̃ and the
/// spread of the estimate) and never falls below the backward error.
pub struct SparseCertifier {
    assembly: Assembly<c64>,
    factor: SparseFactor<c64>,
    /// Position of each diagonal entry of W̃ in the upper-triangle entry list.
    diagonal: Vec<usize>,
    entries: Vec<(usize, usize, c64)>,
    values: Vec<c64>,
    /// Number of factorizations attempted so far.
    pub factorizations: usize,
}

/// The outcome of [`SparseCertifier::certify`].
#[derive(Debug, Clone, Copy)]
pub struct SparseBound {
    /// η with W̃(λ) + η·blkdiag(0, I) ⪰ 0 proven.
    pub eta: f64,
    /// Σλ − n·η, less the rounding of the sum: a lower bound on f*.
    pub lower_bound: f64,
    /// The backward-error allowance α used (equilibrated units).
    pub alpha: f64,
}

impl SparseCertifier {
    /// Analyzes the pattern of W̃ (upper triangle entries, diagonal included, as in
    /// [`crate::manifold::Problem::upper`]) once, rows in a fill-reducing `order`; every later certificate reuses it.
    pub fn new(dim: usize, upper: &[(usize, usize, c64)], order: &[usize]) -> Self {
        let pattern: Vec<(usize, usize)> = upper.iter().map(|&(r, c, _)| (r, c)).collect();
        let assembly = Assembly::<c64>::new(dim, &pattern);
        let factor = SparseFactor::analyze_ordered(assembly.matrix.symbolic(), order);
        let mut diagonal = vec![usize::MAX; dim];
        for (k, &(r, c, _)) in upper.iter().enumerate() {
            if r == c {
                diagonal[r] = k;
            }
        }
        SparseCertifier {
            assembly,
            factor,
            diagonal,
            entries: upper.to_vec(),
            values: Vec::with_capacity(upper.len()),
            factorizations: 0,
        }
    }

    /// The resolution of the certificate at an estimate: the η below which the estimate's own
    /// direction x (W̃(λ)x ≈ 0, x*(ηP)x = η‖Y‖²) cannot clear the allowance α in equilibrated
    /// coordinates, η_res = α·Σ_k ‖x_k‖²/D_k² / n (`x` row-major with `p` entries per row).
    pub fn resolution(&self, lambda: &[f64], x: &[c64], p: usize) -> f64 {
        let Some((a, scale)) = self.scaling(lambda, 0.0, true) else {
            return f64::INFINITY;
        };
        let alpha = self.alpha(&a, &scale);
        let weight: f64 = scale
            .iter()
            .enumerate()
            .map(|(k, d)| {
                x[k * p..(k + 1) * p]
                    .iter()
                    .map(|z| z.norm_sqr())
                    .sum::<f64>()
                    / (d * d)
            })
            .sum();
        let max_w = self
            .diagonal
            .iter()
            .fold(0.0f64, |m, &k| m.max(self.entries[k].2.re));
        (alpha * weight / lambda.len() as f64)
            .max(1e-15 * max_w)
            .max(f64::MIN_POSITIVE)
    }

    /// Tries to prove W̃(λ) + ηP ⪰ 0 for η = 1.25·η_res·2^j ≤ `eta_max` ([`Self::resolution`]);
    /// returns the first η proven (within a factor 2 of the smallest provable).
    pub fn certify(
        &mut self,
        lambda: &[f64],
        x: &[c64],
        p: usize,
        eta_max: f64,
    ) -> Option<SparseBound> {
        let n = lambda.len();
        let mut eta = 1.25 * self.resolution(lambda, x, p);
        let sum: f64 = lambda.iter().sum();
        let sum_error = 2.0 * n as f64 * f64::EPSILON * lambda.iter().map(|l| l.abs()).sum::<f64>();
        // At most 80 doublings (a factor 1e24 above the resolution): beyond, no useful bound.
        let mut attempts = 0;
        while eta <= eta_max && eta.is_finite() && attempts < 80 {
            attempts += 1;
            if let Some(alpha) = self.try_eta(lambda, eta) {
                return Some(SparseBound {
                    eta,
                    lower_bound: sum - n as f64 * eta - sum_error,
                    alpha,
                });
            }
            eta *= 2.0;
        }
        None
    }

    /// The resolution of eigenvalues of W̃(λ) in its own units: the allowance α₀ of the
    /// equilibrated matrix times the largest diagonal entry (Weyl's inequality after undoing D).
    pub fn eigenvalue_resolution(&self, lambda: &[f64]) -> f64 {
        match self.scaling(lambda, 0.0, true) {
            Some((a, scale)) => self.alpha(&a, &scale) * a.iter().fold(0.0f64, |m, &v| m.max(v)),
            None => f64::INFINITY,
        }
    }

    /// The diagonal a_k of W̃(λ) + ηP (absolute values when `absolute`, for estimates) and the
    /// power-of-two scaling D_k = 2^{−⌊log₂(a_k)/2⌋} that puts D_k² a_k in [1, 4). `None` if a
    /// diagonal entry is not positive (then W̃(λ) + ηP is not PSD).
    fn scaling(&self, lambda: &[f64], eta: f64, absolute: bool) -> Option<(Vec<f64>, Vec<f64>)> {
        let dim = self.diagonal.len();
        let rot0 = dim - lambda.len();
        let mut a = vec![0.0; dim];
        let mut scale = vec![0.0; dim];
        for k in 0..dim {
            let w = self.entries[self.diagonal[k]].2.re;
            let v = if k >= rot0 {
                w - lambda[k - rot0] + eta
            } else {
                w
            };
            a[k] = if absolute {
                v.abs().max(f64::MIN_POSITIVE)
            } else {
                v
            };
            if !(a[k] > 0.0 && a[k].is_finite()) {
                return None;
            }
            let e = (a[k].log2() / 2.0).floor();
            scale[k] = 2f64.powi(-(e as i32));
        }
        Some((a, scale))
    }

    /// α = dim·u·‖B‖_∞ for the equilibrated B = D(W̃(λ) + ηP)D (exactly summed row by row;
    /// ‖B‖₂ ≤ ‖B‖_∞ for Hermitian B): the backward-error model of the factorization.
    fn alpha(&self, a: &[f64], scale: &[f64]) -> f64 {
        let dim = self.diagonal.len();
        let mut rows: Vec<f64> = (0..dim).map(|k| a[k] * scale[k] * scale[k]).collect();
        for &(r, c, v) in &self.entries {
            if r != c {
                let e = v.norm() * scale[r] * scale[c];
                rows[r] += e;
                rows[c] += e;
            }
        }
        let norm = rows.iter().fold(0.0f64, |m, &v| m.max(v));
        dim as f64 * (f64::EPSILON / 2.0) * norm
    }

    /// One attempt: B = D(W̃(λ) + ηP)D − αI, LLᴴ. Returns α on success.
    fn try_eta(&mut self, lambda: &[f64], eta: f64) -> Option<f64> {
        let dim = self.diagonal.len();
        let rot0 = dim - lambda.len();
        let (a, scale) = self.scaling(lambda, eta, false)?;
        let base = self.alpha(&a, &scale);
        let mut alpha = base;
        // Plus the rounding of each a_kk itself (two additions), in equilibrated units.
        for k in rot0..dim {
            let w = self.entries[self.diagonal[k]].2.re;
            let magnitude = w + lambda[k - rot0].abs() + eta;
            alpha = alpha.max(base + 4.0 * f64::EPSILON * magnitude * scale[k] * scale[k]);
        }
        self.values.clear();
        for &(r, c, v) in &self.entries {
            let s = scale[r] * scale[c];
            self.values.push(if r == c {
                c64::new(a[r] * s - alpha, 0.0)
            } else {
                v * s
            });
        }
        self.assembly.fill(&self.values);
        self.factorizations += 1;
        self.factor
            .llt(self.assembly.matrix.as_ref())
            .ok()
            .map(|_| alpha)
    }

    /// The number of eigenvalues of W̃(λ) below `threshold` (Sylvester's law of inertia: the
    /// negative pivots of an LDLᴴ of W̃(λ) − threshold·I). `None` on a zero pivot.
    pub fn count_below(&mut self, lambda: &[f64], threshold: f64) -> Option<usize> {
        self.fill_shifted(lambda, threshold);
        self.factor.ldlt(self.assembly.matrix.as_ref()).ok()?;
        Some(self.factor.inertia_below(0.0))
    }

    /// W̃(λ) (upper triangle), e.g. for a negative-curvature direction.
    pub fn penalized_matrix(
        &mut self,
        lambda: &[f64],
    ) -> faer::sparse::SparseColMatRef<'_, usize, c64> {
        self.fill_shifted(lambda, 0.0);
        self.assembly.matrix.as_ref()
    }

    fn fill_shifted(&mut self, lambda: &[f64], threshold: f64) {
        let dim = self.diagonal.len();
        let rot0 = dim - lambda.len();
        self.values.clear();
        for &(r, c, v) in &self.entries {
            self.values.push(if r == c {
                let l = if r >= rot0 { lambda[r - rot0] } else { 0.0 };
                c64::new(v.re - l - threshold, 0.0)
            } else {
                v
            });
        }
        self.assembly.fill(&self.values);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, NoiseKind, Pose2, PoseGraph, SymMat3};
    use crate::matrix::cost;
    use crate::weights::{Weights, edge_weights};

    fn cycle(noise: f64) -> PoseGraph {
        let n = 6;
        let step = Pose2::new(1.0, 0.0, std::f64::consts::TAU / n as f64);
        let edges = (0..n)
            .map(|k| {
                let mut m = step;
                m.x += noise * (k as f64 - 2.5);
                Edge {
                    i: k,
                    j: (k + 1) % n,
                    measurement: m,
                    noise: SymMat3::IDENTITY,
                }
            })
            .collect();
        let mut g = PoseGraph {
            ids: (0..n as u32).collect(),
            poses: vec![Pose2::IDENTITY; n],
            edges,
            fixed: vec![],
            vertices_declared: true,
            noise: NoiseKind::Information,
        };
        g.initialize_spanning_tree();
        g
    }

    #[test]
    fn lambda_zero_bounds_by_zero_and_infeasible_lambda_is_shifted() {
        // λ = 0 is always dual feasible (W̃ ⪰ 0): the bound is 0, up to the rounding shift.
        let g = cycle(0.2);
        let w = edge_weights(&g, Weights::Unit).unwrap();
        let m = PoseGraphMatrix::new(&g, &w);
        let b = dual_bound(&m, &[0.0; 6]).unwrap();
        assert!(
            b.lower_bound <= 0.0 && b.lower_bound > -1e-9,
            "{}",
            b.lower_bound
        );
        // A λ far outside the feasible set is shifted back until W̃(λ − t1) ⪰ 0; whatever λ,
        // the bound never exceeds a feasible point's cost (weak duality (32)).
        let f = cost(&g, &w, &g.poses);
        for big in [1.0, 10.0, 100.0] {
            let b = dual_bound(&m, &[big; 6]).unwrap();
            assert!(b.lower_bound <= f, "{big}: {} > {f}", b.lower_bound);
            let shifted: Vec<f64> = vec![big - b.shift; 6];
            let ev = crate::spectrum::hermitian_eigenvalues(&m.penalized_dense(&shifted));
            assert!(ev[0] >= -1e-9, "{ev:?}");
        }
    }
}
