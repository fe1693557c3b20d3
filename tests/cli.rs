//! `pgo-convert` as a user runs it: warnings, the layout the reader tolerates, stdin/stdout,
//! atomic output.

mod common;

use common::{Dir, s, text};
use std::process::Output;

fn run(args: &[&str], stdin: Option<&[u8]>) -> Output {
    common::run_with_stdin("pgo-convert", args, stdin)
}

const V: &str = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
const INFO: &str = "1 0 0 1 0 1";

// Every validation error (and its location, status 2, untouched output) is checked for every
// tool by tests/corpus.rs on the files of tests/malformed/.

#[test]
fn indefinite_information_is_accepted_on_request() {
    let dir = Dir::new();
    let input = dir.file(
        "in.g2o",
        format!("{V}EDGE_SE2 0 1 1 0 0 1 -2 0 -1 0 1\n").as_bytes(),
    );
    let out = run(&[s(&input), "--allow-indefinite", "-q"], None);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("EDGE_SE2 0 1 1 0 0 1 -2 0 -1 0 1\n"));
}

#[test]
fn unknown_tags_warn_and_are_errors_when_strict() {
    let dir = Dir::new();
    let input = dir.file(
        "in.g2o",
        format!("{V}FOO 1 2\nEDGE_SE2 0 1 1 0 0 {INFO}\nFOO 3\n").as_bytes(),
    );
    let out = run(&[s(&input), "-q"], None);
    assert_eq!(out.status.code(), Some(0));
    let err = text(&out.stderr);
    assert!(
        err.contains(&format!(
            "{}:3:1: warning: unknown tag 'FOO': 2 lines skipped",
            s(&input)
        )),
        "{err}"
    );
    let out = run(&[s(&input), "--strict"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).starts_with(&format!("{}:3:1: error: unknown tag 'FOO'", s(&input))),
        "{}",
        text(&out.stderr)
    );
}

/// Layout g2o and GTSAM tolerate: BOM, CRLF, tabs, runs of spaces, comments, blank lines,
/// vertices after edges, FIX anywhere with several ids, no final newline, a trailing comment.
#[test]
fn tolerated_layout_reads_and_writes_canonically() {
    let messy = "\u{feff}# a comment\r\n\r\nFIX 1\r\nEDGE_SE2\t0  1 1 0 0.5 1 0 0 1 0 1 # note\r\n   \r\nVERTEX_SE2 1 1 0 0.5\r\nVERTEX_SE2 0 0 0 -0\r\nEDGE_SE2 1 0 -1 0 -0.5 2 0 0 2 0 2\r\nFIX 0 1";
    let out = run(&["-", "--to", "g2o", "-q"], Some(messy.as_bytes()));
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout),
        "VERTEX_SE2 0 0 0 -0\nVERTEX_SE2 1 1 0 0.5\n\
         EDGE_SE2 0 1 1 0 0.5 1 0 0 1 0 1\nEDGE_SE2 1 0 -1 0 -0.5 2 0 0 2 0 2\nFIX 1 0\n"
    );
    assert!(out.stderr.is_empty(), "{}", text(&out.stderr));
}

#[test]
fn toro_output_uses_toro_information_order() {
    // g2o order m00 m01 m02 m11 m12 m22 = 1 2 3 11 12 22; TORO writes m00 m01 m11 m22 m02 m12.
    let g2o = format!("{V}EDGE_SE2 0 1 1 0 0 100 2 3 110 12 220\n");
    let out = run(&["-", "--to", "toro", "-q"], Some(g2o.as_bytes()));
    assert_eq!(
        text(&out.stdout),
        "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nEDGE2 0 1 1 0 0 100 2 110 220 3 12\n"
    );
    let back = run(
        &["-", "--from", "toro", "--to", "g2o", "-q"],
        Some(&out.stdout),
    );
    assert_eq!(
        text(&back.stdout),
        format!("{V}EDGE_SE2 0 1 1 0 0 100 2 3 110 12 220\n")
    );
}

