//! Sparse Hermitian factorizations with one symbolic analysis reused across numeric ones: the
//! Newton systems of the staircase (real), the certificate LLᴴ of W̃(λ) + η·blkdiag(0, I)
//! (complex) and LDLᴴ inertia counts (Sylvester's law) for the SZEP at scale.
//!
//! A thin layer over faer's low-level `sparse::linalg::cholesky` API: faer's high-level `Llt`
//! allocates its workspace on every factorization and exposes neither the pivots of an LDLᴴ
//! (needed for inertia) nor the factor's columns (needed for negative-curvature directions), so
//! both are read here from the numeric factor and its symbolic structure.

use crate::linalg::roundoff::gamma_with;
use crate::linalg::tree_factor::{FactorSplit, Kind, SplitRoom};
use crate::linalg::tree_solve::{self, TreeSplit};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::reborrow::ReborrowMut;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, Index, MatMut, Par, Side, c64};

/// A numeric factorization broke down: a pivot that is not positive (LLᴴ) or zero (LDLᴴ).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NotFactorable;

/// How a factor is stored and computed: faer's choice by flop count, column by column
/// (simplicial: scalar code, fine for any [`Scalar`]), or by dense blocks (supernodal: faster on
/// factors with many operations per entry, such as the Newton systems of denser or 3D graphs, but
/// its dense kernels need SIMD support of the scalar type, which double-double lacks).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    Auto,
    /// As `Auto`, with the crossover measured for the complex LDLᴴ of W̃(λ) (the planar
    /// certificate): supernodal from a flop ratio (faer's, the factorization's operations per
    /// stored entry) of 15 instead of faer's 40. Complex multiply-adds are four real ones, so
    /// dense blocks pay off on sparser factors. Measured (median of 9 LDLᴴ of W̃'s pattern,
    /// simplicial/supernodal): city10000 (ratio 29) 34/24 ms, 10⁵-pose Manhattan (49) 314/161 ms;
    /// below 15 simplicial stays ahead: M3500 (13) 4.1/2.9 and 3.0/4.4 ms on two runs,
    /// cityTrees10000 (7.5) 4.4/8.8 ms, ais2klinik (4.9) 4.4/10.9 ms.
    AutoComplex,
    Simplicial,
    Supernodal,
}

impl Layout {
    fn threshold(self) -> SupernodalThreshold {
        match self {
            Layout::Auto => SupernodalThreshold::AUTO,
            Layout::AutoComplex => SupernodalThreshold(15.0 / 40.0),
            Layout::Simplicial => SupernodalThreshold::FORCE_SIMPLICIAL,
            Layout::Supernodal => SupernodalThreshold::FORCE_SUPERNODAL,
        }
    }

    /// The triangle that faer's numeric factorization of this layout reads (it transposes the
    /// other one first); `Auto` decides only at analysis, and is given the upper one.
    pub fn stored_side(self) -> Side {
        match self {
            Layout::Supernodal => Side::Lower,
            Layout::Auto | Layout::AutoComplex | Layout::Simplicial => Side::Upper,
        }
    }
}

/// The last factorization attempted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    None,
    Llt,
    Ldlt,
}

/// A sparse Hermitian matrix's symbolic Cholesky analysis (AMD ordering) with room for numeric
/// LLᴴ or LDLᴴ factors of any matrix with the same pattern (upper triangle stored). Its row
/// indices and positions are of type `I`: `usize`, or `u32` where the counts fit
/// ([`SparseFactor::try_analyze_in_order`]), which halves the analysis's index arrays (the
/// planar Newton systems'); the values are the same bits either way.
pub struct SparseFactor<T, I: Index = usize> {
    symbolic: SymbolicCholesky<I>,
    /// The triangle of the matrices passed to the numeric factorizations.
    side: Side,
    values: Vec<T>,
    mem: MemBuffer,
    /// Whether `values` and `mem` have their room: allocated by the first factorization, not by
    /// the analysis, so that a factor analyzed ahead of its use (on another thread while Newton
    /// runs) holds no numeric memory until then.
    allocated: bool,
    /// Whether `mem` holds the solves' workspace only ([`Self::keep_solves_only`]).
    solves_only: bool,
    state: State,
    /// An earlier factor's values, whose pages are mapped already, for [`Self::allocate`] to
    /// reuse ([`Self::reuse`]).
    spare: Vec<T>,
    /// The elimination tree split between two cores for the LLᴴ solves, where prepared
    /// ([`Self::prepare_split`]).
    split: Option<TreeSplit>,
    /// The elimination tree split between two cores for the LLᴴ and LDLᴴ factorizations, where
    /// prepared ([`Self::prepare_factor_split`]).
    factor_split: Option<FactorSplit>,
    /// Its working memory, kept from one factorization to the next.
    split_room: SplitRoom<T>,
}

impl<T: Scalar> SparseFactor<T> {
    /// Symbolic analysis of a pattern (upper triangle, diagonal included).
    pub fn analyze(pattern: SymbolicSparseColMatRef<'_, usize>) -> Self {
        Self::analyze_with(pattern, SupernodalThreshold::AUTO)
    }

    /// As [`Self::analyze`], always simplicial (column by column), so that the factor's columns
    /// can be read directly (negative-curvature directions of an LDLᴴ).
    pub fn analyze_simplicial(pattern: SymbolicSparseColMatRef<'_, usize>) -> Self {
        Self::analyze_with(pattern, SupernodalThreshold::FORCE_SIMPLICIAL)
    }

    /// As [`Self::analyze`] with a given fill-reducing order (`order[new] = old`), e.g. one from
    /// [`group_ordering`], and a given storage of the factor.
    pub fn analyze_ordered(
        pattern: SymbolicSparseColMatRef<'_, usize>,
        order: &[usize],
        layout: Layout,
    ) -> Self {
        Self::analyze_with_order(pattern, layout.threshold(), Some(order))
    }

    fn analyze_with(
        pattern: SymbolicSparseColMatRef<'_, usize>,
        threshold: SupernodalThreshold,
    ) -> Self {
        Self::analyze_with_order(pattern, threshold, None)
    }

    fn analyze_with_order(
        pattern: SymbolicSparseColMatRef<'_, usize>,
        threshold: SupernodalThreshold,
        order: Option<&[usize]>,
    ) -> Self {
        let inverse: Vec<usize> = order.map_or_else(Vec::new, |o| {
            let mut inv = vec![0; o.len()];
            for (new, &old) in o.iter().enumerate() {
                inv[old] = new;
            }
            inv
        });
        let ordering = match order {
            Some(o) => {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(o, &inverse, o.len()))
            }
            None => SymmetricOrdering::Amd,
        };
        Self::analyze_full(pattern, threshold, ordering)
    }

    /// As [`Self::analyze`] for a matrix already in elimination order (no fill-reducing
    /// permutation) whose `side` triangle is stored, such as an [`Assembly::permuted`]. When
    /// `side` is the triangle faer's numeric kernels read ([`Layout::stored_side`]), each
    /// factorization reads the matrix as it is: faer otherwise copies it into the permuted order
    /// on every factorization (9% of a Newton solve's time on M3500c).
    pub fn analyze_in_order(
        pattern: SymbolicSparseColMatRef<'_, usize>,
        side: Side,
        layout: Layout,
    ) -> Self {
        Self::try_analyze_in_order(pattern, side, layout)
            .expect("the symbolic analysis of a square pattern cannot fail but for memory")
    }

    /// The analysis of an upper triangle's pattern.
    fn analyze_full(
        pattern: SymbolicSparseColMatRef<'_, usize>,
        threshold: SupernodalThreshold,
        ordering: SymmetricOrdering<'_, usize>,
    ) -> Self {
        Self::try_analyze_full(pattern, threshold, ordering)
            .expect("the symbolic analysis of a square pattern cannot fail but for memory")
    }
}

impl<T: Scalar, I: Index> SparseFactor<T, I> {
    /// [`SparseFactor::analyze_in_order`] with indices of type `I`: `None` where the factor's
    /// entries do not fit in it (faer's count overflows; below 2³¹ for `u32`).
    pub fn try_analyze_in_order(
        pattern: SymbolicSparseColMatRef<'_, I>,
        side: Side,
        layout: Layout,
    ) -> Option<Self> {
        // faer's symbolic analysis in the identity order reads the pattern as an upper triangle
        // whatever side it is told (faer 0.24), so a lower one is transposed for it.
        let upper;
        let pattern = match side {
            Side::Upper => pattern,
            Side::Lower => {
                upper = pattern.transpose().to_col_major().ok()?;
                upper.as_ref()
            }
        };
        let mut factor =
            Self::try_analyze_full(pattern, layout.threshold(), SymmetricOrdering::Identity)?;
        factor.side = side;
        Some(factor)
    }

    /// The analysis of an upper triangle's pattern; `None` where faer's counts overflow `I`
    /// (or memory runs out).
    fn try_analyze_full(
        pattern: SymbolicSparseColMatRef<'_, I>,
        threshold: SupernodalThreshold,
        ordering: SymmetricOrdering<'_, I>,
    ) -> Option<Self> {
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: threshold,
            supernodal_params: faer::sparse::linalg::SymbolicSupernodalParams {
                relax: Some(SUPERNODE_RELAXATION),
            },
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(pattern, Side::Upper, ordering, params).ok()?;
        Some(SparseFactor {
            symbolic,
            side: Side::Upper,
            values: Vec::new(),
            mem: MemBuffer::new(StackReq::EMPTY),
            allocated: false,
            solves_only: false,
            state: State::None,
            spare: Vec::new(),
            split: None,
            factor_split: None,
            split_room: SplitRoom::default(),
        })
    }

