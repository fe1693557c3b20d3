//! The SE(3) problem in SE-Sync's form (Rosen et al., IJRR 2019, eq. (1)-(11)): weights, the
//! data matrix Q over the rows of X = [t; Y] with one pose's translation anchored, and the cost
//! edge by edge.
//!
//! ```text
//! f(R, t) = Σ_(i,j)  κ_ij ‖R_j − R_i R̃_ij‖_F² + τ_ij ‖t_j − t_i − R_i t̃_ij‖²
//! ```
//!
//! Weights, side by side (both SE-Sync's rule; its reader `read_g2o_file`):
//!
//! | | τ (translation) | κ (rotation) |
//! |---|---|---|
//! | 2D (`EDGE_SE2`, 3x3 Ω) | 2 / tr(Ω_tt⁻¹) | Ω_θθ in ‖·‖_F² (pgo's complex form writes 2Ω_θθ·\|r_j − r_i R\|², the same number) |
//! | 3D (`EDGE_SE3:QUAT`, 6x6 Ω) | 3 / tr(Ω_tt⁻¹) | 3 / (2 tr(Ω_RR⁻¹)) |
//!
//! Ω_tt is the 3x3 translation block, Ω_RR the 3x3 block over the quaternion's vector part, as
//! SE-Sync reads it. With these weights f is SE-Sync's objective F = tr(Y M Yᵀ) (factor 1: its
//! reported optima, IJRR 2019 Table 2, are values of this f), as the planar f is.
//!
//! Layout of the rank-p form (SE-Sync's Problem 9 with pgo's anchoring, as the planar eq. (15)):
//! X ∈ ℝ^{N×p}, N = 4n − 1; rows 0..n−1 the translations t_i ∈ ℝ^p of every pose but the anchor
//! (whose translation is 0), rows n−1 + 3i + a (a = 0, 1, 2) the three rows of Y_iᵀ, Y_i ∈
//! St(3, p) (Y_iᵀY_i = I₃; at p = 3, Y_i = R_i). Then f(X) = tr(Xᵀ Q X) with Q real symmetric,
//! sparse (one 4x4 block per pose and per pair of adjacent poses): the translations kept, not
//! eliminated, as W̃ in 2D.

use crate::error::Error;
use crate::graph3::Graph3;
use crate::linalg::roundoff::{U, gamma};

/// The weights (τ, κ) of one 3D edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weight3 {
    pub tau: f64,
    pub kappa: f64,
}

/// SE-Sync's weights of every edge: τ = 3 / tr(Ω_tt⁻¹), κ = 3 / (2 tr(Ω_RR⁻¹)); with `unit`,
/// τ = κ = 1. An information block that is not positive definite is an error naming the edge.
pub fn weights3(graph: &Graph3, unit: bool) -> Result<Vec<Weight3>, Error> {
    graph
        .edges
        .iter()
        .map(|e| {
            if unit {
                return Ok(Weight3 {
                    tau: 1.0,
                    kappa: 1.0,
                });
            }
            let bad = |why: &str| {
                Error::Invalid(format!(
                    "edge {} -> {}: {why}, so it has no isotropic weights (use --weights unit)",
                    graph.ids[e.i], graph.ids[e.j]
                ))
            };
            let block =
                |at: usize| nalgebra::Matrix3::from_fn(|r, c| e.information.get(at + r, at + c));
            let trace_inverse = |at: usize| {
                block(at)
                    .cholesky()
                    .map(|c| c.inverse().trace())
                    .filter(|t| *t > 0.0)
            };
            let (Some(tt), Some(rr)) = (trace_inverse(0), trace_inverse(3)) else {
                return Err(bad("its information matrix is not positive definite"));
            };
            let tau = 3.0 / tt;
            let kappa = 3.0 / (2.0 * rr);
            if !(tau > 0.0 && kappa > 0.0 && tau.is_finite() && kappa.is_finite()) {
                return Err(bad(
                    "its information values give weights that are not finite",
                ));
            }
            Ok(Weight3 { tau, kappa })
        })
        .collect()
}

