//! Per-edge weights of the cost (docs/method.md §2.2): the paper's cost (5)/(8) weighs every edge
//! equally; SE-Sync and CPL-SLAM weigh each edge by isotropic precisions taken from its
//! information matrix Ω = [[Ω_tt, Ω_tθ], [Ω_θt, Ω_θθ]]:
//!
//! ```text
//! f(p, r) = Σ_(i,j)  τ_ij |p_j − p_i − r_i Δ_ij|² + κ_ij |r_j − r_i R_ij|²
//! ```

use crate::error::Error;
use crate::graph::PoseGraph;

/// How edges are weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Weights {
    /// τ = κ = 1: exactly the paper's cost (5)/(8).
    Unit,
    /// τ = 2 / tr(Ω_tt⁻¹), κ = 2 Ω_θθ: the objective of SE-Sync and CPL-SLAM (their
    /// κ‖R_j − R_i R_ij‖²_F equals 2κ|r_j − r_i R_ij|² for planar rotations).
    Isotropic,
}

impl Weights {
    pub fn name(self) -> &'static str {
        match self {
            Weights::Unit => "unit",
            Weights::Isotropic => "isotropic",
        }
    }
}

/// The weights (τ, κ) of one edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeWeight {
    /// Translation weight τ.
    pub tau: f64,
    /// Rotation weight κ.
    pub kappa: f64,
}

/// The weights of every edge of `graph` under `policy`, followed by one per landmark
/// observation (in input order): ν as `tau` and `kappa` = 0, the term ν |l_k − p_i − r_i d_ik|²
/// having no rotation part. Isotropic weights need positive, finite τ and κ (ν): an edge or
/// observation whose information matrix does not give them is an error naming it.
///
/// ν = 2 / tr(Ω_ik⁻¹) under `Isotropic` (CPL-SLAM's rule, the same as τ's), 1 under `Unit`.
pub fn edge_weights(graph: &PoseGraph, policy: Weights) -> Result<Vec<EdgeWeight>, Error> {
    let edges = graph.edges.iter().map(|e| match policy {
        Weights::Unit => Ok(EdgeWeight {
            tau: 1.0,
            kappa: 1.0,
        }),
        Weights::Isotropic => {
            let bad = |why: &str| {
                Error::Invalid(format!(
                    "edge {} -> {}: {why}, so it has no isotropic weights (use --weights unit)",
                    graph.ids[e.i], graph.ids[e.j]
                ))
            };
            let info = graph
                .information(e)
                .ok_or_else(|| bad("its covariance is singular"))?;
            let [a, b, _, d, _, f] = info.0;
            let tau = isotropic_precision(a, b, d);
            let kappa = 2.0 * f;
            if !(tau > 0.0 && kappa > 0.0) {
                return Err(bad("its information matrix is not positive definite"));
            }
            if !(tau.is_finite() && kappa.is_finite()) {
                return Err(bad(
                    "its information values are so large that the weights overflow a 64-bit float",
                ));
            }
            Ok(EdgeWeight { tau, kappa })
        }
    });
    let marks = &graph.landmarks;
    let observations = marks.observations.iter().map(|o| {
        let nu = match policy {
            Weights::Unit => 1.0,
            Weights::Isotropic => {
                let [a, b, d] = o.information.0;
                let nu = isotropic_precision(a, b, d);
                if !(nu > 0.0 && nu.is_finite()) {
                    return Err(Error::Invalid(format!(
                        "observation of landmark {} from pose {}: its information matrix is not positive definite or overflows, so it has no isotropic weight (use --weights unit)",
                        marks.ids[o.landmark], graph.ids[o.pose]
                    )));
                }
                nu
            }
        };
        Ok(EdgeWeight {
            tau: nu,
            kappa: 0.0,
        })
    });
    edges.chain(observations).collect()
}