    /// The workspace of the factorizations and of one-column solves.
    fn workspace(&self) -> StackReq {
        let symbolic = &self.symbolic;
        StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<T>(Par::Seq, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<T>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<T>(1, Par::Seq),
        ])
    }

    /// Gives back the factorizations' workspace and keeps the one-column solves' (a later
    /// factorization takes it again): for a factor kept only to solve with, such as L's for the
    /// optimal positions, whose simplicial LLᴴ workspace is about 100 bytes per row (100 MB at
    /// 10⁶ poses) against the solves' 16.
    pub fn keep_solves_only(&mut self) {
        if self.allocated {
            self.mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<T>(1, Par::Seq));
            self.solves_only = true;
        }
    }

    /// The factorizations' workspace back where [`Self::keep_solves_only`] gave it away.
    fn restore_workspace(&mut self) {
        if self.solves_only {
            self.mem = MemBuffer::new(self.workspace());
            self.solves_only = false;
        }
    }

    /// Room for the numeric factor and the factorizations' and solves' workspace.
    fn allocate(&mut self) {
        let req = self.workspace();
        let symbolic = &self.symbolic;
        // A spare room larger than this factor gives its tail back (in place: it is empty).
        let mut values = std::mem::take(&mut self.spare);
        values.clear();
        values.shrink_to(symbolic.len_val());
        values.resize(symbolic.len_val(), T::zero_impl());
        self.values = values;
        self.mem = MemBuffer::new(req);
        self.allocated = true;
    }

    /// As [`Self::release`], handing the numeric factor's values over (for [`Self::reuse`] by a
    /// factor that follows this one).
    pub fn take_values(&mut self) -> Vec<T> {
        let values = std::mem::take(&mut self.values);
        self.release();
        values
    }

    /// Takes the values of a factor that is no longer needed ([`Self::take_values`]) as the room
    /// of this one's, allocated at its first factorization: their pages are mapped already. A
    /// page's first write costs a page fault, about 3 µs in the virtual machines measured (0.8
    /// ms per MB, against 0.03 ms per MB for writing it again): on city10000 the certificate's
    /// LDLᴴ faulted 3 360 pages after Newton's LLᵀ had unmapped its 2 900.
    pub fn reuse(&mut self, values: Vec<T>) {
        if !self.allocated {
            self.spare = values;
        }
    }

    /// The number of values of a numeric factor of this analysis.
    pub fn values_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Frees the numeric factor and the workspace but keeps the analysis (the next factorization
    /// allocates them again): for a factor kept for later while others take the memory.
    pub fn release(&mut self) {
        self.values = Vec::new();
        self.mem = MemBuffer::new(StackReq::EMPTY);
        self.allocated = false;
        self.solves_only = false;
        self.state = State::None;
    }

    /// The triangle its numeric factorizations read as it is: the lower one for a supernodal
    /// factor, the upper one for a simplicial one (faer copies the other into it on every
    /// factorization). An automatic [`Layout`] settles which at the analysis.
    pub fn read_side(&self) -> Side {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => Side::Upper,
            SymbolicCholeskyRaw::Supernodal(_) => Side::Lower,
        }
    }

    /// This analysis, for matrices whose `side` triangle is stored from now on (the pattern
    /// analyzed is the same either way: one triangle is the other's transpose).
    pub fn given(mut self, side: Side) -> Self {
        self.side = side;
        self
    }

    /// The number of entries the factor stores (its fill, with a supernodal layout's zeros).
    pub fn stored_entries(&self) -> usize {
        self.symbolic.len_val()
    }

    /// The multiply-adds of one numeric factorization, counted from the symbolic structure (so
    /// the same on every machine): Σ_j c_j² over the columns j of L, c_j the entries of column j
    /// below the diagonal and on it (a supernode of k columns and m rows below them: its dense
    /// block's k³/3 + k²m + km²).
    pub fn multiply_adds(&self) -> f64 {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let cp = s.col_ptr();
                (0..self.dim())
                    .map(|j| ((cp[j + 1].zx() - cp[j].zx()) as f64).powi(2))
                    .sum()
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let (begin, end, rows) = (
                    s.supernode_begin(),
                    s.supernode_end(),
                    s.col_ptr_for_row_idx(),
                );
                (0..s.n_supernodes())
                    .map(|t| {
                        let k = (end[t].zx() - begin[t].zx()) as f64;
                        let m = (rows[t + 1].zx() - rows[t].zx()) as f64;
                        k * k * k / 3.0 + k * k * m + k * m * m
                    })
                    .sum()
            }
        }
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Numeric LLᴴ of `a` (upper triangle, same pattern as analyzed). `Err` if a pivot is not
    /// positive (the matrix is not numerically positive definite).
    pub fn llt(&mut self, a: SparseColMatRef<'_, I, T>) -> Result<(), NotFactorable> {
        clear_upper_avx();
        self.state = State::None;
        if !self.allocated {
            self.allocate();
        }
        self.restore_workspace();
        if let Some(result) = self.factor_split_with(a, Kind::Llt) {
            return result;
        }
        let stack = MemStack::new(&mut self.mem);
        let result = self.symbolic.factorize_numeric_llt(
            &mut self.values,
            a,
            self.side,
            LltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        );
        match result {
            Ok(_) => {
                self.state = State::Llt;
                Ok(())
            }
            Err(_) => Err(NotFactorable),
        }
    }

    /// The factorization `kind` by the split tree where one is prepared
    /// ([`Self::prepare_factor_split`], [`FactorSplit::factorize`]); `None` where none is. Both
    /// cores where the second is idle, else one after the other: the same values.
    fn factor_split_with(
        &mut self,
        a: SparseColMatRef<'_, I, T>,
        kind: Kind,
    ) -> Option<Result<(), NotFactorable>> {
        let (SymbolicCholeskyRaw::Supernodal(symbolic), Some(split)) =
            (self.symbolic.raw(), self.factor_split.as_ref())
        else {
            return None;
        };
        // Where the second core is busy building ahead, side 1 is offered to it.
        let two_cores = split.splits() && crate::linalg::parallel::second_core();
        let result = split.factorize(
            kind,
            symbolic,
            &mut self.values,
            a,
            &mut self.split_room,
            two_cores,
        );
        Some(match result {
            Ok(()) => {
                self.state = match kind {
                    Kind::Llt => State::Llt,
                    Kind::Ldlt => State::Ldlt,
                };
                Ok(())
            }
            Err(_) => Err(NotFactorable),
        })
    }

    /// Numeric LDLᴴ of `a` without pivoting (upper triangle, same pattern). `Err` on an exactly
    /// zero pivot.
    pub fn ldlt(&mut self, a: SparseColMatRef<'_, I, T>) -> Result<(), NotFactorable> {
        clear_upper_avx();
        self.state = State::None;
        if !self.allocated {
            self.allocate();
        }
        self.restore_workspace();
        if let Some(result) = self.factor_split_with(a, Kind::Ldlt) {
            return result;
        }
        let stack = MemStack::new(&mut self.mem);
        let result = self.symbolic.factorize_numeric_ldlt(
            &mut self.values,
            a,
            self.side,
            LdltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        );
        match result {
            Ok(_) => {
                self.state = State::Ldlt;
                Ok(())
            }
            Err(_) => Err(NotFactorable),
        }
    }

    /// x with A x = b for a matrix assembled in an elimination `order` of its own (`order[new] =
    /// old` coordinate, as [`block_coordinates`] gives), by the last successful factorization:
    /// b's coordinate k is `b(k)`, gathered straight into that order and x scattered out of it,
    /// so that no permuted vector outlives the solve (the Newton systems', planar and SE(3)).
    pub fn solve_gathered(&mut self, order: &[usize], b: impl Fn(usize) -> T) -> Vec<T> {
        let mut permuted: Vec<T> = order.iter().map(|&old| b(old)).collect();
        self.solve_in_place(&mut permuted);
        let mut x = vec![T::zero_impl(); permuted.len()];
        for (p, &old) in permuted.into_iter().zip(order) {
            x[old] = p;
        }
        x
    }

    /// Solves A x = b in place with the last successful factorization: a supernodal LLᴴ's by
    /// [`crate::linalg::tree_solve`], on two cores where its tree's split is prepared
    /// ([`Self::prepare_split`]) and the second core is not busy with work built ahead (the same
    /// bits on one core), other factors by faer's solve.
    pub fn solve_in_place(&mut self, b: &mut [T]) {
        clear_upper_avx();
        let n = self.dim();
        assert_eq!(b.len(), n);
        if self.solve_supernodal_llt(
            MatMut::from_column_major_slice_mut(b, n, 1),
            crate::linalg::parallel::second_core_idle(),
        ) {
            return;
        }
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        let stack = MemStack::new(&mut self.mem);
        match self.state {
            State::Llt => LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                Par::Seq,
                stack,
            ),
            State::Ldlt => LdltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                Par::Seq,
                stack,
            ),
            State::None => panic!("solve without a successful factorization"),
        }
    }

    /// Splits the elimination tree between two cores for the LLᴴ solves ([`TreeSplit`]) where
    /// there is a second core, the factor is supernodal and holds [`SPLIT_SOLVE_MIN_VALUES`]
    /// values at least. For the factors solved many times (the Newton systems'), with their
    /// analysis: before the factorizations' peak of memory, which its working arrays would
    /// otherwise add to (at 10⁶ poses).
    pub fn prepare_split(&mut self) {
        if crate::linalg::parallel::second_core() {
            self.prepare_split_from(SPLIT_SOLVE_MIN_VALUES);
        }
    }

    /// Splits the elimination tree between two cores for the LLᴴ and LDLᴴ factorizations
    /// ([`FactorSplit`]) where the factor is supernodal, in its own order (no permutation, the
    /// lower triangle stored) and takes `min_work` multiply-adds ([`Self::multiply_adds`]) at
    /// least. On one core as well: the factor's values depend on the split, not on the thread
    /// count.
    pub fn prepare_factor_split(&mut self, min_work: f64) {
        self.factor_split = self
            .own_factorizable()
            .and_then(|symbolic| FactorSplit::new(symbolic, min_work));
    }

    /// As [`Self::prepare_factor_split`], and where the LLᴴ does not split (less work than
    /// `min_work`, or a tree that does not divide), the same code on one core, one supernode after
    /// another ([`FactorSplit::sequential`]): its narrow supernodes by plain loops
    /// ([`crate::linalg::tree_factor`]) instead of faer's dense kernels, one call each.
    pub fn prepare_own_factorization(&mut self, min_work: f64) {
        self.factor_split = self.own_factorizable().map(|symbolic| {
            FactorSplit::new(symbolic, min_work)
                .unwrap_or_else(|| FactorSplit::sequential(symbolic))
        });
    }

    /// The analysis where [`FactorSplit`] can factor it: supernodal, in its own order (no
    /// permutation), the lower triangle stored, fewer rows than its 32-bit row map holds
    /// ([`crate::linalg::tree_factor::LOCAL_NONE`]).
    fn own_factorizable(&self) -> Option<&SymbolicSupernodalCholesky<I>> {
        match (self.symbolic.raw(), self.symbolic.perm(), self.side) {
            (SymbolicCholeskyRaw::Supernodal(symbolic), None, Side::Lower)
                if self.dim() < crate::linalg::tree_factor::LOCAL_NONE as usize =>
            {
                Some(symbolic)
            }
            _ => None,
        }
    }

    /// Whether the factorizations are split between the cores ([`Self::prepare_factor_split`]).
    pub fn splits_factorizations(&self) -> bool {
        self.factor_split.as_ref().is_some_and(FactorSplit::splits)
    }

    /// [`Self::prepare_split`] from `min_values` stored values.
    fn prepare_split_from(&mut self, min_values: usize) {
        self.split = match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(symbolic) => TreeSplit::new(symbolic, min_values),
            SymbolicCholeskyRaw::Simplicial(_) => None,
        };
    }

    /// [`Self::solve_in_place`] where the last factorization is a supernodal LLᴴ: by the
    /// [`TreeSplit`] on two cores where one is prepared and `two_cores`, else by
    /// [`tree_solve::solve_sequential`] (the same bits); `false` (b untouched) for other
    /// factors. The fill-reducing permutation, if any, is applied around it as faer's solve
    /// applies it.
    fn solve_supernodal_llt(&mut self, mut b: MatMut<'_, T>, two_cores: bool) -> bool {
        let (SymbolicCholeskyRaw::Supernodal(symbolic), State::Llt) =
            (self.symbolic.raw(), self.state)
        else {
            return false;
        };
        let factor = SupernodalLltRef::new(symbolic, &self.values);
        let split = self.split.as_ref().filter(|_| two_cores);
        let solve = |x: MatMut<'_, T>| match split {
            Some(split) => split.solve_in_place(factor, x),
            None => tree_solve::solve_sequential(factor, x),
        };
        match self.symbolic.perm() {
            Some(perm) => {
                let (fwd, inv) = perm.arrays();
                let mut x =
                    faer::Mat::<T>::from_fn(b.nrows(), b.ncols(), |i, j| b[(fwd[i].zx(), j)]);
                solve(x.as_mut());
                for j in 0..b.ncols() {
                    for (i, &new) in inv.iter().enumerate() {
                        b[(i, j)] = x[(new.zx(), j)];
                    }
                }
            }
            None => solve(b),
        }
        true
    }

    /// Solves A X = B in place for a block of right-hand sides (the columns of `b`) with the
    /// last successful factorization: one pass over the factor for all of them (a supernodal
    /// LLᴴ's on two cores as in [`Self::solve_in_place`]).
    pub fn solve_block_in_place(&mut self, mut b: MatMut<'_, T>) {
        clear_upper_avx();
        assert_eq!(b.nrows(), self.dim());
        if self.solve_supernodal_llt(b.rb_mut(), crate::linalg::parallel::second_core_idle()) {
            return;
        }
        let mut mem = MemBuffer::new(
            self.symbolic
                .solve_in_place_scratch::<T>(b.ncols(), Par::Seq),
        );
        let stack = MemStack::new(&mut mem);
        match self.state {
            State::Llt => LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                b,
                Par::Seq,
                stack,
            ),
            State::Ldlt => LdltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                b,
                Par::Seq,
                stack,
            ),
            State::None => panic!("solve without a successful factorization"),
        }
    }
}

impl<T: Scalar> SparseFactor<T> {
    /// The pivots d_k of the last LDLᴴ (real parts), in the factorization's (permuted) order.
    pub fn ldlt_pivots(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.dim()];
        self.visit_ldlt_columns(|j, _, first| d[j] = self.values[first].re());
        d
    }

    /// Calls `f(j, rows, first)` for every column j of the last LDLᴴ's factors, in the
    /// factorization's (permuted) order: `rows[0] = j` holds the pivot d_j and the rest L's
    /// entries below it (L has a unit diagonal, not stored as such), at consecutive indices of the
    /// factor's values from `first`.
    pub(crate) fn visit_ldlt_columns(&self, f: impl FnMut(usize, &[usize], usize)) {
        assert_eq!(self.state, State::Ldlt);
        self.visit_columns(f);
    }

    /// Calls `f(j, rows, values)` for every column j of the last LLᴴ's factor L, in the
    /// factorization's (permuted) order ([`Self::order`]): `rows[0] = j` and `values[0]` is
    /// l_jj, the rest L's entries below the diagonal, rows ascending. What a sparse inverse
    /// subset (Takahashi's recurrence) reads.
    ///
    /// # Panics
    ///
    /// Without a successful LLᴴ before.
    pub fn visit_llt_columns(&self, mut f: impl FnMut(usize, &[usize], &[T])) {
        assert_eq!(self.state, State::Llt);
        self.visit_columns(|j, rows, first| f(j, rows, &self.values[first..first + rows.len()]));
    }

    /// The fill-reducing order of the analysis, `order[new] = old` (the factor is that of
    /// P A Pᵀ with (P A Pᵀ)_{kl} = A_{order[k], order[l]}); the identity when there is none.
    pub fn order(&self) -> Vec<usize> {
        match self.symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..self.dim()).collect(),
        }
    }

    /// k_i, the entries of row i of L (its unit diagonal included), by original row: the
    /// symbolic structure's, known from the analysis on. The count that
    /// [`Self::ldlt_backward_error`]'s γ_{2k_i+8} reads, for [`ldlt_error_floor`].
    pub fn row_counts(&self) -> Vec<u32> {
        let mut permuted = vec![1u32; self.dim()];
        self.visit_columns(|_, rows, _| {
            for &i in &rows[1..] {
                permuted[i] += 1;
            }
        });
        let mut counts = vec![0; self.dim()];
        for (k, &old) in self.order().iter().enumerate() {
            counts[old] = permuted[k];
        }
        counts
    }

    /// Column by column, for either factorization (same storage).
    fn visit_columns(&self, mut f: impl FnMut(usize, &[usize], usize)) {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (cp, ri) = (s.col_ptr(), s.row_idx());
                for j in 0..self.dim() {
                    f(j, &ri[cp[j]..cp[j + 1]], cp[j]);
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                // Supernode t: columns begin..end stored column-major from col_ptr_for_val[t],
                // the dense diagonal block's rows first, then one row per entry of its pattern.
                let (begin, end) = (s.supernode_begin(), s.supernode_end());
                let (row_ptr, val_ptr, row_idx) =
                    (s.col_ptr_for_row_idx(), s.col_ptr_for_val(), s.row_idx());
                let mut rows = Vec::new();
                for t in 0..s.n_supernodes() {
                    rows.clear();
                    rows.extend(begin[t]..end[t]);
                    rows.extend_from_slice(&row_idx[row_ptr[t]..row_ptr[t + 1]]);
                    for c in 0..end[t] - begin[t] {
                        f(begin[t] + c, &rows[c..], val_ptr[t] + c * rows.len() + c);
                    }
                }
            }
        }
    }

    /// An a-posteriori bound on the backward error of the last LDLᴴ in the 2-norm: the computed
    /// factors are the exact ones of A + ΔA with |ΔA_ij| ≤ c_ij·u·(|L||D||Lᴴ|)_ij (Higham,
    /// *Accuracy and Stability of Numerical Algorithms*, Thm. 9.3, LU without pivoting with
    /// U = DLᴴ). Entry (i, j) sums k_ij ≤ k_i terms L_il d_l L̄_jl, k_i the entries of row i of
    /// L: in complex arithmetic the sum is within √2·γ_{k_i} of Σ|terms| in modulus (any order,
    /// so faer's blocked supernodes too, and the split ones of [`FactorSplit`], which sum a top
    /// supernode's updates from each side apart), each product within √2γ₂ + u (Lemma 3.5), the
    /// division by d_j within u (2u as a product with its rounded reciprocal, as faer's
    /// supernodal kernel and the split compute it: √2·k_i + 3.9 + 2 is still below
    /// 1.5·k_i + 6), so c_ij ≤ 1.5·k_i + 6 and γ_{2k_i+8} covers it. As ‖ΔA‖₂ ≤ ‖|ΔA|‖_∞ for
    /// Hermitian ΔA, the bound is max_i γ_{2k_i+8}·(|L|(|D|(|Lᴴ|·1)))_i, the row sums enlarged for
    /// their own rounding: O(nnz(L)), no second factorization.
    pub fn ldlt_backward_error(&self) -> f64 {
        let (rows_sum, row_count) = self.ldlt_product_row_sums();
        let (u, k_max) = (
            T::UNIT_ROUNDOFF,
            row_count.iter().copied().max().unwrap_or(1),
        );
        // The row sums of moduli are computed with relative error below γ_{2k+4} (and the
        // moduli within 4 units of the double rounding).
        let sums = 1.0
            + gamma_with(crate::linalg::roundoff::U, 2 * k_max + 4)
            + 4.0 * crate::linalg::roundoff::U;
        rows_sum
            .iter()
            .zip(&row_count)
            .fold(0.0f64, |m, (&w, &k)| m.max(gamma_with(u, 2 * k + 8) * w))
            * sums
    }

    /// The row sums (|L||D||Lᴴ|·1)_i of the last LDLᴴ and k_i, the entries of row i of L (its
    /// unit diagonal included), both in the factorization's (permuted) order.
    pub(crate) fn ldlt_product_row_sums(&self) -> (Vec<f64>, Vec<usize>) {
        let dim = self.dim();
        // (|Lᴴ|1)_j·|d_j| from column j alone, then column j's part of the rows of |L| times it:
        // one pass over the factor, the moduli of one column at a time.
        let mut rows_sum = vec![0.0; dim];
        let mut row_count = vec![1usize; dim];
        let mut m = Vec::new();
        self.visit_ldlt_columns(|j, rows, first| {
            T::moduli_into(&self.values[first..first + rows.len()], &mut m);
            let scaled = m[0] * (1.0 + m[1..].iter().sum::<f64>());
            rows_sum[j] += scaled;
            for (&i, &l) in rows[1..].iter().zip(&m[1..]) {
                rows_sum[i] += l * scaled;
                row_count[i] += 1;
            }
        });
        (rows_sum, row_count)
    }

    /// The symbolic structure of the factor, for [`crate::linalg::residual`].
    pub(crate) fn symbolic_raw(&self) -> &SymbolicCholeskyRaw<usize> {
        self.symbolic.raw()
    }

    /// The values of the last LDLᴴ (`ldlt`) or LLᴴ (as [`Self::visit_ldlt_columns`] and
    /// [`Self::visit_llt_columns`] read them).
    ///
    /// # Panics
    ///
    /// Without a successful factorization of that kind before.
    pub(crate) fn factor_values(&self, ldlt: bool) -> &[T] {
        assert_eq!(self.state, if ldlt { State::Ldlt } else { State::Llt });
        &self.values
    }

    /// The row sums (|L||Lᴴ|·1)_i of the last LLᴴ, in the factorization's (permuted) order:
    /// column j adds |L_ij|·Σ_k |L_kj| to each of its rows i.
    pub(crate) fn llt_product_row_sums(&self) -> Vec<f64> {
        assert_eq!(self.state, State::Llt);
        let mut rows_sum = vec![0.0; self.dim()];
        let mut m = Vec::new();
        self.visit_columns(|_, rows, first| {
            T::moduli_into(&self.values[first..first + rows.len()], &mut m);
            let column: f64 = m.iter().sum();
            for (&i, &l) in rows.iter().zip(&m) {
                rows_sum[i] += l * column;
            }
        });
        rows_sum
    }

    /// `inverse[old] = new` of the fill-reducing order; `None` for the identity.
    pub(crate) fn inverse_order(&self) -> Option<Vec<usize>> {
        self.symbolic.perm().map(|p| p.arrays().1.to_vec())
    }

    /// Inertia of the last LDLᴴ: the numbers of negative and of non-positive pivots.
    pub fn inertia_below(&self, threshold: f64) -> usize {
        self.ldlt_pivots()
            .iter()
            .filter(|&&d| d < threshold)
            .count()
    }

    /// For a simplicial LDLᴴ with pivot d_k (permuted index k): v = P L⁻ᴴ e_k, for which
    /// v* A v = d_k exactly in exact arithmetic (a negative-curvature direction when d_k < 0).
    pub fn pivot_direction(&self, k: usize) -> Option<Vec<T>> {
        let SymbolicCholeskyRaw::Simplicial(s) = self.symbolic.raw() else {
            return None;
        };
        let n = self.dim();
        let (cp, ri) = (s.col_ptr(), s.row_idx());
        let mut v = vec![T::zero_impl(); n];
        v[k] = T::one_impl();
        // Back substitution with the unit upper triangular Lᴴ, columns of L read directly.
        for j in (0..k).rev() {
            let mut sum = T::zero_impl();
            for (&i, l) in ri[cp[j] + 1..cp[j + 1]]
                .iter()
                .zip(&self.values[cp[j] + 1..cp[j + 1]])
            {
                if i <= k {
                    sum += T::conj_impl(l) * v[i];
                }
            }
            v[j] = -sum;
        }
        let mut out = vec![T::zero_impl(); n];
        match self.symbolic.perm() {
            Some(perm) => {
                let (fwd, _) = perm.arrays();
                for (i, &f) in fwd.iter().enumerate() {
                    out[f] = v[i];
                }
            }
            None => out = v,
        }
        Some(out)
    }
}

