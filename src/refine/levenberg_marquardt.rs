//! Levenberg-Marquardt refinement on SE(2) under each edge's full information matrix: the local
//! maximum-likelihood estimate g2o computes (docs/method.md §3.3).
//!
//! An edge (i, j) with measurement z = (t_z, θ_z) and information Ω has g2o's `EdgeSE2` error
//!
//! ```text
//! e = toVector(z⁻¹ · (x_i⁻¹ · x_j)) = [ R_zᵀ (u − t_z) ; wrap(θ_j − θ_i − θ_z) ],   u = R_iᵀ (t_j − t_i)
//! chi2 = Σ_e eᵀ Ω e                                            (g2o's χ², without GTSAM's ½)
//! ```
//!
//! with the angle wrapped to (−π, π] ([`wrap_angle`]; g2o's `normalize_theta` maps to [−π, π),
//! which differs only at exactly ±π).
//!
//! The retraction is g2o's `VertexSE2::oplus`, additive on (x, y, θ) with θ wrapped:
//! x ⊕ δ = (x + δ_x, y + δ_y, wrap(θ + δ_θ)). The Jacobians are therefore the plain partial
//! derivatives, with A = R_zᵀ R_iᵀ = R(−(θ_i + θ_z)):
//!
//! ```text
//! ∂e/∂(t_i, θ_i) = [ −A   R_zᵀ (u_y, −u_x)ᵀ ]        ∂e/∂(t_j, θ_j) = [ A   0 ]
//!                  [  0          −1        ]                          [ 0   1 ]
//! ```
//!
//! The normal equations (3x3 blocks, sparse Cholesky analysed once) and the damping schedule
//! are shared with the SE(3) refinement: [`super::damped`].
//!
//! Landmarks (issue 13): a landmark l_k is one more vertex after the n poses, (x, y) with a θ
//! that nothing measures, and its observation from pose i with measurement d and 2x2 information
//! Ω_ik is g2o's `EdgeSE2PointXY`, e = R_iᵀ (l_k − t_i) − d, which is exactly the edge error above
//! with z = (d, 0) and the information [[Ω_ik, 0], [0, 0]] (the θ row of e weighs nothing): so
//! it is one more [`Factor`], the full 2x2 information kept. The landmark's θ gets no gradient
//! and only the damping on its diagonal, so it never moves.
//!
//! Gauge: the graph's FIX poses are held; every connected component without one holds its
//! first pose (smallest index). Held poses are returned unchanged.

use super::damped::{Block, BlockSystem, levenberg, quadratic};
pub use super::damped::{RefineOptions, Stop};
use crate::graph::{Pose2, PoseGraph, SymMat3, VertexId};
use crate::simulate::wrap_angle;
use thiserror::Error;

/// The result of [`refine`].
#[derive(Debug, Clone, PartialEq)]
pub struct Refinement {
    /// The refined poses (θ of the free poses wrapped to (−π, π]).
    pub poses: Vec<Pose2>,
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

/// What [`refine`] refuses.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RefineError {
    #[error("{found} initial poses given for a graph of {expected} poses")]
    PoseCount { expected: usize, found: usize },
    #[error("{what} refers to pose index {index}, out of 0..{n}")]
    IndexOutOfRange {
        what: String,
        index: usize,
        n: usize,
    },
    #[error("initial pose of vertex {id} is not finite")]
    NonFinitePose { id: VertexId },
    #[error("edge {edge} ({from} -> {to}): {what} is not finite")]
    NonFiniteEdge {
        edge: usize,
        from: VertexId,
        to: VertexId,
        what: &'static str,
    },
    #[error("edge {edge} ({from} -> {to}): singular covariance, no information matrix")]
    SingularCovariance {
        edge: usize,
        from: VertexId,
        to: VertexId,
    },
    #[error("chi2 of the initial poses is not finite")]
    NonFiniteChi2,
    #[error("sparse Cholesky analysis failed: {0}")]
    Analysis(String),
}

