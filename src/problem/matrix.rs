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
use crate::problem::weights::EdgeWeight;
use faer::prelude::*;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Side, c64};
use std::sync::Arc;

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
    /// The upper triangle of W̃ ((2n−1+m) x (2n−1+m) Hermitian), every diagonal entry stored
    /// (zero for a pose without edges), so that penalized and shifted matrices share its
    /// pattern. Shared with the certificate ([`crate::certify::SparseCertifier`]), which keeps
    /// no copy of its own (24 bytes an entry: 155 MB at 10⁶ poses).
    pub upper: Arc<SparseColMat<usize, c64>>,
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
        Self::relabeled(graph, weights, |k| k)
    }

    /// [`Self::new`] of the graph whose pose k is `graph`'s pose `label(k)`, `label` a
    /// permutation of the poses that is its own inverse (such as one exchanging the anchor and
    /// pose 0): built from `graph` as it is, without a relabeled copy.
    pub fn relabeled(
        graph: &PoseGraph,
        weights: &[EdgeWeight],
        label: impl Fn(usize) -> usize,
    ) -> Self {
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
        let terms = |out: &mut Upper| {
            for (e, w) in graph.edges.iter().zip(weights) {
                let (i, j) = (label(e.i), label(e.j));
                let delta = translation(e.measurement);
                out.translation(p(i), p(j), r(i), delta, w.tau, w.kappa);
                out.diagonal(Some(r(j)), w.kappa);
                out.pair(
                    Some(r(j)),
                    Some(r(i)),
                    -rotation(e.measurement.theta) * w.kappa,
                );
            }
            for (o, w) in marks.observations.iter().zip(&weights[graph.edges.len()..]) {
                let d = c64::new(o.d[0], o.d[1]);
                let i = label(o.pose);
                out.translation(p(i), lm(o.landmark), r(i), d, w.tau, 0.0);
            }
        };
        let dim = 2 * n - 1 + m;
        PoseGraphMatrix {
            n,
            m,
            upper: Arc::new(upper_triangle(dim, terms)),
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

    /// Calls `f(row, column, value)` for every stored entry (row ≤ column), column by column:
    /// the order of [`Self::upper_entries`], for the loops of every Newton step.
    pub fn for_each_upper(&self, f: impl FnMut(usize, usize, c64)) {
        for_each_entry(&self.upper, f);
    }

    /// The stored entries (row ≤ column) with their values, column by column.
    pub fn upper_entries(&self) -> impl Iterator<Item = (usize, usize, c64)> + '_ {
        (0..self.dim()).flat_map(move |col| {
            let rows = self.upper.symbolic().row_idx_of_col_raw(col);
            rows.iter()
                .zip(self.upper.val_of_col(col))
                .map(move |(&row, &v)| (row, col, v))
        })
    }

    /// W̃ as a dense matrix.
    pub fn dense(&self) -> Mat<c64> {
        let mut w = Mat::zeros(self.dim(), self.dim());
        for (r, c, v) in self.upper_entries() {
            w[(r, c)] = v;
            w[(c, r)] = v.conj();
        }
        w
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

    /// The quadratic form x̃* W̃ x̃ = Σ_a W̃_aa |x_a|² + 2 Re Σ_{a<b} x̄_a W̃_ab x_b.
    pub fn quadratic_form(&self, x: &[c64]) -> f64 {
        assert_eq!(x.len(), self.dim());
        self.upper_entries()
            .map(|(r, c, v)| {
                let t = (x[r].conj() * v * x[c]).re;
                if r == c { t } else { 2.0 * t }
            })
            .fold(0.0, |a, b| a + b)
    }
}

/// Where the edges' terms of W̃ go ([`upper_triangle`]): each entry of the upper triangle
/// (row ≤ column) as it is added, an entry below the diagonal as its conjugate above.
struct Upper<'a>(&'a mut dyn FnMut(usize, usize, c64));