/// Clears the upper halves of the AVX registers (`vzeroupper`) where the CPU has AVX. faer's
/// dense kernels, selected at run time, use AVX and can return with those halves dirty; the
/// SSE code this crate is compiled to then pays a false dependency on them at every instruction:
/// a block solve of W̃ + σI for city10000 took 90 ms from such a state and 24 ms from a clean
/// one (AMD EPYC). The results are the same bits either way.
#[inline]
fn clear_upper_avx() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX (detected above), all `vzeroupper` needs; it touches no memory.
        unsafe { std::arch::x86_64::_mm256_zeroupper() }
    }
}

/// The scalars factored here: f64 (Newton systems) and c64 (W̃(λ)).
pub trait Scalar:
    ComplexField
    + Copy
    + std::ops::Add<Output = Self>
    + std::ops::AddAssign
    + std::ops::Mul<Output = Self>
    + std::ops::Neg<Output = Self>
{
    /// The real part.
    fn re(self) -> f64;
    /// The modulus.
    fn modulus(self) -> f64;
    /// The moduli of a slice, into `out` (cleared first).
    fn moduli_into(values: &[Self], out: &mut Vec<f64>) {
        out.clear();
        out.extend(values.iter().map(|v| v.modulus()));
    }
    /// The memory of real values as room for values of this type (its length cleared), or
    /// nothing where the allocation cannot hold them.
    fn room_of(values: Vec<f64>) -> Vec<Self>;
    /// The unit roundoff of the arithmetic, for the error bounds of [`SparseFactor`].
    const UNIT_ROUNDOFF: f64 = crate::linalg::roundoff::U;
}

impl Scalar for f64 {
    fn re(self) -> f64 {
        self
    }
    fn room_of(mut values: Vec<f64>) -> Vec<Self> {
        values.clear();
        values
    }
    fn modulus(self) -> f64 {
        self.abs()
    }
}

/// Double-double complex numbers (faer's `cx128`, ~32 significant digits), for factorizations
/// whose backward error must lie far below double precision's. The error bounds take the unit
/// roundoff as [`crate::linalg::roundoff::DOUBLE_DOUBLE_U`] = 32·u², twice what each of its
/// operations is proven to need under the weak model of rounding (sums within 5.02u² of
/// |a| + |b|, products within 6.01u², products by a pivot's reciprocal within 15.2u²).
impl Scalar for faer::cx128 {
    fn re(self) -> f64 {
        self.re.0 + self.re.1
    }
    fn room_of(_: Vec<f64>) -> Vec<Self> {
        Vec::new()
    }
    fn modulus(self) -> f64 {
        (self.re.0 * self.re.0 + self.im.0 * self.im.0).sqrt() * (1.0 + 4.0 * f64::EPSILON)
    }
    const UNIT_ROUNDOFF: f64 = crate::linalg::roundoff::DOUBLE_DOUBLE_U;
}

impl Scalar for c64 {
    fn re(self) -> f64 {
        self.re
    }
    /// The same allocation as pairs of f64 (shrunk to an even capacity first, in place: the
    /// vector is empty; bytemuck checks size and alignment).
    fn room_of(mut values: Vec<f64>) -> Vec<Self> {
        values.clear();
        values.shrink_to(values.capacity() & !1);
        bytemuck::allocation::try_cast_vec(values).unwrap_or_default()
    }
    /// √(re² + im²), within 3 units of rounding (the bounds allow 4); `hypot`, five times
    /// slower, only where the squares underflow or overflow.
    fn modulus(self) -> f64 {
        let s = self.re * self.re + self.im * self.im;
        if s >= f64::MIN_POSITIVE && s.is_finite() {
            s.sqrt()
        } else if self.re == 0.0 && self.im == 0.0 {
            // The zeros a supernodal factor stores.
            0.0
        } else {
            self.norm()
        }
    }
    /// As [`Scalar::modulus`], the square roots in one branch-free (vectorized) pass.
    fn moduli_into(values: &[Self], out: &mut Vec<f64>) {
        out.clear();
        out.extend(values.iter().map(|v| v.re * v.re + v.im * v.im));
        for s in out.iter_mut() {
            *s = s.sqrt();
        }
        // Where the square underflowed or overflowed (and at zeros): the careful modulus.
        let smallest = f64::MIN_POSITIVE.sqrt();
        for (m, v) in out.iter_mut().zip(values) {
            if !(*m >= smallest && m.is_finite()) {
                *m = v.modulus();
            }
        }
    }
}

/// Whether `n` fits in the index type `I` as faer reads it (signed: below 2³¹ for `u32`).
fn fits<I: Index>(n: usize) -> bool {
    usize::BITS - n.leading_zeros() < I::BITS
}

/// A triangular sparse matrix (the upper triangle of a Hermitian one, or of a permutation of it:
/// [`Assembly::permuted`]) with a fixed pattern whose values are rebuilt by scatter-adding
/// contributions into precomputed slots (O(nnz) per assembly, no sorting). Its pattern's indices
/// are of type `I`, as its [`SparseFactor`]'s ([`Assembly::try_blocked`] builds `u32` ones).
pub struct Assembly<T, I: Index = usize> {
    /// The matrix (upper triangle), values rewritten by [`Assembly::fill`].
    pub matrix: SparseColMat<I, T>,
    slots: Slots,
}

/// Each contribution's entry of an [`Assembly`]: 32-bit for a matrix of fewer than 2³² entries,
/// 64-bit beyond. At 10⁶ planar poses the Newton system's 16·10⁶ slots took 125 MiB as 64-bit
/// ones, at its peak of memory.
#[derive(Debug, PartialEq)]
enum Slots {
    Narrow(Vec<u32>),
    Wide(Vec<usize>),
}

impl Slots {
    /// Room for `len` slots into a matrix of at most `entries` entries.
    fn with_capacity(len: usize, entries: usize) -> Self {
        if u32::try_from(entries).is_ok() {
            Slots::Narrow(Vec::with_capacity(len))
        } else {
            Slots::Wide(Vec::with_capacity(len))
        }
    }

    /// `len` slots, each 0 until [`Self::set`], into a matrix of at most `entries` entries.
    fn zeroed(len: usize, entries: usize) -> Self {
        if u32::try_from(entries).is_ok() {
            Slots::Narrow(vec![0; len])
        } else {
            Slots::Wide(vec![0; len])
        }
    }

    /// Appends a slot (below the `entries` given at creation).
    fn push(&mut self, at: usize) {
        match self {
            Slots::Narrow(v) => v.push(at as u32),
            Slots::Wide(v) => v.push(at),
        }
    }

    /// Sets slot k (below the `entries` given at creation).
    fn set(&mut self, k: usize, at: usize) {
        match self {
            Slots::Narrow(v) => v[k] = at as u32,
            Slots::Wide(v) => v[k] = at,
        }
    }

    fn len(&self) -> usize {
        match self {
            Slots::Narrow(v) => v.len(),
            Slots::Wide(v) => v.len(),
        }
    }

    fn iter(&self) -> SlotIter<'_> {
        match self {
            Slots::Narrow(v) => SlotIter::Narrow(v.iter()),
            Slots::Wide(v) => SlotIter::Wide(v.iter()),
        }
    }
}

/// The slots of an [`Assembly::fill_with`], in the pattern's order.
enum SlotIter<'a> {
    Narrow(std::slice::Iter<'a, u32>),
    Wide(std::slice::Iter<'a, usize>),
}

impl SlotIter<'_> {
    #[inline]
    fn next(&mut self) -> Option<usize> {
        match self {
            SlotIter::Narrow(i) => i.next().map(|&s| s as usize),
            SlotIter::Wide(i) => i.next().copied(),
        }
    }
}

impl<T: Scalar> Assembly<T> {
    /// The pattern of entries (row, col) of one triangle, row ≤ col (upper) or row ≥ col
    /// (lower, as the supernodal factors read it: [`Layout::stored_side`]), in the order
    /// [`Assembly::fill`] will receive their values (duplicates allowed: they add up).
    pub fn new(dim: usize, entries: &[(usize, usize)]) -> Self {
        debug_assert!(
            entries.iter().all(|&(r, c)| r <= c) || entries.iter().all(|&(r, c)| r >= c),
            "entries of both triangles"
        );
        Self::from_entries(dim, entries.to_vec())
    }

    /// As [`Assembly::new`] for the symmetric permutation P A Pᵀ (`order[new] = old`; entries
    /// still given as (row, col) of A with row ≤ col), stored as the `side` triangle: the form a
    /// [`SparseFactor::analyze_in_order`] factors without copying. Real symmetric matrices only:
    /// a complex entry that the permutation moves across the diagonal would need its conjugate.
    pub fn permuted(dim: usize, entries: &[(usize, usize)], order: &[usize], side: Side) -> Self {
        assert!(
            T::IS_REAL,
            "Assembly::permuted: real symmetric matrices only"
        );
        let mut new = vec![0; dim];
        for (k, &old) in order.iter().enumerate() {
            new[old] = k;
        }
        let entries = entries
            .iter()
            .map(|&(r, c)| {
                debug_assert!(r <= c);
                let (a, b) = (new[r].min(new[c]), new[r].max(new[c]));
                match side {
                    Side::Upper => (a, b),
                    Side::Lower => (b, a),
                }
            })
            .collect();
        Self::from_entries(dim, entries)
    }

    /// [`Assembly::try_blocked`] with `usize` indices, which hold any count.
    pub fn blocked(
        sizes: &[usize],
        blocks: &[(usize, usize)],
        order: &[usize],
        side: Side,
    ) -> Self {
        Self::try_blocked(sizes, blocks, order, side).expect("usize indices hold any count")
    }

    /// The compressed-column pattern of `entries` (duplicates merged, rows sorted) by a
    /// counting sort on the columns ([`column_buckets`]), O(nnz + dim), and each entry's slot in
    /// it. Hand-written: faer's `try_new_from_triplets` sorts all triplets; this made pgo-solve
    /// 3-5% faster on M3500, intel and city10000 (medians of 21 interleaved runs). (W̃ itself,
    /// whose values are summed once, is built by the same bucketing in
    /// `problem::matrix`'s `Terms`.)
    fn from_entries(dim: usize, entries: Vec<(usize, usize)>) -> Self {
        let (start, order) = column_buckets(dim, entries.iter().map(|&(_, c)| c));
        // (row, entry index) bucketed by column, then sorted within each column.
        let mut by_column: Vec<(usize, usize)> = order.iter().map(|&k| (entries[k].0, k)).collect();
        let mut col_ptr = Vec::with_capacity(dim + 1);
        let mut row_idx = Vec::with_capacity(entries.len());
        let mut slots = Slots::zeroed(entries.len(), entries.len());
        col_ptr.push(0);
        for c in 0..dim {
            let bucket = &mut by_column[start[c]..start[c + 1]];
            bucket.sort_unstable();
            for &(r, k) in bucket.iter() {
                if row_idx.len() == col_ptr[c] || row_idx.last() != Some(&r) {
                    row_idx.push(r);
                }
                slots.set(k, row_idx.len() - 1);
            }
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        let symbolic = SymbolicSparseColMat::new_checked(dim, dim, col_ptr, None, row_idx);
        let matrix = SparseColMat::new(symbolic, vec![T::zero_impl(); nnz]);
        Assembly { matrix, slots }
    }
}

impl<T: Scalar, I: Index> Assembly<T, I> {
    /// [`Assembly::permuted`] for a matrix of dense blocks: block u spans `sizes[u]` coordinates
    /// (consecutive, blocks in index order), `blocks` lists the pairs (u, v), u ≤ v, whose block
    /// is in the pattern (duplicates allowed), and `order` orders the blocks (`order[new] = old`;
    /// each block's coordinates stay together, in their order). The entries, in the order
    /// [`Assembly::fill`] receives their values: for each pair (u, v) of `blocks`, for a < sizes[u],
    /// for b < sizes[v], coordinate (a of u, b of v), only a ≤ b within a diagonal block (u = v).
    ///
    /// The same pattern and slots as [`Assembly::permuted`] given every entry and the expanded
    /// order, built from the blocks: one sort of the pairs instead of one of the entries (6×6
    /// blocks in 3D, 21 to 36 entries each). At 10⁶ planar poses the entrywise sort took 2.3 s.
    /// Real symmetric matrices only, as [`Assembly::permuted`]. `None` where the pattern's
    /// entries do not fit in the index type `I` (faer's indices are signed: below 2³¹ for
    /// `u32`).
    pub fn try_blocked(
        sizes: &[usize],
        blocks: &[(usize, usize)],
        order: &[usize],
        side: Side,
    ) -> Option<Self> {
        assert!(
            T::IS_REAL,
            "Assembly::blocked: real symmetric matrices only"
        );
        let nb = sizes.len();
        // Each block's position in the new order, and the new coordinate of its first row.
        let mut position = vec![0usize; nb];
        for (new, &old) in order.iter().enumerate() {
            position[old] = new;
        }
        let mut first = vec![0usize; nb + 1];
        for (new, &old) in order.iter().enumerate() {
            first[new + 1] = first[new] + sizes[old];
        }
        let dim = first[nb];
        // The pairs as (row, col) block positions of the stored triangle, bucketed by column and
        // sorted within it: the block-level pattern, and where each pair lands in it.
        let stored = |&(u, v): &(usize, usize)| {
            debug_assert!(u <= v);
            let (a, b) = (position[u], position[v]);
            match side {
                Side::Upper => (a.min(b), a.max(b)),
                Side::Lower => (a.max(b), a.min(b)),
            }
        };
        let mut start = vec![0usize; nb + 1];
        for pair in blocks {
            start[stored(pair).1 + 1] += 1;
        }
        for c in 0..nb {
            start[c + 1] += start[c];
        }
        let mut by_column = vec![(0usize, 0usize); blocks.len()];
        let mut next = start.clone();
        for (k, pair) in blocks.iter().enumerate() {
            let (r, c) = stored(pair);
            by_column[next[c]] = (r, k);
            next[c] += 1;
        }
        // Per pair: its column, and the coordinate rows above it in each of that column's
        // coordinate columns (off-diagonal blocks only: the diagonal block's count varies with
        // the coordinate column, `diagonal_before` says whether to add it).
        let mut above = vec![0usize; blocks.len()];
        let mut diagonal_before = vec![false; blocks.len()];
        // Per block column: its distinct block rows.
        let mut rows_start = vec![0usize; nb + 1];
        let mut rows: Vec<usize> = Vec::with_capacity(blocks.len());
        for c in 0..nb {
            let bucket = &mut by_column[start[c]..start[c + 1]];
            bucket.sort_unstable();
            let mut offset = 0;
            let mut diagonal = false;
            let mut last = usize::MAX;
            for &(r, k) in bucket.iter() {
                if r != last {
                    if last != usize::MAX {
                        if last == c {
                            diagonal = true;
                        } else {
                            offset += sizes[order[last]];
                        }
                    }
                    rows.push(r);
                    last = r;
                }
                above[k] = offset;
                diagonal_before[k] = diagonal;
            }
            rows_start[c + 1] = rows.len();
        }
        // Rows of the diagonal block in coordinate column b of a block of size s.
        let diagonal_rows = |s: usize, b: usize| match side {
            Side::Upper => b + 1,
            Side::Lower => s - b,
        };
        // The coordinate-level pattern, column by column, its length counted first (no
        // reallocation as it grows).
        let mut nnz = 0;
        for c in 0..nb {
            let s = sizes[order[c]];
            for &r in &rows[rows_start[c]..rows_start[c + 1]] {
                nnz += if r == c {
                    s * (s + 1) / 2
                } else {
                    s * sizes[order[r]]
                };
            }
        }
        if !fits::<I>(nnz) || !fits::<I>(dim) {
            return None;
        }
        let mut col_ptr: Vec<I> = Vec::with_capacity(dim + 1);
        col_ptr.push(I::truncate(0));
        let mut row_idx: Vec<I> = Vec::with_capacity(nnz);
        for c in 0..nb {
            let s = sizes[order[c]];
            for b in 0..s {
                for &r in &rows[rows_start[c]..rows_start[c + 1]] {
                    if r == c {
                        let from = match side {
                            Side::Upper => 0,
                            Side::Lower => b,
                        };
                        row_idx.extend(
                            (from..from + diagonal_rows(s, b)).map(|a| I::truncate(first[c] + a)),
                        );
                    } else {
                        row_idx.extend((first[r]..first[r + 1]).map(I::truncate));
                    }
                }
                col_ptr.push(I::truncate(row_idx.len()));
            }
        }
        debug_assert_eq!(row_idx.len(), nnz);
        // Each entry's slot, in the entries' order.
        let contributions = blocks
            .iter()
            .map(|&(u, v)| {
                if u == v {
                    sizes[u] * (sizes[u] + 1) / 2
                } else {
                    sizes[u] * sizes[v]
                }
            })
            .sum();
        let mut slots = Slots::with_capacity(contributions, row_idx.len());
        for (k, &(u, v)) in blocks.iter().enumerate() {
            let (r, c) = stored(&(u, v));
            let diagonal_block = u == v;
            for a in 0..sizes[u] {
                for b in 0..sizes[v] {
                    if diagonal_block && b < a {
                        continue;
                    }
                    // (a of u, b of v) as (row, col) within the stored blocks (r, c).
                    let (i, j) = match (diagonal_block, side) {
                        (true, Side::Upper) => (a, b),
                        (true, Side::Lower) => (b, a),
                        _ if position[u] == r => (a, b),
                        _ => (b, a),
                    };
                    let mut at = col_ptr[first[c] + j].zx() + above[k];
                    if diagonal_before[k] {
                        at += diagonal_rows(sizes[order[c]], j);
                    }
                    at += match (diagonal_block, side) {
                        (true, Side::Lower) => i - j,
                        _ => i,
                    };
                    slots.push(at);
                }
            }
        }
        let symbolic = SymbolicSparseColMat::new_checked(dim, dim, col_ptr, None, row_idx);
        let matrix = SparseColMat::new(symbolic, vec![T::zero_impl(); nnz]);
        Some(Assembly { matrix, slots })
    }

