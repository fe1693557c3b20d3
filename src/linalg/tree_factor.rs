//! A supernodal LLᴴ factorization, A = L Lᴴ, or LDLᴴ without pivoting, A = L D Lᴴ with L unit
//! lower triangular, on two cores: the supernodes of the elimination tree split into two sides
//! of whole subtrees ([`TreeSplit`], balanced by multiply-adds here) and a top set where the
//! sides meet, as for the solves ([`super::tree_solve`]).
//!
//! Each supernode s is computed left-looking, as faer computes it: A's columns of s scattered
//! into its dense block, the update L_d,below · L_d,midᴴ (L_d,below · D_d · L_d,midᴴ for LDLᴴ)
//! of every descendant d whose pattern has rows in s's columns subtracted, then the dense LLᴴ
//! (LDLᴴ) of the diagonal block and the triangular solve of the rows below (for LDLᴴ with the
//! unit diagonal, then each column divided by its pivot). The factor is stored as faer stores
//! it: for LDLᴴ, D on the diagonal of each supernode's block and L below it. A side supernode's
//! descendants are all on its side, so the two sides are computed side by side. A side's updates
//! of the top set are computed on that side too: side 0's into the top blocks of L themselves,
//! side 1's into a room of its own. The top set is then computed in ascending order on one core,
//! each block adding side 1's room to side 0's updates and A's columns, then subtracting its top
//! descendants' updates.
//!
//! The order of every sum is fixed by the split alone, so the factor is the same whatever the
//! thread count: on one core (or with the second one busy) the sides are computed one after the
//! other. It is not faer's to the last bit. faer subtracts each update through a product that
//! gathers and scatters rows inside its kernel, which is not public; here an update is
//! subtracted in place, one product of faer's per block of contiguous rows and columns of s
//! (where these blocks hold [`MIN_ENTRIES_PER_PRODUCT`] entries on average), else computed as a
//! product of its own and subtracted entry by entry. On the 3D Newton systems that is as fast as
//! faer's on one core; on the planar certificate's complex LDLᴴ (city10000) faster than faer's
//! supernodal LDLᴴ, on one core as on two. faer's supernodal factorization is sequential, and its
//! parallel mode splits the dense kernels inside a supernode, not the tree; written here for
//! that reason.
//!
//! The LDLᴴ's a-posteriori backward error bound
//! ([`super::factor::SparseFactor::ldlt_backward_error`]) holds for these factors as for faer's:
//! each entry of L D Lᴴ is summed here in an order of its own, and each term L_il·d_l·L̄_jl is a
//! product rounded twice, as faer rounds it; the bound allows any order.