#[test]
fn covariance_dialects_invert_on_request() {
    // A GTSAM-style .graph with TORO-order covariances diag(0.01, 0.04, 0.25).
    let graph = "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nEDGE2 0 1 1 0 0 0.01 0 0.04 0.25 0 0\n";
    let out = run(
        &[
            "-",
            "--from",
            "toro",
            "--dialect",
            "toro-cov",
            "--to",
            "g2o",
        ],
        Some(graph.as_bytes()),
    );
    assert_eq!(out.status.code(), Some(0));
    let edge = text(&out.stdout).lines().nth(2).unwrap().to_string();
    let v: Vec<f64> = edge
        .split(' ')
        .skip(6)
        .map(|t| t.parse().unwrap())
        .collect();
    for (a, b) in v.iter().zip([100.0, 0.0, 0.0, 25.0, 0.0, 4.0]) {
        assert!((a - b).abs() <= 1e-12 * b.max(1.0), "{edge}");
    }
    assert!(text(&out.stderr).contains("covariances inverted to information"));
    // Kept as covariances when asked to: values untouched.
    let out = run(
        &[
            "-",
            "--from",
            "toro",
            "--dialect",
            "toro-cov",
            "--to-dialect",
            "toro-cov",
            "-q",
        ],
        Some(graph.as_bytes()),
    );
    assert_eq!(text(&out.stdout), graph);
    // A dialect that does not fit the output format is refused.
    let out = run(
        &["-", "--to", "g2o", "--to-dialect", "toro-info"],
        Some(graph.as_bytes()),
    );
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn reindex_renumbers_densely() {
    let g = format!(
        "VERTEX_SE2 10 0 0 0\nVERTEX_SE2 7 1 0 0\nVERTEX_SE2 99 2 0 0\nEDGE_SE2 10 99 1 0 0 {INFO}\nFIX 99\n"
    );
    let out = run(&["-", "--reindex", "--to", "g2o", "-q"], Some(g.as_bytes()));
    assert_eq!(
        text(&out.stdout),
        format!(
            "VERTEX_SE2 0 1 0 0\nVERTEX_SE2 1 0 0 0\nVERTEX_SE2 2 2 0 0\nEDGE_SE2 1 2 1 0 0 {INFO}\nFIX 2\n"
        )
    );
}

#[test]
fn stats_json_has_the_documented_fields() {
    let g = format!(
        "{V}VERTEX_SE2 5 0 0 0\nEDGE_SE2 0 1 1 0 0 {INFO}\nEDGE_SE2 1 0 1 0 0 {INFO}\nEDGE_SE2 0 1 1 0 0 {INFO}\n"
    );
    let out = run(&["--stats", "--json", "-"], Some(g.as_bytes()));
    assert_eq!(out.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["poses"], 3);
    assert_eq!(v["edges"], 3);
    assert_eq!(v["components"], 2);
    assert_eq!(v["odometry_edges"], 2);
    assert_eq!(v["loop_closures"], 1);
    assert_eq!(v["duplicate_edges"], 2);
    assert_eq!(v["exact_duplicate_edges"], 1);
    assert_eq!(v["isolated_poses"], 1);
    assert_eq!(v["id_gaps"], 3);
    assert_eq!(v["format"], "g2o");
    assert_eq!(v["dialect"], "g2o");
}

#[test]
fn bad_flags_exit_2() {
    for args in [
        &["--no-such-flag", "x.g2o"][..],
        &["--to", "xml", "x.g2o"],
        &["--json", "x.g2o"],
        &[],
    ] {
        let out = run(args, None);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
    }
    let out = run(&["/nonexistent/in.g2o"], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("/nonexistent/in.g2o: No such file"));
}

#[test]
fn unwritable_output_is_an_error_and_leaves_nothing() {
    let dir = Dir::new();
    let input = dir.file("in.g2o", V.as_bytes());
    let out = run(&[s(&input), "-o", s(&dir.path("missing/out.g2o"))], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("missing/out.g2o"));
    assert_eq!(dir.entries(), ["in.g2o"]);
}

#[test]
fn output_file_is_complete_and_readable() {
    let dir = Dir::new();
    let input = common::datasets_dir().join("MIT.g2o");
    let output = dir.path("MIT.graph");
    let out = run(&[s(&input), "-o", s(&output)], None);
    assert_eq!(out.status.code(), Some(0));
    let err = text(&out.stderr);
    assert!(err.contains("808 poses, 827 edges"), "{err}");
    assert!(err.contains("format toro, dialect toro-info"), "{err}");
    let written = std::fs::read_to_string(&output).unwrap();
    assert_eq!(
        written.lines().filter(|l| l.starts_with("EDGE2 ")).count(),
        827
    );
    assert_eq!(dir.entries(), ["MIT.graph"]);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&output).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o644);
    }
}

