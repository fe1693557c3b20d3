//! The certified SE(3) solver (issue 15, second landing), each check against something
//! independent of the code under test: exact measurements, the edge-by-edge formula written
//! again with nalgebra, the first-order conditions, invariances, SE-Sync's published optima,
//! and the tools end to end.

mod common;

use common::{Dir, bin, datasets_dir, s, text};
use nalgebra::{Isometry3, Matrix3, Quaternion, UnitQuaternion, Vector3};
use pgo::graph3::{Edge3, Form3, Graph3, Pose3, Rotation3, SymMat6};
use pgo::io::ReadOptions;
use pgo::se3::local::apply_q;
use pgo::se3::problem::{Problem3, weights3};
use pgo::se3::rounding::{Rt, point_of};
use pgo::se3::{Options3, rt_of, solve_graph3, solve_graph3_from};
use pgo::solve::{CertifyOptions, SolveOptions, certify_estimate3, solve3};
use std::process::Command;

fn read(name: &str) -> Graph3 {
    let path = datasets_dir().join(name);
    let bytes = std::fs::read(&path).unwrap();
    pgo::io::read3(&bytes, name, &ReadOptions::default())
        .unwrap()
        .0
}

fn pose(m: &Isometry3<f64>) -> Pose3 {
    let q = m.rotation.quaternion();
    Pose3 {
        translation: [m.translation.x, m.translation.y, m.translation.z],
        rotation: Rotation3::Quaternion([q.i, q.j, q.k, q.w]),
    }
}

/// A graph over `truth` with edges `pairs`, each measurement perturbed by a rotation of
/// `sigma_r` rad (per axis-angle component) and a translation of `sigma_t`; information
/// diag(w_t·I, w_r·I).
fn synthetic(
    truth: &[Isometry3<f64>],
    pairs: &[(usize, usize)],
    sigma_r: f64,
    sigma_t: f64,
    seed: u64,
) -> Graph3 {
    let mut rng = pgo::linalg::rng::Rng::new(seed);
    let mut info = [0.0; 21];
    for (k, v) in [
        (0, 4.0),
        (6, 4.0),
        (11, 4.0),
        (15, 100.0),
        (18, 100.0),
        (20, 100.0),
    ] {
        info[k] = v;
    }
    let edges = pairs
        .iter()
        .map(|&(i, j)| {
            let z = truth[i].inverse() * truth[j];
            let noise = Isometry3::new(
                Vector3::new(rng.normal(), rng.normal(), rng.normal()) * sigma_t,
                Vector3::new(rng.normal(), rng.normal(), rng.normal()) * sigma_r,
            );
            Edge3 {
                i,
                j,
                measurement: pose(&(z * noise)),
                information: SymMat6(info),
            }
        })
        .collect();
    Graph3 {
        ids: (0..truth.len() as u32).collect(),
        poses: truth.iter().map(pose).collect(),
        edges,
        fixed: Vec::new(),
        form: Form3::G2o,
    }
}

/// Random poses (rotations spread over the whole of SO(3)), a chain and `loops` random loop
/// closures.
fn random_graph(n: usize, loops: usize, seed: u64) -> (Vec<Isometry3<f64>>, Vec<(usize, usize)>) {
    let mut rng = pgo::linalg::rng::Rng::new(seed);
    let truth: Vec<Isometry3<f64>> = (0..n)
        .map(|_| {
            Isometry3::new(
                Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 3.0,
                Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 2.0,
            )
        })
        .collect();
    let mut pairs: Vec<(usize, usize)> = (0..n - 1).map(|k| (k, k + 1)).collect();
    while pairs.len() < n - 1 + loops {
        let a = (rng.uniform() * n as f64) as usize % n;
        let b = (rng.uniform() * n as f64) as usize % n;
        if a + 1 < b {
            pairs.push((a, b));
        }
    }
    (truth, pairs)
}

