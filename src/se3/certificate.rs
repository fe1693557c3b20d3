//! The certificate of an SE(3) estimate (SE-Sync Theorem 7 and its Algorithm 2's verification,
//! made rigorous the way pgo proves the planar one, [`crate::certify::SparseCertifier`]).
//!
//! At a point X (rank p, here the rounded estimate at p = 3), the multipliers of the
//! first-order conditions are Λ_i = sym((QX)_i X_iᵀ) (3x3, SE-Sync eq. (48):
//! Λ = SymBlockDiag(...)), and the certificate matrix is S = Q − blkdiag(0, Λ) (the translation
//! rows kept, as W̃(λ) in 2D). Weak duality: if S + ηP ⪰ 0, P = blkdiag(0, I_{3n}), then for
//! every feasible X', f(X') = tr(X'ᵀ(S + ηP)X') + Σ_i tr(Λ_i − ηI) ≥ Σ_i tr Λ_i − 3nη, so
//! `lower_bound = Σ tr Λ_i − 3nη ≤ f*` (the planar Σλ − nη of eq. (31)-(32)).
//!
//! At an optimum SX = 0: S has (at least) the k = 3 null directions of X's columns (one per
//! dimension of the global rotation; the translation gauge is fixed by the anchor), which no
//! factorization resolves. So the proof deflates them, the block generalization of the planar
//! rank-1 proof: with D a power-of-two equilibration, T(η) = D(S + ηP)D and Z = D⁻¹X (N×k),
//!
//! 1. the gap (the planar certificate's shift ladder, [`crate::certify::ladder`]): an LDLᵀ of
//!    D S D − μI (exact inertia of a matrix within its a-posteriori backward
//!    error, [`SparseFactor::ldlt_backward_error`], plus the rounding of Q's assembly and of the
//!    shift) with at most k negative pivots proves λ_{k+1}(T(η)) ≥ θ = μ − error (Sylvester,
//!    Weyl; ηDPD ⪰ 0 for η ≥ 0);
//! 2. Lehmann-Maehly's bound (the block form of Temple's inequality used in 2D): with ρ ≤
//!    λ_{k+1}(T), M = Zᵀ(T − ρ)Z and N = Zᵀ(T − ρ)²Z, the Ritz values μ_i of (T − ρ)⁻¹ on the
//!    span of (T − ρ)Z bound its eigenvalues 1/(λ_j − ρ) from above (Courant-Fischer), so if the
//!    largest, μ_k, is below −1/ρ then λ₁(T) ≥ ρ + 1/μ_k ≥ 0. μ_k ≤ −1/ρ ⟺ ρM + N ⪯ 0 ⟺
//!    K = ρ·ZᵀTZ − (TZ)ᵀ(TZ) ⪰ 0; K ≻ 0 strictly also gives M ≺ 0 and N ≻ 0. For k = 1 this is
//!    Temple's ρ_R(θ − ρ_R) ≥ ε² of the planar proof.
//! 3. ZᵀTZ = Xᵀ(S + ηP)X and TZ = D(SX + ηPX) are computed from the edges' residuals
//!    ([`Problem3::evaluate`]) with rounding bounds, K ≻ 0 is checked by a 3x3 Cholesky after
//!    subtracting the Frobenius norm of K's error bound, and η is the smallest value found.
//!
//! Where the deflated proof does not go through (a saddle, a gap hidden by rounding), the
//! shifted factorization: an LLᵀ of D(S + ηP)D − αI, α covering its backward error (as
//! [`crate::certify::SparseCertifier::certify_cholesky`]).

use super::problem::{Point3, Problem3};
use crate::certify::ladder::{Ladder, ShiftMemory, isolate, measured_theta, power_of_two_scale};
use crate::linalg::factor::{Assembly, Layout, SparseFactor, ldlt_error_floor};
use crate::linalg::residual::within_allowance;
use crate::linalg::roundoff::{U, gamma};

/// What [`Certifier3::certify`] proved.
#[derive(Debug, Clone, Copy)]
pub struct Bound3 {
    /// S + ηP ⪰ 0 proven.
    pub eta: f64,
    /// Σ tr Λ_i − 3nη, less the rounding of the sum: a lower bound on f*.
    pub lower_bound: f64,
    /// For a deflated proof: θ ≤ λ_{k+1}(D S D) (equilibrated units).
    pub gap: Option<f64>,
    /// The number of eigenvalues of S proven near zero (k) by a deflated proof.
    pub deflated: Option<usize>,
}

