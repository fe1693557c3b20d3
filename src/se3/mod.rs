//! Certified SE(3) pose graph optimization: SE-Sync's problem (Rosen, Carlone, Bandeira,
//! Leonard, IJRR 2019) with pgo's certificate. One module per idea:
//!
//! - [`problem`]: SE-Sync's weights (τ, κ from each 6x6 information matrix, beside the planar
//!   rule), the data matrix Q over the rows [t; Y] with one translation anchored (sparse, the
//!   translations kept as in the planar W̃), the cost and QX edge by edge with rounding bounds;
//! - [`stiefel`]: St(3, p)^n: tangent spaces, projections, the polar retraction;
//! - [`local`]: Riemannian Newton (damped, one symbolic factorization per rank, the
//!   translations projected out: variable projection), SE-Sync's Algorithm 2's local step;
//! - [`rounding`]: chordal initialization (its rotations refined by Gauss-Newton on the rotation
//!   cost where they are visibly off its minimum, then on the whole cost with the translations
//!   projected), the rank-3 rounding with the determinant's sign fixed;
//! - [`certificate`]: S = Q − SymBlockDiag(Λ) proven PSD (LDLᵀ inertia with a-posteriori backward
//!   error, Lehmann-Maehly/Temple for the three deflated directions), the lower bound and gap;
//! - this file: the Riemannian staircase (SE-Sync's Algorithm 1): Newton at rank 3 from the
//!   chordal start, the certificate, and where it fails, the escape along a direction of
//!   negative curvature of S to rank p + 1, the local optimum there rounded back to rank 3 and
//!   polished, certified again.
//!
//! May use: [`crate::certify`] (the shift ladder and equilibration it shares with the planar
//! certificate), [`crate::linalg`], [`crate::graph3`] (the file layer), [`crate::progress`].

// The 3x3 blocks and their rows, columns and local rows are indexed as in the formulas they
// implement (R̃_ab, Λ_i[a][b], Q's block [la][lb]): iterator chains would hide the math.
#![allow(clippy::needless_range_loop)]

pub mod certificate;
pub mod local;
pub mod problem;
pub mod rounding;
pub mod sdp;
pub mod stiefel;

use crate::error::Error;
use crate::graph3::Graph3;
use crate::linalg::heap::Room;
use certificate::{Bound3, Certifier3};
use local::{LocalOptions, Step3, System, Translations, optimize, optimize_with};
use problem::{Point3, Problem3, Weight3};
use rounding::{
    Rt, chordal, point_of, poses_of, refine_projected, refine_rotations, round_to_rank3,
};

/// Options of [`solve_graph3`].
#[derive(Debug, Clone, Copy)]
pub struct Options3 {
    /// Relative suboptimality under which the estimate counts as certified.
    pub tolerance: f64,
    /// Newton iterations per rank at most.
    pub max_iterations: usize,
    /// The staircase's largest rank (3 is the problem itself).
    pub max_rank: usize,
    /// The work above rank 3 at most, in real multiply-adds of the Newton factorizations (as
    /// [`crate::staircase::StaircaseOptions::staircase_budget`] in 2D).
    pub budget: f64,
}

impl Default for Options3 {
    fn default() -> Self {
        Options3 {
            tolerance: 1e-6,
            max_iterations: 200,
            max_rank: 10,
            // The planar staircase's default (its STAIRCASE_BUDGET), which `--staircase-budget` sets.
            budget: 5e10,
        }
    }
}

/// The answer for one connected 3D graph.
#[derive(Debug, Clone)]
pub struct Solution3 {
    /// The estimate (anchor's translation 0, rotations in the solver's frame).
    pub poses: Vec<Rt>,
    pub cost: f64,
    /// A proven lower bound on f* (0 when nothing better is proven: f is a sum of squares).
    pub lower_bound: f64,
    pub bound: Option<Bound3>,
    pub certified: bool,
    /// The largest rank reached (3: no staircase).
    pub rank: usize,
    pub iterations: usize,
    pub gradient_norm: f64,
    pub factorizations: usize,
    pub not_certified_because: Option<String>,
}

/// The anchor of a component: its FIX pose if any, else pose 0.
pub fn anchor_of(graph: &Graph3) -> usize {
    graph.fixed.first().copied().unwrap_or(0)
}

