//! The sparse spectrum of `pgo-spectrum` at scale (`pgo::spectrum::sparse_spectra`, shift-invert
//! subspace iteration on one sparse factorization per matrix) against dense eigenvalues of the
//! same matrices, formed here from the dense blocks: W̃ (eq. (24)), W̃(λ) (Sec. 4.1) and
//! M = Q − S* L⁻¹ S (eq. (38)); and the tool on a public file above the dense limit.

mod common;

use faer::prelude::Solve;
use faer::{Mat, Side, c64};
use pgo::linalg::eigen::hermitian_eigenvalues;
use pgo::problem::matrix::PoseGraphMatrix;
use pgo::problem::weights::{Weights, edge_weights};
use pgo::simulate::{RotationNoise, SimulationConfig, TranslationNoise, simulate};
use pgo::spectrum::{scalable_spectrum, sparse_spectra};
use std::process::Command;

/// M = Q − S* L⁻¹ S from the dense blocks of W̃, exactly Hermitian.
fn dense_rotation_matrix(matrix: &PoseGraphMatrix) -> Mat<c64> {
    let (l, s, q) = matrix.blocks();
    let lc = Mat::from_fn(l.nrows(), l.ncols(), |a, b| c64::new(l[(a, b)], 0.0));
    let m = &q - s.adjoint() * lc.llt(Side::Lower).unwrap().solve(&s);
    Mat::from_fn(m.nrows(), m.ncols(), |a, b| {
        (m[(a, b)] + m[(b, a)].conj()) * 0.5
    })
}

/// Sparse and dense agree: to 1e-8 relative, or to 1e-12 of the largest eigenvalue for values
/// at zero (where both are rounding).
fn assert_agree(what: &str, sparse: &[f64], dense: &[f64], k: usize) {
    assert_eq!(sparse.len(), k, "{what}: {sparse:?}");
    let largest = dense.last().unwrap().abs();
    for (j, (a, b)) in sparse.iter().zip(dense).enumerate() {
        assert!(
            (a - b).abs() <= 1e-8 * b.abs() + 1e-12 * largest,
            "{what}[{j}]: sparse {a:e}, dense {b:e} (largest {largest:e})\nsparse {sparse:?}\ndense {:?}",
            &dense[..k]
        );
    }
}

fn config(n: usize, loops: f64, noise: f64, seed: u64) -> SimulationConfig {
    SimulationConfig {
        n,
        side: 20.0,
        loop_probability: loops,
        rotation_noise: RotationNoise::Gaussian { sigma: noise },
        translation_noise: TranslationNoise::Gaussian { sigma: noise },
        seed,
        ..Default::default()
    }
}

#[test]
fn sparse_smallest_eigenvalues_match_the_dense_spectra_of_simulated_graphs() {
    let k = 8;
    for (cfg, policy) in [
        (config(200, 0.01, 0.1, 1), Weights::Isotropic),
        (config(220, 0.03, 0.3, 2), Weights::Unit),
        (config(180, 0.0, 0.2, 3), Weights::Isotropic), // a tree: W̃ and M are singular
    ] {
        let graph = simulate(&cfg).graph;
        let weights = edge_weights(&graph, policy).unwrap();
        // λ from the scalable solver, as pgo-spectrum takes it at scale.
        let scalable = scalable_spectrum(&graph, &weights, k).unwrap();
        let matrix = PoseGraphMatrix::new(&graph, &weights);
        let dense_w = hermitian_eigenvalues(&matrix.dense());
        let dense_wl = hermitian_eigenvalues(&matrix.penalized_dense(&scalable.lambda));
        let dense_m = hermitian_eigenvalues(&dense_rotation_matrix(&matrix));
        let s = &scalable.spectra;
        assert!(s.converged, "{cfg:?}");
        assert_agree("W", &s.eigenvalues, &dense_w, k);
        assert_agree("W(λ)", &s.penalized_eigenvalues, &dense_wl, k);
        assert_agree("M", &s.rotation_eigenvalues, &dense_m, k);
        // The certificate's SZEP: one eigenvalue of W̃(λ*) at zero, the next clear of it.
        assert!(scalable.certified && scalable.szep, "{cfg:?}");
        assert_eq!(scalable.near_zero, 1);
        assert!(dense_wl[0].abs() <= 1e-10 * dense_wl.last().unwrap());
        assert!(
            dense_wl[1] > 1e3 * (dense_wl[0].abs() + 1e-12 * dense_wl.last().unwrap()),
            "{:?}",
            &dense_wl[..k]
        );
        assert_eq!(
            scalable.dual_objective,
            scalable.lambda.iter().fold(0.0, |a, b| a + b)
        );
    }
}

