//! A generated 100 MB g2o file: read in bounded memory (files over 64 MB are read in 8 MB chunks,
//! never whole), and an error on its last line reported with that line's number, counted while
//! writing the file. Alone in its test binary, so that the peak RSS measured is this test's.

mod common;

use common::{Dir, s, text};
use pgo::io::{self, ReadOptions};
use std::io::Write;

/// Peak resident memory of this process in bytes (VmHWM), if the platform says.
fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Resets the peak to the current RSS (Linux: writing 5 to /proc/self/clear_refs).
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn current_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[test]
fn a_100_mb_file_is_read_in_bounded_memory_and_its_last_line_error_is_located() {
    let dir = Dir::new();
    // 100 MB that hold almost no graph (comments, blank lines, unknown tags): the memory
    // beyond the graph does not grow with the file.
    let padded = dir.path("padded.g2o");
    let mut out = std::io::BufWriter::new(std::fs::File::create(&padded).unwrap());
    let comment = format!("# {}\n", "c".repeat(97));
    for k in 0..1_000_000 {
        match k % 1000 {
            0 => writeln!(out, "VERTEX_SE2 {} 0 0 0", k / 1000).unwrap(),
            1 => writeln!(out).unwrap(),
            2 => writeln!(out, "FOO {k} bar").unwrap(),
            _ => out.write_all(comment.as_bytes()).unwrap(),
        }
    }
    drop(out);
    assert!(std::fs::metadata(&padded).unwrap().len() > 95_000_000);
    let before = current_rss();
    let measured = reset_peak_rss();
    let (graph, report) = io::read_path(s(&padded), &ReadOptions::default()).unwrap();
    assert_eq!((graph.num_poses(), report.lines), (1000, 1_000_000));
    assert_eq!(report.warnings.len(), 1);
    if let (true, Some(before), Some(peak)) = (measured, before, peak_rss()) {
        let used = peak.saturating_sub(before);
        eprintln!(
            "100 MB of comments: peak RSS {:.1} MiB above the {:.1} MiB before",
            used as f64 / 1048576.0,
            before as f64 / 1048576.0
        );
        assert!(used <= 40 << 20, "{used}");
    }

    let path = dir.path("huge.g2o");
    let mut out = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    let lines = common::write_generated(100, &mut out).unwrap();
    out.flush().unwrap();
    drop(out);
    let bytes = std::fs::metadata(&path).unwrap().len();
    assert!(bytes > 95_000_000, "{bytes}");

    // The read alone: the graph plus bounded buffers.
    let before = current_rss();
    let measured = reset_peak_rss();
    let (graph, report) = io::read_path(s(&path), &ReadOptions::default()).unwrap();
    let peak = peak_rss();
    assert_eq!(report.lines, lines);
    let vertices = graph.num_poses();
    assert_eq!(vertices, 100 * 11_500);
    assert_eq!(vertices + graph.edges.len(), lines);
    // What the graph itself takes: ids and poses, edges and the reader's per-edge positions.
    let graph_bytes = vertices * (4 + 24)
        + graph.edges.len() * (std::mem::size_of::<pgo::Edge>() + 16)
        + graph.fixed.len() * 8;
    if let (true, Some(before), Some(peak)) = (measured, before, peak) {
        let used = peak.saturating_sub(before);
        eprintln!(
            "100 MB read: file {bytes} bytes, {lines} lines; peak RSS {:.1} MiB above the {:.1} MiB before; the graph holds {:.1} MiB",
            used as f64 / 1048576.0,
            before as f64 / 1048576.0,
            graph_bytes as f64 / 1048576.0
        );
        // Bounded by the graph: while it is assembled the reader also holds the vertex lines
        // as read, their sort order and the id index, and a chunk or two of 8 MB; at most
        // twice the graph, never the file on top of it.
        let bound = 2 * graph_bytes as u64;
        assert!(
            used <= bound,
            "peak RSS {used} bytes above the start, bound {bound} (graph {graph_bytes})"
        );
    }
    drop(graph);

    // An error on the last line: the line number counted above plus one, column of `nan`.
    let mut out = std::fs::OpenOptions::new()
        .append(true)
        .open(&path)
        .unwrap();
    out.write_all(b"EDGE_SE2 0 1 nan 0 0 1 0 0 1 0 1\n")
        .unwrap();
    drop(out);
    let last = lines + 1;
    let err = io::read_path(s(&path), &ReadOptions::default()).unwrap_err();
    let expect = format!(
        "{}:{last}:14: expected a number, found 'nan' (non-finite values are not allowed: g2o and GTSAM cannot read them back)",
        s(&path)
    );
    assert_eq!(err.to_string(), expect);
    // The same from the tool, with status 2.
    let out = common::run_with_stdin("pgo-convert", &["--stats", s(&path)], None);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        text(&out.stderr),
        format!(
            "{}:{last}:14: error: expected a number, found 'nan' (non-finite values are not allowed: g2o and GTSAM cannot read them back)\n",
            s(&path)
        )
    );
}
