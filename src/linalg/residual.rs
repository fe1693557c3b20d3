//! The residual of an LDLᴴ factorization, a posteriori: R = L D Lᴴ − A for the factors as stored,
//! and the bound ‖R‖₂ ≤ max_i Σ_j |R_ij| it gives (R is Hermitian).
//!
//! Why: [`SparseFactor::ldlt_backward_error`] bounds the backward error a priori, entry (i, j)
//! by γ_{2k_i+8}·(|L||D||Lᴴ|)_ij with k_i the entries of row i of L. In the top separators of a
//! 10⁶-10⁷-pose graph k_i reaches thousands, and the bound 10⁴ units of rounding, where the
//! errors made are a few units each, summed with signs that mostly cancel. At 10⁷ generated
//! poses it was 3.9e-11 against a gap of 5.6e-12 shown by the inertia, so the SZEP stayed
//! unproven. The residual measured here holds for the stored L and D whatever the order of the
//! factorization's operations: A + R = L D Lᴴ exactly, whose inertia is D's (Sylvester), so each
//! eigenvalue of A lies within ‖R‖₂ of one of L D Lᴴ's (Weyl).
//!
//! How: left-looking by panels (supernodes), as a supernodal Cholesky runs: the products L D Lᴴ
//! of a [`Chunk`] of 16 columns at a time in double precision (faer's `matmul`), each within
//! √2·γ₃₂ of the moduli of its terms (Higham, *Accuracy and Stability of Numerical
//! Algorithms*, §3.1 and Lemma 3.5: any order of summation, fused or not), summed with A's entries
//! in double-double (Ogita, Rump and Oishi's Sum2: within u|s| + γ²_m·Σ|terms|). So the computed
//! R̂ is within c·(|L||D||Lᴴ|)_ij of R, c ≈ 46u in ℂ, where the a-priori bound takes (2k + 8)u.
//! Measured: at 10⁶ generated poses 1.7e-13 against 3.3e-11, in 2.7 s against the
//! factorization's 1.1 s.

use crate::linalg::factor::{Scalar, SparseFactor};
use crate::linalg::parallel;
use crate::linalg::roundoff::{U, gamma};
use faer::linalg::matmul::matmul_with_conj;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::{Accum, Conj, Mat, Par, c64};

/// A double-precision scalar (ℝ or ℂ) as its two parts, for the residual's sums.
pub trait Double: Scalar + Send + Sync {
    /// Whether the imaginary part can be nonzero.
    const COMPLEX: bool;
    /// (re, im); im is 0 for a real scalar.
    fn parts(self) -> (f64, f64);
    /// self·d, each part rounded once.
    fn times(self, d: f64) -> Self;
}

impl Double for f64 {
    const COMPLEX: bool = false;
    fn parts(self) -> (f64, f64) {
        (self, 0.0)
    }
    fn times(self, d: f64) -> Self {
        self * d
    }
}

impl Double for c64 {
    const COMPLEX: bool = true;
    fn parts(self) -> (f64, f64) {
        (self.re, self.im)
    }
    fn times(self, d: f64) -> Self {
        c64::new(self.re * d, self.im * d)
    }
}

/// The factor as panels of consecutive columns with one row pattern: a supernode's columns
/// `begin..end`, its rows those columns then `below`, stored column-major from `first` with
/// leading dimension `end − begin + below.len()` (d_l on the diagonal, L below it, the upper
/// triangle of the diagonal block unused); a simplicial factor's columns one by one.
enum Panels<'a> {
    Simplicial {
        col_ptr: &'a [usize],
        row_idx: &'a [usize],
    },
    Supernodal {
        begin: &'a [usize],
        end: &'a [usize],
        row_ptr: &'a [usize],
        val_ptr: &'a [usize],
        row_idx: &'a [usize],
    },
}

/// One panel of [`Panels`].
struct Panel<'a> {
    begin: usize,
    end: usize,
    below: &'a [usize],
    first: usize,
}

impl Panel<'_> {
    fn width(&self) -> usize {
        self.end - self.begin
    }
    /// The leading dimension: the panel's rows.
    fn rows(&self) -> usize {
        self.width() + self.below.len()
    }
    /// The row at position q (its columns first, then `below`).
    fn row(&self, q: usize) -> usize {
        if q < self.width() {
            self.begin + q
        } else {
            self.below[q - self.width()]
        }
    }
}

