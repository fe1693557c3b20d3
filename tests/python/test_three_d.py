"""3D pose graphs from Python (pgo.Graph3): the arrays against an independent parse of the file's
lines, the reports of pgo.solve, pgo.certify and pgo.spectrum against the tools' --json on the
same files (field by field, floats bit for bit), the estimate and Graph3.write against the files
pgo-solve -o and pgo-convert write (byte for byte), and the errors."""

import math
import warnings

import numpy as np
import pytest

import pgo
from conftest import run, run_json

G2O_VERTEX, G2O_EDGE = "VERTEX_SE3:QUAT", "EDGE_SE3:QUAT"
NAMES = ["tinyGrid3D.g2o", "smallGrid3D.g2o"]


def parse_3d(path):
    """VERTEX_SE3:QUAT / VERTEX3, EDGE_SE3:QUAT / EDGE3 and FIX lines by str.split: an
    independent reader (7 pose values for g2o, 6 for TORO; 21 information values)."""
    vertices, edges, fixed = {}, [], []
    for line in path.read_text().splitlines():
        t = line.split()
        if not t or t[0].startswith("#"):
            continue
        if t[0] in (G2O_VERTEX, "VERTEX3"):
            vertices[int(t[1])] = [float(v) for v in t[2:]]
        elif t[0] in (G2O_EDGE, "EDGE3"):
            width = 7 if t[0] == G2O_EDGE else 6
            values = [float(v) for v in t[3:]]
            edges.append(([int(t[1]), int(t[2])], values[:width], values[width:]))
        elif t[0] == "FIX":
            fixed += [int(v) for v in t[1:]]
    return vertices, edges, fixed


def toro_loop():
    """A TORO 3D file (VERTEX3/EDGE3, Euler angles): four poses on a tilted square, odometry and
    one loop closure, measurements slightly off, information diag(100, 100, 100, 25, 25, 25)."""
    info = " 100 0 0 0 0 0 100 0 0 0 0 100 0 0 0 25 0 0 25 0 25"
    return (
        "VERTEX3 0 0 0 0 0 0 0\n"
        "VERTEX3 1 1 0 0.1 0.05 0 1.5\n"
        "VERTEX3 2 1 1 0.2 0 0.1 3.1\n"
        "VERTEX3 3 0 1 0.1 0 0 -1.6\n"
        f"EDGE3 0 1 1.02 0 0.1 0.02 0.01 1.55{info}\n"
        f"EDGE3 1 2 0.98 0.01 0.05 -0.03 0.02 1.58{info}\n"
        f"EDGE3 2 3 1.01 -0.02 -0.1 0 -0.01 1.56{info}\n"
        f"EDGE3 3 0 0.99 0.03 0 0.01 0 1.59{info}\n"
    )


@pytest.fixture(scope="module")
def toro_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("toro") / "loop.graph"
    path.write_text(toro_loop())
    return path


@pytest.fixture(scope="module")
def small(shared_datasets):
    return shared_datasets / "smallGrid3D.g2o"


@pytest.fixture(scope="module")
def small_solution(small):
    return pgo.read(small), pgo.solve(pgo.read(small))


@pytest.mark.parametrize("name", NAMES)
def test_arrays_equal_an_independent_parse(shared_datasets, name):
    path = shared_datasets / name
    vertices, edges, fixed = parse_3d(path)
    g = pgo.read(path)
    assert isinstance(g, pgo.Graph3) and not isinstance(g, pgo.Graph)
    ids = sorted(vertices)
    assert g.ids.tolist() == ids and g.ids.dtype == np.int64
    assert g.poses.shape == (len(ids), 7) and g.poses.dtype == np.float64
    assert g.poses.tolist() == [vertices[i] for i in ids]
    assert g.edges.tolist() == [e[0] for e in edges]
    assert g.measurements.tolist() == [e[1] for e in edges]
    assert g.information.shape == (len(edges), 21)
    assert g.information.tolist() == [e[2] for e in edges]
    assert g.fixed.tolist() == fixed
    assert (g.ids[g.edge_indices] == g.edges).all()
    assert (g.num_poses, g.num_edges, g.dimension) == (len(ids), len(edges), 3)
    assert (g.format, g.dialect, g.source, g.warnings) == ("g2o", "g2o", str(path), [])
    assert repr(g) == f"<pgo.Graph3: {len(ids)} poses, {len(edges)} edges, 3D, g2o (dialect g2o), from {path}>"
    # From the text of the file: the same graph, named <string>.
    text = pgo.read(path.read_text())
    assert text == g and text.source == "<string>"


