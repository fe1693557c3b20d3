//! The rank-p (Burer-Monteiro) form of the problem in the complex domain, for the scalable
//! solver: X = [P; Y] ∈ ℂ^{(2n−1)×p}, rows 0..n−1 the positions of poses 1..n−1 (pose 0 is the
//! anchor, P_0 = 0, eq. (15)), rows n−1..2n−1 the rotations, each a unit vector of ℂ^p. The cost
//! is f(X) = tr(X* W̃ X) (eq. (24) with p columns; p = 1 is the problem itself, and a larger p is
//! the SDP relaxation (37) restricted to rank p), evaluated edge by edge:
//!
//! ```text
//! f(X) = Σ_e τ ‖P_j − P_i − Δ Y_i‖² + κ ‖Y_j − R Y_i‖²
//! ```
//!
//! so that no cancellation between large terms of W̃ spoils it. The Euclidean gradient is 2W̃X,
//! also summed edge by edge from the residuals. On the product of spheres, the first-order
//! conditions give the multipliers λ_a = Re⟨Y_a, (W̃X)_a⟩, and the Riemannian Hessian in an
//! orthonormal tangent basis B is H = 2 Bᵀ (W̃ − blkdiag(0, diag λ)) B = 2 Bᵀ W̃(λ) B (the
//! penalized matrix of Sec. 4.1, real form of eq. (16)): a second-order critical point has
//! W̃(λ) ⪰ 0 on the tangent space, and W̃(λ) ⪰ 0 everywhere proves global optimality (Theorem 1).

use crate::graph::PoseGraph;
use crate::problem::matrix::{PoseGraphMatrix, rotation, translation};
use crate::problem::weights::EdgeWeight;
use faer::c64;

/// One edge's term of f: τ|p_j − p_i − Δ r_i|² + κ|r_j − R r_i|²; or, with `landmark`, one
/// landmark observation's: ν|l_j − p_i − d r_i|² (`j` the landmark, τ = ν, Δ = d, κ = 0: the
/// translation part of an edge whose head is the landmark, without a rotation part).
#[derive(Debug, Clone, Copy)]
pub struct EdgeTerm {
    pub i: usize,
    pub j: usize,
    /// Whether `j` is a landmark (an observation) rather than a pose (an edge).
    pub landmark: bool,
    pub delta: c64,
    pub rot: c64,
    pub tau: f64,
    pub kappa: f64,
}

/// The problem at rank p: the edges, the matrix W̃ (for its pattern) and the layout. With
/// landmarks (issue 13) their positions are rows n−1..n−1+m of X, free like the poses'
/// positions, and the rotations follow them ([`crate::problem::matrix::PoseGraphMatrix`]).
pub struct Problem {
    pub n: usize,
    /// Number of landmarks m.
    pub m: usize,
    pub terms: Vec<EdgeTerm>,
    /// W̃, its upper triangle ([`PoseGraphMatrix::upper`]).
    pub matrix: PoseGraphMatrix,
    /// A fill-reducing rank of each pose, then of each landmark (node n + k)
    /// ([`crate::linalg::factor::pose_rank`]).
    pub pose_rank: Vec<usize>,
}

/// A point of the rank-p manifold: (2n−1) rows of p entries, row-major.
#[derive(Debug, Clone)]
pub struct Point {
    pub p: usize,
    pub x: Vec<c64>,
}

impl Point {
    /// Row k.
    pub fn row(&self, k: usize) -> &[c64] {
        &self.x[k * self.p..(k + 1) * self.p]
    }

    pub(crate) fn row_mut(&mut self, k: usize) -> &mut [c64] {
        &mut self.x[k * self.p..(k + 1) * self.p]
    }
}

pub(crate) fn dot(a: &[c64], b: &[c64]) -> c64 {
    a.iter().zip(b).map(|(x, y)| x.conj() * y).sum()
}

impl Problem {
    /// The problem of a connected graph with per-edge weights.
    pub fn new(graph: &PoseGraph, weights: &[EdgeWeight]) -> Self {
        Self::relabeled(graph, weights, |k| k)
    }

