//! What the Levenberg-Marquardt refinements on SE(2) ([`super::levenberg_marquardt`], blocks of
//! 3) and on SE(3) ([`super::se3`], blocks of 6) share: the block-sparse normal equations over
//! the free poses with their sparse Cholesky analysis done once ([`BlockSystem`]), and the damping
//! schedule ([`levenberg`]).
//!
//! Each iteration assembles, in one pass over the edges, the gradient g = Σ Jᵀ Ω e and the upper
//! triangle of H = Σ Jᵀ Ω J (B·m x B·m over the m free poses, block sparse, written in place into
//! a pattern built once), and solves (H + λ I) δ = −g by sparse Cholesky. The symbolic analysis
//! (AMD ordering, elimination tree, supernodes) is done once per call and reused by every
//! numeric factorization, into a factor buffer and a workspace also allocated once (faer's
//! `SymbolicCholesky`, the analysis `SymbolicLlt` wraps, used directly so that `Llt` does not
//! allocate per factorization); all runs sequentially, so results do not depend on the thread
//! count.
//!
//! Damping, as g2o's `OptimizationAlgorithmLevenberg`: λ₀ = 10⁻⁵ · max_k H_kk; a trial step is
//! accepted iff chi2 decreases, and then, with ρ = (chi2 − chi2_trial) / δᵀ(λ δ − g) (actual over
//! predicted decrease), λ ← λ · min(2/3, max(1/3, 1 − (2ρ − 1)³)) and ν ← 2 (Nielsen's rule with
//! g2o's bounds); a rejected step or a failed factorization sets λ ← λ ν, ν ← 2ν.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// Options of the refinements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineOptions {
    /// Largest number of iterations (linearizations). Default 100.
    pub max_iterations: usize,
    /// Converged when a step changes chi2 by less than `tol · chi2` (relative decrease below
    /// `tol`, or a rejected step whose increase is below it: rounding level). Default 1e-12:
    /// above the ~1e-14 rounding of a sum of 10⁴ terms, and LM converges quadratically near a
    /// minimum, so the chi2 reached is then exact to far better than 1e-12.
    pub tol: f64,
    /// Trials (damping increases) per iteration before giving up, as g2o's
    /// `maxTrialsAfterFailure`. Default 10.
    pub max_trials: usize,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            tol: 1e-12,
            max_trials: 10,
        }
    }
}

/// Why a refinement stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stop {
    /// A step changed chi2 by less than `tol · chi2`, or chi2 is zero.
    Converged,
    /// `max_iterations` reached.
    MaxIterations,
    /// `max_trials` damped steps in a row failed to decrease chi2 (or to factor).
    NoDecrease,
}

/// A B x B matrix, row-major.
pub type Block<const B: usize> = [[f64; B]; B];

/// aᵀ b for B x B matrices.
pub fn at_b<const B: usize>(a: &Block<B>, b: &Block<B>) -> Block<B> {
    let mut m = [[0.0; B]; B];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..B).map(|k| a[k][r] * b[k][c]).fold(0.0, |s, x| s + x);
        }
    }
    m
}

/// a b for B x B matrices.
pub fn mul<const B: usize>(a: &Block<B>, b: &Block<B>) -> Block<B> {
    let mut m = [[0.0; B]; B];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..B).map(|k| a[r][k] * b[k][c]).fold(0.0, |s, x| s + x);
        }
    }
    m
}

/// m v for a B x B matrix.
pub fn mul_vec<const B: usize>(m: &Block<B>, v: &[f64; B]) -> [f64; B] {
    std::array::from_fn(|r| (0..B).map(|k| m[r][k] * v[k]).fold(0.0, |s, x| s + x))
}

/// vᵀ m v.
pub fn quadratic<const B: usize>(m: &Block<B>, v: &[f64; B]) -> f64 {
    (0..B)
        .map(|r| v[r] * (0..B).map(|k| m[r][k] * v[k]).fold(0.0, |s, x| s + x))
        .fold(0.0, |s, x| s + x)
}

/// The damped normal equations over the free poses (blocks of B variables), with their Cholesky
/// analysis.
pub struct BlockSystem<const B: usize> {
    /// B · (number of free poses).
    pub dim: usize,
    /// Block (free pose) index of every pose; `usize::MAX` for a held pose.
    pub block: Vec<usize>,
    /// Pattern of the upper triangle of H: column B·b + c holds, for every free pose a < b
    /// sharing an edge with b (ascending), rows B·a..B·a+B, then rows B·b..=B·b+c.
    pub pattern: SymbolicSparseColMat<usize>,
    /// Per edge: offset, within the columns of block max(b_i, b_j), of the off-diagonal block.
    offset: Vec<usize>,
    /// Per block b: offset of the diagonal block within its columns (B · off-diagonal blocks).
    diag_offset: Vec<usize>,
    /// H (upper triangle, undamped until [`Self::solve`] damps the diagonal) and g.
    pub values: Vec<f64>,
    pub grad: Vec<f64>,
    /// Positions of H_kk in `values`, and the undamped H_kk.
    diag_pos: Vec<usize>,
    diag: Vec<f64>,
    symbolic: SymbolicCholesky<usize>,
    factor: Vec<f64>,
    mem: MemBuffer,
}