use super::tree_solve::TreeSplit;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{
    LdltError, LdltParams, LdltRegularization, cholesky_in_place as ldlt_in_place,
    cholesky_in_place_scratch as ldlt_in_place_scratch,
};
use faer::linalg::cholesky::llt::factor::{
    LltError, LltParams, LltRegularization, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_unit_lower_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::traits::math_utils::{conj, from_real, mul_real, real, recip, sqrt};
use faer::{Accum, Conj, Index, MatMut, MatRef, Par, Spec};

/// The scalars of the factorization: those of the split solve.
pub use super::tree_solve::Entry;

/// The fewest entries per product (on average) for which an update is subtracted in place,
/// block by block of contiguous rows and columns; below, it is one product of its own, then
/// subtracted entry by entry.
const MIN_ENTRIES_PER_PRODUCT: usize = 64;

/// The widest supernode (in columns) whose LLᴴ ends by plain loops ([`llt_by_columns`]) instead
/// of faer's dense Cholesky and triangular solve, whose dispatch costs more than such a block's
/// few multiply-adds (cityTrees10000's Newton systems: 4454 supernodes, all but one at most 12
/// columns wide). Whole process against faer's kernels for every supernode (medians of 21
/// interleaved ratios), loops up to 8, 16 and 32 columns: cityTrees10000 0.99, 0.95, 0.95;
/// M3500 1.01, 1.01, 1.00; city10000 0.99, 0.99, 1.01; torus3D 1.01, 1.00, 1.04. The LDLᴴ keeps
/// faer's kernels.
pub const LOOP_MAX_COLUMNS: usize = 16;

/// The end of a supernode's LLᴴ, column by column: its block (`rows` × `k`, stored by columns,
/// the diagonal block's rows first), its updates subtracted, becomes [L_ss; L_bs] with
/// L_ss L_ssᴴ = A_ss and L_bs = A_bs L_ss⁻ᴴ: for each column j, l_jj = √(a_jj − Σ_{p<j} |l_jp|²)
/// and l_ij = (a_ij − Σ_{p<j} l_ip conj(l_jp)) / l_jj for the rows i below it, the diagonal
/// block's and those below alike. The strictly upper triangle is not touched. `Err(j)` where
/// the pivot of column j is not positive (or not a number). A standard Cholesky: each entry a
/// sum of its products in some order, a square root, a product with the rounded reciprocal of
/// l_jj, as in faer's dense kernel, so the backward-error bounds that the certificates' shifted
/// LLᴴ proofs assume (`try_eta`'s α) hold for it as for faer's.
pub(crate) fn llt_by_columns<T: Entry>(
    block: &mut [T],
    rows: usize,
    k: usize,
) -> Result<(), usize> {
    for j in 0..k {
        let (done, rest) = block.split_at_mut(j * rows);
        let column = &mut rest[j..rows];
        for p in 0..j {
            let left = &done[p * rows + j..(p + 1) * rows];
            let c = conj(&left[0]);
            for (x, &l) in column.iter_mut().zip(left) {
                *x -= l * c;
            }
        }
        let pivot = real(&column[0]);
        let zero = <T::Real as faer::traits::ComplexField>::zero_impl();
        if pivot.partial_cmp(&zero) != Some(std::cmp::Ordering::Greater) {
            return Err(j);
        }
        let diagonal = sqrt(&pivot);
        column[0] = from_real(&diagonal);
        let inverse = recip(&diagonal);
        for x in &mut column[1..] {
            *x = mul_real(x, &inverse);
        }
    }
    Ok(())
}

/// The factorization failed at the pivot of column `index`: not positive (LLᴴ), or zero (LDLᴴ).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FailedPivot {
    pub index: usize,
}

/// Which factorization: LLᴴ, or LDLᴴ without pivoting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Llt,
    Ldlt,
}

/// A supernodal LLᴴ or LDLᴴ split between two cores ([`FactorSplit::new`]).
#[derive(Debug, Clone)]
pub struct FactorSplit {
    split: TreeSplit,
    /// The supernodes d < s whose patterns have rows in supernode s's columns, ascending:
    /// `updaters[start[s]..start[s + 1]]`.
    start: Vec<usize>,
    updaters: Vec<u32>,
    /// The top supernodes, ascending, and the offset of each one's block in a side's room for
    /// its updates of the top set (`offset[k]..offset[k + 1]`).
    top: Vec<u32>,
    offset: Vec<usize>,
    /// The most rows of an update and the widest supernode, for the workspaces.
    max_below: usize,
    max_cols: usize,
    /// [`MIN_ENTRIES_PER_PRODUCT`] (another in tests, to force either way of subtracting).
    pub(crate) min_entries_per_product: usize,
}

impl FactorSplit {
    /// The split of `symbolic`'s factorization balanced by each supernode's multiply-adds (its
    /// own block's k³/3 + k²m and its updates of its ancestors); `None` where they total less
    /// than `min_work`, or where the tree does not split ([`TreeSplit::by_weight`]).
    pub fn new<I: Index>(symbolic: &SymbolicSupernodalCholesky<I>, min_work: f64) -> Option<Self> {
        let ns = symbolic.n_supernodes();
        let end = symbolic.supernode_end();
        let begin = symbolic.supernode_begin();
        // Each supernode's updates: its pattern's rows grouped by the supernode holding them.
        let mut work = vec![0.0f64; ns];
        for d in 0..ns {
            let k = end[d].zx() - begin[d].zx();
            let m = symbolic.supernode(d).pattern().len();
            work[d] = (k * k * k) as f64 / 3.0 + (k * k * m) as f64;
            for (_, below, mid) in updated(symbolic, d) {
                work[d] += (below * mid * k) as f64;
            }
        }
        let split = TreeSplit::by_weight(symbolic, &|s| work[s], min_work)?;
        Some(Self::with_split(symbolic, split))
    }

