//! Pose graph matrices (Sec. 3.2-3.4): the complex anchored pose graph matrix W̃ of eq.
//! (24)-(25), its blocks L, S̃, Q̃, the real matrix W of eq. (16), the penalized matrix W̃(λ)
//! of Sec. 4.1, the rotation-only matrix M = Q̃ − S̃* L⁻¹ S̃, and the cost f edge by edge.
//!
//! Layout of x̃ = [ρ̃; r̃] ∈ ℂ^{2n−1}: pose 0 (the smallest id) is the anchor, p_0 = 0 (eq. (15));
//! entries 0..n−1 hold the positions of poses 1..n−1, entries n−1..2n−1 the rotations of poses
//! 0..n−1. With per-edge weights (τ, κ) ([`crate::problem::weights`]) each edge (i, j) adds
//!
//! ```text
//! τ |p_j − p_i − Δ r_i|² + κ |r_j − R r_i|²,    Δ = dx + i·dy,  R = e^{i·dθ}
//! ```
//!
//! to f = x̃* W̃ x̃ (Prop. 5), i.e. to W̃: τ at (p_i, p_i) and (p_j, p_j), −τ at (p_i, p_j) and
//! (p_j, p_i), τΔ at (p_i, r_i), −τΔ at (p_j, r_i) (and their conjugates below the diagonal),
//! τ|Δ|² + κ at (r_i, r_i), κ at (r_j, r_j), −κR at (r_j, r_i), −κR̄ at (r_i, r_j); the rows of
//! p_0 are dropped (anchoring).

use crate::graph::{Edge, Observation, Pose2, PoseGraph};
use crate::linalg::factor::column_buckets;
use crate::problem::weights::EdgeWeight;
use faer::prelude::*;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Side, c64};

/// The complex anchored pose graph matrix W̃ of a graph (eq. (24)).
///
/// With landmarks (issue 13) the landmark positions l_0..l_{m−1} are more linear variables, rows
/// n−1..n−1+m of x̃ between the pose positions and the rotations: x̃ = [ρ̃; l̃; r̃]. An observation
/// of l_k from pose i with measurement d_ik and weight ν adds ν |l_k − p_i − r_i d_ik|², the
/// translation part of an edge term with p_j replaced by l_k. So the anchored Laplacian L (now
/// over poses 1..n−1 and the landmarks) and S̃ gain the landmark rows, Q̃ gains ν|d|² on the
/// diagonal, and W̃ = [[L, S̃], [S̃*, Q̃]] keeps the form of eq. (24): f = x̃* W̃ x̃ (Prop. 5), the
/// rotation-only matrix M = Q̃ − S̃* L⁻¹ S̃ (eq. (38)) is still n x n, and the dual (31), the
/// SZEP, Algorithm 1 and the certificate W̃(λ) ⪰ 0 (Theorem 1) apply unchanged: only the
/// rotations carry constraints |r_i| = 1, the positions of poses and landmarks are free.
#[derive(Debug, Clone)]
pub struct PoseGraphMatrix {
    /// Number of poses n.
    pub n: usize,
    /// Number of landmarks m.
    pub m: usize,
    /// W̃, (2n−1+m) x (2n−1+m) Hermitian, both triangles stored.
    pub w: SparseColMat<usize, c64>,
}

/// The complex number of a measurement's translation, Δ = dx + i·dy.
pub fn translation(z: Pose2) -> c64 {
    c64::new(z.x, z.y)
}

/// The unit complex number of a rotation angle, e^{iθ}.
pub fn rotation(theta: f64) -> c64 {
    c64::new(theta.cos(), theta.sin())
}