impl<const B: usize> BlockSystem<B> {
    /// The pattern of H for edges `pairs` (pose indices) with `held` poses left out, and its
    /// symbolic Cholesky analysis; `Err` with the reason if the analysis fails.
    pub fn new(pairs: &[(usize, usize)], held: &[bool]) -> Result<Self, String> {
        let mut block = vec![usize::MAX; held.len()];
        let mut m = 0;
        for (b, &h) in block.iter_mut().zip(held) {
            if !h {
                *b = m;
                m += 1;
            }
        }
        // Off-diagonal blocks (a, b), a < b, grouped by b, sorted and deduplicated.
        let pair = |&(i, j): &(usize, usize)| {
            let (bi, bj) = (block[i], block[j]);
            (bi != usize::MAX && bj != usize::MAX && bi != bj).then(|| (bi.min(bj), bi.max(bj)))
        };
        let mut start = vec![0usize; m + 1];
        for (_, b) in pairs.iter().filter_map(pair) {
            start[b + 1] += 1;
        }
        for b in 0..m {
            start[b + 1] += start[b];
        }
        let mut fill = start.clone();
        let mut rows = vec![0usize; start[m]];
        for (a, b) in pairs.iter().filter_map(pair) {
            rows[fill[b]] = a;
            fill[b] += 1;
        }
        let mut neighbours = Vec::with_capacity(rows.len());
        let mut nstart = vec![0usize; m + 1];
        for b in 0..m {
            let seg = &mut rows[start[b]..start[b + 1]];
            seg.sort_unstable();
            for (k, &a) in seg.iter().enumerate() {
                if k == 0 || seg[k - 1] != a {
                    neighbours.push(a);
                }
            }
            nstart[b + 1] = neighbours.len();
        }
        let dim = B * m;
        let mut col_ptr = Vec::with_capacity(dim + 1);
        let mut row_idx = Vec::new();
        let mut diag_offset = Vec::with_capacity(m);
        let mut diag_pos = Vec::with_capacity(dim);
        col_ptr.push(0);
        for b in 0..m {
            let nb = &neighbours[nstart[b]..nstart[b + 1]];
            diag_offset.push(B * nb.len());
            for c in 0..B {
                row_idx.extend(nb.iter().flat_map(|&a| B * a..B * a + B));
                row_idx.extend(B * b..=B * b + c);
                diag_pos.push(row_idx.len() - 1);
                col_ptr.push(row_idx.len());
            }
        }
        let offset = pairs
            .iter()
            .map(|p| match pair(p) {
                Some((a, b)) => {
                    let nb = &neighbours[nstart[b]..nstart[b + 1]];
                    B * nb.binary_search(&a).expect("every pair is in the pattern")
                }
                None => 0,
            })
            .collect();
        let nnz = row_idx.len();
        let pattern = SymbolicSparseColMat::new_checked(dim, dim, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| format!("{e:?}"))?;
        let scratch = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(scratch).map_err(|_| "out of memory".to_string())?;
        Ok(BlockSystem {
            dim,
            block,
            pattern,
            offset,
            diag_offset,
            values: vec![0.0; nnz],
            grad: vec![0.0; dim],
            diag_pos,
            diag: vec![0.0; dim],
            factor: vec![0.0; symbolic.len_val()],
            symbolic,
            mem,
        })
    }

    /// Zeroes H and g before an assembly.
    pub fn clear(&mut self) {
        self.values.fill(0.0);
        self.grad.fill(0.0);
    }

    /// Whether edge (i, j) has variables: not a self-loop (its error is constant) and not
    /// between held poses.
    pub fn moves(&self, i: usize, j: usize) -> bool {
        i != j && (self.block[i] != usize::MAX || self.block[j] != usize::MAX)
    }

