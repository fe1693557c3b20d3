//! Random planar pose graphs (and, in [`space`], SE(3) graphs on the 3D benchmark worlds) by the measurement model of the paper's simulations (Calafiore,
//! Carlone and Dellaert, Sec. 6 "Simulation setup", eq. (47)), seeded and reproducible.
//!
//! The model:
//! - `n` poses x_i = (p_i, θ_i): positions uniform in the square [0, side)² (the paper: a
//!   10 m x 10 m square), headings uniform in (−π, π];
//! - edges: the spanning path (i, i+1) ("odometric edges"), and a loop closure (i, j) for every
//!   other pair i < j, j > i + 1, independently with probability P_c (the paper: 0.1) — about
//!   P_c·n²/2 of them, which is the paper's model for its small n and far too many for large n
//!   (`pgo-simulate -n 100000` would make 5·10⁸): [`LoopModel::PerPose`] is a model whose loop
//!   closures grow linearly, each pose j ≥ 2 closing a loop to one earlier pose with probability
//!   P_c, and [`SimulationConfig::expected_loop_closures`] tells the size beforehand;
//! - measurements, eq. (47):
//!
//! ```text
//! Δ_ij = R_iᵀ (p_j − p_i) + ε_Δ,    ε_Δ ~ N(0₂, σ_Δ² I₂)   (or uniform in [−h, h]²)
//! R_ij = R_iᵀ R_j R(ε_R),           ε_R ~ N(0, σ_R²)        (or uniform in (−π, π])
//! ```
//!
//!   so the measured angle is θ_ij = wrap(θ_j − θ_i + ε_R), wrapped to (−π, π]. The paper's
//!   defaults are σ_R = σ_Δ = 0.1; its "uniform" cases are ε_R uniform in (−π, π] and ε_Δ
//!   uniform in [−5, 5]².
//!
//! Every information matrix is the identity, so `--weights unit` (τ = κ = 1) reproduces the
//! paper's cost (5)/(8) exactly; with zero noise the graph is balanced (every cycle composes to
//! the identity, up to rounding).
//!
//! # Reproducibility
//!
//! The random numbers come from pgo's own generator, [`Rng`] (xoshiro256** seeded by
//! SplitMix64), not from a crate whose stream could change with its version. Uniform deviates
//! are built from the top 53 bits of a draw and normal deviates by the Box-Muller transform, so
//! the only floating-point functions beyond IEEE-754 arithmetic (+, −, ×, ÷, √, all correctly
//! rounded) are `ln`, `sin` and `cos` of the standard library. The same seed and configuration
//! therefore give the same graph, bit for bit, on every platform whose `ln`, `sin` and `cos`
//! agree (they are the platform's libm; glibc, musl and macOS agree on the arguments that arise
//! here in practice, which `tests/simulate.rs` pins).
//!
//! Three independent streams are derived from the seed (the first twelve SplitMix64 outputs: four
//! state words each): one for the poses, one for the loop closures, one for the noise. So the
//! ground truth does not depend on P_c or the noise, and the edge set does not depend on the
//! noise. Draw order within a stream:
//! - poses: for i = 0..n: x_i, y_i, θ_i;
//! - loop closures, [`LoopModel::Pairs`]: for i = 0..n, for j = i+2..n: one uniform u, a loop
//!   closure iff u < P_c (no draws when P_c is 0 or 1); [`LoopModel::PerPose`]: for j = 2..n: one
//!   uniform u (none when P_c is 0 or 1), and if u < P_c one uniform v, the loop closure
//!   (⌊v·(j−1)⌋, j) (no draws at all when P_c is 0);
//! - noise: for every edge in output order: ε_Δ (two normals or two uniforms), then ε_R (a normal
//!   or a uniform). Normals come in Box-Muller pairs; the second of a pair is kept for the next
//!   normal. Draws happen also when σ = 0, so σ does not shift the stream.
//!
//! Edges are written in ascending (i, j) order: after the odometry edge (i, i+1) come the loop
//! closures (i, j), j > i + 1.

pub mod space;

use crate::error::Error;
use crate::graph::{
    Edge, LandmarkForm, Landmarks, MAX_VERTEX_ID, Observation, Pose2, PoseGraph, SymMat2, SymMat3,
};
pub use crate::linalg::rng::{Rng, SplitMix64};
use std::f64::consts::{PI, TAU};
use std::fmt;
use std::str::FromStr;

