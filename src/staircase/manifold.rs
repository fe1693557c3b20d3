//! The Riemannian geometry of the rank-p problem ([`crate::problem::rank_p`]) that the staircase
//! optimizes on: positions free, each rotation row a unit vector of ℂ^p (a product of spheres,
//! the complex Stiefel manifold St(1, p) per pose). An orthonormal tangent basis per row, the
//! Riemannian Hessian 2Bᵀ W̃(λ) B in that basis (Sec. 4.1, real form of eq. (16)), the
//! retraction, and the sparse Newton system built from them.

use crate::linalg::block_system::BlockSystem;
use crate::linalg::factor::NotFactorable;
use crate::problem::matrix::entry_pattern;
use crate::problem::rank_p::{Point, Problem, dot};
use faer::c64;

/// An orthonormal real basis of the tangent space at each row (as complex p-vectors):
/// positions: e_c and i·e_c (2p vectors, the same at every position row, stored once);
/// rotations y: 2p − 1 vectors orthogonal to y in ℝ^{2p} (the last 2p − 1 columns of the
/// Householder reflector that maps y to ±e_1). Coordinates row by row: a position row has 2p,
/// a rotation row 2p − 1 ([`TangentBasis::offsets`]).
pub struct TangentBasis {
    pub p: usize,
    /// The number of rows (positions, then rotations).
    rows: usize,
    /// The number of position rows.
    positions: usize,
    /// Every position row's basis: e_c and i·e_c, c = 0..p, p entries each.
    position_vectors: Vec<c64>,
    /// The rotation rows' basis vectors in order, 2p − 1 per row, p entries each (one
    /// allocation). Storing every row's, with the offsets, wrote 64 MB at every Newton step at
    /// rank 1 and 10⁶ poses, 16 MB now: with the allocator's thresholds (`cli::memory`), the
    /// solve's page faults fell by 6% and its peak memory by 107 MiB.
    rotation_vectors: Vec<c64>,
    pub dim: usize,
}

impl TangentBasis {
    pub fn new(problem: &Problem, x: &Point) -> Self {
        let p = x.p;
        let (rows, positions) = (problem.rows(), problem.positions());
        let mut position_vectors = Vec::with_capacity(2 * p * p);
        position_basis(p, &mut position_vectors);
        let mut rotation_vectors = Vec::with_capacity((rows - positions) * (2 * p - 1) * p);
        for k in positions..rows {
            sphere_basis(x.row(k), &mut rotation_vectors);
        }
        let dim = 2 * p * positions + (2 * p - 1) * (rows - positions);
        debug_assert_eq!((dim - 2 * p * positions) * p, rotation_vectors.len());
        TangentBasis {
            p,
            rows,
            positions,
            position_vectors,
            rotation_vectors,
            dim,
        }
    }

    /// The offsets of every basis of rank p (they depend on p alone): a position row has 2p
    /// coordinates (ℂᵖ as ℝ²ᵖ), a rotation row 2p − 1 (the tangent space of the unit sphere
    /// |r_i| = 1 in ℂᵖ).
    pub fn offsets(problem: &Problem, p: usize) -> Vec<usize> {
        let mut offsets = Vec::with_capacity(problem.rows() + 1);
        let mut off = 0;
        offsets.push(off);
        for k in 0..problem.rows() {
            off += if k < problem.positions() {
                2 * p
            } else {
                2 * p - 1
            };
            offsets.push(off);
        }
        offsets
    }

    /// The first coordinate of row k (k = rows: the dimension), as in [`Self::offsets`].
    pub fn offset(&self, k: usize) -> usize {
        let p = self.p;
        if k <= self.positions {
            2 * p * k
        } else {
            2 * p * self.positions + (2 * p - 1) * (k - self.positions)
        }
    }

    /// The number of coordinates of row k.
    pub fn len(&self, k: usize) -> usize {
        if k < self.positions {
            2 * self.p
        } else {
            2 * self.p - 1
        }
    }

