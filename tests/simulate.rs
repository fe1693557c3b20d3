//! `pgo-simulate` and `pgo::simulate` against facts that do not depend on the implementation:
//! reproducibility, balance of noiseless graphs (every edge is x_i⁻¹·x_j of the ground truth, so
//! every cycle composes to the identity), the edge counts of the model (checked by
//! `pgo-convert --stats`), and the sample statistics of the noise of eq. (47).

mod common;

use nalgebra::Isometry2;
use pgo::simulate::{RotationNoise, SimulationConfig, TranslationNoise, simulate, wrap_angle};
use pgo::{Pose2, PoseGraph};
use std::f64::consts::PI;
use std::process::{Command, Output, Stdio};

fn simulate_cli(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgo-simulate"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn ok_stdout(args: &[&str]) -> Vec<u8> {
    let out = simulate_cli(args);
    assert!(
        out.status.success(),
        "pgo-simulate {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// `pgo-convert --stats --json` of a graph file's bytes fed on stdin.
fn stats_json(bytes: &[u8]) -> serde_json::Value {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_pgo-convert"))
        .args(["--stats", "--json", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(bytes).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn config(
    n: usize,
    p: f64,
    rot: RotationNoise,
    tra: TranslationNoise,
    seed: u64,
) -> SimulationConfig {
    SimulationConfig {
        n,
        side: 10.0,
        loop_probability: p,
        rotation_noise: rot,
        translation_noise: tra,
        seed,
        ..Default::default()
    }
}

const NOISELESS_R: RotationNoise = RotationNoise::Gaussian { sigma: 0.0 };
const NOISELESS_T: TranslationNoise = TranslationNoise::Gaussian { sigma: 0.0 };

/// x_i⁻¹ · x_j by nalgebra, independently of the simulator's arithmetic.
fn relative(a: Pose2, b: Pose2) -> Pose2 {
    Pose2::from_isometry(&(a.to_isometry().inverse() * b.to_isometry()))
}

/// The angle between two angles, in [0, π].
fn angle_diff(a: f64, b: f64) -> f64 {
    wrap_angle(a - b).abs()
}

/// Translation noise of every edge: Δ_ij − R_iᵀ(p_j − p_i) (nalgebra), and rotation noise
/// wrap(θ_ij − (θ_j − θ_i)).
fn noise_samples(g: &PoseGraph, truth: &[Pose2]) -> (Vec<[f64; 2]>, Vec<f64>) {
    let mut t = Vec::new();
    let mut r = Vec::new();
    for e in &g.edges {
        let (a, b) = (truth[e.i], truth[e.j]);
        let rel = relative(a, b);
        t.push([e.measurement.x - rel.x, e.measurement.y - rel.y]);
        r.push(wrap_angle(e.measurement.theta - (b.theta - a.theta)));
    }
    (t, r)
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

#[test]
fn same_seed_same_bytes_different_seed_different_bytes() {
    let a = ok_stdout(&["-n", "30", "--seed", "42"]);
    let b = ok_stdout(&["-n", "30", "--seed", "42"]);
    let c = ok_stdout(&["-n", "30", "--seed", "43"]);
    assert!(!a.is_empty());
    assert_eq!(a, b);
    assert_ne!(a, c);
    // The library gives the same graph as the tool writes.
    let g = common::naive_read(&a);
    let sim = simulate(&SimulationConfig {
        n: 30,
        seed: 42,
        ..Default::default()
    });
    assert_eq!(g.vertices.len(), 30);
    for ((id, v), (k, p)) in g.vertices.iter().zip(sim.truth.iter().enumerate()) {
        assert_eq!(*id as usize, k);
        assert_eq!(common::bits(v), common::bits(&p.values()));
    }
    assert_eq!(g.edges.len(), sim.graph.edges.len());
    for ((i, j, z, info), e) in g.edges.iter().zip(&sim.graph.edges) {
        assert_eq!((*i as usize, *j as usize), (e.i, e.j));
        assert_eq!(common::bits(z), common::bits(&e.measurement.values()));
        assert_eq!(*info, [1.0, 0.0, 0.0, 1.0, 0.0, 1.0]);
    }
}

/// The ground truth depends only on n, side and seed; the edge set not on the noise (the
/// documented stream split).
#[test]
fn truth_and_topology_do_not_depend_on_later_choices() {
    let base = simulate(&config(25, 0.1, NOISELESS_R, NOISELESS_T, 9));
    let other = simulate(&config(
        25,
        0.5,
        RotationNoise::Uniform,
        TranslationNoise::Uniform { half_width: 5.0 },
        9,
    ));
    assert_eq!(base.truth, other.truth);
    let noisy = simulate(&config(
        25,
        0.1,
        RotationNoise::Uniform,
        TranslationNoise::Gaussian { sigma: 1.0 },
        9,
    ));
    let pairs = |s: &pgo::simulate::Simulated| -> Vec<(usize, usize)> {
        s.graph.edges.iter().map(|e| (e.i, e.j)).collect()
    };
    assert_eq!(pairs(&base), pairs(&noisy));
}

/// A reproducibility pin, not a correctness check: these bytes were produced by this generator
/// (xoshiro256**, Box-Muller with the platform's ln/sin/cos) on x86_64 Linux. A failure means
/// either the random stream changed (every simulated data set changes: say so in the changelog)
/// or this platform's libm rounds ln, sin or cos differently.
#[test]
fn output_is_pinned() {
    let out = ok_stdout(&["-n", "3", "--seed", "1", "--loop-probability", "1"]);
    assert_eq!(String::from_utf8(out).unwrap(), PINNED);
}

const PINNED: &str = "\
VERTEX_SE2 0 7.029218331588504 5.204366199388569 -0.4656198455421783\n\
VERTEX_SE2 1 3.9132860204190445 6.971784165599615 2.239502941795304\n\
VERTEX_SE2 2 0.7104521606921232 3.8118444669061766 -2.306887097792547\n\
EDGE_SE2 0 1 -3.677608749204312 0.2109158925470882 2.841954762757295 1 0 0 1 0 1\n\
EDGE_SE2 0 2 -5.103589159273672 -4.107042750863368 -1.8409785993291088 1 0 0 1 0 1\n\
EDGE_SE2 1 2 -0.4309435985764206 4.58367025603718 1.7011826774052565 1 0 0 1 0 1\n";

#[test]
fn noiseless_graph_is_balanced() {
    for seed in 0..20 {
        let sim = simulate(&config(40, 0.2, NOISELESS_R, NOISELESS_T, seed));
        let g = &sim.graph;
        assert_eq!(g.poses, sim.truth);
        assert_eq!(g.ids, (0..40).collect::<Vec<u32>>());
        assert!(g.vertices_declared && g.fixed.is_empty());
        for p in &sim.truth {
            assert!((0.0..10.0).contains(&p.x) && (0.0..10.0).contains(&p.y));
            assert!(p.theta > -PI && p.theta <= PI);
        }
        for e in &g.edges {
            let want = relative(sim.truth[e.i], sim.truth[e.j]);
            let z = e.measurement;
            assert!(
                (z.x - want.x).abs() <= 1e-12,
                "seed {seed} {e:?} vs {want:?}"
            );
            assert!(
                (z.y - want.y).abs() <= 1e-12,
                "seed {seed} {e:?} vs {want:?}"
            );
            assert!(
                angle_diff(z.theta, want.theta) <= 1e-12,
                "seed {seed} {e:?}"
            );
            assert!(z.theta > -PI && z.theta <= PI);
            assert_eq!(e.noise, pgo::SymMat3::IDENTITY);
        }
        // Every cycle made of a loop closure (i, j) and the odometry from i to j composes to
        // the identity.
        let odo: Vec<Isometry2<f64>> = g
            .edges
            .iter()
            .filter(|e| e.j == e.i + 1)
            .map(|e| e.measurement.to_isometry())
            .collect();
        assert_eq!(odo.len(), 39);
        for e in g.edges.iter().filter(|e| e.j > e.i + 1) {
            let path = odo[e.i..e.j]
                .iter()
                .fold(Isometry2::identity(), |acc, z| acc * z);
            let cycle = Pose2::from_isometry(&(path * e.measurement.to_isometry().inverse()));
            assert!(cycle.x.abs() < 1e-11 && cycle.y.abs() < 1e-11, "{cycle:?}");
            assert!(angle_diff(cycle.theta, 0.0) < 1e-12, "{cycle:?}");
        }
    }
}

/// Edge counts by `pgo-convert --stats`: n poses, n − 1 odometry edges, one component, no
/// duplicates, and loop closures Binomial(m, P_c) with m = (n−1)(n−2)/2 candidate pairs. The mean
/// over 200 graphs has standard error √(m P_c (1 − P_c) / 200); we accept 5 standard errors
/// (a false alarm has probability below 1e-6, and the seeds are fixed anyway).
#[test]
fn edge_counts_follow_the_model() {
    let (n, p, runs) = (20usize, 0.1, 200);
    let m = ((n - 1) * (n - 2) / 2) as f64;
    let mut total = 0.0;
    for seed in 0..runs {
        let bytes = ok_stdout(&[
            "-n",
            &n.to_string(),
            "--loop-probability",
            &p.to_string(),
            "--seed",
            &seed.to_string(),
        ]);
        let s = stats_json(&bytes);
        assert_eq!(s["format"], "g2o");
        assert_eq!(s["poses"], n);
        assert_eq!(s["vertices_declared"], true);
        assert_eq!(s["odometry_edges"], n - 1);
        assert_eq!(s["backward_edges"], 0);
        assert_eq!(s["duplicate_edges"], 0);
        assert_eq!(s["components"], 1);
        assert_eq!(s["id_min"], 0);
        assert_eq!(s["id_max"], n - 1);
        let lc = s["loop_closures"].as_u64().unwrap() as f64;
        assert_eq!(s["edges"].as_u64().unwrap() as f64, lc + (n - 1) as f64);
        assert!(lc <= m);
        total += lc;
    }
    let mean = total / runs as f64;
    let se = (m * p * (1.0 - p) / runs as f64).sqrt();
    assert!(
        (mean - m * p).abs() < 5.0 * se,
        "mean loop closures {mean}, expected {} ± {}",
        m * p,
        5.0 * se
    );
}

/// Pc = 0 gives the path, Pc = 1 the complete graph.
#[test]
fn extreme_probabilities() {
    let s = stats_json(&ok_stdout(&["-n", "12", "--loop-probability", "0"]));
    assert_eq!(
        (s["edges"].as_u64(), s["loop_closures"].as_u64()),
        (Some(11), Some(0))
    );
    let s = stats_json(&ok_stdout(&["-n", "12", "--loop-probability", "1"]));
    assert_eq!(s["edges"].as_u64(), Some(12 * 11 / 2));
}

/// Gaussian rotation noise σ_R = 0.3 on n = 2000 path edges: 1999 samples of
/// wrap(θ_ij − (θ_j − θ_i)) (wrapping is negligible at 10σ < π). The sample standard deviation
/// has relative standard error ≈ 1/√(2·1998) ≈ 1.6%, so 5% is ~3 standard errors; the mean has
/// standard error σ/√1999.
#[test]
fn gaussian_rotation_noise_statistics() {
    let sigma = 0.3;
    let sim = simulate(&config(
        2000,
        0.0,
        RotationNoise::Gaussian { sigma },
        NOISELESS_T,
        2024,
    ));
    assert_eq!(sim.graph.edges.len(), 1999);
    let (t, r) = noise_samples(&sim.graph, &sim.truth);
    let (mean, std) = mean_std(&r);
    assert!((std - sigma).abs() < 0.05 * sigma, "std {std}");
    assert!(
        mean.abs() < 5.0 * sigma / (r.len() as f64).sqrt(),
        "mean {mean}"
    );
    // Noiseless translations stay exact.
    assert!(t.iter().all(|e| e[0].abs() < 1e-12 && e[1].abs() < 1e-12));
}

/// Uniform rotation noise in (−π, π] has variance (2π)²/12 = π²/3 and E[ε⁴] = π⁴/5, so the sample
/// variance of 1999 samples has standard error √((π⁴/5 − π⁴/9)/1999) ≈ 0.066; accept 5 of them.
#[test]
fn uniform_rotation_noise_statistics() {
    let sim = simulate(&config(2000, 0.0, RotationNoise::Uniform, NOISELESS_T, 5));
    let (_, r) = noise_samples(&sim.graph, &sim.truth);
    let n = r.len() as f64;
    assert!(r.iter().all(|&e| e > -PI - 1e-12 && e <= PI + 1e-12));
    let (mean, std) = mean_std(&r);
    let var = std * std;
    let se_var = ((PI.powi(4) / 5.0 - PI.powi(4) / 9.0) / n).sqrt();
    assert!((var - PI * PI / 3.0).abs() < 5.0 * se_var, "variance {var}");
    assert!(mean.abs() < 5.0 * (PI * PI / 3.0 / n).sqrt(), "mean {mean}");
    // Spread over the whole circle: each quarter of (−π, π] holds about a quarter of the samples
    // (binomial standard deviation √(1999·3/16) ≈ 19; accept 5 of them).
    for q in 0..4 {
        let (lo, hi) = (-PI + q as f64 * PI / 2.0, -PI + (q + 1) as f64 * PI / 2.0);
        let count = r.iter().filter(|&&e| e > lo && e <= hi).count() as f64;
        assert!(
            (count - n / 4.0).abs() < 5.0 * (n * 3.0 / 16.0).sqrt(),
            "quarter {q}: {count}"
        );
    }
}

/// Uniform translation noise in [−h, h]²: every sample inside (to rounding), both extremes nearly
/// reached, variance h²/3 per coordinate (standard error √((h⁴/5 − h⁴/9)/n); 5 of them).
#[test]
fn uniform_translation_noise_statistics() {
    let h = 5.0;
    let sim = simulate(&config(
        2000,
        0.0,
        NOISELESS_R,
        TranslationNoise::Uniform { half_width: h },
        11,
    ));
    let (t, r) = noise_samples(&sim.graph, &sim.truth);
    assert!(r.iter().all(|e| e.abs() < 1e-12));
    for c in 0..2 {
        let v: Vec<f64> = t.iter().map(|e| e[c]).collect();
        assert!(
            v.iter().all(|x| x.abs() <= h + 1e-9),
            "coordinate {c} outside [-h, h]"
        );
        let max = v.iter().cloned().fold(f64::MIN, f64::max);
        let min = v.iter().cloned().fold(f64::MAX, f64::min);
        // P(all 1999 samples below h − 0.05) = (1 − 0.005)^1999 ≈ 5e-5.
        assert!(max > h - 0.05 && min < -h + 0.05, "range [{min}, {max}]");
        let n = v.len() as f64;
        let (mean, std) = mean_std(&v);
        let se_var = ((h.powi(4) / 5.0 - h.powi(4) / 9.0) / n).sqrt();
        assert!(
            (std * std - h * h / 3.0).abs() < 5.0 * se_var,
            "variance {}",
            std * std
        );
        assert!(mean.abs() < 5.0 * (h * h / 3.0 / n).sqrt(), "mean {mean}");
    }
}

/// Gaussian translation noise σ_Δ = 0.5: per-coordinate sample std within 5% (3 standard errors),
/// coordinates uncorrelated (sample correlation within 5/√n of 0).
#[test]
fn gaussian_translation_noise_statistics() {
    let sigma = 0.5;
    let sim = simulate(&config(
        2000,
        0.0,
        NOISELESS_R,
        TranslationNoise::Gaussian { sigma },
        12,
    ));
    let (t, _) = noise_samples(&sim.graph, &sim.truth);
    let x: Vec<f64> = t.iter().map(|e| e[0]).collect();
    let y: Vec<f64> = t.iter().map(|e| e[1]).collect();
    let n = x.len() as f64;
    for v in [&x, &y] {
        let (mean, std) = mean_std(v);
        assert!((std - sigma).abs() < 0.05 * sigma, "std {std}");
        assert!(mean.abs() < 5.0 * sigma / n.sqrt(), "mean {mean}");
    }
    let (mx, sx) = mean_std(&x);
    let (my, sy) = mean_std(&y);
    let corr = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (a - mx) * (b - my))
        .sum::<f64>()
        / ((n - 1.0) * sx * sy);
    assert!(corr.abs() < 5.0 / n.sqrt(), "correlation {corr}");
}

#[test]
fn writes_toro_and_files_atomically() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sim.graph");
    let out = simulate_cli(&["-n", "5", "-q", "-o", path.to_str().unwrap()]);
    assert!(out.status.success());
    assert!(out.stdout.is_empty() && out.stderr.is_empty());
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("VERTEX2 0 "), "{text}");
    assert!(text.contains("\nEDGE2 0 1 "));
    // The same graph as g2o on stdout (--to overrides nothing here: stdout defaults to g2o).
    let g2o = common::naive_read(&ok_stdout(&["-n", "5"]));
    let toro = common::naive_read(text.as_bytes());
    assert_eq!(g2o.vertices, toro.vertices);
    assert_eq!(g2o.edges.len(), toro.edges.len());
    for (a, b) in g2o.edges.iter().zip(&toro.edges) {
        assert_eq!((a.0, a.1, a.2), (b.0, b.1, b.2));
    }
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["sim.graph"]);
    // --to wins over the extension.
    let path2 = dir.path().join("sim2.graph");
    assert!(
        simulate_cli(&["-n", "3", "--to", "g2o", "-o", path2.to_str().unwrap()])
            .status
            .success()
    );
    assert!(
        std::fs::read_to_string(&path2)
            .unwrap()
            .starts_with("VERTEX_SE2 0 ")
    );
}

#[test]
fn bad_flags_exit_2_with_a_message() {
    let cases: &[(&[&str], &str)] = &[
        (&["-n", "0"], "at least 1 pose"),
        (&["-n", "-3"], "at least 1 pose"),
        (&["-n", "ten"], "not a whole number"),
        (&["-n", "2147483649"], "at most 2147483648"),
        (&["--loop-probability", "1.5"], "must be in [0, 1]"),
        (&["--loop-probability", "nan"], "must be in [0, 1]"),
        (&["--loop-probability", "x"], "not a number"),
        (&["--rotation-noise", "gaussian:-0.1"], "finite number >= 0"),
        (&["--rotation-noise", "gaussian"], "gaussian:SIGMA"),
        (&["--rotation-noise", "uniform:3"], "takes no parameter"),
        (
            &["--rotation-noise", "laplace:1"],
            "expected gaussian:SIGMA or uniform",
        ),
        (&["--translation-noise", "uniform"], "uniform:HALFWIDTH"),
        (&["--translation-noise", "gaussian:abc"], "not a number"),
        (
            &["--translation-noise", "uniform:inf"],
            "finite number >= 0",
        ),
        (&["--side", "0"], "finite number > 0"),
        (&["--side", "-1"], "finite number > 0"),
        (&["--loop-probability", "-0.5"], "must be in [0, 1]"),
        (&["--seed", "-1"], "invalid value"),
        (&["--to", "xml"], "invalid value"),
    ];
    for (args, message) in cases {
        let out = simulate_cli(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    // An unwritable output: the tool's own error path, exit 2.
    let out = simulate_cli(&["-o", "/nonexistent-dir/x.g2o"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).starts_with("pgo-simulate: error: "));
}

/// Large graphs: the pairs model (47) is refused with its size before anything is drawn (it is
/// quadratic in n); the per-pose model grows linearly, and its edges follow it (counted by
/// `pgo-convert --stats`, an independent reader).
#[test]
fn large_graphs_are_refused_by_pairs_and_linear_per_pose() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big.g2o");
    let refused = simulate_cli(&["-n", "100000", "-o", out.to_str().unwrap()]);
    assert_eq!(refused.status.code(), Some(2));
    let err = String::from_utf8_lossy(&refused.stderr);
    // 0.1 · 99999 · 99998 / 2 = 499985000.1 expected loop closures.
    assert!(
        err.starts_with("pgo-simulate: error: -n 100000 with --loop-probability 0.1 makes about 5.000e8 loop closures"),
        "{err}"
    );
    assert!(
        err.contains("--loop-model per-pose") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1);
    assert!(!out.exists());
    // Few expected loop closures but 5e11 pairs to draw: refused too.
    let err = simulate_cli(&["-n", "1000000", "--loop-probability", "1e-9"]);
    assert_eq!(err.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&err.stderr).contains("pairs of poses"));

    let (n, p) = (100_000usize, 0.1);
    let args = [
        "-n",
        "100000",
        "--loop-model",
        "per-pose",
        "--loop-probability",
        "0.1",
        "--seed",
        "4",
    ];
    let bytes = ok_stdout(&args);
    assert_eq!(bytes, ok_stdout(&args), "reproducible");
    let s = stats_json(&bytes);
    assert_eq!(s["poses"], n);
    assert_eq!(s["odometry_edges"], n - 1);
    assert_eq!(s["duplicate_edges"], 0);
    assert_eq!(s["backward_edges"], 0);
    assert_eq!(s["components"], 1);
    // Binomial(n − 2, p): mean 9999.8, standard deviation 94.9.
    let lc = s["loop_closures"].as_f64().unwrap();
    assert!((lc - p * (n - 2) as f64).abs() < 5.0 * 94.9, "{lc}");
    // At most one loop closure ends at each pose, from an earlier one.
    let g = pgo::io::read(&bytes[..], "sim.g2o", &Default::default())
        .unwrap()
        .0;
    let mut ends = vec![0u8; n];
    for e in g.edges.iter().filter(|e| e.j != e.i + 1) {
        assert!(e.i + 1 < e.j);
        ends[e.j] += 1;
    }
    assert!(ends.iter().all(|&c| c <= 1));
    // The summary names the model.
    let out = simulate_cli(&["-n", "50", "--loop-model", "per-pose"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("loop probability 0.1 (per-pose)"));
}