/// The distribution of the rotation noise ε_R of eq. (47).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RotationNoise {
    /// ε_R ~ N(0, σ²) (radians).
    Gaussian { sigma: f64 },
    /// ε_R uniform in (−π, π]: uninformative rotation measurements.
    Uniform,
}

/// The distribution of the translation noise ε_Δ of eq. (47).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TranslationNoise {
    /// ε_Δ ~ N(0₂, σ² I₂) (metres).
    Gaussian { sigma: f64 },
    /// ε_Δ uniform in the square [−h, h]².
    Uniform { half_width: f64 },
}

/// Which loop closures are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum LoopModel {
    /// The paper's model (47): every pair (i, j), j > i + 1, with probability P_c (about
    /// P_c n^2/2 loop closures: for small n)
    #[default]
    Pairs,
    /// Each pose j >= 2 with probability P_c closes one loop to an earlier pose drawn uniformly
    /// (about P_c n loop closures: linear in n)
    PerPose,
}

impl LoopModel {
    pub fn name(self) -> &'static str {
        match self {
            LoopModel::Pairs => "pairs",
            LoopModel::PerPose => "per-pose",
        }
    }
}

/// What to simulate. [`Default`] is the paper's setup: n = 10, a 10 m square, P_c = 0.1,
/// σ_R = σ_Δ = 0.1, seed 0, loop closures by pairs (eq. (47)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulationConfig {
    /// Number of poses (ids 0..n−1).
    pub n: usize,
    /// Side of the square positions are drawn from, [0, side)².
    pub side: f64,
    /// Probability P_c of a loop closure between two poses that are not consecutive (per pair,
    /// or per pose: [`LoopModel`]).
    pub loop_probability: f64,
    pub loop_model: LoopModel,
    pub rotation_noise: RotationNoise,
    pub translation_noise: TranslationNoise,
    pub seed: u64,
}

impl Default for SimulationConfig {
    fn default() -> Self {
        SimulationConfig {
            n: 10,
            side: 10.0,
            loop_probability: 0.1,
            loop_model: LoopModel::Pairs,
            rotation_noise: RotationNoise::Gaussian { sigma: 0.1 },
            translation_noise: TranslationNoise::Gaussian { sigma: 0.1 },
            seed: 0,
        }
    }
}

impl SimulationConfig {
    /// The pairs (i, j), j > i + 1, a loop closure can join: (n−1)(n−2)/2 (as a float: it
    /// overflows 64-bit integers for the largest n).
    pub fn candidate_pairs(&self) -> f64 {
        let n = self.n as f64;
        if self.n < 3 {
            0.0
        } else {
            (n - 1.0) * (n - 2.0) / 2.0
        }
    }

    /// The expected number of loop closures: P_c·(n−1)(n−2)/2 by pairs, P_c·(n−2) per pose.
    pub fn expected_loop_closures(&self) -> f64 {
        match self.loop_model {
            LoopModel::Pairs => self.loop_probability * self.candidate_pairs(),
            LoopModel::PerPose => self.loop_probability * self.n.saturating_sub(2) as f64,
        }
    }

    /// The uniform deviates drawn to choose the loop closures (see the module documentation).
    pub fn loop_draws(&self) -> f64 {
        let p = self.loop_probability;
        match self.loop_model {
            _ if p == 0.0 => 0.0,
            LoopModel::Pairs if p == 1.0 => 0.0,
            LoopModel::Pairs => self.candidate_pairs(),
            LoopModel::PerPose => {
                let poses = self.n.saturating_sub(2) as f64;
                if p == 1.0 { poses } else { poses * (1.0 + p) }
            }
        }
    }

    /// Checks every value: n at most 2³¹ (ids must fit g2o's `int`), side finite and positive,
    /// P_c in [0, 1], σ and h finite and non-negative.
    pub fn validate(&self) -> crate::Result<()> {
        validate_model(
            self.n,
            self.side,
            self.loop_probability,
            self.rotation_noise,
            self.translation_noise,
        )
    }
}

