//! Hard instances (tests/common/hard.rs: large rotation noise, weights from 1e-4 to 1e4,
//! conflicting duplicate edges) held to an independent reference minimum (random starts of the
//! local solver under f, exhaustive grid search for n ≤ 6): the bounds are sound, no estimate
//! above the minimum is called certified. A small seeded subset; the full set and the share per
//! kind and method is `cargo run --release --example hard_share`.

#[path = "common/hard.rs"]
mod hard;

use pgo::solve::{Method, SolveOptions, solve};

fn subset() -> impl Iterator<Item = (&'static str, u64)> {
    hard::KINDS
        .into_iter()
        .flat_map(|kind| (0..if kind == "large" { 2 } else { 4 }).map(move |seed| (kind, seed)))
}

#[test]
fn bounds_are_sound_and_certified_estimates_are_at_the_minimum() {
    for (kind, seed) in subset() {
        let g = hard::instance(kind, seed);
        let reference = hard::reference(&g, 12, seed);
        for method in [Method::Auto, Method::Sdp, Method::Staircase] {
            let options = SolveOptions {
                method,
                weights: hard::WEIGHTS,
                ..Default::default()
            };
            let s = solve(&g, &options).unwrap();
            let best = s.cost.min(reference);
            assert!(
                s.lower_bound <= best + 1e-9 * best.abs() + 1e-12,
                "{kind} {seed} {}: bound {} above the minimum {best}",
                method.name(),
                s.lower_bound
            );
            assert!(
                !s.certified || hard::at_minimum(s.cost, reference, &g),
                "{kind} {seed} {}: certified at {} above the reference {reference}",
                method.name(),
                s.cost
            );
        }
    }
}
