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

#[test]
fn trajectories_for_evo_and_their_refusals() {
    let dir = tempfile::tempdir().unwrap();
    let g = write(&dir, "g.g2o", &[(4, 1.0, 2.0, 0.0), (2, -1.0, 0.5, 3.0)]);
    let convert = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_pgo-convert"))
            .args(args)
            .output()
            .unwrap()
    };
    // Sorted by id; the id is the time stamp unless --stamps gives one.
    let out = convert(&[&g, "--to", "tum", "-q"]);
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8(out.stdout).unwrap();
    let stamps: Vec<&str> = text.lines().map(|l| l.split(' ').next().unwrap()).collect();
    assert_eq!(stamps, ["2", "4"]);
    let stamp_file = dir.path().join("stamps.txt");
    std::fs::write(&stamp_file, "# id stamp\n2 10.5\n4 11\n").unwrap();
    let stamp_file = stamp_file.to_str().unwrap();
    let out = convert(&[&g, "--to", "tum", "--stamps", stamp_file, "-q"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("10.5 -1 0.5 0 0 0 ") && text.contains("\n11 1 2 0 0 0 0 1\n"));
    // Refusals: exit 2, a reason, and no file left behind.
    std::fs::write(dir.path().join("short.txt"), "2 10.5\n").unwrap();
    let short = dir.path().join("short.txt");
    let target = dir.path().join("out.tum");
    let target = target.to_str().unwrap();
    for (args, says) in [
        (
            vec![
                &g[..],
                "--to",
                "tum",
                "--stamps",
                short.to_str().unwrap(),
                "-o",
                target,
            ],
            "no time stamp for vertex 4",
        ),
        (
            vec![&g[..], "--stamps", stamp_file, "-o", target],
            "--stamps is for --to tum",
        ),
        (
            vec![&g[..], "--to", "kitti", "--to-dialect", "g2o", "-o", target],
            "poses only",
        ),
    ] {
        let out = convert(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {out:?}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(says),
            "{out:?}"
        );
        assert!(!std::path::Path::new(target).exists());
    }
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "2 x\n").unwrap();
    let out = convert(&[&g, "--to", "tum", "--stamps", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("bad.txt:1: 'x' is not a finite time stamp")
    );
}
