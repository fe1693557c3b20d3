//! Eigenvalues of the pose graph matrices: W̃ (eq. (24)), the penalized matrix W̃(λ*) (Sec. 4.1)
//! and M (eq. (38)), and the count of eigenvalues at zero (the SZEP, Prop. 10). Dense for small
//! graphs (all eigenvalues, from Algorithm 1's dual analysis); sparse for large ones (the smallest
//! few, [`sparse`], with λ from the scalable solver).
//!
//! May use: [`crate::staircase`], [`crate::dual`], [`crate::certify`], [`crate::problem`],
//! [`crate::linalg`].

pub mod sparse;

pub use sparse::*;

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
    /// sparse (more than [`DENSE_MAX_POSES`] poses), whether the scalable solver's certificate
    /// proved its estimate optimal (pgo-solve's `certified`).
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

fn smallest(mut v: Vec<f64>, k: usize) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    if k > 0 {
        v.truncate(k);
    }
    v
}

/// The spectra of W̃, W̃(λ*) and M of every connected component of `graph` and merged: dense
/// (all eigenvalues, λ* from the dual SDP) for components of at most [`DENSE_MAX_POSES`] poses,
/// sparse beyond (the smallest K, λ from the scalable solver's certificate).
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
    let mut components = Vec::new();
    for (part, _, _) in parts {
        let weights = edge_weights(&part, policy)?;
        if sparse(&part) {
            let s = scalable_spectrum(&part, &weights, sparse_count)?;
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
        // In the units of the normalized weights, scaled back (see DualAnalysis).
        let a = analyze(&part, &weights, options.solver)?;
        let scaled = |v: Vec<f64>| -> Vec<f64> { v.into_iter().map(|x| x * a.scale).collect() };
        let zeros = a.near_zero;
        components.push(ComponentSpectrum {
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
        });
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