/// The η up to which a bound still certifies within `tolerance`: 3nη ≤ tol·max(f, 1).
fn eta_max(problem: &Problem3, cost: f64, tolerance: f64) -> f64 {
    tolerance * cost.max(1.0) / (3.0 * problem.n as f64)
}

/// Whether cost − bound ≤ tolerance·max(cost, 1).
pub fn within(cost: f64, lower_bound: f64, tolerance: f64) -> bool {
    cost - lower_bound <= tolerance * cost.abs().max(1.0)
}

/// The rounded, polished, certified candidate of a step of the staircase.
struct Candidate {
    point: Point3,
    cost: f64,
    gradient_norm: f64,
    bound: Option<Bound3>,
}

fn certify_point(
    problem: &Problem3,
    certifier: &mut Certifier3,
    point: &Point3,
    tolerance: f64,
) -> (f64, f64, Option<Bound3>) {
    let ev = problem.evaluate(point);
    let lambda = problem.multipliers(point, &ev.qx);
    let bound = certifier.certify(
        problem,
        point,
        &lambda,
        eta_max(problem, ev.cost, tolerance),
    );
    let grad = riemannian_gradient_norm(problem, point, &ev.qx, &lambda);
    (ev.cost, grad, bound)
}

/// ‖grad f‖ = 2‖QX − blkdiag(0, Λ)X‖ (the normal part removed).
fn riemannian_gradient_norm(
    problem: &Problem3,
    x: &Point3,
    qx: &[f64],
    lambda: &[[[f64; 3]; 3]],
) -> f64 {
    let p = x.p;
    let mut s = 0.0;
    let n1 = problem.n - 1;
    for r in 0..problem.dim() {
        for c in 0..p {
            let mut v = qx[r * p + c];
            if r >= n1 {
                let (i, a) = ((r - n1) / 3, (r - n1) % 3);
                for b in 0..3 {
                    v -= lambda[i][a][b] * x.x[problem.rotation_row(i, b) * p + c];
                }
            }
            s += v * v;
        }
    }
    2.0 * s.sqrt()
}

/// Solves one connected 3D graph: chordal start, Newton at rank 3, the certificate, the
/// staircase where it fails. `report` sees every Newton step.
pub fn solve_graph3(
    graph: &Graph3,
    weights: &[Weight3],
    options: &Options3,
    report: &mut dyn FnMut(Step3),
) -> Solution3 {
    solve_graph3_from(graph, weights, None, options, report)
}

/// As [`solve_graph3`] from given poses (in the graph's order) instead of the chordal start.
pub fn solve_graph3_from(
    graph: &Graph3,
    weights: &[Weight3],
    start: Option<&[Rt]>,
    options: &Options3,
    report: &mut dyn FnMut(Step3),
) -> Solution3 {
    crate::linalg::parallel::alone_if_small(graph.edges.len(), || {
        solve_problem(graph, weights, start, options, report)
    })
}