impl PoseGraphMatrix {
    /// W̃ of `graph` with the given weights: one per edge, then one per landmark observation
    /// ([`crate::problem::weights::edge_weights`]).
    pub fn new(graph: &PoseGraph, weights: &[EdgeWeight]) -> Self {
        let marks = &graph.landmarks;
        assert_eq!(
            weights.len(),
            graph.edges.len() + marks.observations.len(),
            "one weight per edge and per observation"
        );
        let n = graph.num_poses();
        let m = marks.len();
        assert!(n > 0, "a pose graph matrix needs at least one pose");
        // Positions of poses 1..n at 0..n-1; pose 0 is anchored and has no row; landmarks at
        // n-1..n-1+m, rotations after them.
        let p = |k: usize| (k > 0).then(|| k - 1);
        let lm = |k: usize| Some(n - 1 + k);
        let r = |k: usize| n - 1 + m + k;
        let mut t = Terms::with_capacity(16 * graph.edges.len() + 12 * marks.observations.len());
        // An off-diagonal term v at (a, b) and its conjugate at (b, a); a diagonal term once.
        let mut add = |a: Option<usize>, b: Option<usize>, v: c64| {
            if let (Some(a), Some(b)) = (a, b) {
                t.push(a, b, v);
                t.push(b, a, v.conj());
            }
        };
        // Diagonal terms are added as halves of a pair.
        let half = c64::new(0.5, 0.0);
        // τ |p_j − p_i − Δ r_i|² (the translation part of an edge, or an observation), with κ
        // (the edge's rotation weight, 0 for an observation) added to the (r_i, r_i) entry, in
        // the order and roundings of the pose-graph terms.
        let translation_term = |add: &mut dyn FnMut(Option<usize>, Option<usize>, c64),
                                pi: Option<usize>,
                                pj: Option<usize>,
                                ri: usize,
                                delta: c64,
                                tau: f64,
                                kappa: f64| {
            let tau_c = c64::new(tau, 0.0);
            add(pi, pi, half * tau_c);
            add(pj, pj, half * tau_c);
            add(pi, pj, -tau_c);
            add(pi, Some(ri), tau_c * delta);
            add(pj, Some(ri), -tau_c * delta);
            add(
                Some(ri),
                Some(ri),
                half * c64::new(tau * delta.norm_sqr() + kappa, 0.0),
            );
        };
        for (e, w) in graph.edges.iter().zip(weights) {
            let (i, j) = (e.i, e.j);
            let delta = translation(e.measurement);
            let big_r = rotation(e.measurement.theta);
            translation_term(&mut add, p(i), p(j), r(i), delta, w.tau, w.kappa);
            let kappa = c64::new(w.kappa, 0.0);
            add(Some(r(j)), Some(r(j)), half * kappa);
            add(Some(r(j)), Some(r(i)), -kappa * big_r);
        }
        for (o, w) in marks.observations.iter().zip(&weights[graph.edges.len()..]) {
            let d = c64::new(o.d[0], o.d[1]);
            translation_term(
                &mut add,
                p(o.pose),
                lm(o.landmark),
                r(o.pose),
                d,
                w.tau,
                0.0,
            );
        }
        let dim = 2 * n - 1 + m;
        PoseGraphMatrix {
            n,
            m,
            w: t.matrix(dim),
        }
    }

    /// The number of position rows n − 1 + m (poses 1..n−1, then the landmarks): the rotation
    /// of pose k is row `positions() + k`.
    pub fn positions(&self) -> usize {
        self.n - 1 + self.m
    }

    /// The dimension 2n − 1 + m of W̃.
    pub fn dim(&self) -> usize {
        2 * self.n - 1 + self.m
    }

    /// W̃ as a dense matrix.
    pub fn dense(&self) -> Mat<c64> {
        self.w.to_dense()
    }

    /// The penalized pose graph matrix W̃(λ) = W̃ − blkdiag(0, diag(λ)) (Sec. 4.1), dense.
    pub fn penalized_dense(&self, lambda: &[f64]) -> Mat<c64> {
        assert_eq!(lambda.len(), self.n);
        let mut w = self.dense();
        for (k, l) in lambda.iter().enumerate() {
            let d = self.positions() + k;
            w[(d, d)] -= c64::new(*l, 0.0);
        }
        w
    }

