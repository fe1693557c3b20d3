//! The floor of a certified solve (issue 17): the time to read a file and to factor the
//! penalized matrix W̃(λ) = W̃ − blkdiag(0, diag λ) (eq. (31)) once, at the λ of the solution.
//! No certified solver can do less: it must read the measurements and prove W̃(λ) ⪰ 0 by at
//! least one factorization (or an equivalent eigenvalue computation) of a matrix of this size
//! and pattern. `scripts/bench-solve` divides pgo's whole-process time by this floor.
//!
//! Prints one JSON line per file, medians of 9 runs of each phase:
//! `read_s` (parse the file), `order_s` (AMD on the pose graph), `analyze_s` (the symbolic
//! factorization in that order), `factor_s` (one numeric LDLᴴ of W̃(λ)), `floor_s` (their sum).
//!
//! ```text
//! cargo run --release --example floor -- FILE...
//! ```

use pgo::io::{self, ReadOptions};
use pgo::linalg::factor::{
    Assembly, Layout, PLANAR_BLOCK_WORK, SparseFactor, group_ordering, pose_rank,
};
use pgo::problem::weights::{Weights, edge_weights};
use pgo::staircase::{StaircaseOptions, solve_anchored};
use std::time::Instant;

/// The median wall time of 9 runs of `f`.
fn median(f: &mut dyn FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..9)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[4]
}

fn main() {
    for path in std::env::args().skip(1) {
        let options = ReadOptions::default();
        let mut graph = match io::read_path(&path, &options) {
            Ok((g, _)) => g,
            Err(e) => {
                eprintln!("{e}");
                continue;
            }
        };
        let read_s = median(&mut || {
            std::hint::black_box(io::read_path(&path, &options).ok());
        });
        if !graph.vertices_declared {
            graph.initialize_spanning_tree();
        }
        let weights = match edge_weights(&graph, Weights::Isotropic) {
            Ok(w) => w,
            Err(e) => {
                eprintln!("{path}: {e}");
                continue;
            }
        };
        // λ at the solution (untimed): the matrix the certificate factors.
        let Some((solution, anchored)) =
            solve_anchored(&graph, &weights, &StaircaseOptions::default(), &mut |_| {})
        else {
            eprintln!("{path}: not connected");
            continue;
        };
        let problem = &anchored.problem;
        let lambda = &solution.lambda;
        let n = problem.n + problem.m;
        let order_s = median(&mut || {
            std::hint::black_box(pose_rank(
                n,
                graph.edges.iter().map(|e| (e.i, e.j)).chain(
                    graph
                        .landmarks
                        .observations
                        .iter()
                        .map(|o| (o.pose, problem.n + o.landmark)),
                ),
                PLANAR_BLOCK_WORK,
            ));
        });
        let order = group_ordering(&problem.pose_rank, &problem.row_poses());
        let pattern = pgo::problem::matrix::entry_pattern(&problem.matrix.upper);
        let dim = problem.rows();
        let mut assembly = Assembly::new(dim, &pattern);
        let analyze_s = median(&mut || {
            std::hint::black_box(SparseFactor::<faer::c64>::analyze_ordered(
                assembly.matrix.symbolic(),
                &order,
                Layout::Auto,
            ));
        });
        let rot0 = dim - lambda.len();
        let values: Vec<faer::c64> = problem
            .matrix
            .upper_entries()
            .map(|(r, c, v)| {
                if r == c && r >= rot0 {
                    faer::c64::new(v.re - lambda[r - rot0], 0.0)
                } else {
                    v
                }
            })
            .collect();
        assembly.fill(&values);
        let mut factor =
            SparseFactor::analyze_ordered(assembly.matrix.symbolic(), &order, Layout::Auto);
        let mut ok = true;
        let factor_s = median(&mut || {
            ok &= factor.ldlt(assembly.matrix.as_ref()).is_ok();
        });
        println!(
            "{{\"file\": {:?}, \"poses\": {}, \"rows\": {dim}, \"read_s\": {read_s:.6}, \"order_s\": {order_s:.6}, \
             \"analyze_s\": {analyze_s:.6}, \"factor_s\": {factor_s:.6}, \"floor_s\": {:.6}, \"factored\": {ok}}}",
            path,
            graph.num_poses(),
            read_s + order_s + analyze_s + factor_s
        );
    }
}