    /// [`Self::new`] of the graph whose pose k is `graph`'s pose `label(k)`, `label` a
    /// permutation of the poses that is its own inverse ([`PoseGraphMatrix::relabeled`]).
    pub fn relabeled(
        graph: &PoseGraph,
        weights: &[EdgeWeight],
        label: impl Fn(usize) -> usize + Sync,
    ) -> Self {
        let marks = &graph.landmarks;
        let n = graph.num_poses();
        let m = marks.len();
        let label = &label;
        // The fill-reducing order (a fifth of this function's time on city10000, in perf
        // samples) on a second core beside the assembly.
        let ((terms, matrix), pose_rank) = crate::linalg::parallel::join(
            || Self::assemble(graph, weights, label),
            || {
                crate::linalg::factor::pose_rank(
                    n + m,
                    graph.edges.iter().map(|e| (label(e.i), label(e.j))).chain(
                        marks
                            .observations
                            .iter()
                            .map(|o| (label(o.pose), n + o.landmark)),
                    ),
                    crate::linalg::factor::PLANAR_BLOCK_WORK,
                )
            },
        );
        Problem {
            n,
            m,
            terms,
            matrix,
            pose_rank,
        }
    }

    /// The terms and W̃.
    fn assemble(
        graph: &PoseGraph,
        weights: &[EdgeWeight],
        label: impl Fn(usize) -> usize,
    ) -> (Vec<EdgeTerm>, PoseGraphMatrix) {
        let marks = &graph.landmarks;
        let terms = graph
            .edges
            .iter()
            .zip(weights)
            .map(|(e, w)| EdgeTerm {
                i: label(e.i),
                j: label(e.j),
                landmark: false,
                delta: translation(e.measurement),
                rot: rotation(e.measurement.theta),
                tau: w.tau,
                kappa: w.kappa,
            })
            .chain(
                marks
                    .observations
                    .iter()
                    .zip(&weights[graph.edges.len()..])
                    .map(|(o, w)| EdgeTerm {
                        i: label(o.pose),
                        j: o.landmark,
                        landmark: true,
                        delta: c64::new(o.d[0], o.d[1]),
                        rot: c64::new(1.0, 0.0),
                        tau: w.tau,
                        kappa: 0.0,
                    }),
            )
            .collect();
        let matrix = PoseGraphMatrix::relabeled(graph, weights, &label);
        (terms, matrix)
    }

    /// The pose of each row of X (positions of poses 1..n−1, the landmarks as nodes n..n+m,
    /// then rotations of 0..n−1).
    pub fn row_poses(&self) -> Vec<usize> {
        (1..self.n + self.m).chain(0..self.n).collect()
    }

    /// A fill-reducing order of the rows of X ([`crate::linalg::factor::group_ordering`]).
    pub fn row_order(&self) -> Vec<usize> {
        crate::linalg::factor::group_ordering(&self.pose_rank, &self.row_poses())
    }

    /// A fill-reducing order of poses 1..n−1 (the rows of the anchored Laplacian L and of the
    /// chordal relaxation: [`crate::linalg::factor::group_ordering`] by [`Problem::pose_rank`]), so that
    /// their factorizations need no ordering of their own.
    pub fn anchored_order(&self) -> Vec<usize> {
        let poses: Vec<usize> = (1..self.n + self.m).collect();
        crate::linalg::factor::group_ordering(&self.pose_rank, &poses)
    }

    /// A fill-reducing order of the rotations of poses 1..n−1 (the unknowns of the chordal
    /// relaxation).
    pub fn rotation_order(&self) -> Vec<usize> {
        let poses: Vec<usize> = (1..self.n).collect();
        crate::linalg::factor::group_ordering(&self.pose_rank, &poses)
    }

    /// The dimension 2n − 1 + m (rows of X).
    pub fn rows(&self) -> usize {
        2 * self.n - 1 + self.m
    }

    /// The number of position rows n − 1 + m (poses 1..n−1, then the landmarks).
    pub fn positions(&self) -> usize {
        self.n - 1 + self.m
    }

    /// Row of landmark k's position.
    pub fn landmark_row(&self, k: usize) -> usize {
        self.n - 1 + k
    }

    /// Row of the head's position of a term: pose j's (None for the anchor) or landmark j's.
    pub fn head_position_row(&self, t: &EdgeTerm) -> Option<usize> {
        if t.landmark {
            Some(self.landmark_row(t.j))
        } else {
            self.position_row(t.j)
        }
    }

    /// Row of the head's rotation of a term: pose j's; None for an observation.
    pub fn head_rotation_row(&self, t: &EdgeTerm) -> Option<usize> {
        (!t.landmark).then(|| self.rotation_row(t.j))
    }

    /// Row of pose k's position (None for the anchor, pose 0).
    pub fn position_row(&self, k: usize) -> Option<usize> {
        (k > 0).then(|| k - 1)
    }

    /// Row of pose k's rotation.
    pub fn rotation_row(&self, k: usize) -> usize {
        self.n - 1 + self.m + k
    }