def test_planar_graphs_say_their_dimension():
    g = pgo.read("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n")
    assert isinstance(g, pgo.Graph) and g.dimension == 2
    s = pgo.solve(g)
    assert s.dimension == 2 and "3D" not in repr(s)
    assert pgo.certify(g, s).dimension == 2 and pgo.spectrum(g).dimension == 2


def test_toro_3d_arrays_and_solve(tmp_path, toro_file):
    vertices, edges, fixed = parse_3d(toro_file)
    g = pgo.read(toro_file)
    assert isinstance(g, pgo.Graph3) and (g.format, g.dialect) == ("toro", "toro-info")
    assert g.poses.shape == (4, 6) and g.poses.tolist() == [vertices[i] for i in sorted(vertices)]
    assert g.measurements.tolist() == [e[1] for e in edges]
    assert g.information.tolist() == [e[2] for e in edges]
    out = tmp_path / "cli.graph"
    cli = run_json("pgo-solve", toro_file, "--no-timings", "-o", out)
    s = pgo.solve(g)
    assert s.to_dict() == cli and s.chi2 is None
    assert s.poses.shape == (4, 6)
    mine = tmp_path / "py.graph"
    g.with_poses(s.poses).write(mine)
    assert mine.read_bytes() == out.read_bytes()
    # The information is over Euler angles: no refinement (the library's refusal).
    with pytest.raises(pgo.PgoError, match="TORO 3D") as e:
        pgo.solve(g, refine=True)
    stderr = run("pgo-solve", toro_file, "--refine", "-o", tmp_path / "r.graph", ok=(2,)).stderr
    assert stderr == f"pgo-solve: error: {e.value}\n"


@pytest.mark.parametrize(
    "name, options, flags",
    [
        ("tinyGrid3D.g2o", {}, []),
        ("smallGrid3D.g2o", {}, []),
        ("smallGrid3D.g2o", {"weights": "unit"}, ["--weights", "unit"]),
        ("tinyGrid3D.g2o", {"method": "staircase", "tol": 1e-9, "max_rank": 2}, ["--method", "staircase", "--tol", "1e-9", "--max-rank", "2"]),
        ("smallGrid3D.g2o", {"refine": True}, ["--refine"]),
    ],
    ids=["tiny", "small", "small-unit", "tiny-staircase", "small-refine"],
)
def test_solve_report_equals_pgo_solve_json(tmp_path, shared_datasets, name, options, flags):
    path = shared_datasets / name
    out = tmp_path / "cli.g2o"
    cli = run_json("pgo-solve", path, *flags, "--no-timings", "-o", out)
    graph = pgo.read(path)
    s = pgo.solve(graph, **options)
    assert s.to_dict() == cli
    for key, value in cli.items():
        if key == "poses":
            continue  # the array; the count is in to_dict()
        assert getattr(s, key) == value, key
    assert s.dimension == 3 and cli["dimension"] == 3
    assert s.poses.shape == (cli["poses"], 7) and s.landmarks.shape == (0, 3)
    # The estimate pgo-solve writes, byte for byte.
    mine = tmp_path / "py.g2o"
    graph.with_poses(s.poses).write(mine)
    assert mine.read_bytes() == out.read_bytes()
    assert "3D" in repr(s)