    /// Rewrites the values: entry k of the pattern receives `values[k]` (summed over duplicates).
    pub fn fill(&mut self, values: &[T]) {
        assert_eq!(values.len(), self.slots.len());
        self.fill_with(|fill| values.iter().for_each(|&v| fill.push(v)));
    }

    /// As [`Assembly::fill`], the values handed over one at a time, in the pattern's order, by
    /// `produce` (through [`Fill::push`]): the same sums in the same order, without an array of
    /// the values (at 10⁶ planar poses, 130 MB for a Newton system's and 90 MB for W̃'s).
    pub fn fill_with(&mut self, produce: impl FnOnce(&mut Fill<'_, T>)) {
        let out = self.matrix.val_mut();
        out.fill(T::zero_impl());
        let mut fill = Fill {
            out,
            slots: self.slots.iter(),
        };
        produce(&mut fill);
        assert!(
            fill.slots.next().is_none(),
            "Assembly::fill_with: fewer values than the pattern's entries"
        );
    }
}

/// The values of an [`Assembly::fill_with`], received in the pattern's order.
pub struct Fill<'a, T> {
    out: &'a mut [T],
    slots: SlotIter<'a>,
}

impl<T: Scalar> Fill<'_, T> {
    /// The value of the next entry of the pattern (added to its slot).
    #[inline]
    pub fn push(&mut self, value: T) {
        let s = self
            .slots
            .next()
            .expect("Assembly::fill_with: more values than the pattern's entries");
        self.out[s] += value;
    }
}

/// A lower bound, known before any factorization, on the error bound ‖E‖ that an LDLᴴ of an
/// equilibrated B − μI shows ([`SparseFactor::ldlt_backward_error`]:
/// max_i γ_{2k_i+8}·(|L||D||Lᴴ|·1)_i, k_i the entries of row i of L): as |B| = |LDLᴴ| ≤
/// |L||D||Lᴴ| entrywise (to within that error itself), max_i γ_{2k_i+8}·Σ_j|B_ij|, from the
/// symbolic row counts `row_counts` ([`SparseFactor::row_counts`]) and the row sums `row_sums`
/// of |B|. A shift of the certificates' ladder below it cannot prove a gap
/// (`crate::certify::ladder::isolate`). The error bounds measured on the public planar files and
/// generated graphs of 10⁵ and 10⁶ poses are 2.5-5 times it.
pub fn ldlt_error_floor(row_counts: &[u32], row_sums: &[f64]) -> f64 {
    row_counts.iter().zip(row_sums).fold(0.0f64, |m, (&k, &s)| {
        m.max(crate::linalg::roundoff::gamma(2 * k as usize + 8) * s)
    })
}

/// Where each column's bucket starts for entries in columns `cols` (counts, then their prefix
/// sums): `start[c]..start[c + 1]`, `start[dim]` entries in all.
fn bucket_starts(dim: usize, cols: impl Iterator<Item = usize>) -> Vec<usize> {
    let mut start = vec![0usize; dim + 1];
    for c in cols {
        start[c + 1] += 1;
    }
    for c in 0..dim {
        start[c + 1] += start[c];
    }
    start
}

/// The entries 0..len of a sparse matrix bucketed by their columns `cols` (a counting sort,
/// O(len + dim)): `order[start[c]..start[c + 1]]` are the entries of column c, in their own
/// order. Returns `(start, order)`.
pub fn column_buckets(
    dim: usize,
    cols: impl Iterator<Item = usize> + Clone,
) -> (Vec<usize>, Vec<usize>) {
    let start = bucket_starts(dim, cols.clone());
    let mut next = start.clone();
    let mut order = vec![0usize; start[dim]];
    for (k, c) in cols.enumerate() {
        order[next[c]] = k;
        next[c] += 1;
    }
    (start, order)
}

/// A fill-reducing rank of each pose: AMD on the pose graph (`n` nodes, `edges`), or METIS's
/// nested dissection where that makes the factorization cheaper. Ordering the n-node graph
/// instead of the expanded matrices (3n real or 2n complex rows) is several times cheaper and
/// gives the factorizations dense blocks (supernodes) per pose.
///
/// AMD is greedy (the least fill at each step) and the better order on the sparse planar
/// graphs; on denser ones nested dissection (George 1973; Karypis and Kumar 1998, METIS) can find
/// orders with far fewer operations: sphere_bignoise's pose graph, Σ_j c_j² 2.66e6 against AMD's
/// 4.02e6. It is tried only where AMD's order costs the factorizations at least
/// [`DISSECTION_WORTH`] multiply-adds per entry of the graph, and kept only where its count
/// ([`elimination_work`]) is at most [`DISSECTION_GAIN`] times AMD's. `block_work` converts the
/// pose graph's multiply-adds into the factorizations' real ones: b³ for b real rows per pose
/// ([`SPATIAL_BLOCK_WORK`]), 4b³ for b complex ones ([`PLANAR_BLOCK_WORK`]).
pub fn pose_rank(
    n: usize,
    edges: impl Iterator<Item = (usize, usize)>,
    block_work: f64,
) -> Vec<usize> {
    let graph = pose_graph(n, edges);
    let pattern = graph.as_ref();
    let Some((mut rank, count)) = amd_rank(pattern) else {
        return (0..n).collect();
    };
    if count * block_work >= DISSECTION_WORTH * pattern.compute_nnz() as f64
        && let Some(nd) = nested_dissection(pattern)
        && elimination_work(pattern, &nd) <= DISSECTION_GAIN * elimination_work(pattern, &rank)
    {
        rank = nd;
    }
    rank
}

/// AMD's rank of each pose of the pose graph (`n` nodes, `edges`), the identity where AMD fails:
/// [`pose_rank`] without its nested dissection, for a factorization too cheap to pay for METIS
/// (the 3D chordal relaxation's, [`crate::se3::rounding::chordal`]).
pub fn amd_pose_rank(n: usize, edges: impl Iterator<Item = (usize, usize)>) -> Vec<usize> {
    amd_rank(pose_graph(n, edges).as_ref()).map_or_else(|| (0..n).collect(), |(rank, _)| rank)
}

/// The pattern of the pose graph's matrix (`n` nodes, `edges`): its upper triangle, the diagonal
/// included, each edge once, rows sorted in each column. Bucketed by column (a counting sort),
/// each column's rows then sorted and repeated edges merged: the pattern alone, without an
/// [`Assembly`]'s slots and values: M3500's in 0.2 ms against 0.44, ais2klinik's in 0.6 ms
/// against 1.46, of an ordering that the first Newton step waits for (on the second core, before
/// the Newton system's analysis).
fn pose_graph(
    n: usize,
    edges: impl Iterator<Item = (usize, usize)>,
) -> SymbolicSparseColMat<usize> {
    let pairs: Vec<(usize, usize)> = edges
        .filter(|(i, j)| i != j)
        .map(|(i, j)| (i.min(j), i.max(j)))
        .collect();
    // Each column's edges, then its diagonal entry (the largest row of an upper column).
    let mut col_ptr = vec![0usize; n + 1];
    for &(_, c) in &pairs {
        col_ptr[c + 1] += 1;
    }
    for c in 0..n {
        col_ptr[c + 1] += col_ptr[c] + 1;
    }
    let mut next = col_ptr.clone();
    let mut row_idx = vec![0usize; col_ptr[n]];
    for &(r, c) in &pairs {
        row_idx[next[c]] = r;
        next[c] += 1;
    }
    // Sorted and merged in place, columns moved down over the merged entries.
    let mut len = 0;
    for c in 0..n {
        let (from, to) = (col_ptr[c], col_ptr[c + 1]);
        row_idx[to - 1] = c;
        row_idx[from..to - 1].sort_unstable();
        col_ptr[c] = len;
        for k in from..to {
            if k == from || row_idx[k] != row_idx[k - 1] {
                row_idx[len] = row_idx[k];
                len += 1;
            }
        }
    }
    col_ptr[n] = len;
    row_idx.truncate(len);
    SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
}

/// faer's AMD order of a graph (`pattern`: the upper triangle, diagonal included) as a rank of
/// each node, with AMD's own count of the LDLᵀ's multiply-adds; `None` if it fails.
fn amd_rank(pattern: SymbolicSparseColMatRef<'_, usize>) -> Option<(Vec<usize>, f64)> {
    let n = pattern.ncols();
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    let mut mem = MemBuffer::new(faer::sparse::linalg::amd::order_scratch::<usize>(
        n,
        pattern.compute_nnz(),
    ));
    let count = faer::sparse::linalg::amd::order(
        &mut perm,
        &mut perm_inv,
        pattern,
        Default::default(),
        MemStack::new(&mut mem),
    )
    .ok()?;
    // perm_inv[old] = new.
    Some((perm_inv, count.n_mult_subs_ldl))
}

/// The factorizations' real multiply-adds (AMD's count on the pose graph times the caller's
/// `block_work`) per entry of the pose graph from which [`nested_dissection`] is tried: METIS
/// takes 7 to 34 ms on public graphs of 2 200 to 10 000 poses, which the factorizations must
/// outweigh. In AMD's count per entry (times 6³ = 216 for the 3D Newton systems), the denser 3D
/// graphs reach it (sphere2500 119, sphere_bignoise 182, torus3D 203); cubicle (92) and
/// parking-garage (6) keep AMD without the partitioning's cost. The planar factorizations, with
/// 2 complex rows per pose (32 real multiply-adds per pose-graph one), would need 675: every
/// planar file has 0.5 to 52 (city10000 the largest), and the generated 10⁶-pose Manhattan
/// world of `scripts/bench-scale` 103, where METIS took 5.5 s for an order that halved Σ c_j²
/// but saved the factorizations about 1 s (whole process 45.2 s against 41.0 with AMD; at
/// 10⁵ poses, 71, forcing it cost 21%).
pub const DISSECTION_WORTH: f64 = 100.0 * SPATIAL_BLOCK_WORK;

/// The stored values from which a supernodal LLᴴ's solves split its tree between two cores
/// ([`TreeSplit`]). Measured in whole solves (Newton's, three runs each), split against faer's
/// sequential one: torus3D (4.0·10⁶ values) 2.0-3.5 ms against 3.7-5.5, cubicle (3.9·10⁶)
/// 2.3-3.4 against 4.2-5.4; below it they gained nothing or lost: cityTrees10000 (5.3·10⁵)
/// 0.8-1.9 against 1.0-1.6 ms, parking-garage (5.0·10⁵) 0.37-0.84 against 0.35-0.42 ms (the
/// handing over and the top set's sequential part outweigh half a solve). From 2¹⁷, with the
/// second core's thread kept (no thread started per solve), whole process split/not, 15
/// interleaved pairs: cityTrees10000 1.02, M3500 1.00, parking-garage 0.99.
pub const SPLIT_SOLVE_MIN_VALUES: usize = 1 << 20;

/// When faer merges two adjacent supernodes of n columns in all (relaxed supernodal
/// amalgamation): where the merged block's fraction of stored zeros stays below the bound of the
/// first (limit, bound) with n ≤ limit. Half faer's default bounds (1.0, 0.8, 0.1 and 0.05 for
/// the same limits), whose merges stored the factors' zeros by the ten million at 10⁶ planar
/// poses: the Newton LLᵀ's 103.4·10⁶ values against 85.5·10⁶ with these (788 MiB against 652),
/// the certificate's LDLᴴ 53.9·10⁶ complex values against 38.3·10⁶ (822 MiB against 584). The
/// larger dense blocks bought no speed: whole process at 10⁶ poses 13.6-14.0 s against
/// 14.3-15.2 s (three runs each; 13.3 s both in a later pair), at 10⁵ poses 0.95 of the default's
/// time, on the public files within 3% either way (medians of 9 to 21 interleaved runs).
/// Merging nothing at all stored the fewest zeros (68.7·10⁶ Newton values) but ran slower
/// (14.8-15.4 s at 10⁶), with more supernodes to index.
pub const SUPERNODE_RELAXATION: &[(usize, f64)] =
    &[(4, 0.5), (16, 0.3), (48, 0.05), (usize::MAX, 0.02)];

