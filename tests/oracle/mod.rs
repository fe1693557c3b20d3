//! The checks the fuzz targets (`fuzz/`) run on every input, shared with `tests/fuzz_regressions.rs`,
//! which replays the minimized inputs the fuzzers found, so a regression fails plain `cargo test`.
//!
//! - [`check_reader`]: reading never panics; an error names a line and column inside the input;
//!   a graph that was read is written in both formats and read back identically, bit for bit
//!   (the writer's promise), and its statistics never panic.
//! - [`check_solve`]: on tiny graphs, the solve path of `pgo-solve` (components, weights,
//!   Algorithm 1) never panics, and what it reports is sound: the proven lower bound is below the
//!   cost of the estimate and below the cost of the input's own poses (weak duality holds for any
//!   feasible point), a tree is solved to zero cost, and `certified` agrees with the numbers.
#![allow(dead_code)]

use pgo::PoseGraph;
use pgo::io::{self, Dialect, Format, ReadOptions, WriteOptions};

/// Every way the readers are asked to read in the fuzz targets.
pub fn reader_options() -> Vec<ReadOptions> {
    vec![
        ReadOptions::default(),
        ReadOptions {
            strict: true,
            allow_indefinite: true,
            ..Default::default()
        },
        ReadOptions {
            dialect: Some(Dialect::ToroCov),
            ..Default::default()
        },
        ReadOptions {
            dialect: Some(Dialect::G2oCov),
            allow_indefinite: true,
            ..Default::default()
        },
    ]
}

/// Line count of `data` as an editor shows it (a last line without newline counts).
fn line_count(data: &[u8]) -> usize {
    let newlines = data.iter().filter(|&&c| c == b'\n').count();
    newlines + usize::from(!data.is_empty() && data.last() != Some(&b'\n'))
}

/// Reads `data` as the file `name` with every option set, and checks what comes back.
pub fn check_reader(data: &[u8], name: &str) {
    for options in reader_options() {
        match io::read(data, name, &options) {
            Ok((graph, report)) => {
                assert_eq!(report.lines, line_count(data), "lines counted");
                for w in &report.warnings {
                    assert!(w.location.line >= 1 && w.location.line <= report.lines.max(1));
                }
                check_graph_invariants(&graph);
                let _ = pgo::stats::GraphStats::new(&graph, &report);
                round_trip(&graph, &options);
            }
            Err(pgo_io::Error::Parse(e)) => {
                let text = e.to_string();
                let prefix = format!("{name}:{}:{}: ", e.location.line, e.location.col);
                assert!(text.starts_with(&prefix), "{text}");
                let line = e.location.line;
                assert!(line >= 1 && line <= line_count(data).max(1), "{text}");
                let content = data
                    .split(|&c| c == b'\n')
                    .nth(line - 1)
                    .unwrap_or_default();
                assert!(
                    e.location.col >= 1 && e.location.col <= content.len() + 1,
                    "{text}: column outside line {line} ({} bytes)",
                    content.len()
                );
            }
            Err(e) => panic!("reading from memory failed without a location: {e}"),
        }
    }
}