impl From<RefineError> for crate::Error {
    fn from(e: RefineError) -> Self {
        crate::Error::Invalid(e.to_string())
    }
}

/// g2o's `EdgeSE2` error e = toVector(z⁻¹ · (x_i⁻¹ · x_j)) of a measurement z between poses
/// x_i and x_j, angle wrapped to (−π, π].
pub fn edge_error(xi: Pose2, xj: Pose2, z: Pose2) -> [f64; 3] {
    Factor::new(0, 0, z, SymMat3::IDENTITY).error(&xi, &xj)
}

/// g2o's χ² = Σ_e eᵀ Ω_e e over all edges ([`edge_error`]), with Ω_e = [`PoseGraph::information`]
/// (NaN if a covariance is singular).
///
/// # Panics
///
/// If an edge refers to a pose outside `poses`.
pub fn chi2(graph: &PoseGraph, poses: &[Pose2]) -> f64 {
    let edges: f64 = graph
        .edges
        .iter()
        .map(|e| match graph.information(e) {
            Some(info) => Factor::new(e.i, e.j, e.measurement, info).chi2(poses),
            None => f64::NAN,
        })
        .sum();
    edges + landmark_chi2(graph, poses)
}

/// g2o's chi2 of the landmark observations (`EdgeSE2PointXY`): e = R(θ_i)ᵀ (l_k − p_i) − d,
/// Σ eᵀ Ω_ik e, with the landmark positions after the n poses in `poses` (0 without landmarks).
pub fn landmark_chi2(graph: &PoseGraph, poses: &[Pose2]) -> f64 {
    let n = graph.num_poses();
    graph
        .landmarks
        .observations
        .iter()
        .map(|o| {
            let (x, l) = (poses[o.pose], poses[n + o.landmark]);
            let (s, c) = x.theta.sin_cos();
            let (dx, dy) = (l.x - x.x, l.y - x.y);
            let e = [c * dx + s * dy - o.d[0], -s * dx + c * dy - o.d[1]];
            let [a, b, d] = o.information.0;
            a * e[0] * e[0] + 2.0 * b * e[0] * e[1] + d * e[1] * e[1]
        })
        .fold(0.0, |a, b| a + b)
}

/// Levenberg-Marquardt from `initial` on g2o's chi2 (module docs: retraction, damping, gauge).
/// `initial` holds one pose per pose of `graph`, then one per landmark (its position; θ unused),
/// and so does the result.
///
/// Stops when a trial step changes chi2 by less than `options.tol · chi2` (converged), after
/// `options.max_iterations` iterations, or when `options.max_trials` damped trials in a row
/// neither decrease chi2 nor change it by less than that. A failed factorization counts as a
/// rejected trial (more damping), never as an error.
///
/// # Errors
///
/// Inputs that make chi2 undefined: a wrong number of poses, indices out of range, non-finite
/// poses, measurements or information matrices, a singular covariance, a non-finite initial chi2.
pub fn refine(
    graph: &PoseGraph,
    initial: &[Pose2],
    options: &RefineOptions,
) -> Result<Refinement, RefineError> {
    let factors = validate(graph, initial)?;
    let held = gauge(graph);
    let mut poses = initial.to_vec();
    let initial_chi2 = total_chi2(&factors, &poses);
    if !initial_chi2.is_finite() {
        return Err(RefineError::NonFiniteChi2);
    }
    let mut result = Refinement {
        poses: Vec::new(),
        initial_chi2,
        chi2: initial_chi2,
        iterations: 0,
        factorizations: 0,
        converged: false,
        stop: Stop::MaxIterations,
        held,
    };
    let mut is_held = vec![false; poses.len()];
    for &k in &result.held {
        is_held[k] = true;
    }
    let pairs: Vec<(usize, usize)> = factors.iter().map(|f| (f.i, f.j)).collect();
    let mut system = BlockSystem::<3>::new(&pairs, &is_held).map_err(RefineError::Analysis)?;
    if initial_chi2 == 0.0 || system.dim == 0 {
        result.poses = poses;
        result.converged = true;
        result.stop = Stop::Converged;
        return Ok(result);
    }
    let outcome = levenberg(
        &mut system,
        &mut poses,
        initial_chi2,
        options,
        |system, poses| assemble(system, &factors, poses),
        |poses| total_chi2(&factors, poses),
        retract,
    );
    result.iterations = outcome.iterations;
    result.factorizations = outcome.factorizations;
    result.stop = outcome.stop;
    result.converged = result.stop == Stop::Converged;
    result.poses = poses;
    result.chi2 = outcome.chi2;
    Ok(result)
}

