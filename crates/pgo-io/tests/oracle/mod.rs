//! The checks the reader fuzz targets (`crates/pgo-io/fuzz/`) run on every input, shared with
//! `tests/fuzz_regressions.rs` here and in the root package, which replay the minimized inputs
//! the fuzzers found, so a regression fails plain `cargo test`:
//!
//! - [`check_reader`]: reading never panics; an error names a line and column inside the input;
//!   a graph that was read is written in both formats and read back identically, bit for bit
//!   (the writer's promise), and its statistics never panic. The same for 3D graphs
//!   ([`io::read_any`]), written back in their own form.
//!
//! The checks of the solve path (fuzz target `solve`, in the root package's `fuzz/`) are in the
//! root's `tests/oracle/mod.rs`.
#![allow(dead_code)]

use pgo_io::io::{self, AnyGraph, Dialect, Format, ReadOptions, WriteOptions};
use pgo_io::{Graph3, NoiseKind, PoseGraph};

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
            ignore_equiv: true,
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
                let _ = pgo_io::stats::GraphStats::new(&graph, &report);
                round_trip(&graph, &options);
            }
            Err(pgo_io::Error::Parse(e)) => check_location(data, name, &e),
            Err(e) => panic!("reading from memory failed without a location: {e}"),
        }
        match io::read_any(data, name, &options) {
            Ok((AnyGraph::Spatial(graph), report)) => {
                assert_eq!(report.lines, line_count(data), "lines counted");
                for w in &report.warnings {
                    assert!(w.location.line >= 1 && w.location.line <= report.lines.max(1));
                }
                check_graph3(&graph, &options);
                let _ = pgo_io::GraphStats3::new(&graph, &report);
            }
            Ok((AnyGraph::Planar(_), _)) => {}
            Err(pgo_io::Error::Parse(e)) => check_location(data, name, &e),
            // A covariance (or the other form's) dialect asked of a 3D file.
            Err(pgo_io::Error::Invalid(msg)) if options.dialect.is_some() => {
                assert!(msg.contains("does not apply to a 3D file"), "{msg}");
            }
            Err(e) => panic!("reading from memory failed without a location: {e}"),
        }
    }
}

/// An error names `name`, a line of the input and a column inside it (or just past its end).
fn check_location(data: &[u8], name: &str, e: &pgo_io::ParseError) {
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

/// A 3D graph's invariants, and its round trip in its own form: the same graph, bit for bit.
fn check_graph3(g: &Graph3, read_with: &ReadOptions) {
    assert_eq!(g.ids.len(), g.poses.len());
    assert!(g.ids.windows(2).all(|w| w[0] < w[1]), "ids ascending");
    for e in &g.edges {
        assert!(e.i < g.num_poses() && e.j < g.num_poses() && e.i != e.j);
    }
    assert!(g.fixed.iter().all(|&k| k < g.num_poses()));
    let format = match g.form {
        pgo_io::Form3::G2o => Format::G2o,
        pgo_io::Form3::Toro => Format::Toro,
    };
    let mut out = Vec::new();
    io::write3(g, format, &mut out).unwrap_or_else(|e| panic!("writing a 3D graph read: {e}"));
    let options = ReadOptions {
        strict: true,
        allow_indefinite: read_with.allow_indefinite,
        ..Default::default()
    };
    match io::read_any(&out[..], "written", &options) {
        Ok((AnyGraph::Spatial(back), _)) => {
            let bits3 = |g: &Graph3| -> Vec<u64> {
                g.poses
                    .iter()
                    .flat_map(|p| p.values())
                    .chain(
                        g.edges
                            .iter()
                            .flat_map(|e| e.measurement.values().chain(e.information.0)),
                    )
                    .map(f64::to_bits)
                    .collect()
            };
            assert_eq!(
                (&back.ids, &back.fixed, back.form),
                (&g.ids, &g.fixed, g.form)
            );
            assert_eq!(bits3(&back), bits3(g));
        }
        other => panic!(
            "pgo cannot read back the 3D graph it wrote: {other:?}\n{}",
            String::from_utf8_lossy(&out)
        ),
    }
}

fn check_graph_invariants(g: &PoseGraph) {
    assert_eq!(g.ids.len(), g.poses.len());
    assert!(g.ids.windows(2).all(|w| w[0] < w[1]), "ids ascending");
    assert!(g.ids.iter().all(|&id| id <= pgo_io::graph::MAX_VERTEX_ID));
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

/// Writes `graph` in both formats and reads it back: the same graph, bit for bit. TORO has no
/// landmark type: a graph with landmarks is refused there, with an error that says so.
fn round_trip(graph: &PoseGraph, read_with: &ReadOptions) {
    for format in [Format::G2o, Format::Toro] {
        let dialect = match (format, graph.noise) {
            (Format::G2o, NoiseKind::Information) => Dialect::G2o,
            (Format::G2o, NoiseKind::Covariance) => Dialect::G2oCov,
            (Format::Toro, NoiseKind::Information) => Dialect::ToroInfo,
            (Format::Toro, NoiseKind::Covariance) => Dialect::ToroCov,
        };
        if format == Format::Toro && !graph.landmarks.is_empty() {
            match io::write(graph, WriteOptions { format, dialect }, &mut Vec::new()) {
                Err(e) => assert!(e.to_string().contains("landmark"), "{e}"),
                Ok(()) => panic!("a graph with landmarks written as TORO"),
            }
            continue;
        }
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
            ignore_equiv: false,
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