    /// f(X), edge by edge.
    pub fn cost(&self, x: &Point) -> f64 {
        let p = x.p;
        let zero = vec![c64::new(0.0, 0.0); p];
        let mut f = 0.0;
        for t in &self.terms {
            let pi = self.position_row(t.i).map_or(&zero[..], |r| x.row(r));
            let pj = self.head_position_row(t).map_or(&zero[..], |r| x.row(r));
            let yi = x.row(self.rotation_row(t.i));
            match self.head_rotation_row(t) {
                Some(yj) => {
                    let yj = x.row(yj);
                    for c in 0..p {
                        f += t.tau * (pj[c] - pi[c] - t.delta * yi[c]).norm_sqr()
                            + t.kappa * (yj[c] - t.rot * yi[c]).norm_sqr();
                    }
                }
                None => {
                    for c in 0..p {
                        f += t.tau * (pj[c] - pi[c] - t.delta * yi[c]).norm_sqr();
                    }
                }
            }
        }
        f
    }

    /// G = W̃X (half the Euclidean gradient), summed edge by edge from the residuals.
    pub fn half_gradient(&self, x: &Point) -> Vec<c64> {
        self.half_gradient_rows(x, true)
    }

    /// The position rows of [`Self::half_gradient`] (its first `positions()·p` entries), the
    /// same sums: for the optimal positions ([`crate::staircase::init::OptimalPositions`]),
    /// without the rotation rows' memory (15 MiB at 10⁶ poses, at Newton's peak).
    pub fn position_half_gradient(&self, x: &Point) -> Vec<c64> {
        self.half_gradient_rows(x, false)
    }

    /// [`Self::half_gradient`], or only its position rows.
    fn half_gradient_rows(&self, x: &Point, rotations: bool) -> Vec<c64> {
        let p = x.p;
        let rows = if rotations {
            x.x.len()
        } else {
            self.positions() * p
        };
        let mut g = vec![c64::new(0.0, 0.0); rows];
        let zero = vec![c64::new(0.0, 0.0); p];
        for t in &self.terms {
            let ri = self.position_row(t.i);
            let rj = self.head_position_row(t);
            let yi_row = self.rotation_row(t.i);
            let yj_row = self.head_rotation_row(t);
            for c in 0..p {
                let pi = ri.map_or(zero[c], |r| x.x[r * p + c]);
                let pj = rj.map_or(zero[c], |r| x.x[r * p + c]);
                let yi = x.x[yi_row * p + c];
                let et = (pj - pi - t.delta * yi) * t.tau;
                if let Some(r) = rj {
                    g[r * p + c] += et;
                }
                if let Some(r) = ri {
                    g[r * p + c] -= et;
                }
                if !rotations {
                    continue;
                }
                match yj_row {
                    Some(yj_row) => {
                        let yj = x.x[yj_row * p + c];
                        let er = (yj - t.rot * yi) * t.kappa;
                        g[yi_row * p + c] -= t.delta.conj() * et + t.rot.conj() * er;
                        g[yj_row * p + c] += er;
                    }
                    None => g[yi_row * p + c] -= t.delta.conj() * et,
                }
            }
        }
        g
    }

