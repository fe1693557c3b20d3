//! Warm starts (`pgo::solve_from`) held to the cold start (`pgo::solve`, from the chordal
//! initialization) on the same graphs: from the certified optimum (or a rigid motion of it, which
//! f cannot tell from it) Newton has nothing left to do; from a poor estimate it still reaches
//! the optimum the cold start certifies; a malformed estimate is an error. And GNC with warm
//! starts (`RobustOptions::warm_start`) certifies the inlier set it ends with.

mod common;

use pgo::linalg::rng::Rng;
use pgo::robust::gnc::without_edges;
use pgo::robust::outliers::{OutlierConfig, OutlierModel, add_outliers};
use pgo::robust::{RobustOptions, robust_solve};
use pgo::solve::Method;
use pgo::{Pose2, PoseGraph, Solution, SolveOptions, solve, solve_from};
use std::path::Path;

fn mit() -> PoseGraph {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/MIT.g2o");
    pgo::io::read_path(path.to_str().unwrap(), &Default::default())
        .unwrap()
        .0
}

fn staircase() -> SolveOptions {
    SolveOptions {
        method: Method::Staircase,
        ..Default::default()
    }
}

fn newton_steps(s: &Solution) -> usize {
    s.components.iter().map(|c| c.iterations.unwrap()).sum()
}

/// The largest difference of two estimates in position (m) and heading (rad, modulo 2π).
fn distance(a: &[Pose2], b: &[Pose2]) -> (f64, f64) {
    a.iter().zip(b).fold((0.0f64, 0.0f64), |(dp, dt), (p, q)| {
        let t = (p.theta - q.theta).sin().abs();
        (dp.max((p.x - q.x).hypot(p.y - q.y)), dt.max(t))
    })
}

/// A rigid motion of every pose: rotation by `angle` about the origin, then (dx, dy).
fn moved(poses: &[Pose2], angle: f64, dx: f64, dy: f64) -> Vec<Pose2> {
    let (s, c) = angle.sin_cos();
    poses
        .iter()
        .map(|p| {
            Pose2::new(
                c * p.x - s * p.y + dx,
                s * p.x + c * p.y + dy,
                p.theta + angle,
            )
        })
        .collect()
}

#[test]
fn from_the_optimum_newton_has_nothing_left_to_do() {
    let g = mit();
    let cold = solve(&g, &staircase()).unwrap();
    assert!(cold.certified, "{:?}", cold.not_certified_because);
    let cold_steps = newton_steps(&cold);
    // From the optimum itself and from a rigid motion of it (the same point of f's quotient by
    // the gauge): one or two steps, to the same optimum.
    for start in [
        cold.estimate.clone(),
        moved(&cold.estimate, 2.1, -40.0, 7.5),
    ] {
        let warm = solve_from(&g, &start, &staircase()).unwrap();
        assert!(warm.certified, "{:?}", warm.not_certified_because);
        let steps = newton_steps(&warm);
        assert!(
            steps <= 2 && steps < cold_steps,
            "warm {steps} steps, cold {cold_steps}"
        );
        assert!(
            (warm.cost - cold.cost).abs() <= 1e-12 * cold.cost,
            "warm {} vs cold {}",
            warm.cost,
            cold.cost
        );
        // Each bound proves the other's estimate no better than it.
        assert!(warm.cost >= cold.lower_bound && cold.cost >= warm.lower_bound);
        // Returned in the input's gauge, as the cold start's.
        let (dp, dt) = distance(&warm.estimate, &cold.estimate);
        assert!(dp < 1e-6 && dt < 1e-8, "{dp} m, {dt} rad");
    }
}

#[test]
fn from_a_poor_estimate_the_same_optimum_is_certified() {
    let g = mit();
    let cold = solve(&g, &staircase()).unwrap();
    assert!(cold.certified);
    let mut rng = Rng::new(5);
    // Headings drawn uniformly (nothing of the graph's), positions scattered over 100 m; and the
    // file's own vertices (composed odometry).
    let random: Vec<Pose2> = (0..g.num_poses())
        .map(|_| {
            Pose2::new(
                100.0 * rng.uniform(),
                100.0 * rng.uniform(),
                std::f64::consts::TAU * rng.uniform(),
            )
        })
        .collect();
    for start in [random, g.poses.clone()] {
        let warm = solve_from(&g, &start, &staircase()).unwrap();
        assert!(warm.certified, "{:?}", warm.not_certified_because);
        assert!(
            (warm.cost - cold.cost).abs() <= 1e-9 * cold.cost,
            "warm {} vs cold {}",
            warm.cost,
            cold.cost
        );
        assert!(warm.cost >= cold.lower_bound && cold.cost >= warm.lower_bound);
        let (dp, dt) = distance(&warm.estimate, &cold.estimate);
        // Both certified within 1e-6 relative; MIT's estimate spans 250 m.
        assert!(dp < 1e-4 && dt < 1e-6, "{dp} m, {dt} rad");
    }
}