fn isometry(p: &Rt) -> Isometry3<f64> {
    let r = Matrix3::from_row_slice(&p.r);
    let q = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(r));
    Isometry3::from_parts(p.t.into(), q)
}

/// f written again from its definition (SE-Sync's eq. (1) with its weights), pose by pose with
/// nalgebra: κ‖R_j − R_i R̃‖_F² + τ‖t_j − t_i − R_i t̃‖².
fn formula(graph: &Graph3, poses: &[Isometry3<f64>]) -> f64 {
    graph
        .edges
        .iter()
        .map(|e| {
            let tt = Matrix3::from_fn(|r, c| e.information.get(r, c));
            let rr = Matrix3::from_fn(|r, c| e.information.get(3 + r, 3 + c));
            let tau = 3.0 / tt.try_inverse().unwrap().trace();
            let kappa = 3.0 / (2.0 * rr.try_inverse().unwrap().trace());
            let z = e.measurement.to_isometry();
            let (ri, rj) = (
                poses[e.i].rotation.to_rotation_matrix().into_inner(),
                poses[e.j].rotation.to_rotation_matrix().into_inner(),
            );
            let rz = z.rotation.to_rotation_matrix().into_inner();
            let dt = poses[e.j].translation.vector
                - poses[e.i].translation.vector
                - ri * z.translation.vector;
            kappa * (rj - ri * rz).norm_squared() + tau * dt.norm_squared()
        })
        .sum()
}

#[test]
fn weights_follow_se_syncs_rule() {
    // Ω = diag(1, 2, 4, 10, 20, 40): τ = 3/(1 + 1/2 + 1/4), κ = 3/(2(1/10 + 1/20 + 1/40)).
    let (truth, pairs) = random_graph(2, 0, 1);
    let mut g = synthetic(&truth, &pairs, 0.0, 0.0, 1);
    let mut info = [0.0; 21];
    for (k, v) in [
        (0, 1.0),
        (6, 2.0),
        (11, 4.0),
        (15, 10.0),
        (18, 20.0),
        (20, 40.0),
    ] {
        info[k] = v;
    }
    g.edges[0].information = SymMat6(info);
    let w = weights3(&g, false).unwrap();
    assert!((w[0].tau - 3.0 / 1.75).abs() < 1e-14);
    assert!((w[0].kappa - 3.0 / (2.0 * 0.175)).abs() < 1e-13);
    let u = weights3(&g, true).unwrap();
    assert_eq!((u[0].tau, u[0].kappa), (1.0, 1.0));
    // Not positive definite: an error naming the edge.
    g.edges[0].information = SymMat6([0.0; 21]);
    let err = weights3(&g, false).unwrap_err().to_string();
    assert!(err.contains("edge 0 -> 1"), "{err}");
}

#[test]
fn the_data_matrix_gives_the_edge_by_edge_formula() {
    // At poses away from any optimum: tr(XᵀQX) from Q's blocks, the solver's cost and the
    // formula written with nalgebra agree.
    let g = read("smallGrid3D.g2o");
    let w = weights3(&g, false).unwrap();
    let mut rng = pgo::linalg::rng::Rng::new(5);
    let poses: Vec<Isometry3<f64>> = g
        .poses
        .iter()
        .map(|p| {
            p.to_isometry()
                * Isometry3::new(
                    Vector3::new(rng.normal(), rng.normal(), rng.normal()),
                    Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3,
                )
        })
        .collect();
    let expected = formula(&g, &poses);
    for anchor in [0, 17, g.num_poses() - 1] {
        let problem = Problem3::new(&g, &w, anchor);
        let rts: Vec<Rt> = poses.iter().map(|m| rt_of(&pose(m))).collect();
        let x = point_of(&problem, &rts);
        let qx = apply_q(&problem, &x);
        let quadratic: f64 = x.x.iter().zip(&qx).map(|(a, b)| a * b).sum();
        let edges = problem.cost(&x);
        let ev = problem.evaluate(&x);
        assert!(
            (quadratic - expected).abs() <= 1e-9 * expected,
            "{quadratic} vs {expected}"
        );
        assert!(
            (edges - expected).abs() <= 1e-11 * expected,
            "{edges} vs {expected}"
        );
        // The rounding bound of the enclosure covers the difference to the formula.
        assert!((ev.cost - expected).abs() <= ev.cost_error + 1e-12 * expected);
    }
}

