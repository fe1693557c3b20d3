//! The smallest eigenvalues of a large sparse Hermitian pencil by shift-invert subspace
//! iteration (block inverse iteration with Rayleigh-Ritz), for `pgo-spectrum` at scale.
//!
//! The problem is A x = θ B x with A Hermitian (sparse, upper triangle stored) and
//! B = diag(0, …, 0, 1, …, 1) the identity on a range R of rows. With R all rows it is the
//! eigenproblem of A. With A = W̃ (eq. (24)) and R the rotation rows it is the eigenproblem of
//! the rotation-only matrix M = Q̃ − S̃* L⁻¹ S̃, the Schur complement of L (eq. (38)): for
//! x = [p; y], W̃x = θBx reads Lp + S̃y = 0 and S̃*p + Q̃y = θy, i.e. My = θy with p = −L⁻¹S̃y, so
//! M is never formed.
//!
//! One sparse LLᴴ of A + σB gives the operator T = (A + σB)⁻¹ restricted to R, i.e.
//! T y = rows R of (A + σB)⁻¹ [0; y]: Hermitian positive definite on ℂ^R with eigenvalues
//! 1/(θ_k + σ), so that the smallest θ are its largest. σ starts at 1e-12 of the largest
//! diagonal entry of A on R: far enough above the rounding of a factorization (u·‖A‖) for a
//! positive semidefinite A to factor, and below the eigenvalues sought even on long
//! trajectories, whose smallest eigenvalues of W̃ lie near 1e-13 of its diagonal (ais2klinik); at
//! 1e-8 they would all sit below σ and converge as one slow cluster. If A + σB does not factor
//! (A is indefinite), σ is raised by factors of 16 until it does and the last step narrowed to
//! a factor of 1.5 by bisection, so that A + σB ≻ 0 whatever the inertia of A. With a block of
//! b = 2K + 4 orthonormal vectors X, each step is
//!
//! ```text
//! Y = T X,   X*Y = U diag(μ) U*   (Rayleigh-Ritz of T on span X),   X ← qr(Y U)
//! ```
//!
//! and the estimates 1/μ_k − σ converge to θ_k at the rate ρ_k = ((θ_k + σ)/(θ_{b+1} + σ))² per
//! step. Iteration stops when, for each of the K estimates, the error its last change δ
//! foretells, δ·ρ/(1 − ρ) with ρ the ratio of the last two changes, is at most
//! `tolerance`·|θ_k|, or δ itself is below 16·u·‖A‖_∞ (the rounding level of the estimates),
//! or below 16·u·μ_max/μ_k² (the rounding of the Rayleigh-Ritz values μ of T, where eigenvalues
//! at zero, μ ≈ 1/σ, dwarf the rest) once the theoretical contraction ρ_k^i, ρ_k ≤
//! (μ_min/μ_k)², of the i steps taken is below `tolerance`.
//!
//! The values returned are the Rayleigh-Ritz values of the pencil (A, B) on span(T X), computed
//! with A itself (products with its stored entries, or a form Z ↦ Z*AZ the caller supplies,
//! such as W̃ edge by edge), not with T, so that no cancellation against σ enters: by
//! Courant-Fischer each is at least the eigenvalue of the same rank, and they equal the
//! eigenvalues to rounding once the subspace has converged. Everything is sequential (faer's
//! dense kernels with `Par::Seq`: its default parallel products split their sums by thread
//! count) and the start block comes from a fixed seed, so the same input gives the same bits.

use crate::linalg::factor::{Assembly, NotFactorable, SparseFactor};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{ComputeEigenvectors, self_adjoint_evd, self_adjoint_evd_scratch};
use faer::linalg::householder;
use faer::linalg::matmul::matmul;
use faer::linalg::qr::no_pivoting::factor as qr;
use faer::{Accum, Conj, Mat, MatRef, Par, c64};
use std::ops::Range;

/// The Hermitian pencil (A, B) of the module docs.
pub struct Pencil<'a> {
    /// The dimension of A.
    pub dim: usize,
    /// The entries (row, col, value) of A's upper triangle, row ≤ col, diagonal included
    /// (duplicates add up).
    pub upper: &'a [(usize, usize, c64)],
    /// The rows where B is the identity (B is zero elsewhere).
    pub rows: Range<usize>,
    /// A fill-reducing order of the rows (`order[new] = old`) for the factorization.
    pub order: &'a [usize],
    /// Z*AZ for a block Z (dim x b), if A has a more accurate form than its stored entries
    /// (e.g. W̃ edge by edge); by default it is computed from `upper`.
    pub form: Option<Form<'a>>,
}

