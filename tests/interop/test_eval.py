"""pgo-eval against evo (PyPI evo): APE and RPE of a pgo-solve estimate against ground truth.

The trajectories are handed to evo as TUM files written here from the g2o vertex lines (t = the
vertex id, z = 0, the heading as a rotation about z), so evo reads the same poses pgo-eval reads
from the g2o files; evo aligns with Umeyama's method in 3D (no scale), which for planar
trajectories is the SE(2) alignment pgo-eval computes.
"""

import json
import math
import subprocess

import pytest

from evo.core import metrics as evo_metrics
from evo.tools import file_interface

from conftest import pgo_binary


def g2o_poses(path):
    poses = {}
    for line in open(path):
        t = line.split()
        if t and t[0] == "VERTEX_SE2":
            poses[int(t[1])] = tuple(float(v) for v in t[2:5])
    return poses


def write_tum(poses, path):
    with open(path, "w") as f:
        for i in sorted(poses):
            x, y, th = poses[i]
            f.write(f"{i} {x!r} {y!r} 0 0 0 {math.sin(th / 2)!r} {math.cos(th / 2)!r}\n")


def close(a, b, rel=1e-9, abs_=1e-12):
    return abs(a - b) <= rel * max(abs(a), abs(b)) + abs_


@pytest.fixture(scope="module")
def ring(datasets_dir, tmp_path_factory):
    d = tmp_path_factory.mktemp("eval")
    est = d / "ring-opt.g2o"
    subprocess.run(
        [pgo_binary("pgo-solve"), datasets_dir / "ring.g2o", "-o", est, "--json"],
        check=True,
        capture_output=True,
    )
    gt = datasets_dir / "ring_groundtruth.g2o"
    write_tum(g2o_poses(est), d / "est.tum")
    write_tum(g2o_poses(gt), d / "gt.tum")
    return est, gt, d / "est.tum", d / "gt.tum"


def pgo_eval(est, gt, *flags):
    out = subprocess.run(
        [pgo_binary("pgo-eval"), est, gt, "--json", *flags],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout)


STATS = ["rmse", "mean", "median", "std", "min", "max"]


def assert_same(ours, evo_stats, what):
    for key in STATS:
        assert close(ours[key], evo_stats[key]), (what, key, ours[key], evo_stats[key])


def test_ape_equals_evo(ring):
    est, gt, est_tum, gt_tum = ring
    ours = pgo_eval(est, gt)
    for relation, key in [
        (evo_metrics.PoseRelation.translation_part, "translation"),
        (evo_metrics.PoseRelation.rotation_angle_deg, "rotation_deg"),
    ]:
        ref = file_interface.read_tum_trajectory_file(str(gt_tum))
        traj = file_interface.read_tum_trajectory_file(str(est_tum))
        traj.align(ref, correct_scale=False)
        ape = evo_metrics.APE(relation)
        ape.process_data((ref, traj))
        assert_same(ours["ape"][key], ape.get_all_statistics(), f"APE {key}")
    assert ours["matched"] == 434


@pytest.mark.parametrize("delta,all_pairs", [(1, False), (10, False), (10, True)])
def test_rpe_equals_evo(ring, delta, all_pairs):
    est, gt, est_tum, gt_tum = ring
    ours = pgo_eval(est, gt, "--delta", str(delta), *(["--all-pairs"] if all_pairs else []))
    for relation, key in [
        (evo_metrics.PoseRelation.translation_part, "translation"),
        (evo_metrics.PoseRelation.rotation_angle_deg, "rotation_deg"),
    ]:
        ref = file_interface.read_tum_trajectory_file(str(gt_tum))
        traj = file_interface.read_tum_trajectory_file(str(est_tum))
        rpe = evo_metrics.RPE(
            relation, delta=delta, delta_unit=evo_metrics.Unit.frames, all_pairs=all_pairs
        )
        rpe.process_data((ref, traj))
        assert_same(ours["rpe"][key], rpe.get_all_statistics(), f"RPE {key} delta {delta}")
        assert ours["rpe"][key]["count"] == len(rpe.error)


@pytest.mark.parametrize("fmt", ["tum", "kitti"])
def test_evo_reads_pgo_trajectories_with_pgo_evals_ape(ring, fmt, tmp_path):
    """pgo-convert --to tum|kitti: evo reads both trajectories, and its APE (aligned) equals
    pgo-eval's on the g2o files."""
    est, gt, _, _ = ring
    files = {}
    for name, path in [("est", est), ("gt", gt)]:
        out = tmp_path / f"{name}.{fmt}"
        subprocess.run(
            [pgo_binary("pgo-convert"), path, "--to", fmt, "-o", out, "-q"],
            check=True,
            capture_output=True,
        )
        files[name] = str(out)
    if fmt == "tum":
        ref = file_interface.read_tum_trajectory_file(files["gt"])
        traj = file_interface.read_tum_trajectory_file(files["est"])
    else:
        ref = file_interface.read_kitti_poses_file(files["gt"])
        traj = file_interface.read_kitti_poses_file(files["est"])
    assert ref.num_poses == traj.num_poses == 434
    traj.align(ref, correct_scale=False)
    ours = pgo_eval(est, gt)
    for relation, key in [
        (evo_metrics.PoseRelation.translation_part, "translation"),
        (evo_metrics.PoseRelation.rotation_angle_deg, "rotation_deg"),
    ]:
        ape = evo_metrics.APE(relation)
        ape.process_data((ref, traj))
        assert_same(ours["ape"][key], ape.get_all_statistics(), f"{fmt} APE {key}")
