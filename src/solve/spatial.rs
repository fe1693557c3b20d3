//! The whole jobs on 3D graphs (issue 15): [`solve3`] beside [`super::solve`] and
//! [`certify_estimate3`] beside [`super::certify_estimate`], component by component, with the
//! planar reports' field names (cost, lower_bound, suboptimality_bound, certified, rank, ...).
//! The method is [`crate::se3`] (SE-Sync's problem and staircase with pgo's certificate); the
//! objective is SE-Sync's f with its weights, the same convention as the planar cost (factor 1
//! to SE-Sync's reported optima).

use super::estimate::{CertifyOptions, EstimateComponent, EstimateReport};
use super::tree::{compose3, is_tree3};
use super::{ComponentReport, Method, SolveOptions, report_iteration, within};
use crate::error::Error;
use crate::graph3::{Form3, Graph3, Pose3, Rotation3};
use crate::problem::weights::Weights;
use crate::se3::local::Step3;
use crate::se3::problem::{edge_term, weights3};
use crate::se3::rounding::Rt;
use crate::se3::{
    Options3, certify_estimate3 as certify_component, check3, components3, rt_of, solve_graph3,
};
use nalgebra::{Isometry3, Matrix3, Rotation3 as NRotation3, Translation3, UnitQuaternion};
use serde::Serialize;

/// The solved 3D graph: the estimate and, per component and summed, its cost, the proven lower
/// bound on f* and their difference (the fields of the planar [`super::Solution`] that apply).
#[derive(Debug, Serialize)]
pub struct Solution3 {
    /// 3.
    pub dimension: u8,
    pub method: Method,
    pub weights: Weights,
    pub poses: usize,
    pub edges: usize,
    /// f at the estimate (SE-Sync's objective with its weights).
    pub cost: f64,
    /// g2o's chi2 of the certified estimate (EDGE_SE3:QUAT's error: translation and quaternion
    /// vector part of z⁻¹·x_i⁻¹·x_j, w ≥ 0); `None` for TORO files.
    pub chi2: Option<f64>,
    pub lower_bound: f64,
    pub suboptimality_bound: f64,
    /// With refinement: g2o's chi2 of the returned (refined) estimate, summed over components.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refined_chi2: Option<f64>,
    pub relative_suboptimality_bound: f64,
    pub certified: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_certified_because: Option<String>,
    /// Every component's certificate matrix S proven to have exactly 3 eigenvalues at zero
    /// (the kernel of the rank-3 estimate: the relaxation is exact, SE-Sync's Theorem 7) and
    /// the rest positive: the 3D counterpart of the planar single zero eigenvalue property.
    pub szep: bool,
    pub near_zero_eigenvalues: usize,
    pub components: Vec<ComponentReport>,
    /// One pose per pose of the graph, in its order and form, in the input's gauge (each
    /// component's FIX pose, else its first pose, exactly where the input has it).
    #[serde(skip)]
    pub estimate: Vec<Pose3>,
}

fn isometry(p: &Rt) -> Isometry3<f64> {
    let m = Matrix3::from_row_slice(&p.r);
    let q = UnitQuaternion::from_rotation_matrix(&NRotation3::from_matrix_unchecked(m));
    Isometry3::from_parts(Translation3::new(p.t[0], p.t[1], p.t[2]), q)
}

/// A pose in the graph's form (quaternion `[x, y, z, w]` with w ≥ 0, or TORO's Euler angles).
fn pose_in(form: Form3, m: &Isometry3<f64>) -> Pose3 {
    let t = m.translation.vector;
    let rotation = match form {
        Form3::G2o => {
            let q = m.rotation.quaternion();
            let s = if q.w < 0.0 { -1.0 } else { 1.0 };
            Rotation3::Quaternion([s * q.i, s * q.j, s * q.k, s * q.w])
        }
        Form3::Toro => {
            let (roll, pitch, yaw) = m.rotation.euler_angles();
            Rotation3::Euler([roll, pitch, yaw])
        }
    };
    Pose3 {
        translation: [t.x, t.y, t.z],
        rotation,
    }
}

/// g2o's chi2 of poses under the full information matrices ([`crate::refine::chi2_3`]: g2o
/// files; `None` for TORO's, whose information is over Euler angles, or where not finite).
pub fn chi2_3(graph: &Graph3, poses: &[Pose3]) -> Option<f64> {
    if graph.form != Form3::G2o {
        return None;
    }
    let x: Vec<Isometry3<f64>> = poses.iter().map(|p| p.to_isometry()).collect();
    Some(crate::refine::chi2_3(graph, &x)).filter(|c| c.is_finite())
}

