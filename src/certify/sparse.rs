use crate::certify::ladder::{
    Ladder, ShiftMemory, isolate, measured_theta, power_of_two_scale, smallest_doubling,
};
use crate::linalg::factor::{Layout, Permuted, Scalar, SparseFactor, ldlt_error_floor};
use crate::linalg::residual::within_allowance;
use crate::linalg::roundoff::{U, gamma, modulus_bound};
use crate::problem::matrix::for_each_entry;
use crate::problem::rank_p::{Enclosure, Point, Problem};
use faer::sparse::SparseColMat;
use faer::{c64, cx128, fx128};
use std::sync::Arc;

/// The sparse certificate of the scalable solver (docs/method.md §3.4). For a rank-1 estimate the
/// proof is the deflated one of [`SparseCertifier::certify_rank_one`] (LDLᴴ inertia for the gap,
/// Temple's inequality for the estimate's own eigenvalue), whose loss is set by the estimate's
/// residual rather than the factorization's rounding. Where that cannot isolate one eigenvalue,
/// and above rank 1, the proof is the shifted factorization below
/// ([`SparseCertifier::certify_cholesky`]).
///
/// For multipliers λ (from the first-order conditions at an estimate), a successful LLᴴ
/// factorization of
/// W̃(λ) + η·blkdiag(0, I) proves λ − η1 dual feasible (eq. (31)), so
/// `lower_bound = Σλ − n·η ≤ d* ≤ f*` (weak duality (32)).
///
/// Rounding: the factored matrix is B = D(W̃(λ) + ηP)D − αI, D = diag(2^{−e_k}) a power-of-two
/// equilibration (exact; B's diagonal lies in [1, 4)). A floating-point LLᴴ that succeeds is the
/// exact factor of B + ΔB with ‖ΔB‖₂ of the order of dim·u·‖B‖₂ (Higham, Accuracy and Stability of
/// Numerical Algorithms, §10.1: the backward error of Cholesky; u the unit roundoff). pgo takes
/// α = dim·u·‖B‖_∞ (‖B‖₂ ≤ ‖B‖_∞ for Hermitian B, summed exactly) plus the rounding of B's own
/// diagonal and of W̃'s assembly. The first is a model (the worst-case componentwise bound, γ_k
/// times the fill, would be ~100x larger and the bound it gives too loose to certify at 1e-6),
/// so the LLᴴ that succeeds at the η returned is checked against it: its residual ΔB = L Lᴴ − B, measured
/// ([`SparseFactor::llt_residual_bound`], some 50 units of rounding per entry), must lie within
/// dim·u·‖B‖_∞ (α holds the assembly's rounding apart). Then D(W̃(λ) + ηP)D ⪰ αI − ΔB ⪰ 0 is
/// proven outright, i.e. W̃(λ) + ηP ⪰ 0.
///
/// η is searched upward by factors of 2 from 1.25·η_res ([`SparseCertifier::resolution`]), the
/// smallest value at which the estimate's own direction x (W̃(λ)x ≈ 0, x*(ηP)x = ηn) clears α in
/// equilibrated coordinates. So η is set by the problem's scale (the diagonal of W̃ and the
/// spread of the estimate) and never falls below the backward error.
pub struct SparseCertifier {
    /// The values of the matrix each factorization factors (W̃(λ), shifted and scaled as its
    /// proof needs), in the pattern the factor factors ([`Self::write`]): W̃'s kept in the
    /// factor's order ([`Permuted`]), or, from [`PERMUTED_BELOW_ROWS`] rows, W̃'s own; allocated
    /// at the first factorization. (At 10⁶ poses an assembly of its own, a copy of the pattern
    /// with identity slots, took 114 MB, and its values 99 MB more through the Newton steps.)
    values: Vec<c64>,
    factor: SparseFactor<c64>,
    /// The fill-reducing order of W̃'s rows (`order[new] = old`).
    order: Vec<usize>,
    /// W̃'s pattern in that order, which the factor is analyzed and factors in ([`Permuted`]):
    /// below [`PERMUTED_BELOW_ROWS`] rows. Above, the factor holds the order and faer permutes
    /// each matrix it factors into a copy of its own.
    permuted: Option<Permuted>,
    /// The factor's row counts ([`SparseFactor::row_counts`]), for the ladder's
    /// [`ldlt_error_floor`].
    row_counts: Vec<u32>,
    /// W̃'s upper triangle, shared with the problem
    /// ([`crate::problem::matrix::PoseGraphMatrix::upper`]).
    upper: Arc<SparseColMat<usize, c64>>,
    /// Number of factorizations attempted so far.
    pub factorizations: usize,
    /// What the last successful [`Self::gap`] found, where the next one starts looking.
    shifts: ShiftMemory,
    /// Whether the last [`Self::certify_rank_one`] isolated one eigenvalue of W̃(λ) (whatever
    /// Temple's inequality then made of it).
    pub isolated: bool,
    /// The analysis of W̃'s pattern for the double-double LDLᴴ, built on first need
    /// ([`Self::precise_gap`]).
    precise: Option<SparseFactor<cx128>>,
    /// The last λ [`Self::gap`] was asked about (bit for bit) and its answer: the inertia depends
    /// on λ alone, and a staircase that stops at rank 1 asks twice (the certificate, then the
    /// bound), each time a ladder of factorizations (on city10000 with 1000 false loop closures
    /// 0.7 s).
    last_gap: Option<(Vec<u64>, Option<Gap>)>,
    /// What the last ladder saw where the rounding hid the gap ([`Self::hidden_gap`]).
    hidden: Option<HiddenGap>,
    /// The last rank-1 point enclosed (bit for bit) and its [`Enclosure`]: the forecast
    /// ([`Self::expects_shortfall`]) and the certificate at the same point share it.
    last_enclosure: Option<(Vec<u64>, Enclosure)>,
    /// The last λ (bit for bit) of [`Self::estimate_row_sums`] and what it found.
    last_row_sums: std::sync::Mutex<Option<(Vec<u64>, RowSums)>>,
    /// η (its bits) of the factor's LLᴴ where it is the last [`Self::try_eta`]'s success, and
    /// the allowance dim·u·‖B‖_∞ that attempt gave its rounding ([`Self::measured_llt`]).
    last_llt: Option<(u64, f64)>,
}

/// What the row sums of |B| give, B = D W̃(λ) D at the estimate's equilibration
/// ([`SparseCertifier::scaling`] with η = 0 and |a|): ‖B‖_∞ (for [`SparseCertifier::alpha`]'s
/// allowance) and the ladder's [`ldlt_error_floor`].
#[derive(Debug, Clone, Copy)]
struct RowSums {
    norm: f64,
    floor: f64,
}

/// W̃(λ)'s second eigenvalue hidden by the rounding ([`SparseCertifier::hidden_gap`]): D W̃(λ) D
/// − μI (D the equilibration, diagonal in [1, 4)) showed at most one negative pivot at the shift
/// μ = `shift`, but the factorization's error bound `error` was at least μ, and so was the error
/// `measured` a posteriori (plus the assembly's rounding) where it was measured, so neither the
/// gap nor its absence is proven; and the double-double retry could not prove it either, or was
/// not run (`precise_limit`: the factor's `factor_entries` exceed it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HiddenGap {
    pub shift: f64,
    pub error: f64,
    pub measured: Option<f64>,
    pub factor_entries: usize,
    pub precise_limit: Option<usize>,
}

/// The outcome of [`SparseCertifier::certify`].
#[derive(Debug, Clone, Copy)]
pub struct SparseBound {
    /// η with W̃(λ) + η·blkdiag(0, I) ⪰ 0 proven.
    pub eta: f64,
    /// Σλ − n·η, less the rounding of the sum: a lower bound on f*.
    pub lower_bound: f64,
    /// For a deflated proof ([`SparseCertifier::certify_rank_one`]): θ, a proven lower bound on
    /// the second smallest eigenvalue of D W̃(λ) D (equilibrated units), so W̃(λ) has exactly one
    /// eigenvalue below θ·min_k D_k⁻² (or none, when `eta` is 0 because W̃(λ) ≻ 0 was shown).
    pub gap: Option<f64>,
    /// 1 when a deflated proof isolated W̃(λ)'s one eigenvalue at zero (all others ≥ θ > 0, the
    /// SZEP); `None` otherwise (count them by inertia at a threshold).
    pub near_zero: Option<usize>,
}

impl SparseCertifier {
    /// The real multiply-adds of one of its factorizations (four per complex one), counted from
    /// the symbolic structure ([`SparseFactor::multiply_adds`]).
    pub fn factorization_work(&self) -> f64 {
        4.0 * self.factor.multiply_adds()
    }