    /// The blocks of W̃ = [[L, S̃], [S̃*, Q̃]] (eq. (24)), dense: L is the anchored (weighted)
    /// Laplacian A^T T A, real, over poses 1..n−1 and the landmarks; S̃ is (n−1+m) x n; Q̃ is
    /// n x n Hermitian.
    pub fn blocks(&self) -> (Mat<f64>, Mat<c64>, Mat<c64>) {
        let w = self.dense();
        let m = self.positions();
        let l = Mat::from_fn(m, m, |a, b| w[(a, b)].re);
        let s = Mat::from_fn(m, self.n, |a, b| w[(a, m + b)]);
        let q = Mat::from_fn(self.n, self.n, |a, b| w[(m + a, m + b)]);
        (l, s, q)
    }

    /// The rotation-only matrix M = Q̃ − S̃* L⁻¹ S̃ (the Schur complement of L, eq. (38)): for a
    /// connected graph L ≻ 0, so W̃(λ) ⪰ 0 iff M − diag(λ) ⪰ 0, with the same number of zero
    /// eigenvalues, and min over positions of f = r̃* M r̃. `None` if L is not positive definite
    /// (a disconnected graph).
    pub fn rotation_matrix(&self) -> Option<Mat<c64>> {
        let (l, s, q) = self.blocks();
        if self.positions() == 0 {
            return Some(q);
        }
        let x = laplacian_llt(&l)?.solve(&s);
        let mut m = &q - s.adjoint() * &x;
        // Exactly Hermitian: average out rounding.
        for a in 0..self.n {
            m[(a, a)] = c64::new(m[(a, a)].re, 0.0);
            for b in 0..a {
                let v = (m[(a, b)] + m[(b, a)].conj()) * 0.5;
                m[(a, b)] = v;
                m[(b, a)] = v.conj();
            }
        }
        Some(m)
    }

    /// Positions (of poses 1..n−1, then of the landmarks) minimizing f for fixed rotations r̃:
    /// ρ̃ = −L⁻¹ S̃ r̃. `None` if L is singular.
    pub fn optimal_positions(&self, r: &[c64]) -> Option<Vec<c64>> {
        assert_eq!(r.len(), self.n);
        let (l, s, _) = self.blocks();
        if self.positions() == 0 {
            return Some(vec![]);
        }
        let rv = Mat::from_fn(self.n, 1, |a, _| r[a]);
        let rho = laplacian_llt(&l)?.solve(-(&s * &rv));
        Some((0..self.positions()).map(|a| rho[(a, 0)]).collect())
    }

    /// The real anchored pose graph matrix W of eq. (16): each complex entry a + ib of W̃ becomes
    /// the 2x2 block [[a, −b], [b, a]] (Prop. 5 and the proof of Prop. 7).
    pub fn real_dense(&self) -> Mat<f64> {
        let w = self.dense();
        let d = self.dim();
        Mat::from_fn(2 * d, 2 * d, |a, b| {
            let z = w[(a / 2, b / 2)];
            match (a % 2, b % 2) {
                (0, 0) | (1, 1) => z.re,
                (0, 1) => -z.im,
                _ => z.im,
            }
        })
    }

    /// x̃ = [ρ̃; l̃; r̃] of poses (eq. (20)), anchored at pose 0: ρ̃_k = p_k − p_0 (f is invariant
    /// to translations), r̃_k = e^{iθ_k}. `poses` holds the n poses followed by the m landmarks
    /// (as points: their θ is not used).
    pub fn state(&self, poses: &[Pose2]) -> Vec<c64> {
        assert_eq!(poses.len(), self.n + self.m);
        let p0 = c64::new(poses[0].x, poses[0].y);
        poses[1..]
            .iter()
            .map(|p| c64::new(p.x, p.y) - p0)
            .chain(poses[..self.n].iter().map(|p| rotation(p.theta)))
            .collect()
    }

    /// Poses of a state x̃ = [ρ̃; l̃; r̃]: pose 0 at the origin, θ_k = arg r̃_k (any nonzero
    /// modulus); the n poses, then the m landmarks as points (θ = 0).
    pub fn poses(&self, x: &[c64]) -> Vec<Pose2> {
        assert_eq!(x.len(), self.dim());
        let m = self.positions();
        (0..self.n)
            .map(|k| {
                let p = if k == 0 { c64::new(0.0, 0.0) } else { x[k - 1] };
                Pose2::new(p.re, p.im, x[m + k].arg())
            })
            .chain((0..self.m).map(|k| Pose2::new(x[self.n - 1 + k].re, x[self.n - 1 + k].im, 0.0)))
            .collect()
    }

