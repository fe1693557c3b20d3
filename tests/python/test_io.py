"""pgo.read, Graph.write and pgo.Graph from arrays: the arrays against an independent parse of the
file's text, writing against pgo-convert's output byte for byte, and round trips."""

import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import pgo
from conftest import DATASETS, REPO_ROOT, run

MIT = DATASETS / "MIT.g2o"
TOY = DATASETS / "paper_toy.g2o"


def parse_g2o(path):
    """VERTEX_SE2, EDGE_SE2 and FIX lines by str.split: an independent reader."""
    vertices, edges, fixed = {}, [], []
    for line in Path(path).read_text().splitlines():
        t = line.split()
        if not t or t[0].startswith("#"):
            continue
        if t[0] == "VERTEX_SE2":
            vertices[int(t[1])] = [float(v) for v in t[2:5]]
        elif t[0] == "EDGE_SE2":
            edges.append(([int(t[1]), int(t[2])], [float(v) for v in t[3:6]], [float(v) for v in t[6:12]]))
        elif t[0] == "FIX":
            fixed += [int(v) for v in t[1:]]
    return vertices, edges, fixed


@pytest.mark.parametrize("path", [MIT, TOY], ids=["MIT", "toy"])
def test_arrays_equal_an_independent_parse(path):
    vertices, edges, fixed = parse_g2o(path)
    g = pgo.read(path)
    ids = sorted(vertices)
    assert g.ids.tolist() == ids and g.ids.dtype == np.int64
    assert g.poses.tolist() == [vertices[i] for i in ids]
    assert g.edges.tolist() == [e[0] for e in edges]
    assert g.measurements.tolist() == [e[1] for e in edges]
    assert g.information.tolist() == [e[2] for e in edges]
    assert g.fixed.tolist() == fixed
    assert g.num_poses == len(ids) and g.num_edges == len(edges)
    assert g.format == "g2o" and g.dialect == "g2o" and g.has_vertices
    # edge_indices index poses.
    assert (g.ids[g.edge_indices] == g.edges).all()
    assert g.landmarks.shape == (0, 2) and g.observations.shape == (0, 2)


@pytest.mark.parametrize("to, ext", [("g2o", "g2o"), ("toro", "graph")])
def test_write_equals_pgo_convert(tmp_path, to, ext):
    cli = tmp_path / f"cli.{ext}"
    run("pgo-convert", MIT, "-o", cli)
    g = pgo.read(MIT)
    # By the extension, by format=, and as text.
    by_ext = tmp_path / f"py.{ext}"
    g.write(by_ext)
    assert by_ext.read_bytes() == cli.read_bytes()
    by_flag = tmp_path / "py.out"
    g.write(str(by_flag), format=to)
    assert by_flag.read_bytes() == cli.read_bytes()
    assert g.to_text(format=to).encode() == cli.read_bytes()
    # Read back: the same graph (TORO's order is converted to g2o's when read).
    back = pgo.read(cli)
    assert back == g
    assert back.format == to
    assert back.information.tolist() == g.information.tolist()


def test_covariance_dialect_round_trip(tmp_path):
    cov = tmp_path / "MIT-cov.graph"
    run("pgo-convert", MIT, "--to-dialect", "toro-cov", "-o", cov)
    g = pgo.read(cov, dialect="toro-cov")
    assert g.dialect == "toro-cov"
    # Information, whatever the file holds: the inverse of the covariance, to rounding.
    np.testing.assert_allclose(g.information, pgo.read(MIT).information, rtol=1e-9, atol=1e-9)
    out = tmp_path / "py.g2o"
    g.write(out)
    cli = tmp_path / "cli.g2o"
    run("pgo-convert", cov, "--dialect", "toro-cov", "-o", cli)
    assert out.read_bytes() == cli.read_bytes()
    again = tmp_path / "again.graph"
    g.write(again, dialect="toro-cov")
    assert again.read_bytes() == cov.read_bytes()