/// The multiply-adds of S's factorizations from which they are split between the two cores
/// ([`SparseFactor::prepare_factor_split`]): the LDLᵀ of the inertia ladder, and the LLᵀ. All
/// public 3D files but the two grids are above it, parking-garage (7.8·10⁶) the smallest. Whole
/// process, split/not, 21 interleaved pairs: parking-garage 0.981, sphere2500 0.985, torus3D
/// 0.983, cubicle 0.981, sphere_bignoise 0.976; the same reports and estimates to the last bit.
/// (The LLᵀ alone split, before the LDLᵀ could be, measured 0.99-1.00.)
const SPLIT_FACTOR_MIN_WORK: f64 = 5e6;

/// The pattern of S analyzed once, reused by every factorization.
pub struct Certifier3 {
    /// Q's upper triangle: (row, col, value, Σ|contributions|).
    entries: Vec<(usize, usize, f64, f64)>,
    /// For each entry within one pose's rotation block: (pose, a, b) of Λ to subtract.
    lambda_at: Vec<Option<(usize, usize, usize)>>,
    diagonal: Vec<usize>,
    assembly: Assembly<f64>,
    factor: SparseFactor<f64>,
    /// The factor's row counts by row of S ([`SparseFactor::row_counts`] in the elimination
    /// order, carried back), for the ladder's [`ldlt_error_floor`].
    row_counts: Vec<u32>,
    values: Vec<f64>,
    /// Row sums of D|Q|D's assembly bound, before scaling (per entry abs kept in `entries`).
    max_degree: usize,
    shifts: ShiftMemory,
    pub factorizations: usize,
    /// η (its bits) of the factor's LLᵀ where it is the last [`Self::try_eta`]'s success, and
    /// the allowance dim·u·‖B‖_∞ that attempt gave its rounding ([`Self::measured_llt`]).
    last_llt: Option<(u64, f64)>,
}

impl Certifier3 {
    pub fn new(problem: &Problem3) -> Self {
        // Built ahead on the second core: between its steps, a pause for a factorization's
        // side on offer ([`crate::linalg::parallel::take_offer`]).
        let pause = crate::linalg::parallel::take_offer;
        let entries = problem.upper();
        pause();
        let dim = problem.dim();
        let n1 = problem.n - 1;
        let lambda_at = entries
            .iter()
            .map(|&(r, c, _, _)| {
                if r >= n1 && c >= n1 {
                    let (i, a) = ((r - n1) / 3, (r - n1) % 3);
                    let (j, b) = ((c - n1) / 3, (c - n1) % 3);
                    (i == j).then_some((i, a, b))
                } else {
                    None
                }
            })
            .collect();
        let mut diagonal = vec![usize::MAX; dim];
        for (k, &(r, c, _, _)) in entries.iter().enumerate() {
            if r == c {
                diagonal[r] = k;
            }
        }
        pause();
        // S's rows in their elimination order: `order[new] = row`.
        let order = problem.row_order();
        // Assembled in that elimination order, so that no factorization copies it into that
        // order. Supernodal: S's 3x3 blocks per pose make dense blocks pay off where faer's flop
        // rule chose simplicial; whole process, 11 interleaved pairs new/old, 0.62 (tinyGrid3D)
        // to 0.94 (cubicle) on every public 3D file. Q's entries ([`Problem3::upper`]) are its
        // pairs' dense 4x4 blocks (3 rows for the anchor, without a translation), pair by pair
        // and row by row, so the blocked assembly (pose u's coordinates its rows in their order,
        // one sort of the pairs instead of one of the entries) takes them in the same order and
        // gives the same matrix, entry for entry, as the entrywise one would.
        let layout = Layout::Supernodal;
        let sizes: Vec<usize> = (0..problem.n)
            .map(|u| if u == problem.anchor { 3 } else { 4 })
            .collect();
        let assembly = Assembly::<f64>::blocked(
            &sizes,
            &problem.pairs,
            &problem.pose_order(),
            layout.stored_side(),
        );
        pause();
        let mut factor = SparseFactor::analyze_in_order(
            assembly.matrix.symbolic(),
            layout.stored_side(),
            layout,
        );
        pause();
        factor.prepare_factor_split(SPLIT_FACTOR_MIN_WORK);
        let mut row_counts = vec![0; dim];
        for (&count, &row) in factor.row_counts().iter().zip(&order) {
            row_counts[row] = count;
        }
        Certifier3 {
            entries,
            lambda_at,
            diagonal,
            assembly,
            factor,
            row_counts,
            values: Vec::new(),
            max_degree: problem.max_degree,
            shifts: ShiftMemory::default(),
            factorizations: 0,
            last_llt: None,
        }
    }