/// A block Z ↦ Z*AZ (see [`Pencil::form`]).
pub type Form<'a> = &'a dyn Fn(&Mat<c64>) -> Mat<c64>;

/// Options of [`smallest_eigenvalues`].
#[derive(Debug, Clone, Copy)]
pub struct SubspaceOptions {
    /// Relative error of the estimates, as their changes foretell it, under which they count as
    /// converged.
    pub tolerance: f64,
    /// Steps at most.
    pub max_iterations: usize,
    /// Seed of the start block.
    pub seed: u64,
}

impl Default for SubspaceOptions {
    fn default() -> Self {
        SubspaceOptions {
            tolerance: 1e-12,
            max_iterations: 1000,
            seed: 0x5eed,
        }
    }
}

/// What [`smallest_eigenvalues`] found.
#[derive(Debug, Clone)]
pub struct SmallestEigenvalues {
    /// The K smallest eigenvalues of the pencil (Rayleigh-Ritz values), ascending.
    pub values: Vec<f64>,
    /// Subspace iteration steps taken.
    pub iterations: usize,
    /// Whether the estimates met the tolerance within `max_iterations` (if not, `values` are
    /// the last Rayleigh-Ritz values: upper bounds, less accurate).
    pub converged: bool,
    /// The shift σ the factorization was made at.
    pub shift: f64,
}