def test_text_and_path_read_the_same_graph():
    text = MIT.read_text()
    by_text = pgo.read(text)
    by_bytes = pgo.read(MIT.read_bytes())
    by_path = pgo.read(str(MIT))
    by_pathlike = pgo.read(MIT)
    assert by_text == by_path == by_bytes == by_pathlike
    assert by_text.source == "<string>" and by_path.source == str(MIT)


def test_a_string_without_a_line_break_is_a_path(tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        pgo.read("VERTEX_SE2 0 0 0 0")
    assert e.value.filename == "VERTEX_SE2 0 0 0 0"
    # With its line break it is text.
    g = pgo.read("VERTEX_SE2 0 0 0 0\n")
    assert g.num_poses == 1 and g.source == "<string>"
    with pytest.raises(FileNotFoundError):
        pgo.read(tmp_path / "missing.g2o")
    with pytest.raises(IsADirectoryError):
        pgo.read(tmp_path)


def test_graph_from_arrays_equals_the_file():
    g = pgo.read(MIT)
    built = pgo.Graph(
        poses=g.poses,
        edges=g.edges,
        measurements=g.measurements,
        information=g.information,
        ids=g.ids,
        fixed=g.fixed,
    )
    assert built == g
    assert built.to_text() == g.to_text()
    assert built.to_text().encode() == run("pgo-convert", MIT, "--to", "g2o").stdout.encode()
    # Ids in any order: sorted with their poses, as the reader keeps them.
    perm = np.random.default_rng(1).permutation(g.num_poses)
    shuffled = pgo.Graph(g.poses[perm], g.edges, g.measurements, g.information, ids=g.ids[perm])
    assert shuffled == g
    # From Python lists, default ids and identity information.
    toy = pgo.read(TOY)
    lists = pgo.Graph(
        toy.poses.tolist(), toy.edges.tolist(), toy.measurements.tolist(), ids=toy.ids.tolist()
    )
    assert lists == toy  # the toy graph has unit information
    assert pgo.solve(lists, weights="unit").to_dict() == pgo.solve(toy, weights="unit").to_dict()
    assert pgo.Graph(np.zeros((2, 3)), [[0, 1]], [[1, 0, 0]]).ids.tolist() == [0, 1]


def test_graph_from_arrays_is_checked():
    p = np.zeros((3, 3))
    e = [[0, 1], [1, 2]]
    z = [[1, 0, 0], [1, 0, 0]]
    cases = [
        (dict(poses=np.zeros((3, 2)), edges=e, measurements=z), ValueError, "poses must have shape"),
        (dict(poses=p, edges=e, measurements=z[:1]), ValueError, r"measurements must have shape \(2, 3\)"),
        (dict(poses=p, edges=[[0, 0]], measurements=z[:1]), pgo.PgoError, "self-loop"),
        (dict(poses=p, edges=[[0, 5]], measurements=z[:1]), pgo.PgoError, "vertex 5 is not one"),
        (dict(poses=p, edges=[[0, 1.5]], measurements=z[:1]), pgo.PgoError, "not a vertex id"),
        (dict(poses=p, edges=[[0, -1]], measurements=z[:1]), pgo.PgoError, "not a vertex id"),
        (dict(poses=p, edges=e, measurements=z, ids=[0, 1, 1]), pgo.PgoError, "appears twice"),
        (dict(poses=p, edges=e, measurements=z, ids=[0, 1]), ValueError, "ids has 2 entries"),
        (dict(poses=p, edges=e, measurements=[[1, 0, np.nan], [1, 0, 0]]), pgo.PgoError, "not finite"),
        (
            dict(poses=p, edges=e, measurements=z, information=[[1, 0, 0, -1, 0, 1]] * 2),
            pgo.PgoError,
            "not positive definite",
        ),
        (dict(poses=p, edges=e, measurements=z, fixed=[7]), pgo.PgoError, "fixed"),
    ]
    for kwargs, exc, message in cases:
        with pytest.raises(exc, match=message):
            pgo.Graph(**kwargs)
    # allow_indefinite as the tools' --allow-indefinite.
    g = pgo.Graph(p, e, z, information=[[1, 0, 0, -1, 0, 1]] * 2, allow_indefinite=True)
    assert g.information[0, 3] == -1


def test_with_poses_and_immutability():
    g = pgo.read(TOY)
    poses = g.poses
    poses[0, 0] = 99.0  # a copy: the graph does not change
    assert g.poses[0, 0] != 99.0
    h = g.with_poses(poses)
    assert h.poses[0, 0] == 99.0 and g.poses[0, 0] != 99.0
    with pytest.raises(ValueError, match="shape"):
        g.with_poses(poses[:2])


def test_write_is_atomic_and_checked(tmp_path):
    g = pgo.read(TOY)
    with pytest.raises(OSError):
        g.write(tmp_path / "no-such-dir" / "x.g2o")
    with pytest.raises(pgo.PgoError, match="dialect"):
        g.write(tmp_path / "x.g2o", dialect="toro-info")
    with pytest.raises(ValueError, match="format must be one of"):
        g.write(tmp_path / "x.g2o", format="json")
    g.write(tmp_path / "x.g2o")
    assert [p.name for p in tmp_path.iterdir()] == ["x.g2o"]  # no temporary file left


LANDMARKS = """\
VERTEX_SE2 0 0 0 0
VERTEX_SE2 1 1 0 0.1
VERTEX_XY 5 2 1
EDGE_SE2 0 1 1 0 0.1 1 0 0 1 0 1
EDGE_SE2_XY 0 5 2 1 1 0 1
EDGE_SE2_XY 1 5 1.1 0.9 2 0.5 2
FIX 0
"""


def test_landmarks(tmp_path):
    g = pgo.read(LANDMARKS)
    assert g.landmark_ids.tolist() == [5]
    assert g.landmarks.tolist() == [[2.0, 1.0]]
    assert g.observations.tolist() == [[0, 5], [1, 5]]
    assert g.observation_measurements.tolist() == [[2.0, 1.0], [1.1, 0.9]]
    assert g.observation_information.tolist() == [[1.0, 0.0, 1.0], [2.0, 0.5, 2.0]]
    assert g.fixed.tolist() == [0]
    assert "1 landmarks, 2 observations" in repr(g)
    path = tmp_path / "lm.g2o"
    path.write_text(LANDMARKS)
    cli_out = tmp_path / "cli.g2o"
    from conftest import run_json

    cli = run_json("pgo-solve", path, "--no-timings", "-o", cli_out)
    s = pgo.solve(g)
    assert s.to_dict() == cli
    assert s.landmarks.shape == (1, 2)
    mine = tmp_path / "mine.g2o"
    g.with_poses(s.poses, s.landmarks).write(mine)
    assert mine.read_bytes() == cli_out.read_bytes()
    c = pgo.certify(g, s)
    assert c.to_dict() == run_json("pgo-certify", path, "--estimate", cli_out)
    with pytest.raises(pgo.PgoError, match="landmarks"):
        pgo.certify(g, s.poses)


def test_reader_warnings_are_warnings():
    text = "VERTEX_SE2 0 0 0 0\nFOO 1 2\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n"
    with pytest.warns(pgo.ReadWarning, match=r"<string>:2:1: warning: .*FOO"):
        g = pgo.read(text)
    assert len(g.warnings) == 1
    # The reports carry them, as the tools' --json does.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert pgo.solve(g).warnings == g.warnings
    with pytest.raises(pgo.ParseError, match="unknown tag 'FOO'"):
        pgo.read(text, strict=True)


def test_three_d_files_are_read_as_graph3():
    # A 3D tag gives a pgo.Graph3 (tests/python/test_three_d.py), not an error.
    g = pgo.read("VERTEX_SE3:QUAT 0 1 2 3 0 0 0 1\n")
    assert isinstance(g, pgo.Graph3) and g.dimension == 3
    assert g.poses.tolist() == [[1, 2, 3, 0, 0, 0, 1]] and g.num_edges == 0
    # Other 3D types are still refused, at their place.
    with pytest.raises(pgo.ParseError) as e:
        pgo.read("VERTEX_SE2 0 0 0 0\nEDGE_SE3_PRIOR 0 0 0 0\n")
    assert (e.value.line, e.value.column) == (2, 1)
    assert "3D" in str(e.value)
