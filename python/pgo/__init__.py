"""pgo: certifiably optimal pose graph optimization, planar and 3D, from Python.

Read a g2o or TORO file, solve it to a certified global optimum, certify any estimate (one from
GTSAM or g2o too), and look at the spectra behind the certificate; poses, edges and information
matrices are numpy arrays. A planar file gives a :class:`Graph`, a 3D one (``VERTEX_SE3:QUAT``/
``EDGE_SE3:QUAT``, TORO ``VERTEX3``/``EDGE3``) a :class:`Graph3`, and the same calls solve,
certify and analyse either, as the tools do::

    import pgo
    graph = pgo.read("MIT.g2o")            # or the text of a file, or pgo.Graph(poses=..., ...)
    solution = pgo.solve(graph)            # solution.poses: (n, 3) x, y, theta
    print(solution)                        # certified? cost, proven lower bound, gap
    certificate = pgo.certify(graph, solution.poses)
    graph.with_poses(solution.poses).write("MIT-opt.g2o")

The reports are the command-line tools' own: every field of ``pgo-solve --json`` is an
attribute of a :class:`Solution` (``to_dict()`` gives the report itself), likewise
``pgo-certify --json`` for a :class:`Certificate` and ``pgo-spectrum --json`` for a
:class:`Spectrum`. Errors are exceptions: :class:`ParseError` (a ValueError) for an input error
at ``PATH:LINE:COL``, ``OSError`` for a file that cannot be opened or written, :class:`PgoError`
(a ValueError) for the rest. ``pgo.gtsam`` bridges to GTSAM (optional, imported on use).
"""

from __future__ import annotations

import copy
import json
import os
import warnings
from typing import Any, ClassVar, Dict, List, Optional, Union

import numpy as np

from . import _pgo
from ._pgo import Graph, Graph3, ParseError, PgoError

__version__: str = _pgo.VERSION

__all__ = [
    "Graph",
    "Graph3",
    "ParseError",
    "PgoError",
    "ReadWarning",
    "Solution",
    "Certificate",
    "Spectrum",
    "read",
    "solve",
    "certify",
    "spectrum",
]

PathOrText = Union[str, bytes, bytearray, "os.PathLike[str]"]

# A planar or a 3D pose graph: what read() returns and the jobs take (for annotations:
# pgo.AnyGraph; isinstance(graph, pgo.Graph3) tells them apart).
AnyGraph = Union[Graph, Graph3]


class ReadWarning(UserWarning):
    """A warning of the reader (an unknown tag skipped, a line ignored): the tools print these
    on stderr; ``pgo.read`` issues them with :func:`warnings.warn` and keeps them in
    ``Graph.warnings``."""


def read(
    source: PathOrText,
    *,
    format: Optional[str] = None,
    dialect: Optional[str] = None,
    strict: bool = False,
    ignore_equiv: bool = False,
    allow_indefinite: bool = False,
) -> AnyGraph:
    """Reads a pose graph from a g2o or TORO file, or from the text of one: a :class:`Graph`
    for a planar file, a :class:`Graph3` for a 3D one (g2o ``VERTEX_SE3:QUAT``/``EDGE_SE3:QUAT``,
    TORO ``VERTEX3``/``EDGE3``), as the tools tell them apart.

    ``source`` is text when it is ``bytes``/``bytearray``, or a ``str`` holding a line break
    (``\\n`` or ``\\r``): every graph file with more than one line does; errors then name the
    input ``<string>``. Any other ``str`` or ``os.PathLike`` is a path (a one-line file given as
    text must end with ``\\n``). The format is taken from ``format`` ("g2o" or "toro"), else the
    extension (.g2o, .graph), else the tags; ``dialect`` ("g2o", "toro-info", "toro-cov",
    "g2o-cov") says how to read the six noise values (default: by the edge tags), as the tools'
    ``--from`` and ``--dialect``. ``strict``, ``ignore_equiv`` and ``allow_indefinite`` are the
    tools' flags of the same names (a 3D file takes only its own dialect, information matrices).

    Raises :class:`ParseError` (with ``.path``, ``.line``, ``.column``) for an input error,
    ``OSError`` (e.g. ``FileNotFoundError``) for a file that cannot be read. The reader's
    warnings are issued as :class:`ReadWarning` and kept in ``Graph.warnings``.
    """
    flags = (format, dialect, strict, ignore_equiv, allow_indefinite)
    graph: AnyGraph
    if isinstance(source, (bytes, bytearray)):
        graph = _pgo.read_bytes(bytes(source), "<string>", *flags)
    elif isinstance(source, str):
        if "\n" in source or "\r" in source:
            graph = _pgo.read_bytes(source.encode("utf-8"), "<string>", *flags)
        else:
            graph = _pgo.read_path(source, *flags)
    else:
        path = os.fspath(source)
        if not isinstance(path, str):
            raise TypeError(f"expected a path or the text of a file, found {path!r}")
        graph = _pgo.read_path(path, *flags)
    for w in graph.warnings:
        warnings.warn(w, ReadWarning, stacklevel=2)
    return graph