/// The checks of [`SimulationConfig::validate`], shared with the 3D worlds
/// (`space::SpaceConfig::validate`): n at most 2³¹, side finite and positive, P_c in [0, 1],
/// σ and h finite and non-negative.
pub(crate) fn validate_model(
    n: usize,
    side: f64,
    loop_probability: f64,
    rotation_noise: RotationNoise,
    translation_noise: TranslationNoise,
) -> crate::Result<()> {
    let invalid = |m: String| Err(Error::Invalid(m));
    if n > MAX_VERTEX_ID as usize + 1 {
        return invalid(format!(
            "n = {n} poses: ids must fit g2o's int, at most {}",
            MAX_VERTEX_ID as u64 + 1
        ));
    }
    if !(side.is_finite() && side > 0.0) {
        return invalid(format!("side = {side}: must be a finite number > 0"));
    }
    if !(0.0..=1.0).contains(&loop_probability) {
        return invalid(format!(
            "loop probability = {loop_probability}: must be in [0, 1]"
        ));
    }
    if let RotationNoise::Gaussian { sigma } = rotation_noise {
        check_scale("rotation noise sigma", sigma).map_err(Error::Invalid)?;
    }
    match translation_noise {
        TranslationNoise::Gaussian { sigma } => {
            check_scale("translation noise sigma", sigma).map_err(Error::Invalid)?
        }
        TranslationNoise::Uniform { half_width } => {
            check_scale("translation noise half-width", half_width).map_err(Error::Invalid)?
        }
    }
    Ok(())
}

/// A simulated problem: the graph (poses = ground truth) and the ground truth itself.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulated {
    /// Ids 0..n−1, `poses` = the ground truth, edges in ascending (i, j) order with identity
    /// information matrices, no FIX.
    pub graph: PoseGraph,
    /// The true poses x_i = (p_i, θ_i), θ_i in (−π, π].
    pub truth: Vec<Pose2>,
}

/// Draws a random pose graph by the model of Sec. 6 and eq. (47) (see the module documentation
/// for the model and the exact draw order).
///
/// # Panics
///
/// If the configuration is invalid ([`SimulationConfig::validate`]).
pub fn simulate(config: &SimulationConfig) -> Simulated {
    if let Err(e) = config.validate() {
        panic!("invalid simulation configuration: {e}");
    }
    let n = config.n;
    let mut seeder = SplitMix64::new(config.seed);
    let mut pose_rng = Rng::from_splitmix(&mut seeder);
    let mut edge_rng = Rng::from_splitmix(&mut seeder);
    let mut noise_rng = Rng::from_splitmix(&mut seeder);

    let truth: Vec<Pose2> = (0..n)
        .map(|_| {
            let x = config.side * pose_rng.uniform();
            let y = config.side * pose_rng.uniform();
            let theta = pose_rng.angle();
            Pose2::new(x, y, theta)
        })
        .collect();

    // Topology: the spanning path plus the loop closures, in ascending (i, j) order.
    let p = config.loop_probability;
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    match config.loop_model {
        LoopModel::Pairs => {
            for i in 0..n {
                if i + 1 < n {
                    pairs.push((i, i + 1));
                }
                if p == 0.0 {
                    continue;
                }
                for j in i + 2..n {
                    if p == 1.0 || edge_rng.uniform() < p {
                        pairs.push((i, j));
                    }
                }
            }
        }
        LoopModel::PerPose => {
            pairs.extend((1..n).map(|j| (j - 1, j)));
            if p > 0.0 {
                for j in 2..n {
                    if p == 1.0 || edge_rng.uniform() < p {
                        // ⌊v·(j−1)⌋ ≤ j − 2; the clamp only guards the rounding of v·(j−1).
                        let i = ((edge_rng.uniform() * (j - 1) as f64) as usize).min(j - 2);
                        pairs.push((i, j));
                    }
                }
            }
            pairs.sort_unstable();
        }
    }

    let edges = pairs
        .into_iter()
        .map(|(i, j)| {
            let (a, b) = (truth[i], truth[j]);
            // R_iᵀ (p_j − p_i), R_i = [[c, −s], [s, c]].
            let (c, s) = (a.theta.cos(), a.theta.sin());
            let (dx, dy) = (b.x - a.x, b.y - a.y);
            let (ex, ey) = match config.translation_noise {
                TranslationNoise::Gaussian { sigma } => {
                    let (zx, zy) = (noise_rng.normal(), noise_rng.normal());
                    (sigma * zx, sigma * zy)
                }
                TranslationNoise::Uniform { half_width: h } => (
                    h * (2.0 * noise_rng.uniform() - 1.0),
                    h * (2.0 * noise_rng.uniform() - 1.0),
                ),
            };
            let e_rot = match config.rotation_noise {
                RotationNoise::Gaussian { sigma } => sigma * noise_rng.normal(),
                RotationNoise::Uniform => noise_rng.angle(),
            };
            Edge {
                i,
                j,
                measurement: Pose2::new(
                    c * dx + s * dy + ex,
                    -s * dx + c * dy + ey,
                    wrap_angle(b.theta - a.theta + e_rot),
                ),
                noise: SymMat3::IDENTITY,
            }
        })
        .collect();

    Simulated {
        graph: PoseGraph::with_edges(truth.clone(), edges),
        truth,
    }
}