/// Solves every connected component of a 3D graph to a certified optimum where SE-Sync's
/// relaxation is exact, and bounds the suboptimality where it is not. Newton steps are
/// reported through [`crate::progress`].
///
/// With `options.refine`, each component's certified estimate is then refined by
/// Levenberg-Marquardt under the full 6x6 information matrices ([`crate::refine::refine3`]: g2o's
/// chi2, another objective than f), holding the gauge pose; the estimate returned is the refined
/// one, which the certificate is not about (`certified_chi2` and `refined_chi2` per component).
///
/// # Errors
///
/// Options that do not apply to 3D graphs (`method` sdp; `refine` on a TORO file, whose
/// information is over Euler angles), an information matrix without isotropic weights, several
/// FIX poses in one component, a self-loop.
pub fn solve3(graph: &Graph3, options: &SolveOptions) -> crate::Result<Solution3> {
    if options.refine && graph.form != Form3::G2o {
        return Err(Error::Invalid(
            "--refine: the information matrices of TORO 3D files (EDGE3) are over Euler angles, whose error g2o's refinement does not define; refine g2o files (EDGE_SE3:QUAT)".into(),
        ));
    }
    if options.method == Method::Sdp {
        return Err(Error::Invalid(
            "--method sdp: Algorithm 1 (the dual SDP) is planar; 3D graphs are solved by the staircase (--method auto or staircase)".into(),
        ));
    }
    let parts = components3(graph);
    check3(graph, &parts)?;
    let unit = options.weights == Weights::Unit;
    let staircase = Options3 {
        tolerance: options.tolerance,
        // Rank 3 is the problem itself (rank 1 in 2D): the same number of lifts.
        max_rank: options.max_rank + 2,
        budget: options.staircase_budget,
        ..Default::default()
    };
    let mut estimate = graph.poses.clone();
    // The certified estimate, which `estimate` leaves with --refine.
    let mut certified_estimate = graph.poses.clone();
    let mut reports = Vec::new();
    let mut step = 0u64;
    for (part, members) in &parts {
        let weights = weights3(part, unit)?;
        // The gauge: the FIX pose (else the first) where the input has it.
        let g = part.fixed.first().copied().unwrap_or(0);
        // A tree under auto: composed and certified with nothing computed (`super::tree`);
        // where the cost of the composition, all rounding, is not within the tolerance, the
        // staircase as for any graph.
        let tree = (matches!(options.method, Method::Auto | Method::Tree) && is_tree3(part))
            .then(|| {
                let poses = compose3(part, g, |x| pose_in(graph.form, x));
                let f = part
                    .edges
                    .iter()
                    .zip(&weights)
                    .fold(0.0, |a, (e, w)| a + edge_term(e, *w, &poses));
                (poses, f)
            })
            .filter(|(_, f)| within(*f, *f, options.tolerance));
        let mut report = match tree {
            Some((poses, f)) => {
                for (pose, &at) in poses.iter().zip(members) {
                    estimate[at] = *pose;
                }
                tree_report(part, f)
            }
            None => {
                let s = solve_graph3(part, &weights, &staircase, &mut |it: Step3| {
                    step += 1;
                    report_iteration(step, it.cost, it.gradient_norm, it.rank, it.damping);
                });
                let to_input = part.poses[g].to_isometry() * isometry(&s.poses[g]).inverse();
                for (k, (pose, &at)) in s.poses.iter().zip(members).enumerate() {
                    estimate[at] = if k == g {
                        part.poses[g]
                    } else {
                        pose_in(graph.form, &(to_input * isometry(pose)))
                    };
                }
                staircase_report(part, &s)
            }
        };
        let part_estimate: Vec<Pose3> = members.iter().map(|&k| estimate[k]).collect();
        report.certified_chi2 = chi2_3(part, &part_estimate);
        for (pose, &at) in part_estimate.iter().zip(members) {
            certified_estimate[at] = *pose;
        }
        if options.refine {
            // Levenberg-Marquardt holds the FIX pose (or the first) where it is.
            crate::progress::phase("refinement (Levenberg-Marquardt, SE(3))");
            let r = crate::refine::refine3(part, &part_estimate, &Default::default())?;
            for (pose, &at) in r.poses.iter().zip(members) {
                estimate[at] = *pose;
            }
            report.refined_chi2 = Some(r.chi2);
            report.refine_iterations = Some(r.iterations);
        }
        reports.push(report);
    }
    let cost = reports.iter().fold(0.0, |a, c| a + c.cost);
    let lower_bound = reports.iter().fold(0.0, |a, c| a + c.lower_bound);
    let suboptimality_bound = cost - lower_bound;
    let certified = reports.iter().all(|c| c.certified);
    let several = reports.len() > 1;
    let why: Vec<String> = reports
        .iter()
        .filter_map(|c| {
            let w = c.not_certified_because.as_ref()?;
            Some(if several {
                format!("component at id {}: {w}", c.first_id)
            } else {
                w.clone()
            })
        })
        .collect();
    let chi2 = chi2_3(graph, &certified_estimate);
    Ok(Solution3 {
        dimension: 3,
        method: options.method,
        weights: options.weights,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        cost,
        chi2,
        lower_bound,
        suboptimality_bound,
        refined_chi2: options
            .refine
            .then(|| reports.iter().filter_map(|c| c.refined_chi2).sum()),
        relative_suboptimality_bound: suboptimality_bound / cost.abs().max(1.0),
        certified,
        not_certified_because: (!certified && !why.is_empty()).then(|| why.join("; ")),
        szep: reports.iter().all(|c| c.szep),
        near_zero_eigenvalues: reports.iter().map(|c| c.near_zero_eigenvalues).sum(),
        components: reports,
        estimate,
    })
}

