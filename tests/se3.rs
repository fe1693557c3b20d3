//! The certified SE(3) solver (issue 15, second landing).

mod common;

use pgo::graph3::Graph3;
use pgo::io::ReadOptions;
use pgo::se3::problem::weights3;
use pgo::se3::{Options3, solve_graph3};

fn read(name: &str) -> Graph3 {
    let path = common::datasets_dir().join(name);
    let bytes = std::fs::read(&path).unwrap();
    pgo::io::read3(&bytes, name, &ReadOptions::default())
        .unwrap()
        .0
}

#[test]
fn experiment() {
    for name in std::env::var("SE3_FILES")
        .unwrap_or("tinyGrid3D.g2o smallGrid3D.g2o".into())
        .split_whitespace()
    {
        let g = read(name);
        let w = weights3(&g, false).unwrap();
        let t = std::time::Instant::now();
        let s = solve_graph3(&g, &w, &Options3::default(), &mut |st| {
            eprintln!(
                "  rank {} it {} cost {:.12e} grad {:.3e} mu {:.1e}",
                st.rank, st.iteration, st.cost, st.gradient_norm, st.damping
            )
        });
        eprintln!(
            "{name}: cost {:.10e} lb {:.10e} certified {} rank {} it {} grad {:.2e} {:?} bound {:?} {:?}",
            s.cost,
            s.lower_bound,
            s.certified,
            s.rank,
            s.iterations,
            s.gradient_norm,
            s.not_certified_because,
            s.bound,
            t.elapsed()
        );
    }
}

#[test]
fn experiment_random_start() {
    use pgo::se3::rounding::Rt;
    use pgo::se3::solve_graph3_from;
    let g = read("smallGrid3D.g2o");
    let w = weights3(&g, false).unwrap();
    for seed in 0..5u64 {
        let mut rng = pgo::linalg::rng::Rng::new(seed);
        let start: Vec<Rt> = (0..g.num_poses())
            .map(|_| {
                let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(rng.normal(), rng.normal(), rng.normal(), rng.normal()));
                let m = q.to_rotation_matrix();
                let mut r = [0.0; 9];
                for k in 0..9 { r[k] = m[(k / 3, k % 3)]; }
                Rt { r, t: [0.0; 3] }
            })
            .collect();
        let s = solve_graph3_from(&g, &w, Some(&start), &Options3::default(), &mut |st| {
            if st.rank > 3 { eprintln!("  rank {} it {} cost {:.12e}", st.rank, st.iteration, st.cost) }
        });
        eprintln!("seed {seed}: cost {:.10e} lb {:.10e} certified {} rank {} it {} {:?}", s.cost, s.lower_bound, s.certified, s.rank, s.iterations, s.not_certified_because);
    }
}

/// A graph over `truth` with edges `pairs`, measurements perturbed by rotation noise of
/// `sigma_r` rad (axis-angle, each component) and translation noise `sigma_t`, information I.
fn synthetic(
    truth: &[nalgebra::Isometry3<f64>],
    pairs: &[(usize, usize)],
    sigma_r: f64,
    sigma_t: f64,
    seed: u64,
) -> Graph3 {
    use pgo::graph3::{Edge3, Form3, Pose3, Rotation3, SymMat6};
    let mut rng = pgo::linalg::rng::Rng::new(seed);
    let pose = |m: &nalgebra::Isometry3<f64>| {
        let q = m.rotation.quaternion();
        Pose3 {
            translation: [m.translation.x, m.translation.y, m.translation.z],
            rotation: Rotation3::Quaternion([q.i, q.j, q.k, q.w]),
        }
    };
    let mut info = [0.0; 21];
    for k in [0, 6, 11, 15, 18, 20] {
        info[k] = 1.0;
    }
    let edges = pairs
        .iter()
        .map(|&(i, j)| {
            let z = truth[i].inverse() * truth[j];
            let noise = nalgebra::Isometry3::new(
                nalgebra::Vector3::new(rng.normal(), rng.normal(), rng.normal()) * sigma_t,
                nalgebra::Vector3::new(rng.normal(), rng.normal(), rng.normal()) * sigma_r,
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

fn random_poses(n: usize, seed: u64, spread: f64) -> Vec<nalgebra::Isometry3<f64>> {
    let mut rng = pgo::linalg::rng::Rng::new(seed);
    (0..n)
        .map(|_| {
            nalgebra::Isometry3::new(
                nalgebra::Vector3::new(rng.normal(), rng.normal(), rng.normal()) * spread,
                nalgebra::Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 2.0,
            )
        })
        .collect()
}

#[test]
fn experiment_hard() {
    for seed in 0..40u64 {
        let n = 30;
        let truth = random_poses(n, seed, 3.0);
        let mut pairs: Vec<(usize, usize)> = (0..n - 1).map(|k| (k, k + 1)).collect();
        let mut rng = pgo::linalg::rng::Rng::new(1000 + seed);
        for _ in 0..30 {
            let (a, b) = ((rng.uniform() * n as f64) as usize, (rng.uniform() * n as f64) as usize);
            if a != b { pairs.push((a.min(b), a.max(b))); }
        }
        let sr: f64 = std::env::var("SR").map(|s| s.parse().unwrap()).unwrap_or(0.6); let g = synthetic(&truth, &pairs, sr, 0.5, seed);
        let w = weights3(&g, false).unwrap();
        let s = solve_graph3(&g, &w, &Options3::default(), &mut |_| {});
        eprintln!("seed {seed}: cost {:.10e} lb {:.10e} certified {} rank {} it {} {:?}", s.cost, s.lower_bound, s.certified, s.rank, s.iterations, s.not_certified_because);
    }
}
