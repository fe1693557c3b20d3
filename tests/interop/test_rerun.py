"""Rerun recordings of every tool (`--rerun-save`), read back with rerun-sdk 0.36.3.

Each test runs a tool with `--rerun-save`, checks the file with `rerun rrd verify` (the CLI of the
same rerun version as the Rust crate), reads it with `rerun.experimental.RrdReader` and compares
its contents with expectations computed here, independently of pgo: poses and edges come from a
plain parse of the input (or output) file, residuals from the cost formula evaluated in Python on
the optimized file pgo-solve writes, eigenvalues from the tool's own `--json` report (a second
output channel). The flags must not change the tools' other outputs: stdout, stderr and files
are compared byte for byte with a run without them.

Entity paths are documented in README.md ("Viewing in rerun") and src/viz.rs.
"""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import rerun.experimental as rx

from conftest import REPO_ROOT, pgo_binary

TOY = REPO_ROOT / "datasets" / "paper_toy.g2o"
RERUN_CLI = Path(sys.executable).parent / "rerun"
TOOLS = ["pgo-convert", "pgo-solve", "pgo-spectrum", "pgo-simulate", "pgo-certify"]

# The colors src/viz.rs documents (RGBA, packed as rerun stores them).
ODOMETRY_RGBA = 0x5A96F0FF
LOOP_CLOSURE_RGBA = 0xFA8C28FF
RESIDUAL_SMALLEST_RGBA = 0x3C5AFFFF
RESIDUAL_LARGEST_RGBA = 0xF02828FF
REJECTED_RGBA = 0xFF1E1EFF


# ---------------------------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------------------------


def run(tool: str, args, cwd: Path, check: bool = True, env=None, timeout: int = 300):
    cmd = [str(pgo_binary(tool)), *map(str, args)]
    proc = subprocess.run(cmd, capture_output=True, cwd=cwd, env=env, timeout=timeout)
    if check and proc.returncode != 0:
        pytest.fail(
            f"{' '.join(cmd)} exited with status {proc.returncode}\n"
            f"--- stderr ---\n{proc.stderr.decode(errors='replace')}",
            pytrace=False,
        )
    return proc


def read_g2o(path: Path):
    """VERTEX_SE2 and EDGE_SE2 lines, plainly: ({id: (x, y, theta)}, [(i, j, (dx, dy, dth), info6)])."""
    vertices, edges = {}, []
    for line in Path(path).read_text().splitlines():
        f = line.split()
        if not f:
            continue
        if f[0] == "VERTEX_SE2":
            vertices[int(f[1])] = tuple(map(float, f[2:5]))
        elif f[0] == "EDGE_SE2":
            edges.append((int(f[1]), int(f[2]), tuple(map(float, f[3:6])), tuple(map(float, f[6:12]))))
    return vertices, edges


def edge_terms(vertices, edges, weights: str):
    """The terms of the cost f (README; eq. (8) with per-edge weights), one per edge:
    tau |p_j - p_i - R_i d|^2 + kappa |e^{i th_j} - e^{i (th_i + dth)}|^2."""
    terms = []
    for i, j, (dx, dy, dth), (a, b, _, d, _, f) in edges:
        if weights == "unit":
            tau, kappa = 1.0, 1.0
        else:  # isotropic: tau = 2 / tr(inv(Omega_tt)), kappa = 2 Omega_thth
            tau, kappa = 2.0 * (a * d - b * b) / (a + d), 2.0 * f
        xi, yi, ti = vertices[i]
        xj, yj, tj = vertices[j]
        c, s = math.cos(ti), math.sin(ti)
        ex = xj - xi - (c * dx - s * dy)
        ey = yj - yi - (s * dx + c * dy)
        rot = abs(complex(math.cos(tj), math.sin(tj)) - complex(math.cos(ti + dth), math.sin(ti + dth))) ** 2
        terms.append(tau * (ex * ex + ey * ey) + kappa * rot)
    return terms


class Recording:
    """The recording store of an .rrd file: static entities (column -> value of the last row)
    and time series (entity -> [(iteration, {column: value})])."""

    def __init__(self, path: Path):
        with warnings.catch_warnings():
            # What a viewer's --save writes while receiving has no footer: read it whole.
            warnings.filterwarnings("ignore", message="RRD file has no footer")
            reader = rx.RrdReader(path)
        recordings = reader.recordings()
        assert len(recordings) == 1, recordings
        self.application_id = recordings[0].application_id
        self.blueprints = reader.blueprints()
        self.static: dict[str, dict] = {}
        self.series: dict[str, list] = {}
        for chunk in reader.stream(store=recordings[0]):
            path_ = chunk.entity_path
            if path_.startswith("/__"):
                continue  # recording properties
            batch = chunk.to_record_batch()
            timelines = set(chunk.timeline_names)
            columns = [n for n in batch.schema.names if not n.startswith("rerun.") and n not in timelines]
            if chunk.is_static:
                entity = self.static.setdefault(path_, {})
                for name in columns:
                    for value in batch.column(name).to_pylist():
                        if value is not None:
                            entity[name] = value
            else:
                timeline = next((t for t in ("iteration", "gnc_iteration") if t in timelines), None)
                steps = batch.column(timeline).to_pylist() if timeline else [None] * batch.num_rows
                rows = self.series.setdefault(path_, [])
                for r in range(batch.num_rows):
                    rows.append((steps[r], {n: batch.column(n)[r].as_py() for n in columns}))
        for rows in self.series.values():
            rows.sort(key=lambda row: row[0])

    def paths(self) -> set[str]:
        return set(self.static) | set(self.series)

    def values(self, path: str, column: str):
        return self.static[path][column]


