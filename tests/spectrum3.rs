//! pgo-spectrum on 3D graphs (issue 15), held against matrices built here, densely and
//! independently of `src/se3/problem.rs`: SE-Sync's data matrix Q written out edge by edge from
//! its quadratic form (Rosen et al., IJRR 2019)
//!
//!   f(X) = Σ_(i,j) τ ‖t_j − t_i − R_i t̃‖² + κ ‖R_j − R_i R̃‖_F² = tr(XᵀQX),
//!
//! X = [t_1ᵀ; …; R_1ᵀ; …] (the anchor's translation row left out), its weights computed here from
//! each 6x6 information matrix (τ = 3/tr(Ω_tt⁻¹), κ = 3/(2 tr(Ω_RR⁻¹))), the multipliers
//! Λ_i = sym((QX)_i X_iᵀ) at pgo-solve's estimate (SE-Sync eq. (48)), S = Q − blkdiag(0, Λ),
//! M the Schur complement of the translations, and every eigenvalue by nalgebra's
//! `SymmetricEigen`.

mod common;

use common::{bin, datasets_dir, s};
use nalgebra::{DMatrix, Matrix3, UnitQuaternion, Vector3};
use pgo::graph3::Graph3;
use pgo::io::ReadOptions;
use pgo::problem::weights::Weights;
use pgo::solve::{SolveOptions, solve3};
use pgo::spectrum::spectrum3;
use std::process::Command;

fn read_bytes(bytes: &[u8], name: &str) -> Graph3 {
    pgo::io::read3(bytes, name, &ReadOptions::default())
        .unwrap()
        .0
}

fn read(name: &str) -> Graph3 {
    read_bytes(&std::fs::read(datasets_dir().join(name)).unwrap(), name)
}

/// The dense Q of a connected graph anchored at pose 0, rows [t_1..t_{n−1}; R_0ᵀ rows; …].
fn dense_q(graph: &Graph3) -> DMatrix<f64> {
    let n = graph.poses.len();
    let dim = 4 * n - 1;
    let t_row = |i: usize| (i > 0).then(|| i - 1);
    let y_row = |i: usize, a: usize| n - 1 + 3 * i + a;
    let mut q = DMatrix::<f64>::zeros(dim, dim);
    for e in &graph.edges {
        let block = |at: usize| Matrix3::from_fn(|r, c| e.information.get(at + r, at + c));
        let tau = 3.0 / block(0).try_inverse().unwrap().trace();
        let kappa = 3.0 / (2.0 * block(3).try_inverse().unwrap().trace());
        let rt = e
            .measurement
            .rotation
            .unit_quaternion()
            .to_rotation_matrix()
            .into_inner();
        let tt = Vector3::from(e.measurement.translation);
        // Translation residual (a row): t_jᵀ − t_iᵀ − Σ_a t̃_a (R_iᵀ)_a.
        let mut c = vec![0.0; dim];
        if let Some(r) = t_row(e.j) {
            c[r] += 1.0;
        }
        if let Some(r) = t_row(e.i) {
            c[r] -= 1.0;
        }
        for a in 0..3 {
            c[y_row(e.i, a)] -= tt[a];
        }
        let c = DMatrix::from_column_slice(dim, 1, &c);
        q += &c * c.transpose() * tau;
        // Rotation residual, row b of R_jᵀ − R̃ᵀR_iᵀ: (R_jᵀ)_b − Σ_a R̃_ab (R_iᵀ)_a.
        for b in 0..3 {
            let mut c = vec![0.0; dim];
            c[y_row(e.j, b)] += 1.0;
            for a in 0..3 {
                c[y_row(e.i, a)] -= rt[(a, b)];
            }
            let c = DMatrix::from_column_slice(dim, 1, &c);
            q += &c * c.transpose() * kappa;
        }
    }
    q
}

