//! Random SE(3) pose graphs on the synthetic worlds of the 3D benchmarks (issue 15): a sphere,
//! a torus and a grid, like SE-Sync's and g2o's generated `sphere2500`, `torus3D` and `grid3D`
//! (the geometry is pgo's own, below), seeded and reproducible as the planar model is.
//!
//! # The worlds (ground truth)
//!
//! `n` poses with ids 0..n−1 on a path; every world fits in a cube of side L (`side`).
//! - `sphere`: K = ⌈√n⌉ poses per ring and R = ⌈n/K⌉ rings; pose i = rK + s lies at azimuth
//!   φ = 2πs/K and latitude ψ = −π/2 + π(r + ½)/R on the sphere of radius L/2 about the
//!   origin, t = (L/2)(cos ψ cos φ, cos ψ sin φ, sin ψ); its x axis is the direction of travel
//!   along the ring e_φ = (−sin φ, cos φ, 0), its z axis the outward normal, y = z × x.
//! - `torus`: K = ⌈√n⌉ poses per ring, R = ⌈n/K⌉ rings; pose rK + s at u = 2πr/R around the
//!   axis and v = 2πs/K around the tube, radii a = 3L/8 (the tube's centre line) and b = L/8
//!   (the tube): t = ((a + b cos v) cos u, (a + b cos v) sin u, b sin v); x axis along the
//!   ring ∂t/∂v normalized, z axis the outward normal of the tube, y = z × x.
//! - `grid`: a cubic lattice of m = ⌈∛n⌉ points a side, spacing L/m, walked as a boustrophedon
//!   (rows alternate their direction, layers their row order), so consecutive poses are one
//!   step apart; each pose's x axis points along its step to the next pose (the last pose keeps
//!   its predecessor's).
//!
//! # Edges
//!
//! The odometry path (i, i+1), and loop closures among the candidates, each independently with
//! probability P_c: on the sphere and the torus the pose at the same place of the previous ring
//! (i − K, i), on the torus also the last ring to the first when the last ring is complete; on
//! the grid every pair of lattice neighbours that are not consecutive on the path. Edges are
//! written in ascending (i, j) order.
//!
//! # Measurements and their noise
//!
//! With x_i = (R_i, t_i), an edge (i, j) measures x_i⁻¹ x_j:
//!
//! ```text
//! t̃_ij = R_iᵀ (t_j − t_i) + ε_t,       R̃_ij = R_iᵀ R_j Exp(ω)
//! ```
//!
//! - translation: ε_t ~ N(0, σ_t² I₃) (`gaussian:SIGMA`) or uniform in the cube [−h, h]³
//!   (`uniform:HALFWIDTH`);
//! - rotation: ω ~ N(0, σ_R² I₃), an isotropic Gaussian in the tangent space so(3) ≅ ℝ³
//!   (right perturbation, Exp by the quaternion (cos(θ/2), sin(θ/2) ω/θ), θ = |ω|;
//!   `gaussian:SIGMA`), or Exp(ω) replaced by a rotation uniform on SO(3) (Haar: a quaternion of
//!   four standard normals, normalized; `uniform`).
//!
//! The information matrix is the inverse covariance of g2o's error coordinates of the noise
//! actually drawn, block diagonal (the two noises are independent):
//! - translation block: Cov(ε_t)⁻¹ = I/σ_t², or 3I/h² for the uniform cube (variance h²/3).
//!   g2o's error rotates ε_t by R̃ᵀ, which leaves an isotropic covariance unchanged;
//! - rotation block over the quaternion's vector part q_v = sin(θ/2) ω/θ: for ω ~ N(0, σ² I₃),
//!   E[q_v q_vᵀ] = E[sin²(θ/2)]/3 · I = (1 − E[cos θ])/6 · I with E[cos θ] = (1 − σ²) e^{−σ²/2}
//!   (θ² ~ σ²χ²₃: E[sin(sθ)/θ] = s e^{−s²σ²/2}, the isotropic average of e^{i s u·ω};
//!   differentiate in s at s = 1), so the block is 6 / (1 − (1 − σ²) e^{−σ²/2}) · I, which is
//!   4/σ² + O(1) (the first-order q_v ≈ ω/2). For the uniform rotation E[q_v q_vᵀ] = I/4 (a
//!   uniform unit quaternion has E[q_k²] = 1/4), so the block is 4I.
//!
//! A noiseless measurement (σ = 0 or h = 0) has no finite information; its block is written as
//! the identity (the planar model's information), so a noiseless graph has unit-like weights.
//!
//! # Reproducibility
//!
//! The generator is [`Rng`] as in the planar model, with the same three streams of the seed
//! (the first, for the poses, is unused: the worlds are deterministic); the loop-closure stream
//! draws one uniform u per candidate in ascending (i, j) order (none when P_c is 0 or 1), a
//! loop closure iff u < P_c; the noise stream, for every edge in output order, draws ε_t (three
//! normals or three uniforms), then ω (three normals) or the uniform rotation (four normals),
//! also when σ = 0. The functions beyond IEEE arithmetic are the platform's `ln`, `sin`, `cos`
//! (the draws and the worlds' angles), `exp` and `exp_m1` (the information); the sizes K and m
//! are found by integer arithmetic, and nalgebra's quaternion products are plain arithmetic.