    /// The factorization without a split: every supernode on one side, one after another, on
    /// one core (the same loops and kernels as a split's, in the same order within a side).
    pub fn sequential<I: Index>(symbolic: &SymbolicSupernodalCholesky<I>) -> Self {
        Self::with_split(symbolic, TreeSplit::one_side(symbolic))
    }

    /// The update lists, the top set's room and the workspaces' sizes for `split`.
    fn with_split<I: Index>(symbolic: &SymbolicSupernodalCholesky<I>, split: TreeSplit) -> Self {
        let ns = symbolic.n_supernodes();
        let end = symbolic.supernode_end();
        let begin = symbolic.supernode_begin();
        let mut count = vec![0usize; ns + 1];
        let mut max_below = 0;
        for d in 0..ns {
            for (s, below, _) in updated(symbolic, d) {
                count[s + 1] += 1;
                max_below = max_below.max(below);
            }
        }
        for s in 0..ns {
            count[s + 1] += count[s];
        }
        let start = count;
        let mut next = start.clone();
        let mut updaters = vec![0u32; start[ns]];
        for d in 0..ns {
            for (s, _, _) in updated(symbolic, d) {
                updaters[next[s]] = d as u32;
                next[s] += 1;
            }
        }
        let top: Vec<u32> = (0..ns)
            .filter(|&s| split.side_of(s).is_none())
            .map(|s| s as u32)
            .collect();
        let mut offset = vec![0usize];
        for &s in &top {
            let s = s as usize;
            let k = end[s].zx() - begin[s].zx();
            let rows = k + symbolic.supernode(s).pattern().len();
            offset.push(offset.last().unwrap() + rows * k);
        }
        let max_cols = (0..ns)
            .map(|s| end[s].zx() - begin[s].zx())
            .max()
            .unwrap_or(0);
        FactorSplit {
            split,
            start,
            updaters,
            top,
            offset,
            max_below,
            max_cols,
            min_entries_per_product: MIN_ENTRIES_PER_PRODUCT,
        }
    }

    /// The supernodes of each side.
    pub fn sides(&self) -> &[Vec<u32>; 2] {
        self.split.sides()
    }

    /// Whether both sides have supernodes: false for [`Self::sequential`].
    pub fn splits(&self) -> bool {
        self.split.sides().iter().all(|side| !side.is_empty())
    }

    /// The number of supernodes in the top set.
    pub fn top(&self) -> usize {
        self.top.len()
    }

    /// The supernodes whose patterns have rows in supernode s's columns, ascending.
    fn updaters(&self, s: usize) -> &[u32] {
        &self.updaters[self.start[s]..self.start[s + 1]]
    }