def verify(path: Path):
    proc = subprocess.run([str(RERUN_CLI), "rrd", "verify", str(path)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, f"rerun rrd verify {path}:\n{proc.stdout}\n{proc.stderr}"


def f32(v: float) -> float:
    return float(np.float32(v))


def check_graph(rec: Recording, root: str, vertices, edges, heading_length: float | None = None):
    """`root`/poses, headings, odometry, loop_closures against a plainly parsed graph."""
    poses = rec.static[f"/{root}/poses"]
    ids = [int(i) for i in poses["pose_id"]]
    assert sorted(ids) == sorted(vertices), "one point per pose, with its id"
    assert len(poses["Points2D:positions"]) == len(vertices)
    for k, pid in enumerate(ids):
        x, y, th = vertices[pid]
        assert (poses["x"][k], poses["y"][k], poses["theta"][k]) == (x, y, th)  # exact f64
        assert poses["Points2D:positions"][k] == [f32(x), f32(y)]
    arrows = rec.static[f"/{root}/headings"]
    assert len(arrows["Arrows2D:vectors"]) == len(vertices)
    assert arrows["Arrows2D:origins"] == poses["Points2D:positions"]
    if heading_length is not None:
        for k, pid in enumerate(ids):
            vx, vy = arrows["Arrows2D:vectors"][k]
            th = vertices[pid][2]
            assert math.hypot(vx, vy) == pytest.approx(heading_length, rel=1e-6)
            assert vx * math.cos(th) + vy * math.sin(th) == pytest.approx(heading_length, rel=1e-5)
    odometry = [e for e in edges if abs(e[0] - e[1]) == 1]
    loops = [e for e in edges if abs(e[0] - e[1]) != 1]
    for name, want, rgba in [("odometry", odometry, ODOMETRY_RGBA), ("loop_closures", loops, LOOP_CLOSURE_RGBA)]:
        entity = rec.static[f"/{root}/{name}"]
        strips = entity.get("LineStrips2D:strips", [])
        assert len(strips) == len(want), f"{root}/{name}: one strip per edge"
        assert [(int(a), int(b)) for a, b in zip(entity["from"], entity["to"])] == [(e[0], e[1]) for e in want]
        for strip, (i, j, *_) in zip(strips, want):
            assert strip == [[f32(vertices[i][0]), f32(vertices[i][1])], [f32(vertices[j][0]), f32(vertices[j][1])]]
        if want:
            assert entity["LineStrips2D:colors"] == [rgba]


def median_half_length(edges) -> float:
    lengths = sorted(math.hypot(dx, dy) for _, _, (dx, dy, _), _ in edges if math.hypot(dx, dy) > 0)
    return 0.5 * lengths[len(lengths) // 2] if lengths else 1.0


def bars(rec: Recording, path: str) -> list[float]:
    """The values of a BarChart (a 1-D f64 tensor)."""
    (tensor,) = rec.static[path]["BarChart:values"]
    assert tensor["shape"] == [len(tensor["buffer"])]
    return tensor["buffer"]


# ---------------------------------------------------------------------------------------------
# Tests
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["MIT.g2o", "intel.g2o"])
def test_convert_records_the_graph_as_read(name, datasets_dir, tmp_path):
    src = datasets_dir / name
    plain = run("pgo-convert", ["--stats", src], tmp_path)
    recorded = run("pgo-convert", ["--stats", src, "--rerun-save", "g.rrd"], tmp_path)
    assert (recorded.stdout, recorded.stderr) == (plain.stdout, plain.stderr)
    verify(tmp_path / "g.rrd")
    rec = Recording(tmp_path / "g.rrd")
    assert rec.application_id == "pgo-convert"
    assert rec.paths() == {"/graph/poses", "/graph/headings", "/graph/odometry", "/graph/loop_closures", "/report/graph"}
    vertices, edges = read_g2o(src)
    check_graph(rec, "graph", vertices, edges, median_half_length(edges))
    odometry = sum(1 for e in edges if abs(e[0] - e[1]) == 1)
    assert rec.values("/report/graph", "TextLog:text") == [
        f"{len(vertices)} poses, {len(edges)} edges ({odometry} odometry, {len(edges) - odometry} loop closures)"
    ]
    assert len(rec.blueprints) == 1


def test_convert_edges_only_file_records_every_pose(datasets_dir, tmp_path):
    """CSAIL.g2o has no vertex lines: pgo composes poses along a spanning tree; one point per id."""
    src = datasets_dir / "CSAIL.g2o"
    out_plain, out_rec = tmp_path / "plain.graph", tmp_path / "rec.graph"
    plain = run("pgo-convert", [src, "-o", out_plain], tmp_path)
    recorded = run("pgo-convert", [src, "-o", out_rec, "--rerun-save", "c.rrd"], tmp_path)
    assert out_plain.read_bytes() == out_rec.read_bytes()
    assert recorded.stderr.replace(b"rec.graph", b"plain.graph") == plain.stderr
    rec = Recording(tmp_path / "c.rrd")
    _, edges = read_g2o(src)
    ids = {e[0] for e in edges} | {e[1] for e in edges}
    assert sorted(int(i) for i in rec.values("/graph/poses", "pose_id")) == sorted(ids)
    strips = len(rec.values("/graph/odometry", "LineStrips2D:strips")) + len(
        rec.values("/graph/loop_closures", "LineStrips2D:strips")
    )
    assert strips == len(edges)


@pytest.mark.parametrize("weights", ["unit", "isotropic"])
def test_solve_records_estimates_residuals_iterations_and_certificate(weights, tmp_path):
    if weights == "unit":
        src = TOY
    else:  # a simulated graph (identity information: tau = 1, kappa = 2)
        src = tmp_path / "sim.g2o"
        run("pgo-simulate", ["-n", "30", "--seed", "3", "-q", "-o", src], tmp_path)
    args = [src, "--weights", weights, "--json", "--no-timings"]
    plain = run("pgo-solve", [*args, "-o", "plain.g2o"], tmp_path, check=False)
    recorded = run("pgo-solve", [*args, "-o", "rec.g2o", "--rerun-save", "s.rrd"], tmp_path, check=False)
    assert plain.returncode in (0, 1) and recorded.returncode == plain.returncode
    assert (recorded.stdout, recorded.stderr) == (plain.stdout, plain.stderr)
    assert (tmp_path / "rec.g2o").read_bytes() == (tmp_path / "plain.g2o").read_bytes()
    report = json.loads(plain.stdout)
    verify(tmp_path / "s.rrd")
    rec = Recording(tmp_path / "s.rrd")
    assert rec.application_id == "pgo-solve"
    sdp = {"/solver/primal_objective", "/solver/dual_objective", "/solver/relative_gap", "/solver/mu"}
    staircase = {"/solver/cost", "/solver/gradient_norm", "/solver/rank", "/solver/damping"}
    # Not certified, --method auto runs the staircase too (the better of both is kept).
    solver = sdp | (staircase if not report["certified"] else set())
    assert rec.paths() == {
        *(f"/{root}/{n}" for root in ("graph", "optimized") for n in ("poses", "headings", "odometry", "loop_closures")),
        "/optimized/residuals",
        "/report/graph",
        "/report/certificate",
        *solver,
    }

    # The input, and the estimate pgo-solve wrote.
    vertices, edges = read_g2o(src)
    check_graph(rec, "graph", vertices, edges)
    optimized, out_edges = read_g2o(tmp_path / "rec.g2o")
    check_graph(rec, "optimized", optimized, out_edges)

    # Residuals: every edge in input order, its term of f computed here from the written file.
    residuals = rec.static["/optimized/residuals"]
    want = edge_terms(optimized, out_edges, weights)
    assert len(residuals["LineStrips2D:strips"]) == len(out_edges)
    assert [(int(a), int(b)) for a, b in zip(residuals["from"], residuals["to"])] == [(e[0], e[1]) for e in out_edges]
    assert residuals["residual"] == pytest.approx(want, rel=1e-7, abs=1e-10 * max(1.0, report["cost"]))
    assert sum(residuals["residual"]) == pytest.approx(report["cost"], rel=1e-9, abs=1e-12)
    colors = residuals["LineStrips2D:colors"]
    assert colors[int(np.argmax(want))] == RESIDUAL_LARGEST_RGBA
    assert colors[int(np.argmin(want))] == RESIDUAL_SMALLEST_RGBA

    # The certificate: the same numbers as the JSON report.
    cert = rec.static["/report/certificate"]
    assert cert["cost"] == [report["cost"]]
    assert cert["lower_bound"] == [report["lower_bound"]]
    assert cert["suboptimality_bound"] == [pytest.approx(report["suboptimality_bound"], rel=1e-12, abs=1e-15)]
    assert cert["certified"] == [1.0 if report["certified"] else 0.0]
    assert cert["szep"] == [1.0 if report["szep"] else 0.0]
    assert cert["near_zero"] == [float(report["near_zero_eigenvalues"])]
    assert cert["TextLog:text"][0].startswith("certified optimal" if report["certified"] else "NOT certified")
    assert cert["TextLog:level"] == ["INFO" if report["certified"] else "WARN"]

    # Solver iterations on the `iteration` timeline: consecutive steps from 0, at least one per
    # Newton step of every component, weak duality at every step, and the final gap small.
    steps = None
    for path in sdp:
        rows = rec.series[path]
        got = [step for step, _ in rows]
        assert got == list(range(len(got)))
        steps = steps or len(got)
        assert len(got) == steps
    # The staircase's Newton steps, if it ran, continue the same timeline.
    after = None
    for path in solver - sdp:
        got = [step for step, _ in rec.series[path]]
        assert got == list(range(steps, steps + len(got)))
        after = after or len(got)
        assert len(got) == after
    assert steps >= sum(c["sdp_iterations"] + 1 for c in report["components"])
    primal = [row["Scalars:scalars"][0] for _, row in rec.series["/solver/primal_objective"]]
    dual = [row["Scalars:scalars"][0] for _, row in rec.series["/solver/dual_objective"]]
    assert all(p >= d - 1e-9 * max(1.0, abs(d)) for p, d in zip(primal, dual))
    assert rec.series["/solver/relative_gap"][-1][1]["Scalars:scalars"][0] <= 1e-6


def test_spectrum_records_eigenvalues_and_the_szep(tmp_path):
    args = [TOY, "--weights", "unit", "-k", "4", "--json"]
    plain = run("pgo-spectrum", args, tmp_path)
    recorded = run("pgo-spectrum", [*args, "--rerun-save", "e.rrd"], tmp_path)
    assert (recorded.stdout, recorded.stderr) == (plain.stdout, plain.stderr)
    report = json.loads(plain.stdout)
    verify(tmp_path / "e.rrd")
    rec = Recording(tmp_path / "e.rrd")
    assert rec.application_id == "pgo-spectrum"
    for name in ("eigenvalues", "penalized_eigenvalues", "rotation_eigenvalues"):
        assert bars(rec, f"/spectrum/{name}") == report[name]  # exact f64
    assert rec.values("/spectrum/near_zero", "Scalars:scalars") == [float(report["near_zero"])]
    (text,) = rec.values("/report/spectrum", "TextLog:text")
    assert text.startswith(f"SZEP {'holds' if report['szep'] else 'fails'}: {report['near_zero']} eigenvalue")
    assert rec.values("/report/spectrum", "lower_bound") == [sum(c["lower_bound"] for c in report["components"])]
    vertices, edges = read_g2o(TOY)
    check_graph(rec, "graph", vertices, edges)


def test_certify_records_the_estimate_and_its_certificate(datasets_dir, tmp_path):
    # MIT.g2o's own vertices (odometry): not optimal, exit 1; the recording holds the estimate
    # (one point per vertex line, one strip per edge, parsed in Python) and the same numbers as
    # the JSON report.
    src = datasets_dir / "MIT.g2o"
    plain = run("pgo-certify", [src, "--json"], tmp_path, check=False)
    recorded = run("pgo-certify", [src, "--json", "--rerun-save", "v.rrd"], tmp_path, check=False)
    assert plain.returncode == recorded.returncode == 1
    assert (recorded.stdout, recorded.stderr) == (plain.stdout, plain.stderr)
    report = json.loads(plain.stdout)
    verify(tmp_path / "v.rrd")
    rec = Recording(tmp_path / "v.rrd")
    assert rec.application_id == "pgo-certify"
    vertices, edges = read_g2o(src)
    check_graph(rec, "graph", vertices, edges)
    cert = rec.static["/report/certificate"]
    assert cert["cost"] == [report["cost"]]
    assert cert["lower_bound"] == [report["lower_bound"]]
    assert cert["certified"] == [0.0]
    assert cert["TextLog:text"][0].startswith("NOT certified")


def test_simulate_records_the_generated_graph(tmp_path):
    args = ["-n", "25", "--seed", "7", "--loop-probability", "0.2"]
    plain = run("pgo-simulate", [*args, "-o", "plain.g2o"], tmp_path)
    recorded = run("pgo-simulate", [*args, "-o", "rec.g2o", "--rerun-save", "m.rrd"], tmp_path)
    assert (tmp_path / "rec.g2o").read_bytes() == (tmp_path / "plain.g2o").read_bytes()
    assert recorded.stderr.replace(b"rec.g2o", b"plain.g2o") == plain.stderr
    stdout_plain = run("pgo-simulate", args, tmp_path).stdout
    assert run("pgo-simulate", [*args, "--rerun-save", "m2.rrd"], tmp_path).stdout == stdout_plain
    verify(tmp_path / "m.rrd")
    rec = Recording(tmp_path / "m.rrd")
    vertices, edges = read_g2o(tmp_path / "rec.g2o")
    assert len(vertices) == 25
    check_graph(rec, "graph", vertices, edges, median_half_length(edges))
    assert len(rec.values("/graph/odometry", "LineStrips2D:strips")) == 24  # the spanning path


def test_rrd_print_lists_the_entities(tmp_path):
    """A second reader: the rerun CLI's own listing names the entities and archetypes."""
    run("pgo-convert", ["--stats", TOY, "--rerun-save", "t.rrd"], tmp_path)
    proc = subprocess.run(
        [str(RERUN_CLI), "rrd", "print", str(tmp_path / "t.rrd")], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    for path in ("/graph/poses", "/graph/headings", "/graph/odometry", "/graph/loop_closures", "/report/graph"):
        assert path in proc.stdout


@pytest.mark.parametrize("tool", TOOLS)
def test_a_failed_save_is_exit_2_and_writes_nothing(tool, tmp_path):
    target = tmp_path / "missing" / "x.rrd"
    args = {
        "pgo-convert": [TOY, "-o", "out.g2o"],
        "pgo-solve": [TOY, "--weights", "unit", "-o", "out.g2o"],
        "pgo-spectrum": [TOY, "--weights", "unit"],
        "pgo-simulate": ["-o", "out.g2o"],
        "pgo-certify": [TOY, "--weights", "unit"],
    }[tool]
    proc = run(tool, [*args, "--rerun-save", target], tmp_path, check=False)
    assert proc.returncode == 2
    assert proc.stdout == b""
    assert f"--rerun-save {target}".encode() in proc.stderr
    assert b"panicked" not in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == [], "no output, no partial file"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("tool", TOOLS)
def test_an_unreachable_viewer_is_a_warning(tool, tmp_path):
    url = f"rerun+http://127.0.0.1:{free_port()}/proxy"
    args = {
        "pgo-convert": ["--stats", TOY],
        "pgo-solve": [TOY, "--weights", "unit", "--json", "--no-timings"],
        "pgo-spectrum": [TOY, "--weights", "unit"],
        "pgo-simulate": ["-n", "8"],
        "pgo-certify": [TOY, "--weights", "unit"],
    }[tool]
    plain = run(tool, args, tmp_path, check=False)
    start = time.monotonic()
    proc = run(tool, [*args, f"--rerun-connect={url}", "--rerun-save", "v.rrd"], tmp_path, check=False)
    elapsed = time.monotonic() - start
    assert proc.returncode == plain.returncode
    assert proc.stdout == plain.stdout
    assert proc.stderr.startswith(plain.stderr)
    assert f"{tool}: warning: the rerun viewer at {url}".encode() in proc.stderr
    assert elapsed < 60
    verify(tmp_path / "v.rrd")  # the file is written all the same


@pytest.fixture
def viewer(tmp_path):
    """A rerun server (the CLI's `--save`: no window) on a free port that writes what it receives
    to an .rrd file: (URL, file)."""
    import rerun_cli  # the package of the `rerun` executable

    port = free_port()
    streamed = tmp_path / "streamed.rrd"
    exe = Path(rerun_cli.__file__).parent / "rerun"
    proc = subprocess.Popen(
        [str(exe), "--port", str(port), "--save", str(streamed)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
                break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    pytest.fail("the rerun server did not start", pytrace=False)
                time.sleep(0.1)
        yield f"rerun+http://127.0.0.1:{port}/proxy", streamed
    finally:
        proc.terminate()
        proc.wait(timeout=30)


@pytest.mark.parametrize("tool", TOOLS)
def test_a_running_viewer_receives_what_a_file_would_hold(tool, viewer, tmp_path):
    url, streamed = viewer
    args = {
        "pgo-convert": ["--stats", TOY],
        "pgo-solve": [TOY, "--weights", "unit", "--json", "--no-timings"],
        "pgo-spectrum": [TOY, "--weights", "unit"],
        "pgo-simulate": ["-n", "8"],
        "pgo-certify": [TOY, "--weights", "unit"],
    }[tool]
    plain = run(tool, args, tmp_path, check=False)
    proc = run(tool, [*args, f"--rerun-connect={url}", "--rerun-save", "both.rrd"], tmp_path, check=False)
    assert (proc.returncode, proc.stdout, proc.stderr) == (plain.returncode, plain.stdout, plain.stderr)
    saved = Recording(tmp_path / "both.rrd")
    # The server writes as data arrives: wait for the recording to be complete in its file.
    deadline = time.monotonic() + 30
    while True:
        try:
            received = Recording(streamed)
            if received.paths() == saved.paths():
                break
        except Exception:  # the file is being written
            pass
        if time.monotonic() > deadline:
            pytest.fail(f"the viewer did not receive the recording of {tool}", pytrace=False)
        time.sleep(0.2)
    assert received.application_id == tool
    for path, columns in saved.static.items():
        for column in ("pose_id", "x", "y", "residual", "Points2D:positions", "LineStrips2D:strips"):
            if column in columns:
                assert received.static[path][column] == columns[column], f"{path} {column}"


def test_spawn_without_a_viewer_is_a_warning(tmp_path):
    env = dict(os.environ, PATH="/usr/bin:/bin")  # no `rerun` executable on it
    plain = run("pgo-convert", ["--stats", TOY], tmp_path)
    proc = run("pgo-convert", ["--stats", TOY, "--rerun-spawn"], tmp_path, env=env)
    assert proc.stdout == plain.stdout
    assert b"pgo-convert: warning: cannot start the rerun viewer" in proc.stderr


def test_a_bad_viewer_url_is_exit_2(tmp_path):
    proc = run("pgo-convert", ["--stats", TOY, "--rerun-connect=localhost"], tmp_path, check=False)
    assert proc.returncode == 2
    assert proc.stdout == b""
    assert b"--rerun-connect=localhost: not the address of a rerun viewer" in proc.stderr


def test_staircase_iterations_on_the_timeline(datasets_dir, tmp_path):
    # MIT.g2o (808 poses) goes to the scalable solver: its Newton steps are on the `iteration`
    # timeline, the cost never increases, ends at the reported cost, and the rank is 1.
    args = [datasets_dir / "MIT.g2o", "--json", "--no-timings", "-o", "opt.g2o"]
    report = json.loads(run("pgo-solve", [*args, "--rerun-save", "s.rrd"], tmp_path).stdout)
    assert report["components"][0]["method"] == "staircase"
    rec = Recording(tmp_path / "s.rrd")
    cost = [row["Scalars:scalars"][0] for _, row in rec.series["/solver/cost"]]
    steps = [step for step, _ in rec.series["/solver/cost"]]
    assert steps == list(range(steps[0], steps[0] + len(steps)))
    assert len(cost) >= report["components"][0]["iterations"] - 2
    assert all(b <= a for a, b in zip(cost, cost[1:]))
    assert cost[-1] == pytest.approx(report["cost"], rel=1e-12)
    ranks = {row["Scalars:scalars"][0] for _, row in rec.series["/solver/rank"]}
    assert ranks == {1.0}
    assert all(row["Scalars:scalars"][0] >= 0 for _, row in rec.series["/solver/gradient_norm"])


def test_robust_records_rejected_edges_and_gnc_weights(datasets_dir, tmp_path):
    # intel.g2o with 20 random false loop closures (Vertigo's model): `optimized/rejected` holds
    # exactly the edges the JSON report lists as rejected, drawn between the written estimate's
    # positions in the rejected color; `robust/weights` holds one drawing per GNC iteration on the
    # `gnc_iteration` timeline, whose last weights reject the same edges.
    run("pgo-simulate", ["--corrupt", datasets_dir / "intel.g2o", "--outliers", "20", "--seed", "1",
                         "-o", "bad.g2o"], tmp_path)
    args = ["bad.g2o", "--robust", "tls", "--json", "--no-timings", "-o", "opt.g2o"]
    plain = run("pgo-solve", args, tmp_path)
    recorded = run("pgo-solve", [*args, "--rerun-save", "r.rrd"], tmp_path)
    assert recorded.stdout == plain.stdout
    verify(tmp_path / "r.rrd")
    report = json.loads(recorded.stdout)["robust"]
    assert report["rejected"] >= 20
    rec = Recording(tmp_path / "r.rrd")
    vertices, edges = read_g2o(tmp_path / "opt.g2o")
    rejected = rec.static["/optimized/rejected"]
    pairs = [(int(a), int(b)) for a, b in zip(rejected["from"], rejected["to"])]
    assert pairs == [(e["i"], e["j"]) for e in report["rejected_edges"]]
    assert rejected["residual"] == [e["residual_sq"] for e in report["rejected_edges"]]
    assert rejected["LineStrips2D:colors"] == [REJECTED_RGBA]
    for strip, (i, j) in zip(rejected["LineStrips2D:strips"], pairs):
        assert strip == [[f32(vertices[i][0]), f32(vertices[i][1])], [f32(vertices[j][0]), f32(vertices[j][1])]]
    # The strips and their `weight` column may arrive as separate rows of one step: merge them.
    steps: dict[int, dict] = {}
    for step, row in rec.series["/robust/weights"]:
        steps.setdefault(step, {}).update({k: v for k, v in row.items() if v is not None})
    assert sorted(steps) == list(range(1, report["gnc_iterations"] + 1))
    last = steps[report["gnc_iterations"]]
    assert len(last["weight"]) == len(edges)
    low = {(i, j) for (i, j, *_), w in zip(edges, last["weight"]) if w < 0.5}
    assert low == set(pairs)
    for w, rgba in zip(last["weight"], last["LineStrips2D:colors"]):
        if w == 1.0:
            assert rgba == ODOMETRY_RGBA
        elif w == 0.0:
            assert rgba == REJECTED_RGBA


# ---------------------------------------------------------------------------------------------
# 3D graphs (issue 15): the same entities as Points3D, Arrows3D, LineStrips3D
# ---------------------------------------------------------------------------------------------


def read_g2o_3d(path: Path):
    """VERTEX_SE3:QUAT and EDGE_SE3:QUAT lines, plainly: ({id: (t, q)}, [(i, j, t, q, info21)]),
    q = (qx, qy, qz, qw) as written."""
    vertices, edges = {}, []
    for line in Path(path).read_text().splitlines():
        f = line.split()
        if not f:
            continue
        if f[0] == "VERTEX_SE3:QUAT":
            v = list(map(float, f[2:9]))
            vertices[int(f[1])] = (np.array(v[:3]), np.array(v[3:]))
        elif f[0] == "EDGE_SE3:QUAT":
            v = list(map(float, f[3:31]))
            edges.append((int(f[1]), int(f[2]), np.array(v[:3]), np.array(v[3:7]), v[7:]))
    return vertices, edges


def rotation(q) -> np.ndarray:
    """The rotation matrix of the quaternion (qx, qy, qz, qw), normalized (Hamilton)."""
    x, y, z, w = np.asarray(q) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def full6(upper):
    m = np.zeros((6, 6))
    k = 0
    for r in range(6):
        for c in range(r, 6):
            m[r, c] = m[c, r] = upper[k]
            k += 1
    return m


def edge_terms_3d(vertices, edges, weights: str):
    """SE-Sync's f term by term: tau |t_j - t_i - R_i t~|^2 + kappa |R_j - R_i R~|_F^2 with
    tau = 3 / tr(inv(Omega_tt)), kappa = 3 / (2 tr(inv(Omega_RR))) (SE-Sync's reader)."""
    terms = []
    for i, j, t, q, info in edges:
        if weights == "unit":
            tau, kappa = 1.0, 1.0
        else:
            m = full6(info)
            tau = 3.0 / np.trace(np.linalg.inv(m[:3, :3]))
            kappa = 3.0 / (2.0 * np.trace(np.linalg.inv(m[3:, 3:])))
        (ti, qi), (tj, qj) = vertices[i], vertices[j]
        ri, rj = rotation(qi), rotation(qj)
        terms.append(tau * np.sum((tj - ti - ri @ t) ** 2) + kappa * np.sum((rj - ri @ rotation(q)) ** 2))
    return terms


def check_graph_3d(rec: Recording, root: str, vertices, edges):
    poses = rec.static[f"/{root}/poses"]
    ids = [int(i) for i in poses["pose_id"]]
    assert sorted(ids) == sorted(vertices)
    assert len(poses["Points3D:positions"]) == len(vertices)
    for k, pid in enumerate(ids):
        t, q = vertices[pid]
        assert [poses["x"][k], poses["y"][k], poses["z"][k]] == list(t)  # exact f64
        assert poses["Points3D:positions"][k] == [f32(v) for v in t]
        u = q / np.linalg.norm(q)
        got = np.array([poses["qx"][k], poses["qy"][k], poses["qz"][k], poses["qw"][k]])
        assert min(np.abs(got - u).max(), np.abs(got + u).max()) < 1e-12
    arrows = rec.static[f"/{root}/headings"]
    assert arrows["Arrows3D:origins"] == poses["Points3D:positions"]
    for k, pid in enumerate(ids):
        # Each arrow along the pose's x axis.
        v = np.array(arrows["Arrows3D:vectors"][k])
        x_axis = rotation(vertices[pid][1])[:, 0]
        assert v @ x_axis == pytest.approx(np.linalg.norm(v), rel=1e-5)
    odometry = [e for e in edges if abs(e[0] - e[1]) == 1]
    loops = [e for e in edges if abs(e[0] - e[1]) != 1]
    for name, want, rgba in [("odometry", odometry, ODOMETRY_RGBA), ("loop_closures", loops, LOOP_CLOSURE_RGBA)]:
        entity = rec.static[f"/{root}/{name}"]
        strips = entity.get("LineStrips3D:strips", [])
        assert len(strips) == len(want), f"{root}/{name}: one strip per edge"
        assert [(int(a), int(b)) for a, b in zip(entity["from"], entity["to"])] == [(e[0], e[1]) for e in want]
        for strip, (i, j, *_) in zip(strips, want):
            assert strip == [[f32(v) for v in vertices[i][0]], [f32(v) for v in vertices[j][0]]]
        if want:
            assert entity["LineStrips3D:colors"] == [rgba]


@pytest.mark.parametrize("weights", ["isotropic", "unit"])
def test_solve_records_a_3d_graph(weights, tmp_path):
    src = tmp_path / "sphere.g2o"
    run("pgo-simulate", ["--world", "sphere", "-n", "49", "--seed", "4", "--rotation-noise", "gaussian:0.05", "-q", "-o", src], tmp_path)
    args = [src, "--weights", weights, "--json", "--no-timings"]
    plain = run("pgo-solve", [*args, "-o", "plain.g2o"], tmp_path, check=False)
    recorded = run("pgo-solve", [*args, "-o", "rec.g2o", "--rerun-save", "s.rrd"], tmp_path, check=False)
    assert plain.returncode == recorded.returncode == 0
    assert (recorded.stdout, recorded.stderr) == (plain.stdout, plain.stderr)
    assert (tmp_path / "rec.g2o").read_bytes() == (tmp_path / "plain.g2o").read_bytes()
    report = json.loads(plain.stdout)
    assert report["certified"]
    verify(tmp_path / "s.rrd")
    rec = Recording(tmp_path / "s.rrd")
    assert rec.application_id == "pgo-solve"
    spatial = {f"/{root}/{n}" for root in ("graph", "optimized") for n in ("poses", "headings", "odometry", "loop_closures")}
    assert spatial | {"/optimized/residuals", "/report/graph", "/report/certificate"} <= rec.paths()
    assert all(p.startswith("/solver/") for p in rec.paths() - spatial - {"/optimized/residuals", "/report/graph", "/report/certificate"})
    vertices, edges = read_g2o_3d(src)
    check_graph_3d(rec, "graph", vertices, edges)
    optimized, out_edges = read_g2o_3d(tmp_path / "rec.g2o")
    check_graph_3d(rec, "optimized", optimized, out_edges)
    (summary,) = rec.values("/report/graph", "TextLog:text")
    assert summary.startswith(f"{len(vertices)} poses, {len(edges)} edges")

    residuals = rec.static["/optimized/residuals"]
    want = edge_terms_3d(optimized, out_edges, weights)
    assert len(residuals["LineStrips3D:strips"]) == len(out_edges)
    assert [(int(a), int(b)) for a, b in zip(residuals["from"], residuals["to"])] == [(e[0], e[1]) for e in out_edges]
    assert residuals["residual"] == pytest.approx(want, rel=1e-6, abs=1e-9 * max(1.0, report["cost"]))
    assert sum(residuals["residual"]) == pytest.approx(report["cost"], rel=1e-6)
    colors = residuals["LineStrips3D:colors"]
    assert colors[int(np.argmax(want))] == RESIDUAL_LARGEST_RGBA
    assert colors[int(np.argmin(want))] == RESIDUAL_SMALLEST_RGBA

    cert = rec.static["/report/certificate"]
    assert cert["cost"] == [report["cost"]]
    assert cert["lower_bound"] == [report["lower_bound"]]
    assert cert["certified"] == [1.0]
    assert cert["TextLog:text"][0].startswith("certified optimal")


def test_simulate_records_a_3d_world(tmp_path):
    args = ["--world", "torus", "-n", "36", "--seed", "2", "--loop-probability", "0.5"]
    plain = run("pgo-simulate", [*args, "-o", "plain.g2o"], tmp_path)
    recorded = run("pgo-simulate", [*args, "-o", "rec.g2o", "--rerun-save", "m.rrd"], tmp_path)
    assert (tmp_path / "rec.g2o").read_bytes() == (tmp_path / "plain.g2o").read_bytes()
    assert recorded.stderr.replace(b"rec.g2o", b"plain.g2o") == plain.stderr
    verify(tmp_path / "m.rrd")
    rec = Recording(tmp_path / "m.rrd")
    assert rec.application_id == "pgo-simulate"
    assert rec.paths() == {*(f"/graph/{n}" for n in ("poses", "headings", "odometry", "loop_closures")), "/report/graph"}
    vertices, edges = read_g2o_3d(tmp_path / "rec.g2o")
    assert len(vertices) == 36
    check_graph_3d(rec, "graph", vertices, edges)
    assert len(rec.values("/graph/odometry", "LineStrips3D:strips")) == 35  # the path


def test_convert_and_certify_record_a_3d_graph(tmp_path):
    src = tmp_path / "grid.g2o"
    run("pgo-simulate", ["--world", "grid", "-n", "27", "--seed", "1", "-q", "-o", src], tmp_path)
    vertices, edges = read_g2o_3d(src)
    plain = run("pgo-convert", ["--stats", src], tmp_path)
    recorded = run("pgo-convert", ["--stats", src, "--rerun-save", "c.rrd"], tmp_path)
    assert (recorded.stdout, recorded.stderr) == (plain.stdout, plain.stderr)
    verify(tmp_path / "c.rrd")
    rec = Recording(tmp_path / "c.rrd")
    assert rec.paths() == {*(f"/graph/{n}" for n in ("poses", "headings", "odometry", "loop_closures")), "/report/graph"}
    check_graph_3d(rec, "graph", vertices, edges)
    # pgo-certify on the ground truth (not optimal under noise: exit 1): the estimate recorded
    # and the report's numbers.
    plain = run("pgo-certify", [src, "--json"], tmp_path, check=False)
    recorded = run("pgo-certify", [src, "--json", "--rerun-save", "v.rrd"], tmp_path, check=False)
    assert plain.returncode == recorded.returncode == 1
    assert (recorded.stdout, recorded.stderr) == (plain.stdout, plain.stderr)
    report = json.loads(plain.stdout)
    verify(tmp_path / "v.rrd")
    rec = Recording(tmp_path / "v.rrd")
    assert rec.application_id == "pgo-certify"
    check_graph_3d(rec, "graph", vertices, edges)
    cert = rec.static["/report/certificate"]
    assert cert["cost"] == [report["cost"]]
    assert cert["lower_bound"] == [report["lower_bound"]]
    assert cert["certified"] == [0.0]