/// The `count` smallest eigenvalues of the pencil (at most |R| of them), by shift-invert
/// subspace iteration (module docs). `Err` if A has entries that are not finite, or if A + σB
/// cannot be factored for any σ up to 1000·‖A‖_∞ (with B ≠ I: A is not positive definite on the
/// rows outside R, e.g. the Laplacian L of a disconnected graph).
pub fn smallest_eigenvalues(
    pencil: &Pencil<'_>,
    count: usize,
    options: &SubspaceOptions,
) -> Result<SmallestEigenvalues, NotFactorable> {
    let Pencil {
        dim,
        upper,
        ref rows,
        order,
        form,
    } = *pencil;
    assert!(rows.end <= dim && order.len() == dim);
    let m = rows.len();
    let k = count.min(m);
    if k == 0 {
        return Ok(SmallestEigenvalues {
            values: Vec::new(),
            iterations: 0,
            converged: true,
            shift: 0.0,
        });
    }
    let block = (2 * k + 4).min(m);
    // ‖A‖_∞ (Hermitian: both triangles) and the largest diagonal entry on R.
    let mut row_sums = vec![0.0f64; dim];
    let mut diagonal = vec![0.0f64; dim];
    for &(r, c, v) in upper {
        if !(v.re.is_finite() && v.im.is_finite()) {
            return Err(NotFactorable);
        }
        row_sums[r] += v.norm();
        if r == c {
            diagonal[r] += v.re;
        } else {
            row_sums[c] += v.norm();
        }
    }
    let norm = row_sums.iter().fold(0.0f64, |a, &b| a.max(b));
    let max_diagonal = diagonal[rows.clone()]
        .iter()
        .fold(0.0f64, |a, &b| a.max(b.abs()));
    let scale = [max_diagonal, norm, 1.0]
        .into_iter()
        .find(|s| *s > 0.0 && s.is_finite())
        .unwrap_or(1.0);
    if !norm.is_finite() {
        return Err(NotFactorable);
    }

    // A + σB on A's pattern plus the diagonal of R (where σ goes).
    let pattern: Vec<(usize, usize)> = upper
        .iter()
        .map(|&(r, c, _)| (r, c))
        .chain(rows.clone().map(|r| (r, r)))
        .collect();
    let mut assembly = Assembly::<c64>::new(dim, &pattern);
    let mut factor = SparseFactor::<c64>::analyze_ordered(
        assembly.matrix.symbolic(),
        order,
        crate::linalg::factor::Layout::Auto,
    );
    let mut sigma = 1e-12 * scale;
    let mut values: Vec<c64> = upper.iter().map(|&(_, _, v)| v).collect();
    values.extend(rows.clone().map(|_| c64::new(0.0, 0.0)));
    let mut factor_at = |sigma: f64| {
        for v in &mut values[upper.len()..] {
            *v = c64::new(sigma, 0.0);
        }
        assembly.fill(&values);
        factor.llt(assembly.matrix.as_ref()).is_ok()
    };
    if !factor_at(sigma) {
        // A is not positive semidefinite: raise σ by factors of 16 until A + σB ≻ 0, then
        // narrow the last step to a factor of 1.5 by bisection in log σ (convergence is
        // fastest with σ just above −θ_1).
        let mut failed = sigma;
        loop {
            sigma *= 16.0;
            if sigma > 1e3 * norm.max(scale) {
                return Err(NotFactorable);
            }
            if factor_at(sigma) {
                break;
            }
            failed = sigma;
        }
        let mut factored = true;
        while sigma / failed > 1.5 {
            let mid = (sigma * failed).sqrt();
            factored = factor_at(mid);
            if factored {
                sigma = mid;
            } else {
                failed = mid;
            }
        }
        if !factored && !factor_at(sigma) {
            return Err(NotFactorable);
        }
    }

    // T applied to the columns of X (|R| x b): the full solutions (A + σB)⁻¹ [0; X].
    let mut apply = |x: &Mat<c64>| -> Mat<c64> {
        let mut z = Mat::<c64>::zeros(dim, x.ncols());
        z.as_mut().subrows_mut(rows.start, m).copy_from(x);
        factor.solve_block_in_place(z.as_mut());
        z
    };
    let mut rng = crate::linalg::rng::Rng::new(options.seed);
    let start = Mat::<c64>::from_fn(m, block, |_, _| {
        c64::new(2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0)
    });
    let mut x = orthonormal_basis(start);
    let floor = 16.0 * f64::EPSILON * norm;
    let mut estimates: Vec<f64> = Vec::new();
    let mut changes: Vec<f64> = Vec::new();
    let mut iterations = 0;
    let mut converged = false;
    while iterations < options.max_iterations {
        iterations += 1;
        let y = apply(&x).subrows(rows.start, m).to_owned();
        let Some((mu, u)) = eigh(&hermitian_part(product(x.adjoint(), y.as_ref()))) else {
            break;
        };
        // Descending μ: the smallest θ first.
        let u = Mat::from_fn(block, block, |i, j| u[(i, block - 1 - j)]);
        let next: Vec<f64> = (0..k).map(|j| 1.0 / mu[block - 1 - j] - sigma).collect();
        x = orthonormal_basis(product(y.as_ref(), u.as_ref()));
        let change: Vec<f64> = if estimates.len() == k {
            next.iter()
                .zip(&estimates)
                .map(|(a, b)| (a - b).abs())
                .collect()
        } else {
            vec![f64::INFINITY; k]
        };
        // The change δ_i of an estimate shrinks by the rate ρ = δ_i/δ_{i−1} per step, so the
        // error left after it is about δ_i·ρ/(1 − ρ).
        let settled = changes.len() == k
            && (0..k).all(|j| {
                let (d, previous) = (change[j], changes[j]);
                let rate = if previous > 0.0 {
                    (d / previous).min(0.999)
                } else {
                    0.999
                };
                // μ_j, an eigenvalue of the b x b matrix X*Y, is computed within about
                // u·μ_max (Weyl; a backward stable eigensolver), so θ_j = 1/μ_j − σ within
                // u·μ_max/μ_j²: the rounding level of θ_j when eigenvalues at zero
                // (μ_max ≈ 1/σ) dwarf it, as the three null directions of the SE(3)
                // certificate matrix do. Its changes then no longer tell the convergence, which
                // the theory does: the error of θ_j shrinks by ρ_j = ((θ_j + σ)/(θ_{b+1} + σ))²
                // ≤ (μ_min/μ_j)² per step, so after i steps it is below ρ_j^i times the spread.
                let mu_j = mu[block - 1 - j];
                let ritz = 16.0 * f64::EPSILON * mu[block - 1].abs() / (mu_j * mu_j);
                let theory = (mu[0] / mu_j).powi(2).powi(iterations as i32);
                previous.is_finite()
                    && (d <= floor
                        || (d <= ritz && theory <= options.tolerance)
                        || d * rate / (1.0 - rate) <= options.tolerance * next[j].abs())
            });
        estimates = next;
        changes = change;
        if settled {
            converged = true;
            break;
        }
    }

    // Rayleigh-Ritz of (A, B) on span(Z), Z = T X: H = Z*AZ, G = Z*BZ, columns scaled to unit
    // B-norm, G = V diag(g) V*, C = diag(g)^{-1/2} V* H V diag(g)^{-1/2}.
    let z = apply(&x);
    let zr = z.subrows(rows.start, m);
    let d: Vec<f64> = (0..block)
        .map(|j| {
            let norm = zr.col(j).norm_l2();
            if norm > 0.0 && norm.is_finite() {
                1.0 / norm
            } else {
                0.0
            }
        })
        .collect();
    let scaled = Mat::from_fn(dim, block, |i, j| z[(i, j)] * d[j]);
    let zr = scaled.subrows(rows.start, m);
    let g = hermitian_part(product(zr.adjoint(), zr));
    let h = hermitian_part(match form {
        Some(form) => form(&scaled),
        None => product(scaled.adjoint(), upper_times(dim, upper, &scaled).as_ref()),
    });
    let ritz = eigh(&g).and_then(|(gv, gvec)| {
        let g_max = gv.last().copied().unwrap_or(0.0);
        let keep: Vec<usize> = (0..block)
            .filter(|&j| gv[j] > 1e-12 * g_max && gv[j].is_finite())
            .collect();
        if keep.len() < k {
            return None;
        }
        let s = Mat::from_fn(block, keep.len(), |i, j| {
            gvec[(i, keep[j])] / gv[keep[j]].sqrt()
        });
        let c = product(s.adjoint(), product(h.as_ref(), s.as_ref()).as_ref());
        eigh(&hermitian_part(c)).map(|(values, _)| values)
    });
    let values = match ritz {
        Some(ritz) if ritz.iter().all(|v| v.is_finite()) => ritz[..k].to_vec(),
        _ => {
            let mut e = estimates;
            e.sort_by(f64::total_cmp);
            e
        }
    };
    Ok(SmallestEigenvalues {
        values,
        iterations,
        converged,
        shift: sigma,
    })
}