#[test]
fn exact_measurements_cost_zero_and_the_poses_come_back() {
    let (truth, pairs) = random_graph(40, 40, 7);
    let g = synthetic(&truth, &pairs, 0.0, 0.0, 7);
    let w = weights3(&g, false).unwrap();
    let s = solve_graph3(&g, &w, &Options3::default(), &mut |_| {});
    let scale: f64 = w.iter().map(|w| w.tau + w.kappa).sum();
    assert!(s.cost <= 1e-20 * scale, "{}", s.cost);
    assert!(s.certified, "{:?}", s.not_certified_because);
    assert!(s.lower_bound <= s.cost);
    // Up to the gauge: every pose relative to pose 0 as in the truth.
    let est: Vec<Isometry3<f64>> = s.poses.iter().map(isometry).collect();
    for k in 0..truth.len() {
        let a = truth[0].inverse() * truth[k];
        let b = est[0].inverse() * est[k];
        assert!(
            (a.translation.vector - b.translation.vector).norm() < 1e-9,
            "pose {k}"
        );
        assert!(a.rotation.angle_to(&b.rotation) < 1e-9, "pose {k}");
    }
}

#[test]
fn a_tree_is_composed_at_zero_cost_where_the_staircase_finds_its_optimum() {
    // A random tree (pose k hangs from a random earlier pose, some edges reversed) with noisy
    // measurements and the vertices at the truth, which the noise moves the optimum away from.
    let mut rng = pgo::linalg::rng::Rng::new(11);
    let (truth, _) = random_graph(60, 0, 11);
    let pairs: Vec<(usize, usize)> = (1..truth.len())
        .map(|k| {
            let parent = (rng.uniform() * k as f64) as usize;
            if rng.uniform() < 0.3 {
                (k, parent)
            } else {
                (parent, k)
            }
        })
        .collect();
    let mut g = synthetic(&truth, &pairs, 0.2, 0.5, 11);
    g.fixed = vec![7];
    let options = SolveOptions::default();
    let tree = solve3(&g, &options).unwrap();
    assert_eq!(tree.components[0].method, pgo::solve::Method::Tree);
    assert!(tree.certified && tree.szep && tree.lower_bound == 0.0);
    // The cost of the composition, by the formula written again: rounding alone.
    let est: Vec<Isometry3<f64>> = tree.estimate.iter().map(|p| p.to_isometry()).collect();
    let f = formula(&g, &est);
    assert!(f < 1e-20 && tree.cost < 1e-20, "{f} {}", tree.cost);
    assert_eq!(tree.estimate[7], g.poses[7], "the FIX pose stays as read");
    // The staircase, asked for, independently: certified at a cost of rounding too, at the same
    // poses up to rounding.
    let asked = SolveOptions {
        method: pgo::solve::Method::Staircase,
        ..Default::default()
    };
    let staircase = solve3(&g, &asked).unwrap();
    assert_eq!(
        staircase.components[0].method,
        pgo::solve::Method::Staircase
    );
    assert!(
        staircase.certified && staircase.cost < 1e-12,
        "{}",
        staircase.cost
    );
    for (a, b) in tree.estimate.iter().zip(&staircase.estimate) {
        let (a, b) = (a.to_isometry(), b.to_isometry());
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-8);
        assert!(a.rotation.angle_to(&b.rotation) < 1e-8);
    }
    // pgo-certify's bound of the composition moved off its optimum: 0, the optimum's.
    let moved: Vec<Pose3> = est
        .iter()
        .map(|x| pose(&(x * Isometry3::new(Vector3::new(0.1, 0.0, 0.0), Vector3::zeros()))))
        .collect();
    let report = certify_estimate3(&g, &moved, &CertifyOptions::default(), "x").unwrap();
    assert_eq!(report.lower_bound, 0.0);
    assert!(!report.certified && report.cost > 1e-3);
    // One loop closure more: no longer a tree.
    let mut closed = g.clone();
    closed.edges.push(Edge3 {
        i: 0,
        j: 59,
        ..g.edges[0]
    });
    let solved = solve3(&closed, &options).unwrap();
    assert_eq!(solved.components[0].method, pgo::solve::Method::Staircase);
    assert!(solved.cost > 1e-3);
}