    /// The dimension of W̃.
    fn dim(&self) -> usize {
        self.upper.ncols()
    }

    /// The position of W̃'s k-th diagonal entry among its stored values: the last of column k,
    /// as W̃'s upper triangle stores every diagonal entry and each column's rows ascending
    /// ([`crate::problem::matrix::PoseGraphMatrix::upper`]).
    fn diagonal(&self, k: usize) -> usize {
        let at = self.upper.symbolic().col_ptr()[k + 1] - 1;
        debug_assert_eq!(self.upper.symbolic().row_idx()[at], k);
        at
    }

    /// Analyzes the pattern of W̃ (its upper triangle, diagonal included, as in
    /// [`crate::problem::matrix::PoseGraphMatrix::upper`]) once, rows in a fill-reducing
    /// `order`; every later certificate reuses it.
    pub fn new(upper: &Arc<SparseColMat<usize, c64>>, order: &[usize]) -> Self {
        Self::with_storage(upper, order, upper.ncols() < PERMUTED_BELOW_ROWS)
    }

    /// [`Self::new`], W̃'s pattern kept in the factor's order ([`Permuted`]) or not.
    fn with_storage(
        upper: &Arc<SparseColMat<usize, c64>>,
        order: &[usize],
        keep_permuted: bool,
    ) -> Self {
        let (mut factor, permuted, row_counts) = if keep_permuted {
            let (factor, permuted) = Permuted::analyzed(upper, order, None, Layout::AutoComplex);
            // The counts by row of the permuted matrix, back to W̃'s rows.
            let mut counts = vec![0; order.len()];
            for (k, c) in factor.row_counts().into_iter().enumerate() {
                counts[order[k]] = c;
            }
            (factor, Some(permuted), counts)
        } else {
            let factor =
                SparseFactor::analyze_ordered(upper.symbolic(), order, Layout::AutoComplex);
            let counts = factor.row_counts();
            (factor, None, counts)
        };
        factor.prepare_factor_split(SPLIT_FACTOR_MIN_WORK);
        SparseCertifier {
            values: Vec::new(),
            row_counts,
            factor,
            order: order.to_vec(),
            permuted,
            upper: Arc::clone(upper),
            factorizations: 0,
            shifts: ShiftMemory::default(),
            last_gap: None,
            last_enclosure: None,
            last_row_sums: std::sync::Mutex::new(None),
            last_llt: None,
            isolated: false,
            precise: None,
            hidden: None,
        }
    }

    /// The resolution of the certificate at an estimate: the η below which the estimate's own
    /// direction x (W̃(λ)x ≈ 0, x*(ηP)x = η‖Y‖²) cannot clear the allowance α in equilibrated
    /// coordinates, η_res = α·Σ_k ‖x_k‖²/D_k² / n (`x` row-major with `p` entries per row).
    pub fn resolution(&self, lambda: &[f64], x: &[c64], p: usize) -> f64 {
        let Some((a, scale)) = self.scaling(lambda, 0.0, true) else {
            return f64::INFINITY;
        };
        let alpha = self.allowance(self.estimate_row_sums(lambda, &a, &scale).norm);
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
        let max_w =
            (0..self.dim()).fold(0.0f64, |m, k| m.max(self.upper.val()[self.diagonal(k)].re));
        (alpha * weight / lambda.len() as f64)
            .max(1e-15 * max_w)
            .max(f64::MIN_POSITIVE)
    }

    /// Proves W̃(λ) + ηP ⪰ 0 for the smallest η ≤ `eta_max` it can reach at the estimate `x`:
    /// the deflated proof of [`Self::certify_rank_one`] for a rank-1 estimate, and where that
    /// fails (or above rank 1), the shifted factorization of [`Self::certify_cholesky`].
    pub fn certify(
        &mut self,
        problem: &Problem,
        x: &Point,
        lambda: &[f64],
        eta_max: f64,
    ) -> Option<SparseBound> {
        if x.p == 1
            && let Some(bound) = self.certify_rank_one(problem, x, lambda, eta_max)
        {
            return Some(bound);
        }
        self.certify_cholesky(problem, lambda, &x.x, x.p, eta_max)
    }

    /// Tries to prove W̃(λ) + ηP ⪰ 0 for η = 1.25·η_res·2^j ≤ `eta_max`, j < 80
    /// ([`Self::resolution`]; beyond a factor 1e24 above it, no useful bound), by one LLᴴ each;
    /// returns the smallest η proven. W̃(λ) + ηP ⪰ 0 for every η above one where it holds (P ⪰ 0), so j is found by
    /// bisection ([`smallest_doubling`]): at most 9 factorizations where a scan upward took one
    /// per doubling (40 and more where the relaxation is not exact).
    pub fn certify_cholesky(
        &mut self,
        problem: &Problem,
        lambda: &[f64],
        x: &[c64],
        p: usize,
        eta_max: f64,
    ) -> Option<SparseBound> {
        let first = 1.25 * self.resolution(lambda, x, p);
        if !(first.is_finite() && first <= eta_max) {
            return None;
        }
        // η_j = first·2^j (exact: a power of two), for j in 0..=top.
        let top = ((eta_max / first).log2().floor().max(0.0) as i32).min(79);
        let eta = |j: i32| first * 2f64.powi(j);
        let proven = |eta: f64| SparseBound {
            eta,
            lower_bound: dual_value(lambda, eta),
            gap: None,
            near_zero: None,
        };
        // The largest η_j may round above eta_max: then the one below.
        let top = if eta(top) <= eta_max { top } else { top - 1 };
        self.last_llt = None;
        let j = smallest_doubling(top, |j| self.try_eta(problem, lambda, eta(j), 0.0))?;
        self.measured_llt(problem, lambda, eta(j))
            .then(|| proven(eta(j)))
    }

    /// The lower bound Σλ − n·η (less its rounding) where W̃(λ) + ηP ⪰ 0 is proven at this one
    /// η by the shifted LLᴴ with its residual measured ([`Self::measured_llt`]): for a shift
    /// found otherwise (the dense certificate's, from eigenvalues: [`crate::certify::dense`]).
    pub fn prove_shift(&mut self, problem: &Problem, lambda: &[f64], eta: f64) -> Option<f64> {
        self.last_llt = None;
        (self.try_eta(problem, lambda, eta, 0.0) && self.measured_llt(problem, lambda, eta))
            .then(|| dual_value(lambda, eta))
    }

    /// Whether the LLᴴ that succeeded at η ([`Self::try_eta`], factored again unless it was
    /// the last) holds without the backward-error model α rests on: its residual, measured
    /// ([`SparseFactor::llt_residual_bound`], by the wide chunks, then if need be by the narrow
    /// ones), within the allowance α gave the factorization's rounding (the assembly's is apart).
    /// Then L Lᴴ = B − αI + R with ‖R‖₂ at most that, so D(W̃(λ) + ηP)D ⪰ 0 is proven outright
    /// for the exact W̃. Where the residual exceeds the allowance (small graphs, whose dim·u·‖B‖_∞
    /// is a few units), once more with an allowance twice what it showed ([`within_allowance`]).
    fn measured_llt(&mut self, problem: &Problem, lambda: &[f64], eta: f64) -> bool {
        let last = self.last_llt.filter(|&(e, _)| e == eta.to_bits());
        within_allowance(
            self,
            last.map(|(_, allowance)| allowance),
            |c, chunk| {
                let a = factored(&c.upper, &c.permuted, &c.values);
                c.factor.llt_residual_bound(a, chunk)
            },
            |c, rounding| {
                c.try_eta(problem, lambda, eta, rounding)
                    .then(|| c.last_llt.map(|(_, a)| a))
                    .flatten()
            },
        )
    }