use super::{RotationNoise, TranslationNoise};
use crate::graph3::{Edge3, Form3, Graph3, Pose3, Rotation3, SymMat6};
use crate::linalg::rng::{Rng, SplitMix64};
use nalgebra::{Matrix3, Quaternion, Rotation3 as Rot3, UnitQuaternion, Vector3};
use std::f64::consts::{PI, TAU};

/// A synthetic 3D world.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum World3 {
    Sphere,
    Torus,
    Grid,
}

impl World3 {
    pub fn name(self) -> &'static str {
        match self {
            World3::Sphere => "sphere",
            World3::Torus => "torus",
            World3::Grid => "grid",
        }
    }
}

/// What to simulate in 3D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpaceConfig {
    pub world: World3,
    /// Number of poses (ids 0..n−1).
    pub n: usize,
    /// The side L of the cube the world fits in.
    pub side: f64,
    /// Probability P_c of each candidate loop closure.
    pub loop_probability: f64,
    pub rotation_noise: RotationNoise,
    pub translation_noise: TranslationNoise,
    pub seed: u64,
}

impl SpaceConfig {
    /// Checks every value as [`super::SimulationConfig::validate`] does.
    pub fn validate(&self) -> crate::Result<()> {
        super::validate_model(
            self.n,
            self.side,
            self.loop_probability,
            self.rotation_noise,
            self.translation_noise,
        )
    }
}

/// A simulated 3D problem: the graph (vertex lines = ground truth, g2o form) and the truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulated3 {
    pub graph: Graph3,
    pub truth: Vec<Pose3>,
}

/// Poses per ring of the sphere and the torus: ⌈√n⌉ (at least 1).
pub fn ring_size(n: usize) -> usize {
    let mut k = (n as f64).sqrt() as usize;
    while k * k < n {
        k += 1;
    }
    while k > 1 && (k - 1) * (k - 1) >= n {
        k -= 1;
    }
    k.max(1)
}

/// Points a side of the grid: ⌈∛n⌉ (at least 1), by integer search.
pub fn grid_size(n: usize) -> usize {
    let mut m = 1usize;
    while (m as u128).pow(3) < n as u128 {
        m += 1;
    }
    m
}

/// The rotation variance per component of the quaternion's vector part, E[q_k²], of the drawn
/// rotation noise (see the module documentation); `None` when there is no noise.
pub fn quaternion_variance(noise: RotationNoise) -> Option<f64> {
    match noise {
        RotationNoise::Gaussian { sigma } if sigma > 0.0 => {
            let s2 = sigma * sigma;
            // 1 − (1 − σ²) e^{−σ²/2} = −expm1(−σ²/2) + σ² e^{−σ²/2}: both terms ≥ 0, no
            // cancellation for small σ.
            Some(((-(-s2 / 2.0).exp_m1()) + s2 * (-s2 / 2.0).exp()) / 6.0)
        }
        RotationNoise::Gaussian { .. } => None,
        RotationNoise::Uniform => Some(0.25),
    }
}