/// Landmarks added to a simulated world ([`add_landmarks`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandmarkConfig {
    /// Number of landmarks m, positions uniform in the square of the poses.
    pub count: usize,
    /// A pose observes every landmark within this distance (metres).
    pub range: f64,
}

/// Adds `landmarks.count` landmarks to a simulated world (issue 13): positions uniform in
/// [0, side)², and an observation d_ik = R_iᵀ (l_k − p_i) + ε_d from every pose i of every
/// landmark k with |l_k − p_i| ≤ range, ε_d drawn as the translation noise ε_Δ of eq. (47)
/// (the configuration's), information the identity. Landmarks that no pose sees are dropped
/// (a file declares only what is observed); the kept ones get ids n, n+1, ... in g2o's form
/// (`VERTEX_XY` at the true position, `EDGE_SE2_XY`), in order of their draw.
///
/// Reproducible: the draws come from a fourth stream of the seed (SplitMix64 outputs 13..16,
/// after the three of [`simulate`], so the poses, edges and their noise are those of
/// [`simulate`] with the same configuration): for k = 0..m: x_k, y_k; then for every
/// observation, poses ascending and for each pose landmarks ascending: ε_d (two normals or two
/// uniforms, drawn also when σ = 0).
pub fn add_landmarks(sim: &mut Simulated, config: &SimulationConfig, landmarks: &LandmarkConfig) {
    let mut seeder = SplitMix64::new(config.seed);
    for _ in 0..3 {
        Rng::from_splitmix(&mut seeder);
    }
    let mut rng = Rng::from_splitmix(&mut seeder);
    let points: Vec<[f64; 2]> = (0..landmarks.count)
        .map(|_| {
            let x = config.side * rng.uniform();
            let y = config.side * rng.uniform();
            [x, y]
        })
        .collect();
    let mut seen = Vec::new();
    for (i, a) in sim.truth.iter().enumerate() {
        let (c, s) = (a.theta.cos(), a.theta.sin());
        for (k, l) in points.iter().enumerate() {
            let (dx, dy) = (l[0] - a.x, l[1] - a.y);
            if dx.hypot(dy) > landmarks.range {
                continue;
            }
            let (ex, ey) = match config.translation_noise {
                TranslationNoise::Gaussian { sigma } => {
                    let (zx, zy) = (rng.normal(), rng.normal());
                    (sigma * zx, sigma * zy)
                }
                TranslationNoise::Uniform { half_width: h } => (
                    h * (2.0 * rng.uniform() - 1.0),
                    h * (2.0 * rng.uniform() - 1.0),
                ),
            };
            seen.push((i, k, [c * dx + s * dy + ex, -s * dx + c * dy + ey]));
        }
    }
    let mut index = vec![usize::MAX; points.len()];
    let mut kept = Vec::new();
    let mut by_draw: Vec<usize> = seen.iter().map(|o| o.1).collect();
    by_draw.sort_unstable();
    by_draw.dedup();
    for k in by_draw {
        index[k] = kept.len();
        kept.push(k);
    }
    let n = sim.truth.len();
    sim.graph.landmarks = Landmarks {
        ids: (0..kept.len()).map(|k| (n + k) as u32).collect(),
        positions: kept.iter().map(|&k| points[k]).collect(),
        observations: seen
            .into_iter()
            .map(|(pose, k, d)| Observation {
                pose,
                landmark: index[k],
                d,
                information: SymMat2::IDENTITY,
            })
            .collect(),
        declared: true,
        form: LandmarkForm::G2o,
    };
}