    /// The deflated certificate of a rank-1 estimate x (p = 1), which sidesteps the resolution
    /// limit of [`Self::certify_cholesky`]: at an optimum W̃(λ)x ≈ 0, so W̃(λ) + ηP has an
    /// eigenvalue of the order of η‖Y‖²/‖x‖², which no factorization resolves below its backward
    /// error. Instead, with D the equilibration of [`Self::scaling`], T(η) = D(W̃(λ) + ηP)D and
    /// z = D⁻¹x:
    ///
    /// 1. the gap ([`Self::gap`]): one LDLᴴ of D W̃(λ) D − μI with exactly one negative pivot
    ///    proves λ₂(T(η)) ≥ λ₂(T(0)) ≥ θ = μ − (backward error) > 0 (Sylvester's law of inertia,
    ///    Weyl's inequality; ηDPD ⪰ 0);
    /// 2. Temple's inequality for the Rayleigh quotient ρ = z*Tz/z*z and the residual
    ///    ε = ‖Tz − ρz‖/‖z‖: if ρ < θ ≤ λ₂ then λ₁(T) ≥ ρ − ε²/(θ − ρ). Here
    ///    z*T(η)z = f(x) − Σ_a λ_a|y_a|² + η‖Y‖² and Tz = D(W̃x − diag(0, λ − η)x) are computed
    ///    from the edges' residuals with rigorous rounding bounds ([`Problem::enclose`]), so the
    ///    loss is of the order of ‖D·gradient‖²/θ instead of the factorization's backward error
    ///    times the estimate's spread;
    /// 3. η is the smallest value found with ρ(θ − ρ) ≥ ε² (all quantities enclosed), so
    ///    λ₁(T(η)) ≥ 0, W̃(λ − η1) ⪰ 0 and `lower_bound = Σλ − nη` (weak duality (32)).
    ///
    /// `None` when the inertia does not isolate one eigenvalue (a saddle, a relaxation that is not
    /// exact, or a gap below the rounding level) or η would exceed `eta_max`.
    pub fn certify_rank_one(
        &mut self,
        problem: &Problem,
        x: &Point,
        lambda: &[f64],
        eta_max: f64,
    ) -> Option<SparseBound> {
        if x.p != 1 || x.x.len() != self.dim() {
            return None;
        }
        self.isolated = false;
        let (a, scale) = self.scaling(lambda, 0.0, true)?;
        let gap = self.gap(problem, lambda, &a, &scale)?;
        self.isolated = matches!(gap, Gap::Isolated(_));
        // Isolated: exactly one eigenvalue at zero is proven (the SZEP). Definite proves λ strictly
        // feasible, which says nothing of how many eigenvalues lie within λ's accuracy of zero.
        let (eta, theta, near_zero) = match gap {
            Gap::Definite(theta) => (0.0, theta, None),
            Gap::Isolated(theta) => (
                self.temple_eta(problem, x, lambda, &scale, theta, eta_max)?,
                theta,
                Some(1),
            ),
        };
        if eta.is_nan() || eta > eta_max {
            return None;
        }
        Some(SparseBound {
            eta,
            lower_bound: dual_value(lambda, eta),
            gap: Some(theta),
            near_zero,
        })
    }

    /// Whether Temple's bound at `x` (whose f is `cost`) is expected to leave more than `slack`
    /// between f(x) and the lower bound: the bound that a gap θ as large as the ladder's first shift would give (the
    /// gap proven at a rung μ is μ − ‖E‖, and the ladder steps up from its first rung only
    /// where the rounding hides it). No factorization and no proof: a forecast by which the
    /// caller polishes an estimate before its first certificate rather than after (at 10⁶
    /// poses Newton's cost-based stopping rule leaves a residual of which ‖r‖²/θ exceeds the
    /// tolerance, and the certificate at that point was a whole LDLᴴ spent for nothing).
    pub fn expects_shortfall(
        &mut self,
        problem: &Problem,
        x: &Point,
        cost: f64,
        lambda: &[f64],
        eta_max: f64,
        slack: f64,
    ) -> bool {
        if x.p != 1 || x.x.len() != self.dim() {
            return false;
        }
        let Some((_, scale)) = self.scaling(lambda, 0.0, true) else {
            return false;
        };
        let theta = self.shifts.start(1, self.dim() / 2);
        self.temple_eta(problem, x, lambda, &scale, theta, eta_max)
            .is_none_or(|eta| cost - dual_value(lambda, eta) > slack)
    }

    /// The smallest η ≤ `eta_max` at which Temple's inequality proves λ₁(D(W̃(λ) + ηP)D) ≥ 0
    /// given λ₂ ≥ θ ([`Rayleigh::smallest_eta`]), from the enclosure of f(x) and W̃x
    /// ([`Problem::enclose`]), which is kept for the next call at the same point.
    fn temple_eta(
        &mut self,
        problem: &Problem,
        x: &Point,
        lambda: &[f64],
        scale: &[f64],
        theta: f64,
        eta_max: f64,
    ) -> Option<f64> {
        let bits = || x.x.iter().flat_map(|z| [z.re.to_bits(), z.im.to_bits()]);
        if self
            .last_enclosure
            .as_ref()
            .is_none_or(|(key, _)| !same_bits(key, bits()))
        {
            self.last_enclosure = Some((bits().collect(), problem.enclose(x)));
        }
        let enclosure = &self.last_enclosure.as_ref().expect("just set").1;
        Rayleigh::new(enclosure, &x.x, lambda, scale).smallest_eta(theta, eta_max)
    }

    /// θ ≤ λ₂(D W̃(λ) D): the inertia of an LDLᴴ of B = D W̃(λ) D − μI. With exactly one negative
    /// pivot and none zero, B + E has one negative eigenvalue, E the LDLᴴ's backward error
    /// ([`SparseFactor::ldlt_backward_error`]) plus the rounding of B's diagonal plus the
    /// difference between the stored W̃ and the exact Σ_e of the edges' terms
    /// ([`assembly_error`]); so λ₂ of the exact D W̃(λ) D is at least θ = μ − ‖E‖. With no negative
    /// pivot, λ₁ ≥ θ and W̃(λ) ≻ 0 outright. μ starts where the last ladder ended
    /// ([`ShiftMemory::start`]), else at a shift for the graph's size, and the ladder
    /// ([`isolate`]) moves it until at most one pivot is negative (at most 8 factorizations,
    /// usually one).
    fn gap(&mut self, problem: &Problem, lambda: &[f64], a: &[f64], scale: &[f64]) -> Option<Gap> {
        let bits = || lambda.iter().map(|l| l.to_bits());
        if let Some((key, gap)) = &self.last_gap
            && same_bits(key, bits())
        {
            return *gap;
        }
        let gap = self.gap_by_inertia(problem, lambda, a, scale);
        self.last_gap = Some((bits().collect(), gap));
        gap
    }

    /// [`Self::gap`] without the memo: the shift ladder (`a`, `scale` from [`Self::scaling`]).
    fn gap_by_inertia(
        &mut self,
        problem: &Problem,
        lambda: &[f64],
        a: &[f64],
        scale: &[f64],
    ) -> Option<Gap> {
        self.hidden = None;
        let assembly = assembly_error(problem, scale);
        let start = self.shifts.start(1, self.dim() / 2);
        let floor = self.estimate_row_sums(lambda, a, scale).floor;
        let ladder = isolate(1, start, assembly, floor, |mu| {
            self.inertia_at(lambda, scale, mu)
        });
        self.shifts.remember(&ladder);
        match ladder {
            Ladder::Found {
                theta, negative, ..
            } => Some(Gap::new(negative, theta)),
            // The a-priori bound on double precision's rounding hides the gap: the error measured
            // at the same shift, then the shift in double-double.
            Ladder::Hidden { mu, floor } => {
                let measured = match self.measured_gap(lambda, scale, mu, assembly) {
                    Ok(gap) => return Some(gap),
                    Err(measured) => measured,
                };
                let gap = self.precise_gap(lambda, scale, mu, assembly);
                if gap.is_none() {
                    self.hidden = Some(HiddenGap {
                        shift: mu,
                        error: floor,
                        measured,
                        factor_entries: self.factor.stored_entries(),
                        precise_limit: (self.precise.is_none()).then_some(PRECISE_MAX_ENTRIES),
                    });
                }
                gap
            }
            Ladder::Failed => None,
        }
    }

    /// Where the last inertia ladder ([`Self::gap`]) found W̃(λ)'s second eigenvalue hidden by
    /// the rounding, in double precision and (if it ran) in double-double: what it saw.
    pub fn hidden_gap(&self) -> Option<HiddenGap> {
        self.hidden
    }

    /// Whether a shifted factorization ([`Self::certify_cholesky`]) at this estimate could prove
    /// a lower bound above zero at all: Σλ − n·η > 0 at its smallest η, 1.25 times the
    /// resolution. (At 4·10⁶ generated poses that η was 6.2, and n·η 9.4 times f.)
    pub fn cholesky_within_reach(&self, lambda: &[f64], x: &[c64], p: usize) -> bool {
        dual_value(lambda, 1.25 * self.resolution(lambda, x, p)) > 0.0
    }

    /// Takes the values of a real factor that is no longer needed (Newton's) as the room of its
    /// factor's ([`SparseFactor::reuse`]).
    pub fn reuse(&mut self, values: Vec<f64>) {
        self.factor.reuse(c64::room_of(values));
    }

    /// Forgets the enclosure kept for the next certificate at the same point ([`Self::temple_eta`]):
    /// for a point about to move (a polish), whose enclosure and key (80 MB at 10⁶ poses) would
    /// only be replaced.
    pub fn forget_point(&mut self) {
        self.last_enclosure = None;
    }

