//! A supernodal LLᴴ solve, L Lᴴ x = b, on one core ([`solve_sequential`]) or two
//! ([`TreeSplit`]): the supernodes of the elimination tree split into two sides of whole
//! subtrees, solved side by side, and a top set (their ancestors, where the sides meet) solved
//! on one core. Every entry of x goes through the operations of the sequential solve, on the
//! same operands and in the same order, so the two give the same bits:
//!
//! - forward, L y = b: supernode s solves its diagonal block and subtracts L_bs y_s from the
//!   rows below it, which are its ancestors'. A row of a side is updated by its descendants
//!   alone, all on that side, and each side runs in ascending order, as faer does. A row of the
//!   top set is updated from both sides: the sides keep those updates in a log, and the top set
//!   is then solved in ascending supernode order, each side supernode's logged updates applied
//!   at its place in that order, so each row sees its updates in faer's order;
//! - backward, Lᴴ x = y: the top set first, in descending order (its rows depend on top rows
//!   alone), then the two sides side by side, each in descending order, each reading rows of its
//!   own side and of the top set only.
//!
//! faer's solve is sequential, and its parallel mode (`Par::rayon`) parallelizes the dense
//! kernels inside a supernode, not the tree: at the sizes of pose graphs most supernodes are a
//! few columns wide, and the solve reads the factor once forward and once backward. Written here
//! for that reason. A supernode of more than [`LOOP_MAX_COLUMNS`] columns is solved by faer's
//! dense kernels, the operations of faer's own solve (`SupernodalLltRef::solve_in_place_with_conj`);
//! a narrower one by plain loops, without the dense kernels' dispatch, which costs more than
//! the few multiply-adds of such a supernode (one Newton solve of cityTrees10000, 4454
//! supernodes, all but one at most 12 columns wide: 0.45 ms against faer's 0.96 ms).

use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place_with_conj, solve_upper_triangular_in_place_with_conj,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::traits::ComplexField;
use faer::traits::math_utils::{conj, mul_real, real, recip};
use faer::{Accum, Conj, Index, MatMut, Par};

/// The scalars of the solve: faer's, with the arithmetic its solve and the loops apply to them.
pub trait Entry:
    ComplexField
    + Copy
    + Send
    + Sync
    + std::ops::Neg<Output = Self>
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::AddAssign
    + std::ops::SubAssign
{
}

impl<T> Entry for T where
    T: ComplexField
        + Copy
        + Send
        + Sync
        + std::ops::Neg<Output = T>
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<Output = T>
        + std::ops::AddAssign
        + std::ops::SubAssign
{
}

/// Column c of a supernode's stored values (its diagonal block's rows, then the rows below),
/// which faer keeps by columns.
fn stored_column<T: Entry>(l: faer::MatRef<'_, T>, c: usize) -> &[T] {
    l.col(c)
        .try_as_col_major()
        .expect("a supernode's values are stored by columns")
        .as_slice()
}

/// A column of the solve's own workspace, stored by columns.
fn column<T: Entry>(col: faer::col::ColMut<'_, T>) -> &mut [T] {
    col.try_as_col_major_mut()
        .expect("the workspace is stored by columns")
        .as_slice_mut()
}

/// 1 / Re(d) times x: the division by a diagonal entry of an LLᴴ factor, which is real.
fn divided_by_real<T: Entry>(x: T, d: T) -> T {
    mul_real(&x, &recip(&real(&d)))
}

/// Who solves a supernode: one of the two sides, or the top set.
const TOP: u8 = 2;

/// The widest supernode (in columns) solved by plain loops instead of faer's dense kernels.
/// Measured on Newton systems' factors (one solve, the best of five, loops/faer's whole solve)
/// with the loops up to 4, 8, 16 and 32 columns: cityTrees10000 0.93/0.99, 0.87/0.98,
/// 0.45/0.96, 0.46/0.98 ms; M3500 0.37/0.39, 0.27/0.39, 0.22/0.39, 0.22/0.39; city10000
/// 1.42/1.49, 1.02/1.28, 0.89/1.26, 0.92/1.30; torus3D (3D, wider supernodes) 4.7/4.2,
/// 3.5/3.7, 2.7/3.2, 3.0/3.4; parking-garage 0.35/0.34, 0.34/0.34, 0.28/0.34, 0.26/0.33.
pub const LOOP_MAX_COLUMNS: usize = 16;