/// One edge's term of f (eq. (1) above) at poses given as read:
/// τ‖t_j − t_i − R_i t̃‖² + κ‖R_j − R_i R̃‖_F², evaluated directly with nalgebra (the viewer's
/// residual colours; the solver's cost is [`Problem3::cost`]).
pub fn edge_term(e: &crate::graph3::Edge3, w: Weight3, poses: &[crate::graph3::Pose3]) -> f64 {
    let (a, b) = (poses[e.i].to_isometry(), poses[e.j].to_isometry());
    let ra = a.rotation.to_rotation_matrix();
    let rb = b.rotation.to_rotation_matrix();
    let rz = e
        .measurement
        .rotation
        .unit_quaternion()
        .to_rotation_matrix();
    let tz = nalgebra::Vector3::from(e.measurement.translation);
    let dt = b.translation.vector - a.translation.vector - ra * tz;
    let dr = rb.matrix() - ra.matrix() * rz.matrix();
    w.tau * dt.norm_squared() + w.kappa * dr.norm_squared()
}

/// One edge's term: τ‖t_j − t_i − Y_i t̃‖² + κ‖Y_j − Y_i R̃‖_F².
#[derive(Debug, Clone, Copy)]
pub struct Term3 {
    pub i: usize,
    pub j: usize,
    /// t̃.
    pub t: [f64; 3],
    /// R̃, row-major (`r[a][b]` = R̃_ab), as computed from the file's quaternion.
    pub r: [[f64; 3]; 3],
    pub tau: f64,
    pub kappa: f64,
}

/// The problem of one connected 3D graph at any rank.
pub struct Problem3 {
    pub n: usize,
    /// The pose whose translation is fixed at 0.
    pub anchor: usize,
    pub terms: Vec<Term3>,
    /// The pairs of poses (u ≤ v) with a block of Q: every (u, u), then each adjacent pair once.
    pub pairs: Vec<(usize, usize)>,
    /// Q's 4x4 block of each pair over the local rows (0: translation, 1..4: Y's rows); for
    /// u = v the full symmetric block. Rows of the anchor's translation are zero.
    pub blocks: Vec<[[f64; 4]; 4]>,
    /// Σ_e |Q_e| in the same blocks (for the rounding of the assembly).
    pub abs_blocks: Vec<[[f64; 4]; 4]>,
    /// The largest number of edges at one pose.
    pub max_degree: usize,
    /// A fill-reducing rank of each pose ([`Problem3::pose_rank`]), computed at its first use.
    pose_rank: std::sync::OnceLock<Vec<usize>>,
    /// AMD's rank of each pose ([`Problem3::amd_pose_rank`]), computed at its first use.
    amd_rank: std::sync::OnceLock<Vec<usize>>,
}

/// A point of the rank-p form: N rows of p entries, row-major.
#[derive(Debug, Clone)]
pub struct Point3 {
    pub p: usize,
    pub x: Vec<f64>,
}

impl Point3 {
    pub fn row(&self, k: usize) -> &[f64] {
        &self.x[k * self.p..(k + 1) * self.p]
    }
    pub fn row_mut(&mut self, k: usize) -> &mut [f64] {
        &mut self.x[k * self.p..(k + 1) * self.p]
    }
}

/// f and the Euclidean half-gradient QX at a point, each with a bound on its rounding error
/// (Higham's γ_k on sums of absolute values), edge by edge.
pub struct Evaluation {
    pub cost: f64,
    pub cost_error: f64,
    /// QX, row-major N×p.
    pub qx: Vec<f64>,
    /// |fl(QX) − QX| entrywise at most this.
    pub qx_error: Vec<f64>,
    /// XᵀQX (p×p, row-major), from the residuals.
    pub xqx: Vec<f64>,
    pub xqx_error: Vec<f64>,
}