/// X (dim x 3) of poses, translations relative to pose 0's.
fn point(graph: &Graph3, poses: &[pgo::graph3::Pose3]) -> DMatrix<f64> {
    let n = graph.poses.len();
    let mut x = DMatrix::<f64>::zeros(4 * n - 1, 3);
    let t0 = Vector3::from(poses[0].translation);
    for (i, p) in poses.iter().enumerate() {
        let r = p
            .rotation
            .unit_quaternion()
            .to_rotation_matrix()
            .into_inner();
        if i > 0 {
            let t = Vector3::from(p.translation) - t0;
            for c in 0..3 {
                x[(i - 1, c)] = t[c];
            }
        }
        for a in 0..3 {
            for c in 0..3 {
                // Row a of R_iᵀ.
                x[(n - 1 + 3 * i + a, c)] = r[(c, a)];
            }
        }
    }
    x
}

/// S = Q − blkdiag(0, Λ), Λ_i = sym((QX)_i X_iᵀ).
fn dense_s(q: &DMatrix<f64>, x: &DMatrix<f64>, n: usize) -> DMatrix<f64> {
    let g = q * x;
    let mut s = q.clone();
    for i in 0..n {
        let r0 = n - 1 + 3 * i;
        let gi = g.rows(r0, 3);
        let xi = x.rows(r0, 3);
        let l = gi * xi.transpose();
        let l = (&l + l.transpose()) * 0.5;
        for a in 0..3 {
            for b in 0..3 {
                s[(r0 + a, r0 + b)] -= l[(a, b)];
            }
        }
    }
    s
}

fn eigenvalues(m: DMatrix<f64>) -> Vec<f64> {
    let mut v: Vec<f64> = m.symmetric_eigen().eigenvalues.iter().copied().collect();
    v.sort_by(f64::total_cmp);
    v
}

/// Each computed eigenvalue within 1e-8 of the dense one of the same rank (`dense`: the whole
/// spectrum), relative to it (to 1e-6 of the spectrum's largest for the eigenvalues at zero,
/// where a relative error means nothing).
fn assert_close(what: &str, sparse: &[f64], dense: &[f64], count: usize) {
    assert_eq!(sparse.len(), count.min(dense.len()), "{what}");
    let top = dense.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (k, (a, b)) in sparse.iter().zip(dense).enumerate() {
        let scale = b.abs().max(1e-6 * top);
        assert!(
            (a - b).abs() <= 1e-8 * scale,
            "{what}[{k}]: {a} against {b} dense"
        );
    }
}

#[test]
fn the_spectra_of_q_s_and_m_are_the_dense_ones_at_the_optimum() {
    for name in ["tinyGrid3D.g2o", "smallGrid3D.g2o"] {
        let graph = read(name);
        let n = graph.poses.len();
        let dim = 4 * n - 1;
        // All eigenvalues of Q and S (tinyGrid3D: 35) or the 100 smallest (smallGrid3D: 499).
        let k = dim.min(100);
        let report = spectrum3(&graph, Weights::Isotropic, k).unwrap();
        assert_eq!(report.components.len(), 1);
        let solution = solve3(&graph, &SolveOptions::default()).unwrap();
        assert!(solution.certified, "{name}");
        let q = dense_q(&graph);
        let x = point(&graph, &solution.estimate);
        let s_matrix = dense_s(&q, &x, n);
        // M: the translations (rows 0..n−1) eliminated.
        let t = n - 1;
        let qtt = q.view((0, 0), (t, t)).into_owned();
        let qty = q.view((0, t), (t, 3 * n)).into_owned();
        let qyy = q.view((t, t), (3 * n, 3 * n)).into_owned();
        let m = &qyy - qty.transpose() * qtt.cholesky().unwrap().solve(&qty);
        let q_dense = eigenvalues(q.clone());
        let s_dense = eigenvalues(s_matrix);
        let m_dense = eigenvalues(m);
        assert_close(&format!("{name} Q"), &report.eigenvalues, &q_dense, k);
        assert_close(
            &format!("{name} S"),
            &report.penalized_eigenvalues,
            &s_dense,
            k,
        );
        assert_close(
            &format!("{name} M"),
            &report.rotation_eigenvalues,
            &m_dense,
            k,
        );
        // Exactly three eigenvalues of S at zero, the fourth clearly positive.
        let top = s_dense[dim - 1];
        let zeros = s_dense.iter().filter(|v| v.abs() <= 1e-10 * top).count();
        assert_eq!(zeros, 3, "{name}: {:?}", &s_dense[..5]);
        // Clearly: a gap of at least 1e5 over the zero threshold.
        assert!(s_dense[3] >= 1e-5 * top, "{name}: {} of {top}", s_dense[3]);
        assert_eq!(report.near_zero, 3, "{name}");
        assert!(report.szep && report.certified, "{name}");
        eprintln!(
            "{name}: S {:?}, fourth {} (dense {}), largest {top}",
            &report.penalized_eigenvalues[..3],
            report.penalized_eigenvalues[3],
            s_dense[3]
        );
    }
}