    /// The values of L (faer's layout for `symbolic`, so that faer's solves and
    /// [`TreeSplit::solve_in_place`] read them) for `a_lower`, A's lower triangle in the
    /// factor's own order: LLᴴ, or for [`Kind::Ldlt`] the LDLᴴ without pivoting (each pivot on
    /// its supernode's diagonal, L's entries below it; `Err` on a zero pivot). The sides run
    /// side by side where `two_cores` ([`super::parallel::join_or_offer`]: side 1 offered to the
    /// second core where it is busy building ahead), else one after the other; the values are
    /// the same either way.
    pub fn factorize<T: Entry, I: Index>(
        &self,
        kind: Kind,
        symbolic: &SymbolicSupernodalCholesky<I>,
        values: &mut [T],
        a_lower: SparseColMatRef<'_, I, T>,
        room: &mut SplitRoom<T>,
        two_cores: bool,
    ) -> Result<(), FailedPivot> {
        assert_eq!(values.len(), symbolic.len_val());
        assert_eq!(a_lower.nrows(), symbolic.nrows());
        values.fill(T::zero_impl());
        let shared = Shared(values.as_mut_ptr());
        let side = |side: usize, work: &mut Workspace<T>, room: &mut Vec<T>| {
            work.ready(self, symbolic.nrows());
            for &s in self.split.sides()[side].iter() {
                // SAFETY: s is this side's; it reads its descendants, all on this side.
                unsafe {
                    work.supernode(kind, self, symbolic, &shared, a_lower, s as usize, None)?
                };
            }
            // This side's updates of the top set, each top supernode's block in turn: side 0's
            // in the top blocks of L themselves (zero so far), side 1's in a room of its own.
            if side == 1 {
                room.clear();
                room.resize(*self.offset.last().unwrap(), T::zero_impl());
            }
            for (k, &s) in self.top.iter().enumerate() {
                let s = s as usize;
                let block = if side == 0 {
                    // SAFETY: s's block, which no other thread touches before the top set.
                    unsafe { shared.block(symbolic, s) }
                } else {
                    &mut room[self.offset[k]..self.offset[k + 1]]
                };
                work.map_rows(symbolic, s);
                for &d in self.updaters(s) {
                    if self.split.side_of(d as usize) == Some(side) {
                        // SAFETY: d is this side's, computed above.
                        unsafe { work.update(kind, self, symbolic, &shared, block, s, d as usize) };
                    }
                }
                work.unmap_rows(symbolic, s);
            }
            Ok::<(), FailedPivot>(())
        };
        let SplitRoom { work, room } = room;
        let [work0, work1] = work;
        let (done0, done1) = if two_cores {
            super::parallel::join_or_offer(
                || side(0, work0, &mut Vec::new()),
                || side(1, work1, room),
            )
        } else {
            let done0 = side(0, work0, &mut Vec::new());
            (done0, side(1, work1, room))
        };
        done0?;
        done1?;
        for k in 0..self.top.len() {
            let s = self.top[k] as usize;
            // SAFETY: one thread from here on.
            unsafe {
                work0.supernode(
                    kind,
                    self,
                    symbolic,
                    &shared,
                    a_lower,
                    s,
                    Some(&room[self.offset[k]..self.offset[k + 1]]),
                )?;
            }
        }
        Ok(())
    }
}

/// The supernodes that supernode d updates, ascending, each as (s, below, mid): its pattern's
/// rows from s's first column on (`below`), of which `mid` are s's columns.
fn updated<I: Index>(
    symbolic: &SymbolicSupernodalCholesky<I>,
    d: usize,
) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
    let end = symbolic.supernode_end();
    let pattern = symbolic.supernode(d).pattern();
    let mut i = 0;
    std::iter::from_fn(move || {
        let row = pattern.get(i)?.zx();
        let s = end.partition_point(|e| e.zx() <= row);
        let mid = pattern[i..].partition_point(|r| r.zx() < end[s].zx());
        let below = pattern.len() - i;
        i += mid;
        Some((s, below, mid))
    })
}

/// L's values, written by two threads at once in disjoint supernodes: each side writes its own
/// supernodes' blocks and reads its own descendants' only; the top set is written after both.
struct Shared<T>(*mut T);

impl<T> Shared<T> {
    /// Supernode s's block of L.
    ///
    /// # Safety
    /// Not read or written by another thread meanwhile.
    #[allow(clippy::mut_from_ref)]
    unsafe fn block<I: Index>(
        &self,
        symbolic: &SymbolicSupernodalCholesky<I>,
        s: usize,
    ) -> &mut [T] {
        let (begin, end) = (
            symbolic.col_ptr_for_val()[s].zx(),
            symbolic.col_ptr_for_val()[s + 1].zx(),
        );
        // SAFETY: inside L's values (faer's layout); exclusive by the caller's contract.
        unsafe { std::slice::from_raw_parts_mut(self.0.add(begin), end - begin) }
    }
}

// SAFETY: see the struct's documentation: the threads touch disjoint blocks.
unsafe impl<T: Send> Send for Shared<T> {}
// SAFETY: as above.
unsafe impl<T: Sync> Sync for Shared<T> {}

/// [`Workspace`]'s mark of a row outside the supernode being computed; factors of more rows are
/// not factored here ([`crate::linalg::factor::SparseFactor::prepare_factor_split`]).
pub const LOCAL_NONE: u32 = u32::MAX;