impl Problem3 {
    /// The problem of a connected graph, anchored at `anchor`.
    pub fn new(graph: &Graph3, weights: &[Weight3], anchor: usize) -> Self {
        let n = graph.num_poses();
        let terms: Vec<Term3> = graph
            .edges
            .iter()
            .zip(weights)
            .map(|(e, w)| {
                let m = e
                    .measurement
                    .rotation
                    .unit_quaternion()
                    .to_rotation_matrix();
                let m = m.matrix();
                Term3 {
                    i: e.i,
                    j: e.j,
                    t: e.measurement.translation,
                    r: [
                        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
                        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
                        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
                    ],
                    tau: w.tau,
                    kappa: w.kappa,
                }
            })
            .collect();
        let mut pairs: Vec<(usize, usize)> = (0..n).map(|k| (k, k)).collect();
        let mut others: Vec<(usize, usize)> = terms
            .iter()
            .filter(|t| t.i != t.j)
            .map(|t| (t.i.min(t.j), t.i.max(t.j)))
            .collect();
        others.sort_unstable();
        others.dedup();
        // Pair (u, u) at u; (u, v), u < v, at n + its rank among the sorted others.
        let index = |a: usize, b: usize| match a.cmp(&b) {
            std::cmp::Ordering::Equal => a,
            _ => {
                n + others
                    .binary_search(&(a.min(b), a.max(b)))
                    .expect("an edge's pair")
            }
        };
        let mut blocks = vec![[[0.0; 4]; 4]; n + others.len()];
        let mut abs_blocks = vec![[[0.0; 4]; 4]; n + others.len()];
        let mut degree = vec![0usize; n];
        // Adds v at (node a, local row la) × (node b, local row lb), both orientations, `ij` the
        // index of the term's pair (i, j).
        let mut add = |ij: usize, a: usize, la: usize, b: usize, lb: usize, v: f64| {
            let k = if a == b { a } else { ij };
            let (ra, rb) = if a <= b { (la, lb) } else { (lb, la) };
            blocks[k][ra][rb] += v;
            abs_blocks[k][ra][rb] += v.abs();
            if a == b && ra != rb {
                blocks[k][rb][ra] += v;
                abs_blocks[k][rb][ra] += v.abs();
            }
        };
        for t in &terms {
            degree[t.i] += 1;
            degree[t.j] += 1;
            let (i, j, tau, kappa) = (t.i, t.j, t.tau, t.kappa);
            let ij = index(i, j);
            // τ c cᵀ with c = e_{t_j} − e_{t_i} − Σ_a t̃_a e_{y_ia}.
            let c = [
                (j, 0, 1.0),
                (i, 0, -1.0),
                (i, 1, -t.t[0]),
                (i, 2, -t.t[1]),
                (i, 3, -t.t[2]),
            ];
            for x in 0..c.len() {
                for y in 0..c.len() {
                    let (na, la, va) = c[x];
                    let (nb, lb, vb) = c[y];
                    // Each unordered pair once: the closure adds both orientations.
                    if (na, la) < (nb, lb) || (na == nb && la == lb) {
                        add(ij, na, la, nb, lb, tau * va * vb);
                    }
                }
            }
            // κ Σ_b (e_{y_jb} − Σ_a R̃_ab e_{y_ia})(…)ᵀ.
            for b in 0..3 {
                add(ij, j, 1 + b, j, 1 + b, kappa);
                for a in 0..3 {
                    add(ij, i, 1 + a, j, 1 + b, -kappa * t.r[a][b]);
                }
            }
            for a in 0..3 {
                for a2 in a..3 {
                    let rr: f64 = (0..3).map(|b| t.r[a][b] * t.r[a2][b]).sum();
                    add(ij, i, 1 + a, i, 1 + a2, kappa * rr);
                }
            }
        }
        pairs.extend(others);
        // Anchor's translation row: absent.
        for (k, &(u, v)) in pairs.iter().enumerate() {
            for l in 0..4 {
                if u == anchor {
                    blocks[k][0][l] = 0.0;
                    abs_blocks[k][0][l] = 0.0;
                }
                if v == anchor {
                    blocks[k][l][0] = 0.0;
                    abs_blocks[k][l][0] = 0.0;
                }
            }
        }
        Problem3 {
            n,
            anchor,
            terms,
            pairs,
            blocks,
            abs_blocks,
            max_degree: degree.iter().copied().max().unwrap_or(0),
            pose_rank: std::sync::OnceLock::new(),
            amd_rank: std::sync::OnceLock::new(),
        }
    }

    /// AMD's rank of each pose of the pose graph ([`crate::linalg::factor::amd_pose_rank`]), for
    /// the factorizations of the start too cheap to wait for [`Problem3::pose_rank`]'s nested
    /// dissection (the chordal relaxation's and the projected refinement's, with 3 and 1 rows a
    /// pose): computed once, at the first call.
    pub fn amd_pose_rank(&self) -> &[usize] {
        self.amd_rank.get_or_init(|| {
            crate::linalg::factor::amd_pose_rank(self.n, self.terms.iter().map(|t| (t.i, t.j)))
        })
    }