/// A Hermitian matrix's pattern (`upper`: its upper triangle, stored as faer's CSC) as
/// P A Pᵀ for a fill-reducing order, without one of its rows and columns where asked, stored as
/// the triangle that a factor's numeric factorizations read. Each entry sits where faer's own
/// permutation (`permute_self_adjoint_to_unsorted`, which a factor analyzed with an order runs
/// on every matrix it factors) puts it: columns in order, within each the entries in the order
/// of A's columns and rows, an entry that the order moves across the diagonal conjugated. A
/// factor analyzed in this order ([`SparseFactor::analyze_in_order`]) then factors faer's copies
/// value for value and slot for slot, the same bits, without the copy.
pub struct Permuted {
    /// The permuted pattern (rows unsorted within a column, as faer's copies).
    pub pattern: SymbolicSparseColMat<usize>,
    /// For each of A's stored entries, in its stored order: its place in the permuted matrix's
    /// values, with [`Permuted::CONJUGATE`] set where the conjugate goes there, or
    /// [`Permuted::DROPPED`] for an entry of the row and column left out.
    slots: Vec<usize>,
}

impl Permuted {
    /// The bit of a slot that marks an entry stored conjugate.
    const CONJUGATE: usize = 1 << (usize::BITS - 1);
    /// The slot of an entry left out.
    const DROPPED: usize = usize::MAX;

    /// P A Pᵀ of `upper`'s matrix A for `order` (`order[new] = old`), stored as the `side`
    /// triangle; without row and column `dropped` where given (then the rows above it move up
    /// by one, and `order` orders the rows that are left in that numbering).
    pub fn new(
        upper: &SparseColMat<usize, c64>,
        order: &[usize],
        side: Side,
        dropped: Option<usize>,
    ) -> Self {
        let n = order.len();
        let mut new = vec![0; n];
        for (k, &old) in order.iter().enumerate() {
            new[old] = k;
        }
        // A's row k in the matrix without `dropped`.
        let kept = |k: usize| match dropped {
            Some(d) if k == d => None,
            Some(d) if k > d => Some(k - 1),
            _ => Some(k),
        };
        let (col_ptr, row_idx) = (upper.symbolic().col_ptr(), upper.symbolic().row_idx());
        // Entry (i, j) of A's upper triangle goes to (column, row, conjugated) of the permuted
        // triangle.
        let place = |i: usize, j: usize| {
            let (a, b) = (new[kept(i)?], new[kept(j)?]);
            let stays = match side {
                Side::Upper => a <= b,
                Side::Lower => a >= b,
            };
            Some(if stays { (b, a, false) } else { (a, b, true) })
        };
        let mut next = vec![0usize; n + 1];
        for j in 0..upper.ncols() {
            for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                if let Some((column, _, _)) = place(i, j) {
                    next[column + 1] += 1;
                }
            }
        }
        for c in 0..n {
            next[c + 1] += next[c];
        }
        let starts = next.clone();
        let mut rows = vec![0; next[n]];
        let mut slots = vec![Self::DROPPED; row_idx.len()];
        for j in 0..upper.ncols() {
            for k in col_ptr[j]..col_ptr[j + 1] {
                if let Some((column, row, conjugated)) = place(row_idx[k], j) {
                    let at = next[column];
                    next[column] += 1;
                    rows[at] = row;
                    slots[k] = at | if conjugated { Self::CONJUGATE } else { 0 };
                }
            }
        }
        let pattern = SymbolicSparseColMat::new_unsorted_checked(n, n, starts, None, rows);
        Permuted { pattern, slots }
    }

    /// The pattern for `order` (as [`Permuted::new`]) with its factor's analysis in that order:
    /// analyzed as the upper triangle, which faer's analysis reads, and laid out again as the
    /// lower one where the `layout` settles on a supernodal factor (whose kernels read that).
    pub fn analyzed(
        upper: &SparseColMat<usize, c64>,
        order: &[usize],
        dropped: Option<usize>,
        layout: Layout,
    ) -> (SparseFactor<c64>, Self) {
        let permuted = Self::new(upper, order, Side::Upper, dropped);
        let factor = SparseFactor::analyze_in_order(permuted.pattern.as_ref(), Side::Upper, layout);
        match factor.read_side() {
            Side::Upper => (factor, permuted),
            Side::Lower => (
                factor.given(Side::Lower),
                Self::new(upper, order, Side::Lower, dropped),
            ),
        }
    }

    /// The number of the permuted matrix's stored entries.
    pub fn len(&self) -> usize {
        self.pattern.row_idx().len()
    }

    /// Whether it stores no entry.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Puts the value `v` of A's `k`-th stored entry into its place among `values` (the permuted
    /// matrix's), conjugated where the permutation moved it across the diagonal; nothing for an
    /// entry left out.
    #[inline]
    pub fn put(&self, k: usize, v: c64, values: &mut [c64]) {
        let slot = self.slots[k];
        if slot != Self::DROPPED {
            values[slot & !Self::CONJUGATE] = if slot & Self::CONJUGATE != 0 {
                v.conj()
            } else {
                v
            };
        }
    }

    /// The permuted matrix of A's own values (`upper`'s).
    pub fn values_of(&self, upper: &SparseColMat<usize, c64>) -> Vec<c64> {
        let mut values = vec![c64::new(0.0, 0.0); self.len()];
        for (k, &v) in upper.val().iter().enumerate() {
            self.put(k, v, &mut values);
        }
        values
    }
}

/// `block_work` of [`pose_rank`] for the 3D problems: the Newton systems' 6 real rows per pose.
pub const SPATIAL_BLOCK_WORK: f64 = 216.0;

/// `block_work` of [`pose_rank`] for the planar problems: the certificate's 2 complex rows per
/// pose (a complex multiply-add is 4 real ones); the Newton systems' 3 real rows give 27.
pub const PLANAR_BLOCK_WORK: f64 = 32.0;

/// The largest ratio of nested dissection's [`elimination_work`] to AMD's at which its order is
/// kept. faer's supernodal kernels run its orders at fewer multiply-adds per second (measured,
/// median of 15 Newton LLᵀ each: torus3D 15% fewer multiply-adds and no faster; on
/// sphere_bignoise 34% fewer and 25% faster).
pub const DISSECTION_GAIN: f64 = 0.8;