/// The translation variance per component of the drawn noise; `None` when there is none.
pub fn translation_variance(noise: TranslationNoise) -> Option<f64> {
    match noise {
        TranslationNoise::Gaussian { sigma } if sigma > 0.0 => Some(sigma * sigma),
        TranslationNoise::Uniform { half_width: h } if h > 0.0 => Some(h * h / 3.0),
        _ => None,
    }
}

/// The information matrix of every simulated edge: diag(I/v_t, I/v_q) by the variances above
/// (identity blocks for noiseless parts).
pub fn information(config: &SpaceConfig) -> SymMat6 {
    let t = translation_variance(config.translation_noise).map_or(1.0, |v| 1.0 / v);
    let r = quaternion_variance(config.rotation_noise).map_or(1.0, |v| 1.0 / v);
    let mut m = [0.0; 21];
    // Diagonal positions of the upper triangle stored row by row.
    for (k, v) in [(0, t), (6, t), (11, t), (15, r), (18, r), (20, r)] {
        m[k] = v;
    }
    SymMat6(m)
}

fn pose_of(t: Vector3<f64>, q: UnitQuaternion<f64>) -> Pose3 {
    let q = canonical(q);
    let c = q.quaternion();
    Pose3 {
        translation: [t.x, t.y, t.z],
        rotation: Rotation3::Quaternion([c.i, c.j, c.k, c.w]),
    }
}

/// q or −q, whichever has w ≥ 0 (the same rotation; a fixed choice for the file).
fn canonical(q: UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    if q.quaternion().w < 0.0 {
        UnitQuaternion::new_unchecked(-q.into_inner())
    } else {
        q
    }
}

/// The rotation with columns x, z × x, z (x ⟂ z unit vectors).
fn frame(x: Vector3<f64>, z: Vector3<f64>) -> UnitQuaternion<f64> {
    let y = z.cross(&x);
    let m = Matrix3::from_columns(&[x, y, z]);
    UnitQuaternion::from_rotation_matrix(&Rot3::from_matrix_unchecked(m))
}

/// The ground truth of a world (see the module documentation).
pub fn world_truth(world: World3, n: usize, side: f64) -> Vec<Pose3> {
    match world {
        World3::Sphere | World3::Torus => {
            let k = ring_size(n);
            let rings = n.div_ceil(k);
            (0..n)
                .map(|i| {
                    let (r, s) = (i / k, i % k);
                    let along = TAU * s as f64 / k as f64;
                    let (sa, ca) = along.sin_cos();
                    if world == World3::Sphere {
                        let lat = -PI / 2.0 + PI * (r as f64 + 0.5) / rings as f64;
                        let (sl, cl) = lat.sin_cos();
                        let normal = Vector3::new(cl * ca, cl * sa, sl);
                        let tangent = Vector3::new(-sa, ca, 0.0);
                        pose_of(normal * (side / 2.0), frame(tangent, normal))
                    } else {
                        let (a, b) = (3.0 * side / 8.0, side / 8.0);
                        let u = TAU * r as f64 / rings as f64;
                        let (su, cu) = u.sin_cos();
                        // v = `along`: around the tube.
                        let normal = Vector3::new(ca * cu, ca * su, sa);
                        let tangent = Vector3::new(-sa * cu, -sa * su, ca);
                        let centre = Vector3::new(a * cu, a * su, 0.0);
                        pose_of(centre + normal * b, frame(tangent, normal))
                    }
                })
                .collect()
        }
        World3::Grid => {
            let m = grid_size(n);
            let spacing = side / m as f64;
            let cells: Vec<[usize; 3]> = (0..n).map(|i| grid_cell(i, m)).collect();
            (0..n)
                .map(|i| {
                    let c = cells[i];
                    let step = if i + 1 < n {
                        Some((c, cells[i + 1]))
                    } else if i > 0 {
                        Some((cells[i - 1], c))
                    } else {
                        None
                    };
                    let q = step.map_or(UnitQuaternion::identity(), |(a, b)| heading(a, b));
                    let t = Vector3::new(c[0] as f64, c[1] as f64, c[2] as f64) * spacing;
                    pose_of(t, q)
                })
                .collect()
        }
    }
}