impl<'a> Panels<'a> {
    fn new(raw: &'a SymbolicCholeskyRaw<usize>) -> Self {
        match raw {
            SymbolicCholeskyRaw::Simplicial(s) => Panels::Simplicial {
                col_ptr: s.col_ptr(),
                row_idx: s.row_idx(),
            },
            SymbolicCholeskyRaw::Supernodal(s) => Panels::Supernodal {
                begin: s.supernode_begin(),
                end: s.supernode_end(),
                row_ptr: s.col_ptr_for_row_idx(),
                val_ptr: s.col_ptr_for_val(),
                row_idx: s.row_idx(),
            },
        }
    }

    fn len(&self) -> usize {
        match self {
            Panels::Simplicial { col_ptr, .. } => col_ptr.len() - 1,
            Panels::Supernodal { begin, .. } => begin.len(),
        }
    }

    fn panel(&self, t: usize) -> Panel<'a> {
        match self {
            // The diagonal is stored first in each column.
            Panels::Simplicial { col_ptr, row_idx } => Panel {
                begin: t,
                end: t + 1,
                below: &row_idx[col_ptr[t] + 1..col_ptr[t + 1]],
                first: col_ptr[t],
            },
            Panels::Supernodal {
                begin,
                end,
                row_ptr,
                val_ptr,
                row_idx,
            } => Panel {
                begin: begin[t],
                end: end[t],
                below: &row_idx[row_ptr[t]..row_ptr[t + 1]],
                first: val_ptr[t],
            },
        }
    }
}

/// Knuth's TwoSum: s + e = a + b exactly, s = fl(a + b).
#[inline(always)]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let z = s - a;
    (s, (a - (s - z)) + (b - z))
}

/// A sum in double-double, per part: (re high, re low, im high, im low).
type Accumulator = [f64; 4];

/// Adds (re, im) to a double-double sum (Sum2: the low parts summed in double).
#[inline(always)]
fn add<const COMPLEX: bool>(acc: &mut Accumulator, re: f64, im: f64) {
    let (s, e) = two_sum(acc[0], re);
    acc[0] = s;
    acc[1] += e;
    if COMPLEX {
        let (s, e) = two_sum(acc[2], im);
        acc[2] = s;
        acc[3] += e;
    }
}

/// The columns of a panel the products take at a time: each entry of a product is a dot
/// product of this many terms K in double precision, within √2·γ_{2K} of its terms' moduli
/// (Higham, §3.1 and Lemma 3.5: any order, fused or not), before its double-double sum. `Wide`,
/// 16 (c ≈ 46u in ℂ), is the fast one (dense products of 16 columns: at 10⁶ poses 2.7 s
/// against 1.1 s for the factorization); `Narrow`, 1, each term rounded alone (c ≈ 3.9u), for
/// where the wide bound falls short (its scattered sums some 3x slower).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Chunk {
    Wide,
    Narrow,
}

impl Chunk {
    fn columns(self) -> usize {
        match self {
            Chunk::Wide => 16,
            Chunk::Narrow => 1,
        }
    }
}

/// The columns of a target panel whose residual is summed at a time (its double-double block:
/// the panel's rows times this many, 32 bytes each).
const BLOCK: usize = 128;

/// The factorization a factor holds: LDLᴴ (L unit lower triangular, d_l stored on its diagonal)
/// or LLᴴ (L's diagonal stored, D = I).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Ldlt,
    Llt,
}

impl<T: Double> SparseFactor<T> {
    /// A bound on ‖L D Lᴴ − P A Pᵀ‖₂ for the last LDLᴴ (P its fill-reducing order), `a` the
    /// matrix it factored (one triangle, as passed to [`Self::ldlt`]): max_i of Σ_j |R̂_ij| plus
    /// c·(|L||D||Lᴴ|·1)_i, the computed residual and its rounding, enlarged for the rounding of
    /// the row sums (module doc). `None` where an index does not fit in 31 bits.
    ///
    /// Left-looking by panels (supernodes), as a supernodal Cholesky runs: each target panel's
    /// columns, a block at a time, gather the products L_t D_t L_tᴴ of every panel t whose rows
    /// meet them (its own included), a [`Chunk`] of t's columns per dense product (faer's
    /// `matmul`), each entry then added in double-double; less A's entries, then the moduli
    /// into the row sums.
    pub fn ldlt_residual_bound(
        &self,
        a: SparseColMatRef<'_, usize, T>,
        chunk: Chunk,
    ) -> Option<f64> {
        let products = self.ldlt_product_row_sums().0;
        self.residual_bound(a, Kind::Ldlt, &products, chunk)
    }