class _Report:
    """A tool's ``--json`` report: its fields as attributes, ``to_dict()`` the report itself."""

    # Fields the report leaves out when they are empty or zero, and what they then are.
    _absent: ClassVar[Dict[str, Any]] = {"warnings": []}

    def __init__(self, report: Dict[str, Any]):
        self._report = report

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        report = self.__dict__.get("_report", {})
        if name in report:
            return report[name]
        if name in type(self)._absent:
            return copy.copy(type(self)._absent[name])
        raise AttributeError(f"{type(self).__name__} has no field {name!r}")

    def __dir__(self) -> List[str]:
        return sorted(set(super().__dir__()) | set(self._report) | set(type(self)._absent))

    def to_dict(self) -> Dict[str, Any]:
        """The report as the tool's ``--json`` prints it, parsed (a deep copy)."""
        return copy.deepcopy(self._report)

    def _bound_text(self) -> str:
        r = self._report
        rel = r["relative_suboptimality_bound"]
        return (
            f"cost {r['cost']!r}, proven lower bound {r['lower_bound']!r}, "
            f"gap {r['suboptimality_bound']:.3g} (relative {rel:.3g})"
        )


class Solution(_Report):
    """What :func:`solve` found: the estimate and the ``pgo-solve --json`` report.

    ``poses`` is the estimate, (n, 3) float64 (x, y, theta), one row per pose in the order of
    ``Graph.ids``, in the input's gauge (each component's FIX pose, else its smallest-id pose,
    exactly where the graph has it; headings in (-pi, pi]); the report's count of poses is
    ``to_dict()["poses"]`` (= ``len(solution.poses)``). ``landmarks`` is (L, 2), the landmark
    positions (the report's count: ``to_dict().get("landmarks", 0)``). With ``refine=True`` the
    estimate is the refined one (``written_estimate == "refined"``), which is not the certified
    one.

    Of a :class:`Graph3`: ``poses`` is (n, 7) ``x y z qx qy qz qw`` (quaternions with w >= 0)
    for a g2o graph, (n, 6) ``x y z roll pitch yaw`` for a TORO one, the estimate
    ``pgo-solve -o`` writes; ``landmarks`` is empty, (0, 3); ``dimension`` is 3 (2 for a planar
    graph), and the report is ``pgo-solve --json``'s for 3D graphs, which has no ``solver``,
    ``sdp_converged`` nor landmark counts (accessing them raises AttributeError).

    Every other field of ``pgo-solve --json`` (README "JSON reports") is an attribute: ``cost``,
    ``chi2``, ``lower_bound``, ``suboptimality_bound``, ``relative_suboptimality_bound``,
    ``certified``, ``not_certified_because``, ``szep``, ``near_zero_eigenvalues``,
    ``sdp_converged``, ``method``, ``solver``, ``weights``, ``edges``, ``observations``,
    ``refined_chi2``, ``components`` (a list of dicts), ``written_estimate``, ``written_chi2``,
    ``written_certified``, ``suspect_loop_closures`` (not certified: a dict of
    ``above_threshold``, ``loop_closures`` and ``threshold``, the loop closures above the robust
    inlier threshold at the estimate), ``warnings``. Fields the report leaves out are ``None`` (``0`` for
    ``observations``, ``[]`` for ``warnings``). The report is ``pgo-solve --json --no-timings``'s
    for the same graph and options; ``tol`` is the tolerance asked for.
    """

    _absent: ClassVar[Dict[str, Any]] = {
        "warnings": [],
        "observations": 0,
        "refined_chi2": None,
        "not_certified_because": None,
        "suspect_loop_closures": None,
        "dimension": 2,
    }

    poses: np.ndarray
    landmarks: np.ndarray
    tol: float
    cost: float
    chi2: Optional[float]
    lower_bound: float
    suboptimality_bound: float
    relative_suboptimality_bound: float
    certified: bool
    not_certified_because: Optional[str]
    szep: bool
    near_zero_eigenvalues: int
    sdp_converged: bool
    method: str
    solver: str
    weights: str
    edges: int
    observations: int
    refined_chi2: Optional[float]
    components: List[Dict[str, Any]]
    written_estimate: str
    written_chi2: Optional[float]
    written_certified: bool
    suspect_loop_closures: Optional[Dict[str, Any]]
    warnings: List[str]
    dimension: int

    def __init__(self, report: Dict[str, Any], poses: np.ndarray, landmarks: np.ndarray, tol: float):
        super().__init__(report)
        self.poses = poses
        self.landmarks = landmarks
        self.tol = tol

    def __repr__(self) -> str:
        r = self._report
        if r["certified"]:
            head = f"certified optimal within tol={self.tol:g}"
        else:
            head = f"NOT certified within tol={self.tol:g} (the bound still holds)"
        tail = ""
        if r["written_estimate"] == "refined":
            tail = (
                f"; poses are the LM-refined estimate (chi2 {r['written_chi2']!r}), "
                "not the certified one"
            )
        ran = sorted({c["method"] for c in r["components"]})
        method = r["method"] if ran == [r["method"]] else f"{r['method']} ({', '.join(ran)})"
        dim = ", 3D" if r.get("dimension") == 3 else ""
        return (
            f"<pgo.Solution: {head}: {self._bound_text()}; {r['poses']} poses{dim}, "
            f"{len(r['components'])} component(s), method {method}{tail}>"
        )


