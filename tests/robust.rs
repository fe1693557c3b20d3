//! Robust estimation (`pgo::robust`, `pgo-solve --robust`, `pgo-simulate --corrupt`) against
//! planted truth: false loop closures added by Vertigo's models to a graph whose clean optimum is
//! computed by a separate, plain solve. GNC must reject exactly the planted edges, and the inlier
//! set's certified optimum must be the clean graph's.

mod common;

use pgo::linalg::rng::Rng;
use pgo::robust::outliers::{OutlierConfig, OutlierModel, add_outliers};
use pgo::robust::{Loss, RobustOptions, robust_solve};
use pgo::{Edge, Pose2, PoseGraph, SymMat3};
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// A robot's walk over an 8 x 8 grid of 2 m cells (lawnmower order), twice: poses k and k + 64
/// stand on the same cell, and every other pose of the second lap closes a loop to the first.
/// Measurements are the true relative poses plus Gaussian noise of 0.02 m and 0.004 rad; they
/// carry the information diag(1/0.05², 1/0.05², 1/0.01²), of a noise 2.5 times larger (a
/// conservative front end), so that no true edge comes near the inlier threshold: with noise as
/// large as the information says, 1% of the inliers would exceed the default threshold, which
/// these tests do not measure.
fn walk() -> PoseGraph {
    let mut truth = Vec::new();
    for _lap in 0..2 {
        for row in 0..8 {
            for k in 0..8 {
                let col = if row % 2 == 0 { k } else { 7 - k };
                let heading = if row % 2 == 0 {
                    0.0
                } else {
                    std::f64::consts::PI
                };
                truth.push(Pose2::new(2.0 * col as f64, 2.0 * row as f64, heading));
            }
        }
    }
    let (st, sr) = (0.05, 0.01);
    let info = SymMat3([
        1.0 / (st * st),
        0.0,
        0.0,
        1.0 / (st * st),
        0.0,
        1.0 / (sr * sr),
    ]);
    let mut rng = Rng::new(7);
    let mut measure = |a: Pose2, b: Pose2| {
        let z = Pose2::from_isometry(&a.to_isometry().inv_mul(&b.to_isometry()));
        Pose2::new(
            z.x + 0.4 * st * rng.normal(),
            z.y + 0.4 * st * rng.normal(),
            z.theta + 0.4 * sr * rng.normal(),
        )
    };
    let mut edges = Vec::new();
    for k in 0..truth.len() - 1 {
        edges.push(Edge {
            i: k,
            j: k + 1,
            measurement: measure(truth[k], truth[k + 1]),
            noise: info,
        });
    }
    for k in (0..64).step_by(2) {
        edges.push(Edge {
            i: k,
            j: k + 64,
            measurement: measure(truth[k], truth[k + 64]),
            noise: info,
        });
    }
    let mut g = PoseGraph::with_edges(truth, edges);
    // The composed odometry as the initial guess, as a front end writes it.
    g.vertices_declared = false;
    g.initialize_spanning_tree();
    g.vertices_declared = true;
    g
}