    /// A fill-reducing rank of each pose ([`crate::linalg::factor::pose_rank`]), for the Newton
    /// systems and the certificate. Computed at the first call, on the thread that makes it: the
    /// helper that builds them ahead when there is a second core (its ordering, up to a nested
    /// dissection, then runs beside the chordal estimate).
    pub fn pose_rank(&self) -> &[usize] {
        self.pose_rank.get_or_init(|| {
            crate::linalg::factor::pose_rank(
                self.n,
                self.terms.iter().map(|t| (t.i, t.j)),
                crate::linalg::factor::SPATIAL_BLOCK_WORK,
            )
        })
    }

    /// N = 4n − 1.
    pub fn dim(&self) -> usize {
        4 * self.n - 1
    }

    /// The row of pose i's translation (`None` for the anchor).
    pub fn position_row(&self, i: usize) -> Option<usize> {
        use std::cmp::Ordering::*;
        match i.cmp(&self.anchor) {
            Less => Some(i),
            Equal => None,
            Greater => Some(i - 1),
        }
    }

    /// The row of Y_iᵀ's row a.
    pub fn rotation_row(&self, i: usize, a: usize) -> usize {
        self.n - 1 + 3 * i + a
    }

    /// The global row of node `u`'s local row `l` (0: translation, 1..4: rotation rows).
    pub fn local_row(&self, u: usize, l: usize) -> Option<usize> {
        if l == 0 {
            self.position_row(u)
        } else {
            Some(self.rotation_row(u, l - 1))
        }
    }

    /// The poses in a fill-reducing order ([`crate::linalg::factor::group_ordering`] by
    /// [`Problem3::pose_rank`]): the block order of the Newton systems and the certificate.
    pub fn pose_order(&self) -> Vec<usize> {
        crate::linalg::factor::group_ordering(self.pose_rank(), &(0..self.n).collect::<Vec<_>>())
    }

    /// The rows in a fill-reducing order, each pose's together in their own order (translation,
    /// then Y's rows): `order[new] = row`, [`Problem3::pose_order`] expanded to the rows.
    pub fn row_order(&self) -> Vec<usize> {
        crate::linalg::factor::group_ordering(self.pose_rank(), &self.row_pose())
    }

    /// The pose of each row.
    pub fn row_pose(&self) -> Vec<usize> {
        let mut g = vec![0; self.dim()];
        for i in 0..self.n {
            if let Some(r) = self.position_row(i) {
                g[r] = i;
            }
            for a in 0..3 {
                g[self.rotation_row(i, a)] = i;
            }
        }
        g
    }

    /// The upper triangle of Q (row ≤ col, each entry once, every diagonal entry and every
    /// pose's full 3x3 rotation block present), with Σ_e|Q_e| beside each value.
    pub fn upper(&self) -> Vec<(usize, usize, f64, f64)> {
        let mut out = Vec::new();
        for (k, &(u, v)) in self.pairs.iter().enumerate() {
            for la in 0..4 {
                for lb in 0..4 {
                    if u == v && lb < la {
                        continue;
                    }
                    let (Some(ra), Some(rb)) = (self.local_row(u, la), self.local_row(v, lb))
                    else {
                        continue;
                    };
                    out.push((
                        ra.min(rb),
                        ra.max(rb),
                        self.blocks[k][la][lb],
                        self.abs_blocks[k][la][lb],
                    ));
                }
            }
        }
        out
    }