class Certificate(_Report):
    """What :func:`certify` proved about an estimate: the ``pgo-certify --json`` report.

    Attributes (README "JSON reports"): ``cost`` (f at the estimate), ``chi2``, ``lower_bound``
    (proven, on the optimum f*), ``suboptimality_bound``, ``relative_suboptimality_bound``,
    ``certified`` (within ``tol``), ``gradient_norm``, ``weights``, ``poses``, ``edges``,
    ``components`` (a list of dicts, each with ``bound_from``: "estimate" when the estimate's own
    multipliers proved the bound, "solution" when the optimum's did), ``warnings``; ``tol`` is
    the tolerance asked for, ``dimension`` the graph's (2, or 3 for a :class:`Graph3`: then the
    cost is SE-Sync's objective and a certified component's ``near_zero_eigenvalues`` is 3).
    """

    cost: float
    chi2: Optional[float]
    lower_bound: float
    suboptimality_bound: float
    relative_suboptimality_bound: float
    certified: bool
    gradient_norm: float
    weights: str
    poses: int
    edges: int
    components: List[Dict[str, Any]]
    warnings: List[str]
    tol: float
    dimension: int

    def __init__(self, report: Dict[str, Any], tol: float, dimension: int = 2):
        super().__init__(report)
        self.tol = tol
        self.dimension = dimension

    def __bool__(self) -> bool:
        return bool(self._report["certified"])

    def __repr__(self) -> str:
        head = (
            f"certified optimal within tol={self.tol:g}"
            if self._report["certified"]
            else f"NOT certified within tol={self.tol:g} (the bound still holds)"
        )
        dim = "; 3D" if self.dimension == 3 else ""
        return f"<pgo.Certificate: {head}: {self._bound_text()}{dim}>"