    /// As [`Self::ldlt_residual_bound`] for the last LLᴴ: a bound on ‖L Lᴴ − P A Pᵀ‖₂.
    pub fn llt_residual_bound(
        &self,
        a: SparseColMatRef<'_, usize, T>,
        chunk: Chunk,
    ) -> Option<f64> {
        let products = self.llt_product_row_sums();
        self.residual_bound(a, Kind::Llt, &products, chunk)
    }

    /// The bound from the residual's row sums and `products`, (|L||D||Lᴴ|·1)_i.
    fn residual_bound(
        &self,
        a: SparseColMatRef<'_, usize, T>,
        kind: Kind,
        products: &[f64],
        chunk: Chunk,
    ) -> Option<f64> {
        let row_sums = self.residual_row_sums(a, kind, chunk)?;
        let c = chunk_allowance::<T>(chunk);
        // Each row sum adds at most 2·dim moduli (|re| + |im| bounds the modulus from above, and
        // rounds below it by 2u² at most: roundoff::modulus_bound).
        let sums = 1.0 + gamma(2 * self.dim() + 8);
        let bound = row_sums
            .iter()
            .zip(products)
            .fold(0.0f64, |m, (&r, &p)| m.max(r + 1.01 * c * p));
        Some(bound * sums * (1.0 + 8.0 * U))
    }

    /// Σ_j |R̂_ij| (as |re| + |im|) for each row i of the computed residual R̂ of the last
    /// factorization, of kind `kind` ([`Self::ldlt_residual_bound`]), in the factor's order.
    fn residual_row_sums(
        &self,
        a: SparseColMatRef<'_, usize, T>,
        kind: Kind,
        chunk: Chunk,
    ) -> Option<Vec<f64>> {
        let dim = self.dim();
        if dim >= 1 << 31 || a.compute_nnz() >= 1 << 32 {
            return None;
        }
        let lower = lower_columns(a, self.inverse_order().as_deref());
        let panels = Panels::new(self.symbolic_raw());
        let mut panel_of = vec![0u32; dim];
        for t in 0..panels.len() {
            let p = panels.panel(t);
            panel_of[p.begin..p.end].fill(t as u32);
        }
        let sweep = Sweep {
            a,
            lower: &lower,
            panels: &panels,
            panel_of: &panel_of,
            values: self.factor_values(kind == Kind::Ldlt),
            kind,
            chunk: chunk.columns(),
        };
        // The blocks in two lanes, the second on the second core where it runs, each lane's
        // row sums apart and added at the end: the same bits on one core or two.
        let (first, second) = parallel::join(|| sweep.lane(0), || sweep.lane(1));
        Some(first.iter().zip(&second).map(|(x, y)| x + y).collect())
    }
}

/// Whether a shifted LLᴴ's claim holds by its measured residual, for the certificates' fallback
/// (`certify_cholesky`, planar and 3D): `measure(state, chunk)` bounds the residual of the LLᴴ
/// at hand ([`SparseFactor::llt_residual_bound`]), `allowance` is what its shift α gave the
/// factorization's rounding (`None`: the LLᴴ at hand is not the one to check; then
/// `again(state, 0.0)` factors it first). By the wide chunks, then the narrow; where the
/// residual shown exceeds the allowance, `again(state, rounding)` factors once more with that
/// much allowed (twice the residual shown; the new allowance, or `None` where that LLᴴ fails),
/// measured again.
pub fn within_allowance<S>(
    state: &mut S,
    allowance: Option<f64>,
    measure: impl Fn(&S, Chunk) -> Option<f64>,
    mut again: impl FnMut(&mut S, f64) -> Option<f64>,
) -> bool {
    let Some(allowance) = allowance.or_else(|| again(state, 0.0)) else {
        return false;
    };
    let (mut allowance, mut shown) = (allowance, f64::INFINITY);
    for retry in [false, true] {
        if retry {
            match shown
                .is_finite()
                .then(|| again(state, 2.0 * shown))
                .flatten()
            {
                Some(a) => allowance = a,
                None => return false,
            }
        }
        for chunk in [Chunk::Wide, Chunk::Narrow] {
            match measure(state, chunk) {
                Some(r) if r <= allowance => return true,
                Some(r) => shown = shown.min(r),
                None => return false,
            }
        }
    }
    false
}

/// What the lanes of [`SparseFactor::residual_row_sums`] share: A (one triangle, `lower` its
/// lower triangle in the factor's order), the factor's panels, the panel of each column and the
/// factor's values.
struct Sweep<'a, T> {
    a: SparseColMatRef<'a, usize, T>,
    lower: &'a LowerColumns,
    panels: &'a Panels<'a>,
    panel_of: &'a [u32],
    values: &'a [T],
    kind: Kind,
    chunk: usize,
}

