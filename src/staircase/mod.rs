//! The scalable certified solver (docs/method.md §3.2): chordal initialization, Riemannian Newton on
//! the rank-1 manifold (|r_i| = 1), the sparse certificate of [`crate::certify::SparseCertifier`],
//! and, when the certificate fails, the Riemannian staircase in the complex domain (rank p > 1,
//! unit-norm rows; SE-Sync's scheme with ℂ in place of ℝ²) escaping saddles along a direction of
//! negative curvature of W̃(λ), then rounding back to rank 1 and certifying again.
//!
//! Local optimization: Newton steps on the tangent coordinates of [`crate::problem::rank_p`], with the
//! exact Riemannian Hessian 2 Bᵀ W̃(λ) B, damped Levenberg-Marquardt style (H + μD, D the diagonal
//! of 2W̃, μ updated by Nielsen's rule from the ratio of actual to predicted decrease). The
//! Hessian's pattern is that of W̃ for every iterate, so one symbolic sparse Cholesky per rank is
//! reused across all iterations. μ → 0 near a nondegenerate minimum, where the steps become exact
//! Newton steps and converge quadratically.
//!
//! Variable projection (Golub and Pereyra): f is quadratic in the positions, so every trial point
//! takes the positions optimal for its rotations, ρ̃ = −L⁻¹S̃r̃ (eq. (24); one solve with a Cholesky
//! factor of the anchored Laplacian L computed once, [`OptimalPositions`]). The step still comes
//! from the joint Newton system, but f is evaluated on the reduced function r̃*Mr̃ (eq. (38)),
//! never above the joint step's value: on the M3500 family this halves the Newton iterations
//! (M3500a 16 to 8, M3500b 22 to 9, M3500c 24 to 12), ais2klinik 35 to 17.
//!
//! Stopping rule: after an accepted step whose predicted decrease was at most 1e-12·f (plus a
//! 1e-24 floor relative to the total edge weight, for graphs with f* = 0 such as trees and
//! chains). In the quadratic regime the cost then agrees with the local minimum's to far better
//! than 1e-9 relative; the proven bound is reported separately and does not rely on this.

//!
//! May use: [`crate::certify`], [`crate::problem`], [`crate::linalg`].

pub mod candidate;
pub mod init;
pub mod manifold;

use crate::certify::{HiddenGap, SparseBound, SparseCertifier};
use crate::graph::{Pose2, PoseGraph};
use crate::linalg::factor::SparseFactor;
use crate::linalg::heap::{RELEASE_FROM_ROWS, Room};
use crate::problem::rank_p::{Point, Problem};
use crate::problem::weights::EdgeWeight;
use faer::c64;
use init::{OptimalPositions, chordal_rotations, refine_rotations};
use manifold::{NewtonSystem, TangentBasis};

/// One accepted (or rejected) step, for progress reports and the rerun viewer.
#[derive(Debug, Clone, Copy)]
pub struct Iteration {
    pub rank: usize,
    pub iteration: usize,
    pub cost: f64,
    pub gradient_norm: f64,
    /// The Levenberg-Marquardt damping μ (the inverse of a trust-region radius).
    pub damping: f64,
}

/// Options of the staircase.
#[derive(Debug, Clone, Copy)]
pub struct StaircaseOptions {
    /// Relative suboptimality under which an estimate counts as certified.
    pub tolerance: f64,
    /// Newton iterations per rank at most.
    pub max_iterations: usize,
    /// The largest rank of the staircase.
    pub max_rank: usize,
    /// The work of the staircase at most, in real multiply-adds of its sparse factorizations
    /// (the first descent at rank 1, Newton steps at every rank, the rank-1 polish of each
    /// rounding, the certificate attempts and the final bound's optimization): counted from the factors'
    /// structure ([`SparseFactor::multiply_adds`]), not timed, so the limit and the answer are
    /// the same on every machine. A Newton step at rank p factors a system of the rank-1
    /// pattern with blocks (4p − 1)/3 times as wide ([`step_work`]), and long false loop
    /// closures fill the factor: on manhattan with 1000 of them one step at rank 4 took 10 s and
    /// the staircase ran for minutes. Past the budget the staircase stops and reports the best
    /// estimate and the bound it reached, with [`StaircaseSolution::limit_reached`]; graphs of a
    /// few hundred poses never reach the default. The first descent at rank 1 may take
    /// [`StaircaseOptions::min_descent_steps`] Newton steps whatever their work.
    pub staircase_budget: f64,
    /// The Newton steps the first descent at rank 1 may always take, past the budget (default
    /// [`MIN_DESCENT_STEPS`]), so that a clean graph too large for the budget (10⁶ poses) still
    /// reaches its minimum.
    pub min_descent_steps: usize,
    /// Whether the estimate is proven (default true). Off, [`solve_from`] returns the first
    /// descent's rank-1 estimate with no bound, no certificate attempted and no staircase: for
    /// GNC's inner problems ([`crate::robust`]), of which GNC uses only the estimates.
    pub certify: bool,
    /// Whether the chordal rotations are refined where they are visibly off the minimum of the
    /// rotation part of the cost ([`init::refine_rotations`], default true). Off for GNC's inner
    /// problems: with the false loop closures still weighing, that minimum pulls the rotations
    /// toward them, and the inlier sets came out worse (M3500 with 100 and 500 outliers: 2 to 12
    /// true loop closures rejected where the chordal start rejected 0 or 1).
    pub refine_rotations: bool,
}

impl Default for StaircaseOptions {
    fn default() -> Self {
        StaircaseOptions {
            tolerance: 1e-6,
            max_iterations: 200,
            max_rank: 6,
            staircase_budget: STAIRCASE_BUDGET,
            min_descent_steps: MIN_DESCENT_STEPS,
            certify: true,
            refine_rotations: true,
        }
    }
}

/// [`StaircaseOptions::staircase_budget`]'s default: 5·10¹⁰ multiply-adds, about 2.5 s on one
/// core of a 2026 x86 machine. One Newton step at rank 1 on city10000 (10⁴ poses) factors
/// 1·10⁸; the public planar files all certify at rank 1 in at most 8 steps, far below it. With
/// 1000 random false loop closures one step on city10000 factors 8.9·10⁹ (the long closures fill
/// the factor): the budget then ends the staircase in seconds, not minutes (issue 18).
pub const STAIRCASE_BUDGET: f64 = 5e10;

/// The Newton steps the first descent at rank 1 may always take, past the budget: the public
/// files take at most 8 (M3500b; M3500c took 12 before its chordal rotations were refined,
/// [`init::refine_rotations`]), generated graphs of 10⁶ poses 7 (scripts/bench-scale), so a
/// clean graph too large for the budget still converges. Beyond them and the budget the descent
/// stops: on city10000 with 1000 false loop closures (Vertigo's random model) it ran the 200
/// steps of [`StaircaseOptions::max_iterations`], 0.3 s each, still far from a minimum.
pub const MIN_DESCENT_STEPS: usize = 12;