    fn lambda(&self, k: usize, lambda: &[[[f64; 3]; 3]]) -> f64 {
        self.lambda_at[k].map_or(0.0, |(i, a, b)| lambda[i][a][b])
    }

    /// Whether `k` is a rotation row (those P shifts).
    fn shifted(&self, k: usize, n1: usize) -> bool {
        k >= n1
    }

    /// D_k = 2^{−⌊log₂|S_kk + η P_kk|/2⌋}; `None` if a diagonal entry is not finite or (unless
    /// `absolute`) not positive.
    fn scaling(
        &self,
        lambda: &[[[f64; 3]; 3]],
        eta: f64,
        n1: usize,
        absolute: bool,
    ) -> Option<Vec<f64>> {
        let dim = self.diagonal.len();
        let mut scale = vec![0.0; dim];
        for k in 0..dim {
            let e = self.diagonal[k];
            let mut v = self.entries[e].2 - self.lambda(e, lambda);
            if self.shifted(k, n1) {
                v += eta;
            }
            let a = if absolute {
                v.abs().max(f64::MIN_POSITIVE)
            } else {
                v
            };
            if !(a > 0.0 && a.is_finite()) {
                return None;
            }
            scale[k] = power_of_two_scale(a);
        }
        Some(scale)
    }

    /// ‖D(Q_stored − Q)D‖₂ ≤ its ∞-norm: each stored entry sums at most 6·deg contributions of a
    /// few roundings each, so |ΔQ| ≤ γ_{6deg+12} Σ_e|Q_e| entrywise (doubled for the sums).
    fn assembly_error(&self, scale: &[f64]) -> f64 {
        let mut rows = vec![0.0; scale.len()];
        for &(r, c, _, a) in &self.entries {
            let v = a * scale[r] * scale[c];
            rows[r] += v;
            if r != c {
                rows[c] += v;
            }
        }
        2.0 * gamma(6 * self.max_degree + 12) * rows.iter().fold(0.0f64, |m, &v| m.max(v))
    }

    /// The row sums of |D(S + ηP)D|: for the ladder's [`ldlt_error_floor`] (η = 0) and the
    /// shifted factorization's α.
    fn abs_row_sums(
        &self,
        lambda: &[[[f64; 3]; 3]],
        scale: &[f64],
        eta: f64,
        n1: usize,
    ) -> Vec<f64> {
        let mut rows = vec![0.0; scale.len()];
        for (k, &(r, c, q, _)) in self.entries.iter().enumerate() {
            let mut v = (q - self.lambda(k, lambda)).abs();
            if r == c && self.shifted(r, n1) {
                v += eta.abs();
            }
            let v = v * scale[r] * scale[c];
            rows[r] += v;
            if r != c {
                rows[c] += v;
            }
        }
        rows
    }

    /// Fills D(S + ηP)D − μI and returns the ∞-norm bound of the rounding of forming it.
    fn fill(
        &mut self,
        lambda: &[[[f64; 3]; 3]],
        scale: &[f64],
        eta: f64,
        mu: f64,
        n1: usize,
    ) -> f64 {
        let mut rows = vec![0.0; scale.len()];
        self.values.clear();
        for k in 0..self.entries.len() {
            let (r, c, q, _) = self.entries[k];
            let l = self.lambda(k, lambda);
            let s = scale[r] * scale[c];
            let mut v = q - l;
            let mut mag = q.abs() + l.abs();
            if r == c && self.shifted(r, n1) {
                v += eta;
                mag += eta.abs();
            }
            let e = 4.0 * U * (mag * s + mu);
            rows[r] += e;
            if r != c {
                rows[c] += e;
            }
            self.values.push(if r == c { v * s - mu } else { v * s });
        }
        self.assembly.fill(&self.values);
        rows.iter().fold(0.0f64, |m, &v| m.max(v))
    }

    /// The inertia of D S D − μI: `Some((negative pivots, error))`.
    fn inertia_at(
        &mut self,
        lambda: &[[[f64; 3]; 3]],
        scale: &[f64],
        mu: f64,
        n1: usize,
    ) -> Option<(usize, f64)> {
        let (negative, form) = self.ldlt_shifted(lambda, scale, mu, n1)?;
        Some((negative, self.factor.ldlt_backward_error() + form))
    }

