"""Fixtures for the interoperability tests (pgo-convert vs GTSAM and g2o) and the rerun
recording tests (every tool's --rerun-save, read back with rerun-sdk).

Environment:
  PGO_BIN_DIR       directory holding the `pgo-*` binaries
                    (default: <repo>/target/release; relative paths are taken from the repo root)
  PGO_DATASETS_DIR  directory holding the public data sets
                    (default: ../shared/datasets relative to the repo root)
"""

import os
import subprocess
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_DATASETS_DIR = REPO_ROOT.parent / "shared" / "datasets"


def _bin_dir() -> Path:
    d = Path(os.environ.get("PGO_BIN_DIR", "target/release"))
    return d if d.is_absolute() else REPO_ROOT / d


def pgo_binary(name: str) -> Path:
    """Path of the binary `name` under test. A missing binary is a failure, not a skip: the
    suite must never pass vacuously."""
    exe = _bin_dir() / name
    if not (exe.is_file() and os.access(exe, os.X_OK)):
        pytest.fail(
            f"{name} not found at {exe}. Build it first with "
            f"`cargo build --release` in {REPO_ROOT} (or point PGO_BIN_DIR at it).",
            pytrace=False,
        )
    return exe


@pytest.fixture(scope="session")
def pgo_convert() -> Path:
    return pgo_binary("pgo-convert")


@pytest.fixture(scope="session")
def datasets_dir() -> Path:
    d = Path(os.environ.get("PGO_DATASETS_DIR", DEFAULT_DATASETS_DIR))
    if not d.is_dir():
        pytest.fail(f"data set directory {d} not found (set PGO_DATASETS_DIR)", pytrace=False)
    return d


@pytest.fixture(scope="session")
def run_pgo(pgo_convert):
    """run_pgo(args, stdin=None, check=True) -> CompletedProcess (text mode).

    With check=True a non-zero exit status fails the test and shows pgo's stderr."""

    def run(args, stdin=None, check=True):
        cmd = [str(pgo_convert), *map(str, args)]
        proc = subprocess.run(cmd, input=stdin, capture_output=True, text=True, timeout=300)
        if check and proc.returncode != 0:
            pytest.fail(
                f"{' '.join(cmd)} exited with status {proc.returncode}\n"
                f"--- stderr ---\n{proc.stderr}",
                pytrace=False,
            )
        return proc

    return run
