//! Levenberg-Marquardt refinement on SE(3)ⁿ under each edge's full 6x6 information matrix: the
//! local maximum-likelihood estimate g2o computes for `EDGE_SE3:QUAT` graphs (issue 15), what
//! `pgo-solve --refine` runs on a 3D graph after the certified solve.
//!
//! **The error is g2o's.** An edge (i, j) with measurement z and information Ω (upper triangle
//! over (x, y, z, qx, qy, qz), as written) has g2o's `EdgeSE3::computeError`
//!
//! ```text
//! Δ = z⁻¹ · (x_i⁻¹ · x_j) = (R_Δ, t_Δ),   e = toVectorMQT(Δ) = [ t_Δ ; v ],   chi2 = Σ_e eᵀ Ω e
//! ```
//!
//! where (w, v) is the unit quaternion of R_Δ with the sign chosen so that w ≥ 0 (g2o's
//! `toCompactQuaternion` normalizes the quaternion to w > 0 and keeps its vector part; there is
//! no factor 2 in front of v, unlike GTSAM's or Ceres' tangent-space error, about 2v for small
//! rotations). This is the convention of the file's information matrix, so the chi2 is g2o's
//! `activeChi2()` (without GTSAM's ½), and it is what [`crate::solve::spatial`] reports as
//! `chi2`. With u = R_iᵀ (t_j − t_i): t_Δ = R_zᵀ (u − t_z) and R_Δ = R_zᵀ R_iᵀ R_j.
//!
//! **The retraction** is the right-multiplied one, x ⊕ (δt, ω) = (t + R δt, R · Exp(ω)), the
//! body-frame tangent of g2o's `VertexSE3::oplus` (which increments by the quaternion vector
//! part, ω ≈ 2v: the same first order up to a factor 2 on the rotation columns, so the same
//! stationary points and minimum; only the damping's path differs). From
//! R_Δ(ω_j) = R_Δ Exp(ω_j), R_Δ(ω_i) = R_Δ Exp(−R_Δᵀ R_zᵀ ω_i) to first order, and
//! (w, v) ⊗ (1, φ/2) = (w − v·φ/2, v + (w φ + v × φ)/2), with D = ½ (w I + [v]×):
//!
//! ```text
//! ∂e/∂(δt_i, ω_i) = [ −R_zᵀ   R_zᵀ [u]×        ]     ∂e/∂(δt_j, ω_j) = [ R_Δ   0 ]
//!                   [   0     −D R_Δᵀ R_zᵀ     ]                       [  0    D ]
//! ```
//!
//! (the error is not differentiable where w = 0, a relative error of π; LM then sees the
//! one-sided derivative of the branch it is on, as g2o does).
//!
//! The normal equations (6x6 blocks over the free poses, sparse Cholesky analysed once) and the
//! damping schedule are the planar refinement's ([`super::damped`]).
//!
//! Gauge: the graph's FIX poses are held; every connected component without one holds its first
//! pose (smallest index), as [`crate::solve::solve3`] writes them: held poses are returned
//! exactly as given.

use super::damped::{Block, BlockSystem, RefineOptions, Stop, levenberg, quadratic};
use super::levenberg_marquardt::RefineError;
use crate::graph3::{Edge3, Graph3, Pose3, Rotation3};
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};

/// The result of [`refine3`].
#[derive(Debug, Clone, PartialEq)]
pub struct Refinement3 {
    /// The refined poses, quaternions with w ≥ 0 (held poses exactly as given).
    pub poses: Vec<Pose3>,
    /// chi2 of the initial poses.
    pub initial_chi2: f64,
    /// chi2 of `poses`.
    pub chi2: f64,
    /// Iterations (linearizations) done.
    pub iterations: usize,
    /// Numeric Cholesky factorizations done (one per trial step).
    pub factorizations: usize,
    /// Whether the stopping rule was met ([`Stop::Converged`]).
    pub converged: bool,
    pub stop: Stop,
    /// Dense indices of the poses held fixed (the gauge), ascending.
    pub held: Vec<usize>,
}

