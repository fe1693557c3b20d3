//! Marginal covariances of the poses at an estimate (what `pgo-solve --refine --marginals OUT`
//! writes): the 3x3 diagonal blocks of the inverse of the Gauss-Newton information matrix
//! H = Σ_e J_eᵀ Ω_e J_e, each pose's covariance in its tangent space, GTSAM's convention, so that
//! the numbers are those of GTSAM's `Marginals` on the same graph and estimate.
//!
//! **Tangent space.** A pose x = (t, θ) is perturbed on the right, in its body frame, by GTSAM's
//! `Pose2::Retract`, which is `Pose2::Expmap` (checked on PyPI gtsam 4.3: `x.retract(v)` equals
//! `x.compose(Pose2.Expmap(v))`): x ⊕ δ = x · Exp(δ), δ = [δx, δy, δθ] (translation first). The
//! covariance Σ_x of a pose is that of δ. (At δ = 0 the chart `Pose2(v[0], v[1], v[2])` has the
//! same derivative as Exp, so Σ_x would be the same under it.)
//!
//! **Factors.** Each edge (i, j) with measurement z and information Ω (the file's full matrix,
//! [`PoseGraph::information`]) is GTSAM's `BetweenFactor<Pose2>`: error
//! e = Log(z⁻¹ · h), h = x_i⁻¹ x_j, with the exact Jacobians in the coordinates above:
//!
//! ```text
//! ∂e/∂δ_j = J_r⁻¹(e)        ∂e/∂δ_i = −J_r⁻¹(e) · Ad(h⁻¹)        Ad(x, y, θ) = [ R(θ)  (y, −x)ᵀ ]
//!                                                                              [ 0        1    ]
//! J_r(ρ, w) = [  a    w c₂   ρ₁ c₁ − ρ₂ c₂ ]    a = sin w / w,  c₁ = (w − sin w)/w²,
//!             [ −w c₂  a     ρ₁ c₂ + ρ₂ c₁ ]    c₂ = (1 − cos w)/w²   (series below |w| = 10⁻²)
//!             [  0     0          1        ]
//! ```
//!
//! (J_r the right Jacobian of SE(2) at e = (ρ, w), Solà, Deray, Atchuthan, "A micro Lie theory
//! for state estimation in robotics", 2018, eq. (163)); these are GTSAM 4.3's linearization of
//! `BetweenFactorPose2`, computed to full accuracy: GTSAM's own `Pose2::LogmapDerivative` loses
//! digits at small residual angles (3e-6 absolute at w = 1e-4, w/2 below 1e-5, against 60-digit
//! arithmetic), so its stock factor's marginals differ from these by up to 1e-5 relative on
//! refined estimates (M3500), and by ~1e-11 with exact Jacobians. g2o's error toVector(z⁻¹ h) differs from Log(z⁻¹ h) at
//! second order in e, so at a refined estimate with nonzero residuals H is GTSAM's, not the
//! Hessian of g2o's chi2 in these coordinates; both agree where the residuals vanish.
//!
//! **Gauge.** The held poses (the graph's FIX poses, else the first pose of each connected
//! component: [`gauge`], as [`refine`](super::refine) holds them) are constants: H is over the
//! free poses only, and a held pose's covariance is zero. GTSAM instead adds a prior of
//! information σ⁻² I on the held pose; its marginals tend to these as σ → 0, the free poses'
//! covariances differing by O(σ² ‖H‖) relative (the Schur complement of the prior's block).
//!
//! **Sparse inverse subset.** With H's sparse Cholesky factor P H Pᵀ = L Lᵀ (AMD order P), written
//! as L̃ D L̃ᵀ (L̃ = L diag(L)⁻¹, D = diag(L)²), Z = (P H Pᵀ)⁻¹ satisfies Z = D⁻¹ L̃⁻¹ + (I − L̃ᵀ) Z,
//! so for i ≥ j (Takahashi, Fagan & Chen, "Formation of a sparse bus impedance matrix and its
//! application to short circuit study", PICA 1973; Golub & Plemmons 1980)
//!
//! ```text
//! Z_ij = δ_ij / d_j − Σ_{k > j, L_kj ≠ 0} L̃_kj Z_ki
//! ```
//!
//! and, columns j taken from last to first, the entries of Z on the pattern of L (filled) need
//! only entries of Z on that pattern: the rows k of column j form a clique of the filled graph.
//! A pose's three rows are a dense block of H, hence on the pattern, so its 3x3 block of H⁻¹ is
//! read there. The work is Σ_j c_j² lookups over the columns of L (c_j entries below the
//! diagonal), of the order of one more factorization; no dense inverse is formed. All runs
//! sequentially: the output does not depend on the thread count.
//!
//! Landmarks are not handled: graphs with landmark observations are refused.

