"""Fixtures of the Python package's tests (tests/python): the package `pgo` (installed into the
virtualenv by scripts/test with `pip install ./python`), the tools it is checked against, and the
data sets.

Environment:
  PGO_BIN_DIR       directory holding the `pgo-*` binaries (default: <repo>/target/release)
  PGO_DATASETS_DIR  the public data sets (default: ../shared/datasets beside the repository)
"""

import json
import os
import subprocess
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
DATASETS = REPO_ROOT / "datasets"
MALFORMED = REPO_ROOT / "tests" / "malformed"


def _bin_dir() -> Path:
    d = Path(os.environ.get("PGO_BIN_DIR", "target/release"))
    return d if d.is_absolute() else REPO_ROOT / d


def tool(name: str) -> Path:
    """The binary `name`; missing is a failure, never a skip (the suite must not pass vacuously)."""
    exe = _bin_dir() / name
    if not (exe.is_file() and os.access(exe, os.X_OK)):
        pytest.fail(f"{name} not found at {exe} (set PGO_BIN_DIR)", pytrace=False)
    return exe


def run(name, *args, ok=(0,)):
    """Runs a tool; returns the CompletedProcess (text), failing on an exit status not in ok."""
    proc = subprocess.run(
        [str(tool(name)), *map(str, args)], capture_output=True, text=True, timeout=600
    )
    if proc.returncode not in ok:
        pytest.fail(f"{name} {' '.join(map(str, args))}: exit {proc.returncode}\n{proc.stderr}")
    return proc


def run_json(name, *args, ok=(0,)):
    """A tool's --json report, parsed."""
    return json.loads(run(name, *args, "--json", ok=ok).stdout)


@pytest.fixture(scope="session")
def shared_datasets() -> Path:
    d = Path(os.environ.get("PGO_DATASETS_DIR", REPO_ROOT.parent / "shared" / "datasets"))
    if not d.is_dir():
        pytest.fail(f"data set directory {d} not found (set PGO_DATASETS_DIR)", pytrace=False)
    return d