    /// Frees the numeric factor and the values (the analysis stays; the next factorization
    /// allocates them again): for a phase between two certificates that needs the memory, such
    /// as a Newton polish.
    pub fn release_factor(&mut self) {
        self.factor.release();
        self.values = Vec::new();
    }

    /// The next certificate is of the same minimum, polished (multipliers moved by its last
    /// residual): its ladder starts at the shift that isolated this one's gap
    /// ([`ShiftMemory::hold`]).
    pub fn hold_shift(&mut self) {
        self.shifts.hold();
    }

    /// One LDLᴴ of D W̃(λ) D − μI in double precision: `Some((negative pivots, error))` with
    /// `error` its backward error ([`SparseFactor::ldlt_backward_error`]) plus the rounding of
    /// the shifted diagonal; `Some(None)` on a zero pivot; `None` if the scaled matrix is not
    /// finite (then no shift will do).
    fn inertia_at(
        &mut self,
        lambda: &[f64],
        scale: &[f64],
        mu: f64,
    ) -> Option<Option<(usize, f64)>> {
        let factored = self.ldlt_shifted(lambda, scale, mu)?;
        Some(factored.map(|(negative, form)| (negative, self.factor.ldlt_backward_error() + form)))
    }

    /// The LDLᴴ of [`Self::inertia_at`]: `Some((negative pivots, the rounding of the shifted
    /// diagonal))`.
    fn ldlt_shifted(
        &mut self,
        lambda: &[f64],
        scale: &[f64],
        mu: f64,
    ) -> Option<Option<(usize, f64)>> {
        let rot0 = self.dim() - lambda.len();
        let mut form = f64::MIN_POSITIVE;
        let mut finite = true;
        self.write(|r, c, v| {
            let s = scale[r] * scale[c];
            let value = if r == c {
                let l = if r >= rot0 { lambda[r - rot0] } else { 0.0 };
                form = form.max(4.0 * U * ((v.re.abs() + l.abs()) * s + mu));
                c64::new((v.re - l) * s - mu, 0.0)
            } else {
                v * s
            };
            finite &= value.re.is_finite() && value.im.is_finite();
            value
        });
        if !finite {
            return None;
        }
        self.factorizations += 1;
        if self
            .factor
            .ldlt(factored(&self.upper, &self.permuted, &self.values))
            .is_err()
        {
            return Some(None);
        }
        Some(Some((self.factor.inertia_below(0.0), form)))
    }

    /// [`Self::gap`] at a shift `mu` where the ladder found at most one negative pivot but the
    /// a-priori error bound hid the gap: the same LDLᴴ again, its error measured instead
    /// ([`SparseFactor::ldlt_residual_bound`]: the residual of the stored factors, within some
    /// 50 units of rounding per entry where the a-priori bound counts 2k + 8, k up to thousands
    /// in the top separators of 10⁶ poses and more: at 10⁶ 1.7e-13 against 3.3e-11; then, if
    /// that falls short, within 4 units, [`crate::linalg::residual::Chunk::Narrow`]: the shared
    /// [`measured_theta`]).
    /// `Err(measured)` where it did not prove the gap either (`None`: not measured).
    fn measured_gap(
        &mut self,
        lambda: &[f64],
        scale: &[f64],
        mu: f64,
        assembly: f64,
    ) -> Result<Gap, Option<f64>> {
        let Some(Some((negative, form))) = self.ldlt_shifted(lambda, scale, mu) else {
            return Err(None);
        };
        if negative > 1 {
            return Err(None);
        }
        let a = factored(&self.upper, &self.permuted, &self.values);
        match measured_theta(mu, form + assembly, |chunk| {
            self.factor.ldlt_residual_bound(a, chunk)
        }) {
            Ok(theta) => {
                self.shifts.remember_shift(mu);
                Ok(Gap::new(negative, theta))
            }
            Err(measured) => Err(measured.map(|error| error + form)),
        }
    }

    /// [`Self::gap`] at shift `mu` (and at most two shifts 8 and 64 times smaller while more than
    /// one pivot is negative) with the LDLᴴ in double-double arithmetic: the same proof, with a
    /// backward error some 10¹⁵ times smaller, for graphs whose second eigenvalue lies below double
    /// precision's resolution (long corridors: the bending modes of ais2klinik are ~1e-12 of
    /// ‖D W̃ D‖). The stored W̃ is still double precision, so `assembly` stays.
    fn precise_gap(
        &mut self,
        lambda: &[f64],
        scale: &[f64],
        mut mu: f64,
        assembly: f64,
    ) -> Option<Gap> {
        let dim = self.dim();
        let rot0 = dim - lambda.len();
        // Double-double runs column by column (faer's blocked kernels need SIMD support it lacks)
        // at some 30x the cost of double precision: beyond ~10⁷ factor entries (320 MB, tens of
        // seconds), no proof rather than an hour-long one.
        if self.precise.is_none() && self.factor.stored_entries() > PRECISE_MAX_ENTRIES {
            return None;
        }
        let factor = self.precise.get_or_insert_with(|| {
            SparseFactor::analyze_ordered(self.upper.symbolic(), &self.order, Layout::Simplicial)
        });
        let dd = |v: f64| fx128::from_f64(v);
        let u = <cx128 as crate::linalg::factor::Scalar>::UNIT_ROUNDOFF;
        let mut values = Vec::new();
        for _ in 0..3 {
            let mut form = f64::MIN_POSITIVE;
            write_values(&self.upper, &mut values, |r, c, v| {
                let s = scale[r] * scale[c];
                if r == c {
                    let l = if r >= rot0 { lambda[r - rot0] } else { 0.0 };
                    form = form.max(4.0 * u * ((v.re.abs() + l.abs()) * s + mu));
                    cx128 {
                        re: (dd(v.re) - dd(l)) * dd(s) - dd(mu),
                        im: dd(0.0),
                    }
                } else {
                    cx128 {
                        re: dd(v.re * s),
                        im: dd(v.im * s),
                    }
                }
            });
            self.factorizations += 1;
            if factor.ldlt(matrix(&self.upper, &values)).is_ok() {
                let negative = factor.inertia_below(0.0);
                if negative <= 1 {
                    let theta = mu - factor.ldlt_backward_error() - assembly - form;
                    return (theta > 0.0).then(|| {
                        self.shifts.remember_shift(mu);
                        Gap::new(negative, theta)
                    });
                }
            }
            mu /= 8.0;
            if mu < 4.0 * assembly {
                break;
            }
        }
        None
    }

    /// The resolution of eigenvalues of W̃(λ) in its own units: the allowance α₀ of the
    /// equilibrated matrix times the largest diagonal entry (Weyl's inequality after undoing D).
    pub fn eigenvalue_resolution(&self, lambda: &[f64]) -> f64 {
        match self.scaling(lambda, 0.0, true) {
            Some((a, scale)) => {
                self.allowance(self.estimate_row_sums(lambda, &a, &scale).norm)
                    * a.iter().fold(0.0f64, |m, &v| m.max(v))
            }
            None => f64::INFINITY,
        }
    }

    /// The diagonal a_k of W̃(λ) + ηP (absolute values when `absolute`, for estimates) and the
    /// power-of-two scaling D_k = 2^{−⌊log₂(a_k)/2⌋} that puts D_k² a_k in [1, 4). `None` if a
    /// diagonal entry is not positive (then W̃(λ) + ηP is not PSD).
    fn scaling(&self, lambda: &[f64], eta: f64, absolute: bool) -> Option<(Vec<f64>, Vec<f64>)> {
        let dim = self.dim();
        let rot0 = dim - lambda.len();
        let mut a = vec![0.0; dim];
        let mut scale = vec![0.0; dim];
        for k in 0..dim {
            let w = self.upper.val()[self.diagonal(k)].re;
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
            scale[k] = power_of_two_scale(a[k]);
        }
        Some((a, scale))
    }

    /// α = dim·u·‖B‖_∞ for the equilibrated B = D(W̃(λ) + ηP)D (exactly summed row by row;
    /// ‖B‖₂ ≤ ‖B‖_∞ for Hermitian B): the backward-error model of the factorization.
    fn alpha(&self, a: &[f64], scale: &[f64]) -> f64 {
        let norm = self
            .abs_row_sums(a, scale)
            .iter()
            .fold(0.0f64, |m, &v| m.max(v));
        self.allowance(norm)
    }

    /// α = dim·u·‖B‖_∞ from ‖B‖_∞ ([`Self::alpha`]).
    fn allowance(&self, norm: f64) -> f64 {
        self.dim() as f64 * (f64::EPSILON / 2.0) * norm
    }

