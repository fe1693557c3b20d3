//! The share of hard instances (where the relaxation is often not exact) at which each method
//! returns the best known minimum, per kind and per method, and the soundness of the bounds.
//!
//! The instances and the reference minimum (many random starts of the local solver under f,
//! exhaustive grid search for n ≤ 6) are those of `tests/common/hard.rs`; the best known minimum
//! is the lowest of the reference and every method's cost. A method is at the minimum when its
//! cost is within 1e-6 relative of it.
//!
//! ```text
//! cargo run --release --example hard_share [-- COUNT [STARTS]]
//! ```
//! (COUNT instances per kind, default 40; STARTS random starts of the reference, default 32.)

#[path = "../tests/common/hard.rs"]
mod hard;

use pgo::solve::{Method, SolveOptions, solve};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let count: u64 = args.first().map_or(40, |a| a.parse().expect("COUNT"));
    let starts: usize = args.get(1).map_or(32, |a| a.parse().expect("STARTS"));
    let methods = [Method::Auto, Method::Sdp, Method::Staircase];
    println!(
        "{:<9} {:>5} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}   worst excess (auto, sdp, staircase)",
        "kind", "count", "auto", "sdp", "staircase", "ref", "cert", "unsound"
    );
    let mut seconds = [0.0; 3];
    let mut totals = [0usize; 5];
    let mut all = 0;
    for kind in hard::KINDS {
        let mut at = [0usize; 3];
        let mut at_ref = 0;
        let mut certified = 0;
        let mut unsound = 0;
        let mut worst = [0.0f64; 3];
        for seed in 0..count {
            let g = hard::instance(kind, seed);
            let reference = hard::reference(&g, starts, seed);
            let mut results = Vec::new();
            for (k, &method) in methods.iter().enumerate() {
                let t = Instant::now();
                let s = solve(
                    &g,
                    &SolveOptions {
                        method,
                        weights: hard::WEIGHTS,
                        ..Default::default()
                    },
                )
                .expect("solves");
                seconds[k] += t.elapsed().as_secs_f64();
                results.push(s);
            }
            let best = results.iter().map(|s| s.cost).fold(reference, f64::min);
            if hard::at_minimum(reference, best, &g) {
                at_ref += 1;
            }
            for (k, s) in results.iter().enumerate() {
                if hard::at_minimum(s.cost, best, &g) {
                    at[k] += 1;
                } else {
                    worst[k] = worst[k].max((s.cost - best) / best.abs().max(1e-300));
                }
                if s.certified {
                    certified += 1;
                }
                let slack = 1e-9 * best.abs() + 1e-12;
                if s.lower_bound > best + slack
                    || (s.certified && !hard::at_minimum(s.cost, best, &g))
                {
                    unsound += 1;
                    eprintln!(
                        "UNSOUND {kind} seed {seed} {}: cost {} bound {} best {best} certified {}",
                        methods[k].name(),
                        s.cost,
                        s.lower_bound,
                        s.certified
                    );
                }
            }
        }
        let pct = |a: usize| format!("{:.1}%", 100.0 * a as f64 / count as f64);
        println!(
            "{:<9} {:>5} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}   {:.2e} {:.2e} {:.2e}",
            kind,
            count,
            pct(at[0]),
            pct(at[1]),
            pct(at[2]),
            pct(at_ref),
            certified,
            unsound,
            worst[0],
            worst[1],
            worst[2]
        );
        for k in 0..3 {
            totals[k] += at[k];
        }
        totals[3] += at_ref;
        totals[4] += unsound;
        all += count as usize;
    }
    let pct = |a: usize| format!("{:.1}%", 100.0 * a as f64 / all as f64);
    println!(
        "{:<9} {:>5} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "all",
        all,
        pct(totals[0]),
        pct(totals[1]),
        pct(totals[2]),
        pct(totals[3]),
        "",
        totals[4]
    );
    println!(
        "seconds solving: auto {:.2}, sdp {:.2}, staircase {:.2}",
        seconds[0], seconds[1], seconds[2]
    );
}
