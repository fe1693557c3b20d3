//! Eigenvalues of the pose graph matrices: W̃ (eq. (24)), the penalized matrix W̃(λ*) (Sec. 4.1)
//! and M (eq. (38)), and the count of eigenvalues at zero (the SZEP, Prop. 10). Dense for small
//! graphs and full spectra (all eigenvalues, from Algorithm 1's dual analysis); sparse for large
//! ones and for the K smallest of any component of more than [`SPARSE_MIN_POSES`] poses (the
//! smallest few, [`sparse`], with λ from the scalable solver, where its certificate proves them
//! the same). 3D graphs: [`spatial`] (Q, the certificate matrix S and M of SE-Sync's problem;
//! three zeros of S in place of the SZEP's one).
//!
//! May use: [`crate::staircase`], [`crate::dual`], [`crate::se3`], [`crate::certify`],
//! [`crate::problem`], [`crate::linalg`].

pub mod sparse;
pub mod spatial;

pub use sparse::*;
pub use spatial::{ComponentSpectrum3, Spectrum3, spectrum3};

use crate::dual::algorithm1::{DENSE_MAX_POSES, analyze};
use crate::dual::solver::SdpSolver;
use crate::error::Error;
use crate::graph::PoseGraph;
use crate::linalg::eigen::hermitian_eigenvalues;
use crate::problem::weights::{Weights, edge_weights};
use serde::Serialize;

/// What [`spectrum`] is asked for.
#[derive(Debug, Clone, Copy)]
pub struct SpectrumOptions {
    pub weights: Weights,
    /// The K smallest eigenvalues of each matrix (0: all of a dense component,
    /// [`SPARSE_DEFAULT_COUNT`] of a sparse one).
    pub count: usize,
    /// The SDP solver of the dense components' dual.
    pub solver: SdpSolver,
}

#[derive(Debug, Serialize)]
pub struct ComponentSpectrum {
    pub first_id: u32,
    pub poses: usize,
    pub edges: usize,
    pub eigenvalues: Vec<f64>,
    pub penalized_eigenvalues: Vec<f64>,
    pub rotation_eigenvalues: Vec<f64>,
    pub near_zero: usize,
    pub szep: bool,
    pub tree: bool,
    pub balanced: bool,
    /// d* = Σλ*.
    pub dual_objective: f64,
    /// λ*, one multiplier per pose of the component, in ascending id order.
    pub lambda: Vec<f64>,
    /// The proven lower bound on f* (see pgo-solve).
    pub lower_bound: f64,
    /// Whether the SDP solver reached its tolerance (see pgo-solve); for a component analysed
    /// sparse (see [`spectrum`]), whether the scalable solver's certificate proved its estimate
    /// optimal (pgo-solve's `certified`).
    pub sdp_converged: bool,
    /// Whether the sparse eigenvalue iteration converged (always for a dense component); if not,
    /// its eigenvalues are upper bounds.
    #[serde(skip)]
    pub eigen_converged: bool,
}

/// What `--json` prints; lists are ascending.
#[derive(Debug, Serialize)]
pub struct Spectrum {
    pub weights: Weights,
    pub poses: usize,
    pub edges: usize,
    /// Landmarks and their observations: rows of W beside the poses' (absent from JSON when
    /// none).
    #[serde(skip_serializing_if = "is_zero")]
    pub landmarks: usize,
    #[serde(skip_serializing_if = "is_zero")]
    pub observations: usize,
    /// Eigenvalues of W (all components merged).
    pub eigenvalues: Vec<f64>,
    /// Eigenvalues of W(lambda*).
    pub penalized_eigenvalues: Vec<f64>,
    /// Eigenvalues of M.
    pub rotation_eigenvalues: Vec<f64>,
    /// Eigenvalues of W(lambda*) at zero, summed over components.
    pub near_zero: usize,
    pub szep: bool,
    pub tree: bool,
    pub balanced: bool,
    /// Whether the SDP solver reached its tolerance on every component.
    pub sdp_converged: bool,
    pub components: Vec<ComponentSpectrum>,
}