    /// [`RowSums`] at the estimate's equilibration for λ (`a`, `scale` from [`Self::scaling`]
    /// with η = 0 and |a|). The row sums take a modulus per entry of W̃ (0.25 ms on
    /// cityTrees10000, 2 ms on w10000), and the resolution, the gap and the eigenvalues'
    /// resolution ask for them at the same λ: kept for the last λ, bit for bit, where W̃'s
    /// pattern is kept permuted (below [`PERMUTED_BELOW_ROWS`] rows; above, the key would sit on
    /// the peak memory of 10⁶ poses).
    fn estimate_row_sums(&self, lambda: &[f64], a: &[f64], scale: &[f64]) -> RowSums {
        let bits = || lambda.iter().map(|l| l.to_bits());
        let mut memo = self
            .last_row_sums
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((key, sums)) = &*memo
            && same_bits(key, bits())
        {
            return *sums;
        }
        let rows = self.abs_row_sums(a, scale);
        let sums = RowSums {
            norm: rows.iter().fold(0.0f64, |m, &v| m.max(v)),
            floor: ldlt_error_floor(&self.row_counts, &rows),
        };
        if self.permuted.is_some() {
            *memo = Some((bits().collect(), sums));
        }
        sums
    }

    /// The row sums of |B| for B = D(W̃(λ) + ηP)D, the diagonal's moduli `a` and `scale` from
    /// [`Self::scaling`]: for [`Self::alpha`] and the ladder's [`ldlt_error_floor`].
    fn abs_row_sums(&self, a: &[f64], scale: &[f64]) -> Vec<f64> {
        let mut rows: Vec<f64> = (0..a.len()).map(|k| a[k] * scale[k] * scale[k]).collect();
        for_each_entry(&self.upper, |r, c, v| {
            if r != c {
                let e = v.norm() * scale[r] * scale[c];
                rows[r] += e;
                rows[c] += e;
            }
        });
        rows
    }

    /// One attempt: B = D(W̃(λ) + ηP)D − αI, LLᴴ. Whether it succeeded. α allows for the
    /// factorization's rounding (dim·u·‖B‖_∞, or `rounding` where that is larger: what
    /// [`Self::measured_llt`] checks), the assembly's and that of B's own diagonal.
    fn try_eta(&mut self, problem: &Problem, lambda: &[f64], eta: f64, rounding: f64) -> bool {
        let dim = self.dim();
        let rot0 = dim - lambda.len();
        let Some((a, scale)) = self.scaling(lambda, eta, false) else {
            return false;
        };
        let base = self.alpha(&a, &scale).max(rounding);
        let floor = base + assembly_error(problem, &scale);
        let mut alpha = floor;
        // Plus the rounding of each a_kk itself (two additions), in equilibrated units.
        for k in rot0..dim {
            let w = self.upper.val()[self.diagonal(k)].re;
            let magnitude = w + lambda[k - rot0].abs() + eta;
            alpha = alpha.max(floor + 4.0 * f64::EPSILON * magnitude * scale[k] * scale[k]);
        }
        self.write(|r, c, v| {
            let s = scale[r] * scale[c];
            if r == c {
                c64::new(a[r] * s - alpha, 0.0)
            } else {
                v * s
            }
        });
        self.factorizations += 1;
        let a = factored(&self.upper, &self.permuted, &self.values);
        let proven = self.factor.llt(a).is_ok();
        self.last_llt = proven.then_some((eta.to_bits(), base));
        proven
    }

    /// The eigenvalues of W̃(λ) at zero: the count a deflated proof established when `bound` is
    /// one (1, the SZEP), else the inertia of W̃(λ) below 16 times their resolution
    /// ([`Self::eigenvalue_resolution`]). `None` on a zero pivot.
    pub fn near_zero(&mut self, bound: Option<&SparseBound>, lambda: &[f64]) -> Option<usize> {
        bound.and_then(|b| b.near_zero).or_else(|| {
            let threshold = (16.0 * self.eigenvalue_resolution(lambda)).max(f64::MIN_POSITIVE);
            self.count_below(lambda, threshold)
        })
    }

    /// The number of eigenvalues of W̃(λ) below `threshold` (Sylvester's law of inertia: the
    /// negative pivots of an LDLᴴ of W̃(λ) − threshold·I). `None` on a zero pivot.
    pub fn count_below(&mut self, lambda: &[f64], threshold: f64) -> Option<usize> {
        self.fill_shifted(lambda, threshold);
        let a = factored(&self.upper, &self.permuted, &self.values);
        self.factor.ldlt(a).ok()?;
        Some(self.factor.inertia_below(0.0))
    }

    /// W̃(λ) (upper triangle, W̃'s own pattern and order), e.g. for a negative-curvature
    /// direction.
    pub fn penalized_matrix(
        &mut self,
        lambda: &[f64],
    ) -> faer::sparse::SparseColMatRef<'_, usize, c64> {
        let rot0 = self.dim() - lambda.len();
        write_values(&self.upper, &mut self.values, |r, c, v| {
            shifted(r, c, v, rot0, lambda, 0.0)
        });
        matrix(&self.upper, &self.values)
    }

    fn fill_shifted(&mut self, lambda: &[f64], threshold: f64) {
        let dim = self.dim();
        let rot0 = dim - lambda.len();
        self.write(|r, c, v| shifted(r, c, v, rot0, lambda, threshold));
    }

    /// Writes the values of the next matrix to factor: [`write_values`] in W̃'s pattern, or
    /// each into its place in the permuted one ([`write_permuted`]).
    fn write(&mut self, value: impl FnMut(usize, usize, c64) -> c64) {
        match &self.permuted {
            Some(permuted) => write_permuted(permuted, &self.upper, &mut self.values, value),
            None => write_values(&self.upper, &mut self.values, value),
        }
    }
}

/// The matrix of the values last written ([`SparseCertifier::write`]) in the pattern its factor
/// factors: the permuted one where there is one, else W̃'s.
fn factored<'a>(
    upper: &'a SparseColMat<usize, c64>,
    permuted: &'a Option<Permuted>,
    values: &'a [c64],
) -> faer::sparse::SparseColMatRef<'a, usize, c64> {
    match permuted {
        Some(permuted) => faer::sparse::SparseColMatRef::new(permuted.pattern.as_ref(), values),
        None => matrix(upper, values),
    }
}

/// W̃(λ) − threshold·I's entry at (r, c) from W̃'s entry v (rotations from row `rot0`).
fn shifted(r: usize, c: usize, v: c64, rot0: usize, lambda: &[f64], threshold: f64) -> c64 {
    if r == c {
        let l = if r >= rot0 { lambda[r - rot0] } else { 0.0 };
        c64::new(v.re - l - threshold, 0.0)
    } else {
        v
    }
}

/// The multiply-adds of the certificate's factorizations (complex ones) from which a supernodal
/// factor's are split between the two cores ([`SparseFactor::prepare_factor_split`]; only a
/// factor in its own order, with W̃'s pattern kept permuted below [`PERMUTED_BELOW_ROWS`], can
/// be: so not at 10⁶ poses, whose memory is at its limit). Among the public planar files only
/// city10000 and w10000 have a supernodal certificate (2.8·10⁷ each). Their LDLᴴ took 3.9 ms
/// split against 6.2 ms by faer's on city10000 (whether or not the second core was free: faer's
/// supernodal LDLᴴ is the slower one here); whole process, 31 interleaved pairs, city10000 0.985,
/// the 10⁵-pose world 0.983 (11 pairs, the same peak memory). Bounds and outputs as before to
/// the last bit on both files (at 10⁵ poses η differs in its 15th digit).
const SPLIT_FACTOR_MIN_WORK: f64 = 5e6;

/// The rows from which [`SparseCertifier`] leaves the permutation to faer: below, it keeps W̃'s
/// pattern in the factor's order ([`Permuted`]; 16 bytes a stored entry, some 2 MB on the public
/// landmark files), which saves faer's copy of each matrix it factors (2.7-4.8% of a planar
/// process with the chordal start's, in perf samples); from 2²⁰ rows (10⁶ poses and more) it
/// would be 100 MB on top of the Newton steps' peak memory, where the analysis is built.
const PERMUTED_BELOW_ROWS: usize = 1 << 20;

/// [`write_values`] into the places of a permuted pattern: each value added to a zero, then
/// conjugated where the permutation moved its entry across the diagonal.
fn write_permuted(
    permuted: &Permuted,
    upper: &SparseColMat<usize, c64>,
    values: &mut Vec<c64>,
    mut value: impl FnMut(usize, usize, c64) -> c64,
) {
    values.clear();
    values.resize(permuted.len(), c64::new(0.0, 0.0));
    let mut k = 0;
    for_each_entry(upper, |r, c, v| {
        permuted.put(k, added_to_zero(value(r, c, v)), values);
        k += 1;
    });
}