fn run(tool: &str, args: &[&str]) -> Output {
    let exe = match tool {
        "pgo-solve" => env!("CARGO_BIN_EXE_pgo-solve"),
        "pgo-simulate" => env!("CARGO_BIN_EXE_pgo-simulate"),
        _ => unreachable!(),
    };
    Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn ok(tool: &str, args: &[&str]) -> Output {
    let out = run(tool, args);
    assert!(
        out.status.success(),
        "{tool} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn read(path: &Path) -> PoseGraph {
    pgo::io::read_path(path.to_str().unwrap(), &Default::default())
        .unwrap()
        .0
}

fn write(graph: &PoseGraph, path: &Path) {
    let options = pgo::io::WriteOptions {
        format: pgo::io::Format::G2o,
        dialect: pgo::io::Dialect::G2o,
    };
    pgo::io::write_path(graph, options, path.to_str().unwrap()).unwrap();
}

fn same_edges(a: &PoseGraph, b: &PoseGraph) -> bool {
    a.edges.len() == b.edges.len()
        && a.edges.iter().zip(&b.edges).all(|(x, y)| {
            (a.ids[x.i], a.ids[x.j], x.measurement, x.noise)
                == (b.ids[y.i], b.ids[y.j], y.measurement, y.noise)
        })
}

/// intel.g2o plus 100 random outliers: every one rejected, no true edge, and the certified
/// optimum of the inliers is the clean file's optimum (a separate plain solve).
#[test]
fn intel_with_100_random_outliers() {
    let path = common::datasets_dir().join("intel.g2o");
    let clean = read(&path);
    let mut corrupted = clean.clone();
    let config = OutlierConfig {
        count: 100,
        model: OutlierModel::Random,
        group: 1,
        noise: None,
        seed: 1,
    };
    let planted = add_outliers(&mut corrupted, &config).unwrap();
    let r = robust_solve(&corrupted, &RobustOptions::default()).unwrap();
    let rejected: Vec<usize> = (0..corrupted.edges.len())
        .filter(|&k| r.rejected[k])
        .collect();
    assert_eq!(rejected, planted);
    let reference = pgo::solve(&clean, &Default::default()).unwrap();
    assert!(reference.certified && r.solution.certified);
    assert!(
        (r.solution.cost - reference.cost).abs() <= 1e-9 * reference.cost,
        "{} vs {}",
        r.solution.cost,
        reference.cost
    );
    for (a, b) in r.solution.estimate.iter().zip(&reference.estimate) {
        assert!((a.x - b.x).abs() < 1e-6 && (a.y - b.y).abs() < 1e-6);
    }
    // The inner problems' certificates (off by default) decide nothing GNC does: with them the
    // same iterations, inliers and estimate, and every inner problem checked; the late ones,
    // with the outliers' weights at 0, are the clean problem's and certify.
    assert!(r.iterations.iter().all(|i| i.certified.is_none()));
    let checked = RobustOptions {
        certify_inner: true,
        ..Default::default()
    };
    let c = robust_solve(&corrupted, &checked).unwrap();
    assert_eq!(c.rejected, r.rejected);
    assert_eq!(c.iterations.len(), r.iterations.len());
    for (a, b) in c.iterations.iter().zip(&r.iterations) {
        assert_eq!(a.weighted_cost, b.weighted_cost);
        assert!(a.certified.is_some());
    }
    assert_eq!(c.iterations.last().unwrap().certified, Some(true));
    assert_eq!(c.solution.estimate, r.solution.estimate);
}

/// The tools end to end, for both losses: outliers planted by `pgo-simulate --corrupt` (local
/// groups and random pairs), rejected by line exactly as listed, `-o` lossless, `--drop-outliers`
/// the clean graph's edges, and the clean optimum certified.
#[test]
fn tools_reject_the_listed_outliers() {
    let dir = tempfile::tempdir().unwrap();
    let clean_path = dir.path().join("clean.g2o");
    write(&walk(), &clean_path);
    let clean = read(&clean_path);
    let reference = pgo::solve(&clean, &Default::default()).unwrap();
    assert!(reference.certified);
    for (model, group, loss) in [("local", "3", "tls"), ("random", "1", "gm")] {
        let bad = dir.path().join("bad.g2o");
        let list = dir.path().join("list.txt");
        ok(
            "pgo-simulate",
            &[
                "--corrupt",
                clean_path.to_str().unwrap(),
                "--outliers",
                "8",
                "--outlier-model",
                model,
                "--group",
                group,
                "--seed",
                "3",
                "-q",
                "-o",
                bad.to_str().unwrap(),
                "--outlier-list",
                list.to_str().unwrap(),
            ],
        );
        let listed: Vec<(usize, u32, u32)> = std::fs::read_to_string(&list)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                (
                    f[0].parse().unwrap(),
                    f[1].parse().unwrap(),
                    f[2].parse().unwrap(),
                )
            })
            .collect();
        assert_eq!(listed.len(), 8 * group.parse::<usize>().unwrap());
        // The listed lines hold edges between the listed ids.
        let text = std::fs::read_to_string(&bad).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for &(line, i, j) in &listed {
            let f: Vec<&str> = lines[line - 1].split_whitespace().collect();
            assert_eq!(
                (f[0], f[1], f[2]),
                ("EDGE_SE2", &*i.to_string(), &*j.to_string())
            );
        }
        let all = dir.path().join("all.g2o");
        let inliers = dir.path().join("inliers.g2o");
        let out = ok(
            "pgo-solve",
            &[
                bad.to_str().unwrap(),
                "--robust",
                loss,
                "--json",
                "--no-timings",
                "-o",
                all.to_str().unwrap(),
            ],
        );
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let rejected: Vec<(usize, u32, u32)> = json["robust"]["rejected_edges"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| {
                (
                    e["line"].as_u64().unwrap() as usize,
                    e["i"].as_u64().unwrap() as u32,
                    e["j"].as_u64().unwrap() as u32,
                )
            })
            .collect();
        assert_eq!(rejected, listed, "{model} {loss}");
        assert_eq!(json["robust"]["rejected"], listed.len());
        assert_eq!(json["certified"], true);
        let cost = json["cost"].as_f64().unwrap();
        assert!((cost - reference.cost).abs() <= 1e-9 * reference.cost);
        assert!(same_edges(&read(&all), &read(&bad)));
        ok(
            "pgo-solve",
            &[
                bad.to_str().unwrap(),
                "--robust",
                loss,
                "--drop-outliers",
                "-o",
                inliers.to_str().unwrap(),
            ],
        );
        assert!(same_edges(&read(&inliers), &clean));
    }
}

