//! Hard instances for the relaxation (where it is not exact) and an independent reference
//! minimum, shared by `tests/hard.rs` (a small seeded subset) and `examples/hard_share.rs` (the
//! full set).
//!
//! Kinds:
//! - `tiny`: 3-6 poses, densely looped, rotation noise 0.5-2 rad, duplicates as in `conflict`: the reference adds an exhaustive grid search
//!   over the rotations (positions optimal in closed form for given rotations, eq. (24)).
//! - `noise`: 7-100 poses, rotation noise 0.1-2 rad.
//! - `weights`: 3-100 poses, information from 1e-4 to 1e4 (translation and rotation drawn
//!   independently, log-uniform).
//! - `conflict`: 3-100 poses, rotation noise 0.1-1 rad, a third of the edges duplicated with a rotation 2-3 rad away.
//! - `large`: 100-160 poses, rotation noise 0.1-2 rad, some duplicates and spread weights.
//!
//! The reference minimum is computed without any relaxation: Riemannian Newton at rank 1 (the
//! local solver, variable projection) from many uniformly random rotations, the best one
//! polished by the dense Gauss-Newton of `pgo::refine::gauss_newton` under the full objective
//! f (eq. (8)), plus, for n ≤ 6, a grid over all rotations whose best cells are polished the same
//! way. It is an upper bound on f*; a method that goes below it improves the best known minimum.
#![allow(dead_code)]

use pgo::graph::{Edge, Pose2, PoseGraph, SymMat3};
use pgo::linalg::rng::Rng;
use pgo::problem::matrix::{PoseGraphMatrix, cost};
use pgo::problem::rank_p::{Point, Problem};
use pgo::problem::weights::{EdgeWeight, Weights, edge_weights};
use pgo::staircase::init::OptimalPositions;
use pgo::staircase::{StaircaseOptions, optimize};
use std::f64::consts::{PI, TAU};

pub const KINDS: [&str; 5] = ["tiny", "noise", "weights", "conflict", "large"];

/// The weights every comparison uses (the tools' default).
pub const WEIGHTS: Weights = Weights::Isotropic;

fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(TAU);
    if w > PI { w - TAU } else { w }
}

fn between(a: Pose2, b: Pose2) -> Pose2 {
    Pose2::from_isometry(&(a.to_isometry().inverse() * b.to_isometry()))
}

fn compose(a: Pose2, z: Pose2) -> Pose2 {
    Pose2::from_isometry(&(a.to_isometry() * z.to_isometry()))
}

fn info(t: f64, r: f64) -> SymMat3 {
    // Isotropic weights: τ = 2 / tr(Ω_tt⁻¹) = t, κ = 2 Ω_θθ = r.
    SymMat3([t, 0.0, 0.0, t, 0.0, r / 2.0])
}

/// The instance `seed` of `kind`, deterministic.
pub fn instance(kind: &str, seed: u64) -> PoseGraph {
    let k = KINDS.iter().position(|k| *k == kind).expect("a kind") as u64;
    let mut rng = Rng::new(0x4a5d_0000 + 1000 * k + seed);
    let int =
        |rng: &mut Rng, lo: usize, hi: usize| lo + (rng.uniform() * (hi - lo + 1) as f64) as usize;
    let (n, sigma_r, spread, duplicates) = match kind {
        "tiny" => (int(&mut rng, 3, 6), 0.5 + 1.5 * rng.uniform(), false, 0.3),
        "noise" => (int(&mut rng, 7, 100), 0.1 + 1.9 * rng.uniform(), false, 0.0),
        "weights" => (int(&mut rng, 3, 100), 0.1 + 0.9 * rng.uniform(), true, 0.0),
        "conflict" => (
            int(&mut rng, 3, 100),
            0.1 + 0.9 * rng.uniform(),
            false,
            0.35,
        ),
        _ => (
            int(&mut rng, 100, 160),
            0.1 + 1.9 * rng.uniform(),
            rng.uniform() < 0.5,
            0.05,
        ),
    };
    let sigma_t = 0.1;
    let mut truth = vec![Pose2::new(0.0, 0.0, 0.0)];
    for _ in 1..n {
        let step = Pose2::new(1.0, 0.0, rng.uniform() * 2.0 - 1.0);
        truth.push(compose(*truth.last().unwrap(), step));
    }
    let mut pairs: Vec<(usize, usize)> = (1..n).map(|j| (j - 1, j)).collect();
    // Small graphs densely looped (the paper's toy graph is), larger ones about 0.3 per pose.
    let loops = if n <= 6 {
        2 * n
    } else {
        (n as f64 * 0.3).ceil() as usize + 1
    };
    for _ in 0..loops {
        let i = int(&mut rng, 0, n - 1);
        let j = int(&mut rng, 0, n - 1);
        if i.abs_diff(j) > 1 {
            pairs.push((i.min(j), i.max(j)));
        }
    }
    let mut edges = Vec::new();
    for (i, j) in pairs {
        let z = between(truth[i], truth[j]);
        let measurement = Pose2::new(
            z.x + sigma_t * rng.normal(),
            z.y + sigma_t * rng.normal(),
            wrap(z.theta + sigma_r * rng.normal()),
        );
        let noise = if spread {
            info(
                10f64.powf(8.0 * rng.uniform() - 4.0),
                10f64.powf(8.0 * rng.uniform() - 4.0),
            )
        } else {
            info(1.0, 1.0)
        };
        edges.push(Edge {
            i,
            j,
            measurement,
            noise,
        });
        if rng.uniform() < duplicates {
            let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            let off = sign * (2.0 + rng.uniform());
            let m = Pose2::new(
                z.x + sigma_t * rng.normal(),
                z.y + sigma_t * rng.normal(),
                wrap(measurement.theta + off),
            );
            edges.push(Edge {
                i,
                j,
                measurement: m,
                noise,
            });
        }
    }
    // The initial estimate of a file: the odometry composed.
    let mut poses = vec![Pose2::new(0.0, 0.0, 0.0)];
    for e in edges.iter().filter(|e| e.j == e.i + 1) {
        if e.j == poses.len() {
            poses.push(compose(poses[e.i], e.measurement));
        }
    }
    PoseGraph::with_edges(poses, edges)
}

