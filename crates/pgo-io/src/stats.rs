//! Statistics of a pose graph, as `pgo-convert --stats` reports them.

use crate::graph::{NoiseKind, PoseGraph, VertexId};
use crate::io::{Dialect, Format, ReadReport};
use serde::Serialize;

/// Counts that describe a graph file. Field names are stable: they are the `--json` keys.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraphStats {
    pub format: Format,
    pub dialect: Dialect,
    pub noise: NoiseKind,
    /// Number of poses (declared by vertex lines, or mentioned by edges).
    pub poses: usize,
    /// Whether the file has vertex lines (else initial poses were composed along a spanning tree).
    pub vertices_declared: bool,
    /// Number of edge lines, duplicates counted.
    pub edges: usize,
    /// Edges with j = i + 1.
    pub odometry_edges: usize,
    /// All other edges.
    pub loop_closures: usize,
    /// Edges written with i > j.
    pub backward_edges: usize,
    /// Edges joining the same two poses (either direction) as an earlier edge.
    pub duplicate_edges: usize,
    /// Edges identical in every value (ids, measurement, noise) to an earlier edge.
    pub exact_duplicate_edges: usize,
    /// Connected components, isolated poses included.
    pub components: usize,
    /// Poses without edges and without landmark observations.
    pub isolated_poses: usize,
    pub id_min: Option<VertexId>,
    pub id_max: Option<VertexId>,
    /// Ids missing from `id_min..=id_max`.
    pub id_gaps: u64,
    /// Ids on FIX lines.
    pub fixed: Vec<VertexId>,
    /// Landmarks (declared by vertex lines, or mentioned by observations).
    pub landmarks: usize,
    /// How the file writes landmarks: `g2o` (`VERTEX_XY`, `EDGE_SE2_XY`, one id space) or
    /// `landmark2` (CPL-SLAM's `LANDMARK2`, landmark ids of their own); `null` without landmarks.
    pub landmark_form: Option<crate::graph::LandmarkForm>,
    /// Landmark observation lines (`EDGE_SE2_XY` or `LANDMARK2`).
    pub observations: usize,
    /// Landmarks observed by exactly one pose line.
    pub landmarks_seen_once: usize,
    /// Landmarks no observation mentions (declared by a vertex line only).
    pub landmarks_unseen: usize,
}

impl GraphStats {
    pub fn new(graph: &PoseGraph, report: &ReadReport) -> Self {
        let ids = &graph.ids;
        let ends: Vec<(usize, usize)> = graph.edges.iter().map(|e| (e.i, e.j)).collect();
        let (odometry, backward, mut degree) = edge_counts(ids, &ends);
        for o in &graph.landmarks.observations {
            degree[o.pose] += 1;
        }
        let (duplicate, exact_duplicate) = duplicates(&ends, |k| {
            let e = &graph.edges[k];
            e.measurement
                .values()
                .iter()
                .chain(&e.noise.0)
                .map(|v| v.to_bits())
                .collect()
        });
        let (_, components) = graph.connected_components();
        let seen = graph.landmarks.observation_counts();
        let (id_min, id_max) = (ids.first().copied(), ids.last().copied());
        let id_gaps = id_gaps(ids);
        GraphStats {
            format: report.format,
            dialect: report.dialect,
            noise: graph.noise,
            poses: ids.len(),
            vertices_declared: graph.vertices_declared,
            edges: graph.edges.len(),
            odometry_edges: odometry,
            loop_closures: graph.edges.len() - odometry,
            backward_edges: backward,
            duplicate_edges: duplicate,
            exact_duplicate_edges: exact_duplicate,
            components,
            isolated_poses: degree.iter().filter(|&&d| d == 0).count(),
            id_min,
            id_max,
            id_gaps,
            fixed: graph.fixed.iter().map(|&k| ids[k]).collect(),
            landmarks: graph.landmarks.len(),
            landmark_form: (!graph.landmarks.is_empty()).then_some(graph.landmarks.form),
            observations: graph.landmarks.observations.len(),
            landmarks_seen_once: seen.iter().filter(|&&c| c == 1).count(),
            landmarks_unseen: seen.iter().filter(|&&c| c == 0).count(),
        }
    }
}