/// METIS's nested dissection order of a graph (`pattern`: the upper triangle, diagonal
/// included) as a rank of each node; `None` if METIS fails or the graph is too large for its
/// 32-bit indices.
pub fn nested_dissection(pattern: SymbolicSparseColMatRef<'_, usize>) -> Option<Vec<usize>> {
    let n = pattern.ncols();
    // The adjacency lists of both triangles, without the diagonal (METIS's CSR graph): each
    // off-diagonal entry (i, j) in the lists of i and of j.
    let ends = (0..n).flat_map(|j| {
        pattern
            .row_idx_of_col(j)
            .filter(move |&i| i != j)
            .flat_map(move |i| [i, j])
    });
    let degree = bucket_starts(n, ends);
    let mut next = degree.clone();
    let mut adjacency = vec![0 as metis_sys::idx_t; degree[n]];
    for j in 0..n {
        for i in pattern.row_idx_of_col(j) {
            if i != j {
                adjacency[next[i]] = j as metis_sys::idx_t;
                next[i] += 1;
                adjacency[next[j]] = i as metis_sys::idx_t;
                next[j] += 1;
            }
        }
    }
    let mut xadj: Vec<metis_sys::idx_t> = degree
        .iter()
        .map(|&d| metis_sys::idx_t::try_from(d).ok())
        .collect::<Option<_>>()?;
    let mut nvtxs = metis_sys::idx_t::try_from(n).ok()?;
    if n == 0 {
        return Some(Vec::new());
    }
    let mut perm = vec![0 as metis_sys::idx_t; n];
    let mut iperm = vec![0 as metis_sys::idx_t; n];
    // METIS seeds its random number generator on every call (its default seed, so the order is
    // the same on every run) but keeps its state in a global of the process: one call at a time,
    // so that calls on other threads cannot draw from it in between.
    static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = METIS
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    // SAFETY: METIS_NodeND reads nvtxs + 1 offsets and xadj[nvtxs] neighbours (a valid
    // symmetric CSR graph without self-loops, built above) and writes nvtxs entries to each of
    // perm and iperm; null weights and options ask for its defaults.
    let status = unsafe {
        metis_sys::METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjacency.as_mut_ptr(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return None;
    }
    // iperm[old] = new: the rank.
    iperm.iter().map(|&r| usize::try_from(r).ok()).collect()
}

/// Σ_j c_j² over the columns of the Cholesky factor of a graph's matrix (`pattern`: the upper
/// triangle, diagonal included) eliminated in the order `rank`, c_j the entries of column j on
/// and below the diagonal: the multiply-adds of its factorization (of each pose block's
/// factorizations, scaled by the block's size cubed).
pub fn elimination_work(pattern: SymbolicSparseColMatRef<'_, usize>, rank: &[usize]) -> f64 {
    let n = pattern.ncols();
    let mut entries = Vec::with_capacity(pattern.compute_nnz());
    for j in 0..n {
        for i in pattern.row_idx_of_col(j) {
            let (a, b) = (rank[i], rank[j]);
            entries.push((a.min(b), a.max(b)));
        }
    }
    let permuted = Assembly::<f64>::new(n, &entries);
    let mut etree = vec![0isize; n];
    let mut counts = vec![0usize; n];
    let mut mem = MemBuffer::new(
        faer::sparse::linalg::cholesky::simplicial::prefactorize_symbolic_cholesky_scratch::<usize>(
            n,
            entries.len(),
        ),
    );
    faer::sparse::linalg::cholesky::simplicial::prefactorize_symbolic_cholesky(
        &mut etree,
        &mut counts,
        permuted.matrix.symbolic(),
        MemStack::new(&mut mem),
    );
    counts.iter().map(|&c| (c as f64) * (c as f64)).sum()
}

/// The coordinate order of a block order (`order[new] = old` block): each block's coordinates
/// `offset[u]..offset[u + 1]` together, in their order, blocks in `order`. The order an
/// [`Assembly::blocked`] is assembled in, for permuting vectors into it.
pub fn block_coordinates(order: &[usize], offset: &[usize]) -> Vec<usize> {
    order
        .iter()
        .flat_map(|&u| offset[u]..offset[u + 1])
        .collect()
}

/// An order of rows (`order[new] = old`) that keeps each pose's rows together, poses by `rank`;
/// `group[row]` is the pose of each row. Rows sorted by (rank of their pose, row): a counting
/// sort by rank ([`column_buckets`]: stable, so each pose's rows stay in their order) in
/// O(rows + poses) instead of a comparison sort's O(rows log rows).
pub fn group_ordering(rank: &[usize], group: &[usize]) -> Vec<usize> {
    column_buckets(rank.len(), group.iter().map(|&g| rank[g])).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// [`Permuted`] against faer's own permutation (`permute_self_adjoint_to_unsorted`, the
    /// copy a factor analyzed with an order makes of each matrix): for a random Hermitian pattern
    /// with complex values, random orders, both stored triangles, with and without a row and
    /// column left out (faer then given the matrix without them), the same column pointers, rows
    /// and values, bit for bit.
    #[test]
    fn permuted_is_faers_permutation_without_the_copy() {
        let mut rng = crate::linalg::rng::Rng::new(41);
        let n = 40;
        let mut entries = Vec::new();
        for j in 0..n {
            entries.push((j, j, c64::new(4.0 + rng.normal().abs(), 0.0)));
            for i in 0..j {
                if rng.next_u64().is_multiple_of(5) {
                    entries.push((i, j, c64::new(rng.normal(), rng.normal())));
                }
            }
        }
        let triplets = |dropped: Option<usize>| {
            let kept = |k: usize| match dropped {
                Some(d) if k == d => None,
                Some(d) if k > d => Some(k - 1),
                _ => Some(k),
            };
            entries
                .iter()
                .filter_map(|&(i, j, v)| Some(Triplet::new(kept(i)?, kept(j)?, v)))
                .collect::<Vec<_>>()
        };
        let matrix = |t: &[Triplet<usize, usize, c64>], m: usize| {
            SparseColMat::<usize, c64>::try_new_from_triplets(m, m, t).unwrap()
        };
        let upper = matrix(&triplets(None), n);
        for dropped in [None, Some(0), Some(17), Some(n - 1)] {
            let m = n - usize::from(dropped.is_some());
            let reduced = matrix(&triplets(dropped), m);
            for side in [Side::Upper, Side::Lower] {
                for _ in 0..3 {
                    let mut order: Vec<usize> = (0..m).collect();
                    for k in (1..m).rev() {
                        order.swap(k, (rng.next_u64() % (k as u64 + 1)) as usize);
                    }
                    let permuted = Permuted::new(&upper, &order, side, dropped);
                    let values = permuted.values_of(&upper);
                    let mut inverse = vec![0; m];
                    for (k, &old) in order.iter().enumerate() {
                        inverse[old] = k;
                    }
                    let perm = faer::perm::PermRef::new_checked(&order, &inverse, m);
                    let nnz = reduced.val().len();
                    let (mut val, mut ptr, mut row) = (
                        vec![c64::new(0.0, 0.0); nnz],
                        vec![0usize; m + 1],
                        vec![0usize; nnz],
                    );
                    let mut mem = MemBuffer::new(StackReq::new::<usize>(m));
                    let faers = faer::sparse::utils::permute_self_adjoint_to_unsorted(
                        &mut val,
                        &mut ptr,
                        &mut row,
                        reduced.as_ref(),
                        perm,
                        Side::Upper,
                        side,
                        MemStack::new(&mut mem),
                    );
                    assert_eq!(permuted.pattern.col_ptr(), faers.symbolic().col_ptr());
                    assert_eq!(permuted.pattern.row_idx(), faers.symbolic().row_idx());
                    let bits = |v: &[c64]| -> Vec<(u64, u64)> {
                        v.iter().map(|z| (z.re.to_bits(), z.im.to_bits())).collect()
                    };
                    assert_eq!(bits(&values), bits(faers.val()), "{dropped:?} {side:?}");
                }
            }
        }
    }

    /// Σ_j c_j² by eliminating the nodes one by one in the order of `rank` on a dense adjacency
    /// matrix: each node's later neighbours become a clique (the fill), c_j = 1 + their count.
    fn dense_elimination_work(n: usize, edges: &[(usize, usize)], rank: &[usize]) -> f64 {
        let mut adjacent = vec![vec![false; n]; n];
        for &(i, j) in edges {
            if i != j {
                adjacent[rank[i]][rank[j]] = true;
                adjacent[rank[j]][rank[i]] = true;
            }
        }
        let mut work = 0.0;
        for k in 0..n {
            let later: Vec<usize> = (k + 1..n).filter(|&l| adjacent[k][l]).collect();
            for &a in &later {
                for &b in &later {
                    if a != b {
                        adjacent[a][b] = true;
                    }
                }
            }
            work += ((1 + later.len()) as f64).powi(2);
        }
        work
    }

    /// The LLᴴ solve split between two cores ([`TreeSplit`]) is the sequential one to the last
    /// bit, and both solve the system as faer's own solve does, to rounding (their supernodes
    /// of a few columns by other loops), real and complex, one and three right-hand sides (stored
    /// by columns and by rows), with and without a fill-reducing permutation of the factor's
    /// own: a supernodal factor of a 3D grid's blocked matrix (random values, diagonally
    /// dominant), with supernodes on either side of [`tree_solve::LOOP_MAX_COLUMNS`], whose
    /// tree splits into two sides below a top set that both update. (Checked to fail with the
    /// sides' logged updates applied after the top set instead of at their places, with a
    /// side's rows updated in descending order, and with a narrow supernode's backward step
    /// skipping the rows below it.)
    #[test]
    fn the_split_solve_is_the_sequential_one_to_the_bit() {
        use crate::linalg::rng::Rng;
        fn check<T: Scalar + crate::linalg::tree_solve::Entry>(draw: impl Fn(&mut Rng) -> T) {
            let (block, edges) = (3, grid_edges(9, 8, 7));
            let nodes = 9 * 8 * 7;
            let n = block * nodes;
            let mut rng = Rng::new(11);
            let mut entries: Vec<(usize, usize)> = (0..n)
                .flat_map(|i| {
                    (i..n)
                        .filter(move |&j| j / block == i / block)
                        .map(move |j| (i, j))
                })
                .collect();
            for &(u, v) in &edges {
                let (u, v) = (u.min(v), u.max(v));
                for a in 0..block {
                    for b in 0..block {
                        entries.push((u * block + a, v * block + b));
                    }
                }
            }
            let values = dominant_values(n, &entries, &mut rng, &draw);
            let rank = pose_rank(nodes, edges.iter().copied(), 1.0);
            let order = group_ordering(&rank, &(0..n).map(|r| r / block).collect::<Vec<_>>());
            // The same matrix in that order, for a factor without a permutation of its own.
            let mut at = vec![0; n];
            for (new, &old) in order.iter().enumerate() {
                at[old] = new;
            }
            let (moved, moved_values): (Vec<(usize, usize)>, Vec<T>) = entries
                .iter()
                .zip(&values)
                .map(|(&(i, j), &v)| match (at[i], at[j]) {
                    (a, b) if a <= b => ((a, b), v),
                    (a, b) => ((b, a), T::conj_impl(&v)),
                })
                .unzip();
            for permuted in [false, true] {
                let (mut assembly, mut f) = if permuted {
                    let assembly = Assembly::<T>::new(n, &entries);
                    let f = SparseFactor::<T>::analyze_ordered(
                        assembly.matrix.symbolic(),
                        &order,
                        Layout::Supernodal,
                    );
                    (assembly, f)
                } else {
                    let assembly = Assembly::<T>::new(n, &moved);
                    let f = SparseFactor::<T>::analyze_in_order(
                        assembly.matrix.symbolic(),
                        Side::Upper,
                        Layout::Supernodal,
                    );
                    (assembly, f)
                };
                assembly.fill(if permuted { &values } else { &moved_values });
                assert_eq!(f.symbolic.perm().is_some(), permuted);
                f.llt(assembly.matrix.as_ref())
                    .expect("diagonally dominant");
                let SymbolicCholeskyRaw::Supernodal(symbolic) = f.symbolic.raw() else {
                    panic!("supernodal");
                };
                let split = TreeSplit::new(symbolic, 0).expect("a grid's tree splits");
                assert!(split.sides().iter().all(|s| !s.is_empty()) && split.top() > 0);
                let widths: Vec<usize> = (0..symbolic.n_supernodes())
                    .map(|s| symbolic.supernode_end()[s] - symbolic.supernode_begin()[s])
                    .collect();
                assert!(widths.iter().any(|&w| w <= tree_solve::LOOP_MAX_COLUMNS));
                assert!(widths.iter().any(|&w| w > tree_solve::LOOP_MAX_COLUMNS));
                f.prepare_split_from(0);
                for k in [1, 3] {
                    let b: Vec<T> = (0..n * k).map(|_| draw(&mut rng)).collect();
                    let mut mem =
                        MemBuffer::new(f.symbolic.solve_in_place_scratch::<T>(k, Par::Seq));
                    let bits = |v: &[T]| v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>();
                    // Within 1e-12 of faer's solution's largest entry: this matrix is far from
                    // singular (diagonally dominant), so the two roundings differ by far less.
                    let near_faers = |v: &[T], faers: &[T]| {
                        let scale = faers.iter().map(|x| x.modulus()).fold(0.0, f64::max);
                        v.iter()
                            .zip(faers)
                            .all(|(&a, &b)| (a - b).modulus() <= 1e-12 * scale)
                    };
                    for by_rows in [false, true] {
                        // By rows: the same right-hand sides with a row stride of k.
                        fn view<T: Scalar>(
                            v: &mut [T],
                            (n, k, by_rows): (usize, usize, bool),
                        ) -> MatMut<'_, T> {
                            match by_rows {
                                false => MatMut::from_column_major_slice_mut(v, n, k),
                                true => MatMut::from_row_major_slice_mut(v, n, k),
                            }
                        }
                        let shape = (n, k, by_rows);
                        let mut faers = b.clone();
                        LltRef::new(&f.symbolic, &f.values).solve_in_place_with_conj(
                            Conj::No,
                            view(&mut faers, shape),
                            Par::Seq,
                            MemStack::new(&mut mem),
                        );
                        let (mut sequential, mut split_solve) = (b.clone(), b.clone());
                        assert!(f.solve_supernodal_llt(view(&mut sequential, shape), false));
                        assert!(f.solve_supernodal_llt(view(&mut split_solve, shape), true));
                        let case = format!("permuted: {permuted}, {k} columns, by rows: {by_rows}");
                        assert!(split_solve != b);
                        assert_eq!(bits(&split_solve), bits(&sequential), "{case}");
                        assert!(near_faers(&sequential, &faers), "{case}");
                    }
                }
            }
        }
        check::<f64>(|rng| rng.normal());
        check::<c64>(|rng| c64::new(rng.normal(), rng.normal()));
    }

    /// Values for the entries of an n × n matrix (one triangle, each off the diagonal once):
    /// random off the diagonal (`draw`), and on it 1 more than the row's sum of moduli, so that
    /// the matrix is diagonally dominant, Hermitian positive definite.
    fn dominant_values<T: Scalar>(
        n: usize,
        entries: &[(usize, usize)],
        rng: &mut crate::linalg::rng::Rng,
        draw: &dyn Fn(&mut crate::linalg::rng::Rng) -> T,
    ) -> Vec<T> {
        let mut row_sums = vec![0.0; n];
        let mut values: Vec<T> = entries
            .iter()
            .map(|&(i, j)| {
                if i == j {
                    return T::zero_impl();
                }
                let v = draw(rng);
                row_sums[i] += v.modulus();
                row_sums[j] += v.modulus();
                v
            })
            .collect();
        for (v, &(i, j)) in values.iter_mut().zip(entries) {
            if i == j {
                *v = T::from_f64_impl(row_sums[i] + 1.0);
            }
        }
        values
    }

    /// A supernodal factor of a planar grid's blocked matrix with some random longer edges
    /// (random values, diagonally dominant), in a fill-reducing order of its own and its lower
    /// triangle stored, as the Newton systems are: the assembly and the analysis.
    fn grid_factor<T: Scalar>(
        draw: &dyn Fn(&mut crate::linalg::rng::Rng) -> T,
        seed: u64,
    ) -> GridFactor<T> {
        let mut rng = crate::linalg::rng::Rng::new(seed);
        let (block, mut edges) = (3, grid_edges(30, 24, 1));
        let nodes = 30 * 24;
        for _ in 0..6 {
            let mut node = || (rng.next_u64() % nodes as u64) as usize;
            let (u, v) = (node(), node());
            if u != v {
                edges.push((u.min(v), u.max(v)));
            }
        }
        let rank = pose_rank(nodes, edges.iter().copied(), 1.0);
        let n = block * nodes;
        let order = group_ordering(&rank, &(0..n).map(|r| r / block).collect::<Vec<_>>());
        let mut at = vec![0; n];
        for (new, &old) in order.iter().enumerate() {
            at[old] = new;
        }
        // Entries (row ≥ column) in the new order: each node's block, each edge's.
        let mut pairs: Vec<(usize, usize)> = (0..nodes).map(|u| (u, u)).collect();
        pairs.extend(edges);
        pairs.sort_unstable();
        pairs.dedup();
        let mut entries = Vec::new();
        for &(u, v) in &pairs {
            for a in 0..block {
                for b in 0..block {
                    let (i, j) = (at[u * block + a], at[v * block + b]);
                    if u != v || i >= j {
                        entries.push((i.max(j), i.min(j)));
                    }
                }
            }
        }
        let values = dominant_values(n, &entries, &mut rng, draw);
        let assembly = Assembly::<T>::new(n, &entries);
        let f = SparseFactor::<T>::analyze_in_order(
            assembly.matrix.symbolic(),
            Side::Lower,
            Layout::Supernodal,
        );
        GridFactor {
            assembly,
            entries,
            values,
            factor: f,
        }
    }

    /// [`grid_factor`]'s matrix: its assembly, its entries (row ≥ column) and their values, and
    /// the factor's analysis.
    struct GridFactor<T> {
        assembly: Assembly<T>,
        entries: Vec<(usize, usize)>,
        values: Vec<T>,
        factor: SparseFactor<T>,
    }

    /// The LLᴴ factorization split between two cores ([`FactorSplit`]) against faer's: the same
    /// factor to rounding, real and complex, its updates subtracted in place block by block
    /// and through a product of their own (both ways forced); the same bits on one core as on
    /// two; the tree split into two sides below a top set. (Checked to fail with side 1's
    /// updates of the top set left out, and with a side's updates of the top set subtracted
    /// twice.)
    #[test]
    fn the_split_factorization_is_faers_to_rounding() {
        split_against_faers::<f64>(&|rng| rng.normal(), false);
        split_against_faers::<c64>(&|rng| c64::new(rng.normal(), rng.normal()), false);
    }

    /// As [`the_split_factorization_is_faers_to_rounding`], the LDLᴴ without pivoting against
    /// faer's, on the grid's matrix made indefinite: a tenth of its diagonal negated (every
    /// principal submatrix stays diagonally dominant, so no pivot is zero), as the certificate's
    /// shifted W̃(λ) is. (Checked to fail with the pivots left out of the updates.)
    #[test]
    fn the_split_ldlt_is_faers_to_rounding() {
        split_against_faers::<f64>(&|rng| rng.normal(), true);
        split_against_faers::<c64>(&|rng| c64::new(rng.normal(), rng.normal()), true);
    }

    /// The split factorization (LDLᴴ of the indefinite matrix where `ldlt`, else LLᴴ) against
    /// faer's, both ways of subtracting the updates, on one core and on two.
    fn split_against_faers<T: Scalar + crate::linalg::tree_factor::Entry>(
        draw: &dyn Fn(&mut crate::linalg::rng::Rng) -> T,
        ldlt: bool,
    ) {
        use crate::linalg::tree_factor::SplitRoom;
        {
            for seed in [3, 4] {
                let GridFactor {
                    mut assembly,
                    entries,
                    mut values,
                    factor: mut f,
                } = grid_factor(draw, seed);
                if ldlt {
                    for (v, &(i, j)) in values.iter_mut().zip(&entries) {
                        if i == j && i % 10 == 3 {
                            *v = -*v;
                        }
                    }
                }
                assembly.fill(&values);
                if ldlt {
                    f.ldlt(assembly.matrix.as_ref()).expect("no zero pivot");
                } else {
                    f.llt(assembly.matrix.as_ref())
                        .expect("diagonally dominant");
                }
                let faers = f.values.clone();
                let scale = faers.iter().map(|v| v.modulus()).fold(0.0, f64::max);
                // The entries of L (and D): each column from its diagonal down. The strict upper
                // triangle of a diagonal block is no part of it (faer's dense kernel leaves its
                // intermediate values there, the loops of narrow supernodes nothing).
                let mut of_l = vec![false; faers.len()];
                f.visit_columns(|_, rows, at| of_l[at..at + rows.len()].fill(true));
                let SymbolicCholeskyRaw::Supernodal(symbolic) = f.symbolic.raw() else {
                    panic!("supernodal");
                };
                // Supernodes ended by the loops and by faer's kernels alike.
                let widths: Vec<usize> = (0..symbolic.n_supernodes())
                    .map(|s| symbolic.supernode_end()[s] - symbolic.supernode_begin()[s])
                    .collect();
                let narrow = crate::linalg::tree_factor::LOOP_MAX_COLUMNS;
                assert!(widths.iter().any(|&w| w <= narrow) && widths.iter().any(|&w| w > narrow));
                let mut bits: Option<Vec<String>> = None;
                // Split into two sides and a top set, and not split at all (one side).
                let sequential = FactorSplit::sequential(symbolic);
                assert!(!sequential.splits() && sequential.top() == 0);
                let splits = [0, usize::MAX].map(|min_entries| {
                    let split = FactorSplit::new(symbolic, 0.0).expect("the tree splits");
                    assert!(split.splits() && split.top() > 0);
                    (split, min_entries)
                });
                let unsplit = [0, usize::MAX].map(|min_entries| (sequential.clone(), min_entries));
                for (mut split, min_entries) in splits.into_iter().chain(unsplit) {
                    split.min_entries_per_product = min_entries;
                    for two_cores in [false, true] {
                        let mut ours = vec![T::zero_impl(); faers.len()];
                        let mut room = SplitRoom::default();
                        let kind = if ldlt { Kind::Ldlt } else { Kind::Llt };
                        split
                            .factorize(
                                kind,
                                symbolic,
                                &mut ours,
                                assembly.matrix.as_ref(),
                                &mut room,
                                two_cores,
                            )
                            .expect("no failed pivot");
                        let worst = ours
                            .iter()
                            .zip(&faers)
                            .zip(&of_l)
                            .filter(|&(_, &of_l)| of_l)
                            .map(|((&a, &b), _)| (a - b).modulus())
                            .fold(0.0, f64::max);
                        assert!(worst <= 1e-13 * scale, "seed {seed}: {worst:e}");
                        let these: Vec<String> = ours.iter().map(|x| format!("{x:?}")).collect();
                        if min_entries == 0 && split.splits() {
                            match &bits {
                                None => bits = Some(these),
                                Some(b) => assert_eq!(b, &these, "one core against two"),
                            }
                        }
                    }
                }
            }
        }
    }

    /// A split factorization asked for while the second core works ahead
    /// ([`crate::linalg::parallel::ahead`]) offers side 1 to it
    /// ([`crate::linalg::parallel::join_or_offer`]), which takes it at a pause: the factor is
    /// the one-core factor, bit for bit, whichever thread factors side 1.
    #[test]
    fn a_side_taken_by_the_work_ahead_gives_the_one_core_bits() {
        use crate::linalg::tree_factor::SplitRoom;
        let GridFactor {
            mut assembly,
            values,
            factor: f,
            ..
        } = grid_factor(&|rng| rng.normal().abs() + 0.5, 5);
        assembly.fill(&values);
        let SymbolicCholeskyRaw::Supernodal(symbolic) = f.symbolic.raw() else {
            panic!("supernodal");
        };
        let split = FactorSplit::new(symbolic, 0.0).expect("the tree splits");
        let factor = |two_cores: bool| {
            let mut ours = vec![0.0f64; symbolic.len_val()];
            split
                .factorize(
                    Kind::Llt,
                    symbolic,
                    &mut ours,
                    assembly.matrix.as_ref(),
                    &mut SplitRoom::default(),
                    two_cores,
                )
                .expect("diagonally dominant");
            ours.iter().map(|x| x.to_bits()).collect::<Vec<u64>>()
        };
        let alone = factor(false);
        let done = std::sync::atomic::AtomicBool::new(false);
        let (offered, ()) = crate::linalg::parallel::ahead(
            || {
                // Work ahead that pauses until the factorization is done.
                while !done.load(std::sync::atomic::Ordering::Acquire) {
                    crate::linalg::parallel::take_offer();
                    std::thread::yield_now();
                }
            },
            || (),
            || (),
            |_, _| {
                let bits = factor(true);
                done.store(true, std::sync::atomic::Ordering::Release);
                bits
            },
        );
        assert_eq!(offered, alone);
    }

    /// A matrix that is not positive definite is refused by the split factorization as by
    /// faer's, where its trouble is on a side and where it is in the top set, and the factor
    /// (same split, same room) factors the next matrix as if nothing had failed; likewise by the
    /// factorization that does not split ([`SparseFactor::prepare_own_factorization`] with more
    /// work asked than there is).
    #[test]
    fn the_split_factorization_refuses_what_is_not_positive_definite() {
        for split in [true, false] {
            let GridFactor {
                mut assembly,
                entries,
                values,
                factor: mut f,
            } = grid_factor(&|rng| rng.normal(), 5);
            let n = f.dim();
            // Split: a row on a side and one in the top set; not split: the first, middle and
            // last pivots.
            let rows = if split {
                f.prepare_factor_split(0.0);
                let SymbolicCholeskyRaw::Supernodal(symbolic) = f.symbolic.raw() else {
                    panic!("supernodal");
                };
                let split = f.factor_split.as_ref().expect("the tree splits");
                assert!(split.splits());
                vec![
                    symbolic.supernode_begin()[split.sides()[0][0] as usize],
                    n - 1,
                ]
            } else {
                f.prepare_own_factorization(f64::INFINITY);
                assert!(f.factor_split.is_some() && !f.splits_factorizations());
                vec![0, n / 2, n - 1]
            };
            assembly.fill(&values);
            f.llt(assembly.matrix.as_ref())
                .expect("diagonally dominant");
            let good = f.values.clone();
            for row in rows {
                let mut bad = values.clone();
                let k = entries.iter().position(|&e| e == (row, row)).unwrap();
                bad[k] = -1.0;
                assembly.fill(&bad);
                assert!(f.llt(assembly.matrix.as_ref()).is_err(), "row {row}");
                assembly.fill(&values);
                f.llt(assembly.matrix.as_ref())
                    .expect("diagonally dominant");
                assert!(f.values == good, "row {row}");
            }
        }
    }

    /// The edges of an a × b × c grid graph.
    fn grid_edges(a: usize, b: usize, c: usize) -> Vec<(usize, usize)> {
        let id = |x: usize, y: usize, z: usize| (x * b + y) * c + z;
        let mut edges = Vec::new();
        for x in 0..a {
            for y in 0..b {
                for z in 0..c {
                    if x + 1 < a {
                        edges.push((id(x, y, z), id(x + 1, y, z)));
                    }
                    if y + 1 < b {
                        edges.push((id(x, y, z), id(x, y + 1, z)));
                    }
                    if z + 1 < c {
                        edges.push((id(x, y, z), id(x, y, z + 1)));
                    }
                }
            }
        }
        edges
    }

    /// The 32-bit and 64-bit slots hold the same indices through every operation, against a
    /// plain list kept beside them: pushed, set, read back in order.
    #[test]
    fn narrow_and_wide_slots_agree() {
        let mut rng = crate::linalg::rng::Rng::new(7);
        let mut below = |m: usize| (rng.next_u64() % m as u64) as usize;
        let n = 200;
        let mut plain: Vec<usize> = (0..n).map(|_| below(n)).collect();
        let mut narrow = Slots::Narrow(Vec::new());
        let mut wide = Slots::Wide(Vec::new());
        for &s in &plain {
            narrow.push(s);
            wide.push(s);
        }
        for _ in 0..50 {
            let (k, at) = (below(n), below(n));
            plain[k] = at;
            narrow.set(k, at);
            wide.set(k, at);
        }
        for slots in [&narrow, &wide] {
            assert_eq!(slots.len(), n);
            let mut it = slots.iter();
            let read: Vec<usize> = std::iter::from_fn(|| it.next()).collect();
            assert_eq!(read, plain);
        }
        assert!(matches!(
            Slots::with_capacity(3, u32::MAX as usize),
            Slots::Narrow(_)
        ));
        assert!(matches!(
            Slots::zeroed(3, u32::MAX as usize + 1),
            Slots::Wide(_)
        ));
    }

    /// `group_ordering` is the rows sorted by (rank of their pose, row), on random ranks and
    /// groupings (poses with no row, one or several, rows of a pose not adjacent).
    #[test]
    fn group_ordering_sorts_rows_by_pose_rank_then_row() {
        let mut rng = crate::linalg::rng::Rng::new(31);
        for _ in 0..100 {
            let poses = 1 + (rng.next_u64() % 30) as usize;
            let mut rank: Vec<usize> = (0..poses).collect();
            for k in (1..poses).rev() {
                rank.swap(k, (rng.next_u64() % (k as u64 + 1)) as usize);
            }
            let rows = (rng.next_u64() % 90) as usize;
            let group: Vec<usize> = (0..rows)
                .map(|_| (rng.next_u64() % poses as u64) as usize)
                .collect();
            let mut expected: Vec<usize> = (0..rows).collect();
            expected.sort_by_key(|&r| (rank[group[r]], r));
            assert_eq!(group_ordering(&rank, &group), expected);
        }
    }

    /// `elimination_work` (faer's elimination tree and column counts) against the dense
    /// elimination, on random graphs (repeated edges and self-loops included) in random orders.
    #[test]
    fn elimination_work_is_the_dense_eliminations() {
        let mut rng = crate::linalg::rng::Rng::new(29);
        for trial in 0..100 {
            let n = 1 + (rng.next_u64() % 40) as usize;
            let m = (rng.next_u64() % (3 * n as u64 + 1)) as usize;
            let edges: Vec<(usize, usize)> = (0..m)
                .map(|_| {
                    let i = (rng.next_u64() % n as u64) as usize;
                    (i, (rng.next_u64() % n as u64) as usize)
                })
                .collect();
            let mut rank: Vec<usize> = (0..n).collect();
            for k in (1..n).rev() {
                rank.swap(k, (rng.next_u64() % (k as u64 + 1)) as usize);
            }
            let graph = pose_graph(n, edges.iter().copied());
            let work = elimination_work(graph.as_ref(), &rank);
            assert_eq!(
                work,
                dense_elimination_work(n, &edges, &rank),
                "trial {trial}"
            );
        }
    }

    /// [`amd_pose_rank`] on trees (random parents, the edges in random directions and order):
    /// a permutation whose elimination makes no fill, as eliminating a leaf never does and a tree
    /// always has one of degree 1 (minimum degree's pick): every column holds its diagonal and,
    /// but the last one's, its parent's row, so Σ c_j² = 4(n − 1) + 1 (by hand), against the
    /// dense elimination ([`dense_elimination_work`]).
    #[test]
    fn amd_orders_a_tree_without_fill() {
        let mut rng = crate::linalg::rng::Rng::new(53);
        for n in [1, 2, 3, 10, 57, 300] {
            let mut edges: Vec<(usize, usize)> = (1..n)
                .map(|k| {
                    let parent = (rng.next_u64() % k as u64) as usize;
                    if rng.next_u64().is_multiple_of(2) {
                        (k, parent)
                    } else {
                        (parent, k)
                    }
                })
                .collect();
            for k in (1..edges.len()).rev() {
                edges.swap(k, (rng.next_u64() % (k as u64 + 1)) as usize);
            }
            let rank = amd_pose_rank(n, edges.iter().copied());
            let mut seen = vec![false; n];
            for &r in &rank {
                assert!(r < n && !seen[r], "n = {n}: not a permutation");
                seen[r] = true;
            }
            let expected = (4 * (n - 1) + 1) as f64;
            assert_eq!(
                dense_elimination_work(n, &edges, &rank),
                expected,
                "n = {n}"
            );
        }
    }

    /// The pose graph's pattern is the one an [`Assembly`] of its entries builds (its general
    /// bucketing, with slots): random graphs with repeated and reversed edges and self-loops.
    #[test]
    fn the_pose_graph_pattern_is_the_assembly_of_its_entries() {
        let mut rng = crate::linalg::rng::Rng::new(41);
        for n in [1, 2, 7, 60] {
            let edges: Vec<(usize, usize)> = (0..3 * n)
                .map(|_| {
                    let i = (rng.next_u64() % n as u64) as usize;
                    (i, (rng.next_u64() % n as u64) as usize)
                })
                .collect();
            let mut entries: Vec<(usize, usize)> = (0..n).map(|k| (k, k)).collect();
            entries.extend(
                edges
                    .iter()
                    .filter(|(i, j)| i != j)
                    .map(|&(i, j)| (i.min(j), i.max(j))),
            );
            let assembly = Assembly::<f64>::new(n, &entries);
            let expected = assembly.matrix.symbolic();
            let got = pose_graph(n, edges.iter().copied());
            assert_eq!(got.col_ptr(), expected.col_ptr(), "n = {n}");
            assert_eq!(got.row_idx(), expected.row_idx(), "n = {n}");
        }
    }

    /// METIS's order is a permutation, the same on every call; on a 12 × 12 × 12 grid (AMD's
    /// count 100 times the graph's entries and more) it costs less than AMD's by more than
    /// DISSECTION_GAIN, and `pose_rank` takes it for 3D problems, but not for planar ones, whose
    /// smaller blocks would need AMD's count at 675 times the entries; on a path (no fill either
    /// way) AMD is kept.
    #[test]
    fn nested_dissection_is_kept_where_it_is_cheaper() {
        let n = 12 * 12 * 12;
        let edges = grid_edges(12, 12, 12);
        let graph = pose_graph(n, edges.iter().copied());
        let pattern = graph.as_ref();
        let nd = nested_dissection(pattern).expect("METIS orders a grid");
        let mut seen = vec![false; n];
        for &r in &nd {
            assert!(!seen[r]);
            seen[r] = true;
        }
        assert_eq!(nested_dissection(pattern), Some(nd.clone()));
        let (amd, count) = amd_rank(pattern).unwrap();
        let per_entry = count / pattern.compute_nnz() as f64;
        assert!((100.0..675.0).contains(&per_entry), "{per_entry}");
        let (nd_work, amd_work) = (
            elimination_work(pattern, &nd),
            elimination_work(pattern, &amd),
        );
        assert!(
            nd_work <= DISSECTION_GAIN * amd_work,
            "{nd_work} {amd_work}"
        );
        assert_eq!(pose_rank(n, edges.iter().copied(), SPATIAL_BLOCK_WORK), nd);
        assert_eq!(pose_rank(n, edges.iter().copied(), PLANAR_BLOCK_WORK), amd);
        let path: Vec<(usize, usize)> = (1..50).map(|k| (k - 1, k)).collect();
        let (amd, _) = amd_rank(pose_graph(50, path.iter().copied()).as_ref()).unwrap();
        assert_eq!(pose_rank(50, path.iter().copied(), SPATIAL_BLOCK_WORK), amd);
    }

    /// `Assembly::fill_with` sums repeated entries into their slot, the values received one at a
    /// time (a 3x3 upper triangle by hand); a count that is not the pattern's is refused.
    #[test]
    fn fill_with_sums_the_values_into_the_pattern() {
        let entries = [(0, 2), (1, 1), (0, 0), (0, 2), (2, 2), (1, 1), (1, 2)];
        let mut a = Assembly::<f64>::new(3, &entries);
        a.fill_with(|fill| {
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]
                .iter()
                .for_each(|&v| fill.push(v))
        });
        let dense = a.matrix.to_dense();
        let expected = [[3.0, 0.0, 5.0], [0.0, 8.0, 7.0], [0.0, 0.0, 5.0]];
        for (r, row) in expected.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                assert_eq!(dense[(r, c)], v, "({r}, {c})");
            }
        }
        let short = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            a.fill_with(|fill| fill.push(1.0));
        }));
        assert!(short.is_err());
        let long = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            a.fill_with(|fill| (0..8).for_each(|_| fill.push(1.0)));
        }));
        assert!(long.is_err());
    }

    /// `Assembly::blocked` against `Assembly::permuted` given the expanded entries and order:
    /// the same pattern and the same slot for every entry, on random block patterns (sizes 0 to
    /// 6, repeated pairs, every diagonal or not) in random orders, both triangles.
    #[test]
    fn blocked_matches_the_entrywise_assembly() {
        let mut rng = crate::linalg::rng::Rng::new(17);
        let mut below = |n: usize| (rng.next_u64() % n as u64) as usize;
        for trial in 0..200 {
            let nb = 1 + below(12);
            let sizes: Vec<usize> = (0..nb).map(|_| below(7)).collect();
            let mut blocks = Vec::new();
            for u in 0..nb {
                if trial % 2 == 0 || below(2) == 0 {
                    blocks.push((u, u));
                }
            }
            for _ in 0..below(3 * nb) {
                let (u, v) = (below(nb), below(nb));
                blocks.push((u.min(v), u.max(v)));
            }
            let mut order: Vec<usize> = (0..nb).collect();
            for k in (1..nb).rev() {
                order.swap(k, below(k + 1));
            }
            let mut offset = vec![0usize; nb + 1];
            for u in 0..nb {
                offset[u + 1] = offset[u] + sizes[u];
            }
            let mut entries = Vec::new();
            for &(u, v) in &blocks {
                for a in 0..sizes[u] {
                    for b in 0..sizes[v] {
                        if u != v || a <= b {
                            entries.push((offset[u] + a, offset[v] + b));
                        }
                    }
                }
            }
            let expanded = block_coordinates(&order, &offset);
            for side in [Side::Upper, Side::Lower] {
                let by_entry = Assembly::<f64>::permuted(offset[nb], &entries, &expanded, side);
                let by_block = Assembly::<f64>::blocked(&sizes, &blocks, &order, side);
                let (p, q) = (by_entry.matrix.symbolic(), by_block.matrix.symbolic());
                assert_eq!(p.col_ptr(), q.col_ptr(), "trial {trial} {side:?}");
                assert_eq!(p.row_idx(), q.row_idx(), "trial {trial} {side:?}");
                assert_eq!(by_entry.slots, by_block.slots, "trial {trial} {side:?}");
            }
        }
    }

    /// 32-bit indices change nothing but the indices' width: a grid's blocked system (3×3 blocks)
    /// assembled, analyzed and factored with `u32` and with `usize` indices gives the same
    /// pattern, the same factor and the same solution to the bit, by our own factorization (split
    /// between two sides, and on one) and by faer's. And [`fits`] draws the line where faer's
    /// signed 32-bit indices end, 2³¹ − 1.
    #[test]
    fn narrow_indices_factor_to_the_same_bits() {
        assert!(fits::<u32>((1 << 31) - 1));
        assert!(!fits::<u32>(1 << 31));
        assert!(fits::<usize>(1 << 40));
        let edges = grid_edges(30, 24, 1);
        let nb = 30 * 24;
        let sizes = vec![3usize; nb];
        let mut blocks: Vec<(usize, usize)> = (0..nb).map(|u| (u, u)).collect();
        blocks.extend(edges.iter().map(|&(u, v)| (u.min(v), u.max(v))));
        // A fill-reducing order (`order[new] = old`), whose elimination tree divides.
        let rank = pose_rank(nb, edges.iter().copied(), 1.0);
        let mut order = vec![0; nb];
        for (u, &r) in rank.iter().enumerate() {
            order[r] = u;
        }
        let mut rng = crate::linalg::rng::Rng::new(5);
        let mut values = Vec::new();
        for &(u, v) in &blocks {
            for a in 0..3 {
                for b in 0..3 {
                    if u == v && b < a {
                        continue;
                    }
                    values.push(if u == v && a == b {
                        30.0
                    } else {
                        (rng.next_u64() % 2001) as f64 / 1000.0 - 1.0
                    });
                }
            }
        }
        let b: Vec<f64> = (0..3 * nb).map(|k| (k as f64 * 0.37).sin()).collect();
        let layout = Layout::Supernodal;
        let side = layout.stored_side();
        for own in [None, Some(0.0), Some(f64::INFINITY)] {
            let mut wide = Assembly::<f64>::blocked(&sizes, &blocks, &order, side);
            let mut narrow =
                Assembly::<f64, u32>::try_blocked(&sizes, &blocks, &order, side).unwrap();
            wide.fill(&values);
            narrow.fill(&values);
            let (w, n) = (wide.matrix.symbolic(), narrow.matrix.symbolic());
            assert!(
                w.col_ptr()
                    .iter()
                    .zip(n.col_ptr())
                    .all(|(a, b)| *a == *b as usize)
            );
            assert!(
                w.row_idx()
                    .iter()
                    .zip(n.row_idx())
                    .all(|(a, b)| *a == *b as usize)
            );
            let mut fw = SparseFactor::analyze_in_order(w, side, layout);
            let mut fn_ = SparseFactor::<f64, u32>::try_analyze_in_order(n, side, layout).unwrap();
            if let Some(min_work) = own {
                fw.prepare_own_factorization(min_work);
                fn_.prepare_own_factorization(min_work);
                assert_eq!(fw.splits_factorizations(), fn_.splits_factorizations());
                assert_eq!(fn_.splits_factorizations(), min_work == 0.0);
            }
            assert_eq!(fw.multiply_adds(), fn_.multiply_adds());
            fw.llt(wide.matrix.as_ref()).unwrap();
            fn_.llt(narrow.matrix.as_ref()).unwrap();
            let (mut xw, mut xn) = (b.clone(), b.clone());
            fw.solve_in_place(&mut xw);
            fn_.solve_in_place(&mut xn);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&xw), bits(&xn), "{own:?}");
            assert_eq!(bits(&fw.take_values()), bits(&fn_.take_values()), "{own:?}");
        }
    }

    /// The tridiagonal Hermitian matrix with diagonal `d` and off-diagonal `e` (i on the
    /// superdiagonal), factored by LDLᴴ in both layouts; returns the backward-error bounds and
    /// the number of negative pivots.
    fn factor(dim: usize, d: f64, e: f64) -> Vec<(f64, usize)> {
        let mut entries = Vec::new();
        let mut values = Vec::new();
        for k in 0..dim {
            entries.push((k, k));
            values.push(c64::new(d, 0.0));
            if k + 1 < dim {
                entries.push((k, k + 1));
                values.push(c64::new(0.0, e));
            }
        }
        let mut assembly = Assembly::<c64>::new(dim, &entries);
        assembly.fill(&values);
        [
            SupernodalThreshold::FORCE_SIMPLICIAL,
            SupernodalThreshold::FORCE_SUPERNODAL,
        ]
        .into_iter()
        .map(|t| {
            let mut f = SparseFactor::<c64>::analyze_with(assembly.matrix.symbolic(), t);
            f.ldlt(assembly.matrix.as_ref()).unwrap();
            (f.ldlt_backward_error(), f.inertia_below(0.0))
        })
        .collect()
    }

    #[test]
    fn a_released_factor_factors_and_solves_again() {
        // tridiag(−1, 2, −1) x = (1, …, 1): x_k = k(n + 1 − k)/2 (the discrete Poisson problem).
        let n = 50;
        let mut entries = Vec::new();
        let mut values = Vec::new();
        for k in 0..n {
            entries.push((k, k));
            values.push(2.0);
            if k + 1 < n {
                entries.push((k, k + 1));
                values.push(-1.0);
            }
        }
        let mut assembly = Assembly::<f64>::new(n, &entries);
        assembly.fill(&values);
        let mut f = SparseFactor::<f64>::analyze(assembly.matrix.symbolic());
        let solve = |f: &mut SparseFactor<f64>| {
            f.llt(assembly.matrix.as_ref()).unwrap();
            let mut b = vec![1.0; n];
            f.solve_in_place(&mut b);
            b
        };
        let first = solve(&mut f);
        for (k, x) in first.iter().enumerate() {
            let exact = ((k + 1) * (n - k)) as f64 / 2.0;
            assert!((x - exact).abs() <= 1e-10 * exact, "{k}: {x} {exact}");
        }
        f.release();
        assert_eq!(solve(&mut f), first);
        // With the solves' workspace only: the same solution; a factorization after takes the
        // factorizations' workspace back (faer refuses a workspace too small for it).
        f.keep_solves_only();
        let mut b = vec![1.0; n];
        f.solve_in_place(&mut b);
        assert_eq!(b, first);
        f.keep_solves_only();
        assert_eq!(solve(&mut f), first);
        f.keep_solves_only();
        f.ldlt(assembly.matrix.as_ref()).unwrap();
        let mut b = vec![1.0; n];
        f.solve_in_place(&mut b);
        for (x, y) in b.iter().zip(&first) {
            assert!((x - y).abs() <= 1e-12 * y.abs(), "{x} {y}");
        }
    }

    /// A factor given another's memory (garbage in it, odd and even capacities, real values as
    /// room for complex ones) factors and solves to the same bits as a fresh one; the room is the
    /// same allocation, an odd capacity shrunk by one.
    #[test]
    fn a_factor_in_reused_memory_gives_the_same_bits() {
        // The complex Poisson problem tridiag(−1, 2, −1) with a phase on the off-diagonal: a
        // unitary diagonal similarity of the real one, so Hermitian positive definite.
        let n = 40;
        let phase = c64::new(0.6, 0.8);
        let mut entries = Vec::new();
        let mut values = Vec::new();
        for k in 0..n {
            entries.push((k, k));
            values.push(c64::new(2.0, 0.0));
            if k + 1 < n {
                entries.push((k, k + 1));
                values.push(-phase);
            }
        }
        let mut assembly = Assembly::<c64>::new(n, &entries);
        assembly.fill(&values);
        let solve = |room: Option<Vec<f64>>| {
            let mut f = SparseFactor::<c64>::analyze(assembly.matrix.symbolic());
            if let Some(room) = room {
                f.reuse(c64::room_of(room));
            }
            f.llt(assembly.matrix.as_ref()).unwrap();
            let mut b: Vec<c64> = (0..n).map(|k| c64::new(1.0, k as f64)).collect();
            f.solve_in_place(&mut b);
            b
        };
        let fresh = solve(None);
        for len in [7, 8, 1000, 1001] {
            let room: Vec<f64> = (0..len).map(|k| f64::from(k as u32) * 1e300).collect();
            assert_eq!(solve(Some(room)), fresh, "room of {len}");
        }
        for len in [7, 8] {
            let room = vec![f64::NAN; len];
            let (pointer, capacity) = (room.as_ptr() as usize, room.capacity());
            let complex = c64::room_of(room);
            // An even capacity is the same allocation; an odd one is shrunk (in place with
            // glibc's realloc, but an allocator may move it).
            if capacity % 2 == 0 {
                assert_eq!(complex.as_ptr() as usize, pointer);
            }
            assert_eq!((complex.len(), complex.capacity()), (0, capacity / 2));
        }
    }

    #[test]
    fn inertia_counts_the_eigenvalues_below_a_shift_in_double_and_double_double() {
        // T = tridiag(i, 2, −i) has eigenvalues 2 + 2cos(kπ/(n+1)), k = 1..n (the Hermitian
        // tridiagonal with |e| = 1 is unitarily similar to the real one). The negative pivots of
        // an LDLᴴ of T − μI count those below μ (Sylvester), in either arithmetic and layout.
        let n = 200;
        let mu = 0.7;
        let expected = (1..=n)
            .filter(|&k| 2.0 + 2.0 * (k as f64 * std::f64::consts::PI / (n + 1) as f64).cos() < mu)
            .count();
        assert!(expected > 10);
        let entries: Vec<(usize, usize)> = (0..n)
            .flat_map(|k| [(k, k), (k, k + 1)])
            .filter(|&(_, c)| c < n)
            .collect();
        let order: Vec<usize> = (0..n).rev().collect();
        let value = |&(r, c): &(usize, usize)| if r == c { (2.0 - mu, 0.0) } else { (0.0, 1.0) };
        let mut double = Assembly::<c64>::new(n, &entries);
        double.fill(
            &entries
                .iter()
                .map(|e| {
                    let (a, b) = value(e);
                    c64::new(a, b)
                })
                .collect::<Vec<_>>(),
        );
        for layout in [Layout::Simplicial, Layout::Supernodal] {
            let mut f =
                SparseFactor::<c64>::analyze_ordered(double.matrix.symbolic(), &order, layout);
            f.ldlt(double.matrix.as_ref()).unwrap();
            assert_eq!(f.inertia_below(0.0), expected, "{layout:?}");
        }
        let dd = |v: f64| faer::fx128::from_f64(v);
        let mut precise = Assembly::<faer::cx128>::new(n, &entries);
        precise.fill(
            &entries
                .iter()
                .map(|e| {
                    let (a, b) = value(e);
                    faer::cx128 {
                        re: dd(a),
                        im: dd(b),
                    }
                })
                .collect::<Vec<_>>(),
        );
        let mut f =
            SparseFactor::analyze_ordered(precise.matrix.symbolic(), &order, Layout::Simplicial);
        f.ldlt(precise.matrix.as_ref()).unwrap();
        assert_eq!(f.inertia_below(0.0), expected);
        // Some 10¹⁵ times below double precision's bound for the same factors.
        let bound = f.ldlt_backward_error();
        assert!(bound > 0.0 && bound < 1e-25, "{bound}");
    }

    /// The counting-sort assembly agrees with faer's own triplet builder (an independent
    /// construction): same pattern, duplicates summed, for the plain and the permuted (lower
    /// triangle) forms.
    #[test]
    fn assembly_matches_faers_triplet_builder() {
        let dim = 37;
        let mut entries = Vec::new();
        let mut values = Vec::new();
        for k in 0..400usize {
            let (a, b) = ((k * 7919) % dim, (k * 104729 + k / 3) % dim);
            entries.push((a.min(b), a.max(b)));
            values.push(1.0 + (k % 13) as f64 / 8.0);
        }
        for k in 0..dim {
            entries.push((k, k));
            values.push(0.5);
        }
        let order: Vec<usize> = (0..dim).map(|k| (k * 11) % dim).collect();
        let mut new = vec![0; dim];
        for (i, &old) in order.iter().enumerate() {
            new[old] = i;
        }
        for side in [None, Some(Side::Lower), Some(Side::Upper)] {
            let mut assembly = match side {
                None => Assembly::<f64>::new(dim, &entries),
                Some(s) => Assembly::permuted(dim, &entries, &order, s),
            };
            assembly.fill(&values);
            let place = |(r, c): (usize, usize)| match side {
                None => (r, c),
                Some(Side::Lower) => (new[r].max(new[c]), new[r].min(new[c])),
                Some(Side::Upper) => (new[r].min(new[c]), new[r].max(new[c])),
            };
            let triplets: Vec<Triplet<usize, usize, f64>> = entries
                .iter()
                .zip(&values)
                .map(|(&e, &v)| {
                    let (r, c) = place(e);
                    Triplet::new(r, c, v)
                })
                .collect();
            let reference = SparseColMat::try_new_from_triplets(dim, dim, &triplets).unwrap();
            assert_eq!(assembly.matrix.col_ptr(), reference.col_ptr(), "{side:?}");
            assert_eq!(assembly.matrix.row_idx(), reference.row_idx(), "{side:?}");
            for (a, b) in assembly.matrix.val().iter().zip(reference.val()) {
                assert!((a - b).abs() <= 1e-12 * b.abs(), "{side:?}: {a} vs {b}");
            }
        }
    }

    /// `row_counts` against a dense symbolic elimination in the factor's order (simplicial:
    /// equal; supernodal: faer's relaxed supernodes store explicit zeros, so at least as many), and
    /// the ladder's a-priori rounding floor from them (|A|'s row sums) never above the
    /// a-posteriori backward-error bound of the factorization, on random Hermitian diagonally
    /// dominant sparse matrices, with and without AMD's order.
    #[test]
    fn row_counts_match_a_symbolic_elimination_and_the_floor_stays_below_the_error_bound() {
        let mut rng = crate::linalg::rng::Rng::new(29);
        for trial in 0..40 {
            let dim = 3 + (rng.next_u64() % 60) as usize;
            let mut dense = vec![vec![c64::new(0.0, 0.0); dim]; dim];
            for _ in 0..2 * dim {
                let (a, b) = (
                    (rng.next_u64() % dim as u64) as usize,
                    (rng.next_u64() % dim as u64) as usize,
                );
                if a != b {
                    let v = c64::new(rng.uniform() - 0.5, rng.uniform() - 0.5);
                    dense[a.min(b)][a.max(b)] = v;
                }
            }
            let (mut entries, mut values) = (Vec::new(), Vec::new());
            let mut sums = vec![0.0; dim];
            for c in 0..dim {
                for r in 0..c {
                    if dense[r][c].norm() > 0.0 {
                        entries.push((r, c));
                        values.push(dense[r][c]);
                        sums[r] += dense[r][c].norm();
                        sums[c] += dense[r][c].norm();
                    }
                }
            }
            for (k, sum) in sums.iter_mut().enumerate() {
                // Diagonal dominance by 1 + a random margin: Hermitian positive definite.
                let d = *sum + 1.0 + rng.uniform();
                entries.push((k, k));
                values.push(c64::new(d, 0.0));
                *sum += d;
            }
            let mut assembly = Assembly::<c64>::new(dim, &entries);
            assembly.fill(&values);
            let reversed: Vec<usize> = (0..dim).rev().collect();
            for (layout, order) in [
                (Layout::Simplicial, None),
                (Layout::Supernodal, None),
                (Layout::Simplicial, Some(&reversed)),
            ] {
                let mut f = match order {
                    Some(o) => {
                        SparseFactor::<c64>::analyze_ordered(assembly.matrix.symbolic(), o, layout)
                    }
                    None => SparseFactor::<c64>::analyze_with(
                        assembly.matrix.symbolic(),
                        layout.threshold(),
                    ),
                };
                let counts = f.row_counts();
                // Symbolic elimination of the permuted pattern, densely.
                let order = f.order();
                let mut filled = vec![vec![false; dim]; dim];
                for &(r, c) in &entries {
                    filled[r][c] = true;
                    filled[c][r] = true;
                }
                let mut at: Vec<Vec<bool>> = (0..dim)
                    .map(|i| (0..dim).map(|j| filled[order[i]][order[j]]).collect())
                    .collect();
                for k in 0..dim {
                    let below: Vec<usize> = (k + 1..dim).filter(|&i| at[i][k]).collect();
                    for &i in &below {
                        for &j in &below {
                            at[i][j] = true;
                        }
                    }
                }
                for i in 0..dim {
                    let exact = 1 + (0..i).filter(|&k| at[i][k]).count() as u32;
                    let stored = counts[order[i]];
                    if layout == Layout::Simplicial {
                        assert_eq!(stored, exact, "trial {trial}, row {i}");
                    } else {
                        assert!(
                            stored >= exact,
                            "trial {trial}, row {i}: {stored} < {exact}"
                        );
                    }
                }
                f.ldlt(assembly.matrix.as_ref()).unwrap();
                let floor = ldlt_error_floor(&counts, &sums);
                let bound = f.ldlt_backward_error();
                assert!(
                    floor > 0.0 && floor <= bound,
                    "trial {trial}: {floor} > {bound}"
                );
            }
        }
    }

    #[test]
    fn the_ldlt_backward_error_bound_follows_the_growth_of_the_factors() {
        // Diagonally dominant (d = 4, |e| = 1): pivots stay in [2 + √3, 4], |L| ≤ 1/2, so
        // ‖|L||D||Lᴴ|‖_∞ ≤ 4·(1 + 1/2)² + … is O(10) and the bound O(10·k·u).
        for (bound, negative) in factor(50, 4.0, 1.0) {
            assert_eq!(negative, 0);
            assert!(bound > 0.0 && bound < 1e-12, "{bound}");
        }
        // d = 1e-8 and |e| = 1: the first pivot is 1e-8, L's next entry 1e8 and the next pivot
        // −1e8 (|L||D||Lᴴ| ~ 1e8), so an honest bound is above u·1e8 ≈ 1e-8: the growth of an
        // LDLᴴ without pivoting shows in the bound rather than being assumed away.
        for (bound, _) in factor(50, 1e-8, 1.0) {
            assert!(bound > 1e-8, "{bound}");
        }
    }
}