    /// The s-th basis vector of row k.
    pub fn vector(&self, k: usize, s: usize) -> &[c64] {
        let p = self.p;
        if k < self.positions {
            &self.position_vectors[s * p..(s + 1) * p]
        } else {
            let start = ((k - self.positions) * (2 * p - 1) + s) * p;
            &self.rotation_vectors[start..start + p]
        }
    }

    /// Coordinates of a (2n−1)×p matrix's rows in the basis: Re⟨b, v⟩.
    pub fn coordinates(&self, v: &[c64]) -> Vec<f64> {
        let p = self.p;
        let mut out = vec![0.0; self.dim];
        for k in 0..self.rows {
            let row = &v[k * p..(k + 1) * p];
            let offset = self.offset(k);
            for s in 0..self.len(k) {
                out[offset + s] = dot(self.vector(k, s), row).re;
            }
        }
        out
    }

    /// The Euclidean norm of [`Self::coordinates`] of `v`, the same sum, without the vector.
    pub fn coordinates_norm(&self, v: &[c64]) -> f64 {
        let p = self.p;
        let mut sum = 0.0;
        for k in 0..self.rows {
            let row = &v[k * p..(k + 1) * p];
            for s in 0..self.len(k) {
                let c = dot(self.vector(k, s), row).re;
                sum += c * c;
            }
        }
        sum.sqrt()
    }