/// One thread's working memory: the local row of each global row of the supernode being
/// computed (32-bit: a factor of fewer than 2³² − 1 rows, [`LOCAL_NONE`] for rows outside it;
/// at 10⁶ planar poses a `usize` map per side was 23 MiB more), an update's product, and the
/// dense LLᴴ's scratch.
struct Workspace<T> {
    local: Vec<u32>,
    rows: Vec<usize>,
    runs: Vec<usize>,
    product: Vec<T>,
    /// An LDLᴴ update's left factor L_d,below · D_d.
    scaled: Vec<T>,
    /// The dense LLᴴ's and LDLᴴ's scratch, for supernodes of up to `cols` columns.
    mem: MemBuffer,
    cols: usize,
}

/// The working memory of [`FactorSplit::factorize`], kept from one
/// factorization to the next (its pages mapped once): each side's [`Workspace`] and its updates
/// of the top set.
pub struct SplitRoom<T> {
    work: [Workspace<T>; 2],
    room: Vec<T>,
}

impl<T: Entry> Default for SplitRoom<T> {
    fn default() -> Self {
        SplitRoom {
            work: [Workspace::empty(), Workspace::empty()],
            room: Vec::new(),
        }
    }
}

impl<T: Entry> Workspace<T> {
    fn empty() -> Self {
        Workspace {
            local: Vec::new(),
            rows: Vec::new(),
            runs: Vec::new(),
            product: Vec::new(),
            scaled: Vec::new(),
            mem: MemBuffer::new(StackReq::EMPTY),
            cols: 0,
        }
    }

    /// Room for `split`'s factorizations of dimension n (allocated once, kept after).
    fn ready(&mut self, split: &FactorSplit, n: usize) {
        if self.local.len() != n {
            self.local = vec![LOCAL_NONE; n];
        }
        if self.rows.len() < split.max_below {
            self.rows.resize(split.max_below, 0);
        }
        if self.cols < split.max_cols {
            self.cols = split.max_cols;
            self.mem = MemBuffer::new(
                cholesky_in_place_scratch::<T>(
                    split.max_cols,
                    Par::Seq,
                    Spec::<LltParams, T>::default(),
                )
                .or(ldlt_in_place_scratch::<T>(
                    split.max_cols,
                    Par::Seq,
                    Spec::<LdltParams, T>::default(),
                )),
            );
        }
    }

    /// Supernode s's rows below its columns, numbered as in its block.
    fn map_rows<I: Index>(&mut self, symbolic: &SymbolicSupernodalCholesky<I>, s: usize) {
        let k = symbolic.supernode_end()[s].zx() - symbolic.supernode_begin()[s].zx();
        for (i, row) in symbolic.supernode(s).pattern().iter().enumerate() {
            self.local[row.zx()] = (k + i) as u32;
        }
    }

    fn unmap_rows<I: Index>(&mut self, symbolic: &SymbolicSupernodalCholesky<I>, s: usize) {
        for row in symbolic.supernode(s).pattern() {
            self.local[row.zx()] = LOCAL_NONE;
        }
    }

