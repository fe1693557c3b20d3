//! A supernodal LLᴴ solve, L Lᴴ x = b, on two cores: the supernodes of the elimination tree
//! split into two sides of whole subtrees, solved side by side, and a top set (their ancestors,
//! where the sides meet) solved on one core. Every entry of x goes through the operations of
//! faer's own sequential solve (`SupernodalLltRef::solve_in_place_with_conj`), on the same
//! operands and in the same order, so the result is faer's to the last bit:
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
//! for that reason; the dense kernels are faer's.

use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place_with_conj, solve_upper_triangular_in_place_with_conj,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::traits::ComplexField;
use faer::{Accum, Conj, MatMut, Par};

/// The scalars of the solve: faer's, with the arithmetic its solve applies to them.
pub trait Entry:
    ComplexField + Copy + Send + Sync + std::ops::Neg<Output = Self> + std::ops::SubAssign
{
}

impl<T> Entry for T where
    T: ComplexField + Copy + Send + Sync + std::ops::Neg<Output = T> + std::ops::SubAssign
{
}

/// Who solves a supernode: one of the two sides, or the top set.
const TOP: u8 = 2;

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
    pub fn new(symbolic: &SymbolicSupernodalCholesky<usize>, min_values: usize) -> Option<Self> {
        let (begin, end) = (symbolic.supernode_begin(), symbolic.supernode_end());
        let weight = |s: usize| {
            let cols = end[s] - begin[s];
            ((cols + symbolic.supernode(s).pattern().len()) * cols) as f64
        };
        Self::by_weight(symbolic, &weight, min_values as f64)
    }

    /// As [`Self::new`], each supernode weighing `weight(s)` (the estimate counts these instead
    /// of stored values); `None` below a total of `min_total`.
    pub fn by_weight(
        symbolic: &SymbolicSupernodalCholesky<usize>,
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
            if let Some(&first) = pattern(s).iter().min() {
                let p = end.partition_point(|&e| e <= first);
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
            for r in begin[s]..end[s] {
                top_row[r / 64] |= 1 << (r % 64);
            }
        }
        Some(TreeSplit {
            owner,
            top_row,
            sides,
        })
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
    /// fill-reducing permutation applied here), the same bits as faer's sequential solve.
    pub fn solve_in_place<T: Entry>(
        &self,
        factor: SupernodalLltRef<'_, usize, T>,
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
        let max_pattern = (0..symbolic.n_supernodes())
            .map(|s| symbolic.supernode(s).pattern().len())
            .max()
            .unwrap_or(0);
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
                        for &row in pattern {
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
struct Step<'a, 's, T> {
    factor: SupernodalLltRef<'a, usize, T>,
    x: &'s Shared<T>,
    tmp: Vec<T>,
}

impl<'a, 's, T: Entry> Step<'a, 's, T> {
    fn new(factor: SupernodalLltRef<'a, usize, T>, x: &'s Shared<T>, max_pattern: usize) -> Self {
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
        solve_lower_triangular_in_place_with_conj(l_top, Conj::No, x_top.rb_mut(), Par::Seq);
        let k = self.x.k;
        let mut tmp = MatMut::from_column_major_slice_mut(
            &mut self.tmp[..pattern.len() * k],
            pattern.len(),
            k,
        );
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
        for j in 0..k {
            for (idx, &row) in pattern.iter().enumerate() {
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
            for (idx, &row) in pattern.iter().enumerate() {
                // SAFETY: rows of this side or of the top set, written by no thread now.
                tmp[(idx, j)] = unsafe { self.x.get(row, j) };
            }
        }
        // SAFETY: supernode s's rows are this thread's alone.
        let mut x_top = unsafe { self.x.rows(start, size) };
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