/// [`solve_graph3_from`]'s work, on one core or two.
fn solve_problem(
    graph: &Graph3,
    weights: &[Weight3],
    start: Option<&[Rt]>,
    options: &Options3,
    report: &mut dyn FnMut(Step3),
) -> Solution3 {
    let problem = Problem3::new(graph, weights, anchor_of(graph));
    let local = LocalOptions {
        max_iterations: options.max_iterations,
    };
    let descend = |translations: &dyn Fn() -> Translations,
                   system: &dyn Fn() -> Option<System>,
                   room: &dyn Fn() -> Vec<f64>,
                   report: &mut dyn FnMut(Step3)| {
        let mut point = match start {
            Some(poses) => point_of(&problem, poses),
            None => {
                crate::progress::phase("chordal initialization");
                let mut x = chordal(&problem);
                refine_rotations(&problem, &mut x);
                x
            }
        };
        let mut translations = translations();
        if start.is_none() {
            refine_projected(&problem, &mut translations, &mut point);
        }
        crate::progress::phase("Riemannian Newton, rank 3");
        let first = optimize_with(
            &problem,
            &mut translations,
            point,
            &local,
            report,
            system,
            room,
        );
        (translations, first)
    };
    // The rank-3 Newton system's assembly and analysis, L's factor and the certificate's analysis
    // depend on the problem alone: with a second core they are built there, in that order, while
    // this thread computes the chordal estimate and descends (parking-garage: 11 ms for the
    // certificate's analysis). The descent takes the Newton system once its start is projected
    // (torus3D: the system's 30 ms beside the chordal estimate's instead of before it); L's
    // factor, for that projection, is a spare task that whichever thread comes to it first
    // computes. Each is computed as it would be here: the same bits on one core or two. Before
    // the certificate's analysis, which is needed only after Newton, the second core maps the
    // pages of the room for the Newton factor's values ([`Room`]), which the first factorization
    // would otherwise fault in one by one on this thread (torus3D: its first LLᵀ took 43 ms, the
    // second 30 ms); where this thread comes to it first, it maps the chunks left itself, and
    // while it waits for the system it maps the room as soon as the analysis has sized it
    // (whole process against mapping after the wait, 20 interleaved pairs: cubicle 0.988,
    // parking-garage 0.993, torus3D 0.996, sphere2500 0.998, smallGrid3D 1.001).
    // Then the tasks left for an idle core ([`crate::linalg::parallel::when_idle`]: the output's
    // edge lines) may start there, unless the Newton factorizations split themselves between the
    // cores; else once the descent is over, beside the certificate.
    let room = Room::new();
    let descent_splits = std::sync::atomic::AtomicBool::new(false);
    let ((mut translations, mut first), mut certifier) = crate::linalg::parallel::ahead(
        || {
            // The room is prepared as soon as the values' count is known (this thread maps it
            // while it waits for the system), and forgone whatever happens: that wait must end.
            let _settled = room.settled_on_drop();
            let system = System::announcing(&problem, 3, |_, values| room.prepare(values));
            descent_splits.store(
                system.splits_factorizations(),
                std::sync::atomic::Ordering::Relaxed,
            );
            system
        },
        || Translations::new(&problem),
        || {
            room.map();
            let certifier = Certifier3::new(&problem);
            if !descent_splits.load(std::sync::atomic::Ordering::Relaxed) {
                crate::linalg::parallel::let_idle_tasks_start();
            }
            certifier
        },
        |system, translations| {
            let descent = descend(
                &|| translations.take(|| Translations::new(&problem)),
                &|| system.take_or(|| room.map_once_prepared()),
                &|| room.take(),
                report,
            );
            // Not mapped for nothing where no factorization asked for it (on one core, always).
            room.forgo();
            descent
        },
    );
    crate::linalg::parallel::let_idle_tasks_start();
    // The Newton factor's memory, pages mapped, for the certificate's factor.
    certifier.reuse(std::mem::take(&mut first.room));
    let mut iterations = first.iterations;
    let mut work = 0.0;
    crate::progress::phase("certificate");
    let (cost, gradient_norm, bound) =
        certify_point(&problem, &mut certifier, &first.point, options.tolerance);
    let mut best = Candidate {
        point: first.point.clone(),
        cost,
        gradient_norm,
        bound,
    };
    let certified = |c: &Candidate| {
        c.bound
            .is_some_and(|b| within(c.cost, b.lower_bound, options.tolerance))
    };
    let mut rank = 3;
    let mut current = first.point;
    let mut relaxation_bound: Option<f64> = None;
    let mut why: Option<String> = None;
    let mut previous = f64::INFINITY;
    while !certified(&best) {
        if rank >= options.max_rank {
            why = Some(format!("the staircase reached its largest rank {rank}"));
            break;
        }
        if work > options.budget {
            why = Some("the staircase reached its work budget".into());
            break;
        }
        // Escape: a direction of negative curvature of S at the current rank's point.
        let qx = local::apply_q(&problem, &current);
        let lambda = problem.multipliers(&current, &qx);
        let Some((v, curvature)) = certifier.negative_direction(&problem, &lambda) else {
            why = Some("the certificate matrix could not be factored".into());
            break;
        };
        let scale = problem
            .terms
            .iter()
            .map(|t| t.kappa + t.tau)
            .fold(0.0f64, f64::max);
        // A curvature within the accuracy of the local optimum (or a lift that no longer lowers
        // f): the relaxation's optimum is reached as far as the iterates tell.
        let cost_now = problem.cost(&current);
        if curvature >= -1e-7 * scale || (previous - cost_now) <= 1e-10 * cost_now.abs() {
            why = Some(
                "the relaxation's optimum does not round to a certified estimate (the relaxation is not exact, or not within the tolerance)"
                    .into(),
            );
            break;
        }
        previous = cost_now;
        let Some(escaped) = escape(&problem, &mut translations, &current, &v) else {
            why = Some("no descent along the direction of negative curvature".into());
            break;
        };
        rank += 1;
        crate::progress::phase(&format!("Riemannian Newton, rank {rank}"));
        let lifted = optimize(&problem, &mut translations, escaped, &local, report);
        iterations += lifted.iterations;
        work += lifted.work;
        current = lifted.point;
        let rounded = round_to_rank3(&problem, &current);
        let polished = optimize(&problem, &mut translations, rounded, &local, report);
        iterations += polished.iterations;
        work += polished.work;
        crate::progress::phase("certificate");
        let (cost, gradient_norm, bound) =
            certify_point(&problem, &mut certifier, &polished.point, options.tolerance);
        if cost < best.cost || (bound.is_some() && best.bound.is_none()) {
            best = Candidate {
                point: polished.point,
                cost,
                gradient_norm,
                bound,
            };
        }
    }
    if !certified(&best) && current.p > 3 {
        // The bound of the relaxation at the last rank's point (valid whatever that point is:
        // any Λ with S(Λ) + ηP ⪰ 0 proven bounds f*).
        let ev = problem.evaluate(&current);
        let lambda = problem.multipliers(&current, &ev.qx);
        let reach = ev.cost.max(certificate::dual_value(&lambda, 0.0)) / (3.0 * problem.n as f64);
        if let Some(b) = certifier.certify_cholesky(&problem, &lambda, reach) {
            relaxation_bound = Some(b.lower_bound);
        }
    }
    let mut lower_bound = best.bound.map_or(0.0, |b| b.lower_bound).max(0.0);
    if let Some(r) = relaxation_bound {
        lower_bound = lower_bound.max(r);
    }
    let certified = within(best.cost, lower_bound, options.tolerance) && best.bound.is_some()
        || within(best.cost, lower_bound, options.tolerance) && relaxation_bound.is_some();
    if !certified && why.is_none() {
        why = Some("the suboptimality bound exceeds the tolerance".into());
    }
    Solution3 {
        poses: poses_of(&problem, &best.point),
        cost: best.cost,
        lower_bound,
        bound: best.bound,
        certified,
        rank,
        iterations,
        gradient_norm: best.gradient_norm,
        factorizations: certifier.factorizations,
        not_certified_because: if certified { None } else { why },
    }
}