    /// The quadratic form x̃* W̃ x̃.
    pub fn quadratic_form(&self, x: &[c64]) -> f64 {
        assert_eq!(x.len(), self.dim());
        let mut s = c64::new(0.0, 0.0);
        for (col, xc) in x.iter().enumerate() {
            let rows = self.w.symbolic().row_idx_of_col_raw(col);
            let vals = self.w.val_of_col(col);
            for (&row, v) in rows.iter().zip(vals) {
                s += x[row].conj() * v * xc;
            }
        }
        s.re
    }
}

/// The terms of W̃, (row, column, value) in the order the edges add them, and the matrix they
/// sum to.
struct Terms {
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<c64>,
}

impl Terms {
    fn with_capacity(capacity: usize) -> Self {
        Terms {
            rows: Vec::with_capacity(capacity),
            cols: Vec::with_capacity(capacity),
            vals: Vec::with_capacity(capacity),
        }
    }

    fn push(&mut self, row: usize, col: usize, val: c64) {
        self.rows.push(row);
        self.cols.push(col);
        self.vals.push(val);
    }

    /// The `dim` x `dim` matrix Σ of the terms, duplicates summed: entry for entry and bit for
    /// bit the one faer's `SparseColMat::try_new_from_triplets` builds (faer 0.24: the terms'
    /// indices bucketed by column in their order, each bucket sorted by `sort_unstable_by_key`
    /// on the row, duplicates added in the sorted order), from the rows, columns and values in
    /// separate arrays. faer's builder reads a 32-byte triplet at a random place for every key
    /// of its sort and every value it adds: on city10000 (331 000 terms) it took 9% of
    /// pgo-solve's whole run. The same sort of the same indices under the same comparisons
    /// gives the same permutation (an unstable sort may order equal rows either way, and the
    /// order of additions is its), hence the same sums.
    fn matrix(self, dim: usize) -> SparseColMat<usize, c64> {
        let Terms { rows, cols, vals } = self;
        let (start, mut order) = column_buckets(dim, cols.iter().copied());
        let mut col_ptr = Vec::with_capacity(dim + 1);
        let mut row_idx = Vec::with_capacity(rows.len());
        let mut values: Vec<c64> = Vec::with_capacity(rows.len());
        col_ptr.push(0);
        for c in 0..dim {
            let bucket = &mut order[start[c]..start[c + 1]];
            bucket.sort_unstable_by_key(|&k| rows[k]);
            let first = row_idx.len();
            for &k in bucket.iter() {
                if row_idx.len() > first && row_idx.last() == Some(&rows[k]) {
                    let last = values.len() - 1;
                    values[last] += vals[k];
                } else {
                    row_idx.push(rows[k]);
                    values.push(vals[k]);
                }
            }
            col_ptr.push(row_idx.len());
        }
        let symbolic = SymbolicSparseColMat::new_checked(dim, dim, col_ptr, None, row_idx);
        SparseColMat::new(symbolic, values)
    }
}

/// The Cholesky factor of the anchored Laplacian L (as a complex matrix, to solve with S̃);
/// `None` unless L ≻ 0, i.e. unless the graph is connected.
fn laplacian_llt(l: &Mat<f64>) -> Option<faer::linalg::solvers::Llt<c64>> {
    let lc = Mat::from_fn(l.nrows(), l.ncols(), |a, b| c64::new(l[(a, b)], 0.0));
    lc.llt(Side::Lower).ok()
}