/// Solves L Lᴴ X = B in place on this thread (`x`: B on entry, X on return, in the factor's own
/// order), supernode by supernode: forward in ascending order, backward in descending order,
/// the bits of [`TreeSplit::solve_in_place`].
pub fn solve_sequential<T: Entry, I: Index>(factor: SupernodalLltRef<'_, I, T>, x: MatMut<'_, T>) {
    let symbolic = factor.symbolic();
    assert_eq!(x.nrows(), symbolic.nrows());
    let shared = Shared {
        ptr: x.as_ptr_mut(),
        k: x.ncols(),
        row_stride: x.row_stride(),
        col_stride: x.col_stride(),
    };
    let mut step = Step::new(factor, &shared, max_pattern(symbolic));
    for s in 0..symbolic.n_supernodes() {
        step.forward(s, |_, _| true);
    }
    for s in (0..symbolic.n_supernodes()).rev() {
        step.backward(s);
    }
}

/// The most rows below any supernode's columns.
fn max_pattern<I: Index>(symbolic: &SymbolicSupernodalCholesky<I>) -> usize {
    (0..symbolic.n_supernodes())
        .map(|s| symbolic.supernode(s).pattern().len())
        .max()
        .unwrap_or(0)
}

/// The split of a supernodal factor's elimination tree between two cores ([`TreeSplit::new`]).
#[derive(Debug, Clone)]
pub struct TreeSplit {
    /// Per supernode: its side (0 or 1), or [`TOP`].
    owner: Vec<u8>,
    /// Per row of the factor, a bit: whether its supernode is in the top set.
    top_row: Vec<u64>,
    /// The supernodes of each side, ascending.
    sides: [Vec<u32>; 2],
}

/// A candidate split of [`TreeSplit::new`].
struct Dealt {
    /// max(side 0, side 1) + top, in stored values.
    estimate: f64,
    /// Per supernode: whether it is in the top set.
    top: Vec<bool>,
    /// The roots of the subtrees below the top set, each with its side.
    roots: Vec<(usize, u8)>,
}

/// The most supernodes moved into the top set while the sides are balanced.
const MAX_OPENED: usize = 64;

impl TreeSplit {
    /// The split with the least estimated time, max(side 0, side 1) + top, counting each
    /// supernode's stored values (what the solve reads twice): the top set starts empty and the
    /// subtrees below it are dealt to the lighter side, heaviest first; while the heavier side
    /// holds more than 55% of them, the heaviest subtree's root moves into the top set and its
    /// children's subtrees are dealt instead. `None` where the factor holds fewer than
    /// `min_values` values, or the best split's estimate is above 3/4 of one core's.
    pub fn new<I: Index>(
        symbolic: &SymbolicSupernodalCholesky<I>,
        min_values: usize,
    ) -> Option<Self> {
        let (begin, end) = (symbolic.supernode_begin(), symbolic.supernode_end());
        let weight = |s: usize| {
            let cols = end[s].zx() - begin[s].zx();
            ((cols + symbolic.supernode(s).pattern().len()) * cols) as f64
        };
        Self::by_weight(symbolic, &weight, min_values as f64)
    }

