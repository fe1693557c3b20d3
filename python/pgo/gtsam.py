"""Bridges between pgo's graphs and GTSAM's (PyPI ``gtsam``, imported here only).

:func:`to_gtsam` gives the factor graph GTSAM's own ``readG2o`` builds from the same file: one
``BetweenFactorPose2`` per edge, keyed by the vertex ids, with the edge's full information matrix
as ``noiseModel.Gaussian.Information``, and the graph's poses as ``Values``. No reordering is
needed: g2o's ``EDGE_SE2`` information is over (x, y, theta), the order of GTSAM's Pose2 tangent
(``Pose2.Logmap`` returns (v_x, v_y, omega)), and pgo keeps every graph's information in g2o
order (TORO's order and covariance dialects are converted when read). :func:`from_gtsam` reads an
estimate back as pgo's (n, 3) poses.

A 3D graph (``pgo.Graph3`` of g2o form) becomes what ``readG2o(path, is3D=True)`` builds: one
``BetweenFactorPose3`` per edge, the 6x6 information reordered from g2o's (translation,
quaternion vector) to GTSAM's Pose3 tangent order (rotation, translation), as GTSAM's reader
does, and :func:`from_gtsam` gives (n, 7) rows ``x y z qx qy qz qw``. A TORO 3D graph is refused:
its information is over Euler angles, which no Pose3 tangent matches. Certifying a GTSAM
estimate::

    factors, values = pgo.gtsam.to_gtsam(graph)
    result = gtsam.LevenbergMarquardtOptimizer(factors, values).optimize()
    print(pgo.certify(graph, pgo.gtsam.from_gtsam(graph, result)))

GTSAM minimizes ``graph.error`` = 1/2 sum e^T Omega e with e = Pose2.Logmap(z^-1 x_i^-1 x_j), half
g2o's chi2 to first order, which is not pgo's objective f: its optimum is certified only to
within a small relative bound (intel: about 4%; README, "What the certificate says").
"""

from __future__ import annotations

import math
from typing import Any, Optional, Tuple, Union

import numpy as np

import gtsam as _gtsam  # type: ignore[import-not-found, unused-ignore]

from . import Graph, Graph3

__all__ = ["to_gtsam", "from_gtsam"]

# g2o's EDGE_SE3:QUAT information is over (x, y, z, qx, qy, qz), GTSAM's Pose3 tangent is
# (omega, v): rows and columns 3-5 first, as readG2o reorders them.
_GTSAM_ORDER = [3, 4, 5, 0, 1, 2]


def _check_graph(graph: Any, name: str) -> Union[Graph, Graph3]:
    if isinstance(graph, Graph3):
        if graph.format != "g2o":
            raise NotImplementedError(
                f"{name}: a TORO 3D graph's information is over roll, pitch and yaw, which no "
                "Pose3 tangent matches (GTSAM's readG2o takes it as its own rotation-translation "
                "order); write it as g2o from its source, or build a pgo.Graph3 of g2o form"
            )
        return graph
    if not isinstance(graph, Graph):
        raise TypeError(f"{name}: expected a pgo.Graph or pgo.Graph3, found {type(graph).__name__}")
    return graph


def _held(graph: Union[Graph, Graph3]) -> list[int]:
    """The poses a prior holds: the FIX ones, else the smallest id (where pgo keeps the gauge)."""
    if len(graph.fixed):
        return [int(k) for k in graph.fixed]
    return [int(graph.ids[0])] if graph.num_poses else []


def _pose3(row: Any) -> Any:
    """``gtsam.Pose3`` of a g2o row x y z qx qy qz qw (the quaternion normalized)."""
    x, y, z, qx, qy, qz, qw = (float(v) for v in row)
    norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    rotation = _gtsam.Rot3.Quaternion(qw / norm, qx / norm, qy / norm, qz / norm)
    return _gtsam.Pose3(rotation, np.array([x, y, z], dtype=np.float64))


def _information3(upper: Any) -> np.ndarray:
    """The 6x6 information of a 21-value upper triangle (row by row), in GTSAM's order."""
    m = np.zeros((6, 6), dtype=np.float64)
    m[np.triu_indices(6)] = upper
    m = m + m.T - np.diag(np.diag(m))
    return m[np.ix_(_GTSAM_ORDER, _GTSAM_ORDER)]