impl Upper<'_> {
    /// x on the diagonal at `a` (nothing for the anchor, which has no row).
    fn diagonal(&mut self, a: Option<usize>, x: f64) {
        if let Some(a) = a {
            (self.0)(a, a, c64::new(x, 0.0));
        }
    }

    /// v at (a, b) and v̄ at (b, a).
    fn pair(&mut self, a: Option<usize>, b: Option<usize>, v: c64) {
        match (a, b) {
            (Some(a), Some(b)) if a < b => (self.0)(a, b, v),
            (Some(a), Some(b)) if a > b => (self.0)(b, a, v.conj()),
            (Some(a), Some(_)) => {
                (self.0)(a, a, v);
                (self.0)(a, a, v.conj());
            }
            _ => {}
        }
    }

    /// τ |p_j − p_i − Δ r_i|² (the translation part of an edge, or an observation with l_k for
    /// p_j), with κ (the edge's rotation weight, 0 for an observation) on (r_i, r_i): τ at
    /// (p_i, p_i) and (p_j, p_j), −τ at (p_i, p_j), τΔ at (p_i, r_i), −τΔ at (p_j, r_i),
    /// τ|Δ|² + κ at (r_i, r_i).
    fn translation(
        &mut self,
        pi: Option<usize>,
        pj: Option<usize>,
        ri: usize,
        delta: c64,
        tau: f64,
        kappa: f64,
    ) {
        self.diagonal(pi, tau);
        self.diagonal(pj, tau);
        self.pair(pi, pj, c64::new(-tau, 0.0));
        self.pair(pi, Some(ri), delta * tau);
        self.pair(pj, Some(ri), delta * -tau);
        self.diagonal(Some(ri), tau * delta.norm_sqr() + kappa);
    }
}

/// Calls `f(row, column, value)` for every entry of a compact sparse matrix (no gaps between its
/// columns, as [`upper_triangle`] builds them), column by column; the k-th call is the matrix's
/// k-th stored value.
pub fn for_each_entry(m: &SparseColMat<usize, c64>, mut f: impl FnMut(usize, usize, c64)) {
    debug_assert!(m.symbolic().col_nnz().is_none(), "a compact matrix");
    let (col_ptr, rows, values) = (m.symbolic().col_ptr(), m.symbolic().row_idx(), m.val());
    for c in 0..m.ncols() {
        for k in col_ptr[c]..col_ptr[c + 1] {
            f(rows[k], c, values[k]);
        }
    }
}

/// The (row, column) of every entry of a compact sparse matrix, in [`for_each_entry`]'s order:
/// the pattern an [`crate::linalg::factor::Assembly`] of the same matrix is built from.
pub fn entry_pattern(m: &SparseColMat<usize, c64>) -> Vec<(usize, usize)> {
    let mut pattern = Vec::with_capacity(m.val().len());
    for_each_entry(m, |r, c, _| pattern.push((r, c)));
    pattern
}