/// The cost f of eq. (8) with per-edge weights, summed edge by edge from the poses (no matrix):
/// Σ τ |p_j − p_i − r_i Δ|² + κ |r_j − r_i R|², plus Σ ν |l_k − p_i − r_i d|² over the landmark
/// observations, whose positions follow the n poses in `poses` (when the graph has landmarks).
pub fn cost(graph: &PoseGraph, weights: &[EdgeWeight], poses: &[Pose2]) -> f64 {
    let edges = graph
        .edges
        .iter()
        .zip(weights)
        .map(|(e, w)| edge_cost(e, *w, poses))
        // From +0: an empty sum of f64 is -0 in Rust, and a graph without edges costs 0.
        .fold(0.0, |a, b| a + b);
    let n = graph.num_poses();
    let marks = &graph.landmarks;
    if marks.observations.is_empty() {
        return edges;
    }
    edges
        + marks
            .observations
            .iter()
            .zip(&weights[graph.edges.len()..])
            .map(|(o, w)| {
                let l = poses[n + o.landmark];
                observation_cost(o, *w, poses[o.pose], [l.x, l.y])
            })
            .fold(0.0, |a, b| a + b)
}

/// The term of one landmark observation in the cost f: ν |l_k − p_i − r_i d_ik|² for the pose
/// i it is seen from and the landmark position l_k (ν is the weight's `tau`).
pub fn observation_cost(o: &Observation, w: EdgeWeight, pose: Pose2, landmark: [f64; 2]) -> f64 {
    let t = c64::new(landmark[0] - pose.x, landmark[1] - pose.y)
        - rotation(pose.theta) * c64::new(o.d[0], o.d[1]);
    w.tau * t.norm_sqr()
}

