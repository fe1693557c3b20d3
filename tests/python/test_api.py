"""The package's surface: a docstring on every public function, class and method, and type stubs
(pgo/_pgo.pyi, py.typed) that declare exactly what the extension defines."""

import ast
import inspect
from pathlib import Path

import pgo
import pgo._pgo as ext


def test_every_public_name_has_a_docstring():
    for name in pgo.__all__:
        obj = getattr(pgo, name)
        assert (obj.__doc__ or "").strip(), name
        if inspect.isclass(obj):
            for attr, member in vars(obj).items():
                if attr.startswith("_") or not (callable(member) or isinstance(member, property) or inspect.isdatadescriptor(member)):
                    continue
                assert (getattr(obj, attr).__doc__ or "").strip(), f"{name}.{attr}"
    for fn in ("to_gtsam", "from_gtsam"):
        assert (getattr(pgo.gtsam, fn).__doc__ or "").strip(), fn
    assert pgo.gtsam.__doc__.strip()


def test_stubs_match_the_extension():
    root = Path(pgo.__file__).parent
    assert (root / "py.typed").is_file()
    tree = ast.parse((root / "_pgo.pyi").read_text())
    functions = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
    defined = {n for n in dir(ext) if not n.startswith("_") and n != "VERSION"}
    assert functions | set(classes) == defined
    for cls in ("Graph", "Graph3"):
        stub = {n.name for n in classes[cls].body if isinstance(n, ast.FunctionDef)}
        real = {n for n in dir(getattr(ext, cls)) if not n.startswith("_")}
        assert real <= stub, cls
    for fn in functions:
        stub = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == fn)
        stub_args = [a.arg for a in stub.args.args + stub.args.kwonlyargs]
        real_args = list(inspect.signature(getattr(ext, fn)).parameters)
        assert stub_args == real_args, fn


def test_parse_error_is_a_value_error_with_a_place():
    assert issubclass(pgo.ParseError, pgo.PgoError)
    assert issubclass(pgo.PgoError, ValueError)
    assert pgo.ParseError.__module__ == "pgo" and pgo.Graph.__module__ == "pgo"


USAGE = """\
import numpy as np
import pgo

graph: pgo.AnyGraph = pgo.read("MIT.g2o")
planar: pgo.Graph = pgo.Graph(np.zeros((1, 3)), [], [])
solution = pgo.solve(graph, weights="unit", tol=1e-6)
poses: np.ndarray = solution.poses
certificate = pgo.certify(graph, solution.poses)
ok: bool = certificate.certified
eigenvalues: np.ndarray = pgo.spectrum(graph, 3).eigenvalues
graph.with_poses(poses).write("out.g2o", format="toro")
built = pgo.Graph(np.zeros((2, 3)), [[0, 1]], [[1.0, 0.0, 0.0]], fixed=[0])
three = pgo.read("grid3D.g2o")
if isinstance(three, pgo.Graph3):
    rows: np.ndarray = three.information
    three.with_poses(pgo.solve(three).poses).write("grid3D-opt.g2o")
    dimension: int = pgo.certify(three).dimension + pgo.spectrum(three, 4).near_zero
made: pgo.Graph3 = pgo.Graph3(np.tile([0.0, 0, 0, 0, 0, 0, 1], (2, 1)), [[0, 1]], [[1.0, 0, 0, 0, 0, 0, 1]], form="g2o")
try:
    pgo.read("x.g2o")
except pgo.ParseError as e:
    line: int = e.line
"""


def test_mypy_strict_on_the_package_and_a_users_code(tmp_path):
    import subprocess
    import sys

    (tmp_path / "usage.py").write_text(USAGE)
    for target in (["-p", "pgo"], ["usage.py"]):
        proc = subprocess.run(
            [sys.executable, "-m", "mypy", "--strict", "--no-incremental", *target],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert proc.returncode == 0, proc.stdout + proc.stderr