/// From a rank-p point to rank p + 1 along a unit direction v of negative curvature of S:
/// [X | 0] + α[0 | v], retracted, α halved from √n until the cost decreases.
fn escape(
    problem: &Problem3,
    translations: &mut Translations,
    x: &Point3,
    v: &[f64],
) -> Option<Point3> {
    let p = x.p;
    let q = p + 1;
    let dim = problem.dim();
    let f0 = problem.cost(x);
    let mut alpha = (problem.n as f64).sqrt();
    for _ in 0..40 {
        let mut y = Point3 {
            p: q,
            x: vec![0.0; dim * q],
        };
        for r in 0..dim {
            y.x[r * q..r * q + p].copy_from_slice(x.row(r));
            y.x[r * q + p] = alpha * v[r];
        }
        for i in 0..problem.n {
            let r0 = problem.rotation_row(i, 0);
            stiefel::polar_rows(&mut y.x[r0 * q..(r0 + 3) * q], q);
        }
        translations.project(problem, &mut y);
        if problem.cost(&y) < f0 {
            return Some(y);
        }
        alpha /= 2.0;
    }
    None
}

/// The cost of an estimate and the bound its own multipliers prove (`None`: not proven for any
/// η ≤ `eta_max`).
pub struct EstimateBound3 {
    pub cost: f64,
    pub bound: Option<Bound3>,
    pub gradient_norm: f64,
}

/// Certifies an estimate of one connected graph (poses in the graph's order) with its own
/// multipliers.
pub fn certify_estimate3(
    graph: &Graph3,
    weights: &[Weight3],
    poses: &[Rt],
    tolerance: f64,
) -> EstimateBound3 {
    let problem = Problem3::new(graph, weights, anchor_of(graph));
    let mut certifier = Certifier3::new(&problem);
    let point = point_of(&problem, poses);
    let ev = problem.evaluate(&point);
    let lambda = problem.multipliers(&point, &ev.qx);
    // Any η gives a valid bound; beyond the tolerance's η it only does not certify.
    let limit = eta_max(&problem, ev.cost, tolerance).max(ev.cost / (3.0 * problem.n as f64));
    let bound = certifier.certify(&problem, &point, &lambda, limit);
    let gradient_norm = riemannian_gradient_norm(&problem, &point, &ev.qx, &lambda);
    EstimateBound3 {
        cost: ev.cost,
        bound,
        gradient_norm,
    }
}