impl<T: Double> Sweep<'_, T> {
    /// The row sums of |R̂| over the blocks of lane `lane` (every other block of every target,
    /// in the order of the sweep), each block's residual in full.
    fn lane(&self, lane: usize) -> Vec<f64> {
        let (panels, values, dim) = (self.panels, self.values, self.panel_of.len());
        let n = panels.len();
        // Panels waiting for target s: a list per panel through `next`, with the position in
        // `below` of each one's first row not yet reached.
        const NONE: u32 = u32::MAX;
        let mut head = vec![NONE; n];
        let mut next = vec![NONE; n];
        let mut reached = vec![0u32; n];
        // The position of each row in the target's rows.
        let mut position = vec![0u32; dim];
        let mut row_sums = vec![0.0f64; dim];
        let mut block: Vec<Accumulator> = Vec::new();
        let mut sources: Vec<(usize, usize, usize)> = Vec::new();
        let mut work = Work::<T>::new(self.kind, self.chunk);
        let mut count = 0usize;
        for s in 0..n {
            let target = panels.panel(s);
            // The panels whose rows meet s's columns, at positions p1..p2 of their `below`.
            sources.clear();
            let mut t = head[s];
            while t != NONE {
                let (tu, following) = (t as usize, next[t as usize]);
                let below = panels.panel(tu).below;
                let p1 = reached[tu] as usize;
                let p2 = p1 + below[p1..].partition_point(|&r| r < target.end);
                sources.push((tu, p1, p2));
                if p2 < below.len() {
                    let u = self.panel_of[below[p2]] as usize;
                    reached[tu] = p2 as u32;
                    next[tu] = head[u];
                    head[u] = t;
                }
                t = following;
            }
            if let Some(&r) = target.below.first() {
                let u = self.panel_of[r] as usize;
                next[s] = head[u];
                head[u] = s as u32;
            }
            let rows = target.rows();
            let mut positioned = false;
            for c1 in (0..target.width()).step_by(BLOCK) {
                count += 1;
                if count % 2 != lane {
                    continue;
                }
                if !positioned {
                    for q in 0..rows {
                        position[target.row(q)] = q as u32;
                    }
                    positioned = true;
                }
                let c2 = (c1 + BLOCK).min(target.width());
                block.clear();
                block.resize(rows * (c2 - c1), [0.0; 4]);
                let mut into = Into {
                    block: &mut block,
                    position: &position,
                    rows,
                    c1,
                    begin: target.begin,
                };
                work.own(&target, values, c1, c2, &mut into);
                for &(t, p1, p2) in &sources {
                    let source = panels.panel(t);
                    // Its rows in the block's columns, then all its rows below them.
                    let below = &source.below[p1..p2];
                    let q1 = p1 + below.partition_point(|&r| r < target.begin + c1);
                    let q2 = p1 + below.partition_point(|&r| r < target.begin + c2);
                    if q1 < q2 {
                        work.source(&source, values, q1, q2, &mut into);
                    }
                }
                // − A, then the moduli into the row sums (each entry below the diagonal into its
                // row's and its column's).
                let lower = self.lower;
                for c in c1..c2 {
                    let j = target.begin + c;
                    let column = &mut block[(c - c1) * rows..(c - c1 + 1) * rows];
                    for &(row, entry) in &lower.entries[lower.start[j]..lower.start[j + 1]] {
                        let i = (row & !CONJ) as usize;
                        let (re, im) = self.a.val()[entry as usize].parts();
                        let im = if row & CONJ != 0 { -im } else { im };
                        add::<true>(&mut column[position[i] as usize], -re, -im);
                    }
                    for (q, acc) in column.iter().enumerate().skip(c) {
                        let r = (acc[0] + acc[1]).abs() + (acc[2] + acc[3]).abs();
                        let i = target.row(q);
                        row_sums[i] += r;
                        if i != j {
                            row_sums[j] += r;
                        }
                    }
                }
            }
        }
        row_sums
    }
}

/// c with each entry of the computed residual within c·(|L||D||Lᴴ|)_ij of the exact one: each
/// chunk's dot product within √2·γ_{2K} (real: γ_K) of the moduli of its terms, whose factors
/// d_l·L_il are rounded once more (u); their double-double sums add u² terms.
fn chunk_allowance<T: Double>(chunk: Chunk) -> f64 {
    let k = if T::COMPLEX { 2 } else { 1 } * chunk.columns();
    std::f64::consts::SQRT_2 * gamma(k) * (1.0 + U) + U
}