/// Without outliers nothing of the walk is rejected. With every edge uncertain (odometry
/// included) GNC is not guaranteed to find the planted outliers (on this graph it missed some
/// and rejected odometry edges while developing this test): the test holds only what is
/// reported, the inlier set's problem,
/// against a separate plain solve of the graph without the rejected edges. The same flags give
/// the same bytes.
#[test]
fn no_outliers_all_edges_uncertain_and_reproducible() {
    let clean = walk();
    let r = robust_solve(&clean, &RobustOptions::default()).unwrap();
    assert_eq!(r.rejected_count(), 0);
    let mut bad = clean.clone();
    add_outliers(
        &mut bad,
        &OutlierConfig {
            count: 10,
            model: OutlierModel::Random,
            group: 1,
            noise: None,
            seed: 11,
        },
    )
    .unwrap();
    let options = RobustOptions {
        odometry_inliers: false,
        loss: Loss::Tls,
        ..Default::default()
    };
    let r = robust_solve(&bad, &options).unwrap();
    assert!(r.uncertain.iter().all(|&u| u));
    let mut inliers = bad.clone();
    inliers.edges = (0..bad.edges.len())
        .filter(|&k| !r.rejected[k])
        .map(|k| bad.edges[k])
        .collect();
    let plain = pgo::solve(&inliers, &Default::default()).unwrap();
    assert_eq!(plain.edges, r.solution.edges);
    assert!((plain.cost - r.solution.cost).abs() <= 1e-9 * plain.cost.max(1.0));
    assert_eq!(plain.certified, r.solution.certified);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.g2o");
    write(&bad, &path);
    let args = [
        path.to_str().unwrap(),
        "--robust",
        "tls",
        "--json",
        "--no-timings",
        "-o",
        "-",
    ];
    let a = ok("pgo-solve", &args).stdout;
    let b = ok("pgo-solve", &args).stdout;
    assert_eq!(a, b);
}

/// Bad flags: a message and exit 2, no panic.
#[test]
fn bad_flags_exit_2() {
    let mit = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/MIT.g2o");
    let cases: &[(&str, &[&str])] = &[
        ("pgo-solve", &[mit, "--robust", "huber"]),
        (
            "pgo-solve",
            &[mit, "--robust", "tls", "--inlier-threshold", "-1"],
        ),
        (
            "pgo-solve",
            &[mit, "--robust", "tls", "--inlier-threshold", "nan"],
        ),
        ("pgo-solve", &[mit, "--drop-outliers"]),
        ("pgo-solve", &[mit, "--all-edges-uncertain"]),
        ("pgo-solve", &[mit, "--inlier-threshold", "3"]),
        ("pgo-simulate", &["--outliers", "3"]),
        ("pgo-simulate", &["--corrupt", mit]),
        (
            "pgo-simulate",
            &["--corrupt", mit, "--outliers", "3", "-n", "5"],
        ),
        ("pgo-simulate", &["--corrupt", mit, "--outliers", "-3"]),
        (
            "pgo-simulate",
            &["--corrupt", mit, "--outliers", "3", "--group", "0"],
        ),
        (
            "pgo-simulate",
            &[
                "--corrupt",
                mit,
                "--outliers",
                "3",
                "--outlier-model",
                "near",
            ],
        ),
        (
            "pgo-simulate",
            &["--corrupt", "/nonexistent/x.g2o", "--outliers", "3"],
        ),
        (
            "pgo-simulate",
            &[
                "--corrupt",
                mit,
                "--outliers",
                "1",
                "--group",
                "900",
                "-o",
                "/dev/null",
            ],
        ),
    ];
    for (tool, args) in cases {
        let out = run(tool, args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{tool} {args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{tool} {args:?}: {stderr}");
        assert!(!stderr.trim().is_empty());
    }
}

/// Vertigo's measurement model, by sample statistics of many outliers: x, y ~ N(0, 0.3) and
/// θ ~ N(0, 10°); random pairs never consecutive.
#[test]
fn outlier_measurements_follow_vertigo() {
    let mut g = walk();
    let before = g.edges.len();
    let added = add_outliers(
        &mut g,
        &OutlierConfig {
            count: 20000,
            model: OutlierModel::Random,
            group: 1,
            noise: None,
            seed: 5,
        },
    )
    .unwrap();
    assert_eq!(added.len(), 20000);
    let std = |f: &dyn Fn(&Edge) -> f64| {
        let v: Vec<f64> = g.edges[before..].iter().map(f).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        assert!(mean.abs() < 0.02, "mean {mean}");
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
    };
    let sx = std(&|e| e.measurement.x);
    let sy = std(&|e| e.measurement.y);
    let st = std(&|e| e.measurement.theta);
    // The standard deviation of a sample of 20000 has a relative standard error of 0.5%.
    assert!(
        (sx / 0.3 - 1.0).abs() < 0.025 && (sy / 0.3 - 1.0).abs() < 0.025,
        "{sx} {sy}"
    );
    assert!((st / 10f64.to_radians() - 1.0).abs() < 0.025, "{st}");
    assert!(g.edges[before..].iter().all(|e| e.j >= e.i + 2));
}
