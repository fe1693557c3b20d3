//! `pgo-simulate --world sphere|torus|grid` (issue 15, landing 4) against facts that do not
//! depend on the implementation: the worlds' geometry, reproducibility, noiseless measurements
//! equal to x_i⁻¹·x_j of the vertex lines (composed again here with nalgebra) and a zero cost,
//! the sample statistics of the noise recovered from the file against the flags and against
//! the information matrices written (so g2o's χ² of the truth averages 6 per edge), and
//! `pgo-solve` certifying generated worlds.

mod common;

use common::{Dir, bin, s, text};
use nalgebra::{Isometry3, Vector3};
use pgo::graph3::{Graph3, Pose3};
use pgo::io::ReadOptions;
use pgo::simulate::space::{SpaceConfig, World3, grid_size, ring_size, simulate3};
use pgo::simulate::{RotationNoise, TranslationNoise};
use std::process::{Command, Output, Stdio};

const WORLDS: [World3; 3] = [World3::Sphere, World3::Torus, World3::Grid];

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

fn read3(bytes: &[u8]) -> Graph3 {
    pgo::io::read3(bytes, "<sim>", &ReadOptions::default())
        .unwrap()
        .0
}

fn config(world: World3, n: usize, rot: RotationNoise, tra: TranslationNoise) -> SpaceConfig {
    SpaceConfig {
        world,
        n,
        side: 10.0,
        loop_probability: 1.0,
        rotation_noise: rot,
        translation_noise: tra,
        seed: 5,
    }
}

fn iso(p: &Pose3) -> Isometry3<f64> {
    p.to_isometry()
}

#[test]
fn same_seed_same_bytes_different_seed_different_bytes() {
    for world in ["sphere", "torus", "grid"] {
        let args = ["--world", world, "-n", "40", "--seed", "9", "-q"];
        let a = ok_stdout(&args);
        let b = ok_stdout(&args);
        assert_eq!(a, b, "{world}");
        let c = ok_stdout(&["--world", world, "-n", "40", "--seed", "10", "-q"]);
        assert_ne!(a, c, "{world}");
        // The vertex lines (the truth) do not depend on the seed or the noise.
        let vertices = |b: &[u8]| {
            text(b)
                .lines()
                .filter(|l| l.starts_with("VERTEX_SE3:QUAT"))
                .map(String::from)
                .collect::<Vec<_>>()
        };
        assert_eq!(vertices(&a), vertices(&c));
        assert_eq!(vertices(&a).len(), 40);
        let g = read3(&a);
        assert_eq!(g.ids, (0..40).collect::<Vec<u32>>());
        assert!(g.edges.iter().all(|e| e.i < e.j));
        let pairs: Vec<_> = g.edges.iter().map(|e| (e.i, e.j)).collect();
        assert!(pairs.windows(2).all(|w| w[0] < w[1]), "ascending");
    }
}