/// Rewrites `values` as those of a matrix in W̃'s pattern (`upper`): `value(row, column, W̃'s
/// entry)` for each entry of W̃'s upper triangle in its stored order ([`for_each_entry`]), each
/// added to a zero ([`added_to_zero`]). For the double-precision factorizations
/// ([`SparseCertifier::write`]) and the double-double one ([`SparseCertifier::precise_gap`]).
fn write_values<T: Scalar>(
    upper: &SparseColMat<usize, c64>,
    values: &mut Vec<T>,
    mut value: impl FnMut(usize, usize, c64) -> T,
) {
    values.clear();
    values.reserve_exact(upper.val().len());
    for_each_entry(upper, |r, c, v| values.push(added_to_zero(value(r, c, v))));
}

/// `v` added to a zero, as an assembly adds each value to its zeroed slot
/// ([`crate::linalg::factor::Assembly::fill`]): a −0 is stored as +0, so the matrices factored
/// in W̃'s own pattern hold the same bits as when they were assembled.
fn added_to_zero<T: Scalar>(v: T) -> T {
    let mut zero = T::zero_impl();
    zero += v;
    zero
}

/// The matrix of W̃'s pattern (`upper`) with `values` in its stored order
/// ([`SparseCertifier::write`], [`SparseCertifier::precise_gap`]).
fn matrix<'a, T>(
    upper: &'a SparseColMat<usize, c64>,
    values: &'a [T],
) -> faer::sparse::SparseColMatRef<'a, usize, T> {
    faer::sparse::SparseColMatRef::new(upper.symbolic(), values)
}

/// Whether a memo's `key` holds exactly `bits`, compared as they come: no key is built for a
/// lookup (at 10⁶ poses the rank-1 point's was 32 MB of fresh pages per call).
fn same_bits(key: &[u64], mut bits: impl Iterator<Item = u64>) -> bool {
    key.iter().all(|&k| bits.next() == Some(k)) && bits.next().is_none()
}

/// Σ(λ − η1) = Σλ − nη, the dual objective (31) at a proven dual-feasible point, less the
/// rounding of the sum (2n·ε·Σ|λ|): a lower bound on f* by weak duality (32).
fn dual_value(lambda: &[f64], eta: f64) -> f64 {
    let n = lambda.len() as f64;
    let sum: f64 = lambda.iter().sum();
    let error = 2.0 * n * f64::EPSILON * lambda.iter().map(|l| l.abs()).sum::<f64>();
    sum - n * eta - error
}

/// The largest factor (stored entries of the double-precision one) for which
/// [`SparseCertifier::precise_gap`] runs its double-double LDLᴴ.
const PRECISE_MAX_ENTRIES: usize = 10_000_000;

/// What the inertia of [`SparseCertifier::gap`] proved about D W̃(λ) D.
#[derive(Debug, Clone, Copy)]
enum Gap {
    /// λ₁ ≥ θ > 0.
    Definite(f64),
    /// λ₂ ≥ θ > 0 and λ₁ < θ.
    Isolated(f64),
}

impl Gap {
    /// From the number of negative pivots (0 or 1) of D W̃(λ) D − μI.
    fn new(negative: usize, theta: f64) -> Self {
        if negative == 0 {
            Gap::Definite(theta)
        } else {
            Gap::Isolated(theta)
        }
    }
}

/// A bound on ‖D(W̃_stored − W̃)D‖₂, W̃ = Σ_e W̃_e the exact sum of the edges' terms (the matrix of
/// [`Problem::cost`]) and W̃_stored its floating-point assembly: each stored entry sums at most
/// 2·deg + 2 contributions of at most 4 roundings each (deg the largest number of edges at a pose),
/// so |ΔW̃| ≤ γ_{2·deg+8} Σ_e |W̃_e| entrywise, and the ∞-norm of D(Σ_e |W̃_e|)D is summed edge by
/// edge (doubled for the rounding of those sums).
fn assembly_error(problem: &Problem, scale: &[f64]) -> f64 {
    // Nodes: poses 0..n, then landmarks n..n+m.
    let mut degree = vec![0usize; problem.n + problem.m];
    let mut rows = vec![0.0; scale.len()];
    for t in &problem.terms {
        degree[t.i] += 1;
        degree[if t.landmark { problem.n + t.j } else { t.j }] += 1;
        let yi = problem.rotation_row(t.i);
        // An observation has no head rotation: its κ = 0, so the terms with dyj vanish.
        let yj = problem.head_rotation_row(t);
        let (dyi, dyj) = (scale[yi], yj.map_or(0.0, |r| scale[r]));
        let pi = problem.position_row(t.i).map(|r| (r, scale[r]));
        let pj = problem.head_position_row(t).map(|r| (r, scale[r]));
        let (dpi, dpj) = (pi.map_or(0.0, |p| p.1), pj.map_or(0.0, |p| p.1));
        let (tau, kappa, dn) = (t.tau.abs(), t.kappa.abs(), t.delta.norm());
        if let Some((r, d)) = pi {
            rows[r] += tau * d * (d + dpj + dn * dyi);
        }
        if let Some((r, d)) = pj {
            rows[r] += tau * d * (d + dpi + dn * dyi);
        }
        rows[yi] += dyi * ((tau * dn * dn + kappa) * dyi + tau * dn * (dpi + dpj) + kappa * dyj);
        if let Some(yj) = yj {
            rows[yj] += kappa * dyj * (dyj + dyi);
        }
    }
    let deg = degree.iter().copied().max().unwrap_or(0);
    let norm = rows.iter().fold(0.0f64, |m, &r| m.max(r));
    2.0 * gamma(2 * deg + 8) * norm
}

/// The Rayleigh quotient ρ of z = D⁻¹x for T(η) = D(W̃(λ) + ηP)D and its residual, enclosed
/// (Temple's inequality in [`SparseCertifier::certify_rank_one`]). z*T(η)z = F + η‖Y‖² with
/// F = f(x) − Σ_a λ_a|y_a|² = x*W̃(λ)x, and z*z = N = Σ_k |x_k|²/D_k²; each is kept with a bound on
/// its rounding error. η may be negative (λ raised): F > 0 when the positions are not exactly
/// stationary, and the bound Σλ − nη then recovers it.
struct Rayleigh<'a> {
    enclosure: &'a Enclosure,
    x: &'a [c64],
    lambda: &'a [f64],
    scale: &'a [f64],
    f: f64,
    f_error: f64,
    y: f64,
    y_error: f64,
    norm: f64,
    norm_error: f64,
    /// max_a D_a² over the rotation rows: ‖DPD‖₂, by which a negative η lowers λ₂ (Weyl).
    rotation_scale: f64,
    /// Per row k, the error bound of G_k with its modulus's share, g_error_k + 4u|G_k|, and
    /// |x_k|: the same at every η that [`Self::check`] tries (both moduli as their upper bounds
    /// [`modulus_bound`], as they enter error bounds alone).
    g_slack: Vec<f64>,
    x_modulus: Vec<f64>,
}

impl<'a> Rayleigh<'a> {
    fn new(enclosure: &'a Enclosure, x: &'a [c64], lambda: &'a [f64], scale: &'a [f64]) -> Self {
        let (dim, n) = (x.len(), lambda.len());
        let rot0 = dim - n;
        let y: f64 = x[rot0..].iter().map(|z| z.norm_sqr()).sum();
        let norm: f64 = x
            .iter()
            .zip(scale)
            .map(|(z, d)| z.norm_sqr() / (d * d))
            .sum();
        let (mut s, mut s_abs) = (0.0, 0.0);
        for (l, z) in lambda.iter().zip(&x[rot0..]) {
            s += l * z.norm_sqr();
            s_abs += l.abs() * z.norm_sqr();
        }
        let f = enclosure.cost - s;
        let f_error = enclosure.cost_error
            + gamma(n + 4) * s_abs
            + 2.0 * U * (enclosure.cost.abs() + s.abs());
        let rotation_scale = scale[rot0..].iter().fold(0.0f64, |m, d| m.max(d * d));
        let g_slack = enclosure
            .g
            .iter()
            .zip(&enclosure.g_error)
            .map(|(g, e)| e + 4.0 * U * modulus_bound(*g))
            .collect();
        Rayleigh {
            g_slack,
            x_modulus: x.iter().map(|&z| modulus_bound(z)).collect(),
            enclosure,
            x,
            lambda,
            scale,
            f,
            f_error,
            y,
            y_error: gamma(n + 3) * y,
            norm,
            norm_error: gamma(dim + 4) * norm,
            rotation_scale,
        }
    }

