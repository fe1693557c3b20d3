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
        let _m = pgo::matrix::PoseGraphMatrix::new(&g, &weights);
        let t_matrix = t.elapsed().as_secs_f64();
        let _r = pgo::factor::pose_rank(g.num_poses(), g.edges.iter().map(|e| (e.i, e.j)));
        println!(
            "matrix {t_matrix:.4} rank {:.4}",
            t.elapsed().as_secs_f64() - t_matrix
        );
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
            Some((s, _)) => println!(
                "{path}: cost {:.10} bound {:?} certified {} rank {} iterations {} total {:.4} s",
                s.cost,
                s.bound.map(|b| s.cost - b.lower_bound),
                s.certified,
                s.rank,
                s.iterations,
                t.elapsed().as_secs_f64()
            ),
            None => eprintln!("{path}: not connected"),
        }
    }
}