    /// f, QX and XᵀQX edge by edge with rounding bounds.
    pub fn evaluate(&self, x: &Point3) -> Evaluation {
        let p = x.p;
        let dim = self.dim();
        let mut qx = vec![0.0; dim * p];
        let mut qabs = vec![0.0; dim * p];
        let mut xqx = vec![0.0; p * p];
        let mut xqx_abs = vec![0.0; p * p];
        let mut xqx_err = vec![0.0; p * p];
        let (mut cost, mut cost_abs, mut cost_err) = (0.0, 0.0, 0.0);
        let zero = vec![0.0; p];
        let g5 = gamma(6);
        let mut rt = vec![0.0; p];
        let mut at = vec![0.0; p];
        let mut rr = vec![0.0; 3 * p];
        let mut ar = vec![0.0; 3 * p];
        for t in &self.terms {
            let ti = self.position_row(t.i).map_or(&zero[..], |r| x.row(r));
            let tj = self.position_row(t.j).map_or(&zero[..], |r| x.row(r));
            let yi = |a: usize| x.row(self.rotation_row(t.i, a));
            let yj = |b: usize| x.row(self.rotation_row(t.j, b));
            for c in 0..p {
                let mut v = tj[c] - ti[c];
                let mut a_ = tj[c].abs() + ti[c].abs();
                for a in 0..3 {
                    v -= t.t[a] * yi(a)[c];
                    a_ += (t.t[a] * yi(a)[c]).abs();
                }
                rt[c] = v;
                at[c] = g5 * a_;
            }
            for b in 0..3 {
                for c in 0..p {
                    let mut v = yj(b)[c];
                    let mut a_ = v.abs();
                    for a in 0..3 {
                        v -= t.r[a][b] * yi(a)[c];
                        a_ += (t.r[a][b] * yi(a)[c]).abs();
                    }
                    rr[b * p + c] = v;
                    ar[b * p + c] = g5 * a_;
                }
            }
            // Cost and its error: |(r+δ)² − r²| ≤ 2|r|δ + δ².
            for c in 0..p {
                cost += t.tau * rt[c] * rt[c];
                cost_abs += t.tau * rt[c] * rt[c];
                cost_err += t.tau * (2.0 * rt[c].abs() * at[c] + at[c] * at[c]);
            }
            for k in 0..3 * p {
                cost += t.kappa * rr[k] * rr[k];
                cost_abs += t.kappa * rr[k] * rr[k];
                cost_err += t.kappa * (2.0 * rr[k].abs() * ar[k] + ar[k] * ar[k]);
            }
            // XᵀQX.
            for c in 0..p {
                for d in 0..p {
                    let mut v = t.tau * rt[c] * rt[d];
                    let mut e = t.tau * (rt[c].abs() * at[d] + at[c] * rt[d].abs() + at[c] * at[d]);
                    let mut a_ = v.abs();
                    for b in 0..3 {
                        let (x1, x2) = (rr[b * p + c], rr[b * p + d]);
                        let (e1, e2) = (ar[b * p + c], ar[b * p + d]);
                        v += t.kappa * x1 * x2;
                        a_ += (t.kappa * x1 * x2).abs();
                        e += t.kappa * (x1.abs() * e2 + e1 * x2.abs() + e1 * e2);
                    }
                    xqx[c * p + d] += v;
                    xqx_abs[c * p + d] += a_;
                    xqx_err[c * p + d] += e;
                }
            }
            // QX rows.
            let mut push = |row: usize, c: usize, v: f64, a_: f64| {
                qx[row * p + c] += v;
                qabs[row * p + c] += a_;
            };
            for c in 0..p {
                let (v, a_) = (t.tau * rt[c], t.tau * (rt[c].abs() + at[c]));
                if let Some(r) = self.position_row(t.j) {
                    push(r, c, v, a_);
                }
                if let Some(r) = self.position_row(t.i) {
                    push(r, c, -v, a_);
                }
                for b in 0..3 {
                    let (v, a_) = (
                        t.kappa * rr[b * p + c],
                        t.kappa * (rr[b * p + c].abs() + ar[b * p + c]),
                    );
                    push(self.rotation_row(t.j, b), c, v, a_);
                }
                for a in 0..3 {
                    let mut v = -t.tau * t.t[a] * rt[c];
                    let mut a_ = t.tau * t.t[a].abs() * (rt[c].abs() + at[c]);
                    for b in 0..3 {
                        v -= t.kappa * t.r[a][b] * rr[b * p + c];
                        a_ += t.kappa * t.r[a][b].abs() * (rr[b * p + c].abs() + ar[b * p + c]);
                    }
                    push(self.rotation_row(t.i, a), c, v, a_);
                }
            }
        }
        let sums = gamma(4 * self.max_degree + 16);
        let qx_error = qabs.iter().map(|a| sums * a).collect();
        let m = self.terms.len() * (3 * p + p + 4) + 4;
        let cost_error = (cost_err + gamma(m) * cost_abs) * (1.0 + 4.0 * U);
        let xqx_error = xqx_err
            .iter()
            .zip(&xqx_abs)
            .map(|(e, a)| (e + gamma(self.terms.len() * 4 + 8) * a) * (1.0 + 4.0 * U))
            .collect();
        Evaluation {
            cost,
            cost_error,
            qx,
            qx_error,
            xqx,
            xqx_error,
        }
    }