/// g2o's error e = [t_Δ; v] of `EDGE_SE3:QUAT` (module docs) for a measurement z between x_i
/// and x_j.
pub fn edge_error3(xi: &Isometry3<f64>, xj: &Isometry3<f64>, z: &Isometry3<f64>) -> [f64; 6] {
    error_of(&z.inverse(), xi, xj)
}

/// [t_Δ; v] of Δ = z⁻¹ · (a⁻¹ · b), w ≥ 0.
fn error_of(z_inv: &Isometry3<f64>, a: &Isometry3<f64>, b: &Isometry3<f64>) -> [f64; 6] {
    let d = z_inv * a.inv_mul(b);
    let q = d.rotation.quaternion();
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    let t = d.translation.vector;
    [t.x, t.y, t.z, s * q.i, s * q.j, s * q.k]
}

/// The 6x6 information of an edge, both triangles.
fn omega(e: &Edge3) -> Block<6> {
    std::array::from_fn(|r| std::array::from_fn(|c| e.information.get(r, c)))
}

/// g2o's χ² = Σ_e eᵀ Ω_e e over all edges ([`edge_error3`]) at `poses` (one per pose of
/// `graph`); meaningful for g2o files (TORO's information is over Euler angles).
///
/// # Panics
///
/// If an edge refers to a pose outside `poses`.
pub fn chi2_3(graph: &Graph3, poses: &[Isometry3<f64>]) -> f64 {
    graph
        .edges
        .iter()
        .map(|e| {
            let z = e.measurement.to_isometry();
            quadratic(&omega(e), &edge_error3(&poses[e.i], &poses[e.j], &z))
        })
        .fold(0.0, |a, b| a + b)
}

/// One edge with what its error needs.
struct Factor3 {
    i: usize,
    j: usize,
    z_inv: Isometry3<f64>,
    /// R_zᵀ.
    rzt: Matrix3<f64>,
    omega: Block<6>,
}

impl Factor3 {
    fn chi2(&self, x: &[Isometry3<f64>]) -> f64 {
        quadratic(&self.omega, &self.error(&x[self.i], &x[self.j]))
    }

    fn error(&self, a: &Isometry3<f64>, b: &Isometry3<f64>) -> [f64; 6] {
        error_of(&self.z_inv, a, b)
    }

    /// e, ∂e/∂x_i and ∂e/∂x_j (module docs).
    fn linearize(&self, a: &Isometry3<f64>, b: &Isometry3<f64>) -> ([f64; 6], Block<6>, Block<6>) {
        let d = self.z_inv * a.inv_mul(b);
        let q = d.rotation.quaternion();
        let s = if q.w < 0.0 { -1.0 } else { 1.0 };
        let (w, v) = (s * q.w, Vector3::new(s * q.i, s * q.j, s * q.k));
        let t = d.translation.vector;
        let e = [t.x, t.y, t.z, v.x, v.y, v.z];
        let u = a.rotation.inverse() * (b.translation.vector - a.translation.vector);
        let r_delta = d.rotation.to_rotation_matrix().into_inner();
        let dq = (Matrix3::identity() * w + v.cross_matrix()) * 0.5;
        let tt_i = -self.rzt;
        let tr_i = self.rzt * u.cross_matrix();
        let rr_i = -(dq * r_delta.transpose() * self.rzt);
        let mut ji = [[0.0; 6]; 6];
        let mut jj = [[0.0; 6]; 6];
        for r in 0..3 {
            for c in 0..3 {
                ji[r][c] = tt_i[(r, c)];
                ji[r][c + 3] = tr_i[(r, c)];
                ji[r + 3][c + 3] = rr_i[(r, c)];
                jj[r][c] = r_delta[(r, c)];
                jj[r + 3][c + 3] = dq[(r, c)];
            }
        }
        (e, ji, jj)
    }
}