    /// The pattern of the Hessian in these coordinates (upper triangle), one entry per value
    /// [`TangentBasis::hessian_values`] produces, in the same order.
    pub fn hessian_pattern(&self, problem: &Problem) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        problem.matrix.for_each_upper(|k, l, _| {
            for s in 0..self.len(k) {
                for t in 0..self.len(l) {
                    let (a, b) = (self.offset(k) + s, self.offset(l) + t);
                    if a <= b {
                        out.push((a, b));
                    }
                }
            }
        });
        out
    }

    /// Values of H + μ·D, H = 2 Bᵀ W̃(λ) B, D = diag(2 W̃_kk) per coordinate (a scale-invariant
    /// Levenberg-Marquardt damping), in the order of [`TangentBasis::hessian_pattern`].
    pub fn hessian_values(
        &self,
        problem: &Problem,
        lambda: &[f64],
        mu: f64,
        mut out: impl FnMut(f64),
    ) {
        let positions = problem.positions();
        if self.p == 1 {
            return self.hessian_values_rank_one(problem, lambda, mu, out);
        }
        problem.matrix.for_each_upper(|k, l, w| {
            for s in 0..self.len(k) {
                let bs = self.vector(k, s);
                for t in 0..self.len(l) {
                    let (a, b) = (self.offset(k) + s, self.offset(l) + t);
                    if a > b {
                        continue;
                    }
                    let bt = self.vector(l, t);
                    let mut v = 2.0
                        * bs.iter()
                            .zip(bt)
                            .map(|(x, y)| (x.conj() * w * y).re)
                            .sum::<f64>();
                    if a == b {
                        if k >= positions {
                            v -= 2.0 * lambda[k - positions];
                        }
                        v += mu * 2.0 * w.re;
                    }
                    out(v);
                }
            }
        });
    }

    /// [`TangentBasis::hessian_values`] at rank 1, the staircase's usual rank, where each basis
    /// vector is one complex number: the same values in the same order and the same arithmetic
    /// (2·Re(b̄_s w b_t), the λ and damping terms on the diagonal), with the rows' vectors and
    /// offsets looked up once per entry of W̃ instead of once per value (on victoriaPark the
    /// general form took 0.6 ms per Newton step).
    fn hessian_values_rank_one(
        &self,
        problem: &Problem,
        lambda: &[f64],
        mu: f64,
        mut out: impl FnMut(f64),
    ) {
        let positions = problem.positions();
        let vectors = |k: usize| -> &[c64] {
            if k < positions {
                &self.position_vectors
            } else {
                std::slice::from_ref(&self.rotation_vectors[k - positions])
            }
        };
        problem.matrix.for_each_upper(|k, l, w| {
            let (bk, bl) = (vectors(k), vectors(l));
            let (ok, ol) = (self.offset(k), self.offset(l));
            for (s, &bs) in bk.iter().enumerate() {
                for (t, &bt) in bl.iter().enumerate() {
                    let (a, b) = (ok + s, ol + t);
                    if a > b {
                        continue;
                    }
                    // One term: the general form's sum over the p = 1 entries, as it sums it.
                    let mut v = 2.0 * std::iter::once((bs.conj() * w * bt).re).sum::<f64>();
                    if a == b {
                        if k >= positions {
                            v -= 2.0 * lambda[k - positions];
                        }
                        v += mu * 2.0 * w.re;
                    }
                    out(v);
                }
            }
        });
    }

    /// δᵀHδ for H = 2 Bᵀ W̃(λ) B (the undamped [`TangentBasis::hessian_values`]): 2 (v*W̃v −
    /// Σ_k λ_k ‖v_k‖²) over the rotation rows k, v = Bδ.
    pub fn hessian_form(&self, problem: &Problem, lambda: &[f64], delta: &[f64]) -> f64 {
        let p = self.p;
        let rows = self.rows;
        let mut v = vec![c64::new(0.0, 0.0); rows * p];
        for k in 0..rows {
            for s in 0..self.len(k) {
                let d = delta[self.offset(k) + s];
                for (vc, bc) in v[k * p..(k + 1) * p].iter_mut().zip(self.vector(k, s)) {
                    *vc += bc * d;
                }
            }
        }
        let row = |k: usize| &v[k * p..(k + 1) * p];
        let mut form = 0.0;
        problem.matrix.for_each_upper(|k, l, w| {
            let t: f64 = row(k)
                .iter()
                .zip(row(l))
                .map(|(a, b)| (a.conj() * w * b).re)
                .sum();
            form += if k == l { t } else { 2.0 * t };
        });
        let positions = problem.positions();
        for (k, l) in lambda.iter().enumerate() {
            form -= l * row(positions + k).iter().map(|a| a.norm_sqr()).sum::<f64>();
        }
        2.0 * form
    }

    /// δᵀDδ for the damping weights D = diag(2 W̃_kk) per coordinate, summed coordinate by
    /// coordinate (a vector of D took 23 MiB at 10⁶ poses through the Newton steps).
    pub fn damped_square(&self, problem: &Problem, delta: &[f64]) -> f64 {
        let mut sum = 0.0;
        problem.matrix.for_each_upper(|k, l, w| {
            if k == l {
                let d = 2.0 * w.re;
                for s in 0..self.len(k) {
                    let b = delta[self.offset(k) + s];
                    sum += d * b * b;
                }
            }
        });
        sum
    }

    /// The point moved along tangent coordinates δ: positions X_k + Bδ, rotations
    /// (Y_a + Bδ)/‖Y_a + Bδ‖ (the projection retraction, second order, so Newton keeps its
    /// quadratic convergence). Rows from `positions` on are rotations.
    pub fn retract(&self, x: &Point, delta: &[f64], positions: usize) -> Point {
        let mut y = x.clone();
        for k in 0..self.rows {
            let row = y.row_mut(k);
            let lo = self.offset(k);
            for (s, &d) in delta[lo..lo + self.len(k)].iter().enumerate() {
                for (z, b) in row.iter_mut().zip(self.vector(k, s)) {
                    *z += b * d;
                }
            }
            if k >= positions {
                let norm = row.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
                for z in row.iter_mut() {
                    *z /= norm;
                }
            }
        }
        y
    }
}

/// Appends e_c and i·e_c, c = 0..p (2p vectors of ℂ^p).
fn position_basis(p: usize, out: &mut Vec<c64>) {
    let start = out.len();
    out.resize(start + 2 * p * p, c64::new(0.0, 0.0));
    for c in 0..p {
        out[start + (2 * c) * p + c] = c64::new(1.0, 0.0);
        out[start + (2 * c + 1) * p + c] = c64::new(0.0, 1.0);
    }
}

