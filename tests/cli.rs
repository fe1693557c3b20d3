//! `pgo-convert` as a user runs it: every validation error with its PATH:LINE:COL and exit
//! status 2, warnings, the layout the reader tolerates, stdin/stdout, atomic output.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn pgo_convert() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pgo-convert"))
}

fn run(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut cmd = pgo_convert();
    cmd.args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().unwrap();
    {
        use std::io::Write;
        let mut input = child.stdin.take().unwrap();
        if let Some(bytes) = stdin {
            input.write_all(bytes).unwrap();
        }
    }
    child.wait_with_output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

struct Dir(tempfile::TempDir);

impl Dir {
    fn new() -> Self {
        Dir(tempfile::tempdir().unwrap())
    }
    fn file(&self, name: &str, content: &[u8]) -> PathBuf {
        let p = self.0.path().join(name);
        std::fs::write(&p, content).unwrap();
        p
    }
    fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }
    fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(self.0.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const V: &str = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
const INFO: &str = "1 0 0 1 0 1";

/// Each malformed input gives `PATH:LINE:COL: error: ...` with the message, exit status 2, and
/// leaves an existing output file untouched and no temporary file behind.
#[test]
fn every_validation_error_has_its_location_and_status_2() {
    let cases: Vec<(String, &str, &str)> = vec![
        (
            format!("{V}EDGE_SE2 0 1 1 0 0 1 0 0 1 0\n"),
            "3:29",
            "EDGE_SE2 takes 11 fields",
        ),
        (
            format!("{V}EDGE_SE2 0 1 1 0 0 {INFO} 7\n"),
            "3:32",
            "found 12",
        ),
        (
            "VERTEX_SE2 0 1 2\n".into(),
            "1:17",
            "VERTEX_SE2 takes 4 fields",
        ),
        (
            format!("{V}EDGE_SE2 0 1 nan 0 0 {INFO}\n"),
            "3:14",
            "non-finite",
        ),
        (
            format!("{V}EDGE_SE2 0 1 1 inf 0 {INFO}\n"),
            "3:16",
            "non-finite",
        ),
        (
            format!("{V}EDGE_SE2 0 1 1e400 0 0 {INFO}\n"),
            "3:14",
            "overflows",
        ),
        (
            format!("{V}EDGE_SE2 0 1 0,5 0 0 {INFO}\n"),
            "3:14",
            "decimal comma",
        ),
        (
            format!("{V}EDGE_SE2 0 1 0x10 0 0 {INFO}\n"),
            "3:14",
            "hexadecimal",
        ),
        ("VERTEX_SE2 -1 0 0 0\n".into(), "1:12", "cannot be negative"),
        ("VERTEX_SE2 1.5 0 0 0\n".into(), "1:12", "ids are integers"),
        (
            "VERTEX_SE2 2147483648 0 0 0\n".into(),
            "1:12",
            "at most 2^31 - 1",
        ),
        (
            format!("{V}VERTEX_SE2 0 5 5 5\n"),
            "3:12",
            "vertex 0 is declared twice (first at line 1)",
        ),
        (
            format!("{V}EDGE_SE2 0 7 1 0 0 {INFO}\n"),
            "3:12",
            "vertex 7, which no vertex line declares",
        ),
        (
            format!("{V}EDGE_SE2 1 1 1 0 0 {INFO}\n"),
            "3:12",
            "self-loop",
        ),
        (
            format!("{V}EDGE_SE2 0 1 1 0 0 1 -2 0 -1 0 1\n"),
            "3:20",
            "not positive definite",
        ),
        (
            format!("{V}EDGE_SE2 0 1 1 0 0 1 0 0 1 0 0\n"),
            "3:20",
            "not positive definite",
        ),
        (format!("{V}FIX 9\n"), "3:5", "FIX names vertex 9"),
        (
            "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n".into(),
            "1:1",
            "3D pose graphs are not supported",
        ),
        (
            "EDGE3 0 1 0 0 0 0 0 0\n".into(),
            "1:1",
            "3D pose graphs are not supported",
        ),
        (
            format!("{V}VERTEX_XY 5 1 2\n"),
            "3:1",
            "landmarks are not supported",
        ),
        (
            format!("{V}LANDMARK 0 5 1 2 1 0 1\n"),
            "3:1",
            "landmarks are not supported",
        ),
        (
            format!("{V}EDGE_PRIOR_SE2 0 0 0 0 {INFO}\n"),
            "3:1",
            "unary priors are not supported",
        ),
        (
            format!("{V}EDGE_SE2 0 1 1 0 0 {INFO}\nEDGE2 0 1 1 0 0 {INFO}\n"),
            "4:1",
            "edge tags of both formats",
        ),
        (
            "\u{feff}VERTEX_SE2 0 0 0 x\n".to_string(),
            "1:18",
            "expected a number, found 'x'",
        ),
    ];
    for (content, at, needle) in cases {
        let dir = Dir::new();
        let input = dir.file("in.g2o", content.as_bytes());
        let output = dir.file("out.g2o", b"precious\n");
        let out = run(&[s(&input), "-o", s(&output)], None);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{content:?}: {err}");
        let prefix = format!("{}:{at}: error: ", s(&input));
        assert!(
            err.starts_with(&prefix),
            "{content:?}\nwant {prefix}\ngot  {err}"
        );
        assert!(
            err.contains(needle),
            "{content:?}: want {needle:?} in {err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
        assert_eq!(
            std::fs::read(&output).unwrap(),
            b"precious\n",
            "{content:?}"
        );
        assert_eq!(dir.entries(), ["in.g2o", "out.g2o"], "{content:?}");
        assert!(out.stdout.is_empty());
    }
}

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
        format!("{V}FOO 1 2\nEDGE_SE2 0 1 1 0 0 {INFO}\nFOO 3\nEQUIV 0 1\n").as_bytes(),
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
    assert!(err.contains(":6:1: warning: EQUIV"), "{err}");
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
fn writing_to_a_device_writes_through_it() {
    // `-o /dev/null` must not rename a temporary file over the device (that would replace
    // /dev/null with a regular file for the whole machine); devices and FIFOs are written in place.
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("g.g2o");
    std::fs::write(
        &input,
        "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n",
    )
    .unwrap();
    let out = run(&[s(&input), "-o", "/dev/null"], None);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let meta = std::fs::metadata("/dev/null").unwrap();
    assert!(
        meta.file_type().is_char_device(),
        "/dev/null is no longer a device"
    );
    for solve_args in [["--method", "staircase"], ["--method", "sdp"]] {
        let out = Command::new(env!("CARGO_BIN_EXE_pgo-solve"))
            .arg(&input)
            .args(solve_args)
            .args(["--json", "-o", "/dev/null"])
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", text(&out.stderr));
        let meta = std::fs::metadata("/dev/null").unwrap();
        assert!(meta.file_type().is_char_device());
    }
}
