//! Inputs large enough for the reader's chunking (8 MB chunks) and its two-thread split (chunks
//! of 4 MB and more): the result, the warnings and the first error must be those of a plain
//! line-by-line reading, whatever the split.

mod common;

use common::{bits, naive_read};
use pgo::io::{self, ReadOptions};

/// A deterministic g2o text of about `mb` megabytes (see [`common::write_generated`]).
fn generated(mb: usize) -> String {
    let mut out = Vec::new();
    common::write_generated(mb, &mut out).unwrap();
    String::from_utf8(out).unwrap()
}

fn read(text: &str) -> Result<(pgo::PoseGraph, io::ReadReport), pgo_io::Error> {
    io::read(text.as_bytes(), "big.g2o", &ReadOptions::default())
}

#[test]
fn split_and_chunked_reading_equals_the_plain_reading() {
    // 20 MB: three chunks, each split between two threads.
    let text = generated(20);
    assert!(text.len() > 16 << 20);
    let (g, report) = read(&text).unwrap();
    let naive = naive_read(text.as_bytes());
    assert_eq!(report.lines, text.lines().count());
    assert_eq!(g.num_poses(), naive.vertices.len());
    assert_eq!(g.edges.len(), naive.edges.len());
    for (k, (id, p)) in naive.vertices.iter().enumerate() {
        assert_eq!(g.ids[k], *id);
        assert_eq!(bits(&g.poses[k].values()), bits(p), "vertex {id}");
    }
    for (e, (i, j, z, n)) in g.edges.iter().zip(&naive.edges) {
        assert_eq!((g.ids[e.i], g.ids[e.j]), (*i, *j));
        assert_eq!(bits(&e.measurement.values()), bits(z));
        assert_eq!(bits(&e.noise.0), bits(n));
    }
}

/// Replaces line `line` (1-based) of `text`.
fn with_line(text: &str, line: usize, new: &str) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    lines[line - 1] = new;
    lines.join("\n") + "\n"
}

#[test]
fn errors_and_warnings_carry_file_positions_across_chunks_and_halves() {
    let text = generated(20);
    let total = text.lines().count();
    // Lines in the second half of the first chunk, in a later chunk, and the last line.
    for line in [total / 6, total / 2 + 3, total - 1] {
        let bad = with_line(&text, line, "EDGE_SE2 1 2 nan 0 0 1 0 0 1 0 1");
        let msg = read(&bad).unwrap_err().to_string();
        assert!(msg.starts_with(&format!("big.g2o:{line}:14: ")), "{msg}");
        assert!(msg.contains("non-finite"), "{msg}");
    }
    // The first of two errors is reported, whichever halves they fall in.
    let (a, b) = (total / 3, total / 7);
    let two = with_line(
        &with_line(&text, a, "VERTEX_SE2 1 2 3"),
        b,
        "EDGE_SE2 5 5 0 0 0 1 0 0 1 0 1",
    );
    let msg = read(&two).unwrap_err().to_string();
    assert!(msg.starts_with(&format!("big.g2o:{b}:")), "{msg}");
    assert!(msg.contains("self-loop"), "{msg}");
    // An edge tag of the other format, late in the file: an error at that line.
    let last_edge = text.lines().count();
    let mixed = with_line(&text, last_edge - 10, "EDGE2 0 1 1 0 0 1 0 1 1 0 0");
    let msg = read(&mixed).unwrap_err().to_string();
    assert!(
        msg.starts_with(&format!("big.g2o:{}:1: ", last_edge - 10)),
        "{msg}"
    );
    assert!(msg.contains("edge tags of both formats"), "{msg}");
    // Unknown tags in several chunks (over edge lines, so that no vertex goes missing): one
    // warning, counted over the whole file, at the first.
    let first_edge = text.lines().position(|l| l.starts_with("EDGE")).unwrap() + 1;
    let lines = [total - 2, first_edge + 3, (first_edge + total) / 2];
    let mut warned = text.clone();
    for line in lines {
        warned = with_line(&warned, line, "FOO 1 2");
    }
    let (g, report) = read(&warned).unwrap();
    assert_eq!(g.edges.len(), total - first_edge + 1 - 3);
    assert_eq!(report.warnings.len(), 1);
    let w = report.warnings[0].to_string();
    let expect = format!(
        "big.g2o:{}:1: warning: unknown tag 'FOO': 3 lines",
        first_edge + 3
    );
    assert!(w.starts_with(&expect), "{w}");
}