/// Where a product's entries go: the target's double-double `block` (its `rows` × the columns
/// `c1..` of the target, which begins at column `begin`), rows by their `position`.
struct Into<'a> {
    block: &'a mut [Accumulator],
    position: &'a [u32],
    rows: usize,
    c1: usize,
    begin: usize,
}

/// The dense products' room, kept from one to the next, for factors of one kind.
struct Work<T> {
    kind: Kind,
    /// The columns per product ([`Chunk`]).
    chunk: usize,
    /// d_l·L_il for the chunk's columns l, the rows reached.
    scaled: Mat<T>,
    /// L_jl for the block's columns j.
    picked: Mat<T>,
    product: Mat<T>,
}

impl<T: Double> Work<T> {
    fn new(kind: Kind, chunk: usize) -> Self {
        Work {
            kind,
            chunk,
            scaled: Mat::new(),
            picked: Mat::new(),
            product: Mat::new(),
        }
    }

    /// d_l of column l stored at `diagonal`: the pivot of an LDLᴴ, 1 for an LLᴴ.
    fn pivot(&self, values: &[T], diagonal: usize) -> f64 {
        match self.kind {
            Kind::Ldlt => values[diagonal].parts().0,
            Kind::Llt => 1.0,
        }
    }

    /// A panel's own columns' products into its block of columns c1..c2: column l meets the
    /// block's columns j ≥ l, its rows from l on.
    fn own(&mut self, p: &Panel<'_>, values: &[T], c1: usize, c2: usize, into: &mut Into<'_>) {
        let rows = p.rows();
        let kind = self.kind;
        for k0 in (0..c2).step_by(self.chunk) {
            let k1 = (k0 + self.chunk).min(p.width());
            // L's entry (q, l) of the panel (positions), as an explicit lower trapezoid (its
            // diagonal 1 for an LDLᴴ).
            let entry = |q: usize, l: usize| {
                if q < l {
                    T::zero_impl()
                } else if q == l && kind == Kind::Ldlt {
                    T::one_impl()
                } else {
                    values[p.first + l * rows + q]
                }
            };
            let (top, j0) = (k0, c1.max(k0));
            let pivots: Vec<f64> = (k0..k1)
                .map(|l| self.pivot(values, p.first + l * rows + l))
                .collect();
            fill(&mut self.scaled, rows - top, k1 - k0, |q, l| {
                entry(top + q, k0 + l).times(pivots[l])
            });
            fill(&mut self.picked, c2 - j0, k1 - k0, |q, l| {
                entry(j0 + q, k0 + l)
            });
            self.multiply();
            for jc in 0..c2 - j0 {
                // Column j of the block, its rows from j down (j ≥ top).
                let j = j0 + jc;
                let column = &mut into.block[(j - into.c1) * rows..][..rows];
                for (q, acc) in column.iter_mut().enumerate().skip(j) {
                    let (re, im) = self.product[(q - top, jc)].parts();
                    add::<true>(acc, re, im);
                }
            }
        }
    }

    /// A source panel's products into the target's block: its rows at positions q1..q2 of
    /// `below` are the block's columns, its rows from q1 on the block's rows.
    fn source(&mut self, p: &Panel<'_>, values: &[T], q1: usize, q2: usize, into: &mut Into<'_>) {
        let (rows, width) = (p.rows(), p.width());
        let (top, picked) = (width + q1, q2 - q1);
        for k0 in (0..width).step_by(self.chunk) {
            let k1 = (k0 + self.chunk).min(width);
            let pivots: Vec<f64> = (k0..k1)
                .map(|l| self.pivot(values, p.first + l * rows + l))
                .collect();
            fill(&mut self.scaled, rows - top, k1 - k0, |q, l| {
                values[p.first + (k0 + l) * rows + top + q].times(pivots[l])
            });
            fill(&mut self.picked, picked, k1 - k0, |q, l| {
                values[p.first + (k0 + l) * rows + top + q]
            });
            self.multiply();
            for jc in 0..picked {
                let j = p.below[q1 + jc];
                let column = &mut into.block[(j - into.begin - into.c1) * into.rows..];
                for q in jc..rows - top {
                    let i = p.below[q1 + q];
                    let (re, im) = self.product[(q, jc)].parts();
                    add::<true>(&mut column[into.position[i] as usize], re, im);
                }
            }
        }
    }