/// A B, sequential.
fn product(
    a: MatRef<'_, impl faer::traits::Conjugate<Canonical = c64>>,
    b: MatRef<'_, c64>,
) -> Mat<c64> {
    let mut out = Mat::<c64>::zeros(a.nrows(), b.ncols());
    matmul(
        out.as_mut(),
        Accum::Replace,
        a,
        b,
        c64::new(1.0, 0.0),
        Par::Seq,
    );
    out
}

/// The first columns of Q of a = QR (a tall, full column rank), by Householder QR, sequential.
fn orthonormal_basis(mut a: Mat<c64>) -> Mat<c64> {
    let (m, n) = a.shape();
    let block = qr::recommended_block_size::<c64>(m, n);
    let mut coeff = Mat::<c64>::zeros(block, n);
    qr::qr_in_place(
        a.as_mut(),
        coeff.as_mut(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(qr::qr_in_place_scratch::<c64>(
            m,
            n,
            block,
            Par::Seq,
            Default::default(),
        ))),
        Default::default(),
    );
    // The Householder vectors: the unit lower trapezoid of the factored a.
    for j in 0..n {
        for i in 0..j {
            a[(i, j)] = c64::new(0.0, 0.0);
        }
        a[(j, j)] = c64::new(1.0, 0.0);
    }
    let mut q = Mat::<c64>::identity(m, n);
    householder::apply_block_householder_sequence_on_the_left_in_place_with_conj(
        a.as_ref(),
        coeff.as_ref(),
        Conj::No,
        q.as_mut(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(
            householder::apply_block_householder_sequence_on_the_left_in_place_scratch::<c64>(
                m, block, n,
            ),
        )),
    );
    q
}