    /// f alone, edge by edge.
    pub fn cost(&self, x: &Point3) -> f64 {
        let p = x.p;
        let zero = vec![0.0; p];
        let mut cost = 0.0;
        for t in &self.terms {
            let ti = self.position_row(t.i).map_or(&zero[..], |r| x.row(r));
            let tj = self.position_row(t.j).map_or(&zero[..], |r| x.row(r));
            let yi = |a: usize| x.row(self.rotation_row(t.i, a));
            for c in 0..p {
                let mut v = tj[c] - ti[c];
                for a in 0..3 {
                    v -= t.t[a] * yi(a)[c];
                }
                cost += t.tau * v * v;
            }
            for b in 0..3 {
                let yj = x.row(self.rotation_row(t.j, b));
                for c in 0..p {
                    let mut v = yj[c];
                    for a in 0..3 {
                        v -= t.r[a][b] * yi(a)[c];
                    }
                    cost += t.kappa * v * v;
                }
            }
        }
        cost
    }

    /// Λ_i = sym(G_i X_iᵀ) (3x3, row-major) for G = QX: the multipliers of the first-order
    /// conditions (SE-Sync eq. (48), Λ = SymBlockDiag(XᵀQX) in its layout).
    pub fn multipliers(&self, x: &Point3, qx: &[f64]) -> Vec<[[f64; 3]; 3]> {
        let p = x.p;
        (0..self.n)
            .map(|i| {
                let mut l = [[0.0; 3]; 3];
                for a in 0..3 {
                    for b in 0..3 {
                        let ra = self.rotation_row(i, a);
                        let rb = self.rotation_row(i, b);
                        let g = &qx[ra * p..(ra + 1) * p];
                        l[a][b] = g.iter().zip(x.row(rb)).map(|(u, v)| u * v).sum::<f64>();
                    }
                }
                for a in 0..3 {
                    for b in a + 1..3 {
                        let s = 0.5 * (l[a][b] + l[b][a]);
                        l[a][b] = s;
                        l[b][a] = s;
                    }
                }
                l
            })
            .collect()
    }

    /// Q's τ-weighted Laplacian over the translations (anchored): upper-triangle entries.
    pub fn laplacian(&self) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::new();
        for (k, &(u, v)) in self.pairs.iter().enumerate() {
            if let (Some(a), Some(b)) = (self.position_row(u), self.position_row(v)) {
                out.push((a.min(b), a.max(b), self.blocks[k][0][0]));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::space::{SpaceConfig, World3, simulate3};
    use crate::simulate::{RotationNoise, TranslationNoise};

    /// The anchor has no translation row: every block of a pair with the anchor, off the
    /// diagonal too, holds zeros there (in `abs_blocks` as well), whichever pose is anchored;
    /// and each pair's block sits at its pair's index.
    #[test]
    fn the_anchors_translation_row_is_absent_from_every_block() {
        let graph = simulate3(&SpaceConfig {
            world: World3::Sphere,
            n: 30,
            side: 5.0,
            loop_probability: 0.5,
            rotation_noise: RotationNoise::Gaussian { sigma: 0.05 },
            translation_noise: TranslationNoise::Gaussian { sigma: 0.05 },
            seed: 4,
        })
        .graph;
        let weights = weights3(&graph, false).unwrap();
        for anchor in [0, 7, 29] {
            let problem = Problem3::new(&graph, &weights, anchor);
            let mut off_diagonal = 0;
            for (k, &(u, v)) in problem.pairs.iter().enumerate() {
                assert!(u <= v && (k >= problem.n || (u, v) == (k, k)));
                for l in 0..4 {
                    if u == anchor {
                        assert_eq!(problem.blocks[k][0][l], 0.0);
                        assert_eq!(problem.abs_blocks[k][0][l], 0.0);
                    }
                    if v == anchor {
                        assert_eq!(problem.blocks[k][l][0], 0.0);
                        assert_eq!(problem.abs_blocks[k][l][0], 0.0);
                    }
                }
                off_diagonal += usize::from(u != v && (u == anchor || v == anchor));
            }
            assert!(off_diagonal >= 1, "anchor {anchor}");
        }
    }
}