/// Appends 2p − 1 orthonormal vectors of ℝ^{2p} ≅ ℂ^p orthogonal to the unit vector y.
fn sphere_basis(y: &[c64], out: &mut Vec<c64>) {
    let p = y.len();
    if p == 1 {
        // i·y: the rotation's tangent e^{iθ} → i e^{iθ}.
        out.push(c64::new(-y[0].im, y[0].re));
        return;
    }
    // Real vector v = (Re y_0, Im y_0, ...); Householder H = I − 2uuᵀ/‖u‖², u = v + sign(v_0) e_0,
    // maps v to −sign(v_0) e_0; columns 1..2p of H span v⊥.
    let m = 2 * p;
    let v: Vec<f64> = y.iter().flat_map(|z| [z.re, z.im]).collect();
    let sign = if v[0] >= 0.0 { 1.0 } else { -1.0 };
    let mut u = v.clone();
    u[0] += sign;
    let uu: f64 = u.iter().map(|a| a * a).sum();
    let h =
        |row: usize, col: usize| (if row == col { 1.0 } else { 0.0 }) - 2.0 * u[row] * u[col] / uu;
    for col in 1..m {
        for c in 0..p {
            out.push(c64::new(h(2 * c, col), h(2 * c + 1, col)));
        }
    }
}

/// The multiply-adds from which the Newton systems' LLᵀ is split between two cores where their
/// factor is supernodal ([`crate::linalg::tree_factor`]). Whole process, split/not, 21
/// interleaved pairs: M3500 (7.5·10⁶) 0.85, M3500c 0.86, city10000 (9.3·10⁷) 0.89,
/// cityTrees10000 (1.1·10⁷) 0.94, manhattan (7.5·10⁶) 0.95; below it ais2klinik (4.0·10⁶) 1.01
/// (victoriaPark, unchanged, 0.98-1.03 in the same runs). Each LLᵀ of cityTrees10000 in 1.3-1.4
/// ms instead of 2.4.
const SPLIT_FACTOR_MIN_WORK: f64 = 5e6;

/// The Newton system's sparse matrix for a fixed rank and pattern.
pub struct NewtonSystem {
    /// H + μD in the factor's elimination order (lower triangle) and its factorization, analyzed
    /// once for the pattern (shared by every iterate of a rank).
    system: BlockSystem,
}

impl NewtonSystem {
    /// The system of every basis of rank p (its pattern depends on p alone).
    pub fn new(problem: &Problem, p: usize) -> Self {
        Self::announcing(problem, p, |_, _| ())
    }

    /// [`NewtonSystem::new`], telling `counted` the dimension and the factor's number of values
    /// once its analysis knows them ([`BlockSystem::new`]).
    pub fn announcing(problem: &Problem, p: usize, counted: impl FnOnce(usize, usize)) -> Self {
        // The entries of [`TangentBasis::hessian_pattern`] come in blocks, one per entry of W̃'s
        // upper triangle: the coordinates of its row by those of its column. Rows in the
        // problem's fill-reducing order, each row's coordinates together.
        let offsets = TangentBasis::offsets(problem, p);
        let sizes: Vec<usize> = offsets.windows(2).map(|w| w[1] - w[0]).collect();
        let blocks = entry_pattern(&problem.matrix.upper);
        let row_order = problem.row_order();
        // Supernodal, assembled directly in its order and in the triangle its factorizations
        // read, and factored by our own code ([`SparseFactor::prepare_own_factorization`]: split
        // between the cores from SPLIT_FACTOR_MIN_WORK, else on one, the narrow supernodes by
        // plain loops). With faer's kernels for every supernode the sparser systems were faster
        // simplicial (faer's up-looking LLᵀ, chosen by a flop ratio below 12: ais2klinik, CSAIL,
        // MIT, the kitti files, victoriaPark, intel); against that, whole process, 11-15
        // interleaved runs: ais2klinik 0.85, intel 0.88-0.96, victoriaPark 0.90-0.97, FRH 0.94,
        // ring 0.96, kitti_00 and kitti_02 0.975, MIT 0.98-1.01, CSAIL 1.01-1.03. Fundamental
        // supernodes (no relaxation: the fewest stored zeros) were slower with these loops too:
        // 1.06 (MIT) to 1.41 (M3500). At every size: at 10⁶ poses (3·10⁶ rows) the split's
        // working memory (a 32-bit map of the rows per side, side 1's room for its updates of the
        // top set, the lists of updates) once took the peak over 2 GiB (2057-2088 MiB against
        // 2015-2022 unsplit); with the 32-bit indices of [`BlockSystem`] the split runs peaked at
        // 1892-1953 MiB and took 11.6-12.5 s (six runs) against 1872-1910 MiB and 14.4-15.1 s
        // unsplit (five), and the whole tool at 1908-1938 MiB and 12.0-13.7 s in six more.
        let system = BlockSystem::new(&sizes, &blocks, &row_order, SPLIT_FACTOR_MIN_WORK, counted);
        NewtonSystem { system }
    }