/// The work of one Newton step at rank p in Newton steps at rank 1: the Newton system keeps the
/// pattern of W̃ at every rank, with blocks of 4p − 1 tangent coordinates per pose (2p for the
/// position, 2p − 1 for the rotation on the sphere |r_i| = 1) in place of 3, so its sparse
/// factorization takes ((4p − 1)/3)³ times the multiply-adds (rank 2: 12.7, rank 3: 49,
/// rank 4: 125).
pub fn step_work(p: usize) -> f64 {
    ((4 * p - 1) as f64 / 3.0).powi(3)
}

/// The result of the local optimization at one rank.
#[derive(Debug, Clone)]
pub struct Local {
    pub point: Point,
    pub cost: f64,
    /// λ of the first-order conditions at the point.
    pub lambda: Vec<f64>,
    /// Norm of the Riemannian gradient.
    pub gradient_norm: f64,
    pub iterations: usize,
    pub converged: bool,
    /// The multiply-adds of one factorization of the Newton system at this rank
    /// ([`SparseFactor::multiply_adds`]).
    pub step_work: f64,
    /// Whether a work limit ([`optimize_in`]), not convergence, ended the descent.
    pub limited: bool,
}

/// The scalable solver's answer for one connected graph.
#[derive(Debug, Clone)]
pub struct StaircaseSolution {
    /// The rank-1 estimate [ρ̃; r̃] (anchored at pose 0).
    pub point: Point,
    pub cost: f64,
    /// λ at the estimate.
    pub lambda: Vec<f64>,
    /// The proven bound (from the estimate's own λ, or from the staircase's last rank).
    pub bound: Option<SparseBound>,
    /// A proven lower bound on f* (0 when nothing better is proven: f is a sum of squares).
    pub lower_bound: f64,
    /// cost − lower_bound ≤ tolerance·max(cost, 1) and the bound is the rank-1 estimate's own or
    /// the relaxation's.
    pub certified: bool,
    /// The largest rank the staircase reached.
    pub rank: usize,
    pub iterations: usize,
    pub gradient_norm: f64,
    pub factorizations: usize,
    /// The number of eigenvalues of W̃(λ) below 16 times their resolution (LDLᴴ inertia,
    /// [`SparseCertifier::eigenvalue_resolution`]): 1 is the single zero eigenvalue property
    /// (Prop. 10) as far as double precision can tell. `None` if the
    /// LDLᴴ met a zero pivot.
    pub near_zero: Option<usize>,
    /// Not certified because the rounding hid W̃(λ)'s second eigenvalue
    /// ([`SparseCertifier::hidden_gap`]): then the near-zero eigenvalues are not counted (at
    /// the a-priori resolution the count would take eigenvalues the inertia showed above the
    /// estimate's own for zeros: 639 at 4·10⁶ generated poses).
    pub hidden_gap: Option<HiddenGap>,
    /// The work of the staircase, in multiply-adds ([`StaircaseOptions::staircase_budget`]).
    pub staircase_work: f64,
    /// Whether the staircase stopped at [`StaircaseOptions::staircase_budget`].
    pub limit_reached: bool,
}

/// The problem of a connected graph anchored at a chosen pose (the pose whose position is fixed
/// at 0, eq. (15)), with the maps between the graph's poses and the anchored state.
///
/// The certificate's resolution is proportional to Σ_k W̃_kk |x̃_k|² ([`SparseCertifier`]), which is
/// smallest when positions are measured from the middle of the map rather than from one end, so
/// the anchor is the pose nearest the τ-weighted centroid of an estimate.
pub struct Anchored {
    pub problem: Problem,
    /// The graph's index of the anchor (internal index 0); internal and graph indices differ
    /// only by exchanging 0 and `anchor`.
    pub anchor: usize,
}

impl Anchored {
    /// Anchored at the pose nearest the centroid of `poses` (in the graph's indexing).
    pub fn centered(graph: &PoseGraph, weights: &[EdgeWeight], poses: &[Pose2]) -> Self {
        let n = graph.num_poses();
        let mut degree = vec![0.0; n];
        for (e, w) in graph.edges.iter().zip(weights) {
            degree[e.i] += w.tau;
            degree[e.j] += w.tau;
        }
        let position = |k: usize| c64::new(poses[k].x, poses[k].y);
        let total: f64 = degree.iter().sum();
        let anchor = if total > 0.0 && total.is_finite() {
            let centroid = (0..n).map(|k| position(k) * degree[k]).sum::<c64>() / total;
            (0..n)
                .min_by(|&a, &b| {
                    (position(a) - centroid)
                        .norm()
                        .total_cmp(&(position(b) - centroid).norm())
                })
                .unwrap_or(0)
        } else {
            0
        };
        Self::at(graph, weights, anchor)
    }

    /// Anchored at pose `anchor`.
    pub fn at(graph: &PoseGraph, weights: &[EdgeWeight], anchor: usize) -> Self {
        Anchored {
            problem: Problem::relabeled(graph, weights, swapper(anchor)),
            anchor,
        }
    }

    /// The rank-1 state x̃ = [ρ̃; r̃] of poses given in the graph's indexing.
    pub fn point(&self, poses: &[Pose2]) -> Point {
        let swap = swapper(self.anchor);
        let internal: Vec<Pose2> = (0..poses.len()).map(|k| poses[swap(k)]).collect();
        Point {
            p: 1,
            x: self.problem.matrix.state(&internal),
        }
    }

    /// Per-pose values of the anchored problem (such as λ) in the graph's indexing.
    pub fn graph_order<T: Copy>(&self, internal: &[T]) -> Vec<T> {
        let swap = swapper(self.anchor);
        (0..internal.len()).map(|k| internal[swap(k)]).collect()
    }

    /// Poses of a rank-1 state in the graph's indexing, moved rigidly so that the graph's pose 0
    /// is exactly `pose0` (f is invariant to that).
    pub fn poses(&self, x: &Point, pose0: Pose2) -> Vec<Pose2> {
        let swap = swapper(self.anchor);
        let internal = self.problem.matrix.poses(&x.x);
        let poses: Vec<Pose2> = (0..internal.len()).map(|k| internal[swap(k)]).collect();
        crate::problem::gauge::move_to_anchor(&poses, pose0)
    }
}

/// The index map exchanging 0 and `anchor` (its own inverse).
fn swapper(anchor: usize) -> impl Fn(usize) -> usize {
    move |k| {
        if k == 0 {
            anchor
        } else if k == anchor {
            0
        } else {
            k
        }
    }
}

/// The staircase on a connected graph, from the chordal initialization, anchored at the centre
/// of the input's estimate; poses in the graph's indexing and gauge (pose 0 where the input has it).
pub fn solve_graph(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    options: &StaircaseOptions,
    observer: &mut dyn FnMut(&Iteration),
) -> Option<(StaircaseSolution, Vec<Pose2>)> {
    solve_graph_from_estimate(graph, weights, options, None, observer)
}

/// As [`solve_graph`], warm started: with `start` (one pose per pose of the graph, in its
/// indexing and any gauge), its headings are the rank-1 starting point in place of the chordal
/// initialization, and its positions are not used (every rank-1 point, the start too, takes the
/// positions optimal for its rotations: variable projection, module docs). The problem, its
/// anchor and the certificate are those of the cold start: only where Newton begins changes.
/// The caller checks `start` (its length, finite values).
pub fn solve_graph_from_estimate(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    options: &StaircaseOptions,
    start: Option<&[Pose2]>,
    observer: &mut dyn FnMut(&Iteration),
) -> Option<(StaircaseSolution, Vec<Pose2>)> {
    let (solution, anchored) = solve_anchored_from(graph, weights, options, start, observer)?;
    let poses = anchored.poses(&solution.point, graph.poses[0]);
    Some((solution, poses))
}