/// The held poses of [`refine3`] (its gauge): the FIX poses, plus the first pose of every
/// component without one; dense indices, ascending.
pub fn gauge3(graph: &Graph3) -> Vec<usize> {
    let (label, count) = graph.connected_components();
    let mut anchored = vec![false; count];
    let mut held: Vec<usize> = graph.fixed.clone();
    for &k in &graph.fixed {
        anchored[label[k]] = true;
    }
    for (k, &c) in label.iter().enumerate() {
        if !anchored[c] {
            anchored[c] = true;
            held.push(k);
        }
    }
    held.sort_unstable();
    held.dedup();
    held
}

/// Checks what chi2 needs and returns one [`Factor3`] per edge.
fn validate(graph: &Graph3, initial: &[Pose3]) -> Result<Vec<Factor3>, RefineError> {
    let n = graph.num_poses();
    if initial.len() != n {
        return Err(RefineError::PoseCount {
            expected: n,
            found: initial.len(),
        });
    }
    let out_of_range = |what: String, index: usize| RefineError::IndexOutOfRange { what, index, n };
    for (k, e) in graph.edges.iter().enumerate() {
        if let Some(&index) = [e.i, e.j].iter().find(|&&v| v >= n) {
            return Err(out_of_range(format!("edge {k}"), index));
        }
    }
    if let Some(&index) = graph.fixed.iter().find(|&&v| v >= n) {
        return Err(out_of_range("a FIX line".into(), index));
    }
    let finite = |p: &Pose3| p.values().all(f64::is_finite) && nonzero(p);
    if let Some(k) = initial.iter().position(|p| !finite(p)) {
        return Err(RefineError::NonFinitePose { id: graph.ids[k] });
    }
    graph
        .edges
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let bad = |what| RefineError::NonFiniteEdge {
                edge: k,
                from: graph.ids[e.i],
                to: graph.ids[e.j],
                what,
            };
            if !finite(&e.measurement) {
                return Err(bad("the measurement"));
            }
            if !e.information.0.iter().all(|v| v.is_finite()) {
                return Err(bad("the information matrix"));
            }
            let z = e.measurement.to_isometry();
            Ok(Factor3 {
                i: e.i,
                j: e.j,
                z_inv: z.inverse(),
                rzt: z.rotation.to_rotation_matrix().into_inner().transpose(),
                omega: omega(e),
            })
        })
        .collect()
}

/// A quaternion of positive norm (a zero one is no rotation).
fn nonzero(p: &Pose3) -> bool {
    match p.rotation {
        Rotation3::Quaternion(q) => q.iter().map(|v| v * v).sum::<f64>() > 0.0,
        Rotation3::Euler(_) => true,
    }
}

fn total_chi2(factors: &[Factor3], x: &[Isometry3<f64>]) -> f64 {
    factors.iter().map(|f| f.chi2(x)).fold(0.0, |a, b| a + b)
}

fn assemble(system: &mut BlockSystem<6>, factors: &[Factor3], x: &[Isometry3<f64>]) {
    system.clear();
    for (k, f) in factors.iter().enumerate() {
        if !system.moves(f.i, f.j) {
            continue;
        }
        let (e, ji, jj) = f.linearize(&x[f.i], &x[f.j]);
        system.add(k, f.i, f.j, &e, &f.omega, &ji, &jj);
    }
    system.finish();
}

/// `out` = `x` ⊕ `step`: x ⊕ (δt, ω) = (t + R δt, R Exp(ω)) for free poses; held ones copied.
fn retract(
    system: &BlockSystem<6>,
    x: &[Isometry3<f64>],
    step: &[f64],
    out: &mut [Isometry3<f64>],
) {
    for ((o, p), &b) in out.iter_mut().zip(x).zip(&system.block) {
        *o = if b == usize::MAX {
            *p
        } else {
            let s = &step[6 * b..6 * b + 6];
            let dt = p.rotation * Vector3::new(s[0], s[1], s[2]);
            let mut r =
                p.rotation * UnitQuaternion::from_scaled_axis(Vector3::new(s[3], s[4], s[5]));
            r.renormalize();
            Isometry3::from_parts(Translation3::from(p.translation.vector + dt), r)
        };
    }
}

