//! `pgo-solve --refine --marginals OUT`: the file written (one line per pose by id, the held pose
//! zero, every block a covariance), byte-identical whatever the thread count, and the flags it
//! refuses before any work (exit status 2). Agreement with GTSAM's `Marginals` is checked in
//! tests/interop/test_marginals.py; the algebra in `pgo::refine::marginals`' unit tests.

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn solve(args: &[&str], threads: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgo-solve"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap()
}

/// (id, upper triangle) per line after the comment line.
fn read(path: &Path) -> Vec<(u64, [f64; 6])> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("# id c11 c12 c13 c22 c23 c33")
    );
    lines
        .map(|l| {
            let t: Vec<&str> = l.split(' ').collect();
            assert_eq!(t.len(), 7, "{l}");
            let v: Vec<f64> = t[1..].iter().map(|x| x.parse().unwrap()).collect();
            (t[0].parse().unwrap(), v.try_into().unwrap())
        })
        .collect()
}

#[test]
fn mit_marginals_are_covariances_by_id_and_thread_independent() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("cov{threads}.txt"));
        let o = solve(
            &[
                "datasets/MIT.g2o",
                "--refine",
                "--marginals",
                out.to_str().unwrap(),
                "-o",
                "/dev/null",
            ],
            threads,
        );
        assert!(o.status.success(), "{o:?}");
        bytes.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(bytes[0], bytes[1], "thread count changed the bytes");
    let rows = read(&dir.path().join("cov1.txt"));
    assert_eq!(rows.len(), 808);
    assert!(rows.windows(2).all(|w| w[0].0 < w[1].0), "sorted by id");
    assert_eq!(rows[0].1, [0.0; 6], "the held (first) pose");
    for (id, [a, b, c, d, e, f]) in &rows[1..] {
        // Positive definite: the leading minors.
        let m2 = a * d - b * b;
        let m3 = a * (d * f - e * e) - b * (b * f - e * c) + c * (b * e - d * c);
        assert!(*a > 0.0 && m2 > 0.0 && m3 > 0.0, "pose {id}");
    }
    // Uncertainty grows away from the held pose: the last pose is less certain than the second.
    assert!(rows[807].1[0] > rows[1].1[0]);
}

#[test]
fn a_fix_pose_is_the_held_one() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("fix.g2o");
    let mut text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/MIT.g2o"))
            .unwrap();
    text.push_str("FIX 100\n");
    std::fs::write(&input, text).unwrap();
    let out = dir.path().join("cov.txt");
    let o = solve(
        &[
            input.to_str().unwrap(),
            "--refine",
            "--marginals",
            out.to_str().unwrap(),
            "-o",
            "/dev/null",
        ],
        "1",
    );
    assert!(o.status.success(), "{o:?}");
    let rows = read(&out);
    for (id, c) in rows {
        assert_eq!(c == [0.0; 6], id == 100, "pose {id}");
    }
}

#[test]
fn bad_uses_are_refused_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/dir/cov.txt");
    let landmarks = dir.path().join("landmarks.g2o");
    std::fs::write(
        &landmarks,
        "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_XY 7 0.5 0.5\n\
         EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2_XY 0 7 0.5 0.5 1 0 1\nEDGE_SE2_XY 1 7 -0.5 0.5 1 0 1\n",
    )
    .unwrap();
    let cov = dir.path().join("cov.txt");
    let cases: [(Vec<&str>, &str); 4] = [
        (
            vec!["datasets/MIT.g2o", "--marginals", cov.to_str().unwrap()],
            "--refine",
        ),
        (
            vec![
                "datasets/MIT.g2o",
                "--refine",
                "--marginals",
                missing.to_str().unwrap(),
            ],
            "does not exist",
        ),
        (
            vec!["datasets/MIT.g2o", "--refine", "--marginals", "-"],
            "needs a file",
        ),
        (
            vec![
                landmarks.to_str().unwrap(),
                "--refine",
                "--marginals",
                cov.to_str().unwrap(),
            ],
            "landmarks",
        ),
    ];
    for (args, message) in cases {
        let o = solve(&args, "1");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert!(o.stdout.is_empty(), "{args:?}: nothing solved or written");
        assert!(!cov.exists());
    }
    // Nothing left behind in the directory but the landmark file.
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1);
}