/// Edges with j = i + 1 (odometry) and with i > j (backward), and the number of edges at each
/// pose, from the edges' pose indices `ends` into the ascending `ids`.
fn edge_counts(ids: &[VertexId], ends: &[(usize, usize)]) -> (usize, usize, Vec<usize>) {
    let (mut odometry, mut backward) = (0, 0);
    let mut degree = vec![0usize; ids.len()];
    for &(i, j) in ends {
        let (a, b) = (ids[i], ids[j]);
        if u64::from(b) == u64::from(a) + 1 {
            odometry += 1;
        }
        if a > b {
            backward += 1;
        }
        degree[i] += 1;
        degree[j] += 1;
    }
    (odometry, backward, degree)
}

/// Ids missing from `ids[0]..=ids[last]` (`ids` ascending).
fn id_gaps(ids: &[VertexId]) -> u64 {
    match (ids.first(), ids.last()) {
        (Some(&lo), Some(&hi)) => u64::from(hi - lo) + 1 - ids.len() as u64,
        _ => 0,
    }
}

/// Edges joining the same two poses as an earlier edge, and edges identical in every value to an
/// earlier one (a subset: identical edges join the same poses, the same way, with the same
/// `bits` of their values). Sorting by pose pair groups them.
fn duplicates(ends: &[(usize, usize)], bits: impl Fn(usize) -> Vec<u64>) -> (usize, usize) {
    let pair = |k: usize| {
        let (i, j) = ends[k];
        (i.min(j), i.max(j))
    };
    let mut order: Vec<usize> = (0..ends.len()).collect();
    order.sort_unstable_by_key(|&k| (pair(k), k));
    let identical = |a: usize, b: usize| ends[a] == ends[b] && bits(a) == bits(b);
    let (mut same_pair, mut exact) = (0, 0);
    for group in order.chunk_by(|&a, &b| pair(a) == pair(b)) {
        same_pair += group.len() - 1;
        for (n, &k) in group.iter().enumerate().skip(1) {
            if group[..n].iter().any(|&earlier| identical(earlier, k)) {
                exact += 1;
            }
        }
    }
    (same_pair, exact)
}

/// Counts that describe a 3D graph file (`pgo-convert --stats` on VERTEX_SE3:QUAT/EDGE_SE3:QUAT
/// or VERTEX3/EDGE3 files). Field names are stable `--json` keys, those shared with
/// [`GraphStats`] meaning the same.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraphStats3 {
    /// Always 3 (planar statistics have no such key).
    pub dimension: u32,
    pub format: Format,
    pub dialect: Dialect,
    /// How rotations are written: `g2o` (quaternions) or `toro` (Euler angles).
    pub rotations: crate::graph3::Form3,
    pub poses: usize,
    pub edges: usize,
    /// Edges with j = i + 1.
    pub odometry_edges: usize,
    /// All other edges.
    pub loop_closures: usize,
    /// Edges written with i > j.
    pub backward_edges: usize,
    /// Edges joining the same two poses (either direction) as an earlier edge.
    pub duplicate_edges: usize,
    /// Edges identical in every value (ids, measurement, information) to an earlier edge.
    pub exact_duplicate_edges: usize,
    /// Connected components, isolated poses included.
    pub components: usize,
    /// Poses without edges.
    pub isolated_poses: usize,
    pub id_min: Option<VertexId>,
    pub id_max: Option<VertexId>,
    /// Ids missing from `id_min..=id_max`.
    pub id_gaps: u64,
    /// Ids on FIX lines.
    pub fixed: Vec<VertexId>,
}

impl GraphStats3 {
    pub fn new(graph: &crate::graph3::Graph3, report: &ReadReport) -> Self {
        let ids = &graph.ids;
        let ends: Vec<(usize, usize)> = graph.edges.iter().map(|e| (e.i, e.j)).collect();
        let (odometry, backward, degree) = edge_counts(ids, &ends);
        let (duplicate, exact) = duplicates(&ends, |k| {
            let e = &graph.edges[k];
            e.measurement
                .values()
                .chain(e.information.0)
                .map(f64::to_bits)
                .collect()
        });
        let (_, components) = graph.connected_components();
        let (id_min, id_max) = (ids.first().copied(), ids.last().copied());
        GraphStats3 {
            dimension: 3,
            format: report.format,
            dialect: report.dialect,
            rotations: graph.form,
            poses: ids.len(),
            edges: graph.edges.len(),
            odometry_edges: odometry,
            loop_closures: graph.edges.len() - odometry,
            backward_edges: backward,
            duplicate_edges: duplicate,
            exact_duplicate_edges: exact,
            components,
            isolated_poses: degree.iter().filter(|&&d| d == 0).count(),
            id_min,
            id_max,
            id_gaps: id_gaps(ids),
            fixed: graph.fixed.iter().map(|&k| ids[k]).collect(),
        }
    }
}