    /// The LDLᵀ of [`Self::inertia_at`]: `Some((negative pivots, the rounding of forming
    /// D S D − μI))`.
    fn ldlt_shifted(
        &mut self,
        lambda: &[[[f64; 3]; 3]],
        scale: &[f64],
        mu: f64,
        n1: usize,
    ) -> Option<(usize, f64)> {
        let form = self.fill(lambda, scale, 0.0, mu, n1);
        self.factorizations += 1;
        self.factor.ldlt(self.assembly.matrix.as_ref()).ok()?;
        Some((self.factor.inertia_below(0.0), form))
    }

    /// θ ≤ λ_{k+1}(D S D) by the inertia of D S D − μI: the planar certificate's shift ladder
    /// ([`isolate`]) with k in place of 1.
    fn gap(
        &mut self,
        lambda: &[[[f64; 3]; 3]],
        scale: &[f64],
        k: usize,
        n1: usize,
    ) -> Option<(f64, usize)> {
        let assembly = self.assembly_error(scale);
        let start = self.shifts.start(k, n1 + 1);
        let floor = ldlt_error_floor(&self.row_counts, &self.abs_row_sums(lambda, scale, 0.0, n1));
        let ladder = isolate(k, start, assembly, floor, |mu| {
            Some(self.inertia_at(lambda, scale, mu, n1))
        });
        self.shifts.remember(&ladder);
        match ladder {
            Ladder::Found {
                theta, negative, ..
            } => Some((theta, negative)),
            Ladder::Hidden { mu, .. } => self.measured_gap(lambda, scale, mu, assembly, k, n1),
            Ladder::Failed => None,
        }
    }

    /// [`Self::gap`] at a shift where the ladder found at most k negative pivots but the
    /// a-priori error bound hid the gap: the same LDLᴴ again, its error measured instead
    /// ([`SparseFactor::ldlt_residual_bound`]), as the planar certificate does.
    fn measured_gap(
        &mut self,
        lambda: &[[[f64; 3]; 3]],
        scale: &[f64],
        mu: f64,
        assembly: f64,
        k: usize,
        n1: usize,
    ) -> Option<(f64, usize)> {
        let (negative, form) = self.ldlt_shifted(lambda, scale, mu, n1)?;
        if negative > k {
            return None;
        }
        let a = self.assembly.matrix.as_ref();
        let theta = measured_theta(mu, form + assembly, |chunk| {
            self.factor.ldlt_residual_bound(a, chunk)
        })
        .ok()?;
        self.shifts.remember_shift(mu);
        Some((theta, negative))
    }

    /// Takes the values of a factor that is no longer needed (the Newton descent's, in
    /// [`super::local::Local3::room`]) as the room of this one's ([`SparseFactor::reuse`]): their
    /// pages are mapped already.
    pub fn reuse(&mut self, room: Vec<f64>) {
        self.factor.reuse(room);
    }

    /// Proves S + ηP ⪰ 0 at the multipliers of `x` for the smallest η it finds ≤ `eta_max`
    /// (deflating the k = x.p columns of x), else by the shifted factorization. `None` if no
    /// η ≤ `eta_max` is proven.
    pub fn certify(
        &mut self,
        problem: &Problem3,
        x: &Point3,
        lambda: &[[[f64; 3]; 3]],
        eta_max: f64,
    ) -> Option<Bound3> {
        let deflated = self.certify_deflated(problem, x, lambda, eta_max);
        if deflated.is_some() {
            return deflated;
        }
        self.certify_cholesky(problem, lambda, eta_max)
    }

    /// The deflated proof (module docs, 1-3).
    pub fn certify_deflated(
        &mut self,
        problem: &Problem3,
        x: &Point3,
        lambda: &[[[f64; 3]; 3]],
        eta_max: f64,
    ) -> Option<Bound3> {
        let n1 = problem.n - 1;
        let k = x.p;
        let scale = self.scaling(lambda, 0.0, n1, true)?;
        let (theta, negative) = self.gap(lambda, scale.as_slice(), k, n1)?;
        if negative == 0 {
            // D S D ⪰ θ I: S ≻ 0 outright.
            return Some(Bound3 {
                eta: 0.0,
                lower_bound: dual_value(lambda, 0.0),
                gap: Some(theta),
                deflated: Some(0),
            });
        }
        let parts = Rayleigh3::new(problem, x, lambda, &scale);
        let rotation_scale = scale[n1..].iter().fold(0.0f64, |m, d| m.max(d * d));
        let eta = parts.smallest_eta(theta, rotation_scale, eta_max)?;
        Some(Bound3 {
            eta,
            lower_bound: dual_value(lambda, eta),
            gap: Some(theta),
            deflated: Some(k),
        })
    }