    /// As [`Self::new`], each supernode weighing `weight(s)` (the estimate counts these instead
    /// of stored values); `None` below a total of `min_total`.
    pub fn by_weight<I: Index>(
        symbolic: &SymbolicSupernodalCholesky<I>,
        weight: &dyn Fn(usize) -> f64,
        min_total: f64,
    ) -> Option<Self> {
        let ns = symbolic.n_supernodes();
        let n = symbolic.nrows();
        let (begin, end) = (symbolic.supernode_begin(), symbolic.supernode_end());
        let pattern = |s: usize| symbolic.supernode(s).pattern();
        let total: f64 = (0..ns).map(weight).sum();
        if total < min_total || u32::try_from(ns).is_err() {
            return None;
        }
        // The elimination tree of the supernodes: a supernode's parent holds the first row
        // below its diagonal block, an index above its own. (Its working arrays are per
        // supernode, none per row: at 10⁶ poses this is built beside the Newton system's peak.)
        const ROOT: u32 = u32::MAX;
        let mut parent = vec![ROOT; ns];
        for (s, parent) in parent.iter_mut().enumerate() {
            if let Some(first) = pattern(s).iter().map(|r| r.zx()).min() {
                let p = end.partition_point(|e| e.zx() <= first);
                if p <= s || p >= ns {
                    return None;
                }
                *parent = p as u32;
            }
        }
        let mut subtree: Vec<f64> = (0..ns).map(weight).collect();
        for s in 0..ns {
            if parent[s] != ROOT {
                subtree[parent[s] as usize] += subtree[s];
            }
        }
        // Each supernode's children, in one array by parent.
        let mut child_start = vec![0u32; ns + 1];
        for &p in parent.iter().filter(|&&p| p != ROOT) {
            child_start[p as usize + 1] += 1;
        }
        for s in 0..ns {
            child_start[s + 1] += child_start[s];
        }
        let mut next = child_start.clone();
        let mut children = vec![0u32; child_start[ns] as usize];
        let mut open: Vec<usize> = Vec::new();
        for (s, &p) in parent.iter().enumerate() {
            if p == ROOT {
                open.push(s);
            } else {
                children[next[p as usize] as usize] = s as u32;
                next[p as usize] += 1;
            }
        }
        drop(next);
        let children_of =
            |s: usize| &children[child_start[s] as usize..child_start[s + 1] as usize];
        let mut top = vec![false; ns];
        let mut top_weight = 0.0;
        let mut best: Option<Dealt> = None;
        for _ in 0..=MAX_OPENED {
            // Heaviest first, ties by index, each to the lighter side (side 0 on a tie).
            open.sort_by(|&a, &b| subtree[b].total_cmp(&subtree[a]).then(a.cmp(&b)));
            let mut load = [0.0f64; 2];
            let dealt: Vec<(usize, u8)> = open
                .iter()
                .map(|&s| {
                    let side = usize::from(load[1] < load[0]);
                    load[side] += subtree[s];
                    (s, side as u8)
                })
                .collect();
            let heavier = load[0].max(load[1]);
            let estimate = top_weight + heavier;
            if best.as_ref().is_none_or(|b| estimate < b.estimate) {
                best = Some(Dealt {
                    estimate,
                    top: top.clone(),
                    roots: dealt,
                });
            }
            if heavier <= 0.55 * (load[0] + load[1]) || open.is_empty() {
                break;
            }
            let heaviest = open.remove(0);
            top[heaviest] = true;
            top_weight += weight(heaviest);
            open.extend(children_of(heaviest).iter().map(|&c| c as usize));
        }
        let Dealt {
            estimate,
            top,
            roots: dealt,
        } = best?;
        if estimate > 0.75 * total {
            return None;
        }
        let mut owner = vec![TOP; ns];
        for &(s, side) in &dealt {
            owner[s] = side;
        }
        // Below a dealt subtree's root, each supernode is on its parent's side.
        for s in (0..ns).rev() {
            if !top[s] && owner[s] == TOP {
                owner[s] = owner[parent[s] as usize];
            }
        }
        let sides = [0u8, 1].map(|side| {
            (0..ns)
                .filter(|&s| owner[s] == side)
                .map(|s| s as u32)
                .collect()
        });
        let mut top_row = vec![0u64; n.div_ceil(64)];
        for s in (0..ns).filter(|&s| owner[s] == TOP) {
            for r in begin[s].zx()..end[s].zx() {
                top_row[r / 64] |= 1 << (r % 64);
            }
        }
        Some(TreeSplit {
            owner,
            top_row,
            sides,
        })
    }

    /// Every supernode on side 0: none on side 1 or in the top set.
    pub fn one_side<I: Index>(symbolic: &SymbolicSupernodalCholesky<I>) -> Self {
        let ns = symbolic.n_supernodes();
        TreeSplit {
            owner: vec![0; ns],
            top_row: vec![0; symbolic.nrows().div_ceil(64)],
            sides: [(0..ns as u32).collect(), Vec::new()],
        }
    }

    /// The supernodes of each side.
    pub fn sides(&self) -> &[Vec<u32>; 2] {
        &self.sides
    }

    /// Supernode s's side (0 or 1), or `None` where it is in the top set.
    pub fn side_of(&self, s: usize) -> Option<usize> {
        (self.owner[s] != TOP).then_some(usize::from(self.owner[s]))
    }

    /// Whether row `r`'s supernode is in the top set.
    fn is_top_row(&self, r: usize) -> bool {
        self.top_row[r / 64] >> (r % 64) & 1 == 1
    }

    /// The number of supernodes in the top set.
    pub fn top(&self) -> usize {
        self.owner.iter().filter(|&&o| o == TOP).count()
    }