/// As [`solve_graph`], with the anchored problem the solution's point and λ refer to (see
/// [`Anchored::graph_order`]) instead of the poses.
pub fn solve_anchored(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    options: &StaircaseOptions,
    observer: &mut dyn FnMut(&Iteration),
) -> Option<(StaircaseSolution, Anchored)> {
    solve_anchored_from(graph, weights, options, None, observer)
}

/// The headings of `start` (graph indexing) as the anchored problem's rank-1 rotations, turned
/// so that the anchor's is 1 (the chordal initialization's gauge; f is invariant to it).
fn start_rotations(anchored: &Anchored, start: &[Pose2]) -> Vec<c64> {
    let swap = swapper(anchored.anchor);
    let r: Vec<c64> = (0..anchored.problem.n)
        .map(|k| crate::problem::matrix::rotation(start[swap(k)].theta))
        .collect();
    let turn = r[0].conj();
    r.into_iter().map(|z| z * turn).collect()
}

/// As [`solve_anchored`], from `start`'s headings when given (see
/// [`solve_graph_from_estimate`]).
pub fn solve_anchored_from(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    options: &StaircaseOptions,
    start: Option<&[Pose2]>,
    observer: &mut dyn FnMut(&Iteration),
) -> Option<(StaircaseSolution, Anchored)> {
    let terms = graph.edges.len() + graph.landmarks.observations.len();
    crate::linalg::parallel::alone_if_small(terms, || {
        solve_anchored_here(graph, weights, options, start, observer)
    })
}

/// [`solve_anchored_from`]'s work, on one core or two.
fn solve_anchored_here(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    options: &StaircaseOptions,
    start: Option<&[Pose2]>,
    observer: &mut dyn FnMut(&Iteration),
) -> Option<(StaircaseSolution, Anchored)> {
    // The anchor: the pose nearest the centre of the input's own estimate (the file's vertices,
    // or its spanning-tree composition for edges-only files), so the problem is built once; the
    // same with a warm start, so that warm and cold starts solve the same problem.
    let start = start.filter(|s| s.len() == graph.num_poses());
    crate::progress::phase(if start.is_some() {
        "initialization (the given estimate)"
    } else {
        "initialization (chordal)"
    });
    let anchored = Anchored::centered(graph, weights, &graph.poses);
    let rank_one = |r: Vec<c64>| Point {
        p: 1,
        x: vec![c64::new(0.0, 0.0); anchored.problem.positions()]
            .into_iter()
            .chain(r)
            .collect(),
    };
    if let Some(start) = start {
        if graph.connected_components().1 != 1 {
            return None;
        }
        let start = rank_one(start_rotations(&anchored, start));
        let solution = solve_from(&anchored.problem, start, options, observer);
        return Some((solution, anchored));
    }
    // With landmarks, the chordal relaxation of the whole problem ([`init::chordal_full`]).
    // Poses joined only through landmarks have no rotation measurement between them: the
    // chordal relaxation of the rotations is then singular, and the rotations of the input's estimate (the
    // file's, or composed along the spanning tree through the landmarks) start instead.
    let chordal = || {
        let full = || {
            (!graph.landmarks.is_empty())
                .then(|| crate::staircase::init::chordal_full(&anchored.problem))
                .flatten()
        };
        full()
            .or_else(|| {
                chordal_rotations(&anchored.problem).map(|r| {
                    if options.refine_rotations {
                        refine_rotations(&anchored.problem, r)
                    } else {
                        r
                    }
                })
            })
            .or_else(|| {
                (!graph.landmarks.is_empty()).then(|| {
                    let swap = swapper(anchored.anchor);
                    (0..graph.num_poses())
                        .map(|k| crate::problem::matrix::rotation(graph.poses[swap(k)].theta))
                        .collect()
                })
            })
            .map(rank_one)
    };
    let offer = |point: &Point| candidate::offer(|| anchored.poses(point, graph.poses[0]));
    let solution = solve_from_start(&anchored.problem, chordal, options, &offer, observer)?;
    Some((solution, anchored))
}

/// What the certificate establishes for a given estimate (pgo-certify).
pub struct EstimateCertificate {
    /// f at the estimate.
    pub cost: f64,
    /// The bound proven from the estimate's own multipliers λ, if any within `reach`.
    pub bound: Option<SparseBound>,
    /// Norm of the Riemannian gradient at the estimate (0 at a critical point).
    pub gradient_norm: f64,
    pub lambda: Vec<f64>,
    pub certifier: SparseCertifier,
    pub anchored: Anchored,
}

/// Tries to certify an estimate (poses in the graph's indexing) with its own first-order
/// multipliers λ_a = Re(r̄_a (W̃x̃)_a): W̃(λ) + ηP ⪰ 0 proven for η up to `reach`.
pub fn certify_estimate(
    graph: &PoseGraph,
    weights: &[EdgeWeight],
    poses: &[Pose2],
    reach: f64,
) -> EstimateCertificate {
    crate::progress::phase("certificate");
    let anchored = Anchored::centered(graph, weights, poses);
    let problem = &anchored.problem;
    let x = anchored.point(poses);
    let cost = problem.cost(&x);
    let g = problem.half_gradient(&x);
    let lambda = problem.multipliers(&x, &g);
    let basis = TangentBasis::new(problem, &x);
    let gradient_norm = 2.0
        * basis
            .coordinates(&g)
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt();
    let mut certifier = SparseCertifier::new(&problem.matrix.upper, &problem.row_order());
    let bound = certifier.certify(problem, &x, &lambda, reach);
    EstimateCertificate {
        cost,
        bound,
        gradient_norm,
        lambda,
        certifier,
        anchored,
    }
}

/// Riemannian Newton (damped) at the point's rank, to the stopping rule of the module docs (a
/// looser one, 1e-5·f, above rank 1).
pub fn optimize(
    problem: &Problem,
    positions: Option<&mut OptimalPositions>,
    start: Point,
    options: &StaircaseOptions,
    observer: &mut dyn FnMut(&Iteration),
) -> Local {
    let stop = if start.p == 1 { 1e-12 } else { 1e-5 };
    optimize_to(problem, positions, start, options, observer, stop)
}

/// Riemannian Newton (damped) until a step predicts a decrease of at most `stop`·f. With
/// `positions`, every point (the start too) takes the positions optimal for its rotations
/// (variable projection, module docs).
pub fn optimize_to(
    problem: &Problem,
    positions: Option<&mut OptimalPositions>,
    start: Point,
    options: &StaircaseOptions,
    observer: &mut dyn FnMut(&Iteration),
    stop_tolerance: f64,
) -> Local {
    optimize_in(
        problem,
        positions,
        start,
        options,
        observer,
        stop_tolerance,
        None,
        &mut None,
        &|| None,
    )
}