/// The report of a component the staircase solved.
fn staircase_report(part: &Graph3, s: &crate::se3::Solution3) -> ComponentReport {
    let proven = s.bound.is_some() || s.lower_bound > 0.0;
    let deflated = s.bound.and_then(|b| b.deflated);
    ComponentReport {
        rank: Some(s.rank),
        iterations: Some(s.iterations),
        eta: s.bound.map(|b| b.eta),
        gradient_norm: Some(s.gradient_norm),
        not_certified_because: s.not_certified_because.clone(),
        ..part_report(
            part,
            Method::Staircase,
            (s.cost, s.lower_bound),
            s.certified && proven,
            deflated,
        )
    }
}

/// The report of a tree, composed at cost `f` (`super::tree`): the lower bound 0 and the 3 zero
/// eigenvalues of S = Q that the theory of trees gives.
fn tree_report(part: &Graph3, f: f64) -> ComponentReport {
    part_report(part, Method::Tree, (f, 0.0), true, Some(3))
}

/// What every method reports of a 3D component: `bounds` = (cost, lower bound), `deflated` the
/// zero eigenvalues of S proven (3: the relaxation is exact).
fn part_report(
    part: &Graph3,
    method: Method,
    bounds: (f64, f64),
    certified: bool,
    deflated: Option<usize>,
) -> ComponentReport {
    let (cost, lower_bound) = bounds;
    ComponentReport {
        first_id: part.ids[0],
        poses: part.num_poses(),
        edges: part.edges.len(),
        cost,
        lower_bound,
        suboptimality_bound: cost - lower_bound,
        certified,
        szep: deflated == Some(3),
        near_zero_eigenvalues: deflated.unwrap_or(0),
        method,
        ..Default::default()
    }
}

/// Bounds the suboptimality of a 3D `estimate` (one pose per pose of `graph`, in its order):
/// the estimate's own multipliers and the certificate of [`crate::se3::certificate`]; where
/// they do not certify it within the tolerance, the proven bound of the optimum (the solver),
/// whichever is higher. The report is the planar one ([`EstimateReport`]).
pub fn certify_estimate3(
    graph: &Graph3,
    estimate: &[Pose3],
    options: &CertifyOptions,
    source: &str,
) -> crate::Result<EstimateReport> {
    let parts = components3(graph);
    check3(graph, &parts)?;
    let unit = options.weights == Weights::Unit;
    let tol = options.tolerance;
    let mut comps = Vec::new();
    for (part, members) in &parts {
        let weights = weights3(part, unit)?;
        let poses: Vec<Rt> = members.iter().map(|&k| rt_of(&estimate[k])).collect();
        let own = certify_component(part, &weights, &poses, tol);
        if !own.cost.is_finite() {
            return Err(Error::Invalid(format!(
                "{source}: the cost of the estimate overflows a 64-bit float (its poses are too far apart for the weights)"
            )));
        }
        let own_bound = own.bound.map(|b| b.lower_bound.max(0.0));
        let (lower_bound, bound_from) = match own_bound {
            Some(lb) if within(own.cost - lb, own.cost, tol) => (lb, "estimate"),
            _ => {
                // The optimum's proven bound; a tree's is its optimum, 0 (`super::tree`).
                let solved = if is_tree3(part) {
                    0.0
                } else {
                    let options = Options3 {
                        tolerance: tol,
                        ..Default::default()
                    };
                    solve_graph3(part, &weights, &options, &mut |_| {}).lower_bound
                };
                match own_bound {
                    Some(lb) if lb >= solved => (lb, "estimate"),
                    _ => (solved, "solution"),
                }
            }
        };
        let suboptimality_bound = own.cost - lower_bound;
        comps.push(EstimateComponent {
            first_id: part.ids[0],
            poses: part.num_poses(),
            edges: part.edges.len(),
            cost: own.cost,
            lower_bound,
            suboptimality_bound,
            certified: within(suboptimality_bound, own.cost, tol),
            bound_from,
            eta: own
                .bound
                .filter(|_| bound_from == "estimate")
                .map(|b| b.eta),
            gradient_norm: own.gradient_norm,
            near_zero_eigenvalues: own.bound.and_then(|b| b.deflated),
        });
    }
    let cost = comps.iter().fold(0.0, |a, c| a + c.cost);
    let lower_bound = comps.iter().fold(0.0, |a, c| a + c.lower_bound);
    let suboptimality_bound = cost - lower_bound;
    let gradient_norm = comps
        .iter()
        .map(|c| c.gradient_norm * c.gradient_norm)
        .sum::<f64>()
        .sqrt();
    Ok(EstimateReport {
        weights: options.weights,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        cost,
        chi2: chi2_3(graph, estimate),
        lower_bound,
        suboptimality_bound,
        relative_suboptimality_bound: suboptimality_bound / cost.abs().max(1.0),
        certified: comps.iter().all(|c| c.certified),
        gradient_norm,
        components: comps,
    })
}