    /// f(X) and G = W̃X as [`Self::cost`] and [`Self::half_gradient`] compute them, each with a
    /// rigorous bound on its rounding error ([`crate::linalg::roundoff`]; the moduli in the bounds
    /// are [`crate::linalg::roundoff::modulus_bound`]'s upper bounds): the exact f and W̃X of the
    /// floating-point data (τ, κ, Δ, R of every edge and the entries of X) lie within them. The
    /// residuals P_j − P_i − ΔY_i and Y_j − RY_i are formed first, so the errors scale with the
    /// edges' residuals and lengths, not with how far the positions lie from the anchor.
    pub fn enclose(&self, x: &Point) -> Enclosure {
        // m(z) ≥ |z|, for the error terms alone ([`modulus_bound`]).
        use crate::linalg::roundoff::{U, gamma, modulus_bound as m};
        let p = x.p;
        let zero = c64::new(0.0, 0.0);
        let mut g = vec![zero; x.x.len()];
        let mut g_error = vec![0.0; x.x.len()];
        // Per entry of G: Σ|contributions| and their number, for the rounding of the sums.
        let mut magnitude = vec![0.0; x.x.len()];
        let mut count = vec![0usize; x.x.len()];
        let (mut cost, mut cost_error) = (0.0, 0.0);
        let mut add = |k: usize, v: c64, error: f64, g: &mut [c64]| {
            g[k] += v;
            g_error[k] += error;
            magnitude[k] += m(v);
            count[k] += 1;
        };
        for t in &self.terms {
            let ri = self.position_row(t.i);
            let rj = self.head_position_row(t);
            let yi_row = self.rotation_row(t.i);
            // An observation has no rotation part: its κ = 0 term is evaluated on y_j = R y_i
            // exactly (er = 0), and nothing is added to a head rotation it does not have.
            let yj_row = self.head_rotation_row(t);
            let (dn, rn) = (m(t.delta), m(t.rot));
            for c in 0..p {
                let pi = ri.map_or(zero, |r| x.x[r * p + c]);
                let pj = rj.map_or(zero, |r| x.x[r * p + c]);
                let yi = x.x[yi_row * p + c];
                let yj = yj_row.map_or(t.rot * yi, |r| x.x[r * p + c]);
                // Residuals: one rounding for P_j − P_i, √2γ₂ for each complex product, one
                // for the last subtraction (each component), all within 4u of the moduli.
                let d = pj - pi;
                let et = d - t.delta * yi;
                let er = if yj_row.is_some() {
                    yj - t.rot * yi
                } else {
                    zero
                };
                let det = 4.0 * U * (m(d) + dn * m(yi) + m(et));
                let der = if yj_row.is_some() {
                    4.0 * U * (m(yj) + rn * m(yi) + m(er))
                } else {
                    0.0
                };
                let (nt, nr) = (m(et), m(er));
                cost += t.tau * et.norm_sqr() + t.kappa * er.norm_sqr();
                cost_error += t.tau * ((2.0 * nt + det) * det + 4.0 * U * nt * nt)
                    + t.kappa * ((2.0 * nr + der) * der + 4.0 * U * nr * nr);
                let wt = et * t.tau;
                let wr = er * t.kappa;
                let (ewt, ewr) = (t.tau * (det + U * nt), t.kappa * (der + U * nr));
                if let Some(r) = rj {
                    add(r * p + c, wt, ewt, &mut g);
                }
                if let Some(r) = ri {
                    add(r * p + c, -wt, ewt, &mut g);
                }
                let back = t.delta.conj() * wt + t.rot.conj() * wr;
                let eback = dn * ewt + rn * ewr + 4.0 * U * (dn * m(wt) + rn * m(wr));
                add(yi_row * p + c, -back, eback, &mut g);
                if let Some(yj_row) = yj_row {
                    add(yj_row * p + c, wr, ewr, &mut g);
                }
            }
        }
        for k in 0..g.len() {
            g_error[k] += 2.0 * gamma(count[k] + 1) * magnitude[k];
        }
        cost_error += gamma(2 * self.terms.len() * p + 2) * cost;
        Enclosure {
            cost,
            cost_error,
            g,
            g_error,
        }
    }

    /// The multipliers λ_a = Re⟨Y_a, (W̃X)_a⟩ of the first-order conditions (Sec. 4.1, eq. (33)).
    pub fn multipliers(&self, x: &Point, g: &[c64]) -> Vec<f64> {
        let p = x.p;
        (0..self.n)
            .map(|a| {
                let r = self.rotation_row(a);
                dot(x.row(r), &g[r * p..(r + 1) * p]).re
            })
            .collect()
    }
}