    /// LLᵀ of D(S + ηP)D − αI: η = eta_max first, then down by factors of 16 while it
    /// succeeds and a log-scale bisection between the last success and the first failure (the
    /// smallest η proven to within a factor 1.2), or, where eta_max fails, up by factors of 16
    /// (four times) for a weaker bound.
    pub fn certify_cholesky(
        &mut self,
        problem: &Problem3,
        lambda: &[[[f64; 3]; 3]],
        eta_max: f64,
    ) -> Option<Bound3> {
        if !(eta_max.is_finite() && eta_max > 0.0) {
            return None;
        }
        self.last_llt = None;
        let mut hi = eta_max;
        let mut proven = self.try_eta(problem, lambda, hi, 0.0);
        if !proven {
            for _ in 0..4 {
                hi *= 16.0;
                if self.try_eta(problem, lambda, hi, 0.0) {
                    proven = true;
                    break;
                }
            }
        }
        if !proven {
            return None;
        }
        let mut lo = None;
        for _ in 0..12 {
            let eta = hi / 16.0;
            if self.try_eta(problem, lambda, eta, 0.0) {
                hi = eta;
            } else {
                lo = Some(eta);
                break;
            }
        }
        if let Some(mut lo) = lo {
            for _ in 0..4 {
                let mid = (lo * hi).sqrt();
                if self.try_eta(problem, lambda, mid, 0.0) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
        }
        if !self.measured_llt(problem, lambda, hi) {
            return None;
        }
        Some(Bound3 {
            eta: hi,
            lower_bound: dual_value(lambda, hi),
            gap: None,
            deflated: None,
        })
    }

    /// Whether the LLᵀ that succeeded at η ([`Self::try_eta`], factored again unless it was the
    /// last) holds without the backward-error model α rests on: its residual, measured
    /// ([`SparseFactor::llt_residual_bound`]), within the allowance α gave the factorization's
    /// rounding, else once more with twice what it showed ([`within_allowance`]), as in the
    /// planar certificate ([`crate::certify::SparseCertifier`]).
    fn measured_llt(&mut self, problem: &Problem3, lambda: &[[[f64; 3]; 3]], eta: f64) -> bool {
        let last = self.last_llt.filter(|&(e, _)| e == eta.to_bits());
        within_allowance(
            self,
            last.map(|(_, allowance)| allowance),
            |c, chunk| {
                c.factor
                    .llt_residual_bound(c.assembly.matrix.as_ref(), chunk)
            },
            |c, rounding| {
                c.try_eta(problem, lambda, eta, rounding)
                    .then(|| c.last_llt.map(|(_, a)| a))
                    .flatten()
            },
        )
    }

    fn try_eta(
        &mut self,
        problem: &Problem3,
        lambda: &[[[f64; 3]; 3]],
        eta: f64,
        rounding: f64,
    ) -> bool {
        let n1 = problem.n - 1;
        let Some(scale) = self.scaling(lambda, eta, n1, false) else {
            return false;
        };
        let dim = scale.len();
        // α: the backward error of LLᵀ (dim·u·‖B‖_∞), the assembly's and the forming's.
        let norm = self
            .abs_row_sums(lambda, &scale, eta, n1)
            .iter()
            .fold(0.0f64, |m, &v| m.max(v));
        let model = (dim as f64 * U * norm).max(rounding);
        let alpha0 = model + self.assembly_error(&scale);
        let form = self.fill(lambda, &scale, eta, 0.0, n1);
        let alpha = (alpha0 + form) * (1.0 + 8.0 * U);
        // Subtract α on the diagonal.
        for k in 0..self.entries.len() {
            if self.entries[k].0 == self.entries[k].1 {
                self.values[k] -= alpha;
            }
        }
        self.assembly.fill(&self.values);
        self.factorizations += 1;
        let proven = self.factor.llt(self.assembly.matrix.as_ref()).is_ok();
        self.last_llt = proven.then_some((eta.to_bits(), model));
        proven
    }

    /// The number of eigenvalues of S below `threshold` (inertia of S − threshold·I).
    pub fn count_below(
        &mut self,
        problem: &Problem3,
        lambda: &[[[f64; 3]; 3]],
        threshold: f64,
    ) -> Option<usize> {
        let ones = vec![1.0; self.diagonal.len()];
        self.fill(lambda, &ones, 0.0, threshold, problem.n - 1);
        self.factor.ldlt(self.assembly.matrix.as_ref()).ok()?;
        Some(self.factor.inertia_below(0.0))
    }

    /// S (upper triangle) at Λ, and a direction v of its most negative LDLᵀ pivot with
    /// vᵀSv/‖v‖² (a direction of negative curvature when negative).
    pub fn negative_direction(
        &mut self,
        problem: &Problem3,
        lambda: &[[[f64; 3]; 3]],
    ) -> Option<(Vec<f64>, f64)> {
        let dim = self.diagonal.len();
        let n1 = problem.n - 1;
        let scale = self.scaling(lambda, 0.0, n1, true)?;
        self.fill(lambda, &scale, 0.0, 0.0, n1);
        let pattern: Vec<(usize, usize)> = self.entries.iter().map(|e| (e.0, e.1)).collect();
        let mut assembly = Assembly::<f64>::new(dim, &pattern);
        assembly.fill(&self.values);
        let order = problem.row_order();
        let mut factor =
            SparseFactor::analyze_ordered(assembly.matrix.symbolic(), &order, Layout::Simplicial);
        factor.ldlt(assembly.matrix.as_ref()).ok()?;
        let pivots = factor.ldlt_pivots();
        let (k, _) = pivots
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))?;
        let mut v = factor.pivot_direction(k)?;
        // Undo the equilibration: v is a direction for D S D; D v is one for S.
        for (vk, d) in v.iter_mut().zip(&scale) {
            *vk *= d;
        }
        // Rayleigh quotient of S at v.
        let mut sv = vec![0.0; dim];
        for (idx, &(r, c, q, _)) in self.entries.iter().enumerate() {
            let s = q - self.lambda(idx, lambda);
            sv[r] += s * v[c];
            if r != c {
                sv[c] += s * v[r];
            }
        }
        let num: f64 = sv.iter().zip(&v).map(|(a, b)| a * b).sum();
        let den: f64 = v.iter().map(|a| a * a).sum();
        let norm = den.sqrt();
        for vk in v.iter_mut() {
            *vk /= norm;
        }
        Some((v, num / den))
    }
}

