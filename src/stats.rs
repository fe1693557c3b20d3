//! Statistics of a pose graph, as `pgo-convert --stats` reports them.

use crate::graph::{NoiseKind, PoseGraph, VertexId};
use crate::io::{Dialect, Format, ReadReport};
use serde::Serialize;
use std::collections::HashMap;

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
    /// Poses without edges.
    pub isolated_poses: usize,
    pub id_min: Option<VertexId>,
    pub id_max: Option<VertexId>,
    /// Ids missing from `id_min..=id_max`.
    pub id_gaps: u64,
    /// Ids on FIX lines.
    pub fixed: Vec<VertexId>,
}

impl GraphStats {
    pub fn new(graph: &PoseGraph, report: &ReadReport) -> Self {
        let ids = &graph.ids;
        let mut odometry = 0;
        let mut backward = 0;
        let mut degree = vec![0usize; ids.len()];
        let mut pairs: HashMap<(usize, usize), ()> = HashMap::with_capacity(graph.edges.len());
        let mut exact: HashMap<[u64; 11], ()> = HashMap::with_capacity(graph.edges.len());
        let mut duplicate = 0;
        let mut exact_duplicate = 0;
        for e in &graph.edges {
            let (a, b) = (ids[e.i], ids[e.j]);
            if u64::from(b) == u64::from(a) + 1 {
                odometry += 1;
            }
            if a > b {
                backward += 1;
            }
            degree[e.i] += 1;
            degree[e.j] += 1;
            if pairs.insert((e.i.min(e.j), e.i.max(e.j)), ()).is_some() {
                duplicate += 1;
            }
            let mut key = [0u64; 11];
            key[0] = e.i as u64;
            key[1] = e.j as u64;
            for (k, v) in e.measurement.values().iter().chain(&e.noise.0).enumerate() {
                key[k + 2] = v.to_bits();
            }
            if exact.insert(key, ()).is_some() {
                exact_duplicate += 1;
            }
        }
        let (_, components) = graph.connected_components();
        let (id_min, id_max) = (ids.first().copied(), ids.last().copied());
        let id_gaps = match (id_min, id_max) {
            (Some(lo), Some(hi)) => u64::from(hi - lo) + 1 - ids.len() as u64,
            _ => 0,
        };
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
        }
    }
}