    /// Adds edge number `edge` = (i, j), with error e, information Ω and Jacobians J_i, J_j:
    /// Jᵀ Ω J to H and Jᵀ Ω e to g (held poses' parts left out).
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &mut self,
        edge: usize,
        i: usize,
        j: usize,
        e: &[f64; B],
        omega: &Block<B>,
        ji: &Block<B>,
        jj: &Block<B>,
    ) {
        let (bi, bj) = (self.block[i], self.block[j]);
        let col_ptr = self.pattern.col_ptr();
        let values = &mut self.values;
        let oe = mul_vec(omega, e);
        let oji = mul(omega, ji);
        let ojj = mul(omega, jj);
        for (b, jac, ojac) in [(bi, ji, &oji), (bj, jj, &ojj)] {
            if b == usize::MAX {
                continue;
            }
            let h = at_b(jac, ojac);
            for c in 0..B {
                let base = col_ptr[B * b + c] + self.diag_offset[b];
                for (r, hr) in h.iter().enumerate().take(c + 1) {
                    values[base + r] += hr[c];
                }
                self.grad[B * b + c] += (0..B).map(|k| jac[k][c] * oe[k]).fold(0.0, |s, x| s + x);
            }
        }
        if bi != usize::MAX && bj != usize::MAX {
            // H_{b_i b_j} = J_iᵀ Ω J_j; the stored block is the one above the diagonal.
            let hij = at_b(ji, &ojj);
            let (col, transposed) = if bi < bj { (bj, false) } else { (bi, true) };
            for c in 0..B {
                let base = col_ptr[B * col + c] + self.offset[edge];
                for r in 0..B {
                    values[base + r] += if transposed { hij[c][r] } else { hij[r][c] };
                }
            }
        }
    }

    /// Records the undamped diagonal after an assembly.
    pub fn finish(&mut self) {
        for (d, &p) in self.diag.iter_mut().zip(&self.diag_pos) {
            *d = self.values[p];
        }
    }

    /// Solves (H + λ I) δ = −g into `step`; false if the factorization fails.
    pub fn solve(&mut self, lambda: f64, step: &mut [f64]) -> bool {
        for (&p, &d) in self.diag_pos.iter().zip(&self.diag) {
            self.values[p] = d + lambda;
        }
        let h = SparseColMatRef::new(self.pattern.as_ref(), &self.values);
        let Ok(llt) = self.symbolic.factorize_numeric_llt(
            &mut self.factor,
            h,
            Side::Upper,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        ) else {
            return false;
        };
        for (s, g) in step.iter_mut().zip(&self.grad) {
            *s = -g;
        }
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(step, self.dim, 1),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
        step.iter().all(|s| s.is_finite())
    }
}

/// What [`levenberg`] did.
#[derive(Debug, Clone, Copy)]
pub struct Outcome {
    pub chi2: f64,
    pub iterations: usize,
    pub factorizations: usize,
    pub stop: Stop,
}

/// The damped iteration (module docs) from `poses` with chi2 `chi2_0`: `assemble` fills the
/// system (H, g, diagonal recorded) at poses, `chi2` evaluates poses, `retract` writes poses ⊕ δ.
/// `poses` ends at the last accepted iterate.
pub fn levenberg<P: Clone, const B: usize>(
    system: &mut BlockSystem<B>,
    poses: &mut Vec<P>,
    chi2_0: f64,
    options: &RefineOptions,
    assemble: impl Fn(&mut BlockSystem<B>, &[P]),
    chi2: impl Fn(&[P]) -> f64,
    retract: impl Fn(&BlockSystem<B>, &[P], &[f64], &mut [P]),
) -> Outcome {
    let mut out = Outcome {
        chi2: chi2_0,
        iterations: 0,
        factorizations: 0,
        stop: Stop::MaxIterations,
    };
    let mut chi = chi2_0;
    let mut trial = poses.clone();
    let mut step = vec![0.0; system.dim];
    let mut lambda = 0.0;
    let mut nu = 2.0;
    'outer: while out.iterations < options.max_iterations {
        out.iterations += 1;
        assemble(system, poses);
        if out.iterations == 1 {
            let max_diag = system.diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
            lambda = if max_diag > 0.0 && max_diag.is_finite() {
                1e-5 * max_diag
            } else {
                1e-5
            };
        }
        let mut trials = 0;
        loop {
            trials += 1;
            out.factorizations += 1;
            let solved = system.solve(lambda, &mut step);
            let chi_trial = if solved {
                retract(system, poses, &step, &mut trial);
                chi2(&trial)
            } else {
                f64::INFINITY
            };
            if chi_trial < chi {
                let predicted: f64 = step
                    .iter()
                    .zip(&system.grad)
                    .map(|(d, g)| d * (lambda * d - g))
                    .sum();
                let rho = (chi - chi_trial) / predicted;
                let alpha = 1.0 - (2.0 * rho - 1.0).powi(3);
                lambda *= if alpha.is_nan() {
                    1.0 / 3.0
                } else {
                    alpha.clamp(1.0 / 3.0, 2.0 / 3.0)
                };
                nu = 2.0;
                let small = chi - chi_trial < options.tol * chi;
                std::mem::swap(poses, &mut trial);
                chi = chi_trial;
                if small || chi == 0.0 {
                    out.stop = Stop::Converged;
                    break 'outer;
                }
                break;
            }
            if chi_trial - chi < options.tol * chi {
                // The step changes chi2 by less than the tolerance: stationary to rounding.
                out.stop = Stop::Converged;
                break 'outer;
            }
            lambda *= nu;
            nu *= 2.0;
            if trials >= options.max_trials || !lambda.is_finite() {
                out.stop = Stop::NoDecrease;
                break 'outer;
            }
        }
    }
    out.chi2 = chi;
    out
}
