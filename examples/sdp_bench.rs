//! Benchmark of the interior-point solver for the reduced dual SDP (31) (`pgo::dual::ipm`).
//!
//! Random pose graphs after the paper's Section 6 model (47): n poses uniform in a 10 m x 10 m
//! square with uniform headings, a spanning path (i, i+1) plus loop closures (i, j), j > i + 1,
//! with probability p_c, and noisy relative measurements Δ_ij = R_iᵀ(p_j − p_i) + N(0, σ_Δ²),
//! θ_ij = θ_j − θ_i + N(0, σ_R²); unit weights. Positions are eliminated densely,
//! M = Q − Sᴴ L⁻¹ S, and the SDP is solved on M.
//!
//! Prints: a table (n, iterations, median wall time of 3 solves, relative duality gap), the time
//! of 2,000 SDPs at n = 10 (σ = 0.1, 0.5, 1 as in Fig. 5) and of an n-sweep 10..=50.
//!
//! ```text
//! cargo run --release --example sdp_bench [-- --quick]
//! ```

use faer::prelude::*;
use faer::{Mat, Side, c64};
use pgo::dual::ipm::{self, IpmOptions};
use std::time::{Duration, Instant};

/// SplitMix64 with Box-Muller normals: deterministic, no extra dependency.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn normal(&mut self) -> f64 {
        let u = 1.0 - self.uniform();
        let v = self.uniform();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// An edge (i, j) with measurement Δ (in the frame of i) and relative angle θ.
struct Edge {
    i: usize,
    j: usize,
    delta: c64,
    theta: f64,
}

/// A random graph of the paper's model (47) with `n` poses.
fn random_graph(rng: &mut Rng, n: usize, loop_probability: f64, sigma: f64) -> Vec<Edge> {
    let p: Vec<c64> = (0..n)
        .map(|_| c64::new(10.0 * rng.uniform(), 10.0 * rng.uniform()))
        .collect();
    let theta: Vec<f64> = (0..n)
        .map(|_| std::f64::consts::TAU * rng.uniform() - std::f64::consts::PI)
        .collect();
    let mut pairs: Vec<(usize, usize)> = (1..n).map(|i| (i - 1, i)).collect();
    for i in 0..n {
        for j in i + 2..n {
            if rng.uniform() < loop_probability {
                pairs.push((i, j));
            }
        }
    }
    pairs
        .into_iter()
        .map(|(i, j)| {
            let r_i = c64::new(theta[i].cos(), theta[i].sin());
            let noise = c64::new(sigma * rng.normal(), sigma * rng.normal());
            Edge {
                i,
                j,
                delta: r_i.conj() * (p[j] - p[i]) + noise,
                theta: theta[j] - theta[i] + sigma * rng.normal(),
            }
        })
        .collect()
}

/// M = Q − Sᴴ L⁻¹ S for the anchored (p_0 = 0) complex pose graph matrix W of
/// f = Σ |p_j − p_i − r_i Δ|² + |r_j − r_i R|² (unit weights).
fn reduced_matrix(n: usize, edges: &[Edge]) -> Mat<c64> {
    let p = |i: usize| i.checked_sub(1);
    let r = |i: usize| n - 1 + i;
    let mut w = Mat::<c64>::zeros(2 * n - 1, 2 * n - 1);
    for e in edges {
        let mut c = vec![(r(e.i), -e.delta)];
        if let Some(k) = p(e.j) {
            c.push((k, c64::new(1.0, 0.0)));
        }
        if let Some(k) = p(e.i) {
            c.push((k, c64::new(-1.0, 0.0)));
        }
        for &(a, ca) in &c {
            for &(b, cb) in &c {
                w[(a, b)] += ca.conj() * cb;
            }
        }
        let rot = c64::new(e.theta.cos(), e.theta.sin());
        w[(r(e.j), r(e.j))] += 1.0;
        w[(r(e.i), r(e.i))] += 1.0;
        w[(r(e.j), r(e.i))] -= rot;
        w[(r(e.i), r(e.j))] -= rot.conj();
    }
    let np = n - 1;
    let l = w.submatrix(0, 0, np, np).to_owned();
    let s = w.submatrix(0, np, np, n).to_owned();
    let q = w.submatrix(np, np, n, n).to_owned();
    let l_inv_s = l.llt(Side::Lower).expect("connected graph").solve(&s);
    let m = &q - s.adjoint() * &l_inv_s;
    Mat::from_fn(n, n, |i, j| (m[(i, j)] + m[(j, i)].conj()) * 0.5)
}

