"""pgo.gtsam against PyPI gtsam: the factor graph to_gtsam builds equals the one GTSAM's own
readG2o builds from the file (same error at any values, so the information order is right, for
g2o and TORO input alike); GTSAM's error at pgo's optimum equals 1/2 sum e^T Omega e computed
here with numpy from the closed-form SE(2) log map; and a GTSAM estimate is certified in three
lines."""

import math

import numpy as np
import pytest

import pgo
from conftest import DATASETS, run

gtsam = pytest.importorskip("gtsam")
import pgo.gtsam  # noqa: E402  (after the skip: gtsam is optional)

MIT = DATASETS / "MIT.g2o"


def se2_log(x, y, theta):
    """Log map of SE(2) (GTSAM's Pose2.Logmap): (V^-1 t, theta), theta in (-pi, pi]."""
    w = math.atan2(math.sin(theta), math.cos(theta))
    if abs(w) < 1e-10:
        return np.array([x, y, w])
    half = w / 2
    a = half * math.sin(w) / (1 - math.cos(w))  # (w/2) cot(w/2)
    vinv = np.array([[a, half], [-half, a]])
    return np.array([*(vinv @ [x, y]), w])


def compose_inverse(a, b):
    """a^-1 * b for poses (x, y, theta)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, b[2] - a[2]])


def compose(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]])


def independent_error(graph, poses):
    """GTSAM's error of BetweenFactorPose2s, 1/2 sum e^T Omega e with
    e = Log(z^-1 x_i^-1 x_j), by numpy alone."""
    total = 0.0
    index = {int(k): r for r, k in enumerate(graph.ids)}
    for (i, j), z, info in zip(graph.edges, graph.measurements, graph.information):
        h = compose_inverse(poses[index[int(i)]], poses[index[int(j)]])
        zinv = compose_inverse(z, np.zeros(3))
        r = compose(zinv, h)
        e = se2_log(*r)
        a, b, c, d, f, g = info
        omega = np.array([[a, b, c], [b, d, f], [c, f, g]])
        total += 0.5 * e @ omega @ e
    return total


def independent_chi2(graph, poses):
    """g2o's chi2 of EdgeSE2s: sum e^T Omega e with e = (x, y, theta in [-pi, pi)) of
    z^-1 x_i^-1 x_j, by numpy alone."""
    total = 0.0
    index = {int(k): r for r, k in enumerate(graph.ids)}
    for (i, j), z, info in zip(graph.edges, graph.measurements, graph.information):
        h = compose_inverse(poses[index[int(i)]], poses[index[int(j)]])
        r = compose(compose_inverse(z, np.zeros(3)), h)
        e = np.array([r[0], r[1], math.atan2(math.sin(r[2]), math.cos(r[2]))])
        a, b, c, d, f, g = info
        total += e @ np.array([[a, b, c], [b, d, f], [c, f, g]]) @ e
    return total


def values_of(graph, poses):
    v = gtsam.Values()
    for key, p in zip(graph.ids, poses):
        v.insert(int(key), gtsam.Pose2(*map(float, p)))
    return v


def test_to_gtsam_equals_gtsams_own_reader(tmp_path):
    graph = pgo.read(MIT)
    factors, values = pgo.gtsam.to_gtsam(graph)
    theirs, their_values = gtsam.readG2o(str(MIT), False)
    assert factors.size() == theirs.size() == graph.num_edges
    assert values.size() == their_values.size() == graph.num_poses
    for key in graph.ids:
        assert values.atPose2(int(key)).equals(their_values.atPose2(int(key)), 0.0)
    # Same error at the file's poses and at a perturbed estimate (exact information order).
    rng = np.random.default_rng(7)
    for poses in (graph.poses, graph.poses + rng.normal(scale=0.05, size=graph.poses.shape)):
        v = values_of(graph, poses)
        assert factors.error(v) == pytest.approx(theirs.error(v), rel=1e-13)
    # TORO input: its information order is converted when read, so the factors are the same.
    toro = tmp_path / "MIT.graph"
    run("pgo-convert", MIT, "-o", toro)
    f2, _ = pgo.gtsam.to_gtsam(pgo.read(toro))
    v = values_of(graph, graph.poses + rng.normal(scale=0.05, size=graph.poses.shape))
    assert f2.error(v) == factors.error(v)


def test_gtsam_error_at_pgo_optimum_equals_independent_value():
    graph = pgo.read(MIT)
    s = pgo.solve(graph)
    assert s.certified
    factors, _ = pgo.gtsam.to_gtsam(graph)
    error = factors.error(values_of(graph, s.poses))
    expected = independent_error(graph, s.poses)
    assert error == pytest.approx(expected, rel=1e-10)
    # And the report's chi2 is g2o's: e = (x, y, normalized theta) of z^-1 x_i^-1 x_j, not
    # the log map (the two differ by 2% here: the residuals are not small).
    assert s.chi2 == pytest.approx(independent_chi2(graph, s.poses), rel=1e-10)
    assert error != pytest.approx(s.chi2 / 2, rel=1e-3)


def test_prior_adds_nothing_at_pgos_estimate():
    graph = pgo.read(MIT)
    s = pgo.solve(graph)
    plain, _ = pgo.gtsam.to_gtsam(graph)
    held, _ = pgo.gtsam.to_gtsam(graph, prior_sigma=1e-6)
    assert held.size() == plain.size() + 1
    v = values_of(graph, s.poses)
    assert held.error(v) == plain.error(v)


def test_certify_a_gtsam_estimate_in_three_lines(shared_datasets):
    graph = pgo.read(shared_datasets / "intel.g2o")
    # The three lines:
    factors, values = pgo.gtsam.to_gtsam(graph)
    result = gtsam.LevenbergMarquardtOptimizer(factors, values).optimize()
    certificate = pgo.certify(graph, pgo.gtsam.from_gtsam(graph, result))

    optimum = pgo.solve(graph)
    assert optimum.certified
    # GTSAM minimizes chi2/2, not f: its estimate costs more under f, and the bound holds.
    assert certificate.lower_bound <= optimum.cost * (1 + 1e-9)
    assert certificate.cost >= optimum.lower_bound
    assert certificate.suboptimality_bound >= 0
    # GTSAM's estimate is a better minimum of GTSAM's error than pgo's (another objective).
    assert factors.error(result) <= factors.error(values_of(graph, optimum.poses)) * (1 + 1e-9)
    # from_gtsam gives the poses in graph.ids order.
    back = pgo.gtsam.from_gtsam(graph, values)
    assert np.array_equal(back[:, :2], graph.poses[:, :2])
    wrapped = np.angle(np.exp(1j * (back[:, 2] - graph.poses[:, 2])))
    assert np.abs(wrapped).max() < 1e-15


def test_landmarks_and_missing_keys_are_refused():
    g = pgo.read(
        "VERTEX_SE2 0 0 0 0\nVERTEX_XY 1 1 1\nEDGE_SE2_XY 0 1 1 1 1 0 1\n"
    )
    with pytest.raises(NotImplementedError):
        pgo.gtsam.to_gtsam(g)
    graph = pgo.read(DATASETS / "paper_toy.g2o")
    with pytest.raises(KeyError):
        pgo.gtsam.from_gtsam(graph, gtsam.Values())


def rotation_matrix(q):
    """R of a quaternion (qx, qy, qz, qw) normalized, by the textbook formula."""
    x, y, z, w = np.asarray(q) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def values3_of(graph, poses):
    """gtsam.Values of Pose3 built here from (n, 7) rows, independently of pgo.gtsam."""
    v = gtsam.Values()
    for key, row in zip(graph.ids, poses):
        v.insert(int(key), gtsam.Pose3(gtsam.Rot3(rotation_matrix(row[3:])), np.array(row[:3])))
    return v


@pytest.mark.parametrize("name", ["tinyGrid3D.g2o", "smallGrid3D.g2o", "parking-garage.g2o"])
def test_to_gtsam_3d_equals_gtsams_own_reader(shared_datasets, name):
    path = shared_datasets / name
    graph = pgo.read(path)
    factors, values = pgo.gtsam.to_gtsam(graph)
    theirs, their_values = gtsam.readG2o(str(path), True)
    assert factors.size() == theirs.size() == graph.num_edges
    assert values.size() == their_values.size() == graph.num_poses
    for key in graph.ids:
        assert values.atPose3(int(key)).equals(their_values.atPose3(int(key)), 1e-12)
    # The same error at the file's poses, at pgo's optimum and at a perturbed estimate: the
    # information reordered as GTSAM's reader does, off-diagonal blocks included.
    rng = np.random.default_rng(3)
    optimum = pgo.solve(graph).poses
    noisy = graph.poses + rng.normal(scale=0.02, size=graph.poses.shape)
    for poses in (graph.poses, optimum, noisy):
        v = values3_of(graph, poses)
        assert factors.error(v) == pytest.approx(theirs.error(v), rel=1e-12)
    # from_gtsam: the translations as read, the rotations equal (a quaternion's sign is free).
    back = pgo.gtsam.from_gtsam(graph, values)
    assert back.shape == (graph.num_poses, 7)
    assert np.allclose(back[:, :3], graph.poses[:, :3], rtol=0, atol=1e-12)
    for mine, read in zip(back, graph.poses):
        assert np.allclose(rotation_matrix(mine[3:]), rotation_matrix(read[3:]), atol=1e-12)


def test_certify_a_gtsam_3d_estimate(shared_datasets):
    graph = pgo.read(shared_datasets / "smallGrid3D.g2o")
    factors, values = pgo.gtsam.to_gtsam(graph, prior_sigma=1e-6)
    result = gtsam.LevenbergMarquardtOptimizer(factors, values).optimize()
    certificate = pgo.certify(graph, pgo.gtsam.from_gtsam(graph, result))
    optimum = pgo.solve(graph)
    assert optimum.certified
    # GTSAM's LM minimizes its own error, not SE-Sync's f: its estimate costs at least f*, and
    # the bound it gets is a lower bound on f*.
    assert certificate.cost >= optimum.lower_bound
    assert certificate.lower_bound <= optimum.cost * (1 + 1e-9)


def test_toro_3d_and_missing_keys_are_refused():
    g = pgo.read("VERTEX3 0 0 0 0 0 0 0\nVERTEX3 1 1 0 0 0 0 0\n")
    with pytest.raises(NotImplementedError, match="roll, pitch and yaw"):
        pgo.gtsam.to_gtsam(g)
    g = pgo.read("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n")
    with pytest.raises(KeyError, match="no pose 0"):
        pgo.gtsam.from_gtsam(g, gtsam.Values())
    with pytest.raises(TypeError, match="expected a pgo.Graph"):
        pgo.gtsam.to_gtsam("graph.g2o")
