"""pgo-convert --to tum|kitti on 3D graphs, read by evo (PyPI evo).

The poses evo reads are held against the g2o file's vertex lines parsed here: translations bit
for bit, rotations those of the normalized quaternions (as g2o and pgo read them), built here
by the textbook formula. evo's APE between a pgo-solve estimate and the input's vertices is the
same whether the two trajectories went through TUM or KITTI files, and pgo-eval's APE and RPE
on the g2o files equal evo's on TUM files written here from the vertex lines.
"""

import json

import subprocess

import numpy as np
import pytest

from evo.core import metrics as evo_metrics
from evo.tools import file_interface

from conftest import pgo_binary


def g2o_poses3(path):
    """{id: (translation, unit quaternion [x, y, z, w])} from VERTEX_SE3:QUAT lines."""
    poses = {}
    for line in open(path):
        t = line.split()
        if t and t[0] == "VERTEX_SE3:QUAT":
            v = [float(a) for a in t[2:9]]
            q = np.array(v[3:7])
            poses[int(t[1])] = (np.array(v[:3]), q / np.linalg.norm(q))
    return poses


def rotation(q):
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def convert(path, fmt, out):
    subprocess.run(
        [pgo_binary("pgo-convert"), path, "--to", fmt, "-o", out, "-q"],
        check=True,
        capture_output=True,
    )
    if fmt == "tum":
        return file_interface.read_tum_trajectory_file(str(out))
    return file_interface.read_kitti_poses_file(str(out))


@pytest.fixture(scope="module")
def grid(datasets_dir, tmp_path_factory):
    d = tmp_path_factory.mktemp("traj3d")
    est = d / "smallGrid3D-opt.g2o"
    subprocess.run(
        [pgo_binary("pgo-solve"), datasets_dir / "smallGrid3D.g2o", "-o", est, "-q"],
        check=True,
        capture_output=True,
    )
    return d, est, datasets_dir / "smallGrid3D.g2o"


@pytest.mark.parametrize("fmt", ["tum", "kitti"])
def test_evo_reads_the_poses_of_3d_graphs(grid, fmt):
    d, est, _ = grid
    poses = g2o_poses3(est)
    traj = convert(est, fmt, d / f"est.{fmt}")
    ids = sorted(poses)
    assert traj.num_poses == len(ids) == 125
    if fmt == "tum":
        assert list(traj.timestamps) == [float(i) for i in ids]
    for k, i in enumerate(ids):
        t, q = poses[i]
        assert np.array_equal(traj.positions_xyz[k], t), i
        r = traj.poses_se3[k][:3, :3]
        # evo forms the matrix from the quaternion by its own sequence of products (normalized
        # again, an outer product): entries of magnitude at most 1 agree to a few roundings.
        assert np.abs(r - rotation(q)).max() <= 16 * np.finfo(float).eps, i


def test_evo_ape_is_the_same_through_tum_and_kitti(grid):
    d, est, reference = grid
    ape = {}
    for fmt in ["tum", "kitti"]:
        traj = convert(est, fmt, d / f"ape-est.{fmt}")
        ref = convert(reference, fmt, d / f"ape-ref.{fmt}")
        traj.align(ref, correct_scale=False)
        metric = evo_metrics.APE(evo_metrics.PoseRelation.translation_part)
        metric.process_data((ref, traj))
        ape[fmt] = metric.get_all_statistics()
    assert ape["tum"]["rmse"] > 0
    for key, value in ape["tum"].items():
        assert abs(value - ape["kitti"][key]) <= 1e-12 * max(1.0, abs(value)), key


def test_toro_3d_trajectories_carry_euler_rotations(tmp_path):
    # TORO's VERTEX3 x y z roll pitch yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
    path = tmp_path / "two.graph"
    path.write_text(
        "VERTEX3 0 0 0 0 0 0 0\n"
        "VERTEX3 1 1 2 3 0.1 -0.2 0.3\n"
        "EDGE3 0 1 1 2 3 0.1 -0.2 0.3 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
    )
    traj = convert(path, "kitti", tmp_path / "two.kitti")
    roll, pitch, yaw = 0.1, -0.2, 0.3
    rx = np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)], [0, np.sin(roll), np.cos(roll)]])
    ry = np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]])
    rz = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    assert np.abs(traj.poses_se3[1][:3, :3] - rz @ ry @ rx).max() < 1e-15
    assert np.array_equal(traj.positions_xyz[1], [1.0, 2.0, 3.0])


def write_tum(poses, path):
    with open(path, "w") as f:
        for i in sorted(poses):
            t, q = poses[i]
            f.write(" ".join(repr(float(v)) for v in [i, *t, *q]) + "\n")


def close(a, b, rel=1e-9, abs_=1e-12):
    return abs(a - b) <= rel * max(abs(a), abs(b)) + abs_


@pytest.mark.parametrize("delta, all_pairs", [(1, False), (10, False), (10, True)])
def test_pgo_eval_on_3d_graphs_equals_evo(grid, delta, all_pairs):
    d, est, reference = grid
    flags = ["--delta", str(delta)] + (["--all-pairs"] if all_pairs else [])
    out = subprocess.run(
        [pgo_binary("pgo-eval"), est, reference, "--json", *flags],
        check=True,
        capture_output=True,
    )
    ours = json.loads(out.stdout)
    assert ours["matched"] == 125 and len(ours["alignment"]["rotation"]) == 3
    write_tum(g2o_poses3(est), d / "eval-est.tum")
    write_tum(g2o_poses3(reference), d / "eval-ref.tum")
    for kind in ["ape", "rpe"]:
        for relation, key in [
            (evo_metrics.PoseRelation.translation_part, "translation"),
            (evo_metrics.PoseRelation.rotation_angle_deg, "rotation_deg"),
        ]:
            ref = file_interface.read_tum_trajectory_file(str(d / "eval-ref.tum"))
            traj = file_interface.read_tum_trajectory_file(str(d / "eval-est.tum"))
            if kind == "ape":
                traj.align(ref, correct_scale=False)
                metric = evo_metrics.APE(relation)
            else:
                metric = evo_metrics.RPE(
                    relation, delta, evo_metrics.Unit.frames, all_pairs=all_pairs
                )
            metric.process_data((ref, traj))
            theirs = metric.get_all_statistics()
            for stat in ["rmse", "mean", "median", "std", "min", "max"]:
                assert close(ours[kind][key][stat], theirs[stat]), (kind, key, stat)