use super::levenberg_marquardt::gauge;
use crate::graph::{Pose2, PoseGraph, SymMat3};
use crate::linalg::factor::{Assembly, Layout, SparseFactor};
use crate::simulate::wrap_angle;
use thiserror::Error;

/// What [`marginals`] refuses.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MarginalsError {
    #[error("{found} poses given for a graph of {expected} poses")]
    PoseCount { expected: usize, found: usize },
    #[error("marginal covariances of graphs with landmarks are not implemented")]
    Landmarks,
    #[error("{what} refers to pose index {index}, out of 0..{n}")]
    IndexOutOfRange {
        what: String,
        index: usize,
        n: usize,
    },
    #[error("pose of vertex {id} is not finite")]
    NonFinitePose { id: crate::graph::VertexId },
    #[error("edge {edge}: the measurement or the information matrix is not finite or singular")]
    BadEdge { edge: usize },
    #[error(
        "the information matrix J^T Omega J of the free poses is not positive definite (a pose is not determined by the measurements)"
    )]
    NotPositiveDefinite,
}

impl From<MarginalsError> for crate::Error {
    fn from(e: MarginalsError) -> Self {
        crate::Error::Invalid(e.to_string())
    }
}

type Mat3 = [[f64; 3]; 3];

/// The covariance of every pose of `graph` at `poses` (module docs: tangent convention, factors,
/// gauge), in the graph's pose order, as the upper triangle `[c11, c12, c13, c22, c23, c33]` over
/// (δx, δy, δθ); zero for the held poses ([`gauge`]).
///
/// # Errors
///
/// A wrong number of poses, indices out of range, non-finite poses, measurements or information
/// matrices, a singular covariance, landmarks, or an H that is not numerically positive definite.
pub fn marginals(graph: &PoseGraph, poses: &[Pose2]) -> Result<Vec<SymMat3>, MarginalsError> {
    marginals_with(graph, poses, Layout::Auto)
}