#[test]
fn sparse_eigenvalues_of_an_indefinite_penalized_matrix_match_the_dense_ones() {
    // λ* raised by 1% of its mean: W̃(λ) has negative eigenvalues, so the factorization's shift
    // must climb above them.
    let k = 6;
    let graph = simulate(&config(200, 0.02, 0.2, 4)).graph;
    let weights = edge_weights(&graph, Weights::Isotropic).unwrap();
    let lambda = scalable_spectrum(&graph, &weights, 1).unwrap().lambda;
    let mean = lambda.iter().sum::<f64>() / lambda.len() as f64;
    let raised: Vec<f64> = lambda.iter().map(|l| l + 0.01 * mean).collect();
    let sparse = sparse_spectra(&graph, &weights, &raised, k).unwrap();
    let matrix = PoseGraphMatrix::new(&graph, &weights);
    let dense = hermitian_eigenvalues(&matrix.penalized_dense(&raised));
    assert!(dense[0] < 0.0);
    assert_agree("W(λ + δ)", &sparse.penalized_eigenvalues, &dense, k);
}

#[test]
fn pgo_spectrum_analyses_m3500_beyond_the_dense_limit() {
    let path = common::datasets_dir().join("M3500.g2o");
    let run = |threads: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_pgo-spectrum"))
            .arg(&path)
            .args(["--json", "-k", "6"])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    let out = run("2");
    // The same bytes whatever the thread count.
    assert_eq!(out.stdout, run("1").stdout);
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let list = |key: &str| -> Vec<f64> {
        r[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    assert_eq!(r["poses"], 3500);
    assert_eq!(r["szep"], true);
    assert_eq!(r["near_zero"], 1);
    assert_eq!(r["balanced"], false);
    assert_eq!(r["tree"], false);
    let penalized = list("penalized_eigenvalues");
    assert_eq!(penalized.len(), 6);
    assert!(penalized.windows(2).all(|w| w[0] <= w[1]), "{penalized:?}");
    // |μ₁| ≤ 1e-8·μ_max, checked against μ₆ ≤ μ_max.
    assert!(penalized[0].abs() <= 1e-8 * penalized[5], "{penalized:?}");
    assert!(penalized[1..].iter().all(|v| *v > 0.0), "{penalized:?}");
    assert!(penalized[1] > 1e3 * penalized[0].abs(), "{penalized:?}");
    let w = list("eigenvalues");
    assert_eq!(w.len(), 6);
    assert!(w[0] > 0.0, "M3500 is not balanced: {w:?}");
    let m = list("rotation_eigenvalues");
    assert_eq!(m.len(), 6);
    assert!(m[0] > 0.0, "{m:?}");
    assert_eq!(r["components"][0]["sdp_converged"], true);
}

#[test]
fn pgo_spectrum_at_scale_prints_ten_by_default_and_refuses_more_than_a_hundred() {
    let path = common::datasets_dir().join("M3500.g2o");
    let tool = || Command::new(env!("CARGO_BIN_EXE_pgo-spectrum"));
    let out = tool().arg(&path).arg("--json").output().unwrap();
    assert!(out.status.success());
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "eigenvalues",
        "penalized_eigenvalues",
        "rotation_eigenvalues",
    ] {
        assert_eq!(r[key].as_array().unwrap().len(), 10, "{key}");
        assert_eq!(r["components"][0][key].as_array().unwrap().len(), 10);
    }
    assert_eq!(r["components"][0]["lambda"].as_array().unwrap().len(), 3500);
    let out = tool().arg(&path).args(["-k", "101"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("-k 101 is more than the 100"), "{stderr}");
    assert!(out.stdout.is_empty());
}

/// `pgo-spectrum FILE ARGS --json` with RAYON_NUM_THREADS=`threads`.
fn spectrum_json(
    path: &std::path::Path,
    args: &[&str],
    threads: &str,
) -> (Vec<u8>, serde_json::Value) {
    let out = Command::new(env!("CARGO_BIN_EXE_pgo-spectrum"))
        .arg(path)
        .args(args)
        .arg("--json")
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = serde_json::from_slice(&out.stdout).unwrap();
    (out.stdout, r)
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn a_few_eigenvalues_of_a_mid_sized_graph_are_computed_sparse_with_the_dense_answer() {
    // 300 poses: below the dense limit, above pgo::spectrum::SPARSE_MIN_POSES. -k 6 takes the
    // sparse path (λ from the staircase's certificate), -k 0 the dense one (λ* from the dual SDP,
    // every eigenvalue of the dense matrices): the same numbers to 1e-8.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sim.g2o");
    let graph = simulate(&config(300, 0.01, 0.1, 5)).graph;
    let options = pgo::io::WriteOptions {
        format: pgo::io::Format::G2o,
        dialect: pgo::io::Dialect::G2o,
    };
    pgo::io::write_path(&graph, options, path.to_str().unwrap()).unwrap();
    let (bytes, sparse) = spectrum_json(&path, &["-k", "6"], "2");
    assert_eq!(
        bytes,
        spectrum_json(&path, &["-k", "6"], "1").0,
        "thread count"
    );
    let (_, dense) = spectrum_json(&path, &["-k", "0"], "2");
    for key in [
        "eigenvalues",
        "penalized_eigenvalues",
        "rotation_eigenvalues",
    ] {
        let all = floats(&dense[key]);
        assert_eq!(
            all.len(),
            if key == "rotation_eigenvalues" {
                300
            } else {
                599
            }
        );
        assert_agree(key, &floats(&sparse[key]), &all, 6);
    }
    for key in [
        "near_zero",
        "szep",
        "tree",
        "balanced",
        "sdp_converged",
        "poses",
    ] {
        assert_eq!(sparse[key], dense[key], "{key}");
    }
    assert_eq!(sparse["near_zero"], 1);
    // Proven bounds on the same optimum: both below the cost of the optimum, equal to 1e-6.
    let bound = |r: &serde_json::Value| r["components"][0]["lower_bound"].as_f64().unwrap();
    assert!((bound(&sparse) - bound(&dense)).abs() <= 1e-6 * bound(&dense).abs());
    // The sparse path did run: its λ is the staircase's, not the SDP's.
    assert_ne!(
        sparse["components"][0]["lambda"],
        dense["components"][0]["lambda"]
    );
}

#[test]
fn without_a_certificate_a_mid_sized_graph_is_analysed_dense() {
    // Uninformative rotations: the relaxation is not exact (two eigenvalues of W(λ*) at zero),
    // the staircase cannot certify, and -k 4 gives exactly the first four of -k 0.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sim.g2o");
    let mut cfg = config(120, 0.05, 0.0, 1);
    cfg.side = 10.0;
    cfg.rotation_noise = RotationNoise::Uniform;
    cfg.translation_noise = TranslationNoise::Uniform { half_width: 5.0 };
    let graph = simulate(&cfg).graph;
    let options = pgo::io::WriteOptions {
        format: pgo::io::Format::G2o,
        dialect: pgo::io::Dialect::G2o,
    };
    pgo::io::write_path(&graph, options, path.to_str().unwrap()).unwrap();
    let (_, few) = spectrum_json(&path, &["-k", "4", "--weights", "unit"], "2");
    let (_, all) = spectrum_json(&path, &["-k", "0", "--weights", "unit"], "2");
    assert_eq!(few["szep"], false);
    for key in [
        "eigenvalues",
        "penalized_eigenvalues",
        "rotation_eigenvalues",
    ] {
        let (a, b) = (floats(&few[key]), floats(&all[key]));
        assert_eq!(bits(&a), bits(&b[..4]), "{key}");
    }
    assert_eq!(
        few["components"][0]["lambda"],
        all["components"][0]["lambda"]
    );
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}
