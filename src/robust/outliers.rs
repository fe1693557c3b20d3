//! False loop closures planted in an existing graph by Vertigo's outlier models (Sünderhauf and
//! Protzel's benchmark generator, `generateDataset.py` of openslam_vertigo), reproducibly, so
//! that a robust back end can be scored against the edges known to be false.
//!
//! Each of `count` draws picks a pair of poses (dense indices v1 < v2, never consecutive, both at
//! most n − 1 − G so that the group fits), then a measurement z = (x, y, θ) with x, y ~ N(0, 0.3 m)
//! and θ ~ N(0, 10°), and appends G edges (v1 + k, v2 + k, z), k = 0..G−1: a group of G
//! consecutive pairs sharing one measurement. The pair is drawn
//!
//! - `random`: v1 and v2 uniform over the poses;
//! - `local`: v1 uniform, v2 uniform in [v1, v1 + 20].
//!
//! As in Vertigo, a draw with v1 = v2 is repeated and v2 = v1 + 1 becomes v1 + 2. The information
//! matrix of every outlier is that of the graph's first loop closure (the first edge whose ids
//! are not consecutive), else of its first edge, unless one is given. Vertigo's own generator
//! counts groups the same way: `count` groups of G edges each.

use crate::error::Error;
use crate::graph::{Edge, PoseGraph, SymMat3};
use crate::linalg::rng::Rng;
use std::f64::consts::PI;

/// Which pose pairs the outliers connect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OutlierModel {
    /// Any two poses, uniformly
    Random,
    /// Poses at most 20 ids apart
    Local,
}

impl OutlierModel {
    pub fn name(self) -> &'static str {
        match self {
            OutlierModel::Random => "random",
            OutlierModel::Local => "local",
        }
    }
}

/// Largest id distance of a local outlier (Vertigo's constant).
pub const LOCAL_SPAN: usize = 20;
/// Standard deviation of an outlier's translation, per axis, in metres (Vertigo's).
pub const TRANSLATION_SIGMA: f64 = 0.3;
/// Standard deviation of an outlier's rotation, in radians (10°, Vertigo's).
pub const ROTATION_SIGMA: f64 = 10.0 * PI / 180.0;

/// What [`add_outliers`] plants.
#[derive(Debug, Clone, Copy)]
pub struct OutlierConfig {
    /// Number of groups drawn.
    pub count: usize,
    pub model: OutlierModel,
    /// Consecutive pairs per group (G ≥ 1).
    pub group: usize,
    /// The outliers' noise block; `None`: that of the graph's first loop closure.
    pub noise: Option<SymMat3>,
    pub seed: u64,
}

/// Appends `config.count` groups of false loop closures to `graph.edges` (after the edges it
/// has) and returns the positions of the added edges in `graph.edges`.
///
/// # Errors
///
/// A graph too small for a group of `config.group` pairs (it needs at least G + 3 poses), or
/// without an edge to take the information matrix from when none is given.
pub fn add_outliers(graph: &mut PoseGraph, config: &OutlierConfig) -> crate::Result<Vec<usize>> {
    let n = graph.num_poses();
    let g = config.group;
    if g == 0 {
        return Err(Error::Invalid("the group size must be at least 1".into()));
    }
    if config.count == 0 {
        return Ok(Vec::new());
    }
    // v1, v2 in [0, top], v2 ≥ v1 + 2 must be possible.
    if n < g + 3 {
        return Err(Error::Invalid(format!(
            "the graph has {n} pose{}: groups of {g} outlier{} need at least {} poses",
            if n == 1 { "" } else { "s" },
            if g == 1 { "" } else { "s" },
            g + 3
        )));
    }
    let noise = match config.noise {
        Some(m) => m,
        None => first_loop_closure(graph)
            .or(graph.edges.first())
            .map(|e| e.noise)
            .ok_or_else(|| {
                Error::Invalid(
                    "the graph has no edge to take the outliers' information matrix from".into(),
                )
            })?,
    };
    let top = n - 1 - g;
    let mut rng = Rng::new(config.seed);
    let mut added = Vec::with_capacity(config.count * g);
    for _ in 0..config.count {
        let (v1, v2) = draw_pair(&mut rng, top, config.model);
        let x = rng.normal() * TRANSLATION_SIGMA;
        let y = rng.normal() * TRANSLATION_SIGMA;
        let theta = rng.normal() * ROTATION_SIGMA;
        for k in 0..g {
            added.push(graph.edges.len());
            graph.edges.push(Edge {
                i: v1 + k,
                j: v2 + k,
                measurement: crate::graph::Pose2::new(x, y, theta),
                noise,
            });
        }
    }
    Ok(added)
}