/// A noise-free ring with chords: measurements composed from the true poses.
fn noise_free(n: usize) -> String {
    let pose = |i: usize| {
        let f = i as f64;
        let q = UnitQuaternion::from_euler_angles(0.3 * f, 0.7 * (0.5 * f).sin(), 0.2 * f * f);
        let t = Vector3::new((0.4 * f).cos() * 5.0, (0.4 * f).sin() * 5.0, 0.1 * f);
        (q, t)
    };
    let mut text = String::new();
    for i in 0..n {
        let (q, t) = pose(i);
        let c = q.quaternion().coords;
        text += &format!(
            "VERTEX_SE3:QUAT {i} {} {} {} {} {} {} {}\n",
            t.x, t.y, t.z, c.x, c.y, c.z, c.w
        );
    }
    let mut edges: Vec<(usize, usize)> = (0..n).map(|i| (i, (i + 1) % n)).collect();
    edges.extend([(0, n / 2), (1, n / 3), (2, n - 2)]);
    for (i, j) in edges {
        let (qi, ti) = pose(i);
        let (qj, tj) = pose(j);
        let qz = qi.inverse() * qj;
        let tz = qi.inverse() * (tj - ti);
        let c = qz.quaternion().coords;
        text += &format!(
            "EDGE_SE3:QUAT {i} {j} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n",
            tz.x, tz.y, tz.z, c.x, c.y, c.z, c.w
        );
    }
    text
}

#[test]
fn q_of_a_noise_free_graph_has_the_rigid_body_null_space() {
    let graph = read_bytes(noise_free(12).as_bytes(), "ring.g2o");
    let n = graph.poses.len();
    let q = dense_q(&graph);
    let dense = eigenvalues(q.clone());
    let top = dense[4 * n - 2];
    // The translation gauge is anchored: the null space is the global rotation, the three
    // columns of the true X.
    let zeros = dense.iter().filter(|v| v.abs() <= 1e-10 * top).count();
    assert_eq!(zeros, 3, "{:?}", &dense[..5]);
    assert!(dense[3] >= 1e-5 * top, "{} of {top}", dense[3]);
    let x = point(&graph, &graph.poses);
    assert!((&q * &x).norm() <= 1e-10 * top * x.norm());
    eprintln!("ring: Q {:?}, largest {top}", &dense[..5]);
    let report = spectrum3(&graph, Weights::Isotropic, 6).unwrap();
    assert_close("ring Q", &report.eigenvalues, &dense, 6);
    // At the optimum f = 0, Λ = 0 and S = Q: the same three zeros.
    assert_eq!(report.near_zero, 3);
    assert!(report.szep && report.certified);
    assert_close("ring S", &report.penalized_eigenvalues, &dense, 6);
}

#[test]
fn pgo_spectrum_reports_3d_graphs_in_text_and_json() {
    let input = datasets_dir().join("tinyGrid3D.g2o");
    let out = Command::new(bin("pgo-spectrum"))
        .args([s(&input), "-k", "4", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["dimension"], 3);
    assert_eq!(v["near_zero"], 3);
    assert_eq!(v["szep"], true);
    assert_eq!(v["penalized_eigenvalues"].as_array().unwrap().len(), 4);
    assert!(v.get("tree").is_none() && v.get("lambda").is_none());
    let text = Command::new(bin("pgo-spectrum"))
        .args([s(&input), "-k", "4"])
        .output()
        .unwrap();
    assert!(text.status.success());
    assert!(String::from_utf8_lossy(&text.stdout).contains("zero eigenvalues:      3 of S"));
    // -k beyond 100 and the rerun flags are refused (exit 2).
    for args in [vec!["-k", "101"], vec!["--rerun-save", "x.rrd"]] {
        let out = Command::new(bin("pgo-spectrum"))
            .arg(s(&input))
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}: {out:?}");
    }
}
