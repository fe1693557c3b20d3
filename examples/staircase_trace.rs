//! Iteration trace of the scalable solver (`pgo::staircase`) and the time of its phases, for
//! tuning the Newton loop: one line per step (rank, iteration, cost, gradient norm, damping).
//!
//! ```text
//! cargo run --release --example staircase_trace -- FILE...
//! ```

use pgo::io::{self, ReadOptions};
use pgo::staircase::{StaircaseOptions, solve_graph};
use pgo::weights::{Weights, edge_weights};
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
        let t = Instant::now();
        let anchored = pgo::staircase::Anchored::centered(&g, &weights, &g.poses);
        let t_problem = t.elapsed().as_secs_f64();
        let r = pgo::init::chordal_rotations(&anchored.problem).expect("connected");
        let t_chordal = t.elapsed().as_secs_f64();
        let _ = pgo::init::with_optimal_positions(&anchored.problem, &r).expect("connected");
        let t_positions = t.elapsed().as_secs_f64();
        println!(
            "problem {t_problem:.4} chordal {:.4} positions {:.4}",
            t_chordal - t_problem,
            t_positions - t_chordal
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