#[test]
#[allow(clippy::needless_range_loop)]
fn at_the_certified_optimum_s_annihilates_x_and_the_bound_is_below_the_cost() {
    let g = read("smallGrid3D.g2o");
    let w = weights3(&g, false).unwrap();
    let s = solve_graph3(&g, &w, &Options3::default(), &mut |_| {});
    assert!(s.certified);
    let bound = s.bound.unwrap();
    assert_eq!(bound.deflated, Some(3));
    assert!(s.lower_bound <= s.cost && s.cost - s.lower_bound <= 1e-6 * s.cost);
    // S X = QX − blkdiag(0, Λ)X with Λ_i = sym((QX)_i X_iᵀ): zero to the accuracy of the
    // optimum, relative to |Q||X|.
    let problem = Problem3::new(&g, &w, 0);
    let x = point_of(&problem, &s.poses);
    let ev = problem.evaluate(&x);
    let lambda = problem.multipliers(&x, &ev.qx);
    // ‖SX‖_F against ‖QX‖_F (the two terms it is the difference of are of that size).
    let (mut sx, mut qx) = (0.0, 0.0);
    for r in 0..problem.dim() {
        for c in 0..3 {
            let mut v = ev.qx[r * 3 + c];
            qx += v * v;
            if r >= problem.n - 1 {
                let (i, a) = ((r - (problem.n - 1)) / 3, (r - (problem.n - 1)) % 3);
                for b in 0..3 {
                    v -= lambda[i][a][b] * x.x[problem.rotation_row(i, b) * 3 + c];
                }
            }
            sx += v * v;
        }
    }
    // SX is half the Riemannian gradient (the translations' rows zero at their optimum, the
    // rotations' the projection of QX onto the tangent space): its norm is half the gradient
    // norm the solver reports from its own tangent coordinates, and small against ‖QX‖ (the
    // size of the two terms it is the difference of) to the accuracy Newton's stopping rule
    // leaves.
    assert!(
        (sx.sqrt() - s.gradient_norm / 2.0).abs() <= 1e-6 * sx.sqrt() + 1e-14 * qx.sqrt(),
        "{} vs {}",
        sx.sqrt(),
        s.gradient_norm / 2.0
    );
    assert!(
        sx.sqrt() <= 1e-7 * qx.sqrt(),
        "{} vs {}",
        sx.sqrt(),
        qx.sqrt()
    );
    // The bound is the dual value Σ tr Λ − 3nη.
    let trace: f64 = lambda.iter().map(|l| l[0][0] + l[1][1] + l[2][2]).sum();
    assert!((trace - 3.0 * problem.n as f64 * bound.eta - bound.lower_bound).abs() < 1e-9 * trace);
}