/// Σ_i tr(Λ_i − ηI) = Σ tr Λ_i − 3nη, less the rounding of the sum.
pub fn dual_value(lambda: &[[[f64; 3]; 3]], eta: f64) -> f64 {
    let n = lambda.len();
    let (mut sum, mut abs) = (0.0, 0.0);
    for l in lambda {
        for a in 0..3 {
            sum += l[a][a];
            abs += l[a][a].abs();
        }
    }
    let three_n = 3.0 * n as f64;
    sum - three_n * eta - gamma(3 * n + 2) * (abs + three_n * eta.abs())
}

/// The k×k pieces of K(η) = ρ(F + ηY) − (B₀ + η(C + Cᵀ) + η²E) with their error bounds:
/// F = XᵀSX, Y = XᵀPX, B₀ = Σ_r D_r² R_rᵀR_r, C = Σ_{rot r} D_r² R_rᵀX_r, E = Σ_{rot r} D_r² X_rᵀX_r,
/// R = SX (rows R_r).
struct Rayleigh3 {
    k: usize,
    f: Vec<f64>,
    ef: Vec<f64>,
    y: Vec<f64>,
    ey: Vec<f64>,
    b0: Vec<f64>,
    eb0: Vec<f64>,
    c: Vec<f64>,
    ec: Vec<f64>,
    e: Vec<f64>,
    ee: Vec<f64>,
}

