//! Same input and flags, the same bytes on one core or two: `pgo-solve` pinned to one CPU
//! (`taskset -c 0`, so that it finds no second core and runs every task on one thread) and free
//! to use two writes the same JSON report and the same estimate, for a pose graph, a landmark
//! graph, a 3D graph, graphs whose Newton factorizations are split between the cores and a
//! robust (GNC) run. `pgo::linalg::parallel` promises this: only whole, independent tasks run
//! side by side, and where a factorization is split (`pgo::linalg::tree_factor`) the order of
//! its sums depends on the split, not on the threads.

mod common;

use std::process::Command;

/// The JSON report and the written estimate, with `cpus` CPUs allowed (`None`: all of them).
fn run(args: &[&str], cpus: Option<&str>) -> (Vec<u8>, Vec<u8>) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.g2o");
    let bin = env!("CARGO_BIN_EXE_pgo-solve");
    let mut cmd = match cpus {
        Some(list) => {
            let mut c = Command::new("taskset");
            c.args(["-c", list, bin]);
            c
        }
        None => Command::new(bin),
    };
    let o = cmd
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .args(["--json", "--no-timings", "-o", out.to_str().unwrap()])
        .output()
        .expect("taskset (util-linux) runs");
    assert!(o.status.code().is_some_and(|c| c <= 1), "{o:?}");
    (o.stdout, std::fs::read(&out).unwrap())
}

fn same_bytes(args: &[&str]) {
    let two_cores = std::thread::available_parallelism().is_ok_and(|c| c.get() > 1);
    assert!(
        two_cores,
        "this test compares one core against two and needs a machine with two"
    );
    let one = run(args, Some("0"));
    let both = run(args, None);
    assert!(one.0 == both.0, "{args:?}: the JSON reports differ");
    assert!(one.1 == both.1, "{args:?}: the estimates differ");
}

#[test]
fn a_pose_graph_is_solved_to_the_same_bytes() {
    same_bytes(&["datasets/MIT.g2o"]);
}

#[test]
fn a_landmark_graph_is_solved_to_the_same_bytes() {
    let file = common::datasets_dir().join("victoriaPark.g2o");
    same_bytes(&[file.to_str().unwrap()]);
}

#[test]
fn a_3d_graph_is_solved_to_the_same_bytes() {
    let file = common::datasets_dir().join("smallGrid3D.g2o");
    same_bytes(&[file.to_str().unwrap()]);
    // 6275 edges: its estimate's edge lines are formatted on two threads when two are free.
    let file = common::datasets_dir().join("parking-garage.g2o");
    same_bytes(&[file.to_str().unwrap()]);
}

/// M3500's planar Newton systems and sphere2500's 3D ones are factored by the split LLᵀ, and
/// city10000's and sphere2500's certificates by the split LDLᴴ, on both cores where the second
/// is free and one after the other where it is not.
#[test]
fn graphs_whose_factorizations_are_split_are_solved_to_the_same_bytes() {
    for name in ["M3500.g2o", "sphere2500.g2o", "city10000.g2o"] {
        let file = common::datasets_dir().join(name);
        same_bytes(&[file.to_str().unwrap()]);
    }
}

#[test]
fn a_robust_run_is_the_same_bytes() {
    same_bytes(&["datasets/MIT.g2o", "--robust", "tls", "--certify-inner"]);
}