fn graph_matrix(rng: &mut Rng, n: usize, sigma: f64) -> Mat<c64> {
    let loop_probability = (2.0 / n as f64).min(0.1);
    reduced_matrix(n, &random_graph(rng, n, loop_probability, sigma))
}

fn relative_gap(s: &pgo::dual::sdp::DualSolution) -> f64 {
    (s.primal_objective - s.dual_objective).abs() / s.dual_objective.abs().max(1.0)
}

/// Median wall time of 3 solves.
fn median_time(m: &Mat<c64>) -> (Duration, pgo::dual::sdp::DualSolution) {
    let options = IpmOptions::default();
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..3 {
        let start = Instant::now();
        let s = ipm::solve(m.as_ref(), &options).expect("solve");
        times.push(start.elapsed());
        last = Some(s);
    }
    times.sort();
    (times[1], last.unwrap())
}

/// Solves `count` random graphs of each size; returns (total time, failures, worst gap).
fn batch(rng: &mut Rng, sizes: &[usize], sigmas: &[f64], count: usize) -> (Duration, usize, f64) {
    let (mut total, mut failures, mut worst) = (Duration::ZERO, 0, 0.0_f64);
    for &n in sizes {
        for k in 0..count {
            let m = graph_matrix(rng, n, sigmas[k % sigmas.len()]);
            let start = Instant::now();
            let result = ipm::solve(m.as_ref(), &IpmOptions::default());
            total += start.elapsed();
            match result {
                Ok(s) => worst = worst.max(relative_gap(&s)),
                Err(e) => {
                    failures += 1;
                    eprintln!("n = {n}: {e}");
                }
            }
        }
    }
    (total, failures, worst)
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let mut rng = Rng(20_240_601);
    let sizes: &[usize] = if quick {
        &[10, 20, 50, 100]
    } else {
        &[10, 20, 50, 100, 200, 500]
    };
    println!("random pose graphs (10 m square, σ_R = σ_Δ = 0.1), median of 3 solves");
    println!("{:>5} {:>5} {:>12} {:>10}", "n", "iter", "time", "rel. gap");
    for &n in sizes {
        let m = graph_matrix(&mut rng, n, 0.1);
        let (t, s) = median_time(&m);
        println!(
            "{:>5} {:>5} {:>12.3?} {:>10.2e}",
            n,
            s.iterations,
            t,
            relative_gap(&s)
        );
    }
    let sigmas = [0.1, 0.5, 1.0];
    let start = Instant::now();
    let (solve, failures, worst) = batch(&mut rng, &[10], &sigmas, 2000);
    println!(
        "2000 SDPs at n = 10 (σ = 0.1, 0.5, 1): solve {:.3?}, with graph building {:.3?}, \
         {failures} failures, worst gap {worst:.1e}",
        solve,
        start.elapsed()
    );
    let start = Instant::now();
    let (solve, failures, worst) = batch(&mut rng, &[10, 20, 30, 40, 50], &sigmas, 100);
    println!(
        "n-sweep 10, 20, 30, 40, 50 x 100 SDPs: solve {:.3?}, with graph building {:.3?}, \
         {failures} failures, worst gap {worst:.1e}",
        solve,
        start.elapsed()
    );
}