    /// Subtracts d's update of supernode s, L_d,below · L_d,midᴴ (L_d,below · D_d · L_d,midᴴ for
    /// LDLᴴ), from `block` (s's block, column-major, rows mapped by [`Self::map_rows`]): its
    /// lower triangle in s's diagonal block and all of it below.
    ///
    /// # Safety
    /// d's block is computed and not written by another thread meanwhile.
    #[allow(clippy::too_many_arguments)]
    unsafe fn update<I: Index>(
        &mut self,
        kind: Kind,
        split: &FactorSplit,
        symbolic: &SymbolicSupernodalCholesky<I>,
        shared: &Shared<T>,
        block: &mut [T],
        s: usize,
        d: usize,
    ) {
        let (begin, end) = (symbolic.supernode_begin(), symbolic.supernode_end());
        let (s_start, s_end) = (begin[s].zx(), end[s].zx());
        let s_rows = block.len() / (s_end - s_start);
        let d_cols = end[d].zx() - begin[d].zx();
        let d_pattern = symbolic.supernode(d).pattern();
        let d_rows = d_cols + d_pattern.len();
        let first = d_pattern.partition_point(|r| r.zx() < s_start);
        let mid = d_pattern[first..].partition_point(|r| r.zx() < s_end);
        let below = d_pattern.len() - first;
        let at = symbolic.col_ptr_for_val()[d].zx();
        // SAFETY: d's block, read only (the caller's contract).
        let ld = unsafe { std::slice::from_raw_parts(shared.0.add(at), d_rows * d_cols) };
        let ld = MatRef::from_column_major_slice(ld, d_rows, d_cols);
        let ld_below = ld.subrows(d_cols + first, below);
        let ld_mid = ld.subrows(d_cols + first, mid);
        // The update's left factor: L_d,below, or L_d,below · D_d for LDLᴴ (the pivots on the
        // diagonal of d's block), as faer's supernodal LDLᴴ scales it.
        if kind == Kind::Ldlt {
            self.scaled.clear();
            for c in 0..d_cols {
                let pivot = real(&ld[(c, c)]);
                self.scaled
                    .extend(ld_below.col(c).iter().map(|v| mul_real(v, &pivot)));
            }
        }
        let left = match kind {
            Kind::Llt => ld_below,
            Kind::Ldlt => MatRef::from_column_major_slice(&self.scaled, below, d_cols),
        };
        // The rows of the update in s's block: increasing, as d's pattern is; the first `mid`
        // of them are s's columns as well.
        let rows = &mut self.rows[..below];
        for (local, row) in rows
            .iter_mut()
            .zip(d_pattern[first..].iter().map(|r| r.zx()))
        {
            *local = if row < s_end {
                row - s_start
            } else {
                self.local[row] as usize
            };
        }
        let s_cols = s_end - s_start;
        let mut ls = MatMut::from_column_major_slice_mut(block, s_rows, s_cols);
        let minus_one = -T::one_impl();
        // Runs of contiguous rows (split where s's columns end), `runs[r]..runs[r + 1]`; the
        // first `column_runs` of them are runs of s's columns too.
        let runs = &mut self.runs;
        runs.clear();
        runs.push(0);
        for i in 1..below {
            if i == mid || rows[i] != rows[i - 1] + 1 {
                runs.push(i);
            }
        }
        runs.push(below);
        let column_runs = runs.partition_point(|&i| i < mid);
        // The products of the update in place: one per pair of a column run and a row run at
        // or below it (its lower triangle where the two are the same run).
        let products: usize = (0..column_runs).map(|c| runs.len() - 1 - c).sum();
        if below * mid >= split.min_entries_per_product.saturating_mul(products) {
            for c in 0..column_runs {
                let (c0, c1) = (runs[c], runs[c + 1]);
                let rhs = ld_below.subrows(c0, c1 - c0).transpose();
                triangular::matmul_with_conj(
                    ls.rb_mut()
                        .submatrix_mut(rows[c0], rows[c0], c1 - c0, c1 - c0),
                    BlockStructure::TriangularLower,
                    Accum::Add,
                    left.subrows(c0, c1 - c0),
                    BlockStructure::Rectangular,
                    Conj::No,
                    rhs,
                    BlockStructure::Rectangular,
                    Conj::Yes,
                    minus_one,
                    Par::Seq,
                );
                for r in c + 1..runs.len() - 1 {
                    let (r0, r1) = (runs[r], runs[r + 1]);
                    matmul_with_conj(
                        ls.rb_mut()
                            .submatrix_mut(rows[r0], rows[c0], r1 - r0, c1 - c0),
                        Accum::Add,
                        left.subrows(r0, r1 - r0),
                        Conj::No,
                        rhs,
                        Conj::Yes,
                        minus_one,
                        Par::Seq,
                    );
                }
            }
            return;
        }
        if self.product.len() < below * mid {
            self.product.resize(below * mid, T::zero_impl());
        }
        let mut u =
            MatMut::from_column_major_slice_mut(&mut self.product[..below * mid], below, mid);
        matmul_with_conj(
            u.rb_mut(),
            Accum::Replace,
            left,
            Conj::No,
            ld_mid.transpose(),
            Conj::Yes,
            T::one_impl(),
            Par::Seq,
        );
        let product = &self.product[..below * mid];
        for j in 0..mid {
            let col = rows[j];
            let target = &mut block[col * s_rows..(col + 1) * s_rows];
            let (rows, column) = (&rows[j..], &product[j * below + j..(j + 1) * below]);
            for (&r, &v) in rows.iter().zip(column) {
                target[r] -= v;
            }
        }
    }