    /// Lower and upper bounds on z*T(η)z.
    fn numerator(&self, eta: f64) -> (f64, f64) {
        let slack = 4.0 * U * (self.f.abs() + self.f_error + eta.abs() * self.y);
        let (y_lo, y_hi) = (self.y - self.y_error, self.y + self.y_error);
        let (a, b) = (eta * y_lo, eta * y_hi);
        (
            self.f - self.f_error + a.min(b) - slack,
            self.f + self.f_error + a.max(b) + slack,
        )
    }

    /// The η at which the lower bound of z*T(η)z reaches `target`.
    fn eta_for(&self, target: f64) -> f64 {
        let (f_lo, _) = self.numerator(0.0);
        let need = target - f_lo;
        let y = if need >= 0.0 {
            self.y - self.y_error
        } else {
            self.y + self.y_error
        };
        need / y * (1.0 + 1e-6) + 1e-6 * need.abs() / y
    }

    /// Whether Temple's inequality proves λ₁(T(η)) ≥ 0, given λ₂(T(0)) ≥ θ (so
    /// λ₂(T(η)) ≥ θ + min(η, 0)·max_a D_a²). `Err(Some(η'))`: not at η, try η' (the η whose ρ
    /// would clear the residual at η); `Err(None)`: ρ reaches θ, no η will do.
    fn check(&self, theta: f64, eta: f64) -> Result<(), Option<f64>> {
        let theta = theta + eta.min(0.0) * self.rotation_scale * (1.0 + 4.0 * U);
        let (num_lo, num_hi) = self.numerator(eta);
        let (norm_lo, norm_hi) = (self.norm - self.norm_error, self.norm + self.norm_error);
        if !(norm_lo > 0.0 && theta > 0.0) {
            return Err(None);
        }
        let rho_hi = num_hi.max(0.0) / norm_lo * (1.0 + 2.0 * U);
        if rho_hi.is_nan() || rho_hi >= theta {
            return Err(None);
        }
        let sigma = 0.5 * (num_lo.max(0.0) / norm_hi + rho_hi);
        // ‖Tz − σz‖ ≥ ‖Tz − ρz‖ for any σ (ρ minimizes it): the residual at σ, enclosed.
        let rot0 = self.x.len() - self.lambda.len();
        let (mut res, mut err) = (0.0, 0.0);
        for (k, (&xk, &d)) in self.x.iter().zip(self.scale).enumerate() {
            let (mut r, mut e) = (self.enclosure.g[k], self.g_slack[k]);
            let xk_modulus = self.x_modulus[k];
            if k >= rot0 {
                let l = self.lambda[k - rot0];
                r -= xk * (l - eta);
                e += 4.0 * U * (l.abs() + eta.abs()) * xk_modulus;
            }
            let v = r * d - xk * (sigma / d);
            let ev = d * e + 4.0 * U * (sigma * xk_modulus / d + modulus_bound(v));
            res += v.norm_sqr();
            err += ev * ev;
        }
        let grow = 1.0 + gamma(self.x.len() + 4);
        let eps2 = ((res.sqrt() + err.sqrt()) * grow).powi(2) / norm_lo * (1.0 + 4.0 * U);
        if num_lo > 0.0 {
            let rho_lo = num_lo / norm_hi * (1.0 - 2.0 * U);
            // λ₁ ≥ ρ − ε²/(θ − ρ), increasing in ρ < θ: at ρ_lo, with θ − ρ_hi ≤ θ − ρ_lo.
            if rho_lo * (theta - rho_hi) * (1.0 - 4.0 * U) >= eps2 {
                return Ok(());
            }
        }
        let rho = 2.0 * eps2 / theta;
        if rho.is_nan() || rho >= 0.5 * theta {
            return Err(None);
        }
        Err(Some(self.eta_for(rho * norm_hi)))
    }