/// The worlds' shapes, checked on the vertex lines: the sphere's poses at distance L/2 from
/// the origin with z along the outward normal, the torus's at distance L/8 from its centre
/// circle of radius 3L/8, the grid's on the lattice of spacing L/m one step apart.
#[test]
fn the_worlds_have_their_shapes() {
    let none = (
        RotationNoise::Gaussian { sigma: 0.0 },
        TranslationNoise::Gaussian { sigma: 0.0 },
    );
    let n = 100;
    for world in WORLDS {
        let sim = simulate3(&config(world, n, none.0, none.1));
        let poses: Vec<_> = sim.truth.iter().map(iso).collect();
        for (i, p) in poses.iter().enumerate() {
            let t = p.translation.vector;
            let z_axis = p.rotation * Vector3::z();
            assert!((p.rotation.norm() - 1.0).abs() < 1e-15);
            match world {
                World3::Sphere => {
                    assert!((t.norm() - 5.0).abs() < 1e-12, "{i}");
                    assert!((z_axis - t / 5.0).norm() < 1e-12, "{i}");
                }
                World3::Torus => {
                    let radial = Vector3::new(t.x, t.y, 0.0).normalize() * 3.75;
                    assert!(((t - radial).norm() - 1.25).abs() < 1e-12, "{i}");
                    assert!((z_axis - (t - radial) / 1.25).norm() < 1e-12, "{i}");
                }
                World3::Grid => {
                    let h = 10.0 / grid_size(n) as f64;
                    for k in 0..3 {
                        let c = t[k] / h;
                        assert!((c - c.round()).abs() < 1e-12 && c > -0.5 && c < 10.0 / h);
                    }
                    if i + 1 < n {
                        let d = poses[i + 1].translation.vector - t;
                        assert!((d.norm() - h).abs() < 1e-12, "{i}");
                        // The x axis points along the step.
                        assert!((p.rotation * Vector3::x() - d / h).norm() < 1e-12, "{i}");
                    }
                }
            }
        }
        // Edges: the path plus every candidate (P_c = 1). Sphere: one per pose from the second
        // ring on; torus: also the last ring (complete at n = 100) to the first; grid: every
        // lattice-neighbour pair minus the path's steps.
        let loops = sim.graph.edges.len() - (n - 1);
        let k = ring_size(n);
        let expected = match world {
            World3::Sphere => n - k,
            World3::Torus => n - k + k,
            World3::Grid => {
                let m = grid_size(n);
                let cells: std::collections::HashSet<[i64; 3]> = poses
                    .iter()
                    .map(|p| {
                        let t = p.translation.vector * (m as f64 / 10.0);
                        [t.x.round() as i64, t.y.round() as i64, t.z.round() as i64]
                    })
                    .collect();
                let neighbours: usize = cells
                    .iter()
                    .map(|c| {
                        (0..3)
                            .filter(|&a| {
                                let mut d = *c;
                                d[a] += 1;
                                cells.contains(&d)
                            })
                            .count()
                    })
                    .sum();
                neighbours - (n - 1)
            }
        };
        assert_eq!(loops, expected, "{world:?}");
    }
}