    /// Computes supernode s: A's columns, the updates of its descendants, its dense LLᴴ (LDLᴴ)
    /// and the solve of the rows below. For a top supernode, `side_1` is side 1's room for it: the
    /// block holds side 0's updates already, the room side 1's, and only the updates of top
    /// descendants are computed here.
    ///
    /// # Safety
    /// s's block is written by no other thread, and the descendants whose updates are computed
    /// here are computed and not written meanwhile.
    #[allow(clippy::too_many_arguments)]
    unsafe fn supernode<I: Index>(
        &mut self,
        kind: Kind,
        split: &FactorSplit,
        symbolic: &SymbolicSupernodalCholesky<I>,
        shared: &Shared<T>,
        a_lower: SparseColMatRef<'_, I, T>,
        s: usize,
        side_1: Option<&[T]>,
    ) -> Result<(), FailedPivot> {
        let (s_start, s_end) = (
            symbolic.supernode_begin()[s].zx(),
            symbolic.supernode_end()[s].zx(),
        );
        let k = s_end - s_start;
        let rows = k + symbolic.supernode(s).pattern().len();
        // SAFETY: s's block, this thread's alone (the caller's contract).
        let block = unsafe { shared.block(symbolic, s) };
        self.map_rows(symbolic, s);
        for j in s_start..s_end {
            let column = &mut block[(j - s_start) * rows..(j - s_start + 1) * rows];
            for (i, &v) in a_lower.row_idx_of_col(j).zip(a_lower.val_of_col(j)) {
                if i < j {
                    continue;
                }
                let local = if i < s_end {
                    i - s_start
                } else {
                    self.local[i] as usize
                };
                column[local] += v;
            }
        }
        if let Some(sum) = side_1 {
            // Side 1's updates, subtracted from zero in its room (side 0's are in the block).
            for (b, &u) in block.iter_mut().zip(sum) {
                *b += u;
            }
        }
        for &d in split.updaters(s) {
            let d = d as usize;
            if side_1.is_some() && split.split.side_of(d).is_some() {
                continue;
            }
            // SAFETY: d is a descendant of s, computed (the caller's contract).
            unsafe { self.update(kind, split, symbolic, shared, block, s, d) };
        }
        self.unmap_rows(symbolic, s);
        let mut ls = MatMut::from_column_major_slice_mut(block, rows, k);
        let (mut top, mut bottom) = ls.rb_mut().split_at_row_mut(k);
        let stack = MemStack::new(&mut self.mem);
        let failed = |index: usize| FailedPivot {
            index: index + s_start,
        };
        match kind {
            Kind::Llt if k <= LOOP_MAX_COLUMNS => {
                llt_by_columns(block, rows, k).map_err(failed)?;
            }
            Kind::Llt => {
                cholesky_in_place(
                    top.rb_mut(),
                    LltRegularization::default(),
                    Par::Seq,
                    stack,
                    Default::default(),
                )
                .map_err(|LltError::NonPositivePivot { index }| failed(index))?;
                solve_lower_triangular_in_place(
                    top.rb().conjugate(),
                    bottom.rb_mut().transpose_mut(),
                    Par::Seq,
                );
            }
            Kind::Ldlt => {
                // As faer's supernodal LDLᴴ: the dense LDLᴴ in place (D on the diagonal, L
                // below it, the upper triangle cleared), the rows below solved with the unit
                // triangle, then each column scaled by its pivot's reciprocal.
                ldlt_in_place(
                    top.rb_mut(),
                    LdltRegularization::default(),
                    Par::Seq,
                    stack,
                    Default::default(),
                )
                .map_err(|LdltError::ZeroPivot { index }| failed(index))?;
                for j in 1..k {
                    for i in 0..j {
                        top[(i, j)] = T::zero_impl();
                    }
                }
                solve_unit_lower_triangular_in_place(
                    top.rb().conjugate(),
                    bottom.rb_mut().transpose_mut(),
                    Par::Seq,
                );
                for j in 0..k {
                    let inverse = recip(&real(&top[(j, j)]));
                    for v in bottom.rb_mut().col_mut(j).iter_mut() {
                        *v = mul_real(v, &inverse);
                    }
                }
            }
        }
        Ok(())
    }
}