#[cfg(unix)]
#[test]
fn writing_to_a_fifo_writes_through_it() {
    // `-o /dev/null` (or a named pipe) must not rename a temporary file over the special file:
    // that replaced /dev/null with a regular file for the whole machine. Devices and FIFOs are
    // written in place. Checked on a FIFO of the test's own, read by a thread.
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("g.g2o");
    std::fs::write(
        &input,
        "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n",
    )
    .unwrap();
    let fifo = dir.path().join("pipe");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("mkfifo unavailable: skipped");
        return;
    }
    let tools: [(&str, Vec<&str>); 3] = [
        ("pgo-convert", vec![]),
        ("pgo-solve", vec!["--method", "staircase", "--json"]),
        ("pgo-solve", vec!["--method", "sdp", "--json"]),
    ];
    for (tool, extra) in tools {
        let path = fifo.clone();
        let reader = std::thread::spawn(move || std::fs::read(path).unwrap());
        let out = std::process::Command::new(common::bin(tool))
            .arg(&input)
            .args(&extra)
            .arg("-o")
            .arg(&fifo)
            .output()
            .unwrap();
        assert!(out.status.success(), "{tool}: {}", text(&out.stderr));
        let written = reader.join().unwrap();
        assert!(
            text(&written).starts_with("VERTEX_SE2 0 "),
            "{tool}: {}",
            text(&written)
        );
        let meta = std::fs::symlink_metadata(&fifo).unwrap();
        assert!(meta.file_type().is_fifo(), "{tool} replaced the FIFO");
    }
}

/// TORO's EQUIV (merge two vertices) is not implemented: every tool refuses it at its line unless
/// --ignore-equiv is given, and then the warning says what was skipped, also in the JSON reports
/// (whose verdict is for the graph without the EQUIV lines).
#[test]
fn equiv_lines_are_refused_unless_ignored_on_request() {
    let dir = Dir::new();
    let input = dir.file(
        "w.graph",
        b"VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nVERTEX2 2 2 0 0\nEDGE2 0 1 1 0 0 1 0 1 1 0 0\n\
          EDGE2 1 2 1 0 0 1 0 1 1 0 0\nEQUIV 0 2\nEQUIV 1 2\n",
    );
    for tool in ["pgo-solve", "pgo-certify", "pgo-spectrum", "pgo-convert"] {
        let out = common::run_with_stdin(tool, &[s(&input)], None);
        assert_eq!(out.status.code(), Some(2), "{tool}");
        let err = text(&out.stderr);
        assert!(
            err.starts_with(&format!("{}:6:1: error: EQUIV", s(&input))),
            "{tool}: {err}"
        );
        assert!(err.contains("--ignore-equiv"), "{tool}: {err}");
        assert!(out.stdout.is_empty(), "{tool}");
        // Skipping them and being strict contradict each other.
        let out = common::run_with_stdin(tool, &[s(&input), "--ignore-equiv", "--strict"], None);
        assert_eq!(out.status.code(), Some(2), "{tool}");
    }
    let warning = format!(
        "{}:6:1: warning: EQUIV (vertex equivalence) is not supported: 2 lines skipped (first here); the graph is read without them",
        s(&input)
    );
    for tool in ["pgo-solve", "pgo-certify", "pgo-spectrum"] {
        let out = common::run_with_stdin(tool, &[s(&input), "--ignore-equiv", "--json"], None);
        // pgo-certify: the file's own vertices are optimal (a chain fits exactly).
        assert_eq!(out.status.code(), Some(0), "{tool}: {}", text(&out.stderr));
        assert!(text(&out.stderr).starts_with(&warning), "{tool}");
        let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(r["warnings"], serde_json::json!([warning]), "{tool}");
        assert_eq!(r["poses"], 3, "{tool}");
    }
    // Without warnings, no `warnings` field.
    let clean = dir.file(
        "clean.g2o",
        format!("{V}EDGE_SE2 0 1 1 0 0 {INFO}\n").as_bytes(),
    );
    let out = common::run_with_stdin("pgo-solve", &[s(&clean), "--json", "-o", "-"], None);
    let json = text(&out.stdout).lines().last().unwrap().to_string();
    let r: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!(r.get("warnings").is_none(), "{r}");
}

/// A graph without poses is an error of the library entries too (the readers never give one).
#[test]
fn the_library_refuses_an_empty_graph() {
    let empty = pgo::PoseGraph::with_edges(vec![], vec![]);
    let err = pgo::solve::solve(&empty, &Default::default()).unwrap_err();
    assert!(err.to_string().contains("no poses"), "{err}");
    let err = pgo::solve::certify_estimate(&empty, &[], &Default::default(), "x").unwrap_err();
    assert!(err.to_string().contains("no poses"), "{err}");
    let options = pgo::spectrum::SpectrumOptions {
        weights: pgo::problem::weights::Weights::Unit,
        count: 0,
        solver: pgo::dual::solver::SdpSolver::Ipm,
    };
    let err = pgo::spectrum::spectrum(&empty, &options).unwrap_err();
    assert!(err.to_string().contains("no poses"), "{err}");
}