/// Tolerance of the balanced test (metres and radians), Definition 1.
const BALANCE_TOLERANCE: f64 = 1e-9;

/// How many of the smallest eigenvalues `-k 0` prints for a component of more than
/// [`DENSE_MAX_POSES`] poses, where not all are computed.
pub const SPARSE_DEFAULT_COUNT: usize = 10;

/// The most eigenvalues per matrix computed for a component of more than [`DENSE_MAX_POSES`]
/// poses (each costs two solves per iteration of the subspace iteration).
pub const SPARSE_MAX_COUNT: usize = 100;

/// With `-k K` (1 ≤ K ≤ [`SPARSE_MAX_COUNT`]), components of more poses than this are analysed
/// sparse too, when the scalable solver's certificate proves its λ the dual optimum λ* with the
/// SZEP: then W̃(λ) is W̃(λ*) and the K smallest eigenvalues are those of the dense path (to
/// about 1e-8 relative, `tests/sparse_spectrum.rs`), at a fraction of its cost (the dual SDP is
/// cubic in the poses: MIT, 808 poses, `-k 6` took 30 s dense and takes 0.1 s sparse). Measured
/// on simulated graphs (-k 6, about 2.4 edges per pose): 100 poses 94 ms dense, 14 ms sparse;
/// 300 poses 1.8 s and 47 ms; 500 poses 6.1 s and 0.12 s. Below 100 poses both take well under
/// 0.1 s, and the dense path computes every eigenvalue from the SDP's own λ*; above it every
/// matrix has more rows than the K ≤ 100 eigenvalues asked for (M has one per pose), as the
/// subspace iteration needs.
pub const SPARSE_MIN_POSES: usize = 100;

fn smallest(mut v: Vec<f64>, k: usize) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    if k > 0 {
        v.truncate(k);
    }
    v
}

