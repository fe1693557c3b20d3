//! Weak duality and the zero duality gap in 3D, against SE-Sync's semidefinite relaxation
//! (IJRR 2019, Problem 7) solved densely by clarabel (`pgo::se3::sdp`, feature `clarabel-sdp`)
//! on generated worlds of n ≤ 15 poses:
//! - the relaxation's optimum d* is at least pgo's lower bound (every certificate is a dual
//!   feasible point of Problem 8, and d* is their maximum), within the SDP's own certified gap;
//! - at low noise, d* equals pgo's certified f* to about 1e-6 relative (the relaxation is exact);
//! - at high noise, pgo's bound ≤ d* ≤ pgo's cost, whether or not pgo certified.
//!
//! clarabel's answer is independent of pgo's staircase and certificate: it sees only the
//! reduced matrix M, itself checked here against pgo's cost (tr(VᵀMV) at pgo's rotations is the
//! cost with the translations optimal, which at pgo's optimum is the optimum).

#![cfg(feature = "clarabel-sdp")]

use pgo::se3::problem::{Problem3, weights3};
use pgo::se3::sdp::{reduced_cost, reduced_matrix, solve_relaxation};
use pgo::se3::{Options3, anchor_of, solve_graph3};
use pgo::simulate::space::{SpaceConfig, World3, simulate3};
use pgo::simulate::{RotationNoise, TranslationNoise};

struct Case {
    cost: f64,
    lower_bound: f64,
    certified: bool,
    /// The SDP's certified interval: dual ≤ d* ≤ primal.
    dual: f64,
    primal: f64,
}

fn run(world: World3, n: usize, sigma_r: f64, sigma_t: f64, seed: u64) -> Case {
    let sim = simulate3(&SpaceConfig {
        world,
        n,
        side: 10.0,
        loop_probability: 1.0,
        rotation_noise: RotationNoise::Gaussian { sigma: sigma_r },
        translation_noise: TranslationNoise::Gaussian { sigma: sigma_t },
        seed,
    });
    let g = &sim.graph;
    let w = weights3(g, false).unwrap();
    let solution = solve_graph3(g, &w, &Options3::default(), &mut |_| {});
    let problem = Problem3::new(g, &w, anchor_of(g));
    let m = reduced_matrix(&problem).unwrap();
    // pgo's cost again from M: the translations of an optimum are optimal for its rotations.
    let rotations: Vec<[f64; 9]> = solution.poses.iter().map(|p| p.r).collect();
    let again = reduced_cost(&m, &rotations);
    assert!(
        again <= solution.cost * (1.0 + 1e-9) + 1e-12,
        "{world:?} n {n}: tr(VᵀMV) {again} above the cost {}",
        solution.cost
    );
    if solution.certified {
        assert!(
            (again - solution.cost).abs() <= 1e-7 * solution.cost.max(1e-12),
            "{world:?} n {n}: {again} vs {}",
            solution.cost
        );
    }
    let sdp = solve_relaxation(&m).unwrap();
    assert!(sdp.dual_objective <= sdp.primal_objective * (1.0 + 1e-12));
    Case {
        cost: solution.cost,
        lower_bound: solution.lower_bound,
        certified: solution.certified,
        dual: sdp.dual_objective,
        primal: sdp.primal_objective,
    }
}

#[test]
fn low_noise_zero_gap_and_weak_duality() {
    let mut worst: f64 = 0.0;
    for (world, n) in [
        (World3::Sphere, 9),
        (World3::Sphere, 15),
        (World3::Torus, 12),
        (World3::Torus, 9),
        (World3::Grid, 8),
        (World3::Grid, 15),
    ] {
        for seed in 0..2 {
            let c = run(world, n, 0.02, 0.05, seed);
            assert!(c.certified, "{world:?} n {n} seed {seed}");
            // The SDP's interval is tight: a few 1e-8 relative.
            assert!(
                c.primal - c.dual <= 1e-6 * c.primal,
                "{world:?} n {n}: SDP gap {} .. {}, f* {}",
                c.dual,
                c.primal,
                c.cost
            );
            // Weak duality: pgo's bound is dual feasible, so at most d* ≤ primal.
            assert!(
                c.lower_bound <= c.primal * (1.0 + 1e-9),
                "{world:?} n {n}: bound {} above d* ≤ {}",
                c.lower_bound,
                c.primal
            );
            // d* ≤ f* ≤ cost, and at low noise d* = f*: zero gap.
            assert!(c.dual <= c.cost * (1.0 + 1e-9));
            let gap = (c.cost - c.dual) / c.cost;
            worst = worst.max(gap.abs());
            assert!(
                gap.abs() <= 1e-6,
                "{world:?} n {n} seed {seed}: f* {} d* in [{}, {}]",
                c.cost,
                c.dual,
                c.primal
            );
        }
    }
    eprintln!("largest |f* − d*| / f*: {worst:.3e}");
}

#[test]
fn high_noise_bound_below_sdp_below_cost() {
    let mut uncertified = 0;
    for (world, n) in [
        (World3::Sphere, 12),
        (World3::Torus, 12),
        (World3::Grid, 12),
    ] {
        for seed in 0..3 {
            let c = run(world, n, 1.0, 1.0, seed);
            eprintln!(
                "{world:?} seed {seed}: bound {:.6e} d* in [{:.6e}, {:.6e}] cost {:.6e} certified {}",
                c.lower_bound, c.dual, c.primal, c.cost, c.certified
            );
            // bound ≤ d* ≤ cost, each within the SDP's certified interval [dual, primal].
            assert!(
                c.lower_bound <= c.primal * (1.0 + 1e-9),
                "{world:?} seed {seed}: bound {} > d* ≤ {}",
                c.lower_bound,
                c.primal
            );
            assert!(
                c.dual <= c.cost * (1.0 + 1e-9),
                "{world:?} seed {seed}: d* ≥ {} > cost {}",
                c.dual,
                c.cost
            );
            if c.certified {
                assert!((c.cost - c.dual).abs() <= 1e-6 * c.cost);
            } else {
                uncertified += 1;
            }
        }
    }
    eprintln!("high noise: {uncertified} of 9 not certified");
}