def test_certify_the_solved_estimate(tmp_path, small, small_solution):
    graph, s = small_solution
    assert s.certified
    est = tmp_path / "est.g2o"
    graph.with_poses(s.poses).write(est)
    cli = run_json("pgo-certify", small, "--estimate", est)
    c = pgo.certify(graph, s.poses)
    assert c.to_dict() == cli
    assert c.certified and bool(c) and c.dimension == 3
    # A Solution is taken as its poses.
    assert pgo.certify(graph, s).to_dict() == cli


def test_certify_a_perturbed_estimate_is_not_certified(tmp_path, small, small_solution):
    graph, s = small_solution
    rng = np.random.default_rng(1)
    perturbed = s.poses.copy()
    perturbed[:, :3] += rng.normal(scale=0.05, size=(len(perturbed), 3))
    est = tmp_path / "perturbed.g2o"
    graph.with_poses(perturbed).write(est)
    cli = run_json("pgo-certify", small, "--estimate", est, ok=(1,))
    c = pgo.certify(graph, perturbed)
    assert c.to_dict() == cli
    assert not c.certified and not c
    # The bound still holds: below the optimum's cost, which is below the perturbed one's.
    assert c.lower_bound <= s.cost < c.cost
    assert "NOT certified" in repr(c) and "3D" in repr(c)


def test_certify_own_poses_equals_pgo_certify(small):
    # The file's own poses (odometry): pgo-certify exits 1 and bounds the gap.
    cli = run_json("pgo-certify", small, ok=(1,))
    c = pgo.certify(pgo.read(small))
    assert c.to_dict() == cli and not c.certified


@pytest.mark.parametrize("name, k", [("tinyGrid3D.g2o", 4), ("smallGrid3D.g2o", 6)])
def test_spectrum_equals_pgo_spectrum_json(shared_datasets, name, k):
    path = shared_datasets / name
    cli = run_json("pgo-spectrum", path, "-k", k)
    sp = pgo.spectrum(pgo.read(path), k)
    assert sp.to_dict() == cli
    for key in ("eigenvalues", "penalized_eigenvalues", "rotation_eigenvalues"):
        arr = getattr(sp, key)
        assert isinstance(arr, np.ndarray) and arr.dtype == np.float64
        assert arr.tolist() == cli[key] and len(arr) == k
    assert sp.dimension == 3 and sp.certified == cli["certified"]
    assert f"{cli['near_zero']} at zero" in repr(sp) and "3D" in repr(sp)
    with pytest.raises(AttributeError):
        sp.tree  # a planar field, which the 3D report leaves out


def test_write_equals_pgo_convert_and_round_trips(tmp_path, small, toro_file):
    for path, ext in ((small, "g2o"), (toro_file, "graph")):
        cli = tmp_path / f"cli.{ext}"
        run("pgo-convert", path, "-o", cli)
        g = pgo.read(path)
        mine = tmp_path / f"py.{ext}"
        g.write(mine)
        assert mine.read_bytes() == cli.read_bytes()
        assert g.to_text() == cli.read_text()
        by_format = tmp_path / "by-format.txt"
        g.write(by_format, format=g.format, dialect=g.dialect)
        assert by_format.read_bytes() == cli.read_bytes()
        # Read back: every value bit for bit.
        assert pgo.read(mine) == g


def test_write_refuses_what_pgo_convert_refuses(tmp_path, small, toro_file):
    for path, other in ((small, "toro"), (toro_file, "g2o")):
        g = pgo.read(path)
        with pytest.raises(pgo.PgoError) as e:
            g.write(tmp_path / "out", format=other)
        stderr = run("pgo-convert", path, "--to", other, "-o", tmp_path / "cli", ok=(2,)).stderr
        assert stderr == f"pgo-convert: error: {e.value}\n"
        with pytest.raises(pgo.PgoError):
            g.to_text(format=other)
    g = pgo.read(small)
    with pytest.raises(pgo.PgoError) as e:
        g.write(tmp_path / "out.g2o", dialect="g2o-cov")
    stderr = run("pgo-convert", small, "--to-dialect", "g2o-cov", "-o", tmp_path / "c.g2o", ok=(2,)).stderr
    # The same message, naming pgo-convert's option --to-dialect where Python's is dialect=.
    assert str(e.value).startswith("dialect g2o-cov: ")
    assert stderr == f"pgo-convert: error: --to-{e.value}\n"
    assert not (tmp_path / "out").exists() and not (tmp_path / "out.g2o").exists()