/// The term of one edge in the cost f: τ |p_j − p_i − r_i Δ|² + κ |r_j − r_i R|² (the
/// residuals `pgo-solve --rerun-*` colors edges by).
pub fn edge_cost(e: &Edge, w: EdgeWeight, poses: &[Pose2]) -> f64 {
    let (a, b) = (poses[e.i], poses[e.j]);
    let ri = rotation(a.theta);
    let t = c64::new(b.x - a.x, b.y - a.y) - ri * translation(e.measurement);
    let rot = rotation(b.theta) - ri * rotation(e.measurement.theta);
    w.tau * t.norm_sqr() + w.kappa * rot.norm_sqr()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::graph::{Edge, SymMat3};
    use crate::problem::weights::{Weights, edge_weights};

    /// A small deterministic generator, so that the tests need no dependency.
    pub(crate) struct Rng(pub(crate) u64);

    impl Rng {
        pub(crate) fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        pub(crate) fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.next()
        }
    }

    /// A graph with `n` poses: the path 0-1-...-(n-1), plus `extra` (i, j) edges; measurements
    /// from `truth` composed, perturbed by `noise` (0 gives a balanced graph).
    pub(crate) fn graph(
        truth: &[Pose2],
        extra: &[(usize, usize)],
        noise: f64,
        rng: &mut Rng,
    ) -> PoseGraph {
        let n = truth.len();
        let pairs: Vec<(usize, usize)> = (0..n - 1)
            .map(|k| (k, k + 1))
            .chain(extra.iter().copied())
            .collect();
        let edges = pairs
            .iter()
            .map(|&(i, j)| {
                let z = truth[i].to_isometry().inv_mul(&truth[j].to_isometry());
                let mut m = Pose2::from_isometry(&z);
                m.x += noise * rng.range(-1.0, 1.0);
                m.y += noise * rng.range(-1.0, 1.0);
                m.theta += noise * rng.range(-1.0, 1.0);
                Edge {
                    i,
                    j,
                    measurement: m,
                    noise: SymMat3([2.0, 0.3, 0.1, 3.0, 0.2, 5.0]),
                }
            })
            .collect();
        PoseGraph::with_edges(truth.to_vec(), edges)
    }

    pub(crate) fn random_poses(n: usize, rng: &mut Rng) -> Vec<Pose2> {
        (0..n)
            .map(|_| {
                Pose2::new(
                    rng.range(0.0, 10.0),
                    rng.range(0.0, 10.0),
                    rng.range(-3.1, 3.1),
                )
            })
            .collect()
    }

    fn eigenvalues(m: &Mat<c64>) -> Vec<f64> {
        m.self_adjoint_eigenvalues(Side::Lower).unwrap()
    }

    /// [`Terms::matrix`] is faer's `try_new_from_triplets` bit for bit: the same pattern and the
    /// same sums, on terms with many duplicates (columns of up to 200 terms, beyond the lengths
    /// a sort handles by insertion, where an unstable sort reorders equal rows) whose sums
    /// depend on the order of their additions (values of magnitudes 1e-8 to 1e8), and on empty
    /// columns.
    #[test]
    fn terms_sum_to_faers_matrix_bit_for_bit() {
        use faer::sparse::Triplet;
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for (dim, count, rows_per_col) in [(1, 3, 1), (7, 40, 3), (30, 2000, 4), (50, 6000, 12)] {
            let mut terms = Terms::with_capacity(count);
            let mut triplets = Vec::with_capacity(count);
            for _ in 0..count {
                let col = (rng.next() * dim as f64) as usize % dim;
                // Rows from a few per column (many duplicates), some columns left empty.
                let row = (col + (rng.next() * rows_per_col as f64) as usize) % dim;
                if col % 5 == 3 {
                    continue;
                }
                let scale = 10f64.powi((rng.next() * 16.0) as i32 - 8);
                let val = c64::new(rng.range(-1.0, 1.0) * scale, rng.range(-1.0, 1.0) * scale);
                terms.push(row, col, val);
                triplets.push(Triplet::new(row, col, val));
            }
            let ours = terms.matrix(dim);
            let faers = SparseColMat::try_new_from_triplets(dim, dim, &triplets).unwrap();
            assert_eq!(
                ours.symbolic().col_ptr(),
                faers.symbolic().col_ptr(),
                "dim {dim}"
            );
            assert_eq!(ours.symbolic().row_idx(), faers.symbolic().row_idx());
            let bits = |m: &SparseColMat<usize, c64>| -> Vec<(u64, u64)> {
                m.val()
                    .iter()
                    .map(|v| (v.re.to_bits(), v.im.to_bits()))
                    .collect()
            };
            assert_eq!(bits(&ours), bits(&faers), "dim {dim}");
        }
    }

    #[test]
    fn prop5_cost_three_ways() {
        // f edge by edge, x̃* W̃ x̃ (complex), and xᵀ W x (real, eq. (15)) agree at arbitrary
        // poses, for both weight policies.
        let mut rng = Rng(7);
        for (n, noise) in [(2, 0.3), (6, 0.5), (12, 1.0)] {
            let truth = random_poses(n, &mut rng);
            let g = graph(&truth, &[(0, n - 1), (1, n / 2)], noise, &mut rng);
            let eval = random_poses(n, &mut rng);
            for policy in [Weights::Unit, Weights::Isotropic] {
                let w = edge_weights(&g, policy).unwrap();
                let m = PoseGraphMatrix::new(&g, &w);
                let f = cost(&g, &w, &eval);
                let x = m.state(&eval);
                let complex = m.quadratic_form(&x);
                let xr: Vec<f64> = x.iter().flat_map(|z| [z.re, z.im]).collect();
                let wr = m.real_dense();
                let mut real = 0.0;
                for a in 0..xr.len() {
                    for b in 0..xr.len() {
                        real += xr[a] * wr[(a, b)] * xr[b];
                    }
                }
                assert!((f - complex).abs() <= 1e-10 * f.max(1.0), "{f} {complex}");
                assert!((f - real).abs() <= 1e-10 * f.max(1.0), "{f} {real}");
            }
        }
    }

    #[test]
    fn prop7_real_spectrum_is_the_complex_one_twice() {
        let mut rng = Rng(11);
        let truth = random_poses(7, &mut rng);
        let g = graph(&truth, &[(0, 6), (2, 5)], 0.4, &mut rng);
        let w = edge_weights(&g, Weights::Isotropic).unwrap();
        let m = PoseGraphMatrix::new(&g, &w);
        let complex = eigenvalues(&m.dense());
        let real = m
            .real_dense()
            .self_adjoint_eigenvalues(Side::Lower)
            .unwrap();
        assert_eq!(real.len(), 2 * complex.len());
        let scale = complex.last().unwrap().abs();
        for (k, c) in complex.iter().enumerate() {
            for r in &real[2 * k..2 * k + 2] {
                assert!((r - c).abs() <= 1e-10 * scale, "{r} vs {c}");
            }
        }
    }

    #[test]
    fn prop6_single_zero_eigenvalue_iff_balanced_or_tree() {
        let mut rng = Rng(3);
        for trial in 0..5 {
            let n = 5 + trial;
            let truth = random_poses(n, &mut rng);
            let cases = [
                (graph(&truth, &[], 0.5, &mut rng), true), // tree, noisy
                (graph(&truth, &[(0, n - 1), (1, 3)], 0.0, &mut rng), true), // balanced
                (graph(&truth, &[(0, n - 1), (1, 3)], 0.3, &mut rng), false), // noisy loops
            ];
            for (g, zero) in cases {
                let w = edge_weights(&g, Weights::Unit).unwrap();
                let ev = eigenvalues(&PoseGraphMatrix::new(&g, &w).dense());
                let scale = ev.last().unwrap();
                let near_zero = ev.iter().filter(|v| v.abs() <= 1e-9 * scale).count();
                assert_eq!(near_zero, usize::from(zero), "trial {trial}: {ev:?}");
                if !zero {
                    assert!(ev[0] > 1e-6 * scale, "{ev:?}");
                }
            }
        }
    }

    #[test]
    fn props1_11_trees_have_zero_cost_and_zero_multipliers() {
        // On a tree the measurements composed along it annihilate f (Prop. 1, Appendix 8.1),
        // and λ = 0 is dual optimal (Prop. 11): W̃(0) = W̃ ⪰ 0 with d(0) = 0 = f*.
        let mut rng = Rng(5);
        let truth = random_poses(8, &mut rng);
        let mut g = graph(&truth, &[], 0.7, &mut rng);
        g.initialize_spanning_tree();
        let w = edge_weights(&g, Weights::Isotropic).unwrap();
        let f = cost(&g, &w, &g.poses);
        assert!(f < 1e-20, "{f}");
        let m = PoseGraphMatrix::new(&g, &w);
        let ev = eigenvalues(&m.penalized_dense(&[0.0; 8]));
        assert!(ev[0] >= -1e-10 * ev.last().unwrap(), "{ev:?}");
        // And x̃ of the composed poses spans the kernel: W̃ x̃ = 0 (Theorem 1's certificate).
        let x = m.state(&g.poses);
        let scale: f64 = x.iter().map(|v| v.norm_sqr()).sum::<f64>() * ev.last().unwrap();
        assert!(m.quadratic_form(&x).abs() < 1e-14 * scale);
    }

    #[test]
    fn schur_complement_and_optimal_positions() {
        // min over positions of f(ρ, r) = r* M r, attained at ρ = −L⁻¹ S r.
        let mut rng = Rng(9);
        let truth = random_poses(6, &mut rng);
        let g = graph(&truth, &[(0, 5), (1, 4)], 0.6, &mut rng);
        let w = edge_weights(&g, Weights::Isotropic).unwrap();
        let m = PoseGraphMatrix::new(&g, &w);
        let mm = m.rotation_matrix().unwrap();
        let r: Vec<c64> = (0..6).map(|_| rotation(rng.range(-3.0, 3.0))).collect();
        let rho = m.optimal_positions(&r).unwrap();
        let x: Vec<c64> = rho.iter().chain(&r).copied().collect();
        let reduced: f64 = (0..6)
            .flat_map(|a| (0..6).map(move |b| (a, b)))
            .map(|(a, b)| (r[a].conj() * mm[(a, b)] * r[b]).re)
            .sum();
        let full = m.quadratic_form(&x);
        assert!((reduced - full).abs() <= 1e-10 * full, "{reduced} {full}");
        // Any other positions cost more.
        let mut y = x.clone();
        y[2] += c64::new(0.1, -0.2);
        assert!(m.quadratic_form(&y) > full);
        // Same zero-eigenvalue count: both W̃(λ) and M − diag(λ) are singular at the λ that
        // makes M − diag(λ) singular.
        let lmin = eigenvalues(&mm)[0];
        let lambda = vec![lmin; 6];
        let ew = eigenvalues(&m.penalized_dense(&lambda));
        assert!(
            ew[0].abs() < 1e-9 * ew.last().unwrap() && ew[1] > 1e-9,
            "{ew:?}"
        );
    }
}