    /// Rewrites the matrix to H + μD at the point whose basis and multipliers are given.
    pub fn update(&mut self, problem: &Problem, basis: &TangentBasis, lambda: &[f64], mu: f64) {
        self.system
            .fill_with(|fill| basis.hessian_values(problem, lambda, mu, |v| fill.push(v)));
    }

    /// Numeric LLᵀ of the last [`NewtonSystem::update`]; `Err` if H + μD is not numerically
    /// positive definite. On large systems the steps' freed vectors go back to the system first:
    /// the Newton steps hold the solve's peak of memory ([`crate::linalg::heap::release_for`]).
    pub fn factorize(&mut self) -> Result<(), NotFactorable> {
        crate::linalg::heap::release_for(self.dim());
        self.system.llt()
    }

    /// δ with (H + μD) δ = b, b's coordinate k given by `b(k)`, by the last successful
    /// [`NewtonSystem::factorize`]. b is gathered straight into the factor's order and δ
    /// scattered out of it, so that between two solves the system holds no vector (at 10⁶ poses
    /// a kept right-hand side and its permuted copy were 46 MiB at the Newton steps' peak).
    pub fn solve(&mut self, b: impl Fn(usize) -> f64) -> Vec<f64> {
        self.system.solve(b)
    }

    /// The system's dimension (the tangent space's).
    pub fn dim(&self) -> usize {
        self.system.dim()
    }

    /// The multiply-adds of one factorization.
    pub fn multiply_adds(&self) -> f64 {
        self.system.multiply_adds()
    }

    /// The number of values of the numeric factor.
    pub fn values_len(&self) -> usize {
        self.system.values_len()
    }

    /// Whether its factorizations are split between the cores.
    pub fn splits_factorizations(&self) -> bool {
        self.system.splits_factorizations()
    }

    /// The room of the first factorization's values ([`BlockSystem::reuse`]).
    pub fn reuse(&mut self, values: Vec<f64>) {
        self.system.reuse(values)
    }

    /// The numeric factor's values, handed over, the factor released.
    pub fn take_values(&mut self) -> Vec<f64> {
        self.system.take_values()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, Pose2, PoseGraph, SymMat3};
    use crate::problem::weights::{Weights, edge_weights};

    /// A noisy square with a diagonal.
    fn square() -> Problem {
        let edge = |i, j, x, y, t| Edge {
            i,
            j,
            measurement: Pose2::new(x, y, t),
            noise: SymMat3::IDENTITY,
        };
        let edges = vec![
            edge(0, 1, 1.0, 0.1, 1.5),
            edge(1, 2, 1.1, -0.1, 1.6),
            edge(2, 3, 0.9, 0.0, 1.5),
            edge(3, 0, 1.0, 0.2, 1.7),
            edge(0, 2, 1.4, 1.5, 3.0),
        ];
        let mut g = PoseGraph::with_edges(vec![Pose2::IDENTITY; 4], edges);
        g.initialize_spanning_tree();
        Problem::new(&g, &edge_weights(&g, Weights::Isotropic).unwrap())
    }

    /// A rank-p point of `problem`: positions and unit rotation rows from a fixed sequence.
    fn point(problem: &Problem, p: usize) -> Point {
        let rows = problem.rows();
        let mut x: Vec<c64> = (0..rows * p)
            .map(|k| c64::new((k as f64 * 0.7).sin(), (k as f64 * 1.3).cos()))
            .collect();
        for k in problem.positions()..rows {
            let row = &mut x[k * p..(k + 1) * p];
            let norm = row.iter().map(|a| a.norm_sqr()).sum::<f64>().sqrt();
            row.iter_mut().for_each(|a| *a /= norm);
        }
        Point { p, x }
    }