/// The spectra of W̃, W̃(λ*) and M of every connected component of `graph` and merged: dense
/// (all eigenvalues, λ* from the dual SDP) for components of at most [`DENSE_MAX_POSES`] poses,
/// sparse beyond (the smallest K, λ from the scalable solver's certificate). With K in
/// 1..=[`SPARSE_MAX_COUNT`], a component of more than [`SPARSE_MIN_POSES`] poses is analysed
/// sparse as well, and falls back to the dense path unless the certificate proves the estimate
/// optimal with the SZEP and the eigenvalue iterations converge (the answer is then the dense
/// path's).
pub fn spectrum(graph: &PoseGraph, options: &SpectrumOptions) -> crate::Result<Spectrum> {
    crate::problem::checks::check_not_empty(graph)?;
    let policy = options.weights;
    let parts = graph.components();
    let sparse = |part: &crate::graph::PoseGraph| part.num_poses() > DENSE_MAX_POSES;
    let any_sparse = parts.iter().any(|(part, _, _)| sparse(part));
    let sparse_count = match options.count {
        0 => SPARSE_DEFAULT_COUNT,
        k if k > SPARSE_MAX_COUNT && any_sparse => {
            return Err(Error::Invalid(format!(
                "-k {k} is more than the {SPARSE_MAX_COUNT} smallest eigenvalues computed for components of more than {DENSE_MAX_POSES} poses"
            )));
        }
        k => k,
    };
    // The K smallest are asked for, few enough to be computed sparse.
    let few = (1..=SPARSE_MAX_COUNT).contains(&options.count);
    let mut components = Vec::new();
    for (part, _, _) in parts {
        let weights = edge_weights(&part, policy)?;
        let must = sparse(&part);
        if must || (few && part.num_poses() > SPARSE_MIN_POSES) {
            crate::progress::phase("staircase (for λ)");
            let s = scalable_spectrum(&part, &weights, sparse_count)?;
            let proven = s.certified && s.szep && s.spectra.converged;
            if !(must || proven) {
                // Not proven the dual optimum: the dense path, whose λ* is the SDP's.
                components.push(dense_component(&part, &weights, options)?);
                continue;
            }
            components.push(ComponentSpectrum {
                first_id: part.ids[0],
                poses: part.num_poses(),
                edges: part.edges.len(),
                eigenvalues: s.spectra.eigenvalues,
                penalized_eigenvalues: s.spectra.penalized_eigenvalues,
                rotation_eigenvalues: s.spectra.rotation_eigenvalues,
                near_zero: s.near_zero,
                szep: s.szep,
                tree: part.is_forest(),
                balanced: part.is_balanced(BALANCE_TOLERANCE),
                dual_objective: s.dual_objective,
                lambda: s.lambda,
                lower_bound: s.lower_bound,
                sdp_converged: s.certified,
                eigen_converged: s.spectra.converged,
            });
            continue;
        }
        components.push(dense_component(&part, &weights, options)?);
    }
    // The K smallest of each component hold the K smallest of the graph; with -k 0 and a
    // component analysed sparse, its SPARSE_DEFAULT_COUNT are all the merged lists can hold.
    let merged_count = if any_sparse {
        sparse_count
    } else {
        options.count
    };
    let merge = |f: fn(&ComponentSpectrum) -> &Vec<f64>| {
        smallest(
            components
                .iter()
                .flat_map(|c| f(c).iter().copied())
                .collect(),
            merged_count,
        )
    };
    Ok(Spectrum {
        weights: policy,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        landmarks: graph.landmarks.len(),
        observations: graph.landmarks.observations.len(),
        eigenvalues: merge(|c| &c.eigenvalues),
        penalized_eigenvalues: merge(|c| &c.penalized_eigenvalues),
        rotation_eigenvalues: merge(|c| &c.rotation_eigenvalues),
        near_zero: components.iter().map(|c| c.near_zero).sum(),
        szep: components.iter().all(|c| c.szep),
        tree: components.iter().all(|c| c.tree),
        balanced: components.iter().all(|c| c.balanced),
        sdp_converged: components.iter().all(|c| c.sdp_converged),
        components,
    })
}

/// The spectra of a connected component by Algorithm 1's dense dual analysis: all eigenvalues
/// (the smallest `options.count` of them with K > 0), λ* from the dual SDP.
fn dense_component(
    part: &PoseGraph,
    weights: &[crate::problem::weights::EdgeWeight],
    options: &SpectrumOptions,
) -> crate::Result<ComponentSpectrum> {
    // In the units of the normalized weights, scaled back (see DualAnalysis).
    let a = analyze(part, weights, options.solver)?;
    crate::progress::phase("eigenvalues");
    let scaled = |v: Vec<f64>| -> Vec<f64> { v.into_iter().map(|x| x * a.scale).collect() };
    let zeros = a.near_zero;
    Ok(ComponentSpectrum {
        first_id: part.ids[0],
        poses: part.num_poses(),
        edges: part.edges.len(),
        eigenvalues: smallest(
            scaled(hermitian_eigenvalues(&a.matrix.dense())),
            options.count,
        ),
        penalized_eigenvalues: smallest(scaled(a.bound.eigenvalues.clone()), options.count),
        rotation_eigenvalues: smallest(scaled(hermitian_eigenvalues(&a.m)), options.count),
        near_zero: zeros,
        szep: zeros <= 1,
        tree: part.is_forest(),
        balanced: part.is_balanced(BALANCE_TOLERANCE),
        dual_objective: a.dual.dual_objective * a.scale,
        lambda: scaled(a.dual.lambda.clone()),
        lower_bound: a.bound.lower_bound * a.scale,
        sdp_converged: a.dual.converged,
        eigen_converged: true,
    })
}

fn is_zero(v: &usize) -> bool {
    *v == 0
}