class Spectrum(_Report):
    """The spectra of the pose graph matrices (:func:`spectrum`): the ``pgo-spectrum --json``
    report, with its eigenvalue lists as float64 arrays, ascending.

    ``eigenvalues`` (of W), ``penalized_eigenvalues`` (of W(lambda*)), ``rotation_eigenvalues``
    (of M); ``near_zero`` (eigenvalues of W(lambda*) at zero), ``szep`` (the single zero
    eigenvalue property holds), ``tree``, ``balanced``, ``sdp_converged``, ``weights``,
    ``poses``, ``edges``, ``components`` (a list of dicts), ``warnings``.

    Of a :class:`Graph3` (``dimension`` 3, else 2): the eigenvalues of SE-Sync's data matrix Q,
    of the certificate matrix S at the solved estimate and of the rotation-only M; ``near_zero``
    counts S's zeros (3 at a certified optimum), ``szep`` says the certificate counted exactly
    three, ``certified`` is added and ``tree``, ``balanced``, ``sdp_converged`` are left out
    (accessing them raises AttributeError), as in ``pgo-spectrum --json``.
    """

    _absent: ClassVar[Dict[str, Any]] = {"warnings": [], "dimension": 2}

    eigenvalues: np.ndarray
    penalized_eigenvalues: np.ndarray
    rotation_eigenvalues: np.ndarray
    near_zero: int
    szep: bool
    tree: bool
    balanced: bool
    sdp_converged: bool
    weights: str
    poses: int
    edges: int
    components: List[Dict[str, Any]]
    warnings: List[str]
    dimension: int
    certified: bool

    _arrays = ("eigenvalues", "penalized_eigenvalues", "rotation_eigenvalues")

    def __init__(self, report: Dict[str, Any]):
        super().__init__(report)
        for name in self._arrays:
            setattr(self, name, np.array(report[name], dtype=np.float64))

    def __repr__(self) -> str:
        r = self._report
        if r.get("dimension") == 3:
            return (
                f"<pgo.Spectrum: {r['poses']} poses, 3D; smallest eigenvalues of S "
                f"{list(r['penalized_eigenvalues'][:4])}; {r['near_zero']} at zero, "
                f"three zeros (SZEP) {'yes' if r['szep'] else 'no'}>"
            )
        return (
            f"<pgo.Spectrum: {r['poses']} poses; smallest eigenvalues of W(lambda*) "
            f"{list(r['penalized_eigenvalues'][:3])}; {r['near_zero']} at zero, "
            f"SZEP {'yes' if r['szep'] else 'no'}>"
        )


def _check_graph(graph: Any) -> AnyGraph:
    if not isinstance(graph, (Graph, Graph3)):
        raise TypeError(f"expected a pgo.Graph or a pgo.Graph3, found {type(graph).__name__}")
    return graph


def solve(
    graph: AnyGraph,
    weights: str = "isotropic",
    tol: float = 1e-6,
    method: str = "auto",
    *,
    solver: Optional[str] = None,
    max_rank: int = 6,
    staircase_budget: float = 50.0,
    refine: bool = False,
) -> Solution:
    """Solves ``graph`` to a certified global optimum, as ``pgo-solve`` does.

    ``weights``: "isotropic" (tau = 2/tr(inv(Omega_tt)), kappa = 2 Omega_thth, the SE-Sync
    objective) or "unit"; ``tol``: the relative suboptimality bound under which the result is
    called certified; ``method``: "auto" (the SDP for components of at most 100 poses, else the
    staircase; a tree, no loop closure, composed at f* = 0), "sdp" or "staircase"; ``solver``,
    ``max_rank``, ``staircase_budget`` (in 10^9 multiply-adds) and ``refine`` (Levenberg-Marquardt
    under the full information matrices after certification) are pgo-solve's flags of the same
    names (``solver``: "ipm", the default, or "clarabel"). Each connected component is solved on
    its own.

    A :class:`Graph3` is solved as ``pgo-solve`` solves a 3D file: SE-Sync's problem (weights
    tau = 3/tr(inv(Omega_tt)), kappa = 3/(2 tr(inv(Omega_RR))), or "unit") by the staircase on
    St(3, p)^n, certified by the certificate matrix S; ``method="sdp"`` and ``refine`` on a TORO
    file are refused (:class:`PgoError`, the library's message); a ``solver`` given has no
    effect (a RuntimeWarning says so, as pgo-solve's warning does).

    Returns a :class:`Solution`: ``poses`` ((n, 3); (n, 7) or (n, 6) in 3D) and the report's
    fields. Raises :class:`PgoError` for what the library refuses (e.g. two FIX poses in one
    component).
    """
    _check_graph(graph)
    if isinstance(graph, Graph3) and solver is not None:
        warnings.warn(
            "solver had no effect: 3D graphs are solved by the staircase",
            RuntimeWarning,
            stacklevel=2,
        )
    report, poses, landmarks = _pgo.solve(
        graph,
        weights=weights,
        tol=float(tol),
        method=method,
        solver=solver,
        max_rank=int(max_rank),
        staircase_budget=float(staircase_budget),
        refine=bool(refine),
    )
    return Solution(json.loads(report), poses, landmarks, float(tol))