/// The first edge whose file ids are not consecutive (a loop closure, not odometry).
pub fn first_loop_closure(graph: &PoseGraph) -> Option<&Edge> {
    graph.edges.iter().find(|e| !is_odometry(graph, e))
}

/// Whether an edge joins consecutive file ids (i, i + 1) in either direction: odometry.
pub fn is_odometry(graph: &PoseGraph, e: &Edge) -> bool {
    let (a, b) = (graph.ids[e.i], graph.ids[e.j]);
    a.abs_diff(b) == 1
}

/// Uniform integer in [lo, hi].
fn uniform_int(rng: &mut Rng, lo: usize, hi: usize) -> usize {
    let span = (hi - lo + 1) as u64;
    // Lemire's multiply-shift, without its rejection step: the bias is below span / 2⁶⁴.
    lo + ((u128::from(rng.next_u64()) * u128::from(span)) >> 64) as usize
}

/// One pose pair v1 < v2 ≤ top, v2 ≠ v1 + 1, by Vertigo's rules.
fn draw_pair(rng: &mut Rng, top: usize, model: OutlierModel) -> (usize, usize) {
    loop {
        let v1 = uniform_int(rng, 0, top);
        let v2 = match model {
            OutlierModel::Random => uniform_int(rng, 0, top),
            OutlierModel::Local => uniform_int(rng, v1, top.min(v1 + LOCAL_SPAN)),
        };
        if v1 == v2 {
            continue;
        }
        let (v1, mut v2) = (v1.min(v2), v1.max(v2));
        if v2 == v1 + 1 {
            v2 = v1 + 2;
        }
        if v2 <= top {
            return (v1, v2);
        }
        // v1 + 2 beyond the last pose a group may start at: draw again.
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::Pose2;

    fn chain(n: usize) -> PoseGraph {
        let poses = (0..n).map(|k| Pose2::new(k as f64, 0.0, 0.0)).collect();
        let mut edges: Vec<Edge> = (0..n - 1)
            .map(|k| Edge {
                i: k,
                j: k + 1,
                measurement: Pose2::new(1.0, 0.0, 0.0),
                noise: SymMat3::IDENTITY,
            })
            .collect();
        edges.push(Edge {
            i: 0,
            j: n - 1,
            measurement: Pose2::new(n as f64 - 1.0, 0.0, 0.0),
            noise: SymMat3([7.0, 0.0, 0.0, 7.0, 0.0, 9.0]),
        });
        PoseGraph::with_edges(poses, edges)
    }

    #[test]
    fn groups_are_consecutive_pairs_after_the_edges() {
        let mut g = chain(50);
        let before = g.edges.len();
        let config = OutlierConfig {
            count: 30,
            model: OutlierModel::Local,
            group: 3,
            noise: None,
            seed: 4,
        };
        let added = add_outliers(&mut g, &config).unwrap();
        assert_eq!(added, (before..before + 90).collect::<Vec<_>>());
        for group in added.chunks(3) {
            let e0 = g.edges[group[0]];
            for (k, &p) in group.iter().enumerate() {
                let e = g.edges[p];
                assert_eq!((e.i, e.j), (e0.i + k, e0.j + k));
                assert_eq!(e.measurement, e0.measurement);
                // The first loop closure's information (the last edge of the chain).
                assert_eq!(e.noise.0, [7.0, 0.0, 0.0, 7.0, 0.0, 9.0]);
                assert!(e.j >= e.i + 2 && e.j - e.i <= LOCAL_SPAN && e.j <= 49);
            }
        }
        // The same seed draws the same edges.
        let mut again = chain(50);
        add_outliers(&mut again, &config).unwrap();
        assert_eq!(again, g);
    }

    #[test]
    fn too_small_a_graph_is_refused() {
        let mut g = chain(4);
        let config = OutlierConfig {
            count: 1,
            model: OutlierModel::Random,
            group: 2,
            noise: None,
            seed: 0,
        };
        assert!(add_outliers(&mut g, &config).is_err());
    }
}