/// [`marginals`] with the factor stored as `layout` (`Auto`: faer's choice after AMD; the others
/// in the identity order, for the tests of both storages).
fn marginals_with(
    graph: &PoseGraph,
    poses: &[Pose2],
    layout: Layout,
) -> Result<Vec<SymMat3>, MarginalsError> {
    let n = graph.num_poses();
    if !graph.landmarks.observations.is_empty() || !graph.landmarks.is_empty() {
        return Err(MarginalsError::Landmarks);
    }
    if poses.len() != n {
        return Err(MarginalsError::PoseCount {
            expected: n,
            found: poses.len(),
        });
    }
    for (k, e) in graph.edges.iter().enumerate() {
        if let Some(&index) = [e.i, e.j].iter().find(|&&v| v >= n) {
            return Err(MarginalsError::IndexOutOfRange {
                what: format!("edge {k}"),
                index,
                n,
            });
        }
    }
    if let Some(&index) = graph.fixed.iter().find(|&&v| v >= n) {
        return Err(MarginalsError::IndexOutOfRange {
            what: "a FIX line".into(),
            index,
            n,
        });
    }
    if let Some(k) = poses
        .iter()
        .position(|p| !p.values().iter().all(|v| v.is_finite()))
    {
        return Err(MarginalsError::NonFinitePose { id: graph.ids[k] });
    }
    let mut block = vec![usize::MAX; n];
    let held = gauge(graph);
    let mut free = 0;
    for (k, b) in block.iter_mut().enumerate() {
        if held.binary_search(&k).is_err() {
            *b = free;
            free += 1;
        }
    }
    let mut out = vec![SymMat3([0.0; 6]); n];
    if free == 0 {
        return Ok(out);
    }
    let dim = 3 * free;
    // H's upper triangle as (row, col) entries with their values (duplicates add up).
    let mut entries = Vec::with_capacity(6 * free + 9 * graph.edges.len());
    let mut values = Vec::with_capacity(entries.capacity());
    for b in 0..free {
        for c in 0..3 {
            for r in 0..=c {
                entries.push((3 * b + r, 3 * b + c));
                values.push(0.0);
            }
        }
    }
    for (k, e) in graph.edges.iter().enumerate() {
        let omega = graph
            .information(e)
            .map(|m| {
                let [a, b, c, d, e, f] = m.0;
                [[a, b, c], [b, d, e], [c, e, f]]
            })
            .filter(|m| m.iter().flatten().all(|v| v.is_finite()))
            .filter(|_| e.measurement.values().iter().all(|v| v.is_finite()))
            .ok_or(MarginalsError::BadEdge { edge: k })?;
        let (bi, bj) = (block[e.i], block[e.j]);
        if e.i == e.j || (bi == usize::MAX && bj == usize::MAX) {
            continue; // a self-loop's error is constant; held poses have no variables
        }
        let (ji, jj) = between_jacobians(&poses[e.i], &poses[e.j], &e.measurement);
        let oji = mul(&omega, &ji);
        let ojj = mul(&omega, &jj);
        for (b, jac, ojac) in [(bi, &ji, &oji), (bj, &jj, &ojj)] {
            if b == usize::MAX {
                continue;
            }
            let h = at_b(jac, ojac);
            for c in 0..3 {
                for (r, hr) in h.iter().enumerate().take(c + 1) {
                    values[6 * b + c * (c + 1) / 2 + r] += hr[c];
                }
            }
        }
        if bi != usize::MAX && bj != usize::MAX {
            let hij = at_b(&ji, &ojj);
            for (r, row) in hij.iter().enumerate() {
                for (c, &v) in row.iter().enumerate() {
                    let (a, b) = (3 * bi + r, 3 * bj + c);
                    entries.push((a.min(b), a.max(b)));
                    values.push(v);
                }
            }
        }
    }
    let mut h = Assembly::new(dim, &entries);
    h.fill(&values);
    let mut factor = match layout {
        Layout::Auto => SparseFactor::<f64>::analyze(h.matrix.symbolic()),
        _ => {
            let identity: Vec<usize> = (0..dim).collect();
            SparseFactor::analyze_ordered(h.matrix.symbolic(), &identity, layout)
        }
    };
    factor
        .llt(h.matrix.as_ref())
        .map_err(|_| MarginalsError::NotPositiveDefinite)?;
    let z = SparseInverse::new(&factor);
    let order = factor.order();
    let mut position = vec![0; dim];
    for (new, &old) in order.iter().enumerate() {
        position[old] = new;
    }
    for (k, &b) in block.iter().enumerate() {
        if b == usize::MAX {
            continue;
        }
        let q = [position[3 * b], position[3 * b + 1], position[3 * b + 2]];
        let at = |r: usize, c: usize| z.get(q[r], q[c]).expect("a pose's block is on the pattern");
        out[k] = SymMat3([at(0, 0), at(0, 1), at(0, 2), at(1, 1), at(1, 2), at(2, 2)]);
    }
    Ok(out)
}

/// The entries of Z = (P H Pᵀ)⁻¹ on the pattern of the Cholesky factor (Takahashi's recurrence,
/// module docs), stored like L: per column j, the rows below the diagonal ascending.
pub struct SparseInverse {
    col_ptr: Vec<usize>,
    rows: Vec<usize>,
    values: Vec<f64>,
    diag: Vec<f64>,
}