/// Checks what chi2 needs and returns one [`Factor`] per edge.
fn validate(graph: &PoseGraph, initial: &[Pose2]) -> Result<Vec<Factor>, RefineError> {
    let n = graph.num_poses();
    let marks = &graph.landmarks;
    if initial.len() != n + marks.len() {
        return Err(RefineError::PoseCount {
            expected: n + marks.len(),
            found: initial.len(),
        });
    }
    if let Some((k, o)) = marks
        .observations
        .iter()
        .enumerate()
        .find(|(_, o)| o.pose >= n || o.landmark >= marks.len())
    {
        let index = if o.pose >= n { o.pose } else { n + o.landmark };
        return Err(RefineError::IndexOutOfRange {
            what: format!("landmark observation {k}"),
            index,
            n: n + marks.len(),
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
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if let Some(k) = initial.iter().position(|p| !finite(&p.values())) {
        let id = if k < n {
            graph.ids[k]
        } else {
            marks.ids[k - n]
        };
        return Err(RefineError::NonFinitePose { id });
    }
    let observations = marks.observations.iter().enumerate().map(|(k, o)| {
        let [a, b, d] = o.information.0;
        if !finite(&o.d) || !finite(&o.information.0) {
            return Err(RefineError::NonFiniteEdge {
                edge: graph.edges.len() + k,
                from: graph.ids[o.pose],
                to: marks.ids[o.landmark],
                what: "the landmark observation",
            });
        }
        Ok(Factor::new(
            o.pose,
            n + o.landmark,
            Pose2::new(o.d[0], o.d[1], 0.0),
            SymMat3([a, b, 0.0, d, 0.0, 0.0]),
        ))
    });
    graph
        .edges
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let (from, to) = (graph.ids[e.i], graph.ids[e.j]);
            let bad = |what| RefineError::NonFiniteEdge {
                edge: k,
                from,
                to,
                what,
            };
            if !finite(&e.measurement.values()) {
                return Err(bad("the measurement"));
            }
            if !finite(&e.noise.0) {
                return Err(bad("the noise matrix"));
            }
            let info = graph
                .information(e)
                .ok_or(RefineError::SingularCovariance { edge: k, from, to })?;
            Ok(Factor::new(e.i, e.j, e.measurement, info))
        })
        .chain(observations)
        .collect()
}

/// The held poses of [`refine`] (its gauge): the FIX poses, plus the first pose of every
/// component without one; dense indices, ascending.
pub fn gauge(graph: &PoseGraph) -> Vec<usize> {
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

/// One edge, with what its error needs precomputed.
#[derive(Debug, Clone, Copy)]
struct Factor {
    i: usize,
    j: usize,
    /// t_z, cos θ_z, sin θ_z, θ_z.
    tz: [f64; 2],
    cz: f64,
    sz: f64,
    thz: f64,
    /// Ω, both triangles.
    omega: [[f64; 3]; 3],
}

impl Factor {
    fn new(i: usize, j: usize, z: Pose2, info: SymMat3) -> Self {
        let [a, b, c, d, e, f] = info.0;
        let (sz, cz) = z.theta.sin_cos();
        Factor {
            i,
            j,
            tz: [z.x, z.y],
            cz,
            sz,
            thz: z.theta,
            omega: [[a, b, c], [b, d, e], [c, e, f]],
        }
    }

    /// u = R_iᵀ (t_j − t_i) and e.
    fn error_parts(&self, a: &Pose2, b: &Pose2) -> ([f64; 2], [f64; 3], f64, f64) {
        let (si, ci) = a.theta.sin_cos();
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let u = [ci * dx + si * dy, -si * dx + ci * dy];
        let v = [u[0] - self.tz[0], u[1] - self.tz[1]];
        let e = [
            self.cz * v[0] + self.sz * v[1],
            -self.sz * v[0] + self.cz * v[1],
            wrap_angle(b.theta - a.theta - self.thz),
        ];
        (u, e, si, ci)
    }

    fn error(&self, a: &Pose2, b: &Pose2) -> [f64; 3] {
        self.error_parts(a, b).1
    }

    fn chi2(&self, poses: &[Pose2]) -> f64 {
        quadratic(&self.omega, &self.error(&poses[self.i], &poses[self.j]))
    }

    /// e, ∂e/∂x_i and ∂e/∂x_j (module docs).
    fn linearize(&self, a: &Pose2, b: &Pose2) -> ([f64; 3], Block<3>, Block<3>) {
        let (u, e, si, ci) = self.error_parts(a, b);
        let (cz, sz) = (self.cz, self.sz);
        // A = R(−φ), φ = θ_i + θ_z.
        let (c, s) = (ci * cz - si * sz, si * cz + ci * sz);
        let w = [cz * u[1] - sz * u[0], -sz * u[1] - cz * u[0]];
        let ji = [[-c, -s, w[0]], [s, -c, w[1]], [0.0, 0.0, -1.0]];
        let jj = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
        (e, ji, jj)
    }
}

fn total_chi2(factors: &[Factor], poses: &[Pose2]) -> f64 {
    factors.iter().map(|f| f.chi2(poses)).sum()
}

/// H and g at `poses`, in one pass over the factors.
fn assemble(system: &mut BlockSystem<3>, factors: &[Factor], poses: &[Pose2]) {
    system.clear();
    for (k, f) in factors.iter().enumerate() {
        if !system.moves(f.i, f.j) {
            continue; // a self-loop's error is constant; held poses have no variables
        }
        let (e, ji, jj) = f.linearize(&poses[f.i], &poses[f.j]);
        system.add(k, f.i, f.j, &e, &f.omega, &ji, &jj);
    }
    system.finish();
}

/// `out` = `poses` ⊕ `step`: free poses moved additively, θ wrapped; held poses copied.
fn retract(system: &BlockSystem<3>, poses: &[Pose2], step: &[f64], out: &mut [Pose2]) {
    for ((o, p), &b) in out.iter_mut().zip(poses).zip(&system.block) {
        *o = if b == usize::MAX {
            *p
        } else {
            Pose2::new(
                p.x + step[3 * b],
                p.y + step[3 * b + 1],
                wrap_angle(p.theta + step[3 * b + 2]),
            )
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, NoiseKind};
    use crate::problem::matrix::tests::{Rng, graph, random_poses};
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI, SQRT_2};

    const OMEGA: SymMat3 = SymMat3([2.0, 0.5, 0.3, 3.0, 0.1, 4.0]);

    fn random_pose(rng: &mut Rng) -> Pose2 {
        Pose2::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-3.1, 3.1),
        )
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * a.abs().max(b.abs()).max(1.0)
    }

    #[test]
    fn edge_error_is_the_relative_pose_error_composed_by_nalgebra() {
        let mut rng = Rng(17);
        for _ in 0..200 {
            let (xi, xj, z) = (
                random_pose(&mut rng),
                random_pose(&mut rng),
                random_pose(&mut rng),
            );
            let d = z
                .to_isometry()
                .inv_mul(&xi.to_isometry().inv_mul(&xj.to_isometry()));
            let e = edge_error(xi, xj, z);
            assert!(close(e[0], d.translation.vector.x, 1e-12), "{e:?} {d}");
            assert!(close(e[1], d.translation.vector.y, 1e-12), "{e:?} {d}");
            assert!(e[2] > -PI && e[2] <= PI);
            assert!(
                wrap_angle(e[2] - d.rotation.angle()).abs() < 1e-12,
                "{e:?} {d}"
            );
        }
    }

    #[test]
    fn single_edge_chi2_by_hand() {
        let edge = |xi, xj, z, noise| PoseGraph {
            ids: vec![0, 1],
            poses: vec![xi, xj],
            edges: vec![Edge {
                i: 0,
                j: 1,
                measurement: z,
                noise,
            }],
            fixed: vec![],
            vertices_declared: true,
            noise: NoiseKind::Information,
            landmarks: Default::default(),
        };
        // x_i = (1, 2, π/2), x_j = (1, 5, π): x_i⁻¹ x_j = (R(−π/2)(0, 3), π/2) = (3, 0, π/2).
        // z = (2, 1, π/4): e = (R(−π/4)(1, −1), π/4) = (0, −√2, π/4), so with Ω = OMEGA
        // eᵀΩe = 3·2 + 4·π²/16 + 2·0.1·(−√2)·π/4.
        let g = edge(
            Pose2::new(1.0, 2.0, FRAC_PI_2),
            Pose2::new(1.0, 5.0, PI),
            Pose2::new(2.0, 1.0, FRAC_PI_4),
            OMEGA,
        );
        let e = edge_error(g.poses[0], g.poses[1], g.edges[0].measurement);
        assert!(e[0].abs() < 1e-15 && close(e[1], -SQRT_2, 1e-15) && close(e[2], FRAC_PI_4, 1e-15));
        let by_hand = 6.0 + PI * PI / 4.0 - 0.05 * SQRT_2 * PI;
        assert!(
            close(chi2(&g, &g.poses), by_hand, 1e-14),
            "{}",
            chi2(&g, &g.poses)
        );
        // The angle is wrapped: θ_j − θ_i − θ_z = 3 − (−3) − 0 = 6 ↦ 6 − 2π.
        let g = edge(
            Pose2::new(0.0, 0.0, -3.0),
            Pose2::new(0.0, 0.0, 3.0),
            Pose2::IDENTITY,
            OMEGA,
        );
        let w = 6.0 - 2.0 * PI;
        assert!(close(chi2(&g, &g.poses), 4.0 * w * w, 1e-14));
        // A covariance graph: chi2 under its inverse.
        let mut cov = g.clone();
        cov.edges[0].noise = OMEGA.inverse().unwrap();
        cov.noise = NoiseKind::Covariance;
        assert!(close(chi2(&cov, &g.poses), 4.0 * w * w, 1e-12));
        cov.edges[0].noise = SymMat3([1.0, 1.0, 0.0, 1.0, 0.0, 1.0]); // singular
        assert!(chi2(&cov, &g.poses).is_nan());
    }

    #[test]
    fn consistent_graph_has_zero_chi2() {
        let mut rng = Rng(5);
        let truth = random_poses(12, &mut rng);
        let g = graph(&truth, &[(0, 11), (2, 7), (9, 3)], 0.0, &mut rng);
        let f = chi2(&g, &truth);
        assert!(f < 1e-24, "{f}");
        let noisy = graph(&truth, &[(0, 11), (2, 7), (9, 3)], 0.1, &mut rng);
        assert!(chi2(&noisy, &truth) > 1e-3);
    }

    /// ∂e/∂(x_i, x_j) by central differences of `edge_error` (3 x 6, angle differences wrapped).
    fn numeric_jacobian(xi: Pose2, xj: Pose2, z: Pose2, h: f64) -> [[f64; 6]; 3] {
        let mut jac = [[0.0; 6]; 3];
        for v in 0..6 {
            let shift = |s: f64| {
                let (mut a, mut b) = (xi, xj);
                let p = if v < 3 { &mut a } else { &mut b };
                match v % 3 {
                    0 => p.x += s,
                    1 => p.y += s,
                    _ => p.theta += s,
                }
                edge_error(a, b, z)
            };
            let (plus, minus) = (shift(h), shift(-h));
            for (r, row) in jac.iter_mut().enumerate() {
                let d = plus[r] - minus[r];
                row[v] = if r == 2 { wrap_angle(d) } else { d } / (2.0 * h);
            }
        }
        jac
    }

    #[test]
    fn jacobians_match_central_differences() {
        let mut rng = Rng(23);
        for _ in 0..200 {
            let (xi, xj, z) = (
                random_pose(&mut rng),
                random_pose(&mut rng),
                random_pose(&mut rng),
            );
            let f = Factor::new(0, 1, z, OMEGA);
            let (e, ji, jj) = f.linearize(&xi, &xj);
            assert_eq!(e, edge_error(xi, xj, z));
            let num = numeric_jacobian(xi, xj, z, 1e-6);
            for r in 0..3 {
                for c in 0..3 {
                    assert!((ji[r][c] - num[r][c]).abs() < 1e-7, "J_i[{r}][{c}]");
                    assert!((jj[r][c] - num[r][c + 3]).abs() < 1e-7, "J_j[{r}][{c}]");
                }
            }
        }
    }

    /// Two components {0..4}, {4..8}: a path in each, loop closures (one duplicated, some
    /// written backwards), FIX 5; so poses 0 and 5 are held.
    fn two_components(noise: f64, rng: &mut Rng) -> (PoseGraph, Vec<Pose2>) {
        let truth = random_poses(8, rng);
        let mut g = graph(
            &truth,
            &[(0, 3), (1, 3), (3, 2), (4, 7), (4, 7), (7, 4), (7, 5)],
            noise,
            rng,
        );
        g.edges.retain(|e| (e.i, e.j) != (3, 4));
        g.fixed = vec![5];
        (g, truth)
    }

    #[test]
    fn gauge_holds_fix_poses_and_one_pose_per_free_component() {
        let mut rng = Rng(3);
        let (mut g, _) = two_components(0.1, &mut rng);
        assert_eq!(gauge(&g), vec![0, 5]);
        g.fixed = vec![];
        assert_eq!(gauge(&g), vec![0, 4]);
        g.fixed = vec![6, 2, 7];
        assert_eq!(gauge(&g), vec![2, 6, 7]);
        // An isolated pose is a component of its own.
        g.ids.push(8);
        g.poses.push(Pose2::IDENTITY);
        assert_eq!(gauge(&g), vec![2, 6, 7, 8]);
    }

    #[test]
    fn normal_equations_match_a_dense_assembly_from_numeric_jacobians() {
        let mut rng = Rng(29);
        let (g, _) = two_components(0.3, &mut rng);
        let poses: Vec<Pose2> = (0..8).map(|_| random_pose(&mut rng)).collect();
        let factors = validate(&g, &poses).unwrap();
        let mut held = vec![false; 8];
        for k in gauge(&g) {
            held[k] = true;
        }
        let pairs: Vec<(usize, usize)> = factors.iter().map(|f| (f.i, f.j)).collect();
        let mut system = BlockSystem::<3>::new(&pairs, &held).unwrap();
        assemble(&mut system, &factors, &poses);
        let dim = system.dim;
        assert_eq!(dim, 18);
        // H from the stored upper triangle.
        let mut h = vec![vec![0.0; dim]; dim];
        let col_ptr = system.pattern.col_ptr();
        let row_idx = system.pattern.row_idx();
        for col in 0..dim {
            for k in col_ptr[col]..col_ptr[col + 1] {
                assert!(row_idx[k] <= col);
                h[row_idx[k]][col] = system.values[k];
                h[col][row_idx[k]] = system.values[k];
            }
        }
        // The same from finite-difference Jacobians, densely; free variables numbered in
        // pose order.
        let var = |k: usize, c: usize| {
            let free_before = (0..k).filter(|&p| !held[p]).count();
            (!held[k]).then_some(3 * free_before + c)
        };
        let mut hd = vec![vec![0.0; dim]; dim];
        let mut gd = vec![0.0; dim];
        for e in &g.edges {
            let jac = numeric_jacobian(poses[e.i], poses[e.j], e.measurement, 1e-6);
            let err = edge_error(poses[e.i], poses[e.j], e.measurement);
            let om = e.noise.matrix();
            let vars: Vec<Option<usize>> = (0..6)
                .map(|v| var(if v < 3 { e.i } else { e.j }, v % 3))
                .collect();
            for (p, vp) in vars.iter().enumerate() {
                let Some(vp) = vp else { continue };
                for r in 0..3 {
                    for s in 0..3 {
                        gd[*vp] += jac[r][p] * om[(r, s)] * err[s];
                        for (q, vq) in vars.iter().enumerate() {
                            if let Some(vq) = vq {
                                hd[*vp][*vq] += jac[r][p] * om[(r, s)] * jac[s][q];
                            }
                        }
                    }
                }
            }
        }
        let scale = hd.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for a in 0..dim {
            for b in 0..dim {
                assert!((h[a][b] - hd[a][b]).abs() < 1e-6 * scale, "H[{a}][{b}]");
            }
            assert!((system.grad[a] - gd[a]).abs() < 1e-6 * scale, "g[{a}]");
        }
        // And 2g is the gradient of chi2 itself.
        let f = |p: &[Pose2]| chi2(&g, p);
        for k in (0..8).filter(|&k| !held[k]) {
            for c in 0..3 {
                let step = |s: f64| {
                    let mut p = poses.clone();
                    match c {
                        0 => p[k].x += s,
                        1 => p[k].y += s,
                        _ => p[k].theta += s,
                    }
                    f(&p)
                };
                let d = (step(1e-6) - step(-1e-6)) / 2e-6;
                let v = var(k, c).unwrap();
                assert!(close(2.0 * system.grad[v], d, 1e-6), "pose {k} var {c}");
            }
        }
    }

    #[test]
    fn consistent_graph_is_recovered_from_a_perturbed_start() {
        let mut rng = Rng(31);
        let (g, truth) = two_components(0.0, &mut rng);
        let start: Vec<Pose2> = truth
            .iter()
            .enumerate()
            .map(|(k, p)| match k {
                0 | 5 => *p,
                _ => Pose2::new(
                    p.x + rng.range(-0.3, 0.3),
                    p.y + rng.range(-0.3, 0.3),
                    p.theta + rng.range(-0.2, 0.2),
                ),
            })
            .collect();
        let r = refine(&g, &start, &RefineOptions::default()).unwrap();
        assert!(r.initial_chi2 > 1.0);
        assert!(r.chi2 < 1e-20, "{}", r.chi2);
        assert!(r.converged && r.stop == Stop::Converged);
        assert_eq!(r.held, vec![0, 5]);
        assert_eq!((r.poses[0], r.poses[5]), (start[0], start[5]));
        for (p, t) in r.poses.iter().zip(&truth) {
            assert!((p.x - t.x).abs() < 1e-9 && (p.y - t.y).abs() < 1e-9);
            assert!(wrap_angle(p.theta - t.theta).abs() < 1e-9);
        }
    }

    #[test]
    fn refinement_stops_at_a_stationary_point() {
        let mut rng = Rng(37);
        let truth = random_poses(15, &mut rng);
        let g = graph(&truth, &[(0, 14), (3, 9), (12, 2), (5, 10)], 0.2, &mut rng);
        let r = refine(&g, &truth, &RefineOptions::default()).unwrap();
        assert!(r.converged, "{r:?}");
        assert!(r.chi2 < r.initial_chi2 && r.chi2 > 0.0);
        assert!(close(r.chi2, chi2(&g, &r.poses), 1e-14));
        // Central differences of chi2 vanish (to their own accuracy) at every free variable.
        let h = 1e-5;
        for k in 1..15 {
            for c in 0..3 {
                let step = |s: f64| {
                    let mut p = r.poses.clone();
                    match c {
                        0 => p[k].x += s,
                        1 => p[k].y += s,
                        _ => p[k].theta += s,
                    }
                    chi2(&g, &p)
                };
                let d = (step(h) - step(-h)) / (2.0 * h);
                assert!(d.abs() < 1e-7 * r.chi2.max(1.0), "pose {k} var {c}: {d}");
                assert!(step(h) >= r.chi2 && step(-h) >= r.chi2);
            }
        }
        // Zero iterations: the start comes back.
        let none = RefineOptions {
            max_iterations: 0,
            ..Default::default()
        };
        let r0 = refine(&g, &truth, &none).unwrap();
        assert_eq!(
            (r0.poses, r0.iterations, r0.stop),
            (truth, 0, Stop::MaxIterations)
        );
    }

    #[test]
    fn invalid_inputs_are_errors_and_indefinite_information_is_survived() {
        let mut rng = Rng(41);
        let truth = random_poses(5, &mut rng);
        let g = graph(&truth, &[(0, 4)], 0.1, &mut rng);
        let opts = RefineOptions::default();
        let err = |g: &PoseGraph, p: &[Pose2]| refine(g, p, &opts).unwrap_err();
        assert!(matches!(
            err(&g, &truth[..4]),
            RefineError::PoseCount { .. }
        ));
        let mut p = truth.clone();
        p[2].theta = f64::NAN;
        assert_eq!(err(&g, &p), RefineError::NonFinitePose { id: 2 });
        p[2].theta = 0.0;
        p[3].x = f64::INFINITY;
        assert_eq!(err(&g, &p), RefineError::NonFinitePose { id: 3 });
        let mut b = g.clone();
        b.edges[1].measurement.y = f64::NAN;
        assert!(matches!(
            err(&b, &truth),
            RefineError::NonFiniteEdge { edge: 1, .. }
        ));
        let mut b = g.clone();
        b.edges[2].noise.0[4] = f64::INFINITY;
        assert!(matches!(
            err(&b, &truth),
            RefineError::NonFiniteEdge { edge: 2, .. }
        ));
        let mut b = g.clone();
        b.edges[0].j = 9;
        assert!(matches!(
            err(&b, &truth),
            RefineError::IndexOutOfRange { index: 9, .. }
        ));
        let mut b = g.clone();
        b.fixed = vec![5];
        assert!(matches!(
            err(&b, &truth),
            RefineError::IndexOutOfRange { index: 5, .. }
        ));
        let mut b = g.clone();
        b.noise = NoiseKind::Covariance;
        b.edges[3].noise = SymMat3([1.0, 1.0, 0.0, 1.0, 0.0, 1.0]);
        assert!(matches!(
            err(&b, &truth),
            RefineError::SingularCovariance { edge: 3, .. }
        ));
        let mut b = g.clone();
        for e in &mut b.edges {
            e.noise = SymMat3([1e300, 0.0, 0.0, 1e300, 0.0, 1e300]);
        }
        let far: Vec<Pose2> = truth
            .iter()
            .map(|p| Pose2::new(p.x * 1e200, p.y, p.theta))
            .collect();
        assert_eq!(err(&b, &far), RefineError::NonFiniteChi2);
        // Negative definite information on every edge: H + λI does not factor until λ is large;
        // the damping grows and the call returns.
        let mut b = g.clone();
        for e in &mut b.edges {
            e.noise = SymMat3([-1.0, 0.0, 0.0, -1.0, 0.0, -1.0]);
        }
        let r = refine(&b, &truth, &opts).unwrap();
        assert!(r.factorizations >= 1 && r.chi2 <= r.initial_chi2);
        // Nothing to optimize: a single pose, or every pose held.
        let mut one = g.clone();
        one.ids.truncate(1);
        one.edges.clear();
        let r = refine(&one, &truth[..1], &opts).unwrap();
        assert!(r.converged && r.iterations == 0 && r.held == vec![0]);
        let mut all = g.clone();
        all.fixed = (0..5).collect();
        let r = refine(&all, &truth, &opts).unwrap();
        assert!(r.converged && r.poses == truth && r.chi2 == r.initial_chi2);
    }
}
