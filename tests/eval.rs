//! pgo-eval held to hand computations: a rigidly moved copy has no error once aligned, a known
//! offset is measured as such, and bad requests are errors (exit 2) that name the problem.

use std::process::{Command, Output};

fn eval(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgo-eval"))
        .args(args)
        .output()
        .unwrap()
}

fn json(out: &Output) -> serde_json::Value {
    assert!(out.status.success(), "{out:?}");
    serde_json::from_slice(&out.stdout).unwrap()
}

fn write(dir: &tempfile::TempDir, name: &str, poses: &[(u32, f64, f64, f64)]) -> String {
    let mut text = String::new();
    for &(id, x, y, th) in poses {
        text.push_str(&format!("VERTEX_SE2 {id} {x:?} {y:?} {th:?}\n"));
    }
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn a_moved_copy_aligns_to_zero_and_an_offset_is_measured() {
    let dir = tempfile::tempdir().unwrap();
    let truth: Vec<(u32, f64, f64, f64)> = (0..6)
        .map(|k| (k, k as f64, (k * k) as f64 * 0.1, 0.2 * k as f64))
        .collect();
    // The copy moved by 30 degrees and (5, -1), plus one pose (id 9) the truth lacks.
    let (s, c) = 30f64.to_radians().sin_cos();
    let mut moved: Vec<(u32, f64, f64, f64)> = truth
        .iter()
        .map(|&(id, x, y, th)| {
            (
                id,
                c * x - s * y + 5.0,
                s * x + c * y - 1.0,
                th + 30f64.to_radians(),
            )
        })
        .collect();
    moved.push((9, 0.0, 0.0, 0.0));
    let gt = write(&dir, "gt.g2o", &truth);
    let est = write(&dir, "est.g2o", &moved);
    let r = json(&eval(&[&est, &gt, "--json"]));
    assert_eq!(r["matched"], 6);
    assert_eq!(r["estimate_poses"], 7);
    assert!(
        r["ape"]["translation"]["max"].as_f64().unwrap() < 1e-12,
        "{r}"
    );
    assert!(
        r["ape"]["rotation_deg"]["max"].as_f64().unwrap() < 1e-10,
        "{r}"
    );
    assert!((r["alignment"]["angle"].as_f64().unwrap() + 30f64.to_radians()).abs() < 1e-12);
    // Without alignment the error is the motion itself: |R p + t − p| per pose.
    let r = json(&eval(&[&est, &gt, "--json", "--no-align"]));
    assert!(r.get("alignment").is_none());
    let moves: Vec<f64> = truth
        .iter()
        .zip(&moved)
        .map(|(a, b)| (b.1 - a.1).hypot(b.2 - a.2))
        .collect();
    let max = moves.iter().cloned().fold(0.0, f64::max);
    let mean = moves.iter().sum::<f64>() / moves.len() as f64;
    assert!((moves[0] - 26f64.sqrt()).abs() < 1e-12);
    assert!((r["ape"]["translation"]["max"].as_f64().unwrap() - max).abs() < 1e-12);
    assert!((r["ape"]["translation"]["mean"].as_f64().unwrap() - mean).abs() < 1e-12);
    assert!((r["ape"]["rotation_deg"]["mean"].as_f64().unwrap() - 30.0).abs() < 1e-10);
    // The relative motion is unchanged by a rigid motion: RPE 0 either way.
    assert!(r["rpe"]["translation"]["max"].as_f64().unwrap() < 1e-12);
    assert_eq!(r["rpe"]["translation"]["count"], 5);
}

#[test]
fn bad_requests_exit_2_with_a_reason() {
    let dir = tempfile::tempdir().unwrap();
    let a = write(&dir, "a.g2o", &[(0, 0.0, 0.0, 0.0), (1, 1.0, 0.0, 0.0)]);
    let b = write(&dir, "b.g2o", &[(5, 0.0, 0.0, 0.0)]);
    let one = write(&dir, "one.g2o", &[(1, 0.0, 0.0, 0.0)]);
    let edges = dir.path().join("edges.g2o");
    std::fs::write(&edges, "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n").unwrap();
    let edges = edges.to_str().unwrap();
    for (args, says) in [
        (vec![&a[..], &b], "no vertex id in common"),
        (vec![&a[..], edges], "no vertex lines"),
        (vec![&a[..], "/nonexistent/x.g2o"], "/nonexistent/x.g2o"),
        (vec![&a[..], &a, "--delta", "0"], "--delta"),
    ] {
        let out = eval(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {out:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
    // One pose in common: moved onto its reference (no rotation); RPE then has no pair.
    let r = json(&eval(&[&a, &one, "--json"]));
    assert_eq!(r["matched"], 1);
    // Pose 1 is at (1, 0) in a.g2o and at (0, 0) in one.g2o.
    assert_eq!(
        (&r["alignment"]["x"], &r["alignment"]["angle"]),
        (&(-1.0).into(), &0.0.into())
    );
    assert_eq!(r["ape"]["translation"]["max"], 0.0);
    assert!(r.get("rpe").is_none());
}