    /// Solves L Lᴴ X = B in place (`x`: B on entry, X on return, in the factor's own order: no
    /// fill-reducing permutation applied here), the same bits as [`solve_sequential`].
    pub fn solve_in_place<T: Entry, I: Index>(
        &self,
        factor: SupernodalLltRef<'_, I, T>,
        x: MatMut<'_, T>,
    ) {
        let symbolic = factor.symbolic();
        assert_eq!(x.nrows(), symbolic.nrows());
        assert_eq!(self.owner.len(), symbolic.n_supernodes());
        let shared = Shared {
            ptr: x.as_ptr_mut(),
            k: x.ncols(),
            row_stride: x.row_stride(),
            col_stride: x.col_stride(),
        };
        let max_pattern = max_pattern(symbolic);
        let side = |side: usize, forward: bool| {
            let mut step = Step::new(factor, &shared, max_pattern);
            let mut log = Vec::new();
            if forward {
                for &s in &self.sides[side] {
                    step.forward(s as usize, |row, t| {
                        if self.is_top_row(row) {
                            log.push(t);
                            false
                        } else {
                            true
                        }
                    });
                }
            } else {
                for &s in self.sides[side].iter().rev() {
                    step.backward(s as usize);
                }
            }
            log
        };
        // Forward: the sides side by side, then the top set in order, each side supernode's
        // logged updates at its place.
        let logs = crate::linalg::parallel::join(|| side(0, true), || side(1, true));
        let logs = [logs.0, logs.1];
        let mut next = [0usize; 2];
        let mut step = Step::new(factor, &shared, max_pattern);
        for s in 0..symbolic.n_supernodes() {
            match self.owner[s] {
                TOP => step.forward(s, |_, _| true),
                side => {
                    let side = usize::from(side);
                    let pattern = symbolic.supernode(s).pattern();
                    for j in 0..shared.k {
                        for row in pattern.iter().map(|r| r.zx()) {
                            if self.is_top_row(row) {
                                // SAFETY: one thread here; (row, j) is inside x.
                                unsafe { shared.subtract(row, j, logs[side][next[side]]) };
                                next[side] += 1;
                            }
                        }
                    }
                }
            }
        }
        // Backward: the top set, then the sides side by side.
        for s in (0..symbolic.n_supernodes()).rev() {
            if self.owner[s] == TOP {
                step.backward(s);
            }
        }
        crate::linalg::parallel::join(|| side(0, false), || side(1, false));
    }
}

/// The solution vector(s), written by two threads at once on disjoint rows: each side writes the
/// rows of its own supernodes only (in the forward pass the top set's rows are logged instead),
/// and reads rows of its own side and of the top set, which no thread writes meanwhile.
struct Shared<T> {
    ptr: *mut T,
    k: usize,
    row_stride: isize,
    col_stride: isize,
}

// SAFETY: see the struct's documentation: the threads touch disjoint rows.
unsafe impl<T: Send> Send for Shared<T> {}
// SAFETY: as above.
unsafe impl<T: Sync> Sync for Shared<T> {}

impl<T: Entry> Shared<T> {
    /// Entry (row, j).
    ///
    /// # Safety
    /// In bounds, and not written by another thread meanwhile.
    unsafe fn get(&self, row: usize, j: usize) -> T {
        unsafe { *self.at(row, j) }
    }

    /// The address of entry (row, j).
    ///
    /// # Safety
    /// In bounds.
    unsafe fn at(&self, row: usize, j: usize) -> *mut T {
        unsafe {
            self.ptr
                .offset(row as isize * self.row_stride + j as isize * self.col_stride)
        }
    }

    /// x(row, j) −= t, as faer's solve subtracts.
    ///
    /// # Safety
    /// In bounds, and not read or written by another thread meanwhile.
    unsafe fn subtract(&self, row: usize, j: usize, t: T) {
        unsafe { *self.at(row, j) -= t }
    }

    /// The rows `start..start + size` as a matrix.
    ///
    /// # Safety
    /// In bounds, and not touched by another thread while the view lives.
    unsafe fn rows(&self, start: usize, size: usize) -> MatMut<'_, T> {
        unsafe {
            MatMut::from_raw_parts_mut(
                self.at(start, 0),
                size,
                self.k,
                self.row_stride,
                self.col_stride,
            )
        }
    }
}

/// One supernode's forward or backward step, faer's operations, with room for L_bs's product.
struct Step<'a, 's, T, I: Index> {
    factor: SupernodalLltRef<'a, I, T>,
    x: &'s Shared<T>,
    tmp: Vec<T>,
}

impl<'a, 's, T: Entry, I: Index> Step<'a, 's, T, I> {
    fn new(factor: SupernodalLltRef<'a, I, T>, x: &'s Shared<T>, max_pattern: usize) -> Self {
        Step {
            factor,
            x,
            tmp: vec![T::zero_impl(); max_pattern * x.k],
        }
    }