#[test]
fn the_optimum_does_not_depend_on_the_pose_order_or_the_frame() {
    let g = read("smallGrid3D.g2o");
    let options = SolveOptions::default();
    let base = solve3(&g, &options).unwrap();
    assert!(base.certified);
    // Ids relabeled by a permutation (so the internal order, the anchor and the elimination
    // order all change).
    let n = g.num_poses();
    let perm: Vec<usize> = (0..n).map(|k| (k * 37 + 11) % n).collect();
    let mut moved = Graph3 {
        ids: (0..n as u32).collect(),
        poses: vec![Pose3::IDENTITY; n],
        edges: Vec::new(),
        fixed: Vec::new(),
        form: g.form,
    };
    for (k, &to) in perm.iter().enumerate() {
        moved.poses[to] = g.poses[k];
    }
    moved.edges = g
        .edges
        .iter()
        .map(|e| Edge3 {
            i: perm[e.i],
            j: perm[e.j],
            ..*e
        })
        .collect();
    let permuted = solve3(&moved, &options).unwrap();
    assert!(permuted.certified);
    assert!((permuted.cost - base.cost).abs() <= 1e-9 * base.cost);
    // The optimum moved by a rigid motion of the whole map: the same cost, certified again.
    let motion = Isometry3::new(Vector3::new(5.0, -2.0, 1.0), Vector3::new(0.3, -1.2, 2.0));
    let rotated: Vec<Pose3> = base
        .estimate
        .iter()
        .map(|p| pose(&(motion * p.to_isometry())))
        .collect();
    let report = certify_estimate3(&g, &rotated, &CertifyOptions::default(), "test").unwrap();
    assert!(report.certified);
    assert_eq!(report.components[0].bound_from, "estimate");
    assert!((report.cost - base.cost).abs() <= 1e-9 * base.cost);
}

/// SE-Sync's Table 2 (Rosen et al., IJRR 2019), 4 significant digits: f* and each certified.
/// (All four take about 4 s in release; run with --release.)
#[test]
fn se_syncs_published_optima() {
    for (name, optimum) in [
        ("parking-garage.g2o", 1.263e0),
        ("sphere2500.g2o", 1.687e3),
        ("torus3D.g2o", 2.423e4),
        ("cubicle.g2o", 7.171e2),
    ] {
        let g = read(name);
        let s = solve3(&g, &SolveOptions::default()).unwrap();
        assert!(s.certified, "{name}: {:?}", s.not_certified_because);
        assert!(s.szep, "{name}");
        let rounded: f64 = format!("{:.3e}", s.cost).parse().unwrap();
        assert_eq!(rounded, optimum, "{name}: {}", s.cost);
        assert!(s.lower_bound <= s.cost);
        assert!(s.relative_suboptimality_bound <= 1e-6);
    }
}

#[test]
fn the_staircase_lifts_where_rank_3_fails_and_its_bounds_hold() {
    // Random graphs with noise large enough that the first rank-3 Newton point is not
    // certified: the staircase lifts; whatever it ends with, the bound holds: it lies below
    // the cost of every estimate found from random starts.
    let mut lifted = 0;
    for seed in 0..6u64 {
        let (truth, pairs) = random_graph(30, 30, seed);
        let g = synthetic(&truth, &pairs, 0.8, 0.5, seed);
        let w = weights3(&g, false).unwrap();
        let s = solve_graph3(&g, &w, &Options3::default(), &mut |_| {});
        eprintln!(
            "seed {seed}: rank {} cost {} bound {} certified {}",
            s.rank, s.cost, s.lower_bound, s.certified
        );
        assert!(s.lower_bound <= s.cost + 1e-9 * s.cost, "{seed}");
        if s.rank > 3 {
            lifted += 1;
        }
        let mut rng = pgo::linalg::rng::Rng::new(100 + seed);
        for _ in 0..3 {
            let start: Vec<Rt> = (0..g.num_poses())
                .map(|_| {
                    let q = UnitQuaternion::from_quaternion(Quaternion::new(
                        rng.normal(),
                        rng.normal(),
                        rng.normal(),
                        rng.normal(),
                    ));
                    rt_of(&pose(&Isometry3::from_parts(Default::default(), q)))
                })
                .collect();
            let other = solve_graph3_from(&g, &w, Some(&start), &Options3::default(), &mut |_| {});
            assert!(s.lower_bound <= other.cost * (1.0 + 1e-12), "{seed}");
            assert!(other.lower_bound <= s.cost * (1.0 + 1e-12), "{seed}");
        }
    }
    assert!(lifted > 0, "no graph needed the staircase");
}