/// 2 / tr(Ω⁻¹) for the 2x2 Ω = [[a, b], [b, d]]: tr(Ω⁻¹) = (a + d) / det(Ω), computed on Ω / s,
/// s = max(|a|, |d|), so that det does not overflow (or underflow) for entries near 1e±200 whose
/// precision is representable.
fn isotropic_precision(a: f64, b: f64, d: f64) -> f64 {
    let s = a.abs().max(d.abs());
    let (a, b, d) = (a / s, b / s, d / s);
    2.0 * s * ((a * d - b * b) / (a + d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, NoiseKind, Pose2, SymMat3};

    fn graph(noise: SymMat3, kind: NoiseKind) -> PoseGraph {
        PoseGraph {
            ids: vec![0, 1],
            poses: vec![Pose2::IDENTITY; 2],
            edges: vec![Edge {
                i: 0,
                j: 1,
                measurement: Pose2::new(1.0, 0.0, 0.0),
                noise,
            }],
            fixed: vec![],
            vertices_declared: true,
            noise: kind,
            landmarks: Default::default(),
        }
    }

    #[test]
    fn isotropic_weights_by_hand() {
        // Ω_tt = diag(100, 25): tr(Ω_tt⁻¹) = 0.01 + 0.04 = 0.05, τ = 2 / 0.05 = 40; κ = 2·4.
        let g = graph(
            SymMat3([100.0, 0.0, 0.0, 25.0, 0.0, 4.0]),
            NoiseKind::Information,
        );
        let w = edge_weights(&g, Weights::Isotropic).unwrap()[0];
        assert!((w.tau - 40.0).abs() < 1e-12 && w.kappa == 8.0, "{w:?}");
        // Isotropic Ω_tt = ω I gives τ = ω (SE-Sync's τ for isotropic noise).
        let g = graph(
            SymMat3([44.72, 0.0, 0.0, 44.72, 0.0, 44.72]),
            NoiseKind::Information,
        );
        let w = edge_weights(&g, Weights::Isotropic).unwrap()[0];
        assert!((w.tau - 44.72).abs() < 1e-12, "{w:?}");
        // The same edge given as a covariance: inverted first.
        let g = graph(
            SymMat3([0.01, 0.0, 0.0, 0.04, 0.0, 0.25]),
            NoiseKind::Covariance,
        );
        let w = edge_weights(&g, Weights::Isotropic).unwrap()[0];
        assert!(
            (w.tau - 40.0).abs() < 1e-9 && (w.kappa - 8.0).abs() < 1e-12,
            "{w:?}"
        );
        assert_eq!(
            edge_weights(&g, Weights::Unit).unwrap()[0],
            EdgeWeight {
                tau: 1.0,
                kappa: 1.0
            }
        );
    }

    #[test]
    fn isotropic_weights_of_extreme_magnitudes() {
        // Ω_tt = ω I gives τ = ω, also where det(Ω_tt) = ω² overflows or underflows.
        for omega in [1e200, 1e-200, 1e-9, 1e9] {
            let g = graph(
                SymMat3([omega, 0.0, 0.0, omega, 0.0, 1.0]),
                NoiseKind::Information,
            );
            let w = edge_weights(&g, Weights::Isotropic).unwrap()[0];
            assert!((w.tau - omega).abs() <= 1e-15 * omega, "{omega}: {w:?}");
        }
        // κ = 2 Ω_θθ overflows: said so, not called indefinite.
        let g = graph(
            SymMat3([1.0, 0.0, 0.0, 1.0, 0.0, 1e308]),
            NoiseKind::Information,
        );
        let e = edge_weights(&g, Weights::Isotropic)
            .unwrap_err()
            .to_string();
        assert!(e.contains("overflow") && e.contains("edge 0 -> 1"), "{e}");
    }

    #[test]
    fn indefinite_information_has_no_isotropic_weights() {
        let g = graph(
            SymMat3([1.0, 2.0, 0.0, 1.0, 0.0, 1.0]),
            NoiseKind::Information,
        );
        let e = edge_weights(&g, Weights::Isotropic)
            .unwrap_err()
            .to_string();
        assert!(e.contains("edge 0 -> 1"), "{e}");
    }
}