/// A pose as g2o writes it: quaternion `[x, y, z, w]` with w ≥ 0.
pub fn pose_of(m: &Isometry3<f64>) -> Pose3 {
    let t = m.translation.vector;
    let q = m.rotation.quaternion();
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    Pose3 {
        translation: [t.x, t.y, t.z],
        rotation: Rotation3::Quaternion([s * q.i, s * q.j, s * q.k, s * q.w]),
    }
}

/// Levenberg-Marquardt from `initial` (one pose per pose of `graph`) on g2o's chi2 (module docs:
/// error, retraction, gauge); the stopping rule and damping of the planar
/// [`super::levenberg_marquardt::refine`].
///
/// # Errors
///
/// Inputs that make chi2 undefined: a wrong number of poses, indices out of range, non-finite
/// poses, measurements or information matrices, a non-finite initial chi2.
pub fn refine3(
    graph: &Graph3,
    initial: &[Pose3],
    options: &RefineOptions,
) -> Result<Refinement3, RefineError> {
    let factors = validate(graph, initial)?;
    let held = gauge3(graph);
    let mut x: Vec<Isometry3<f64>> = initial.iter().map(|p| p.to_isometry()).collect();
    let initial_chi2 = total_chi2(&factors, &x);
    if !initial_chi2.is_finite() {
        return Err(RefineError::NonFiniteChi2);
    }
    let mut is_held = vec![false; x.len()];
    for &k in &held {
        is_held[k] = true;
    }
    let pairs: Vec<(usize, usize)> = factors.iter().map(|f| (f.i, f.j)).collect();
    let mut system = BlockSystem::<6>::new(&pairs, &is_held).map_err(RefineError::Analysis)?;
    let mut result = Refinement3 {
        poses: initial.to_vec(),
        initial_chi2,
        chi2: initial_chi2,
        iterations: 0,
        factorizations: 0,
        converged: true,
        stop: Stop::Converged,
        held,
    };
    if initial_chi2 == 0.0 || system.dim == 0 {
        return Ok(result);
    }
    let outcome = levenberg(
        &mut system,
        &mut x,
        initial_chi2,
        options,
        |system, x| assemble(system, &factors, x),
        |x| total_chi2(&factors, x),
        retract,
    );
    for (k, p) in result.poses.iter_mut().enumerate() {
        if !is_held[k] {
            *p = pose_of(&x[k]);
        }
    }
    result.chi2 = outcome.chi2;
    result.iterations = outcome.iterations;
    result.factorizations = outcome.factorizations;
    result.stop = outcome.stop;
    result.converged = outcome.stop == Stop::Converged;
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph3::{Form3, SymMat6};
    use crate::linalg::rng::Rng;

    fn random_pose(rng: &mut Rng, spread: f64) -> Isometry3<f64> {
        let t = Vector3::new(
            spread * (2.0 * rng.uniform() - 1.0),
            spread * (2.0 * rng.uniform() - 1.0),
            spread * (2.0 * rng.uniform() - 1.0),
        );
        let axis = Vector3::new(rng.normal(), rng.normal(), rng.normal());
        let r = UnitQuaternion::from_scaled_axis(axis.normalize() * 3.0 * rng.uniform());
        Isometry3::from_parts(Translation3::from(t), r)
    }

    /// A rigid motion of translation up to `size` per axis and rotation angle up to `size`.
    fn perturbation(rng: &mut Rng, size: f64) -> Isometry3<f64> {
        let mut p = random_pose(rng, size);
        let axis = p.rotation.scaled_axis();
        p.rotation = UnitQuaternion::from_scaled_axis(axis / 3.0 * size);
        p
    }

    /// A positive definite information with off-diagonal coupling (a symmetric matrix filled
    /// by its indices).
    #[allow(clippy::needless_range_loop)]
    fn information(rng: &mut Rng) -> SymMat6 {
        let mut m = [[0.0; 6]; 6];
        for (r, row) in m.iter_mut().enumerate() {
            row[r] = 5.0 + 10.0 * rng.uniform();
        }
        for r in 0..6 {
            for c in r + 1..6 {
                let v = rng.uniform() - 0.5;
                m[r][c] = v;
                m[c][r] = v;
            }
        }
        let mut up = [0.0; 21];
        let mut k = 0;
        for r in 0..6 {
            for c in r..6 {
                up[k] = m[r][c];
                k += 1;
            }
        }
        SymMat6(up)
    }

    /// A graph over `truth`: odometry and `loops`, each measurement the true relative pose
    /// times a perturbation of size `noise`.
    fn graph3(
        truth: &[Isometry3<f64>],
        loops: &[(usize, usize)],
        noise: f64,
        rng: &mut Rng,
    ) -> Graph3 {
        let pairs: Vec<(usize, usize)> = (0..truth.len() - 1)
            .map(|k| (k, k + 1))
            .chain(loops.iter().copied())
            .collect();
        let edges = pairs
            .iter()
            .map(|&(i, j)| {
                let d = truth[i].inv_mul(&truth[j]) * perturbation(rng, noise);
                Edge3 {
                    i,
                    j,
                    measurement: pose_of(&d),
                    information: information(rng),
                }
            })
            .collect();
        Graph3 {
            ids: (0..truth.len() as u32).collect(),
            poses: truth.iter().map(pose_of).collect(),
            edges,
            fixed: vec![],
            form: Form3::G2o,
        }
    }

    #[test]
    fn jacobians_match_central_differences_of_the_retraction() {
        let mut rng = Rng::new(7);
        for _ in 0..100 {
            let (a, b, z) = (
                random_pose(&mut rng, 3.0),
                random_pose(&mut rng, 3.0),
                random_pose(&mut rng, 3.0),
            );
            let f = Factor3 {
                i: 0,
                j: 1,
                z_inv: z.inverse(),
                rzt: z.rotation.to_rotation_matrix().into_inner().transpose(),
                omega: [[0.0; 6]; 6],
            };
            let (e, ji, jj) = f.linearize(&a, &b);
            assert_eq!(e, edge_error3(&a, &b, &z));
            if e[3..].iter().map(|v| v * v).sum::<f64>() > 0.99 {
                continue; // w near 0: the error's sign switch is near
            }
            let h = 1e-6;
            for v in 0..12 {
                let shifted = |s: f64| {
                    let mut step = [0.0; 6];
                    step[v % 6] = s;
                    let p = if v < 6 { &a } else { &b };
                    let dt = p.rotation * Vector3::new(step[0], step[1], step[2]);
                    let r = p.rotation
                        * UnitQuaternion::from_scaled_axis(Vector3::new(step[3], step[4], step[5]));
                    let moved =
                        Isometry3::from_parts(Translation3::from(p.translation.vector + dt), r);
                    if v < 6 {
                        edge_error3(&moved, &b, &z)
                    } else {
                        edge_error3(&a, &moved, &z)
                    }
                };
                let (p, m) = (shifted(h), shifted(-h));
                for r in 0..6 {
                    let num = (p[r] - m[r]) / (2.0 * h);
                    let an = if v < 6 { ji[r][v] } else { jj[r][v - 6] };
                    assert!((num - an).abs() < 1e-7, "row {r} var {v}: {num} vs {an}");
                }
            }
        }
    }

    #[test]
    fn consistent_graph_is_recovered_and_noisy_one_is_stationary() {
        let mut rng = Rng::new(11);
        let truth: Vec<Isometry3<f64>> = (0..10).map(|_| random_pose(&mut rng, 4.0)).collect();
        let g = graph3(&truth, &[(0, 9), (2, 7), (8, 3)], 0.0, &mut rng);
        assert!(chi2_3(&g, &truth) < 1e-24);
        // From a perturbed start (pose 0 held).
        let start: Vec<Pose3> = truth
            .iter()
            .enumerate()
            .map(|(k, p)| {
                if k == 0 {
                    pose_of(p)
                } else {
                    pose_of(&(p * perturbation(&mut rng, 0.2)))
                }
            })
            .collect();
        let r = refine3(&g, &start, &RefineOptions::default()).unwrap();
        assert!(r.initial_chi2 > 1e-3, "{}", r.initial_chi2);
        assert!(r.chi2 < 1e-20, "{}", r.chi2);
        assert!(r.converged && r.held == vec![0]);
        assert_eq!(r.poses[0], start[0]);
        for (p, t) in r.poses.iter().zip(&truth) {
            let d = p.to_isometry().inv_mul(t);
            assert!(d.translation.vector.norm() < 1e-9 && d.rotation.angle() < 1e-9);
        }
        // Noisy: a stationary point of chi2 along every coordinate of every free pose.
        let noisy = graph3(&truth, &[(0, 9), (2, 7), (8, 3)], 0.3, &mut rng);
        let r = refine3(&noisy, &noisy.poses, &RefineOptions::default()).unwrap();
        assert!(r.converged && r.chi2 < r.initial_chi2 && r.chi2 > 0.0);
        let x: Vec<Isometry3<f64>> = r.poses.iter().map(|p| p.to_isometry()).collect();
        let f0 = chi2_3(&noisy, &x);
        assert!((f0 - r.chi2).abs() <= 1e-12 * f0);
        let h = 1e-5;
        for k in 1..10 {
            for c in 0..6 {
                let f = |s: f64| {
                    let mut y = x.clone();
                    let mut v = Vector3::zeros();
                    v[c % 3] = s;
                    y[k] = if c < 3 {
                        Isometry3::from_parts(
                            Translation3::from(x[k].translation.vector + v),
                            x[k].rotation,
                        )
                    } else {
                        Isometry3::from_parts(
                            x[k].translation,
                            x[k].rotation * UnitQuaternion::from_scaled_axis(v),
                        )
                    };
                    chi2_3(&noisy, &y)
                };
                let d = (f(h) - f(-h)) / (2.0 * h);
                assert!(d.abs() < 1e-6 * f0.max(1.0), "pose {k} coordinate {c}: {d}");
            }
        }
    }

    #[test]
    fn invalid_inputs_are_errors() {
        let mut rng = Rng::new(3);
        let truth: Vec<Isometry3<f64>> = (0..4).map(|_| random_pose(&mut rng, 4.0)).collect();
        let g = graph3(&truth, &[(0, 3)], 0.1, &mut rng);
        let opts = RefineOptions::default();
        assert!(matches!(
            refine3(&g, &g.poses[..3], &opts),
            Err(RefineError::PoseCount { .. })
        ));
        let mut p = g.poses.clone();
        p[2].translation[1] = f64::NAN;
        assert_eq!(
            refine3(&g, &p, &opts),
            Err(RefineError::NonFinitePose { id: 2 })
        );
        let mut b = g.clone();
        b.edges[1].information.0[4] = f64::INFINITY;
        assert!(matches!(
            refine3(&b, &g.poses, &opts),
            Err(RefineError::NonFiniteEdge { edge: 1, .. })
        ));
        let mut b = g.clone();
        b.edges[0].j = 7;
        assert!(matches!(
            refine3(&b, &g.poses, &opts),
            Err(RefineError::IndexOutOfRange { index: 7, .. })
        ));
        // Everything held: the start comes back.
        let mut all = g.clone();
        all.fixed = (0..4).collect();
        let r = refine3(&all, &g.poses, &opts).unwrap();
        assert!(r.converged && r.poses == g.poses && r.iterations == 0);
    }
}