impl Rayleigh3 {
    fn new(problem: &Problem3, x: &Point3, lambda: &[[[f64; 3]; 3]], scale: &[f64]) -> Self {
        let k = x.p;
        let n1 = problem.n - 1;
        let ev = problem.evaluate(x);
        let dim = problem.dim();
        // R = QX − ΛX on the rotation rows, with error bounds.
        let mut r = ev.qx.clone();
        let mut er = ev.qx_error.clone();
        for i in 0..problem.n {
            for a in 0..3 {
                let ra = problem.rotation_row(i, a);
                for c in 0..k {
                    let mut s = 0.0;
                    let mut abs = 0.0;
                    for b in 0..3 {
                        let v = lambda[i][a][b] * x.x[problem.rotation_row(i, b) * k + c];
                        s += v;
                        abs += v.abs();
                    }
                    r[ra * k + c] -= s;
                    er[ra * k + c] += gamma(5) * (abs + r[ra * k + c].abs() + s.abs());
                }
            }
        }
        let kk = k * k;
        let (mut f, mut ef) = (ev.xqx.clone(), ev.xqx_error.clone());
        let (mut y, mut yabs) = (vec![0.0; kk], vec![0.0; kk]);
        let (mut b0, mut eb0, mut b0abs) = (vec![0.0; kk], vec![0.0; kk], vec![0.0; kk]);
        let (mut c, mut ec, mut cabs) = (vec![0.0; kk], vec![0.0; kk], vec![0.0; kk]);
        let (mut e, mut eabs) = (vec![0.0; kk], vec![0.0; kk]);
        // F −= Σ_i X_iᵀ Λ_i X_i.
        let mut lx_abs = vec![0.0; kk];
        for i in 0..problem.n {
            let row = |a: usize| x.row(problem.rotation_row(i, a));
            for c1 in 0..k {
                for c2 in 0..k {
                    let mut s = 0.0;
                    let mut abs = 0.0;
                    for a in 0..3 {
                        for b in 0..3 {
                            let v = row(a)[c1] * lambda[i][a][b] * row(b)[c2];
                            s += v;
                            abs += v.abs();
                        }
                    }
                    f[c1 * k + c2] -= s;
                    lx_abs[c1 * k + c2] += abs;
                }
            }
        }
        for q in 0..kk {
            ef[q] += gamma(3 * problem.n + 12) * (lx_abs[q] + f[q].abs() + ev.xqx[q].abs());
        }
        for rr in 0..dim {
            let d2 = scale[rr] * scale[rr];
            let xr = x.row(rr);
            let (rv, re) = (&r[rr * k..(rr + 1) * k], &er[rr * k..(rr + 1) * k]);
            for c1 in 0..k {
                for c2 in 0..k {
                    let q = c1 * k + c2;
                    let v = d2 * rv[c1] * rv[c2];
                    b0[q] += v;
                    b0abs[q] += v.abs();
                    eb0[q] +=
                        d2 * (rv[c1].abs() * re[c2] + re[c1] * rv[c2].abs() + re[c1] * re[c2]);
                    if rr >= n1 {
                        let v = d2 * rv[c1] * xr[c2];
                        c[q] += v;
                        cabs[q] += v.abs();
                        ec[q] += d2 * re[c1] * xr[c2].abs();
                        let v = d2 * xr[c1] * xr[c2];
                        e[q] += v;
                        eabs[q] += v.abs();
                        let v = xr[c1] * xr[c2];
                        y[q] += v;
                        yabs[q] += v.abs();
                    }
                }
            }
        }
        let g = gamma(dim + 8);
        for q in 0..kk {
            eb0[q] = (eb0[q] + g * b0abs[q]) * (1.0 + 4.0 * U);
            ec[q] = (ec[q] + g * cabs[q]) * (1.0 + 4.0 * U);
        }
        let ee = eabs.iter().map(|a| g * a).collect();
        let ey = yabs.iter().map(|a| g * a).collect();
        Rayleigh3 {
            k,
            f,
            ef,
            y,
            ey,
            b0,
            eb0,
            c,
            ec,
            e,
            ee,
        }
    }