def certify(
    graph: AnyGraph,
    poses: Union[np.ndarray, Solution, None] = None,
    landmarks: Optional[np.ndarray] = None,
    *,
    weights: str = "isotropic",
    tol: float = 1e-6,
) -> Certificate:
    """Certifies an estimate of ``graph``, or bounds how far it is from optimal, as
    ``pgo-certify`` does.

    ``poses``: (n, 3) (x, y, theta) in the order of ``graph.ids`` (e.g. from GTSAM through
    :func:`pgo.gtsam.from_gtsam`), a :class:`Solution` (its poses and landmarks), or None for
    the graph's own poses (its vertex lines); ``landmarks``: (L, 2) positions when the graph has
    landmarks. The estimate's own Lagrange multipliers are tested first; where they do not
    certify it within ``tol``, the optimum's proven bound is reported: the bound always holds.
    The cost is pgo's objective f under ``weights``, not g2o's chi2 (reported beside it): an
    optimum of chi2 (GTSAM's, g2o's) is certified only to within a small relative bound.

    Of a :class:`Graph3`: ``poses`` is (n, 7) ``x y z qx qy qz qw`` for a g2o graph, (n, 6)
    ``x y z roll pitch yaw`` for a TORO one (its :class:`Solution`, or None for the file's own
    poses), certified as ``pgo-certify`` certifies a 3D estimate; ``landmarks`` must be None.
    """
    _check_graph(graph)
    if isinstance(poses, Solution):
        if landmarks is None and len(poses.landmarks):
            landmarks = poses.landmarks
        poses = poses.poses
    report = _pgo.certify(graph, poses, landmarks, weights=weights, tol=float(tol))
    return Certificate(json.loads(report), float(tol), graph.dimension)


def spectrum(
    graph: AnyGraph,
    k: int = 0,
    *,
    weights: str = "isotropic",
    solver: str = "ipm",
) -> Spectrum:
    """The smallest ``k`` eigenvalues (0: all of a component of at most 2000 poses, 10 of a
    larger one) of W, W(lambda*) and M, the zero count and the SZEP, as ``pgo-spectrum -k K``.

    Components of more than 100 poses are analysed sparse when ``k`` is 1 to 100 and the
    certificate allows it (fast), else dense (the dual SDP: cubic in the poses; MIT with k=0
    takes about 30 s). A warning is issued for a component whose eigenvalue iteration did not
    converge (its eigenvalues are then upper bounds).

    Of a :class:`Graph3`: each component is solved as by :func:`solve`, then the ``k`` smallest
    eigenvalues (10 with 0, at most 100) of Q, S and M are computed sparse, as
    ``pgo-spectrum -k K`` does for a 3D file; ``solver`` is not used.
    """
    _check_graph(graph)
    if isinstance(k, bool) or int(k) != k or k < 0:
        raise ValueError(f"k must be an integer >= 0, found {k!r}")
    text, unconverged = _pgo.spectrum(graph, int(k), weights=weights, solver=solver)
    for first_id in unconverged:
        warnings.warn(
            f"the eigenvalue iteration of the component of pose {first_id} did not "
            "converge; its eigenvalues are upper bounds",
            RuntimeWarning,
            stacklevel=2,
        )
    return Spectrum(json.loads(text))



def __getattr__(name: str) -> Any:
    # pgo.gtsam is imported on first use, so that GTSAM stays optional.
    if name == "gtsam":
        import importlib

        return importlib.import_module(".gtsam", __name__)
    raise AttributeError(f"module 'pgo' has no attribute {name!r}")