/// The Newton system of `basis`'s rank: the one in `system` if it is of that rank (its pattern
/// and symbolic factorization depend on nothing else), else a new one, kept there.
fn system_for<'a>(
    system: &'a mut Option<NewtonSystem>,
    problem: &Problem,
    basis: &TangentBasis,
) -> &'a mut NewtonSystem {
    if system.as_ref().is_some_and(|s| s.dim() == basis.dim) {
        return system.as_mut().expect("checked");
    }
    system.insert(NewtonSystem::new(problem, basis.p))
}

/// As [`optimize_to`], within `work_limit` multiply-adds of its factorizations when given: at
/// most work_limit / (one factorization's multiply-adds) steps, and never fewer than
/// [`StaircaseOptions::min_descent_steps`] (nor more than `options.max_iterations`); with the
/// Newton system of an earlier call at the same rank in `system` (at 10⁶ poses its analysis
/// takes longer than three factorizations), or else the one `arriving` hands over when the
/// first step needs it (built on a second core: the start's projection, cost, gradient and
/// multipliers are computed while it is being built).
#[allow(clippy::too_many_arguments)]
fn optimize_in(
    problem: &Problem,
    mut positions: Option<&mut OptimalPositions>,
    start: Point,
    options: &StaircaseOptions,
    observer: &mut dyn FnMut(&Iteration),
    stop_tolerance: f64,
    work_limit: Option<f64>,
    system: &mut Option<NewtonSystem>,
    arriving: &dyn Fn() -> Option<NewtonSystem>,
) -> Local {
    let mut project = |x: &mut Point| {
        if let Some(positions) = positions.as_deref_mut() {
            positions.apply(problem, x);
        }
    };
    let mut start = start;
    project(&mut start);
    let p = start.p;
    let weight_scale: f64 = problem.terms.iter().map(|t| t.tau + t.kappa).sum();
    let cost = problem.cost(&start);
    let mut at = Iterate::new(problem, start, cost);
    if system.is_none() {
        *system = arriving();
    }
    let system = system_for(system, problem, &at.basis);
    let step_work = system.multiply_adds();
    let max_iterations = match work_limit {
        Some(w) => options.max_iterations.min(
            options
                .min_descent_steps
                .max((w / step_work).max(0.0) as usize),
        ),
        None => options.max_iterations,
    };
    let mut mu = 1e-6;
    let mut nu = 2.0;
    // Nielsen's rule, μ·max(1 − (2ρ − 1)³, c), with c = 1/1000 at rank 1 rather than his 1/3: the
    // damping μ·2diag(W̃) slows Newton to linear convergence along the graph's soft directions
    // (long corridors: Hessian eigenvalues ~10⁻⁷ of its diagonal), so where the quadratic model
    // predicted the decrease well (ρ ≈ 1) μ falls 1000x per step, from 1e-6 to its floor 1e-12 in
    // two. Newton steps with c = 1/100 against 1/3: victoriaPark 9 to 5, kitti_00 7 to 4, M3500 7
    // to 5, ais2klinik 17 to 10; with 1/1000 against 1/100: ais2klinik 10 to 7 (whole process
    // 0.85 of its time), FRH, manhattan's TORO file and ring_groundtruth one fewer, the other
    // public planar files and 60 generated ones as many (the same optima to 1e-14 relative; 1e-4
    // and 1e-6 took as many steps as 1e-3). Above rank 1 the minima are degenerate (a singular
    // Hessian along the rank-deficient directions) and a collapsed μ overshoots there: his 1/3.
    let fastest_decrease: f64 = if p == 1 { 1e-3 } else { 1.0 / 3.0 };
    // Far from a minimum the exact Hessian 2BᵀW̃(λ)B is indefinite and its model poor; the
    // Gauss-Newton model 2BᵀW̃B (⪰ 0: the λ term dropped) makes faster progress there. Exact
    // Newton takes over once a step gains less than 1% (quadratic convergence near the end).
    let zeros = vec![0.0; problem.n];
    let mut gauss_newton = true;
    let mut iterations = 0;
    let mut converged = false;
    let mut chord_next = false;
    let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
    while iterations < max_iterations {
        if norm(&at.grad) == 0.0 {
            converged = true;
            break;
        }
        iterations += 1;
        let small = |predicted: f64| predicted <= stop_tolerance * at.cost + 1e-24 * weight_scale;
        // The chord step: after an exact Newton step that gained less than 1e-6 f, quadratic
        // convergence leaves a decrease below the stopping rule, and the factorization of the
        // point just left finds that last step as well as a new one would (the Hessian moved by
        // the length of that step). Its model decrease takes δᵀHδ at the current point.
        // δ = −(the last factorization)⁻¹ g.
        let direction = |system: &mut NewtonSystem| system.solve(|k| -at.grad[k]);
        let chord = std::mem::take(&mut chord_next)
            .then(|| {
                let delta = direction(system);
                let gd: f64 = at.grad.iter().zip(&delta).map(|(a, b)| a * b).sum();
                let dhd = at.basis.hessian_form(problem, &at.lambda, &delta);
                let predicted = -gd - 0.5 * dhd;
                (predicted >= 0.0 && small(predicted)).then_some((delta, dhd))
            })
            .flatten();
        let (delta, chord_curvature) = match chord {
            Some((delta, dhd)) => (delta, Some(dhd)),
            None => {
                let model = if gauss_newton { &zeros } else { &at.lambda };
                system.update(problem, &at.basis, model, mu);
                if system.factorize().is_err() {
                    mu = (mu * 10.0).max(1e-9);
                    if mu > 1e12 {
                        break;
                    }
                    continue;
                }
                (direction(system), None)
            }
        };
        // The model's decrease along αδ: m(0) − m(αδ) = −α gᵀδ − ½α² δᵀHδ, where (H + μD)δ = −g
        // gives δᵀHδ = −gᵀδ − μ δᵀDδ.
        let gd: f64 = at.grad.iter().zip(&delta).map(|(a, b)| a * b).sum();
        let dd = at.basis.damped_square(problem, &delta);
        let predicted_at = |alpha: f64| match chord_curvature {
            Some(dhd) => -alpha * gd - 0.5 * alpha * alpha * dhd,
            None => alpha * (1.0 - 0.5 * alpha) * -gd + 0.5 * alpha * alpha * mu * dd,
        };
        let predicted = predicted_at(1.0);
        let mut trial = at.basis.retract(&at.x, &delta, problem.positions());
        project(&mut trial);
        let trial_cost = problem.cost(&trial);
        let rho = (at.cost - trial_cost) / predicted;
        observer(&Iteration {
            rank: p,
            iteration: iterations,
            cost: trial_cost.min(at.cost),
            gradient_norm: norm(&at.grad),
            damping: mu,
        });
        let small = small(predicted);
        if rho > 1e-4 && predicted > 0.0 {
            let gain = at.cost - trial_cost;
            chord_next = !gauss_newton && chord_curvature.is_none() && gain <= 1e-6 * at.cost;
            // The old iterate goes before the new one is built: at 10⁶ poses its point, basis,
            // gradient and multipliers are some 85 MB, on top of the step's peak.
            drop(at);
            at = Iterate::new(problem, trial, trial_cost);
            mu = (mu * fastest_decrease.max(1.0 - (2.0 * rho - 1.0).powi(3))).max(1e-12);
            nu = 2.0;
            if gauss_newton && gain < 1e-2 * at.cost {
                gauss_newton = false;
            }
            if small && !gauss_newton {
                converged = true;
                break;
            }
            continue;
        }
        if gauss_newton && !small {
            // The Gauss-Newton model failed here: exact Newton from now on. Where the decrease
            // it predicted is below the stopping rule already, the step is judged as an exact
            // one's would be (below) instead: the two models differ by the λ term, and at
            // kitti_08's start (a zero residual, f = 1.4e-18, λ ≈ 0) exact Newton factored again
            // for the same step and the same verdict (whole process 0.947 of its time, 31
            // interleaved runs; the same bytes on the 46 public files).
            gauss_newton = false;
            continue;
        }
        if small && (predicted >= 0.0 || predicted.is_nan()) {
            // Nothing left to gain at this precision. Where the model predicted a decrease
            // below the cost's own rounding, the measured one is rounding too and cannot judge
            // the step; the gradient can: a step that halves it, at a cost no higher than
            // rounding allows, is kept (as in [`polish`]). Which side of ρ's test such a step
            // falls on is the rounding's choice: M3500c's last step from a gradient of 1.3e-6
            // failed it, and the certificate's gap was 3.7e-7; kept, 1.7e-8 (ring 2.1e-9 to
            // 7.6e-11, input_INTEL 1.1e-7 to 5.4e-10).
            if predicted >= 0.0 && no_costlier(trial_cost, at.cost) {
                // Only the gradients' norms are compared: the current iterate's basis and
                // gradient go first, and the trial's gradient is summed into its norm, without
                // its coordinates (at 10⁶ poses a second whole iterate raised the peak by 54
                // MiB); the trial becomes a whole iterate only once kept.
                let now = norm(&at.grad);
                let Iterate {
                    x, cost, lambda, ..
                } = at;
                let then = 2.0
                    * TangentBasis::new(problem, &trial)
                        .coordinates_norm(&problem.half_gradient(&trial));
                let (point, cost, lambda, gradient_norm) = if halves(then, now) {
                    drop((x, lambda));
                    let kept = Iterate::new(problem, trial, trial_cost);
                    (kept.x, kept.cost, kept.lambda, then)
                } else {
                    (x, cost, lambda, now)
                };
                return Local {
                    gradient_norm,
                    point,
                    cost,
                    lambda,
                    iterations,
                    converged: true,
                    step_work,
                    limited: false,
                };
            }
            converged = true;
            break;
        }
        // Backtracking along the same direction costs a cost evaluation, not a factorization:
        // on M3500c, where every other exact Newton step overshoots in the nonconvex region,
        // it halves the number of factorizations (48 to 24). A shortened step that decreases f
        // enough is taken and μ doubled (the model held only within a shorter step); otherwise
        // μ grows by Nielsen's rule and the system is solved again.
        let shortened = [0.5, 0.25].into_iter().find_map(|alpha| {
            let step: Vec<f64> = delta.iter().map(|d| alpha * d).collect();
            let mut trial = at.basis.retract(&at.x, &step, problem.positions());
            project(&mut trial);
            let trial_cost = problem.cost(&trial);
            let predicted = predicted_at(alpha);
            (predicted > 0.0 && at.cost - trial_cost > 1e-4 * predicted)
                .then_some((trial, trial_cost))
        });
        if let Some((trial, trial_cost)) = shortened {
            drop(at);
            at = Iterate::new(problem, trial, trial_cost);
            mu *= 2.0;
            continue;
        }
        mu *= nu;
        nu *= 2.0;
        if mu > 1e12 {
            break;
        }
    }
    Local {
        gradient_norm: norm(&at.grad),
        point: at.x,
        cost: at.cost,
        lambda: at.lambda,
        iterations,
        converged,
        step_work,
        limited: !converged
            && iterations >= max_iterations
            && max_iterations < options.max_iterations,
    }
}