/// The angle `a` wrapped to (−π, π] (for finite `a`): `a mod 2π` by the exact IEEE remainder,
/// then shifted by one turn if needed.
pub fn wrap_angle(a: f64) -> f64 {
    let mut w = a % TAU;
    if w > PI {
        w -= TAU;
    } else if w <= -PI {
        w += TAU;
    }
    // `w ∓ TAU` rounds; a result a hair outside the interval lands on the nearer end.
    if w > PI || w <= -PI { PI } else { w }
}

fn check_scale(what: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("{what} = {v}: must be a finite number >= 0"))
    }
}

fn parse_scale(what: &str, text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("{what} '{text}' is not a number"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{what} '{text}' must be a finite number >= 0"))
    }
}

impl FromStr for RotationNoise {
    type Err = String;

    /// `gaussian:SIGMA` (σ_R ≥ 0, radians) or `uniform` (uniform in (−π, π]).
    fn from_str(s: &str) -> Result<Self, String> {
        match s.split_once(':') {
            Some(("gaussian", sigma)) => Ok(RotationNoise::Gaussian {
                sigma: parse_scale("SIGMA", sigma)?,
            }),
            None if s == "uniform" => Ok(RotationNoise::Uniform),
            Some(("uniform", _)) => Err(
                "'uniform' takes no parameter: rotation noise is uniform in (-pi, pi]".to_string(),
            ),
            None if s == "gaussian" => {
                Err("'gaussian' needs a standard deviation: gaussian:SIGMA".to_string())
            }
            _ => Err(format!("expected gaussian:SIGMA or uniform, found '{s}'")),
        }
    }
}

impl FromStr for TranslationNoise {
    type Err = String;

    /// `gaussian:SIGMA` (σ_Δ ≥ 0, metres) or `uniform:HALFWIDTH` (uniform in [−h, h]²).
    fn from_str(s: &str) -> Result<Self, String> {
        match s.split_once(':') {
            Some(("gaussian", sigma)) => Ok(TranslationNoise::Gaussian {
                sigma: parse_scale("SIGMA", sigma)?,
            }),
            Some(("uniform", h)) => Ok(TranslationNoise::Uniform {
                half_width: parse_scale("HALFWIDTH", h)?,
            }),
            None if s == "gaussian" => {
                Err("'gaussian' needs a standard deviation: gaussian:SIGMA".to_string())
            }
            None if s == "uniform" => Err(
                "'uniform' needs a half-width: uniform:HALFWIDTH (noise uniform in [-h, h]^2)"
                    .to_string(),
            ),
            _ => Err(format!(
                "expected gaussian:SIGMA or uniform:HALFWIDTH, found '{s}'"
            )),
        }
    }
}

impl fmt::Display for RotationNoise {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RotationNoise::Gaussian { sigma } => write!(f, "gaussian:{sigma}"),
            RotationNoise::Uniform => f.write_str("uniform"),
        }
    }
}

impl fmt::Display for TranslationNoise {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TranslationNoise::Gaussian { sigma } => write!(f, "gaussian:{sigma}"),
            TranslationNoise::Uniform { half_width } => write!(f, "uniform:{half_width}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        assert_eq!(wrap_angle(PI), PI);
        assert_eq!(wrap_angle(-PI), PI);
        assert_eq!(wrap_angle(0.0), 0.0);
        assert_eq!(wrap_angle(TAU), 0.0);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert!((wrap_angle(-7.0) - (-7.0 + TAU)).abs() < 1e-15);
        for k in -1000..=1000 {
            let w = wrap_angle(k as f64 * 0.37);
            assert!(w > -PI && w <= PI, "{k}: {w}");
        }
    }

