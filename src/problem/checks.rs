//! What double precision can evaluate: graphs whose edge terms, pose graph matrix W̃ (eq. (24))
//! or rotation-only matrix M (eq. (38)) overflow, or whose anchored Laplacian L is numerically
//! singular, are refused with a message naming the cause, before any solver runs.

use crate::error::Error;
use crate::graph::PoseGraph;
use crate::problem::matrix::PoseGraphMatrix;
use crate::problem::weights::EdgeWeight;
use faer::{Mat, c64};

/// Refuses a graph without poses (and so without edges): there is nothing to solve, certify or
/// analyse, and a report of it would call nothing "certified optimal". (The readers never return
/// one: a file without vertex and edge lines is an input error at its place.)
pub fn check_not_empty(graph: &PoseGraph) -> Result<(), Error> {
    if graph.num_poses() == 0 {
        return Err(Error::Invalid(
            "the graph has no poses and no edges: nothing to solve".into(),
        ));
    }
    Ok(())
}

/// Refuses a graph whose edge terms τ|Δ|² + κ overflow a 64-bit float (the cost cannot be
/// evaluated), naming the edge by its ids; `original` are the weights as the user's graph has
/// them (for the message), `weights` those the matrices are built from.
pub fn check_edge_terms(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    original: &[EdgeWeight],
) -> Result<(), Error> {
    for ((e, w), o) in graph.edges.iter().zip(weights).zip(original) {
        let length = e.measurement.x.hypot(e.measurement.y);
        let term = w.tau * length * length + w.kappa;
        if !term.is_finite() {
            let mut weight = Vec::new();
            crate::io::format_f64(o.tau, &mut weight);
            return Err(Error::Invalid(format!(
                "edge {} -> {}: its translation of {length:e} m, squared and weighted by {}, overflows a 64-bit float, so the cost cannot be evaluated",
                graph.ids[e.i],
                graph.ids[e.j],
                String::from_utf8_lossy(&weight)
            )));
        }
    }
    Ok(())
}

/// W̃ of `graph` with `weights` and its rotation-only matrix M, or why they cannot be computed
/// in double precision: an edge's weighted squared translation τ|Δ|² overflows (named by its
/// ids, with `original`, the weights of the user's graph), or a sum of them does, or L is
/// singular ([`singular_laplacian`]).
pub fn matrices(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    original: &[EdgeWeight],
) -> Result<(PoseGraphMatrix, Mat<c64>), Error> {
    check_edge_terms(graph, weights, original)?;
    let matrix = PoseGraphMatrix::new(graph, weights);
    // The proven bound takes the Frobenius norm of W̃(λ) (crate::certify): its square must be
    // finite, so no entry may reach about 1e154. With the weights normalized to at most about
    // one, only translations that long do that; the longest is named.
    let dense = matrix.dense();
    let fro2: f64 = (0..dense.ncols())
        .flat_map(|c| (0..dense.nrows()).map(move |r| (r, c)))
        .map(|(r, c)| dense[(r, c)].norm_sqr())
        .sum();
    if !fro2.is_finite() {
        let (e, length) = graph
            .edges
            .iter()
            .map(|e| (e, e.measurement.x.hypot(e.measurement.y)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("a graph with entries has edges");
        return Err(Error::Invalid(format!(
            "edge {} -> {}: its translation of {length:e} m makes entries of the pose graph matrix too large for the eigenvalue bounds in double precision (their squares overflow); rescale the translations",
            graph.ids[e.i], graph.ids[e.j]
        )));
    }
    let finite = |m: &Mat<c64>| {
        (0..m.ncols())
            .all(|c| (0..m.nrows()).all(|r| m[(r, c)].re.is_finite() && m[(r, c)].im.is_finite()))
    };
    if !finite(&dense) {
        return Err(Error::Invalid(
            "the pose graph matrix overflows a 64-bit float: the weighted squared translations of the edges at one pose add up to more than 1.8e308".into(),
        ));
    }
    let m = matrix
        .rotation_matrix()
        .ok_or_else(|| singular_laplacian(graph, original))?;
    if !finite(&m) {
        return Err(Error::Invalid(
            "the rotation matrix M = Q - S* L^-1 S of this graph overflows a 64-bit float: its translations are too long for its weights".into(),
        ));
    }
    Ok((matrix, m))
}

/// Why the anchored Laplacian L of `graph` could not be factored: the graph is disconnected, or
/// (connected, so L ≻ 0 in exact arithmetic) its translation weights span a range that double
/// precision cannot resolve, e.g. 1e-9 next to 1e9: light edges then vanish in the rounding of
/// the heavy ones.
pub fn singular_laplacian(graph: &PoseGraph, weights: &[EdgeWeight]) -> Error {
    if graph.connected_components().1 != 1 {
        return Error::Invalid("the graph is not connected".into());
    }
    let (lo, hi) = weights.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), w| {
        (lo.min(w.tau), hi.max(w.tau))
    });
    Error::Invalid(format!(
        "the weighted Laplacian of this connected graph is numerically singular: its translation weights range from {lo:e} to {hi:e}, too wide for double precision (edges that light are lost in the rounding of the heavy ones); rescale the information matrices or use --weights unit"
    ))
}
