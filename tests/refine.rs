//! Levenberg-Marquardt under the files' information matrices (`pgo::refine`) on public data
//! sets, against the chi2 that g2o-style solvers reach there: M3500 137.912951, intel 45.005.

mod common;

use common::datasets_dir;
use pgo::io::{self, ReadOptions};
use pgo::refine::{RefineOptions, Refinement, Stop, chi2, refine};
use pgo::{Pose2, PoseGraph};
use std::time::Instant;

fn read(name: &str) -> PoseGraph {
    let path = datasets_dir().join(name);
    io::read_path(path.to_str().unwrap(), &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .0
}

/// Refines `graph` from `initial`, checks what holds whatever the start, and reports.
fn run(name: &str, graph: &PoseGraph, start: &str, initial: &[Pose2]) -> Refinement {
    let t = Instant::now();
    let r = refine(graph, initial, &RefineOptions::default()).unwrap();
    eprintln!(
        "{name} from {start}: chi2 {} -> {:.9}, {} iterations, {} factorizations, {:?}, {:.3} s",
        r.initial_chi2,
        r.chi2,
        r.iterations,
        r.factorizations,
        r.stop,
        t.elapsed().as_secs_f64()
    );
    assert!(
        r.converged && r.stop == Stop::Converged,
        "{name} from {start}"
    );
    assert!(r.chi2 < r.initial_chi2);
    // The chi2 reported is the chi2 of the poses returned, and the gauge pose did not move.
    assert!((chi2(graph, &r.poses) - r.chi2).abs() <= 1e-12 * r.chi2);
    assert_eq!(r.held, vec![0]);
    assert_eq!(r.poses[0], initial[0]);
    r
}

/// From the file's own vertices and from poses composed along a spanning tree (no vertex
/// information): both reach `expected` to `tolerance` (relative).
fn reaches(name: &str, expected: f64, tolerance: f64) {
    let g = read(name);
    let mut tree = g.clone();
    tree.initialize_spanning_tree();
    let from_file = run(name, &g, "file vertices", &g.poses);
    let from_tree = run(name, &g, "spanning tree", &tree.poses);
    for r in [&from_file, &from_tree] {
        assert!(
            (r.chi2 - expected).abs() <= tolerance * expected,
            "{name}: chi2 {} vs {expected}",
            r.chi2
        );
    }
    // Same minimum from both starts, to the stopping tolerance.
    assert!((from_file.chi2 - from_tree.chi2).abs() <= 1e-10 * expected);
}

#[test]
fn m3500_reaches_g2o_chi2() {
    reaches("M3500.g2o", 137.912951, 1e-6);
}

#[test]
fn intel_reaches_g2o_chi2() {
    // The reference value has five significant digits.
    reaches("intel.g2o", 45.005, 1e-5);
}
