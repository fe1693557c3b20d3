//! Iteration trace of the scalable solver (`pgo::staircase`) and the time of its phases, for
//! tuning the Newton loop: one line per step (rank, iteration, cost, gradient norm, damping).
//!
//! ```text
//! cargo run --release --example staircase_trace -- FILE...
//! ```

use pgo::io::{self, ReadOptions};
use pgo::problem::weights::{Weights, edge_weights};
use pgo::staircase::{StaircaseOptions, solve_graph};
use std::time::Instant;

fn main() {
    for path in std::env::args().skip(1) {
        let mut g = match io::read_path(&path, &ReadOptions::default()) {
            Ok((g, _)) => g,
            Err(e) => {
                eprintln!("{e}");
                continue;
            }
        };
        if !g.vertices_declared {
            g.initialize_spanning_tree();
        }
        let weights = match edge_weights(&g, Weights::Isotropic) {
            Ok(w) => w,
            Err(e) => {
                eprintln!("{path}: {e}");
                continue;
            }
        };
        // Setup phases, medians of 15 runs each.
        let median = |f: &mut dyn FnMut()| {
            let mut times: Vec<f64> = (0..15)
                .map(|_| {
                    let t = Instant::now();
                    f();
                    t.elapsed().as_secs_f64()
                })
                .collect();
            times.sort_by(f64::total_cmp);
            times[7]
        };
        let anchored = pgo::staircase::Anchored::centered(&g, &weights, &g.poses);
        let problem = &anchored.problem;
        println!(
            "setup medians: matrix {:.4} problem {:.4} chordal {:.4} positions {:.4} certifier {:.4} newton system {:.4}",
            median(&mut || {
                std::hint::black_box(pgo::problem::matrix::PoseGraphMatrix::new(&g, &weights));
            }),
            median(&mut || {
                std::hint::black_box(pgo::staircase::Anchored::centered(&g, &weights, &g.poses));
            }),
            median(&mut || {
                std::hint::black_box(pgo::staircase::init::chordal_rotations(problem));
            }),
            median(&mut || {
                std::hint::black_box(pgo::staircase::init::OptimalPositions::new(problem));
            }),
            median(&mut || {
                std::hint::black_box(pgo::certify::SparseCertifier::new(
                    &problem.matrix.upper,
                    &problem.row_order(),
                ));
            }),
            median(&mut || {
                std::hint::black_box(pgo::staircase::manifold::NewtonSystem::new(problem, 1));
            }),
        );
        let t = Instant::now();
        let mut trace = |it: &pgo::staircase::Iteration| {
            println!(
                "{}\t{}\t{:.12e}\t{:.3e}\t{:.1e}\t{:.4}",
                it.rank,
                it.iteration,
                it.cost,
                it.gradient_norm,
                it.damping,
                t.elapsed().as_secs_f64()
            )
        };
        match solve_graph(&g, &weights, &StaircaseOptions::default(), &mut trace) {
            Some((s, poses)) => {
                // The certificate alone, as pgo-certify runs it on the solution: median of 9.
                let mut times: Vec<f64> = (0..9)
                    .map(|_| {
                        let t = Instant::now();
                        let c = pgo::staircase::certify_estimate(
                            &g,
                            &weights,
                            &poses,
                            1e-6 * s.cost / g.num_poses() as f64,
                        );
                        std::hint::black_box(c.bound);
                        t.elapsed().as_secs_f64()
                    })
                    .collect();
                times.sort_by(f64::total_cmp);
                println!("certify_estimate median {:.4} s", times[4]);
                println!(
                    "{path}: cost {:.10} bound {:?} certified {} rank {} iterations {} certificate factorizations {} total {:.4} s",
                    s.cost,
                    s.bound.map(|b| s.cost - b.lower_bound),
                    s.certified,
                    s.rank,
                    s.iterations,
                    s.factorizations,
                    t.elapsed().as_secs_f64()
                )
            }
            None => eprintln!("{path}: not connected"),
        }
    }
}