/// f(X) and G = W̃X with bounds on their rounding errors ([`Problem::enclose`]):
/// |f − cost| ≤ cost_error and |G_k − g_k| ≤ g_error_k for the exact values.
#[derive(Debug, Clone)]
pub struct Enclosure {
    pub cost: f64,
    pub cost_error: f64,
    pub g: Vec<c64>,
    pub g_error: Vec<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, Pose2, SymMat3};
    use crate::problem::weights::{Weights, edge_weights};
    use faer::fx128;

    type Dd = fx128;

    fn dd(v: f64) -> Dd {
        Dd::from_f64(v)
    }

    /// A corridor: 2000 poses one metre apart along x, odometry with a small bias and a loop
    /// closure every 50 poses back to the pose 7 behind, so positions reach 2000 m from the anchor
    /// while every residual is about a centimetre.
    fn corridor() -> (Problem, Point) {
        let n = 2000;
        let mut edges = Vec::new();
        for k in 0..n - 1 {
            let wobble = 0.01 * ((k * 7919) % 13) as f64 / 13.0;
            edges.push(Edge {
                i: k,
                j: k + 1,
                measurement: Pose2::new(1.0 + wobble, 0.002, 0.001),
                noise: SymMat3::IDENTITY,
            });
            if k % 50 == 49 {
                edges.push(Edge {
                    i: k - 7,
                    j: k,
                    measurement: Pose2::new(7.0, 0.0, 0.0),
                    noise: SymMat3::IDENTITY,
                });
            }
        }
        let mut g = PoseGraph::with_edges(vec![Pose2::IDENTITY; n], edges);
        g.initialize_spanning_tree();
        let w = edge_weights(&g, Weights::Isotropic).unwrap();
        let problem = Problem::new(&g, &w);
        let x = (1..n)
            .map(|k| c64::new(g.poses[k].x, g.poses[k].y))
            .chain(
                g.poses
                    .iter()
                    .map(|p| c64::new(p.theta.cos(), p.theta.sin())),
            )
            .collect();
        (problem, Point { p: 1, x })
    }

    #[test]
    fn the_enclosure_contains_the_double_double_values_without_the_spread() {
        let (problem, x) = corridor();
        let e = problem.enclose(&x);
        // Reference: the same sums in double-double (qd, ~32 digits) from the same floats.
        let (mut f, mut g) = (dd(0.0), vec![(dd(0.0), dd(0.0)); x.x.len()]);
        let get =
            |k: Option<usize>| k.map_or((dd(0.0), dd(0.0)), |r| (dd(x.x[r].re), dd(x.x[r].im)));
        for t in &problem.terms {
            let (pi, pj) = (
                get(problem.position_row(t.i)),
                get(problem.position_row(t.j)),
            );
            let (ri, rj) = (problem.rotation_row(t.i), problem.rotation_row(t.j));
            let (yi, yj) = (
                (dd(x.x[ri].re), dd(x.x[ri].im)),
                (dd(x.x[rj].re), dd(x.x[rj].im)),
            );
            let mul = |a: (f64, f64), b: (Dd, Dd)| {
                (dd(a.0) * b.0 - dd(a.1) * b.1, dd(a.0) * b.1 + dd(a.1) * b.0)
            };
            let dy = mul((t.delta.re, t.delta.im), yi);
            let ry = mul((t.rot.re, t.rot.im), yi);
            let et = (pj.0 - pi.0 - dy.0, pj.1 - pi.1 - dy.1);
            let er = (yj.0 - ry.0, yj.1 - ry.1);
            f = f
                + dd(t.tau) * (et.0 * et.0 + et.1 * et.1)
                + dd(t.kappa) * (er.0 * er.0 + er.1 * er.1);
            let wt = (dd(t.tau) * et.0, dd(t.tau) * et.1);
            let wr = (dd(t.kappa) * er.0, dd(t.kappa) * er.1);
            let add = |g: &mut Vec<(Dd, Dd)>, k: usize, v: (Dd, Dd), s: f64| {
                g[k] = (g[k].0 + dd(s) * v.0, g[k].1 + dd(s) * v.1);
            };
            if let Some(r) = problem.position_row(t.j) {
                add(&mut g, r, wt, 1.0);
            }
            if let Some(r) = problem.position_row(t.i) {
                add(&mut g, r, wt, -1.0);
            }
            let back_t = mul((t.delta.re, -t.delta.im), wt);
            let back_r = mul((t.rot.re, -t.rot.im), wr);
            add(&mut g, ri, back_t, -1.0);
            add(&mut g, ri, back_r, -1.0);
            add(&mut g, rj, wr, 1.0);
        }
        let f_ref = f.0 + f.1;
        assert!(
            (e.cost - f_ref).abs() <= e.cost_error,
            "{} vs {f_ref} ± {}",
            e.cost,
            e.cost_error
        );
        for (k, (gk, (re, im))) in e.g.iter().zip(&g).enumerate() {
            let diff = ((gk.re - (re.0 + re.1)).powi(2) + (gk.im - (im.0 + im.1)).powi(2)).sqrt();
            assert!(diff <= e.g_error[k], "row {k}: {diff} > {}", e.g_error[k]);
        }
        // The bounds scale with the residuals, not with Σ W̃_kk|x_k|² (positions 2000 m out).
        let spread: f64 = problem
            .matrix
            .upper_entries()
            .filter(|(r, c, _)| r == c)
            .map(|(r, _, w)| w.re * x.x[r].norm_sqr())
            .sum();
        assert!(
            e.cost_error < 1e-12 * e.cost,
            "{} vs cost {}",
            e.cost_error,
            e.cost
        );
        assert!(
            crate::linalg::roundoff::U * spread > 1e3 * e.cost_error,
            "{spread}"
        );
    }
}