/// Zero noise: every measurement is x_i⁻¹·x_j of the vertex lines (recomputed here), so the
/// cost at the truth is 0 to rounding, and pgo-solve finds cost 0.
#[test]
fn noiseless_measurements_are_the_truth_and_cost_nothing() {
    let dir = Dir::new();
    for world in ["sphere", "torus", "grid"] {
        let path = dir.path(&format!("{world}.g2o"));
        let out = simulate_cli(&[
            "--world",
            world,
            "-n",
            "64",
            "--rotation-noise",
            "gaussian:0",
            "--translation-noise",
            "gaussian:0",
            "-o",
            s(&path),
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let g = read3(&std::fs::read(&path).unwrap());
        for e in &g.edges {
            let want = iso(&g.poses[e.i]).inverse() * iso(&g.poses[e.j]);
            let got = iso(&e.measurement);
            assert!(
                (want.translation.vector - got.translation.vector).norm() < 1e-13,
                "{world}"
            );
            assert!(want.rotation.angle_to(&got.rotation) < 1e-7, "{world}");
            // No noise, no finite information: identity blocks.
            for r in 0..6 {
                assert_eq!(e.information.get(r, r), 1.0);
            }
        }
        let weights = pgo::se3::problem::weights3(&g, false).unwrap();
        let problem = pgo::se3::problem::Problem3::new(&g, &weights, 0);
        let truth: Vec<_> = g.poses.iter().map(pgo::se3::rt_of).collect();
        let cost = problem.cost(&pgo::se3::rounding::point_of(&problem, &truth));
        assert!(cost < 1e-20, "{world}: cost {cost}");
        let solved = Command::new(bin("pgo-solve"))
            .args(["--json", "-o", "/dev/null", s(&path)])
            .output()
            .unwrap();
        let report: serde_json::Value = serde_json::from_slice(&solved.stdout).unwrap();
        assert_eq!(report["certified"], true, "{world}: {report}");
        assert!(
            report["cost"].as_f64().unwrap() < 1e-18,
            "{world}: {report}"
        );
    }
}

/// Mean and variance of samples with the standard error of the variance (from the fourth
/// moment): the bound of a test is a number of these.
fn moments(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let m4 = v.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / n;
    (mean, var, ((m4 - var * var) / n).sqrt())
}

/// The noise recovered from a file: ε_t = t̃ − R_iᵀ(t_j − t_i) and the rotation error
/// E = (R_iᵀR_j)ᵀR̃ = Exp(ω) as ω (Log) and as the quaternion's vector part (w ≥ 0).
fn recovered(g: &Graph3) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (mut t, mut w, mut q) = (Vec::new(), Vec::new(), Vec::new());
    for e in &g.edges {
        let truth = iso(&g.poses[e.i]).inverse() * iso(&g.poses[e.j]);
        let z = iso(&e.measurement);
        let d = z.translation.vector - truth.translation.vector;
        let err = truth.rotation.inverse() * z.rotation;
        let v = err.scaled_axis();
        let c = err.quaternion();
        let sign = if c.w < 0.0 { -1.0 } else { 1.0 };
        for k in 0..3 {
            t.push(d[k]);
            w.push(v[k]);
        }
        q.extend([sign * c.i, sign * c.j, sign * c.k]);
    }
    (t, w, q)
}

/// Gaussian noise: the variances of ε_t and ω are σ_t² and σ_R² (the flags), and the
/// quaternion's vector part has the variance the information matrix states (its inverse);
/// g2o's χ² at the truth then averages 6 per edge (6 error coordinates, each of unit variance
/// under the written information).
#[test]
fn gaussian_noise_statistics_match_the_flags_and_the_information() {
    for (world, sigma_t, sigma_r) in [(World3::Grid, 0.2, 0.3), (World3::Sphere, 0.05, 0.8)] {
        let sim = simulate3(&config(
            world,
            4096,
            RotationNoise::Gaussian { sigma: sigma_r },
            TranslationNoise::Gaussian { sigma: sigma_t },
        ));
        let g = &sim.graph;
        let (t, w, q) = recovered(g);
        let (mt, vt, st) = moments(&t);
        assert!(
            mt.abs() < 5.0 * (vt / t.len() as f64).sqrt(),
            "{world:?} mean {mt}"
        );
        assert!(
            (vt - sigma_t * sigma_t).abs() < 5.0 * st,
            "{world:?}: {vt} ± {st}"
        );
        if sigma_r < 0.5 {
            // Angles beyond π wrap (probability below 1e-20 here): ω's variance is σ_R².
            let (_, vw, sw) = moments(&w);
            assert!(
                (vw - sigma_r * sigma_r).abs() < 5.0 * sw,
                "{world:?}: {vw} ± {sw}"
            );
        }
        let (mq, vq, sq) = moments(&q);
        assert!(mq.abs() < 5.0 * (vq / q.len() as f64).sqrt());
        let info = g.edges[0].information;
        assert!(g.edges.iter().all(|e| e.information == info));
        assert!((info.get(0, 0) * sigma_t * sigma_t - 1.0).abs() < 1e-12);
        assert!(
            (1.0 / info.get(3, 3) - vq).abs() < 5.0 * sq,
            "{world:?}: {vq} ± {sq}"
        );
        for r in 0..6 {
            for c in 0..6 {
                if r != c {
                    assert_eq!(info.get(r, c), 0.0);
                }
            }
        }
        if sigma_r > 0.5 {
            // σ²/4 (the first-order q_v ≈ ω/2) would be wrong here by far more than the
            // sampling error: the exact variance is what is written.
            assert!((vq - sigma_r * sigma_r / 4.0).abs() > 20.0 * sq, "{vq}");
        }
        let chi2 = pgo::solve::chi2_3(g, &g.poses).unwrap();
        let per_edge = chi2 / g.edges.len() as f64;
        // χ² of 6 unit-variance coordinates: standard deviation about √12 per edge.
        let tolerance = 6.0 * (12.0 / g.edges.len() as f64).sqrt();
        assert!((per_edge - 6.0).abs() < tolerance, "{world:?}: {per_edge}");
    }
}

/// Uniform noise: ε_t uniform in [−h, h]³ (variance h²/3, information 3/h²), rotations uniform
/// on SO(3) (E[q_k²] = 1/4, information 4; the angle's density ∝ sin²(θ/2), mean π/2 + 2/π).
#[test]
fn uniform_noise_statistics_match_the_flags_and_the_information() {
    let h = 0.5;
    let sim = simulate3(&config(
        World3::Torus,
        4096,
        RotationNoise::Uniform,
        TranslationNoise::Uniform { half_width: h },
    ));
    let g = &sim.graph;
    let (t, _, q) = recovered(g);
    assert!(t.iter().all(|x| x.abs() <= h * (1.0 + 1e-12)));
    let (_, vt, st) = moments(&t);
    assert!((vt - h * h / 3.0).abs() < 5.0 * st, "{vt}");
    let (_, vq, sq) = moments(&q);
    assert!((vq - 0.25).abs() < 5.0 * sq, "{vq} ± {sq}");
    let info = g.edges[0].information;
    assert!((info.get(0, 0) - 3.0 / (h * h)).abs() < 1e-12);
    assert_eq!(info.get(3, 3), 4.0);
    let angles: Vec<f64> = g
        .edges
        .iter()
        .map(|e| {
            let truth = iso(&g.poses[e.i]).inverse() * iso(&g.poses[e.j]);
            truth.rotation.angle_to(&iso(&e.measurement).rotation)
        })
        .collect();
    let (ma, va, _) = moments(&angles);
    let want = std::f64::consts::FRAC_PI_2 + 2.0 / std::f64::consts::PI;
    assert!(
        (ma - want).abs() < 5.0 * (va / angles.len() as f64).sqrt(),
        "{ma}"
    );
}

/// pgo-solve certifies generated worlds at moderate noise.
#[test]
fn pgo_solve_certifies_generated_worlds() {
    let dir = Dir::new();
    for (world, n) in [("sphere", "400"), ("torus", "400"), ("grid", "343")] {
        let path = dir.path(&format!("{world}.g2o"));
        let out = simulate_cli(&[
            "--world",
            world,
            "-n",
            n,
            "--rotation-noise",
            "gaussian:0.05",
            "--translation-noise",
            "gaussian:0.1",
            "--seed",
            "3",
            "-q",
            "-o",
            s(&path),
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let solved = Command::new(bin("pgo-solve"))
            .args(["--json", "-o", "/dev/null", s(&path)])
            .output()
            .unwrap();
        let report: serde_json::Value = serde_json::from_slice(&solved.stdout).unwrap();
        assert_eq!(report["certified"], true, "{world}: {report}");
        let cost = report["cost"].as_f64().unwrap();
        let bound = report["lower_bound"].as_f64().unwrap();
        assert!(
            bound <= cost && cost - bound <= 1e-6 * cost,
            "{world}: {report}"
        );
        // The optimum is below the truth's cost (the truth is feasible).
        let g = read3(&std::fs::read(&path).unwrap());
        let w = pgo::se3::problem::weights3(&g, false).unwrap();
        let problem = pgo::se3::problem::Problem3::new(&g, &w, 0);
        let truth: Vec<_> = g.poses.iter().map(pgo::se3::rt_of).collect();
        let at_truth = problem.cost(&pgo::se3::rounding::point_of(&problem, &truth));
        assert!(
            cost <= at_truth * (1.0 + 1e-9),
            "{world}: {cost} > {at_truth}"
        );
    }
}

#[test]
fn bad_flags_exit_2_with_a_message() {
    let cases: &[(&[&str], &str)] = &[
        (&["--world", "cube"], "invalid value"),
        (&["--world", "sphere", "--landmarks", "3"], "--landmarks"),
        (
            &["--world", "torus", "--loop-model", "per-pose"],
            "--loop-model",
        ),
        (&["--world", "grid", "--to", "toro"], "--to toro"),
        (&["--world", "grid", "-o", "out.graph"], "not TORO"),
        (
            &["--world", "sphere", "--rotation-noise", "gaussian:-1"],
            "finite number >= 0",
        ),
        (
            &["--world", "sphere", "--loop-probability", "2"],
            "must be in [0, 1]",
        ),
        (&["--world", "grid", "-n", "0"], "at least 1 pose"),
        (
            &["--world", "grid", "--corrupt", "x.g2o", "--outliers", "1"],
            "cannot be used with",
        ),
    ];
    for (args, message) in cases {
        let out = simulate_cli(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    // One pose: no edges, a valid file.
    let one = read3(&ok_stdout(&["--world", "torus", "-n", "1", "-q"]));
    assert_eq!((one.num_poses(), one.edges.len()), (1, 0));
}