    #[test]
    fn noise_specs_parse_and_print_back() {
        for s in ["gaussian:0.1", "gaussian:0", "uniform"] {
            assert_eq!(s.parse::<RotationNoise>().unwrap().to_string(), s);
        }
        for s in ["gaussian:0.25", "uniform:5"] {
            assert_eq!(s.parse::<TranslationNoise>().unwrap().to_string(), s);
        }
        for bad in [
            "gaussian:-1",
            "gaussian:x",
            "gaussian",
            "uniform:1",
            "laplace:1",
            "",
        ] {
            assert!(bad.parse::<RotationNoise>().is_err(), "{bad}");
        }
        for bad in [
            "gaussian:nan",
            "uniform",
            "uniform:-5",
            "uniform:inf",
            "cauchy",
        ] {
            assert!(bad.parse::<TranslationNoise>().is_err(), "{bad}");
        }
    }

    #[test]
    fn one_pose_has_no_edges_and_zero_poses_are_fine() {
        for n in [0, 1] {
            let s = simulate(&SimulationConfig {
                n,
                ..Default::default()
            });
            assert_eq!(s.graph.num_poses(), n);
            assert!(s.graph.edges.is_empty());
        }
    }

    #[test]
    fn certain_loop_closures_give_the_complete_graph() {
        let s = simulate(&SimulationConfig {
            n: 7,
            loop_probability: 1.0,
            ..Default::default()
        });
        let pairs: Vec<(usize, usize)> = s.graph.edges.iter().map(|e| (e.i, e.j)).collect();
        let all: Vec<(usize, usize)> = (0..7)
            .flat_map(|i| (i + 1..7).map(move |j| (i, j)))
            .collect();
        assert_eq!(pairs, all);
    }

    #[test]
    fn per_pose_loop_closures_are_linear_distinct_and_reach_back() {
        let config = SimulationConfig {
            n: 20_000,
            loop_model: LoopModel::PerPose,
            loop_probability: 0.3,
            ..Default::default()
        };
        let s = simulate(&config);
        let edges = &s.graph.edges;
        let pairs: Vec<(usize, usize)> = edges.iter().map(|e| (e.i, e.j)).collect();
        assert!(pairs.windows(2).all(|w| w[0] < w[1]), "ascending, distinct");
        assert!(pairs.iter().all(|&(i, j)| i < j && j < config.n));
        let loops: Vec<&(usize, usize)> = pairs.iter().filter(|(i, j)| j - i > 1).collect();
        assert_eq!(pairs.len() - loops.len(), config.n - 1, "the odometry path");
        // At most one per pose; Binomial(19998, 0.3): mean 5999.4, sd 64.8.
        let mut by_pose = vec![0; config.n];
        for &&(_, j) in &loops {
            by_pose[j] += 1;
        }
        assert!(by_pose.iter().all(|&c| c <= 1));
        let expected = config.expected_loop_closures();
        assert!(
            (loops.len() as f64 - expected).abs() < 5.0 * 64.8,
            "{}",
            loops.len()
        );
        // i uniform below j − 1: the mean of i/(j−1) is 1/2 (sd 0.29/sqrt(6000) = 0.004).
        let mean = loops
            .iter()
            .map(|&&(i, j)| (i as f64 + 0.5) / (j - 1) as f64)
            .sum::<f64>()
            / loops.len() as f64;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
        // Certain loop closures: one per pose from 2 on.
        let all = simulate(&SimulationConfig {
            loop_probability: 1.0,
            ..config
        });
        assert_eq!(all.graph.edges.len(), 2 * config.n - 3);
    }

    #[test]
    fn the_expected_size_is_known_before_drawing() {
        let big = SimulationConfig {
            n: 100_000,
            ..Default::default()
        };
        assert_eq!(big.candidate_pairs(), 99_999.0 * 99_998.0 / 2.0);
        assert!((big.expected_loop_closures() - 0.1 * 99_999.0 * 99_998.0 / 2.0).abs() < 1.0);
        let linear = SimulationConfig {
            loop_model: LoopModel::PerPose,
            ..big
        };
        assert!((linear.expected_loop_closures() - 0.1 * 99_998.0).abs() < 1e-6);
        for n in [0, 1, 2] {
            let c = SimulationConfig { n, ..big };
            assert_eq!(c.expected_loop_closures(), 0.0);
        }
    }

    #[test]
    #[should_panic(expected = "loop probability")]
    fn invalid_probability_panics() {
        simulate(&SimulationConfig {
            loop_probability: 1.5,
            ..Default::default()
        });
    }
}