/// The upper triangle (every diagonal entry included, zero or not) of the `dim` x `dim` Hermitian
/// matrix that `terms` adds up, each entry the sum of its terms in the order `terms` gives them,
/// from 0; rows ascending in each column. Two passes over the terms (count each column's, then
/// place them) and one over the columns (duplicates summed through a row marker, the distinct
/// rows sorted): O(terms + nnz·log(column length)) and 24 bytes per term, where sorting
/// (row, column, value) triplets of both triangles took ten times the memory and, on city10000,
/// a tenth of pgo-solve's run.
fn upper_triangle(dim: usize, terms: impl Fn(&mut Upper)) -> SparseColMat<usize, c64> {
    // Each column's first term is a zero on its diagonal.
    let mut start = vec![1usize; dim + 1];
    start[0] = 0;
    terms(&mut Upper(&mut |_, c, _| start[c + 1] += 1));
    for c in 0..dim {
        start[c + 1] += start[c];
    }
    let mut rows = vec![0usize; start[dim]];
    let mut vals = vec![c64::new(0.0, 0.0); start[dim]];
    let mut next: Vec<usize> = start[..dim].to_vec();
    for (c, k) in next.iter_mut().enumerate() {
        rows[*k] = c;
        *k += 1;
    }
    terms(&mut Upper(&mut |r, c, v| {
        rows[next[c]] = r;
        vals[next[c]] = v;
        next[c] += 1;
    }));
    drop(next);
    // Column by column, in place: a column's entries never outnumber its terms, so they are
    // written at or before the place its terms are read from.
    let mut mark = vec![usize::MAX; dim];
    let mut slot = vec![0usize; dim];
    let mut column: Vec<(usize, c64)> = Vec::new();
    let mut col_ptr = Vec::with_capacity(dim + 1);
    col_ptr.push(0);
    for c in 0..dim {
        column.clear();
        for k in start[c]..start[c + 1] {
            let r = rows[k];
            if mark[r] == c {
                column[slot[r]].1 += vals[k];
            } else {
                mark[r] = c;
                slot[r] = column.len();
                column.push((r, vals[k]));
            }
        }
        column.sort_unstable_by_key(|&(r, _)| r);
        let first = col_ptr[c];
        for (k, &(r, v)) in column.iter().enumerate() {
            rows[first + k] = r;
            vals[first + k] = v;
        }
        col_ptr.push(first + column.len());
    }
    let nnz = col_ptr[dim];
    // The matrix lives as long as its problem: without the terms' room.
    rows.truncate(nnz);
    rows.shrink_to_fit();
    vals.truncate(nnz);
    vals.shrink_to_fit();
    let symbolic = SymbolicSparseColMat::new_checked(dim, dim, col_ptr, None, rows);
    SparseColMat::new(symbolic, vals)
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

    /// [`upper_triangle`] against a dense matrix summed term by term in the same order: the same
    /// pattern (the entries the terms touch, and every diagonal entry) and the same sums bit for
    /// bit, on terms of both triangles with many duplicates (columns of up to 200 terms) whose
    /// sums depend on the order of their additions (magnitudes 1e-8 to 1e8), and on rows without
    /// terms.
    #[test]
    fn upper_triangle_sums_the_terms_in_their_order() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for (dim, count, spread) in [(1, 3, 1), (7, 40, 3), (30, 2000, 4), (50, 6000, 12)] {
            let mut ops = Vec::with_capacity(count);
            for _ in 0..count {
                let a = (rng.next() * dim as f64) as usize % dim;
                let b = (a + (rng.next() * spread as f64) as usize) % dim;
                if a % 5 == 3 || b % 5 == 3 {
                    continue;
                }
                let scale = 10f64.powi((rng.next() * 16.0) as i32 - 8);
                let v = c64::new(rng.range(-1.0, 1.0) * scale, rng.range(-1.0, 1.0) * scale);
                // Half of them given from below the diagonal.
                ops.push(if rng.next() < 0.5 {
                    (a, b, v)
                } else {
                    (b, a, v)
                });
            }
            let ours = upper_triangle(dim, |out| {
                for &(a, b, v) in &ops {
                    if a == b {
                        out.diagonal(Some(a), v.re);
                    } else {
                        out.pair(Some(a), Some(b), v);
                    }
                }
            });
            let mut dense = vec![vec![None::<c64>; dim]; dim];
            for (k, row) in dense.iter_mut().enumerate() {
                row[k] = Some(c64::new(0.0, 0.0));
            }
            for &(a, b, v) in &ops {
                let (r, c, v) = match a.cmp(&b) {
                    std::cmp::Ordering::Less => (a, b, v),
                    std::cmp::Ordering::Greater => (b, a, v.conj()),
                    std::cmp::Ordering::Equal => (a, a, c64::new(v.re, 0.0)),
                };
                let e = dense[r][c].get_or_insert(c64::new(0.0, 0.0));
                *e += v;
            }
            let bits = |v: c64| (v.re.to_bits(), v.im.to_bits());
            let want: Vec<(usize, usize, (u64, u64))> = (0..dim)
                .flat_map(|c| (0..=c).map(move |r| (r, c)))
                .filter_map(|(r, c)| dense[r][c].map(|v| (r, c, bits(v))))
                .collect();
            let m = PoseGraphMatrix {
                n: 1,
                m: dim - 1,
                upper: Arc::new(ours),
            };
            let got: Vec<_> = m.upper_entries().map(|(r, c, v)| (r, c, bits(v))).collect();
            assert_eq!(got, want, "dim {dim}");
            // The same entries in the same order from the loop the Newton steps use, the k-th
            // call with the k-th stored value (the certificate's diagonal indices rely on it).
            let mut each = Vec::new();
            m.for_each_upper(|r, c, v| each.push((r, c, bits(v))));
            assert_eq!(each, want, "dim {dim}");
            let stored: Vec<_> = m.upper.val().iter().map(|&v| bits(v)).collect();
            assert_eq!(stored, want.iter().map(|w| w.2).collect::<Vec<_>>());
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