/// A point of the Newton iteration with what the next step needs: f, λ of the first-order
/// conditions, the tangent basis and the Riemannian gradient's coordinates 2Bᵀ(W̃x̃).
struct Iterate {
    x: Point,
    cost: f64,
    lambda: Vec<f64>,
    basis: TangentBasis,
    grad: Vec<f64>,
}

impl Iterate {
    fn new(problem: &Problem, x: Point, cost: f64) -> Self {
        let g = problem.half_gradient(&x);
        let lambda = problem.multipliers(&x, &g);
        let basis = TangentBasis::new(problem, &x);
        // Twice the half gradient's coordinates, doubled where they are (one vector of the
        // basis's dimension, not two).
        let mut grad = basis.coordinates(&g);
        grad.iter_mut().for_each(|v| *v *= 2.0);
        Iterate {
            x,
            cost,
            lambda,
            basis,
            grad,
        }
    }
}

/// Whether a step that the cost cannot judge (its change is rounding) is kept, as far as the
/// cost goes: no higher than rounding allows ([`polish`], and Newton's last step).
fn no_costlier(trial: f64, current: f64) -> bool {
    trial <= current * (1.0 + 1e-12)
}

/// Whether a step's Riemannian gradient norm is less than half the current one: the rule that
/// keeps a step the cost cannot judge ([`polish`], and Newton's last step).
fn halves(trial: f64, current: f64) -> bool {
    trial < 0.5 * current
}

/// Polishes a local minimum below the resolution of its cost: exact Newton steps (damping
/// 1e-10 for the gauge direction), each kept only if it at least halves the Riemannian gradient,
/// at most 4. Near the end the cost changes by less than its own rounding, so the stopping rule
/// of [`optimize_to`] cannot see further steps; the certificate can, as its loss grows with the
/// square of the residual W̃(λ)x ([`SparseCertifier::certify_rank_one`]).
///
/// After a step that cut the gradient a thousandfold, the next one is a chord step (the
/// factorization of the point just left, whose Hessian differs by the length of that step):
/// quadratic convergence leaves the next exact step a further cut of that order, which a chord
/// step comes close to, so where it does not even halve the gradient, the rounding of the
/// gradient is reached and the polish ends without another factorization.
pub fn polish(problem: &Problem, local: Local) -> Local {
    polish_in(problem, local, &mut None)
}

/// [`polish`] with the rank-1 Newton system of an earlier call.
fn polish_in(problem: &Problem, local: Local, system: &mut Option<NewtonSystem>) -> Local {
    let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
    let mut local = local;
    // The basis and gradient at the current point, carried from one step to the next.
    let mut basis = TangentBasis::new(problem, &local.point);
    let mut grad = basis.coordinates(&problem.half_gradient(&local.point));
    let system = system_for(system, problem, &basis);
    let mut chord = false;
    for _ in 0..4 {
        if !chord {
            system.update(problem, &basis, &local.lambda, 1e-10);
            if system.factorize().is_err() {
                break;
            }
        }
        // (H + μD)δ = −2Bᵀg: the Riemannian gradient is twice the half gradient's coordinates.
        let delta = system.solve(|k| -2.0 * grad[k]);
        let trial = basis.retract(&local.point, &delta, problem.positions());
        // The step, the basis and the gradient of the point left go before the trial's are
        // built (the gradient's norm kept): at 10⁶ poses the polish's trial holds the process's
        // peak of memory, a median of 2015 MiB so against 2038 MiB (20 and 13 runs, 1992-2053
        // against 2015-2046).
        let now = norm(&grad);
        drop((delta, basis, grad));
        let cost = problem.cost(&trial);
        let g_trial = problem.half_gradient(&trial);
        let basis_trial = TangentBasis::new(problem, &trial);
        let grad_trial = basis_trial.coordinates(&g_trial);
        let next = norm(&grad_trial);
        if !(halves(next, now) && no_costlier(cost, local.cost)) {
            break;
        }
        chord = next <= 1e-3 * now;
        local = Local {
            lambda: problem.multipliers(&trial, &g_trial),
            point: trial,
            cost,
            gradient_norm: 2.0 * next,
            iterations: local.iterations + 1,
            ..local
        };
        (basis, grad) = (basis_trial, grad_trial);
    }
    local
}