    /// [`TangentBasis::coordinates_norm`] is the norm of the coordinates, to the bit (the
    /// staircase compares it with an iterate's gradient norm), at ranks 1 to 3.
    #[test]
    fn the_coordinates_norm_is_the_norm_of_the_coordinates() {
        let problem = square();
        for p in 1..=3 {
            let x = point(&problem, p);
            let basis = TangentBasis::new(&problem, &x);
            let g = problem.half_gradient(&x);
            let norm = basis
                .coordinates(&g)
                .iter()
                .map(|c| c * c)
                .sum::<f64>()
                .sqrt();
            assert!(norm > 0.0);
            assert_eq!(
                basis.coordinates_norm(&g).to_bits(),
                norm.to_bits(),
                "rank {p}"
            );
        }
    }

    /// Each row's basis is orthonormal in ℝ^{2p} (Re⟨a, b⟩ = δ_ab), a rotation row's is
    /// orthogonal to the row itself (its tangent space), and the coordinates lie where
    /// [`TangentBasis::offsets`] puts them.
    #[test]
    fn the_tangent_basis_is_orthonormal_and_tangent_row_by_row() {
        let problem = square();
        for p in 1..=3 {
            let x = point(&problem, p);
            let basis = TangentBasis::new(&problem, &x);
            let offsets = TangentBasis::offsets(&problem, p);
            assert_eq!(basis.dim, offsets[problem.rows()]);
            for k in 0..problem.rows() {
                assert_eq!(basis.offset(k), offsets[k]);
                assert_eq!(basis.len(k), offsets[k + 1] - offsets[k]);
                let rotation = k >= problem.positions();
                assert_eq!(basis.len(k), if rotation { 2 * p - 1 } else { 2 * p });
                for s in 0..basis.len(k) {
                    for t in 0..basis.len(k) {
                        let inner = dot(basis.vector(k, s), basis.vector(k, t)).re;
                        let want = if s == t { 1.0 } else { 0.0 };
                        assert!((inner - want).abs() <= 1e-15, "row {k}: {s} {t} {inner}");
                    }
                    if rotation {
                        let along = dot(basis.vector(k, s), x.row(k)).re;
                        assert!(along.abs() <= 1e-15, "row {k}: {along}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_hessian_form_is_the_second_derivative_along_the_retraction() {
        let problem = square();
        for p in [1, 3] {
            let x = point(&problem, p);
            let basis = TangentBasis::new(&problem, &x);
            let lambda = problem.multipliers(&x, &problem.half_gradient(&x));
            let delta: Vec<f64> = (0..basis.dim)
                .map(|k| ((k * 37 % 11) as f64 - 5.0) / 10.0)
                .collect();
            let form = basis.hessian_form(&problem, &lambda, &delta);
            // The same quadratic form from the assembled upper triangle of H.
            let mut values = Vec::new();
            basis.hessian_values(&problem, &lambda, 0.0, |v| values.push(v));
            let assembled: f64 = basis
                .hessian_pattern(&problem)
                .iter()
                .zip(&values)
                .map(|(&(a, b), v)| if a == b { 1.0 } else { 2.0 } * v * delta[a] * delta[b])
                .sum();
            assert!(
                (form - assembled).abs() <= 1e-12 * assembled.abs(),
                "{form} {assembled}"
            );
            // d²/dt² f(R(x, tδ)) at t = 0 (the retraction is of second order), by a central
            // second difference.
            let f = |t: f64| {
                let d: Vec<f64> = delta.iter().map(|v| t * v).collect();
                problem.cost(&basis.retract(&x, &d, problem.positions()))
            };
            let t = 1e-4;
            let second = (f(t) - 2.0 * f(0.0) + f(-t)) / (t * t);
            assert!(
                (second - form).abs() <= 1e-5 * form.abs(),
                "p {p}: {second} {form}"
            );
        }
    }
}