    /// product = scaled · pickedᴴ.
    fn multiply(&mut self) {
        let (m, n) = (self.scaled.nrows(), self.picked.nrows());
        self.product.resize_with(m, n, |_, _| T::zero_impl());
        matmul_with_conj(
            self.product.as_mut(),
            Accum::Replace,
            self.scaled.as_ref(),
            Conj::No,
            self.picked.as_ref().transpose(),
            Conj::Yes,
            T::one_impl(),
            Par::Seq,
        );
    }
}

/// `m` reshaped to rows × cols, every entry (i, j) set to f(i, j) (faer's `resize_with` fills only
/// the entries it adds).
fn fill<T: Double>(m: &mut Mat<T>, rows: usize, cols: usize, f: impl Fn(usize, usize) -> T) {
    m.resize_with(rows, cols, |_, _| T::zero_impl());
    for j in 0..cols {
        for (i, v) in m.col_mut(j).iter_mut().enumerate() {
            *v = f(i, j);
        }
    }
}

/// The top bit of [`LowerColumns`]' row: the entry is the conjugate of the stored one.
const CONJ: u32 = 1 << 31;

/// A's lower triangle in the factor's order, column by column: column j's entries are
/// `entries[start[j]..start[j + 1]]`, each (row, with [`CONJ`] where the stored entry is
/// conjugated; index of the stored entry in `a`).
struct LowerColumns {
    start: Vec<usize>,
    entries: Vec<(u32, u32)>,
}