/// The staircase from a rank-1 starting point (whose positions are replaced by the ones optimal for
/// its rotations).
pub fn solve_from(
    problem: &Problem,
    start: Point,
    options: &StaircaseOptions,
    observer: &mut dyn FnMut(&Iteration),
) -> StaircaseSolution {
    crate::linalg::parallel::alone_if_small(problem.terms.len(), || {
        solve_from_start(problem, || Some(start), options, &|_| false, observer)
            .expect("a given start is always there")
    })
}

/// As [`solve_from`], from the rank-1 point that `start` computes (the chordal initialization) on
/// this thread while a second core builds the pattern's analyses; `None` when `start` finds none.
/// `offer` is shown the rank-1 point about to be certified first ([`candidate`]); it says whether
/// it was taken.
fn solve_from_start(
    problem: &Problem,
    start: impl FnOnce() -> Option<Point>,
    options: &StaircaseOptions,
    offer: &dyn Fn(&Point) -> bool,
    observer: &mut dyn FnMut(&Iteration),
) -> Option<StaircaseSolution> {
    let n = problem.n;
    // Variable projection at rank 1 (None only if L is not numerically positive definite). The
    // ranks above keep the joint steps: projecting their escape points made the paper's toy graph
    // (Appendix 8.8) stop at a saddle of rank 5 and end at rank 6 with a relaxation λ 6.5e-8 less
    // accurate, one of its two zero eigenvalues of W(λ*) lost.
    let descend = |start: Point,
                   positions: Option<&mut OptimalPositions>,
                   rank_one: &mut Option<NewtonSystem>,
                   arriving: &dyn Fn() -> Option<NewtonSystem>,
                   observer: &mut dyn FnMut(&Iteration)| {
        crate::progress::phase("Newton");
        // The first descent gets the budget but its reserve (below), and min_descent_steps at
        // least.
        optimize_in(
            problem,
            positions,
            start,
            options,
            observer,
            1e-12,
            Some(0.75 * options.staircase_budget),
            rank_one,
            arriving,
        )
    };
    // The rank-1 Newton system's assembly and analysis, L's factor (the projection's) and the
    // certificate's analysis depend on the problem alone: with a second core they are built
    // there, in that order, while this thread computes the start and descends. The descent takes
    // the Newton system when its first step needs it (city10000: 15 ms to build; the start's
    // projection, cost, gradient and multipliers come first: on kitti_02 this thread waited up
    // to 4 ms for it). L's factor is a spare task, computed by whichever thread comes to it
    // first: the second core where the start takes long (the chordal relaxation of a landmark
    // graph), this thread where it is quick (the rotations' alone). Then the certificate's
    // analysis (city10000: 11 ms). Each is computed as it would be here, so the results are the
    // same bits on one core or two. The certificate's factor allocates its values at its first
    // factorization, after Newton's gave its memory back. The pages of the first Newton
    // factorization's values ([`Room`], below [`RELEASE_FROM_ROWS`] Newton rows: at 10⁶ poses
    // they would be held beside the start's own peak) are mapped by this thread while it waits
    // for the system (the room is allocated as soon as the analysis knows its size), and by the
    // second core before the certificate's analysis; whichever thread comes to a chunk first
    // maps it. Mapped while waiting, against after the system came (30 interleaved pairs, whole
    // process): M3500, intel and ais2klinik 0.99, kitti_00 0.986, CSAIL 0.997 (after the wait
    // this thread had spent 0.6 ms mapping M3500's 2 MB, 1.5 ms on ais2klinik's 5.7 MB).
    //
    // The tasks left for the second core's idle time (the output's constant lines,
    // [`crate::linalg::parallel::when_idle`]) start after the certificate's analysis where the
    // Newton factorizations are not split between the cores, else once the descent is done: the
    // second core is then the factorizations' (M3500: its first two factorizations found it
    // formatting lines).
    let room = Room::new();
    let descent_splits = std::sync::atomic::AtomicBool::new(false);
    let ((mut positions, local, mut rank_one), certifier) = crate::linalg::parallel::ahead(
        || {
            // The room is prepared (or forgone) as soon as the values' count is known, and
            // forgone whatever happens: this thread's wait for it must end.
            let _settled = room.settled_on_drop();
            let system = NewtonSystem::announcing(problem, 1, |rows, values| {
                if rows < RELEASE_FROM_ROWS {
                    room.prepare(values);
                } else {
                    room.forgo();
                }
            });
            descent_splits.store(
                system.splits_factorizations(),
                std::sync::atomic::Ordering::Relaxed,
            );
            system
        },
        || OptimalPositions::new(problem),
        || {
            room.map();
            let certifier = options
                .certify
                .then(|| SparseCertifier::new(&problem.matrix.upper, &problem.row_order()));
            if !descent_splits.load(std::sync::atomic::Ordering::Relaxed) {
                crate::linalg::parallel::let_idle_tasks_start();
            }
            certifier
        },
        |system, positions| {
            let start = start();
            let mut positions = start
                .as_ref()
                .and_then(|_| positions.take(|| OptimalPositions::new(problem)));
            let mut rank_one = None;
            let local = start.map(|s| {
                descend(
                    s,
                    positions.as_mut(),
                    &mut rank_one,
                    &|| {
                        system
                            .take_or(|| room.map_once_prepared())
                            .map(|mut system| {
                                system.reuse(room.take());
                                system
                            })
                    },
                    observer,
                )
            });
            // Not mapped for nothing where no system came from the second core.
            room.forgo();
            (positions, local, rank_one)
        },
    );
    crate::linalg::parallel::let_idle_tasks_start();
    let mut local = local?;
    let mut iterations = local.iterations;
    let Some(mut certifier) = certifier else {
        let (work, limited) = (local.iterations as f64 * local.step_work, local.limited);
        let mut solution = finish(local, None, None, 1, iterations, None, options);
        solution.staircase_work = work;
        solution.limit_reached = limited;
        return Some(solution);
    };
    // The work so far in multiply-adds (the staircase's budget): Newton's factorizations, one
    // rank-1 step each, and the certificate's below.
    let rank_1_step = local.step_work;
    let mut newton_work = local.iterations as f64 * rank_1_step;
    let descent_cut = local.limited;
    let eta_max = |cost: f64| options.tolerance * cost.max(1.0) / n as f64;
    // How far to search η at a rank-1 estimate: the tolerance, or 64 times the shifted
    // factorization's resolution there, whichever is larger.
    let reach = |certifier: &SparseCertifier, l: &Local| {
        eta_max(l.cost).max(64.0 * certifier.resolution(&l.lambda, &l.point.x, 1))
    };
    let mut reach_1 = reach(&certifier, &local);
    // On large graphs what the Newton steps freed goes back before the forecast's enclosure and
    // the polish, the Newton system still held ([`crate::linalg::heap::release_for`]).
    crate::linalg::heap::release_for(local.point.x.len());
    // Where even a gap as large as the ladder's first shift leaves Temple's bound short of the
    // tolerance, the residual of Newton's cost-based stopping rule is polished away before the
    // certificate's first factorization instead of after it (below).
    if certifier.expects_shortfall(
        problem,
        &local.point,
        local.cost,
        &local.lambda,
        reach_1,
        options.tolerance * local.cost.max(1.0),
    ) {
        let before = local.iterations;
        certifier.forget_point();
        crate::progress::phase("Newton polish, rank 1 (the residual is too large for the bound)");
        local = polish_in(problem, local, &mut rank_one);
        iterations += local.iterations - before;
        newton_work += (local.iterations - before) as f64 * rank_1_step;
        reach_1 = reach(&certifier, &local);
    }
    // The Newton system's numeric factor gives its memory to the certificate's, pages mapped;
    // the rest of it (assembly, analysis) goes too: at 10⁶ poses the certificate's phase peaked
    // at 2.9 GiB with it, 2.5 GiB without. A polish after the certificate, which none of the
    // public files needs, builds it again.
    if let Some(mut system) = rank_one.take() {
        certifier.reuse(system.take_values());
    }
    // Rank 1 first: the common case. A proof within 64x the certificate's resolution means the
    // estimate is optimal as far as double precision can tell; only a larger η (a clearly
    // negative eigenvalue of W̃(λ): a saddle, or a relaxation that is not exact) calls for the
    // staircase.
    // The estimate as it stands, to a caller that starts work on it beside the certificate
    // (the output file): the second core's, unless the certificate's factorization takes it.
    if offer(&local.point) {
        crate::linalg::parallel::let_idle_tasks_start();
    }
    crate::progress::phase("certificate");
    let mut first = certifier.certify_rank_one(problem, &local.point, &local.lambda, reach_1);
    if certifier.isolated
        && first
            .is_none_or(|b| local.cost - b.lower_bound > options.tolerance * local.cost.max(1.0))
    {
        // The estimate's eigenvalue is isolated but Temple's inequality fell short of the
        // tolerance: a residual that Newton's cost-based stopping rule left. The shifted
        // factorization's proof (below) waits for the polished point: its η must also cover the
        // negative eigenvalue of order ‖residual‖²/θ that the residual leaves in W̃(λ).
        let before = local.iterations;
        // The certificate's factor gives its memory to Newton's and takes it back after.
        certifier.release_factor();
        certifier.forget_point();
        crate::progress::phase("Newton polish, rank 1 (the certificate's bound fell short)");
        // The Newton system is built for this polish and goes with it.
        local = polish(problem, local);
        crate::progress::phase("certificate");
        if local.iterations > before {
            iterations += local.iterations - before;
            newton_work += (local.iterations - before) as f64 * rank_1_step;
            certifier.hold_shift();
            first = certifier
                .certify_rank_one(problem, &local.point, &local.lambda, reach_1)
                .or(first);
        }
    }
    // Where the inertia showed at most one eigenvalue of W̃(λ) below a positive shift (the
    // estimate's own), the gap above it hidden by the rounding, and no shifted factorization
    // could prove a bound above zero, the estimate is reported without a bound: there is no
    // direction of negative curvature for the staircase to escape along (at 4·10⁶ generated
    // poses the shifted LLᴴ and the count of near-zero eigenvalues took 31 s of the 152, for a
    // bound of 0).
    let hopeless = first.is_none()
        && certifier.hidden_gap().is_some()
        && !certifier.cholesky_within_reach(&local.lambda, &local.point.x, 1);
    if first.is_none() && !hopeless {
        first = certifier.certify_cholesky(problem, &local.lambda, &local.point.x, 1, reach_1);
    }
    if first.is_some() || hopeless {
        return Some(finish(
            local,
            first,
            None,
            1,
            iterations,
            Some(&mut certifier),
            options,
        ));
    }
    // The staircase: lift along negative curvature, optimize at rank p (to a loose tolerance:
    // the minimum there is degenerate when the relaxation is exact, so Newton is slow to finish),
    // round to rank 1, polish, and try to certify; repeat one rank higher while that fails.
    let mut best = local.clone();
    let mut rank = 1;
    let mut escape_factor: Option<SparseFactor<c64>> = None;
    let mut limit_reached = descent_cut;
    // The work so far (multiply-adds), and what is left of the budget as a limit on the Newton
    // steps of the next call at rank p.
    let certificate_step = certifier.factorization_work();
    let work = |newton_work: f64, certifier: &SparseCertifier| {
        newton_work + certifier.factorizations as f64 * certificate_step
    };
    let budget = |work: f64, p: usize| StaircaseOptions {
        max_iterations: options.max_iterations.min(
            ((options.staircase_budget - work) / (rank_1_step * step_work(p))).max(0.0) as usize,
        ),
        ..*options
    };
    // A quarter of the budget is kept for the bound at the last rank (its multipliers make a
    // useful bound only once the rank-p point has converged).
    let reserved = options.staircase_budget / 4.0;
    // Whether the budget, not convergence, ended a call.
    let cut = |limit: &StaircaseOptions, local: &Local| {
        !local.converged
            && local.iterations >= limit.max_iterations
            && limit.max_iterations < options.max_iterations
    };
    while rank < options.max_rank {
        if budget(reserved + work(newton_work, &certifier), rank + 1).max_iterations == 0 {
            limit_reached = true;
            break;
        }
        let Some(next) = escape(problem, &local, &mut certifier, &mut escape_factor) else {
            break;
        };
        rank += 1;
        crate::progress::phase(&format!("staircase rank {rank}"));
        let limit = budget(reserved + work(newton_work, &certifier), rank);
        local = optimize(problem, None, next, &limit, observer);
        limit_reached |= cut(&limit, &local);
        iterations += local.iterations;
        newton_work += local.iterations as f64 * rank_1_step * step_work(rank);
        let limit = budget(reserved + work(newton_work, &certifier), 1);
        let polished = optimize(
            problem,
            positions.as_mut(),
            round_to_rank_one(problem, &local.point),
            &limit,
            observer,
        );
        limit_reached |= cut(&limit, &polished);
        iterations += polished.iterations;
        newton_work += polished.iterations as f64 * rank_1_step;
        if polished.cost < best.cost {
            best = polished;
        }
        let reach_p = reach(&certifier, &best);
        crate::progress::phase("certificate");
        if let Some(bound) = certifier.certify(problem, &best.point, &best.lambda, reach_p) {
            let mut solution = finish(
                best,
                Some(bound),
                None,
                rank,
                iterations,
                Some(&mut certifier),
                options,
            );
            solution.staircase_work = work(newton_work, &certifier);
            return Some(solution);
        }
    }
    // No certificate: the relaxation's bound at the last rank (converged tightly for it), or the
    // estimate's own λ with whatever η makes W̃(λ) + ηP ⪰ 0 — whichever is higher.
    crate::progress::phase("bound");
    let mut bound = None;
    let mut relaxed_lambda = None;
    if rank > 1 {
        let tight = StaircaseOptions {
            tolerance: 0.0,
            ..budget(work(newton_work, &certifier), rank)
        };
        let relaxed = optimize_to(problem, None, local.point.clone(), &tight, observer, 1e-12);
        limit_reached |= cut(&tight, &relaxed);
        iterations += relaxed.iterations;
        newton_work += relaxed.iterations as f64 * rank_1_step * step_work(rank);
        let eta_all = relaxed.lambda.iter().fold(0.0f64, |m, &l| m.max(l.abs())) * 4.0 + 1.0;
        bound = certifier.certify(problem, &relaxed.point, &relaxed.lambda, eta_all);
        relaxed_lambda = Some(relaxed.lambda);
    }
    let eta_all = best.lambda.iter().fold(0.0f64, |m, &l| m.max(l.abs())) * 4.0 + 1.0;
    let own = certifier.certify(problem, &best.point, &best.lambda, eta_all);
    let bound = match (bound, own) {
        (Some(a), Some(b)) if a.lower_bound < b.lower_bound => Some(b),
        (a, b) => a.or(b),
    };
    // The near-zero eigenvalues are counted at the relaxation's λ when there is one: converged
    // at rank p, it is the closest to λ* (the estimate's own λ may be strictly feasible, its
    // eigenvalues lifted off zero by its distance from λ*).
    let own_lambda = best.lambda.clone();
    let mut solution = finish(
        best,
        bound,
        Some(relaxed_lambda.as_deref().unwrap_or(&own_lambda)),
        rank,
        iterations,
        Some(&mut certifier),
        options,
    );
    solution.limit_reached = limit_reached;
    solution.staircase_work = work(newton_work, &certifier);
    Some(solution)
}