def test_malformed_3d_line_raises_parse_error_at_its_place(tmp_path):
    # Line 2, the pose's z ("1e400", not a finite double) at column 23: "VERTEX_SE3:QUAT" is
    # 15 bytes, then " 1 0 0 " (id, x, y) puts it at 15 + 7 + 1.
    text = "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 0 0 1e400 0 0 0 1\n"
    path = tmp_path / "bad.g2o"
    path.write_text(text)
    with pytest.raises(pgo.ParseError) as e:
        pgo.read(path)
    assert (e.value.path, e.value.line, e.value.column) == (str(path), 2, 23)
    cli = run("pgo-convert", path, "-o", "/dev/null", ok=(2,))
    assert cli.stderr.splitlines()[-1] == str(e.value)
    with pytest.raises(pgo.ParseError) as e2:
        pgo.read(text)
    assert (e2.value.path, e2.value.line, e2.value.column) == ("<string>", 2, 23)
    # A zero quaternion, at its first value (column 25: 15 + " 1 0 0 0 " is 9, then 1).
    with pytest.raises(pgo.ParseError) as e3:
        pgo.read("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 0 0 0 0 0 0 0\n")
    assert (e3.value.line, e3.value.column) == (2, 25)
    # Planar and 3D lines in one file: the second kind's tag, at line 2 column 1.
    with pytest.raises(pgo.ParseError) as e4:
        pgo.read("VERTEX_SE2 0 0 0 0\nVERTEX_SE3:QUAT 1 0 0 0 0 0 0 1\n")
    assert (e4.value.line, e4.value.column) == (2, 1)


def test_refused_options_raise_pgo_error(small_solution):
    graph, s = small_solution
    with pytest.raises(pgo.PgoError, match="sdp") as e:
        pgo.solve(graph, method="sdp")
    assert not isinstance(e.value, pgo.ParseError)
    with pytest.raises(pgo.PgoError, match="landmarks"):
        pgo.certify(graph, s.poses, np.zeros((0, 3)))
    with pytest.raises(pgo.PgoError, match="cannot be normalized"):
        pgo.certify(graph, np.zeros_like(s.poses))
    with pytest.raises(ValueError, match="shape"):
        pgo.certify(graph, s.poses[:, :6])
    with pytest.raises(ValueError, match="shape"):
        graph.with_poses(np.zeros((graph.num_poses, 3)))
    with pytest.raises(pgo.PgoError, match="not finite"):
        graph.with_poses(np.full_like(s.poses, math.inf))
    with pytest.raises(pgo.PgoError, match="-k 101"):
        pgo.spectrum(graph, 101)
    with pytest.warns(RuntimeWarning, match="solver had no effect"):
        pgo.solve(graph, solver="ipm")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pgo.solve(graph)  # no warning without solver=


def test_no_panic_on_extreme_estimates(small_solution):
    graph, s = small_solution
    for scale in (1e150, 1e300):
        far = s.poses.copy()
        far[:, :3] *= scale
        try:
            c = pgo.certify(graph, far)
        except pgo.PgoError:
            continue
        assert not c.certified


def test_graph3_from_arrays_equals_the_file(shared_datasets, toro_file):
    for path, form in [(shared_datasets / "smallGrid3D.g2o", "g2o"), (toro_file, "toro")]:
        g = pgo.read(path)
        built = pgo.Graph3(g.poses, g.edges, g.measurements, g.information, ids=g.ids, fixed=g.fixed, form=form)
        assert built == g
        assert built.to_text() == g.to_text()
        assert (built.format, built.dialect, built.source) == (g.format, g.dialect, "<arrays>")
        # Ids in any order: sorted with their poses, as the reader keeps them.
        perm = np.random.default_rng(1).permutation(g.num_poses)
        shuffled = pgo.Graph3(
            g.poses[perm], g.edges, g.measurements, g.information, ids=g.ids[perm], form=form
        )
        assert shuffled.ids.tolist() == g.ids.tolist() and (shuffled.poses == g.poses).all()
    g = pgo.read(shared_datasets / "smallGrid3D.g2o")
    built = pgo.Graph3(g.poses, g.edges, g.measurements, g.information, ids=g.ids, fixed=g.fixed)
    assert pgo.solve(built).to_dict() == pgo.solve(g).to_dict()