fn run(tool: &str, args: &[&str]) -> std::process::Output {
    Command::new(bin(tool)).args(args).output().unwrap()
}

fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn pgo_solve_writes_a_3d_estimate_that_pgo_certify_certifies() {
    let dir = Dir::new();
    let input = datasets_dir().join("smallGrid3D.g2o");
    let output = dir.path("opt.g2o");
    let out = run("pgo-solve", &[s(&input), "-o", s(&output), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let r = json(&out);
    for field in [
        "cost",
        "lower_bound",
        "suboptimality_bound",
        "relative_suboptimality_bound",
        "certified",
        "chi2",
        "components",
        "timings",
    ] {
        assert!(r.get(field).is_some(), "{field}: {r}");
    }
    assert_eq!(r["dimension"], 3);
    assert_eq!(r["certified"], true);
    assert_eq!(r["components"][0]["rank"], 3);
    let cost = r["cost"].as_f64().unwrap();
    // The written file: the same graph (edges kept as read), the optimal poses, the first pose
    // where the input has it.
    let written = std::fs::read_to_string(&output).unwrap();
    let original = std::fs::read_to_string(&input).unwrap();
    let edges = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| l.starts_with("EDGE"))
            .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
            .collect()
    };
    assert_eq!(edges(&written).len(), edges(&original).len());
    let first = |t: &str| {
        t.lines()
            .find(|l| l.starts_with("VERTEX_SE3:QUAT 0 "))
            .unwrap()
            .split_whitespace()
            .skip(2)
            .map(|v| v.parse::<f64>().unwrap())
            .collect::<Vec<_>>()
    };
    assert_eq!(first(&written), first(&original));
    let out = run("pgo-certify", &[s(&output), "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let c = json(&out);
    assert_eq!(c["certified"], true);
    assert_eq!(c["components"][0]["bound_from"], "estimate");
    assert!((c["cost"].as_f64().unwrap() - cost).abs() <= 1e-9 * cost);
    // The same through --estimate.
    let out = run("pgo-certify", &[s(&input), "--estimate", s(&output)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("certified optimal"));
}

#[test]
fn pgo_certify_rejects_a_perturbed_3d_estimate_with_a_positive_gap() {
    let dir = Dir::new();
    let input = datasets_dir().join("smallGrid3D.g2o");
    let output = dir.path("opt.g2o");
    let out = run("pgo-solve", &[s(&input), "-o", s(&output), "--json"]);
    assert!(out.status.success());
    // One pose moved by 5 cm: a feasible estimate that is not optimal.
    let text_opt = std::fs::read_to_string(&output).unwrap();
    let perturbed: String = text_opt
        .lines()
        .map(|l| {
            if l.starts_with("VERTEX_SE3:QUAT 60 ") {
                let mut f: Vec<String> = l.split_whitespace().map(String::from).collect();
                let x: f64 = f[2].parse().unwrap();
                f[2] = (x + 0.05).to_string();
                f.join(" ")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let bad = dir.file("bad.g2o", perturbed.as_bytes());
    let out = run("pgo-certify", &[s(&bad), "--json"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let c = json(&out);
    assert_eq!(c["certified"], false);
    let gap = c["suboptimality_bound"].as_f64().unwrap();
    assert!(gap > 0.0, "{c}");
    // The bound is the optimum's, below the optimal cost.
    let best = json(&run("pgo-certify", &[s(&output), "--json"]));
    assert!(c["lower_bound"].as_f64().unwrap() <= best["cost"].as_f64().unwrap());
    assert!(c["cost"].as_f64().unwrap() > best["cost"].as_f64().unwrap());
}

#[test]
fn options_that_do_not_apply_to_3d_are_refused_with_status_2() {
    let dir = Dir::new();
    let input = datasets_dir().join("tinyGrid3D.g2o");
    let output = dir.path("out.g2o");
    for flags in [
        &["--robust", "tls"][..],
        &["--method", "sdp"],
        &["--refine", "--marginals", "m.txt"],
    ] {
        let mut args = vec![s(&input), "-o", s(&output)];
        args.extend_from_slice(flags);
        let out = run("pgo-solve", &args);
        assert_eq!(out.status.code(), Some(2), "{flags:?}");
        let err = text(&out.stderr);
        assert!(
            err.contains("not implemented for 3D graphs"),
            "{flags:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert!(!output.exists(), "{flags:?}");
    }
    // A planar estimate for a 3D graph.
    let planar = datasets_dir().join("MIT.g2o");
    let out = run("pgo-certify", &[s(&input), "--estimate", s(&planar)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("planar"),
        "{}",
        text(&out.stderr)
    );
}

/// A TORO 3D file (Euler angles) with two components, one with a FIX line: pgo-solve writes
/// TORO back, the FIX pose and each component's first pose exactly as read, both components
/// certified; pgo-certify certifies what it wrote.
#[test]
fn toro_3d_with_two_components_and_a_fix_pose() {
    let dir = Dir::new();
    let (a, pa) = random_graph(12, 8, 21);
    let (b, pb) = random_graph(9, 5, 22);
    let mut truth = a.clone();
    truth.extend(b.iter().copied());
    let mut pairs = pa.clone();
    pairs.extend(pb.iter().map(|&(i, j)| (i + 12, j + 12)));
    let mut g = synthetic(&truth, &pairs, 0.05, 0.05, 3);
    g.form = Form3::Toro;
    let euler = |p: &Pose3| {
        let (r, pi, y) = p.to_isometry().rotation.euler_angles();
        Pose3 {
            translation: p.translation,
            rotation: Rotation3::Euler([r, pi, y]),
        }
    };
    g.poses = g.poses.iter().map(euler).collect();
    for e in &mut g.edges {
        e.measurement = euler(&e.measurement);
    }
    g.fixed = vec![15];
    let mut bytes = Vec::new();
    pgo::io::write3(&g, pgo::io::Format::Toro, &mut bytes).unwrap();
    let input = dir.file("two.graph", &bytes);
    let output = dir.path("two-opt.graph");
    // --refine: g2o's error is not defined over Euler angles' information; refused, nothing
    // written.
    let refused = run("pgo-solve", &[s(&input), "-o", s(&output), "--refine"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(text(&refused.stderr).contains("Euler angles"));
    assert!(!output.exists());
    let out = run("pgo-solve", &[s(&input), "-o", s(&output), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let r = json(&out);
    assert_eq!(r["components"].as_array().unwrap().len(), 2);
    assert_eq!(r["certified"], true, "{r}");
    assert!(r["chi2"].is_null());
    let written = std::fs::read_to_string(&output).unwrap();
    assert!(written.lines().all(|l| !l.starts_with("VERTEX_SE3")));
    let original = String::from_utf8(bytes).unwrap();
    for id in [0, 15] {
        let line = |t: &str| {
            t.lines()
                .find(|l| l.starts_with(&format!("VERTEX3 {id} ")))
                .unwrap()
                .to_string()
        };
        assert_eq!(line(&written), line(&original), "pose {id}");
    }
    // Component 2's first pose (12) moved: the FIX pose 15 holds the gauge there.
    let out = run("pgo-certify", &[s(&output), "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let c = json(&out);
    assert_eq!(c["certified"], true);
    assert!(
        (c["cost"].as_f64().unwrap() - r["cost"].as_f64().unwrap()).abs()
            <= 1e-9 * r["cost"].as_f64().unwrap()
    );
}