pub fn weights(g: &PoseGraph) -> Vec<EdgeWeight> {
    edge_weights(g, WEIGHTS).unwrap()
}

/// Rank-1 Riemannian Newton from rotations `r` (positions optimal for them): poses and f.
fn local_from(
    g: &PoseGraph,
    w: &[EdgeWeight],
    problem: &Problem,
    r: Vec<f64>,
) -> (Vec<Pose2>, f64) {
    let n = g.num_poses();
    let x = vec![faer::c64::new(0.0, 0.0); n - 1]
        .into_iter()
        .chain(r.iter().map(|t| faer::c64::new(t.cos(), t.sin())))
        .collect();
    let mut positions = OptimalPositions::new(problem);
    let local = optimize(
        problem,
        positions.as_mut(),
        Point { p: 1, x },
        &StaircaseOptions::default(),
        &mut |_| {},
    );
    let poses = problem.matrix.poses(&local.point.x);
    let f = cost(g, w, &poses);
    (poses, f)
}

/// Polishes with dense Gauss-Newton under f; the better of before and after.
fn gauss_newton(g: &PoseGraph, w: &[EdgeWeight], poses: Vec<Pose2>, f: f64) -> f64 {
    let r = pgo::refine::gauss_newton::refine(g, w, &poses, 100);
    r.cost.min(f)
}

/// The reference minimum of f: `starts` random starts (and the grid for n ≤ 6).
pub fn reference(g: &PoseGraph, starts: usize, seed: u64) -> f64 {
    let w = weights(g);
    let n = g.num_poses();
    let problem = Problem::new(g, &w);
    let mut rng = Rng::new(0x5eed_0000 ^ seed);
    let mut candidates: Vec<(Vec<Pose2>, f64)> = Vec::new();
    for _ in 0..starts {
        let r: Vec<f64> = (0..n)
            .map(|k| if k == 0 { 0.0 } else { rng.angle() })
            .collect();
        candidates.push(local_from(g, &w, &problem, r));
    }
    if n <= 6 {
        for r in grid_best(g, &w, 8) {
            candidates.push(local_from(g, &w, &problem, r));
        }
    }
    candidates.sort_by(|a, b| a.1.total_cmp(&b.1));
    candidates
        .into_iter()
        .take(3)
        .map(|(p, f)| gauss_newton(g, &w, p, f))
        .fold(f64::INFINITY, f64::min)
}

/// Exhaustive search on a grid of the rotations (pose 0 at 0, the others at multiples of 2π/G):
/// the reduced cost r*Mr (eq. (38), positions optimal) at every grid point; the `keep` best.
fn grid_best(g: &PoseGraph, w: &[EdgeWeight], keep: usize) -> Vec<Vec<f64>> {
    let n = g.num_poses();
    let m = PoseGraphMatrix::new(g, w).rotation_matrix().unwrap();
    let steps: usize = if n <= 5 { 24 } else { 16 };
    let total = steps.pow(n as u32 - 1);
    let unit: Vec<faer::c64> = (0..steps)
        .map(|s| {
            let t = TAU * s as f64 / steps as f64;
            faer::c64::new(t.cos(), t.sin())
        })
        .collect();
    let mut best: Vec<(f64, usize)> = Vec::new();
    let mut r = vec![faer::c64::new(1.0, 0.0); n];
    for index in 0..total {
        let mut rest = index;
        for v in r.iter_mut().skip(1) {
            *v = unit[rest % steps];
            rest /= steps;
        }
        let mut f = 0.0;
        for a in 0..n {
            let mut s = faer::c64::new(0.0, 0.0);
            for b in 0..n {
                s += m[(a, b)] * r[b];
            }
            f += (r[a].conj() * s).re;
        }
        if best.len() < keep || f < best[keep - 1].0 {
            best.push((f, index));
            best.sort_by(|a, b| a.0.total_cmp(&b.0));
            best.truncate(keep);
        }
    }
    best.into_iter()
        .map(|(_, index)| {
            let mut rest = index;
            (0..n)
                .map(|k| {
                    if k == 0 {
                        return 0.0;
                    }
                    let t = TAU * (rest % steps) as f64 / steps as f64;
                    rest /= steps;
                    t
                })
                .collect()
        })
        .collect()
}

/// Whether `cost` is at the minimum `best` (within 1e-6 relative; a floor for f* = 0).
pub fn at_minimum(cost: f64, best: f64, g: &PoseGraph) -> bool {
    let total: f64 = weights(g).iter().map(|w| w.tau + w.kappa).sum();
    cost <= best + 1e-6 * best.abs() + 1e-12 * total
}