def test_graph3_from_lists_by_hand():
    # Two poses, one edge: pose 1 one metre ahead of pose 0 and turned a quarter about z; unit
    # information by default. The measurement is consistent, so the optimum costs 0 and puts
    # pose 1 at the measurement from pose 0 (fixed at the origin).
    s = math.sqrt(0.5)
    g = pgo.Graph3(
        [[0, 0, 0, 0, 0, 0, 1], [0.5, 0.2, 0, 0, 0, 0, 1]],
        [[0, 1]],
        [[1, 0, 0, 0, 0, s, s]],
        fixed=[0],
    )
    assert g.information.tolist() == [
        [1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 1]
    ]
    solution = pgo.solve(g)
    assert solution.certified and abs(solution.cost) < 1e-12
    p = solution.poses[1]
    assert np.allclose(p[:3], [1, 0, 0], atol=1e-9)
    assert np.allclose(abs(p[3:] @ np.array([0, 0, s, s])), 1, atol=1e-9)


def test_graph3_from_arrays_is_checked():
    p = np.tile([0, 0, 0, 0, 0, 0, 1.0], (3, 1))
    e = [[0, 1], [1, 2]]
    z = [[1, 0, 0, 0, 0, 0, 1.0]] * 2
    eye = [1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 1]
    indefinite = list(eye)
    indefinite[20] = -1
    cases = [
        (dict(poses=np.zeros((3, 6)), edges=e, measurements=z), ValueError, r"poses must have shape \(3, 7\)"),
        (dict(poses=p, edges=e, measurements=z[:1]), ValueError, r"measurements must have shape \(2, 7\)"),
        (dict(poses=p, edges=e, measurements=z, form="toro"), ValueError, r"poses must have shape \(3, 6\)"),
        (dict(poses=p, edges=e, measurements=z, form="se3"), pgo.PgoError, "form must be"),
        (dict(poses=p, edges=[[0, 0]], measurements=z[:1]), pgo.PgoError, "self-loop"),
        (dict(poses=p, edges=[[0, 5]], measurements=z[:1]), pgo.PgoError, "vertex 5 is not one"),
        (dict(poses=p, edges=[[0, 1.5]], measurements=z[:1]), pgo.PgoError, "not a vertex id"),
        (dict(poses=p, edges=e, measurements=z, ids=[0, 1, 1]), pgo.PgoError, "appears twice"),
        (dict(poses=p, edges=e, measurements=z, ids=[0, 1]), ValueError, "ids has 2 entries"),
        (dict(poses=p, edges=e, measurements=[[1, 0, 0, 0, 0, 0, np.inf]] * 2), pgo.PgoError, "not finite"),
        (dict(poses=p, edges=e, measurements=[[1, 0, 0, 0, 0, 0, 0]] * 2), pgo.PgoError, "cannot be normalized"),
        (dict(poses=p, edges=e, measurements=z, information=[eye]), ValueError, r"information must have shape \(2, 21\)"),
        (dict(poses=p, edges=e, measurements=z, information=[indefinite] * 2), pgo.PgoError, "not positive definite"),
        (dict(poses=p, edges=e, measurements=z, fixed=[7]), pgo.PgoError, "fixed"),
    ]
    for kwargs, exc, message in cases:
        with pytest.raises(exc, match=message):
            pgo.Graph3(**kwargs)
    g = pgo.Graph3(p, e, z, information=[indefinite] * 2, allow_indefinite=True)
    assert g.information[0, 20] == -1