/// The lattice cell [x, y, z] of path position i in the boustrophedon of an m³ grid: layer
/// z = i / m², rows in order in even layers and reversed in odd ones, each row's direction
/// alternating with the row's global count z·m + row.
fn grid_cell(i: usize, m: usize) -> [usize; 3] {
    let z = i / (m * m);
    let k = i % (m * m);
    let (row, col) = (k / m, k % m);
    let y = if z.is_multiple_of(2) {
        row
    } else {
        m - 1 - row
    };
    let x = if (z * m + row).is_multiple_of(2) {
        col
    } else {
        m - 1 - col
    };
    [x, y, z]
}

/// The path position of lattice cell c (the inverse of [`grid_cell`]).
fn grid_index(c: [usize; 3], m: usize) -> usize {
    let [x, y, z] = c;
    let row = if z.is_multiple_of(2) { y } else { m - 1 - y };
    let col = if (z * m + row).is_multiple_of(2) {
        x
    } else {
        m - 1 - x
    };
    z * m * m + row * m + col
}

/// The rotation taking e_x to the unit step from cell a to its lattice neighbour b: exact
/// quaternions of quarter and half turns about z (±x, ±y) or y (±z).
fn heading(a: [usize; 3], b: [usize; 3]) -> UnitQuaternion<f64> {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let q =
        |x: f64, y: f64, z: f64, w: f64| UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z));
    let d = |k: usize| b[k] as i64 - a[k] as i64;
    match (d(0), d(1), d(2)) {
        (-1, 0, 0) => q(0.0, 0.0, 1.0, 0.0),
        (0, 1, 0) => q(0.0, 0.0, h, h),
        (0, -1, 0) => q(0.0, 0.0, -h, h),
        (0, 0, 1) => q(0.0, -h, 0.0, h),
        (0, 0, -1) => q(0.0, h, 0.0, h),
        _ => UnitQuaternion::identity(),
    }
}