/// Eigenvalues (ascending) and eigenvectors of a small Hermitian matrix, sequential; `None` if
/// the eigensolver fails (entries that are not finite).
fn eigh(h: &Mat<c64>) -> Option<(Vec<f64>, Mat<c64>)> {
    let n = h.nrows();
    let mut s = faer::diag::Diag::<c64>::zeros(n);
    let mut u = Mat::<c64>::zeros(n, n);
    let scratch =
        self_adjoint_evd_scratch::<c64>(n, ComputeEigenvectors::Yes, Par::Seq, Default::default());
    self_adjoint_evd(
        h.as_ref(),
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .ok()?;
    Some(((0..n).map(|k| s[k].re).collect(), u))
}

/// (H + H*)/2: exactly Hermitian, so that the dense eigensolver reads what it assumes.
fn hermitian_part(h: Mat<c64>) -> Mat<c64> {
    Mat::from_fn(h.nrows(), h.ncols(), |i, j| {
        (h[(i, j)] + h[(j, i)].conj()) * 0.5
    })
}

/// A Z for A given by its upper triangle.
fn upper_times(dim: usize, upper: &[(usize, usize, c64)], z: &Mat<c64>) -> Mat<c64> {
    let mut out = Mat::<c64>::zeros(dim, z.ncols());
    for j in 0..z.ncols() {
        let zc = z.col_as_slice(j);
        let oc = out.col_as_slice_mut(j);
        for &(r, c, v) in upper {
            oc[r] += v * zc[c];
            if r != c {
                oc[c] += v.conj() * zc[r];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::eigen::hermitian_eigenvalues;
    use faer::Side;
    use faer::prelude::Solve;

    /// A random sparse Hermitian matrix (a ring with chords), dense and as an upper triangle.
    fn ring(dim: usize, shift: f64) -> (Mat<c64>, Vec<(usize, usize, c64)>) {
        let mut rng = crate::linalg::rng::Rng::new(3);
        let mut dense = Mat::<c64>::zeros(dim, dim);
        let mut add = |a: usize, b: usize, v: c64| {
            dense[(a, b)] += v;
            if a != b {
                dense[(b, a)] += v.conj();
            }
        };
        for i in 0..dim {
            add(i, i, c64::new(2.0 + shift + rng.uniform(), 0.0));
            let j = (i + 1) % dim;
            add(i.min(j), i.max(j), c64::new(-1.0, rng.uniform() - 0.5));
            let l = (i * 7 + 3) % dim;
            if l != i && l != j && (l + 1) % dim != i {
                add(i.min(l), i.max(l), c64::new(0.3 * rng.uniform(), 0.1));
            }
        }
        let mut upper = Vec::new();
        for c in 0..dim {
            for r in 0..=c {
                if dense[(r, c)] != c64::new(0.0, 0.0) {
                    upper.push((r, c, dense[(r, c)]));
                }
            }
        }
        (dense, upper)
    }

    #[test]
    fn smallest_eigenvalues_of_a_sparse_hermitian_matrix_match_the_dense_ones() {
        // Indefinite (shift −2.5): the shift σ must be raised until A + σI ≻ 0.
        for shift in [0.0, -2.5] {
            let (dense, upper) = ring(150, shift);
            let order: Vec<usize> = (0..150).collect();
            let pencil = Pencil {
                dim: 150,
                upper: &upper,
                rows: 0..150,
                order: &order,
                form: None,
            };
            let found = smallest_eigenvalues(&pencil, 6, &SubspaceOptions::default()).unwrap();
            assert!(found.converged);
            eprintln!(
                "{shift}: {} iterations, σ = {}",
                found.iterations, found.shift
            );
            let exact = dense.self_adjoint_eigenvalues(Side::Lower).unwrap();
            for (a, b) in found.values.iter().zip(&exact) {
                assert!((a - b).abs() <= 1e-10 * b.abs().max(1.0), "{a} vs {b}");
            }
        }
    }

    #[test]
    fn the_pencil_with_a_partial_identity_gives_the_schur_complement() {
        // A = [[A11, A12], [A21, A22]] ≻ 0, B = blkdiag(0, I): the eigenvalues of
        // A22 − A21 A11⁻¹ A12.
        let (dense, upper) = ring(120, 0.5);
        let order: Vec<usize> = (0..120).collect();
        let pencil = Pencil {
            dim: 120,
            upper: &upper,
            rows: 50..120,
            order: &order,
            form: None,
        };
        let found = smallest_eigenvalues(&pencil, 5, &SubspaceOptions::default()).unwrap();
        let a11 = dense.submatrix(0, 0, 50, 50).to_owned();
        let a12 = dense.submatrix(0, 50, 50, 70).to_owned();
        let a22 = dense.submatrix(50, 50, 70, 70).to_owned();
        let schur = &a22 - a12.adjoint() * a11.llt(Side::Lower).unwrap().solve(&a12);
        let exact = hermitian_eigenvalues(&hermitian_part(schur));
        for (a, b) in found.values.iter().zip(&exact) {
            assert!((a - b).abs() <= 1e-10 * b.abs().max(1.0), "{a} vs {b}");
        }
    }
}