    /// Whether K(η) ≻ 0 is proven with ρ = θ + min(η, 0)·max D²_rot.
    fn check(&self, theta: f64, rotation_scale: f64, eta: f64) -> bool {
        let k = self.k;
        let rho = theta + eta.min(0.0) * rotation_scale * (1.0 + 4.0 * U);
        if rho.is_nan() || rho <= 0.0 {
            return false;
        }
        let mut kmat = vec![0.0; k * k];
        let mut err2 = 0.0;
        let mut absum = 0.0;
        for a in 0..k {
            for b in 0..k {
                let q = a * k + b;
                let qt = b * k + a;
                let v = rho * (self.f[q] + eta * self.y[q])
                    - (self.b0[q] + eta * (self.c[q] + self.c[qt]) + eta * eta * self.e[q]);
                let mag = rho * (self.f[q].abs() + eta.abs() * self.y[q].abs())
                    + self.b0[q].abs()
                    + eta.abs() * (self.c[q].abs() + self.c[qt].abs())
                    + eta * eta * self.e[q].abs();
                let err = rho * (self.ef[q] + eta.abs() * self.ey[q])
                    + self.eb0[q]
                    + eta.abs() * (self.ec[q] + self.ec[qt])
                    + eta * eta * self.ee[q]
                    + gamma(8) * mag;
                err2 += err * err;
                absum += v.abs();
                kmat[q] = v;
            }
        }
        // Symmetrize (K is symmetric in exact arithmetic; the difference is within the error).
        for a in 0..k {
            for b in a + 1..k {
                let s = 0.5 * (kmat[a * k + b] + kmat[b * k + a]);
                kmat[a * k + b] = s;
                kmat[b * k + a] = s;
            }
        }
        let shift = (err2.sqrt() + 8.0 * (k as f64 + 2.0) * U * absum) * (1.0 + 8.0 * U);
        for a in 0..k {
            kmat[a * k + a] -= shift;
        }
        cholesky_positive(&kmat, k)
    }

    /// The smallest η ≤ `eta_max` found at which [`Self::check`] holds.
    fn smallest_eta(&self, theta: f64, rotation_scale: f64, eta_max: f64) -> Option<f64> {
        let k = self.k;
        // Start where θ(λ_min(F) + η λ_min(Y)) reaches ‖B₀‖ (estimates from the diagonals).
        let fmin = (0..k)
            .map(|a| self.f[a * k + a])
            .fold(f64::INFINITY, f64::min);
        let ymin = (0..k)
            .map(|a| self.y[a * k + a])
            .fold(f64::INFINITY, f64::min);
        let bmax: f64 = (0..k).map(|a| self.b0[a * k + a]).sum();
        if ymin.is_nan() || ymin <= 0.0 {
            return None;
        }
        let floor = -0.25 * theta / (rotation_scale * (1.0 + 4.0 * U));
        let mut eta = ((bmax / theta - fmin) / ymin).max(floor);
        let mut step = (1e-6 * eta.abs()).max(1e-300);
        for _ in 0..200 {
            if eta.is_nan() || eta > eta_max {
                return None;
            }
            if self.check(theta, rotation_scale, eta) {
                return Some(eta);
            }
            eta += step;
            step *= 1.5;
        }
        None
    }
}

/// Whether the Cholesky factorization of a small symmetric matrix (row-major) has only
/// positive pivots.
fn cholesky_positive(m: &[f64], k: usize) -> bool {
    let mut l = vec![0.0; k * k];
    for j in 0..k {
        let d = m[j * k + j] - (0..j).map(|s| l[j * k + s] * l[j * k + s]).sum::<f64>();
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let djj = d.sqrt();
        l[j * k + j] = djj;
        for i in j + 1..k {
            l[i * k + j] =
                (m[i * k + j] - (0..j).map(|s| l[i * k + s] * l[j * k + s]).sum::<f64>()) / djj;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The certificate's blocked assembly against the entrywise one ([`Assembly::permuted`] of
    /// Q's entries, [`Problem3::upper`], in the rows' elimination order): the same pattern and,
    /// filled with the same values, the same matrix bit for bit, wherever the anchor is (its
    /// block has no translation row).
    #[test]
    fn the_blocked_assembly_is_the_entrywise_one() {
        for (seed, anchor) in [(1, 0), (2, 13), (3, 26)] {
            let problem = crate::se3::grid_problem(seed, anchor, 0.05);
            let mut certifier = Certifier3::new(&problem);
            let entries = problem.upper();
            let pattern: Vec<(usize, usize)> = entries.iter().map(|e| (e.0, e.1)).collect();
            let order = problem.row_order();
            let side = Layout::Supernodal.stored_side();
            let mut entrywise = Assembly::<f64>::permuted(problem.dim(), &pattern, &order, side);
            let blocked = certifier.assembly.matrix.symbolic();
            let by_entry = entrywise.matrix.symbolic();
            assert_eq!(blocked.col_ptr(), by_entry.col_ptr());
            assert_eq!(blocked.row_idx(), by_entry.row_idx());
            // Values that tell every entry apart.
            let values: Vec<f64> = (0..entries.len()).map(|k| 1.0 + k as f64 / 7.0).collect();
            entrywise.fill(&values);
            certifier.assembly.fill(&values);
            let bits = |m: &[f64]| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(certifier.assembly.matrix.val()),
                bits(entrywise.matrix.val())
            );
        }
    }
}