def _to_gtsam3(graph: Graph3, prior_sigma: Optional[float]) -> Tuple[Any, Any]:
    factors = _gtsam.NonlinearFactorGraph()
    values = _gtsam.Values()
    ids = graph.ids
    for key, row in zip(ids, graph.poses):
        values.insert(int(key), _pose3(row))
    for (i, j), z, info in zip(graph.edges, graph.measurements, graph.information):
        factors.add(
            _gtsam.BetweenFactorPose3(
                int(i), int(j), _pose3(z), _gtsam.noiseModel.Gaussian.Information(_information3(info))
            )
        )
    if prior_sigma is not None:
        held = _held(graph)
        noise = _gtsam.noiseModel.Isotropic.Sigma(6, float(prior_sigma))
        for key in held:
            factors.add(_gtsam.PriorFactorPose3(int(key), values.atPose3(int(key)), noise))
    return factors, values


def to_gtsam(graph: Union[Graph, Graph3], prior_sigma: Optional[float] = None) -> Tuple[Any, Any]:
    """``(gtsam.NonlinearFactorGraph, gtsam.Values)`` of ``graph``: a ``BetweenFactorPose2`` per
    edge (keys = vertex ids, measurement (dx, dy, dtheta), ``noiseModel.Gaussian.Information`` of
    the edge's 3x3 information matrix), and a ``Pose2`` per pose at the graph's estimate.

    Like GTSAM's ``readG2o``, no prior: the gauge is free (Levenberg-Marquardt's damping copes;
    ``Marginals`` needs one). With ``prior_sigma``, a ``PriorFactorPose2`` with that sigma on
    x, y and theta at each held pose (the FIX poses, else the smallest id), where pgo's solutions
    keep it, so it adds nothing to the error at pgo's estimates. Graphs with landmarks are
    refused (GTSAM's Python API has no factor for pgo's (dx, dy) observations). A 3D graph gives
    ``BetweenFactorPose3`` and ``Pose3`` (module documentation), the prior on all six axes.
    """
    graph = _check_graph(graph, "to_gtsam")
    if isinstance(graph, Graph3):
        return _to_gtsam3(graph, prior_sigma)
    if len(graph.landmark_ids):
        raise NotImplementedError("to_gtsam: graphs with landmarks are not bridged")
    factors = _gtsam.NonlinearFactorGraph()
    values = _gtsam.Values()
    ids = graph.ids
    for key, (x, y, theta) in zip(ids, graph.poses):
        values.insert(int(key), _gtsam.Pose2(float(x), float(y), float(theta)))
    for (i, j), z, info in zip(graph.edges, graph.measurements, graph.information):
        a, b, c, d, e, f = info
        omega = np.array([[a, b, c], [b, d, e], [c, e, f]], dtype=np.float64)
        factors.add(
            _gtsam.BetweenFactorPose2(
                int(i),
                int(j),
                _gtsam.Pose2(float(z[0]), float(z[1]), float(z[2])),
                _gtsam.noiseModel.Gaussian.Information(omega),
            )
        )
    if prior_sigma is not None:
        held = _held(graph)
        noise = _gtsam.noiseModel.Isotropic.Sigma(3, float(prior_sigma))
        for key in held:
            factors.add(_gtsam.PriorFactorPose2(int(key), values.atPose2(int(key)), noise))
    return factors, values


def from_gtsam(graph: Union[Graph, Graph3], values: Any) -> np.ndarray:
    """The poses of ``values`` (a ``gtsam.Values`` holding a ``Pose2`` for each vertex id of
    ``graph``) as an (n, 3) float64 array (x, y, theta) in the order of ``graph.ids``: what
    :func:`pgo.certify` and ``Graph.with_poses`` take. For a ``Graph3``, ``Pose3`` values as an
    (n, 7) array x y z qx qy qz qw (GTSAM's unit quaternion)."""
    graph = _check_graph(graph, "from_gtsam")
    three = isinstance(graph, Graph3)
    out = np.empty((graph.num_poses, 7 if three else 3), dtype=np.float64)
    for row, key in enumerate(graph.ids):
        if not values.exists(int(key)):
            raise KeyError(f"from_gtsam: the values have no pose {int(key)}, which the graph has")
        if three:
            p = values.atPose3(int(key))
            q = p.rotation().toQuaternion()
            out[row] = (*p.translation(), q.x(), q.y(), q.z(), q.w())
        else:
            p = values.atPose2(int(key))
            out[row] = (p.x(), p.y(), p.theta())
    return out