#[test]
fn components_take_their_own_poses_of_the_start() {
    // Two copies of MIT side by side (ids shifted): two components, each warm started from its
    // own part of the start (the first copy's optimum, the second's poses scrambled).
    let one = mit();
    let n = one.num_poses();
    let shift = one.ids[n - 1] + 1;
    let mut two = one.clone();
    two.ids.extend(one.ids.iter().map(|id| id + shift));
    two.poses.extend(one.poses.iter().copied());
    two.edges.extend(one.edges.iter().map(|e| pgo::Edge {
        i: e.i + n,
        j: e.j + n,
        ..*e
    }));
    let cold = solve(&one, &staircase()).unwrap();
    let mut start = cold.estimate.clone();
    start.extend(moved(&one.poses, -1.0, 3.0, 3.0));
    let warm = solve_from(&two, &start, &staircase()).unwrap();
    assert_eq!(warm.components.len(), 2);
    assert!(warm.certified);
    assert!(warm.components[0].iterations.unwrap() <= 2);
    for c in &warm.components {
        assert!((c.cost - cold.cost).abs() <= 1e-9 * cold.cost, "{}", c.cost);
    }
}

#[test]
fn malformed_starts_are_errors() {
    let g = mit();
    let n = g.num_poses();
    let good = g.poses.clone();
    let mut bad: Vec<(Vec<Pose2>, &str)> = vec![
        (good[..n - 1].to_vec(), "poses, the graph"),
        ([good.clone(), vec![good[0]]].concat(), "poses, the graph"),
        (Vec::new(), "poses, the graph"),
    ];
    for (k, v) in [
        (0, f64::NAN),
        (n / 2, f64::INFINITY),
        (n - 1, f64::NEG_INFINITY),
    ] {
        let mut p = good.clone();
        p[k].theta = v;
        bad.push((p.clone(), "not finite"));
        p[k] = Pose2::new(v, 0.0, 0.0);
        bad.push((p, "not finite"));
    }
    for (start, says) in bad {
        match solve_from(&g, &start, &staircase()) {
            Err(pgo::Error::Invalid(m)) => assert!(m.contains(says), "{m}"),
            other => panic!("{} poses: {:?}", start.len(), other.map(|s| s.cost)),
        }
    }
}

/// MIT with 20 random false loop closures (as many as its true ones), GNC from chordal starts
/// (the default) and with warm starts (`RobustOptions::warm_start`): whatever inlier set each
/// settles on, the estimate returned and a plain cold solve of the graph without the rejected
/// edges bound each other, and where the plain solve certifies its optimum, so does GNC's.
#[test]
fn gnc_inlier_set_bounds_agree_warm_or_cold() {
    let mut g = mit();
    add_outliers(
        &mut g,
        &OutlierConfig {
            count: 20,
            model: OutlierModel::Random,
            group: 1,
            noise: None,
            seed: 3,
        },
    )
    .unwrap();
    for warm_start in [false, true] {
        let options = RobustOptions {
            warm_start,
            ..Default::default()
        };
        let r = robust_solve(&g, &options).unwrap();
        let plain = solve(&without_edges(&g, &r.rejected), &Default::default()).unwrap();
        // Both bound the same f* of the same inlier set: neither estimate below the other's bound.
        assert!(r.solution.cost >= plain.lower_bound * (1.0 - 1e-12));
        assert!(plain.cost >= r.solution.lower_bound * (1.0 - 1e-12));
        if plain.certified {
            assert!(r.solution.certified, "warm start {warm_start}");
            assert!(
                (r.solution.cost - plain.cost).abs() <= 1e-9 * plain.cost,
                "warm start {warm_start}: {} vs {}",
                r.solution.cost,
                plain.cost
            );
        }
    }
}