/// The solution, with the near-zero eigenvalue count: the deflated proof's (one, proven) or the
/// inertia of W̃(λ) at `count_lambda` (the estimate's own λ when `None`); without a certifier
/// (an estimate left unchecked) no count and no bound.
fn finish(
    local: Local,
    bound: Option<SparseBound>,
    count_lambda: Option<&[f64]>,
    rank: usize,
    iterations: usize,
    mut certifier: Option<&mut SparseCertifier>,
    options: &StaircaseOptions,
) -> StaircaseSolution {
    let lambda = count_lambda.unwrap_or(&local.lambda);
    let lower_bound = bound.map_or(0.0, |b| b.lower_bound.max(0.0));
    let certified =
        bound.is_some() && local.cost - lower_bound <= options.tolerance * local.cost.max(1.0);
    let hidden_gap = certifier
        .as_deref()
        .and_then(SparseCertifier::hidden_gap)
        .filter(|_| !certified);
    let near_zero = certifier
        .as_deref_mut()
        .filter(|_| hidden_gap.is_none())
        .and_then(|c| c.near_zero(bound.as_ref(), lambda));
    StaircaseSolution {
        point: local.point,
        cost: local.cost,
        lambda: local.lambda,
        bound,
        lower_bound,
        certified,
        rank,
        iterations,
        gradient_norm: local.gradient_norm,
        factorizations: certifier.map_or(0, |c| c.factorizations),
        near_zero,
        hidden_gap,
        staircase_work: 0.0,
        limit_reached: false,
    }
}

