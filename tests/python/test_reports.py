"""pgo.solve, pgo.certify and pgo.spectrum against the tools' --json reports on the same files:
the same library calls and the same report builders, so every field must be equal (floats bit
for bit), and the estimate pgo.solve returns is the one pgo-solve writes, byte for byte."""

import math

import numpy as np
import pytest

import pgo
from conftest import DATASETS, run, run_json

MIT = DATASETS / "MIT.g2o"
TOY = DATASETS / "paper_toy.g2o"

# README "Quick start": pgo-solve datasets/MIT.g2o prints this cost and bound.
MIT_COST = 61.15411552463644
MIT_BOUND = 61.15411552451574


@pytest.fixture(scope="module")
def mit():
    return pgo.read(MIT)


@pytest.fixture(scope="module")
def mit_solution(mit):
    return pgo.solve(mit)


def test_mit_known_optimum(mit_solution):
    s = mit_solution
    assert s.certified is True
    assert s.cost == MIT_COST
    assert s.lower_bound == MIT_BOUND
    assert s.poses.shape == (808, 3) and s.poses.dtype == np.float64
    assert s.landmarks.shape == (0, 2)
    assert "certified" in repr(s) and "NOT" not in repr(s)
    assert repr(MIT_COST) in repr(s)


@pytest.mark.parametrize(
    "path, options, flags",
    [
        (MIT, {}, []),
        (TOY, {"weights": "unit"}, ["--weights", "unit"]),
        (TOY, {"method": "staircase", "tol": 1e-9}, ["--method", "staircase", "--tol", "1e-9"]),
        (MIT, {"refine": True}, ["--refine"]),
    ],
    ids=["MIT", "toy-unit", "toy-staircase", "MIT-refine"],
)
def test_solve_report_equals_pgo_solve_json(tmp_path, path, options, flags):
    out = tmp_path / "cli.g2o"
    cli = run_json("pgo-solve", path, *flags, "--no-timings", "-o", out)
    graph = pgo.read(path)
    s = pgo.solve(graph, **options)
    assert s.to_dict() == cli
    for key, value in cli.items():
        if key in ("poses", "landmarks"):
            continue  # the arrays; the counts are in to_dict()
        assert getattr(s, key) == value, key
    assert len(s.poses) == cli["poses"]
    # The estimate pgo-solve writes, byte for byte.
    mine = tmp_path / "py.g2o"
    graph.with_poses(s.poses).write(mine)
    assert mine.read_bytes() == out.read_bytes()


def test_a_chain_is_composed_as_pgo_solve_composes_it(tmp_path):
    # Odometry alone (a tree): composed at f* = 0 with the bound 0 (Props. 1, 11), by the
    # library call as by the tool, field for field and byte for byte.
    rng = np.random.default_rng(3)
    n = 40
    poses = rng.normal(size=(n, 3))
    edges = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    graph = pgo.Graph(poses, edges, rng.normal(size=(n - 1, 3)))
    s = pgo.solve(graph)
    assert s.certified and s.lower_bound == 0.0 and s.cost < 1e-20
    assert [c["method"] for c in s.components] == ["tree"]
    assert "method auto (tree)" in repr(s)
    path, out = tmp_path / "chain.g2o", tmp_path / "cli.g2o"
    graph.write(path)
    cli = run_json("pgo-solve", path, "--no-timings", "-o", out)
    assert s.to_dict() == cli
    mine = tmp_path / "py.g2o"
    graph.with_poses(s.poses).write(mine)
    assert mine.read_bytes() == out.read_bytes()


def test_absent_fields_have_defaults(mit_solution):
    d = mit_solution.to_dict()
    assert "not_certified_because" not in d and mit_solution.not_certified_because is None
    assert "refined_chi2" not in d and mit_solution.refined_chi2 is None
    assert mit_solution.warnings == [] and mit_solution.observations == 0
    with pytest.raises(AttributeError):
        mit_solution.no_such_field


def test_certify_equals_pgo_certify_json(tmp_path, mit, mit_solution):
    est = tmp_path / "est.g2o"
    mit.with_poses(mit_solution.poses).write(est)
    cli = run_json("pgo-certify", MIT, "--estimate", est)
    c = pgo.certify(mit, mit_solution.poses)
    assert c.to_dict() == cli
    assert c.certified and bool(c)
    assert c.cost == cli["cost"] and c.lower_bound == cli["lower_bound"]
    # A Solution is taken as its poses.
    assert pgo.certify(mit, mit_solution).to_dict() == cli