impl SparseInverse {
    /// From a successful LLᵀ of `factor`.
    pub fn new(factor: &SparseFactor<f64>) -> Self {
        let n = factor.dim();
        let mut col_ptr = vec![0usize; n + 1];
        let mut rows = Vec::new();
        let mut lt = Vec::new();
        let mut d = vec![0.0; n];
        // L̃ = L diag(L)⁻¹ and D = diag(L)², column by column (the visit is in column order).
        factor.visit_llt_columns(|j, r, v| {
            d[j] = v[0] * v[0];
            rows.extend_from_slice(&r[1..]);
            lt.extend(v[1..].iter().map(|l| l / v[0]));
            col_ptr[j + 1] = rows.len();
        });
        let mut z = SparseInverse {
            col_ptr,
            rows,
            values: vec![0.0; lt.len()],
            diag: vec![0.0; n],
        };
        let mut acc = Vec::new();
        for j in (0..n).rev() {
            let (s, e) = (z.col_ptr[j], z.col_ptr[j + 1]);
            let k = e - s;
            acc.clear();
            acc.resize(k, 0.0);
            // acc[t] = Σ_u L̃_{r_u j} Z_{r_t r_u}: each pair (t < u) read once, used twice.
            for t in 0..k {
                let rt = z.rows[s + t];
                let lt_t = lt[s + t];
                acc[t] += lt_t * z.diag[rt];
                let (cs, ce) = (z.col_ptr[rt], z.col_ptr[rt + 1]);
                let mut lo = cs;
                for u in t + 1..k {
                    let ru = z.rows[s + u];
                    // Rows r_u > r_t of column j are rows of column r_t (a clique of the filled
                    // graph), ascending: search forward from the last hit, which is mostly the
                    // next row (within a supernode the structures coincide).
                    let p = if lo < ce && z.rows[lo] == ru {
                        lo
                    } else {
                        lo + z.rows[lo..ce]
                            .binary_search(&ru)
                            .expect("column j's rows below r_t are in column r_t")
                    };
                    lo = p + 1;
                    let zv = z.values[p];
                    acc[t] += lt[s + u] * zv;
                    acc[u] += lt_t * zv;
                }
            }
            let mut dj = 1.0 / d[j];
            for t in 0..k {
                z.values[s + t] = -acc[t];
                dj += lt[s + t] * acc[t];
            }
            z.diag[j] = dj;
        }
        z
    }

    /// Z_ab, if (a, b) is on the pattern of the factor.
    pub fn get(&self, a: usize, b: usize) -> Option<f64> {
        if a == b {
            return self.diag.get(a).copied();
        }
        let (c, r) = (a.min(b), a.max(b));
        let (s, e) = (*self.col_ptr.get(c)?, *self.col_ptr.get(c + 1)?);
        self.rows[s..e]
            .binary_search(&r)
            .ok()
            .map(|p| self.values[s + p])
    }
}

/// ∂e/∂δ_i and ∂e/∂δ_j of GTSAM's `BetweenFactor<Pose2>` error e = Log(z⁻¹ x_i⁻¹ x_j) (module
/// docs).
pub fn between_jacobians(xi: &Pose2, xj: &Pose2, z: &Pose2) -> (Mat3, Mat3) {
    let (si, ci) = xi.theta.sin_cos();
    let (dx, dy) = (xj.x - xi.x, xj.y - xi.y);
    // h = x_i⁻¹ x_j.
    let th = [ci * dx + si * dy, -si * dx + ci * dy];
    let wh = xj.theta - xi.theta;
    // d = z⁻¹ h.
    let (sz, cz) = z.theta.sin_cos();
    let (ux, uy) = (th[0] - z.x, th[1] - z.y);
    let td = [cz * ux + sz * uy, -sz * ux + cz * uy];
    let w = wrap_angle(wh - z.theta);
    let (sw, cw) = w.sin_cos();
    let (a, c1, c2) = if w.abs() < 1e-2 {
        let w2 = w * w;
        (
            1.0 - w2 / 6.0 * (1.0 - w2 / 20.0 * (1.0 - w2 / 42.0)),
            w / 6.0 * (1.0 - w2 / 20.0 * (1.0 - w2 / 42.0 * (1.0 - w2 / 72.0))),
            0.5 * (1.0 - w2 / 12.0 * (1.0 - w2 / 30.0 * (1.0 - w2 / 56.0))),
        )
    } else {
        (sw / w, (w - sw) / (w * w), (1.0 - cw) / (w * w))
    };
    let b = w * c2;
    // ρ = V⁻¹ t_d with V = [[a, −b], [b, a]] (the translation part of Exp).
    let det = a * a + b * b;
    let rho = [
        (a * td[0] + b * td[1]) / det,
        (-b * td[0] + a * td[1]) / det,
    ];
    // J_r = [[A, v], [0, 1]], A = [[a, b], [−b, a]]; J_r⁻¹ = [[A⁻¹, −A⁻¹ v], [0, 1]].
    let v = [rho[0] * c1 - rho[1] * c2, rho[0] * c2 + rho[1] * c1];
    let ainv = [[a / det, -b / det], [b / det, a / det]];
    let jj = [
        [
            ainv[0][0],
            ainv[0][1],
            -(ainv[0][0] * v[0] + ainv[0][1] * v[1]),
        ],
        [
            ainv[1][0],
            ainv[1][1],
            -(ainv[1][0] * v[0] + ainv[1][1] * v[1]),
        ],
        [0.0, 0.0, 1.0],
    ];
    // Ad(h⁻¹), h⁻¹ = (−R(w_h)ᵀ t_h, −w_h).
    let (sh, ch) = wh.sin_cos();
    let hinv = [-(ch * th[0] + sh * th[1]), -(-sh * th[0] + ch * th[1])];
    let ad = [[ch, sh, hinv[1]], [-sh, ch, -hinv[0]], [0.0, 0.0, 1.0]];
    let m = mul(&jj, &ad);
    let ji = m.map(|row| row.map(|x| -x));
    (ji, jj)
}

fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c];
        }
    }
    m
}

/// aᵀ b for 3x3 matrices.
fn at_b(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = a[0][r] * b[0][c] + a[1][r] * b[1][c] + a[2][r] * b[2][c];
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::Edge;
    use crate::problem::matrix::tests::{Rng, graph, random_poses};

    /// SE(2)'s Exp: (V(w) ρ, w), V = [[a, −b], [b, a]].
    fn exp(v: [f64; 3]) -> Pose2 {
        let w = v[2];
        let (a, b) = if w == 0.0 {
            (1.0, 0.0)
        } else {
            (w.sin() / w, (1.0 - w.cos()) / w)
        };
        Pose2::new(a * v[0] - b * v[1], b * v[0] + a * v[1], w)
    }

    fn compose(x: &Pose2, y: &Pose2) -> Pose2 {
        Pose2::from_isometry(&(x.to_isometry() * y.to_isometry()))
    }

    /// Log by Newton on Exp (independent of the closed form used by the code).
    fn log(p: &Pose2) -> [f64; 3] {
        let w = wrap_angle(p.theta);
        let mut v = [p.x, p.y, w];
        for _ in 0..50 {
            let q = exp(v);
            // Exp is linear in ρ for fixed w: solve the 2x2 system exactly.
            let ex = exp([1.0, 0.0, w]);
            let ey = exp([0.0, 1.0, w]);
            let det = ex.x * ey.y - ey.x * ex.y;
            let (rx, ry) = (p.x - q.x, p.y - q.y);
            v[0] += (ey.y * rx - ey.x * ry) / det;
            v[1] += (-ex.y * rx + ex.x * ry) / det;
        }
        v
    }

    fn error(xi: &Pose2, xj: &Pose2, z: &Pose2) -> [f64; 3] {
        let d = z
            .to_isometry()
            .inv_mul(&xi.to_isometry().inv_mul(&xj.to_isometry()));
        log(&Pose2::from_isometry(&d))
    }

    #[test]
    fn jacobians_are_the_derivatives_of_the_log_error_under_right_exp() {
        let mut rng = Rng(5);
        for _ in 0..50 {
            let p = random_poses(3, &mut rng);
            let (xi, xj, mut z) = (p[0], p[1], p[2]);
            if rng.next() < 0.3 {
                // Small residual angles: the series branch.
                let h = Pose2::from_isometry(&xi.to_isometry().inv_mul(&xj.to_isometry()));
                z = Pose2::new(h.x + 0.3, h.y - 0.2, h.theta + rng.range(-1e-3, 1e-3));
            }
            let (ji, jj) = between_jacobians(&xi, &xj, &z);
            let h = 1e-6;
            for c in 0..3 {
                let mut d = [0.0; 3];
                for (which, jac) in [(0, &ji), (1, &jj)] {
                    d[c] = h;
                    let plus = |s: f64| {
                        let step = exp(d.map(|v| s * v));
                        if which == 0 {
                            error(&compose(&xi, &step), &xj, &z)
                        } else {
                            error(&xi, &compose(&xj, &step), &z)
                        }
                    };
                    let (ep, em) = (plus(1.0), plus(-1.0));
                    for r in 0..3 {
                        let fd = (ep[r] - em[r]) / (2.0 * h);
                        assert!(
                            (fd - jac[r][c]).abs() < 1e-6,
                            "{which} {r} {c}: {fd} {jac:?}"
                        );
                    }
                    d[c] = 0.0;
                }
            }
        }
    }

    fn two_pose_graph(z: Pose2, info: SymMat3) -> PoseGraph {
        PoseGraph::with_edges(
            vec![Pose2::new(1.0, 2.0, 0.5), Pose2::new(3.0, -1.0, 2.0)],
            vec![Edge {
                i: 0,
                j: 1,
                measurement: z,
                noise: info,
            }],
        )
    }

    #[test]
    fn two_poses_without_residual_by_hand() {
        // e = 0: J_j = I, so H = Ω and Σ_1 = Ω⁻¹; pose 0 is held.
        let g0 = two_pose_graph(Pose2::new(0.0, 0.0, 0.0), SymMat3::IDENTITY);
        let h = Pose2::from_isometry(
            &g0.poses[0]
                .to_isometry()
                .inv_mul(&g0.poses[1].to_isometry()),
        );
        let g = two_pose_graph(h, SymMat3([4.0, 0.0, 0.0, 9.0, 0.0, 16.0]));
        let m = marginals(&g, &g.poses).unwrap();
        assert_eq!(m[0].0, [0.0; 6]);
        let want = [0.25, 0.0, 0.0, 1.0 / 9.0, 0.0, 0.0625];
        for (a, b) in m[1].0.iter().zip(want) {
            assert!((a - b).abs() < 1e-15, "{:?}", m[1]);
        }
    }

    #[test]
    fn chain_without_residual_propagates_by_the_adjoint() {
        // x0 (held) - x1 - x2, exact measurements: Σ_2 = Ad(h₁₂⁻¹) Σ_1 Ad(h₁₂⁻¹)ᵀ + Ω₁₂⁻¹ with
        // Σ_1 = Ω₀₁⁻¹, the covariance of a composition in body-frame coordinates.
        let x = [
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(2.0, 1.0, 0.7),
            Pose2::new(3.0, 4.0, -1.2),
        ];
        let rel =
            |a: &Pose2, b: &Pose2| Pose2::from_isometry(&a.to_isometry().inv_mul(&b.to_isometry()));
        let edge = |i: usize, j: usize, d: f64| Edge {
            i,
            j,
            measurement: rel(&x[i], &x[j]),
            noise: SymMat3([1.0 / d, 0.0, 0.0, 1.0 / d, 0.0, 1.0 / (d * d)]),
        };
        let g = PoseGraph::with_edges(x.to_vec(), vec![edge(0, 1, 0.5), edge(1, 2, 0.25)]);
        let m = marginals(&g, &g.poses).unwrap();
        let h = rel(&x[1], &x[2]);
        let (s, c) = (-h.theta).sin_cos();
        let hinv = Pose2::from_isometry(&h.to_isometry().inverse());
        let ad = [[c, -s, hinv.y], [s, c, -hinv.x], [0.0, 0.0, 1.0]];
        let s1 = [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.25]];
        let mut want = [[0.0; 3]; 3];
        for r in 0..3 {
            for q in 0..3 {
                for a in 0..3 {
                    for b in 0..3 {
                        want[r][q] += ad[r][a] * s1[a][b] * ad[q][b];
                    }
                }
            }
        }
        want[0][0] += 0.25;
        want[1][1] += 0.25;
        want[2][2] += 0.0625;
        let got = m[2].0;
        let w = [
            want[0][0], want[0][1], want[0][2], want[1][1], want[1][2], want[2][2],
        ];
        for (a, b) in got.iter().zip(w) {
            assert!((a - b).abs() < 1e-14, "{got:?} {w:?}");
        }
    }

    /// Gauss-Jordan inverse with partial pivoting.
    fn dense_inverse(mut a: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        let n = a.len();
        let mut inv: Vec<Vec<f64>> = (0..n)
            .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
            .collect();
        for c in 0..n {
            let p = (c..n)
                .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
                .unwrap();
            a.swap(c, p);
            inv.swap(c, p);
            let d = a[c][c];
            for k in 0..n {
                a[c][k] /= d;
                inv[c][k] /= d;
            }
            for r in 0..n {
                if r != c {
                    let f = a[r][c];
                    for k in 0..n {
                        a[r][k] -= f * a[c][k];
                        inv[r][k] -= f * inv[c][k];
                    }
                }
            }
        }
        inv
    }

    #[test]
    fn sparse_inverse_subset_equals_the_dense_inverse() {
        let mut rng = Rng(11);
        // The last: dense enough for faer's supernodal layout (dense blocks of columns).
        for (n, fixed, loops) in [(25, vec![], 1), (40, vec![7usize, 30], 1), (150, vec![], 6)] {
            let truth = random_poses(n, &mut rng);
            let extra: Vec<(usize, usize)> = (0..loops * n)
                .map(|_| {
                    let i = (rng.next() * n as f64) as usize % n;
                    let j = (rng.next() * n as f64) as usize % n;
                    (i, j)
                })
                .filter(|(i, j)| i != j)
                .collect();
            let mut g = graph(&truth, &extra, 0.1, &mut rng);
            g.fixed = fixed;
            // An estimate off the measurements: nonzero residuals everywhere.
            let poses: Vec<Pose2> = truth
                .iter()
                .map(|p| Pose2::new(p.x + rng.range(-0.1, 0.1), p.y, p.theta + 0.05))
                .collect();
            let held = gauge(&g);
            let free: Vec<usize> = (0..n).filter(|k| !held.contains(k)).collect();
            let mut at = vec![usize::MAX; n];
            for (b, &k) in free.iter().enumerate() {
                at[k] = b;
            }
            let dim = 3 * free.len();
            let mut h = vec![vec![0.0; dim]; dim];
            for e in &g.edges {
                let (ji, jj) = between_jacobians(&poses[e.i], &poses[e.j], &e.measurement);
                let [a, b, c, d, f, q] = g.information(e).unwrap().0;
                let om = [[a, b, c], [b, d, f], [c, f, q]];
                for (u, ju) in [(e.i, &ji), (e.j, &jj)] {
                    for (v, jv) in [(e.i, &ji), (e.j, &jj)] {
                        if at[u] == usize::MAX || at[v] == usize::MAX {
                            continue;
                        }
                        let blk = at_b(ju, &mul(&om, jv));
                        for r in 0..3 {
                            for s in 0..3 {
                                h[3 * at[u] + r][3 * at[v] + s] += blk[r][s];
                            }
                        }
                    }
                }
            }
            let inv = dense_inverse(h);
            for layout in [Layout::Auto, Layout::Simplicial, Layout::Supernodal] {
                let m = marginals_with(&g, &poses, layout).unwrap();
                for k in 0..n {
                    if at[k] == usize::MAX {
                        assert_eq!(m[k].0, [0.0; 6]);
                        continue;
                    }
                    let o = 3 * at[k];
                    let want = [
                        inv[o][o],
                        inv[o][o + 1],
                        inv[o][o + 2],
                        inv[o + 1][o + 1],
                        inv[o + 1][o + 2],
                        inv[o + 2][o + 2],
                    ];
                    let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    for (a, b) in m[k].0.iter().zip(want) {
                        assert!(
                            (a - b).abs() <= 1e-11 * scale,
                            "{layout:?} pose {k}: {:?} {want:?}",
                            m[k]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn refuses_what_it_cannot_do() {
        let g = two_pose_graph(Pose2::new(0.0, 0.0, 0.0), SymMat3::IDENTITY);
        assert!(matches!(
            marginals(&g, &g.poses[..1]),
            Err(MarginalsError::PoseCount { .. })
        ));
        let bad = [g.poses[0], Pose2::new(f64::NAN, 0.0, 0.0)];
        assert!(matches!(
            marginals(&g, &bad),
            Err(MarginalsError::NonFinitePose { .. })
        ));
        let singular = two_pose_graph(
            Pose2::new(0.0, 0.0, 0.0),
            SymMat3([1.0, 0.0, 0.0, 1.0, 0.0, 0.0]),
        );
        assert_eq!(
            marginals(&singular, &singular.poses),
            Err(MarginalsError::NotPositiveDefinite)
        );
    }
}