/// A point of rank p + 1 with lower cost: the current point with a new column ε·v, v a direction
/// of negative curvature of W̃(λ) (v*W̃(λ)v < 0: a pivot of its LDLᴴ that is negative), rows of
/// the rotations renormalized. To second order f changes by ε² v*W̃(λ)v.
fn escape(
    problem: &Problem,
    local: &Local,
    certifier: &mut SparseCertifier,
    factor: &mut Option<SparseFactor<c64>>,
) -> Option<Point> {
    let positions = problem.positions();
    let rows = problem.rows();
    let a = certifier.penalized_matrix(&local.lambda);
    let f = factor.get_or_insert_with(|| SparseFactor::analyze_simplicial(a.symbolic()));
    f.ldlt(a).ok()?;
    let pivots = f.ldlt_pivots();
    let mut order: Vec<usize> = (0..pivots.len()).filter(|&k| pivots[k] < 0.0).collect();
    order.sort_by(|&i, &j| pivots[i].total_cmp(&pivots[j]));
    let p = local.point.p;
    for &k in order.iter().take(8) {
        let Some(mut v) = f.pivot_direction(k) else {
            break;
        };
        let curvature = quadratic(a, &v);
        if curvature >= 0.0 || curvature.is_nan() {
            continue;
        }
        let big = v[positions..]
            .iter()
            .chain(&v[..positions])
            .fold(0.0f64, |m, z| m.max(z.norm()));
        if !(big > 0.0 && big.is_finite()) {
            continue;
        }
        for z in &mut v {
            *z /= big;
        }
        let mut eps = 1.0;
        for _ in 0..60 {
            let mut x = Vec::with_capacity(rows * (p + 1));
            for (k, vk) in v.iter().enumerate().take(rows) {
                let row = local.point.row(k);
                let mut new: Vec<c64> = row.iter().copied().chain([vk * eps]).collect();
                if k >= positions {
                    let norm = new.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
                    for z in &mut new {
                        *z /= norm;
                    }
                }
                x.extend(new);
            }
            let point = Point { p: p + 1, x };
            if problem.cost(&point) < local.cost * (1.0 - 1e-10) {
                return Some(point);
            }
            eps *= 0.5;
        }
    }
    None
}

/// v* A v for A given by its upper triangle.
fn quadratic(a: faer::sparse::SparseColMatRef<'_, usize, c64>, v: &[c64]) -> f64 {
    let mut s = 0.0;
    for col in 0..a.ncols() {
        let rows = a.symbolic().row_idx_of_col_raw(col);
        for (&row, w) in rows.iter().zip(a.val_of_col(col)) {
            let t = (v[row].conj() * w * v[col]).re;
            s += if row == col { t } else { 2.0 * t };
        }
    }
    s
}

/// Rank-1 rounding of a rank-p point X: x = X u with u the top eigenvector of Y*Y (Y the rotation
/// rows), rotations normalized (the SDP rank-1 rounding of Sec. 6 applied to the factor).
pub fn round_to_rank_one(problem: &Problem, x: &Point) -> Point {
    let p = x.p;
    let n = problem.n;
    let mut c = faer::Mat::<c64>::zeros(p, p);
    for a in 0..n {
        let y = x.row(problem.rotation_row(a));
        for s in 0..p {
            for t in 0..p {
                c[(s, t)] += y[s].conj() * y[t];
            }
        }
    }
    let (_, vectors) = crate::linalg::eigen::hermitian_eigen(&c);
    let u: Vec<c64> = (0..p).map(|s| vectors[(s, p - 1)]).collect();
    let mut out = Vec::with_capacity(problem.rows());
    for k in 0..problem.rows() {
        let z: c64 = x.row(k).iter().zip(&u).map(|(a, b)| a * b).sum();
        out.push(if k >= problem.positions() {
            let m = z.norm();
            if m > 0.0 { z / m } else { c64::new(1.0, 0.0) }
        } else {
            z
        });
    }
    Point { p: 1, x: out }
}