    /// The smallest η ≤ `eta_max` found at which [`Self::check`] holds, searched upward from the
    /// η that makes z*T(η)z vanish (λ raised by F/‖Y‖²), each step at least the η the residual
    /// asks for and the steps doubling.
    fn smallest_eta(&self, theta: f64, eta_max: f64) -> Option<f64> {
        // Not below −θ/(4·max D_a²): a larger negative η would eat the gap it relies on.
        let mut eta = self
            .eta_for(0.0)
            .max(-0.25 * theta / (self.rotation_scale * (1.0 + 4.0 * U)));
        let mut step = (1e-6 * eta.abs()).max(f64::MIN_POSITIVE);
        for _ in 0..64 {
            if eta.is_nan() || eta > eta_max {
                return None;
            }
            match self.check(theta, eta) {
                Ok(()) => return Some(eta),
                Err(None) => return None,
                Err(Some(next)) => {
                    eta = next.max(eta + step);
                    step *= 2.0;
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::rank_p::Point;
    use crate::problem::weights::{Weights, edge_weights};
    use crate::simulate::{RotationNoise, SimulationConfig, TranslationNoise, simulate};
    use faer::{Mat, Side};

    /// A generated graph's ground truth as a rank-1 point: positions relative to pose 0's, unit
    /// rotations.
    fn truth_point(problem: &Problem, truth: &[crate::graph::Pose2]) -> Point {
        let mut x = vec![c64::new(0.0, 0.0); problem.rows()];
        for (k, pose) in truth.iter().enumerate() {
            if let Some(r) = problem.position_row(k) {
                x[r] = c64::new(pose.x - truth[0].x, pose.y - truth[0].y);
            }
            x[problem.rotation_row(k)] = c64::new(pose.theta.cos(), pose.theta.sin());
        }
        Point { p: 1, x }
    }

    /// A generated graph without noise (`n` poses, `seed`, loop closures with probability
    /// `loops`) at its ground truth, where f = 0: the problem, the point, its multipliers λ, the
    /// certifier of W̃ and the mean of W̃'s diagonal over the rotation rows.
    fn noiseless_truth(
        n: usize,
        seed: u64,
        loops: f64,
    ) -> (Problem, Point, Vec<f64>, SparseCertifier, f64) {
        let (problem, point, lambda) = at_truth(n, seed, loops, 0.0);
        let certifier = SparseCertifier::new(&problem.matrix.upper, &problem.row_order());
        let (dim, rot0) = (certifier.dim(), certifier.dim() - lambda.len());
        let mean = (rot0..dim)
            .map(|k| problem.matrix.upper.val()[certifier.diagonal(k)].re)
            .sum::<f64>()
            / lambda.len() as f64;
        (problem, point, lambda, certifier, mean)
    }

    /// A generated graph (`n` poses, `seed`, loop closures with probability `loops`, rotation
    /// and translation noise `sigma`) at its ground truth: the problem, the point and its
    /// multipliers λ.
    fn at_truth(n: usize, seed: u64, loops: f64, sigma: f64) -> (Problem, Point, Vec<f64>) {
        let sim = simulate(&SimulationConfig {
            n,
            seed,
            loop_probability: loops,
            rotation_noise: RotationNoise::Gaussian { sigma },
            translation_noise: TranslationNoise::Gaussian { sigma },
            ..Default::default()
        });
        let w = edge_weights(&sim.graph, Weights::Isotropic).unwrap();
        let problem = Problem::new(&sim.graph, &w);
        let point = truth_point(&problem, &sim.truth);
        let lambda = problem.multipliers(&point, &problem.half_gradient(&point));
        (problem, point, lambda)
    }

    /// A shift proven by [`SparseCertifier::prove_shift`] (the dense certificate's check) is one
    /// that makes W̃(λ − η1) = W̃(λ) + ηP PSD: at a noiseless graph's ground truth W̃(λ) has its
    /// one zero eigenvalue along x, whose rotations are nonzero, so η > 0 (a tenth of the mean
    /// rotation diagonal) lifts it and is proven, with the bound Σλ − nη less its rounding, while
    /// η < 0 (the same, negated) takes x*W̃x below zero and must be refused, as must a smaller
    /// negative one, 1e-9 of it.
    #[test]
    fn a_proven_shift_is_one_that_makes_the_matrix_psd() {
        let (problem, _, lambda, mut certifier, mean) = noiseless_truth(60, 9, 0.1);
        let (problem, eta) = (&problem, 0.1 * mean);
        let n = lambda.len() as f64;
        let lower = certifier.prove_shift(problem, &lambda, eta).expect("PSD");
        let exact = lambda.iter().sum::<f64>() - n * eta;
        assert!(lower <= exact && lower >= exact - 1e-9 * exact.abs().max(1.0));
        assert_eq!(certifier.prove_shift(problem, &lambda, -eta), None);
        assert_eq!(certifier.prove_shift(problem, &lambda, -1e-9 * eta), None);
    }

    /// The double-double gap ([`SparseCertifier::precise_gap`]), which no public file reaches (it
    /// runs where double precision's rounding hides the gap), held against the eigenvalues of
    /// B = D W̃(λ) D from a dense eigendecomposition, at the optimum of a generated graph without
    /// noise (its ground truth, f = 0: B's smallest eigenvalue at zero) and with its multipliers
    /// lowered by δ (W̃(λ − δ1) = W̃(λ) + δ·blkdiag(0, I) ≻ 0). At shifts μ between B's
    /// eigenvalues its verdict must follow the count of eigenvalues below μ: at most one below μ
    /// (or below μ/8, μ/64, its two retries) proves θ ≤ μ with that count (Definite for none,
    /// Isolated for one), θ within the rounding of μ; two or more below all three shifts prove
    /// nothing. The double-precision LDLᴴ at the same shifts must count the same pivots, and its
    /// measured error ([`SparseCertifier::measured_gap`]) prove the gap where at most one lies
    /// below μ and nothing where more do.
    #[test]
    fn the_double_double_gap_follows_the_dense_eigenvalues() {
        let (problem, point, lambda, mut certifier, mean) = noiseless_truth(30, 5, 0.2);
        let problem = &problem;
        let weight: f64 = problem.terms.iter().map(|t| t.tau + t.kappa).sum();
        assert!(
            problem.cost(&point) < 1e-20 * weight,
            "the truth is not a zero of f"
        );
        let (dim, rot0) = (certifier.dim(), certifier.dim() - lambda.len());
        // δ a twentieth of the rotation rows' mean diagonal entry of W̃.
        let delta = 0.05 * mean;
        let lowered: Vec<f64> = lambda.iter().map(|l| l - delta).collect();
        let mut proven = [0; 2];
        let mut measured = [0; 2];
        let mut unproven = 0;
        for (k, lambda) in [&lambda, &lowered].into_iter().enumerate() {
            let (_, scale) = certifier.scaling(lambda, 0.0, true).unwrap();
            let assembly = assembly_error(problem, &scale);
            // B, dense and Hermitian, from W̃'s upper triangle.
            let mut b = Mat::<c64>::zeros(dim, dim);
            for_each_entry(&problem.matrix.upper, |r, c, v| {
                let v = if r == c {
                    let l = if r >= rot0 { lambda[r - rot0] } else { 0.0 };
                    c64::new(v.re - l, 0.0)
                } else {
                    v
                } * (scale[r] * scale[c]);
                b[(r, c)] = v;
                b[(c, r)] = v.conj();
            });
            let eig = b.self_adjoint_eigenvalues(Side::Lower).unwrap();
            let spread = 1e-9 * eig[dim - 1];
            if k == 0 {
                // One eigenvalue at zero (the optimum's direction), the rest clear of it.
                assert!(
                    eig[0].abs() < spread && eig[1] > 1e3 * spread,
                    "{:?}",
                    &eig[..3]
                );
            } else {
                assert!(eig[0] > 1e3 * spread, "{:?}", &eig[..3]);
            }
            let below = |mu: f64| eig.iter().filter(|&&e| e < mu).count();
            // Shifts from μ/64 to 100μ around B's low eigenvalues; none within 1e-6 (relative)
            // of an eigenvalue, where the count would be the rounding's choice.
            let mut shifts = vec![];
            for anchor in [eig[0], eig[1], eig[2], eig[dim / 4]] {
                for f in [1.0 / 64.0, 0.3, 0.7, 2.0, 5.0, 9.0, 100.0] {
                    let mu = anchor * f;
                    if mu > 10.0 * spread && eig.iter().all(|e| (e - mu).abs() > 1e-6 * mu) {
                        shifts.push(mu);
                    }
                }
            }
            for &mu in &shifts {
                // The double-precision LDLᴴ counts the same (these gaps lie far above its
                // rounding).
                let double = certifier.inertia_at(lambda, &scale, mu);
                assert_eq!(double.flatten().map(|d| d.0), Some(below(mu)), "μ = {mu:e}");
                let expected = [mu, mu / 8.0, mu / 64.0]
                    .into_iter()
                    .take_while(|&m| m >= 4.0 * assembly)
                    .find(|&m| below(m) <= 1);
                let gap = certifier.precise_gap(lambda, &scale, mu, assembly);
                match (expected, gap) {
                    (None, None) => unproven += 1,
                    (Some(m), Some(Gap::Definite(theta) | Gap::Isolated(theta))) => {
                        let negative = usize::from(matches!(gap, Some(Gap::Isolated(_))));
                        assert_eq!(negative, below(m), "μ = {mu:e}: at {m:e}");
                        assert!(
                            theta > 0.0 && theta <= m && theta >= m - 1e-12,
                            "μ = {mu:e}: θ = {theta:e} at {m:e}"
                        );
                        proven[negative] += 1;
                    }
                    _ => panic!("μ = {mu:e}: {gap:?}, expected a proof at {expected:?}"),
                }
                // The error measured at μ itself (SparseFactor::ldlt_residual_bound) proves the
                // gap exactly where at most one eigenvalue lies below μ, θ within it of μ.
                match (
                    below(mu),
                    certifier.measured_gap(lambda, &scale, mu, assembly),
                ) {
                    (n @ (0 | 1), Ok(gap)) => {
                        let (negative, theta) = match gap {
                            Gap::Definite(theta) => (0, theta),
                            Gap::Isolated(theta) => (1, theta),
                        };
                        assert_eq!(n, negative, "μ = {mu:e}");
                        assert!(
                            theta > 0.0 && theta <= mu && theta >= mu - 1e-12,
                            "{theta:e}"
                        );
                        measured[n] += 1;
                    }
                    (2.., Err(_)) => {}
                    (n, g) => panic!("μ = {mu:e}: {n} below, measured {g:?}"),
                }
            }
        }
        // Both kinds of proof were reached, and shifts that prove nothing.
        assert!(
            proven[0] > 0 && proven[1] > 0 && unproven > 0,
            "{proven:?} {unproven}"
        );
        assert!(measured[0] > 0 && measured[1] > 0, "{measured:?}");
    }

    /// W̃'s pattern kept in the factor's order ([`Permuted`]) factors the matrices that faer's
    /// own permutation copies: at noisy graphs' ground truth, the inertia and error bound of each
    /// shifted LDLᴴ, the shifted LLᴴ's bound and the count below a threshold are the same bits
    /// either way, for a factor read as its upper triangle (simplicial) and one read as its lower
    /// (supernodal: the permutation moves entries across the diagonal both ways).
    #[test]
    fn the_kept_permuted_pattern_factors_faers_own_copies() {
        let mut sides = Vec::new();
        for (n, loops, seed) in [(40, 0.02, 3), (300, 0.05, 7)] {
            let (problem, point, lambda) = at_truth(n, seed, loops, 0.05);
            let problem = &problem;
            let x = point.x;
            let order = problem.row_order();
            let mut kept = SparseCertifier::with_storage(&problem.matrix.upper, &order, true);
            let mut copied = SparseCertifier::with_storage(&problem.matrix.upper, &order, false);
            assert!(kept.permuted.is_some() && copied.permuted.is_none());
            assert_eq!(kept.row_counts, copied.row_counts);
            sides.push(kept.factor.read_side());
            let (_, scale) = kept.scaling(&lambda, 0.0, true).unwrap();
            for mu in [1e-6, 1e-3, 1e-1, 1.0] {
                let bits =
                    |r: Option<Option<(usize, f64)>>| r.flatten().map(|(k, e)| (k, e.to_bits()));
                assert_eq!(
                    bits(kept.inertia_at(&lambda, &scale, mu)),
                    bits(copied.inertia_at(&lambda, &scale, mu)),
                    "n {n}, μ {mu:e}"
                );
                assert_eq!(
                    kept.count_below(&lambda, mu),
                    copied.count_below(&lambda, mu),
                    "n {n}, μ {mu:e}"
                );
            }
            let bound = |c: &mut SparseCertifier| {
                c.certify_cholesky(problem, &lambda, &x, 1, 1e3)
                    .map(|b| (b.eta.to_bits(), b.lower_bound.to_bits()))
            };
            let proven = bound(&mut kept);
            assert!(proven.is_some(), "n {n}: no shifted LLᴴ succeeded");
            assert_eq!(proven, bound(&mut copied), "n {n}");
        }
        assert_eq!(sides, [Side::Upper, Side::Lower]);
    }
}