/// Every connected component of a 3D graph as a graph of its own, and its poses' indices in the
/// whole graph (ascending).
pub fn components3(graph: &Graph3) -> Vec<(Graph3, Vec<usize>)> {
    let (label, count) = graph.connected_components();
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); count];
    let mut local = vec![0; graph.num_poses()];
    for (k, &l) in label.iter().enumerate() {
        local[k] = members[l].len();
        members[l].push(k);
    }
    members
        .into_iter()
        .enumerate()
        .map(|(c, m)| {
            let part = Graph3 {
                ids: m.iter().map(|&k| graph.ids[k]).collect(),
                poses: m.iter().map(|&k| graph.poses[k]).collect(),
                edges: graph
                    .edges
                    .iter()
                    .filter(|e| label[e.i] == c)
                    .map(|e| {
                        let mut e = *e;
                        e.i = local[e.i];
                        e.j = local[e.j];
                        e
                    })
                    .collect(),
                fixed: graph
                    .fixed
                    .iter()
                    .filter(|&&k| label[k] == c)
                    .map(|&k| local[k])
                    .collect(),
                form: graph.form,
            };
            (part, m)
        })
        .collect()
}

/// The 3D graphs the staircase does not take (an error naming why): no poses, an edge from a
/// pose to itself, several FIX poses in one component.
pub fn check3(graph: &Graph3, parts: &[(Graph3, Vec<usize>)]) -> Result<(), Error> {
    if graph.num_poses() == 0 {
        return Err(Error::Invalid("the graph has no poses".into()));
    }
    if let Some(e) = graph.edges.iter().find(|e| e.i == e.j) {
        return Err(Error::Invalid(format!(
            "edge {} -> {} joins a pose to itself: 3D graphs with such edges are not solved",
            graph.ids[e.i], graph.ids[e.j]
        )));
    }
    if let Some((part, _)) = parts.iter().find(|(p, _)| p.fixed.len() > 1) {
        let mut ids: Vec<u32> = part.fixed.iter().map(|&k| part.ids[k]).collect();
        ids.sort_unstable();
        let list: Vec<String> = ids.iter().map(u32::to_string).collect();
        return Err(Error::Invalid(format!(
            "FIX lines name vertices {}, which are in one connected component: several fixed \
             poses in one component are known poses, a constrained problem that pgo does not \
             solve or certify (one FIX per component only sets the gauge); keep at most one \
             FIX line per component",
            list.join(", ")
        )));
    }
    Ok(())
}

/// The rotation matrix and translation of a file pose.
pub fn rt_of(pose: &crate::graph3::Pose3) -> Rt {
    let m = pose.rotation.unit_quaternion().to_rotation_matrix();
    let m = m.matrix();
    let mut r = [0.0; 9];
    for a in 0..3 {
        for b in 0..3 {
            r[a * 3 + b] = m[(a, b)];
        }
    }
    Rt {
        r,
        t: pose.translation,
    }
}

/// The problem of a noisy 27-pose grid world (seed `seed`, rotation noise `sigma`), anchored at
/// pose `anchor`: for the tests of the modules that take a [`Problem3`].
#[cfg(test)]
pub(crate) fn grid_problem(seed: u64, anchor: usize, sigma: f64) -> Problem3 {
    use crate::simulate::space::{SpaceConfig, World3, simulate3};
    use crate::simulate::{RotationNoise, TranslationNoise};
    let graph = simulate3(&SpaceConfig {
        world: World3::Grid,
        n: 27,
        side: 6.0,
        loop_probability: 0.3,
        rotation_noise: RotationNoise::Gaussian { sigma },
        translation_noise: TranslationNoise::Gaussian { sigma: 0.05 },
        seed,
    })
    .graph;
    let weights = problem::weights3(&graph, false).unwrap();
    Problem3::new(&graph, &weights, anchor)
}
