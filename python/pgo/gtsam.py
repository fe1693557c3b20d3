"""Bridges between pgo's graphs and GTSAM's (PyPI ``gtsam``, imported here only).

:func:`to_gtsam` gives the factor graph GTSAM's own ``readG2o`` builds from the same file: one
``BetweenFactorPose2`` per edge, keyed by the vertex ids, with the edge's full information matrix
as ``noiseModel.Gaussian.Information``, and the graph's poses as ``Values``. No reordering is
needed: g2o's ``EDGE_SE2`` information is over (x, y, theta), the order of GTSAM's Pose2 tangent
(``Pose2.Logmap`` returns (v_x, v_y, omega)), and pgo keeps every graph's information in g2o
order (TORO's order and covariance dialects are converted when read). :func:`from_gtsam` reads an
estimate back as pgo's (n, 3) poses. Certifying a GTSAM estimate::

    factors, values = pgo.gtsam.to_gtsam(graph)
    result = gtsam.LevenbergMarquardtOptimizer(factors, values).optimize()
    print(pgo.certify(graph, pgo.gtsam.from_gtsam(graph, result)))

GTSAM minimizes ``graph.error`` = 1/2 sum e^T Omega e with e = Pose2.Logmap(z^-1 x_i^-1 x_j), half
g2o's chi2 to first order, which is not pgo's objective f: its optimum is certified only to
within a small relative bound (intel: about 4%; README, "What the certificate says").
"""

from __future__ import annotations

from typing import Any, Optional, Tuple

import numpy as np

import gtsam as _gtsam  # type: ignore[import-not-found, unused-ignore]

from . import Graph

__all__ = ["to_gtsam", "from_gtsam"]


def _check_planar(graph: Any, name: str) -> None:
    if not isinstance(graph, Graph):
        raise TypeError(
            f"{name}: expected a planar pgo.Graph, found {type(graph).__name__} "
            "(3D graphs are not bridged to GTSAM yet)"
        )


def to_gtsam(graph: Graph, prior_sigma: Optional[float] = None) -> Tuple[Any, Any]:
    """``(gtsam.NonlinearFactorGraph, gtsam.Values)`` of ``graph``: a ``BetweenFactorPose2`` per
    edge (keys = vertex ids, measurement (dx, dy, dtheta), ``noiseModel.Gaussian.Information`` of
    the edge's 3x3 information matrix), and a ``Pose2`` per pose at the graph's estimate.

    Like GTSAM's ``readG2o``, no prior: the gauge is free (Levenberg-Marquardt's damping copes;
    ``Marginals`` needs one). With ``prior_sigma``, a ``PriorFactorPose2`` with that sigma on
    x, y and theta at each held pose (the FIX poses, else the smallest id), where pgo's solutions
    keep it, so it adds nothing to the error at pgo's estimates. Graphs with landmarks are
    refused (GTSAM's Python API has no factor for pgo's (dx, dy) observations).
    """
    _check_planar(graph, "to_gtsam")
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
        held = list(graph.fixed) if len(graph.fixed) else ([int(ids[0])] if len(ids) else [])
        noise = _gtsam.noiseModel.Isotropic.Sigma(3, float(prior_sigma))
        for key in held:
            factors.add(_gtsam.PriorFactorPose2(int(key), values.atPose2(int(key)), noise))
    return factors, values


def from_gtsam(graph: Graph, values: Any) -> np.ndarray:
    """The poses of ``values`` (a ``gtsam.Values`` holding a ``Pose2`` for each vertex id of
    ``graph``) as an (n, 3) float64 array (x, y, theta) in the order of ``graph.ids``: what
    :func:`pgo.certify` and ``Graph.with_poses`` take."""
    _check_planar(graph, "from_gtsam")
    out = np.empty((graph.num_poses, 3), dtype=np.float64)
    for row, key in enumerate(graph.ids):
        if not values.exists(int(key)):
            raise KeyError(f"from_gtsam: the values have no pose {int(key)}, which the graph has")
        p = values.atPose2(int(key))
        out[row] = (p.x(), p.y(), p.theta())
    return out
