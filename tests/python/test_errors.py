"""Errors as Python exceptions: every file of the malformed corpus (tests/malformed/cases.tsv,
places counted by hand) raises pgo.ParseError at its LINE:COL with the tools' message, read from
a path or as text; and no input of the repository's corpora (malformed, tolerated, fuzz
regressions) makes a Rust panic reach Python, whatever is called on it."""

from pathlib import Path

import numpy as np
import pytest

import pgo
from conftest import MALFORMED, REPO_ROOT, run


def cases():
    rows = []
    for line in (MALFORMED / "cases.tsv").read_text(encoding="utf-8").splitlines():
        if not line or line.startswith("#"):
            continue
        name, flags, place, message = line.split("\t")
        rows.append((name, flags, place, message))
    return rows


CASES = cases()

# The tools' flags in cases.tsv, as pgo.read's keyword arguments.
FLAGS = {
    "-": {},
    "--strict": {"strict": True},
    "--dialect toro-info": {"dialect": "toro-info"},
    "--dialect toro-cov": {"dialect": "toro-cov"},
}


def test_the_corpus_is_all_here():
    assert len(CASES) >= 50
    listed = {c[0] for c in CASES}
    on_disk = {p.name for p in MALFORMED.iterdir() if p.name != "cases.tsv"}
    assert listed == on_disk


@pytest.mark.parametrize("name, flags, place, message", CASES, ids=[c[0] for c in CASES])
def test_malformed_file_raises_parse_error_at_its_place(name, flags, place, message):
    path = MALFORMED / name
    line, col = map(int, place.split(":"))
    kwargs = FLAGS[flags]
    with pytest.raises(pgo.ParseError) as e:
        pgo.read(path, **kwargs)
    err = e.value
    assert isinstance(err, ValueError) and isinstance(err, pgo.PgoError)
    assert (err.path, err.line, err.column) == (str(path), line, col)
    assert err.reason == message
    assert str(err) == f"{path}:{line}:{col}: error: {message}"
    # Exactly the line pgo-convert prints.
    cli = run("pgo-convert", path, *([] if flags == "-" else flags.split()), "-o", "/dev/null", ok=(2,))
    assert cli.stderr.splitlines()[-1] == str(err)
    # The same from the bytes of the file, named <string>.
    with pytest.raises(pgo.ParseError) as e2:
        pgo.read(path.read_bytes(), **kwargs)
    assert (e2.value.path, e2.value.line, e2.value.column) == ("<string>", line, col)
    assert str(e2.value) == f"<string>:{line}:{col}: error: {message}"


def _corpus():
    files = []
    for d in [
        REPO_ROOT / "tests" / "malformed",
        REPO_ROOT / "tests" / "tolerated",
        REPO_ROOT / "tests" / "fuzz-regressions",
        REPO_ROOT / "crates" / "pgo-io" / "tests" / "fuzz-regressions",
        REPO_ROOT / "tests" / "golden" / "inputs",
    ]:
        files += sorted(p for p in d.rglob("*") if p.is_file() and p.suffix not in (".md", ".tsv"))
    return files


CORPUS = _corpus()


def _call(f, *args, **kwargs):
    """Calls f; a pgo error or OSError is an answer, anything else (PanicException above all,
    a BaseException) fails the test."""
    try:
        return f(*args, **kwargs)
    except (pgo.PgoError, OSError, ValueError):
        return None


@pytest.mark.filterwarnings("ignore::pgo.ReadWarning")
def test_no_panic_reaches_python_on_any_corpus_file():
    assert len(CORPUS) > 70
    read = solved = 0
    for path in CORPUS:
        for flags in ({}, {"allow_indefinite": True, "ignore_equiv": True}):
            g = _call(pgo.read, path, **flags)
            if g is None or g.num_poses > 2000:
                continue
            read += 1
            for weights in ("isotropic", "unit"):
                s = _call(pgo.solve, g, weights=weights)
                if s is not None:
                    solved += 1
                    _call(pgo.certify, g, s)
                _call(pgo.certify, g, weights=weights)
                _call(pgo.certify, g, np.zeros((g.num_poses, 3)), weights=weights)
                if g.num_poses <= 100:
                    _call(pgo.spectrum, g, 3, weights=weights)
            _call(g.to_text)
            _call(g.to_text, format="toro")
            _call(g.to_text, dialect="g2o-cov")
    assert read > 40 and solved > 20


@pytest.mark.parametrize(
    "args",
    [
        ([], [], []),
        (np.zeros((1, 3)), [], []),
        (np.zeros((2, 3)), [[0, 1]], [[0, 0, 0]]),
        (np.zeros((2, 3)), [[0, 1]], [[1e300, -1e300, 1e300]]),
        (np.zeros((2, 3)), [[0, 1], [1, 0]], [[1, 0, 0], [1, 0, 3]]),
        (np.zeros((3, 3)), [[0, 1]], [[1, 0, 0]]),  # pose 2 isolated
        (np.full((2, 3), 1e308), [[0, 1]], [[1, 0, 0]]),
    ],
)
def test_no_panic_on_degenerate_arrays(args):
    g = _call(pgo.Graph, *args)
    if g is None:
        return
    for weights in ("isotropic", "unit"):
        for method in ("auto", "sdp", "staircase"):
            s = _call(pgo.solve, g, weights=weights, method=method, refine=True)
            if s is not None:
                assert s.poses.shape == (g.num_poses, 3)
        _call(pgo.certify, g, weights=weights)
        _call(pgo.spectrum, g, 0, weights=weights)
        _call(pgo.spectrum, g, 2, weights=weights)
    with pytest.raises(pgo.PgoError):
        pgo.certify(g, np.full((g.num_poses, 3), np.inf)) if g.num_poses else pgo.certify(g)