fn check_graph_invariants(g: &PoseGraph) {
    assert_eq!(g.ids.len(), g.poses.len());
    assert!(g.ids.windows(2).all(|w| w[0] < w[1]), "ids ascending");
    assert!(g.ids.iter().all(|&id| id <= pgo::graph::MAX_VERTEX_ID));
    for e in &g.edges {
        assert!(e.i < g.num_poses() && e.j < g.num_poses() && e.i != e.j);
        let values = e.measurement.values();
        assert!(values.iter().chain(&e.noise.0).all(|v| v.is_finite()));
    }
    assert!(g.fixed.iter().all(|&k| k < g.num_poses()));
    if g.vertices_declared {
        assert!(
            g.poses
                .iter()
                .all(|p| p.values().iter().all(|v| v.is_finite()))
        );
    }
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Writes `graph` in both formats and reads it back: the same graph, bit for bit.
fn round_trip(graph: &PoseGraph, read_with: &ReadOptions) {
    for format in [Format::G2o, Format::Toro] {
        let dialect = match (format, graph.noise) {
            (Format::G2o, pgo::NoiseKind::Information) => Dialect::G2o,
            (Format::G2o, pgo::NoiseKind::Covariance) => Dialect::G2oCov,
            (Format::Toro, pgo::NoiseKind::Information) => Dialect::ToroInfo,
            (Format::Toro, pgo::NoiseKind::Covariance) => Dialect::ToroCov,
        };
        let mut out = Vec::new();
        if let Err(e) = io::write(graph, WriteOptions { format, dialect }, &mut out) {
            // Only poses composed from the measurements (no vertex lines) can overflow.
            let finite = graph
                .poses
                .iter()
                .all(|p| p.values().iter().all(|v| v.is_finite()));
            assert!(
                !graph.vertices_declared && !finite,
                "writing a graph that was read failed: {e}"
            );
            return;
        }
        let options = ReadOptions {
            format: Some(format),
            dialect: Some(dialect),
            strict: true,
            allow_indefinite: read_with.allow_indefinite,
        };
        let (back, _) = io::read(&out[..], "written", &options).unwrap_or_else(|e| {
            panic!(
                "pgo cannot read back what it wrote: {e}\n{}",
                String::from_utf8_lossy(&out)
            )
        });
        assert_eq!(back.ids, graph.ids);
        assert_eq!(back.fixed, graph.fixed);
        assert_eq!(back.noise, graph.noise);
        for (a, b) in back.poses.iter().zip(&graph.poses) {
            assert_eq!(bits(&a.values()), bits(&b.values()));
        }
        assert_eq!(back.edges.len(), graph.edges.len());
        for (a, b) in back.edges.iter().zip(&graph.edges) {
            assert_eq!((a.i, a.j), (b.i, b.j));
            assert_eq!(bits(&a.measurement.values()), bits(&b.measurement.values()));
            assert_eq!(bits(&a.noise.0), bits(&b.noise.0));
        }
    }
}

/// Largest graph [`check_solve`] solves (the dense SDP path is cubic).
pub const SOLVE_MAX_POSES: usize = 8;
pub const SOLVE_MAX_EDGES: usize = 24;

/// Reads `data` (format from the tags) and, if it is a graph of at most [`SOLVE_MAX_POSES`]
/// poses, runs the solve path of `pgo-solve` on it with both weight policies.
pub fn check_solve(data: &[u8]) {
    use pgo::algorithm1::{SdpSolver, solve_connected};
    use pgo::weights::{Weights, edge_weights};
    let options = ReadOptions {
        allow_indefinite: true,
        ..Default::default()
    };
    let Ok((graph, _)) = io::read(data, "fuzz.txt", &options) else {
        return;
    };
    if graph.num_poses() > SOLVE_MAX_POSES || graph.edges.len() > SOLVE_MAX_EDGES {
        return;
    }
    for policy in [Weights::Unit, Weights::Isotropic] {
        for (part, _, _) in graph.components() {
            let weights = match edge_weights(&part, policy) {
                Ok(w) => w,
                Err(e) => {
                    assert_eq!(policy, Weights::Isotropic, "unit weights always exist");
                    // Only an information matrix that is not positive definite is called so.
                    let msg = e.to_string();
                    if msg.contains("not positive definite") {
                        assert!(
                            part.edges.iter().any(|e| part
                                .information(e)
                                .is_none_or(|m| m.check_positive_definite().is_err())),
                            "{msg}"
                        );
                    }
                    continue;
                }
            };
            let s = match solve_connected(&part, &weights, SdpSolver::Ipm) {
                Ok(s) => s,
                Err(pgo::Error::Invalid(msg)) => {
                    // Said in the user's terms: `part` is a connected component, and the
                    // solver's internal conditions are not the user's business.
                    assert!(!msg.contains("not connected"), "{msg}");
                    assert!(!msg.contains("not Hermitian"), "{msg}");
                    continue;
                }
                Err(e) => panic!("unexpected error kind: {e}"),
            };
            check_solution(&part, &weights, &s);
        }
    }
}

fn check_solution(
    part: &PoseGraph,
    weights: &[pgo::weights::EdgeWeight],
    s: &pgo::algorithm1::ComponentSolution,
) {
    use pgo::matrix::cost;
    assert_eq!(s.poses.len(), part.num_poses());
    assert!(s.cost.is_finite() && s.cost >= 0.0, "cost {}", s.cost);
    assert!(!s.lower_bound.is_nan(), "bound is NaN");
    // Rounding of the cost itself: every term is a sum of a few products.
    let slack = |f: f64| 1e-9 * f.abs().max(1.0);
    assert!(
        s.lower_bound <= s.cost + slack(s.cost),
        "bound {} above the cost {} of the estimate",
        s.lower_bound,
        s.cost
    );
    // Weak duality: the bound is below the cost of every feasible point, e.g. the input's.
    let input_cost = cost(part, weights, &part.poses);
    if input_cost.is_finite() {
        assert!(
            s.lower_bound <= input_cost + slack(input_cost),
            "bound {} above the cost {input_cost} of the input poses",
            s.lower_bound
        );
    }
    // The cost of the returned poses, recomputed, is the one reported.
    let recomputed = cost(part, weights, &s.poses);
    assert!(
        (recomputed - s.cost).abs() <= slack(s.cost),
        "{recomputed} vs {}",
        s.cost
    );
    // A tree is solved exactly: f* = 0 (Prop. 6).
    if part.is_forest() {
        let scale: f64 = part
            .edges
            .iter()
            .zip(weights)
            .map(|(e, w)| w.tau * (e.measurement.x.powi(2) + e.measurement.y.powi(2)) + w.kappa)
            .sum();
        if scale.is_finite() {
            assert!(
                s.cost <= 1e-6 * scale.max(1.0),
                "tree solved to cost {} (scale {scale})",
                s.cost
            );
        }
    }
}