def test_certify_own_poses_not_certified(mit):
    # The file's own poses (odometry): pgo-certify exits 1 and bounds the gap.
    cli = run_json("pgo-certify", MIT, ok=(1,))
    c = pgo.certify(mit)
    assert c.to_dict() == cli
    assert not c.certified and not c
    assert c.lower_bound <= MIT_COST <= c.cost
    assert "NOT certified" in repr(c)


def test_spectrum_equals_pgo_spectrum_json(mit):
    cli = run_json("pgo-spectrum", MIT, "-k", "6")
    sp = pgo.spectrum(mit, 6)
    assert sp.to_dict() == cli
    for name in ("eigenvalues", "penalized_eigenvalues", "rotation_eigenvalues"):
        arr = getattr(sp, name)
        assert isinstance(arr, np.ndarray) and arr.dtype == np.float64
        assert arr.tolist() == cli[name]
    assert sp.szep and sp.near_zero == 1


def test_spectrum_all_eigenvalues_of_a_small_graph():
    graph = pgo.read(TOY)
    cli = run_json("pgo-spectrum", TOY, "--weights", "unit")
    sp = pgo.spectrum(graph, weights="unit")
    assert sp.to_dict() == cli
    assert len(sp.eigenvalues) > 6  # all of them (-k 0)


def test_intel_from_the_shared_data_sets(tmp_path, shared_datasets):
    path = shared_datasets / "intel.g2o"
    out = tmp_path / "intel-opt.g2o"
    cli = run_json("pgo-solve", path, "--no-timings", "-o", out)
    graph = pgo.read(path)
    s = pgo.solve(graph)
    assert s.to_dict() == cli
    assert s.certified
    mine = tmp_path / "mine.g2o"
    graph.with_poses(s.poses).write(mine)
    assert mine.read_bytes() == out.read_bytes()


def test_options_are_checked(mit):
    with pytest.raises(ValueError, match="weights must be one of"):
        pgo.solve(mit, weights="huber")
    with pytest.raises(ValueError, match="method"):
        pgo.solve(mit, method="gauss-newton")
    with pytest.raises(ValueError, match="tol"):
        pgo.solve(mit, tol=math.nan)
    with pytest.raises(ValueError, match="k must be"):
        pgo.spectrum(mit, -1)
    with pytest.raises(TypeError):
        pgo.solve("MIT.g2o")
    # What the library refuses is a PgoError, with the library's message.
    with pytest.raises(pgo.PgoError, match="sdp"):
        pgo.solve(_big_graph(), method="sdp")


def _big_graph():
    # A chain of 2100 poses: more than --method sdp takes (2000).
    n = 2100
    poses = np.zeros((n, 3))
    poses[:, 0] = np.arange(n)
    edges = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    meas = np.tile([1.0, 0.0, 0.0], (n - 1, 1))
    return pgo.Graph(poses, edges, meas)


def test_pgo_error_for_two_fixed_poses_in_a_component(tmp_path):
    g = pgo.read(TOY)
    two = pgo.Graph(g.poses, g.edges, g.measurements, g.information, g.ids, fixed=g.ids[:2])
    with pytest.raises(pgo.PgoError) as e:
        pgo.solve(two)
    assert isinstance(e.value, ValueError) and not isinstance(e.value, pgo.ParseError)
    # The message is pgo-solve's on the same graph.
    path = tmp_path / "two-fixed.g2o"
    two.write(path)
    stderr = run("pgo-solve", path, "-o", tmp_path / "out.g2o", ok=(2,)).stderr
    assert stderr == f"pgo-solve: error: {e.value}\n"


def _solve_cost(path):
    return pgo.solve(pgo.read(path)).cost


def test_a_forked_process_solves_too(mit_solution):
    """pgo keeps a thread for the second core once a solve has used it; a process forked after
    that (multiprocessing's fork start method, Linux's default before Python 3.14) has not the
    thread, and its solves must run all the same, to the same bits."""
    import multiprocessing

    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(1) as pool:
        cost = pool.apply_async(_solve_cost, (str(MIT),)).get(timeout=120)
    assert cost == mit_solution.cost == MIT_COST