/// The candidate loop closures (i, j), i < j − 1, of a world in ascending order.
pub fn loop_candidates(world: World3, n: usize) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    match world {
        World3::Sphere | World3::Torus => {
            let k = ring_size(n);
            for j in k..n {
                if j - k + 1 < j {
                    pairs.push((j - k, j));
                }
            }
            let rings = n.div_ceil(k);
            if world == World3::Torus && rings > 2 && n == rings * k {
                // The last ring back to the first.
                pairs.extend((0..k).map(|s| (s, (rings - 1) * k + s)));
            }
        }
        World3::Grid => {
            let m = grid_size(n);
            for j in 0..n {
                let c = grid_cell(j, m);
                for axis in 0..3 {
                    if c[axis] == 0 {
                        continue;
                    }
                    let mut b = c;
                    b[axis] -= 1;
                    let i = grid_index(b, m);
                    if i < n && i + 1 != j && j + 1 != i {
                        pairs.push((i.min(j), i.max(j)));
                    }
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// Exp(ω) as a unit quaternion: (cos(θ/2), sin(θ/2) ω/θ), θ = |ω|.
pub fn exp_quaternion(w: Vector3<f64>) -> UnitQuaternion<f64> {
    let theta = w.norm();
    let s = if theta == 0.0 {
        0.5
    } else {
        (theta / 2.0).sin() / theta
    };
    UnitQuaternion::new_unchecked(Quaternion::new(
        (theta / 2.0).cos(),
        s * w.x,
        s * w.y,
        s * w.z,
    ))
}

/// Draws a 3D pose graph on a world (see the module documentation for the model, the
/// information matrices and the draw order).
///
/// # Panics
///
/// If the configuration is invalid ([`SpaceConfig::validate`]).
pub fn simulate3(config: &SpaceConfig) -> Simulated3 {
    if let Err(e) = config.validate() {
        panic!("invalid simulation configuration: {e}");
    }
    let n = config.n;
    let mut seeder = SplitMix64::new(config.seed);
    let _pose_rng = Rng::from_splitmix(&mut seeder);
    let mut edge_rng = Rng::from_splitmix(&mut seeder);
    let mut noise_rng = Rng::from_splitmix(&mut seeder);
    let truth = world_truth(config.world, n, config.side);

    let p = config.loop_probability;
    let mut pairs: Vec<(usize, usize)> = (1..n).map(|j| (j - 1, j)).collect();
    if p > 0.0 {
        for c in loop_candidates(config.world, n) {
            if p == 1.0 || edge_rng.uniform() < p {
                pairs.push(c);
            }
        }
    }
    pairs.sort_unstable();

    let information = information(config);
    let isometries: Vec<_> = truth.iter().map(|x| x.to_isometry()).collect();
    let edges = pairs
        .into_iter()
        .map(|(i, j)| {
            let (a, b) = (&isometries[i], &isometries[j]);
            let e = match config.translation_noise {
                TranslationNoise::Gaussian { sigma } => {
                    let z: [f64; 3] = std::array::from_fn(|_| noise_rng.normal());
                    Vector3::from(z) * sigma
                }
                TranslationNoise::Uniform { half_width: h } => {
                    let u: [f64; 3] = std::array::from_fn(|_| 2.0 * noise_rng.uniform() - 1.0);
                    Vector3::from(u) * h
                }
            };
            let noise = match config.rotation_noise {
                RotationNoise::Gaussian { sigma } => {
                    let z: [f64; 3] = std::array::from_fn(|_| noise_rng.normal());
                    exp_quaternion(Vector3::from(z) * sigma)
                }
                RotationNoise::Uniform => loop {
                    let z: [f64; 4] = std::array::from_fn(|_| noise_rng.normal());
                    let q = Quaternion::new(z[3], z[0], z[1], z[2]);
                    // A zero draw has probability 0; draw again rather than divide by 0.
                    if q.norm() > 0.0 {
                        break UnitQuaternion::from_quaternion(q);
                    }
                },
            };
            let t = a.rotation.inverse() * (b.translation.vector - a.translation.vector) + e;
            let r = a.rotation.inverse() * b.rotation * noise;
            Edge3 {
                i,
                j,
                measurement: pose_of(t, r),
                information,
            }
        })
        .collect();
    Simulated3 {
        graph: Graph3 {
            ids: (0..n as u64).map(|k| k as _).collect(),
            poses: truth.clone(),
            edges,
            fixed: Vec::new(),
            form: Form3::G2o,
        },
        truth,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_ceilings() {
        for n in 0..2000usize {
            let k = ring_size(n);
            assert!(k * k >= n && (k == 1 || (k - 1) * (k - 1) < n), "{n}: {k}");
            let m = grid_size(n);
            assert!(m.pow(3) >= n && (m == 1 || (m - 1).pow(3) < n), "{n}: {m}");
        }
    }

    #[test]
    fn the_grid_walk_steps_to_a_neighbour_and_inverts() {
        for m in 1..7 {
            for i in 0..m * m * m {
                let c = grid_cell(i, m);
                assert_eq!(grid_index(c, m), i);
                if i + 1 < m * m * m {
                    let d = grid_cell(i + 1, m);
                    let dist: usize = (0..3).map(|k| c[k].abs_diff(d[k])).sum();
                    assert_eq!(dist, 1, "m {m}, step {i}");
                }
            }
        }
    }

    #[test]
    fn headings_turn_x_onto_the_step() {
        let base = [1, 1, 1];
        for axis in 0..3 {
            for up in [true, false] {
                let mut b = base;
                if up {
                    b[axis] += 1
                } else {
                    b[axis] -= 1
                };
                let v = heading(base, b) * Vector3::x();
                let mut want = Vector3::zeros();
                want[axis] = if up { 1.0 } else { -1.0 };
                assert!((v - want).norm() < 1e-15, "{axis} {up}: {v}");
            }
        }
    }

    #[test]
    fn quaternion_variance_is_a_quarter_sigma_squared_for_small_sigma() {
        for sigma in [1e-6, 1e-3, 0.01] {
            let v = quaternion_variance(RotationNoise::Gaussian { sigma }).unwrap();
            let first = sigma * sigma / 4.0;
            // The next term is −(5/48)σ⁴.
            assert!((v - first).abs() <= 0.2 * sigma.powi(4) + 1e-30, "{sigma}");
        }
        // σ → ∞: θ mod 2π spreads out, E[cos θ] → 0, the variance → 1/6.
        let v = quaternion_variance(RotationNoise::Gaussian { sigma: 40.0 }).unwrap();
        assert!((v - 1.0 / 6.0).abs() < 1e-12);
    }
}