    /// y_s = L_ss⁻¹ y_s, then t = L_bs y_s, subtracted from the rows below where `direct(row,
    /// t)` says so (it keeps the others).
    fn forward(&mut self, s: usize, mut direct: impl FnMut(usize, T) -> bool) {
        let node = self.factor.supernode(s);
        let (start, pattern, l) = (node.start(), node.pattern(), node.val());
        let size = l.ncols();
        let (l_top, l_bot) = l.split_at_row(size);
        // SAFETY: supernode s's rows are this thread's alone (module docs).
        let mut x_top = unsafe { self.x.rows(start, size) };
        let k = self.x.k;
        let mut tmp = MatMut::from_column_major_slice_mut(
            &mut self.tmp[..pattern.len() * k],
            pattern.len(),
            k,
        );
        if size <= LOOP_MAX_COLUMNS {
            // Column by column: y_c = x_c / L_cc, then y_c's multiples of column c subtracted
            // from the rows of the block below it and added up for the rows below the block.
            for j in 0..k {
                let t = column(tmp.rb_mut().col_mut(j));
                t.fill(T::zero_impl());
                for c in 0..size {
                    let col = stored_column(l, c);
                    let y = divided_by_real(x_top[(c, j)], col[c]);
                    x_top[(c, j)] = y;
                    for r in c + 1..size {
                        x_top[(r, j)] -= col[r] * y;
                    }
                    for (t, &v) in t.iter_mut().zip(&col[size..]) {
                        *t += v * y;
                    }
                }
            }
        } else {
            solve_lower_triangular_in_place_with_conj(l_top, Conj::No, x_top.rb_mut(), Par::Seq);
            matmul_with_conj(
                tmp.rb_mut(),
                Accum::Replace,
                l_bot,
                Conj::No,
                x_top.rb(),
                Conj::No,
                T::one_impl(),
                Par::Seq,
            );
        }
        for j in 0..k {
            for (idx, row) in pattern.iter().map(|r| r.zx()).enumerate() {
                let t = tmp[(idx, j)];
                if direct(row, t) {
                    // SAFETY: a row of this thread's side, or of the top set with one thread.
                    unsafe { self.x.subtract(row, j, t) };
                }
            }
        }
    }

    /// x_s = L_ssᴴ⁻¹ (x_s − L_bsᴴ x_b).
    fn backward(&mut self, s: usize) {
        let node = self.factor.supernode(s);
        let (start, pattern, l) = (node.start(), node.pattern(), node.val());
        let size = l.ncols();
        let (l_top, l_bot) = l.split_at_row(size);
        let k = self.x.k;
        let mut tmp = MatMut::from_column_major_slice_mut(
            &mut self.tmp[..pattern.len() * k],
            pattern.len(),
            k,
        );
        for j in 0..k {
            for (idx, row) in pattern.iter().map(|r| r.zx()).enumerate() {
                // SAFETY: rows of this side or of the top set, written by no thread now.
                tmp[(idx, j)] = unsafe { self.x.get(row, j) };
            }
        }
        // SAFETY: supernode s's rows are this thread's alone.
        let mut x_top = unsafe { self.x.rows(start, size) };
        if size <= LOOP_MAX_COLUMNS {
            // Column by column, last first: x_c −= L_bcᴴ x_b + Σ_{r>c} conj(L_rc) x_r, then
            // divided by L_cc (real).
            for j in 0..k {
                let t = column(tmp.rb_mut().col_mut(j));
                for c in (0..size).rev() {
                    let col = stored_column(l, c);
                    let mut below = T::zero_impl();
                    for (&v, &t) in col[size..].iter().zip(t.iter()) {
                        below += conj(&v) * t;
                    }
                    let mut x = x_top[(c, j)] - below;
                    for r in c + 1..size {
                        x -= conj(&col[r]) * x_top[(r, j)];
                    }
                    x_top[(c, j)] = divided_by_real(x, col[c]);
                }
            }
            return;
        }
        matmul_with_conj(
            x_top.rb_mut(),
            Accum::Add,
            l_bot.transpose(),
            Conj::Yes,
            tmp.rb(),
            Conj::No,
            -T::one_impl(),
            Par::Seq,
        );
        solve_upper_triangular_in_place_with_conj(
            l_top.transpose(),
            Conj::Yes,
            x_top.rb_mut(),
            Par::Seq,
        );
    }
}