/// [`LowerColumns`] from one stored triangle of Hermitian A, `inverse[old] = new` (none: the
/// identity).
fn lower_columns<T: Scalar>(
    a: SparseColMatRef<'_, usize, T>,
    inverse: Option<&[usize]>,
) -> LowerColumns {
    let new = |k: usize| inverse.map_or(k, |p| p[k]);
    let dim = a.nrows();
    let each = |f: &mut dyn FnMut(usize, usize, usize)| {
        let (cp, ri) = (a.symbolic().col_ptr(), a.symbolic().row_idx());
        for c in 0..a.ncols() {
            for (e, &r) in ri.iter().enumerate().take(cp[c + 1]).skip(cp[c]) {
                f(r, c, e);
            }
        }
    };
    let mut start = vec![0usize; dim + 1];
    each(&mut |r, c, _| start[new(r).min(new(c)) + 1] += 1);
    for k in 0..dim {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut entries = vec![(0u32, 0u32); start[dim]];
    each(&mut |r, c, e| {
        let (kr, kc) = (new(r), new(c));
        // Stored (r, c) is A_rc; below the diagonal in the new order it is A_rc at (kr, kc) or
        // its conjugate A_cr at (kc, kr).
        let (row, col, conj) = if kr >= kc {
            (kr, kc, 0)
        } else {
            (kc, kr, CONJ)
        };
        entries[fill[col]] = (row as u32 | conj, e as u32);
        fill[col] += 1;
    });
    LowerColumns { start, entries }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::factor::Layout;
    use crate::linalg::rng::Rng;
    use faer::Side;
    use faer::fx128;
    use faer::sparse::{SparseColMat, Triplet};

    /// An indefinite Hermitian matrix on a 14 × 12 grid with a few long edges (upper triangle):
    /// random off-diagonal entries of modulus up to 1, the diagonal its row's sum less `shift`
    /// times a random factor in [0, 2), so that a share of the pivots is negative.
    fn indefinite<T: Double>(
        draw: impl Fn(&mut Rng) -> T,
        shift: f64,
        seed: u64,
    ) -> SparseColMat<usize, T> {
        let (a, b) = (14, 12);
        let dim = a * b;
        let mut rng = Rng::new(seed);
        let mut edges = Vec::new();
        for x in 0..a {
            for y in 0..b {
                let k = x * b + y;
                if x + 1 < a {
                    edges.push((k, k + b));
                }
                if y + 1 < b {
                    edges.push((k, k + 1));
                }
            }
        }
        for _ in 0..8 {
            let (u, v) = (
                (rng.next_u64() % dim as u64) as usize,
                (rng.next_u64() % dim as u64) as usize,
            );
            if u != v && !edges.contains(&(u.min(v), u.max(v))) {
                edges.push((u.min(v), u.max(v)));
            }
        }
        let mut sums = vec![0.0; dim];
        let mut triplets = Vec::new();
        for &(u, v) in &edges {
            let w = draw(&mut rng);
            sums[u] += w.modulus();
            sums[v] += w.modulus();
            triplets.push(Triplet::new(u, v, w));
        }
        for (k, s) in sums.iter().enumerate() {
            let d = s - shift * 2.0 * rng.uniform();
            triplets.push(Triplet::new(k, k, T::from_f64_impl(d)));
        }
        SparseColMat::try_new_from_triplets(dim, dim, &triplets).unwrap()
    }

    /// max_i Σ_j |(L D Lᴴ − P A Pᵀ)_ij| in double-double from the factor's columns as
    /// [`SparseFactor::visit_ldlt_columns`] (`ldlt`) or [`SparseFactor::visit_llt_columns`]
    /// (D = I) gives them and A's dense upper triangle, and the largest row sum of |L||D||Lᴴ|.
    fn dense_residual<T: Double>(
        f: &SparseFactor<T>,
        a: &SparseColMat<usize, T>,
        ldlt: bool,
    ) -> (f64, f64) {
        let dim = f.dim();
        let dd = fx128::from_f64;
        // L's rows as (column, value) lists, D, and PAPᵀ dense.
        let mut rows: Vec<Vec<(usize, T)>> = vec![Vec::new(); dim];
        let mut d = vec![1.0; dim];
        if ldlt {
            let values = f.factor_values(true);
            f.visit_ldlt_columns(|j, r, first| {
                d[j] = values[first].parts().0;
                rows[j].push((j, T::from_f64_impl(1.0)));
                for (q, &i) in r.iter().enumerate().skip(1) {
                    rows[i].push((j, values[first + q]));
                }
            });
        } else {
            f.visit_llt_columns(|j, r, values| {
                for (&i, &v) in r.iter().zip(values) {
                    rows[i].push((j, v));
                }
            });
        }
        let order = f.order();
        let mut at = vec![0; dim];
        for (new, &old) in order.iter().enumerate() {
            at[old] = new;
        }
        let mut dense = vec![(0.0, 0.0); dim * dim];
        let (cp, ri) = (a.symbolic().col_ptr(), a.symbolic().row_idx());
        for c in 0..dim {
            for e in cp[c]..cp[c + 1] {
                let (re, im) = a.val()[e].parts();
                let (i, j) = (at[ri[e]], at[c]);
                dense[i * dim + j] = (re, im);
                dense[j * dim + i] = (re, -im);
            }
        }
        let (mut worst, mut product) = (0.0f64, 0.0f64);
        for i in 0..dim {
            let (mut sum, mut abs) = (0.0, 0.0);
            for j in 0..dim {
                let (mut re, mut im) = (dd(-dense[i * dim + j].0), dd(-dense[i * dim + j].1));
                for &(m, lim) in &rows[i] {
                    if let Some(&(_, ljm)) = rows[j].iter().find(|(c, _)| *c == m) {
                        let ((ar, ai), (br, bi)) = (lim.parts(), ljm.parts());
                        // L_im d_m conj(L_jm).
                        let (pr, pi) = (dd(ar) * dd(d[m]), dd(ai) * dd(d[m]));
                        re = re + pr * dd(br) + pi * dd(bi);
                        im = im + pi * dd(br) - pr * dd(bi);
                        abs += (ar * ar + ai * ai).sqrt() * d[m].abs() * (br * br + bi * bi).sqrt();
                    }
                }
                let (re, im) = (re.0 + re.1, im.0 + im.1);
                sum += (re * re + im * im).sqrt();
            }
            worst = worst.max(sum);
            product = product.max(abs);
        }
        (worst, product)
    }

    /// Factors of `a` to test, each with the chunk to measure it by: simplicial and supernodal
    /// in a random order, AMD's and the identity's, both chunks on the supernodal ones.
    fn factors<T: Double>(a: &SparseColMat<usize, T>, seed: u64) -> Vec<(SparseFactor<T>, Chunk)> {
        let dim = a.nrows();
        let mut rng = Rng::new(seed);
        let mut order: Vec<usize> = (0..dim).collect();
        for k in (1..dim).rev() {
            order.swap(k, (rng.next_u64() % (k as u64 + 1)) as usize);
        }
        let analyzed = || SparseFactor::analyze_ordered(a.symbolic(), &order, Layout::Supernodal);
        vec![
            (
                SparseFactor::analyze_ordered(a.symbolic(), &order, Layout::Simplicial),
                Chunk::Wide,
            ),
            (analyzed(), Chunk::Wide),
            (analyzed(), Chunk::Narrow),
            (SparseFactor::analyze(a.symbolic()), Chunk::Wide),
            (
                SparseFactor::analyze_in_order(a.symbolic(), Side::Upper, Layout::Supernodal),
                Chunk::Narrow,
            ),
        ]
    }

    /// Each of [`factors`] of `a`, by LDLᴴ (`ldlt`, `a` indefinite) or LLᴴ: the bound holds
    /// the dense residual (in double-double) from above and exceeds it by no more than its own
    /// allowance: √2 for |re| + |im|, and c·|L||D||Lᴴ| both for the computed residual's rounding
    /// and for the bound's allowance of it.
    fn bound_holds_the_residual<T: Double>(a: &SparseColMat<usize, T>, seed: u64, ldlt: bool) {
        for (mut f, chunk) in factors(a, seed) {
            let bound = if ldlt {
                f.ldlt(a.as_ref()).expect("no zero pivot");
                assert!(f.inertia_below(0.0) > 0, "indefinite");
                f.ldlt_residual_bound(a.as_ref(), chunk).unwrap()
            } else {
                f.llt(a.as_ref()).expect("positive definite");
                f.llt_residual_bound(a.as_ref(), chunk).unwrap()
            };
            let (exact, product) = dense_residual(&f, a, ldlt);
            assert!(exact > 0.0 && bound >= exact, "{bound} < {exact}");
            let allowance = 2.44 * chunk_allowance::<T>(chunk) * product;
            assert!(bound <= 1.42 * exact + allowance, "{bound} vs {exact}");
        }
    }

    /// [`bound_holds_the_residual`] for real and complex matrices: LDLᴴ of indefinite ones (a
    /// shift of 1.5 puts a share of the pivots below zero), LLᴴ of positive definite ones (the
    /// diagonal above its row's sum), simplicial and supernodal factors, in a random order,
    /// AMD's and the identity.
    #[test]
    fn the_bound_holds_the_residual_of_the_stored_factors() {
        let complex =
            |rng: &mut Rng| c64::new(2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0) * 0.7;
        let real = |rng: &mut Rng| 2.0 * rng.uniform() - 1.0;
        for seed in 1..4 {
            bound_holds_the_residual(&indefinite(complex, 1.5, seed), seed, true);
            bound_holds_the_residual(&indefinite(real, 1.5, seed), seed, true);
            bound_holds_the_residual(&indefinite(complex, -0.5, seed), seed, false);
            bound_holds_the_residual(&indefinite(real, -0.5, seed), seed, false);
        }
    }

    /// Against another matrix than the one factored, A + E with every stored entry moved by a
    /// random ε of modulus up to 1e-8 (off the diagonal complex, so half of them conjugated
    /// where the order puts them), each row sum of the residual is that of E (as |re| + |im|,
    /// E = (A + E) − A exact in doubles) to within the residual of A itself (dense, in
    /// double-double) and the rounding allowance: each entry lands at its row and column,
    /// conjugated where it should be.
    #[test]
    fn the_residual_against_a_perturbed_matrix_measures_the_perturbation() {
        let draw =
            |rng: &mut Rng| c64::new(2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0) * 0.7;
        let a = indefinite(draw, 1.0, 7);
        let mut rng = Rng::new(11);
        let mut b = a.clone();
        let dim = a.nrows();
        let mut moved = vec![0.0; dim];
        let (cp, ri) = (
            a.symbolic().col_ptr().to_vec(),
            a.symbolic().row_idx().to_vec(),
        );
        for c in 0..dim {
            for (e, &r) in ri.iter().enumerate().take(cp[c + 1]).skip(cp[c]) {
                let im = if r == c {
                    0.0
                } else {
                    1e-8 * (2.0 * rng.uniform() - 1.0)
                };
                let v = &mut b.val_mut()[e];
                *v += c64::new(1e-8 * (2.0 * rng.uniform() - 1.0), im);
                let d = *v - a.val()[e];
                moved[r] += d.re.abs() + d.im.abs();
                if r != c {
                    moved[c] += d.re.abs() + d.im.abs();
                }
            }
        }
        for (mut f, chunk) in factors(&a, 7) {
            f.ldlt(a.as_ref()).unwrap();
            let (exact, product) = dense_residual(&f, &a, true);
            let own = exact + 1.01 * chunk_allowance::<c64>(chunk) * product;
            let sums = f.residual_row_sums(b.as_ref(), Kind::Ldlt, chunk).unwrap();
            for (new, &old) in f.order().iter().enumerate() {
                assert!(moved[old] > 1e-8);
                assert!(
                    (sums[new] - moved[old]).abs() <= 1.42 * own,
                    "{} {} {own}",
                    sums[new],
                    moved[old]
                );
            }
        }
    }
}
