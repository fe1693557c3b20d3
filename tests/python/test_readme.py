"""The Python blocks of the README's section "Python", run in order in one namespace from a
directory holding the bundled data sets (as from the repository root), with matplotlib's Agg
backend and $DATA the public data sets; each `<pgo....>` line they print must be the one the README shows in the comment after
it (a comment of `# <...` continued by `#  ...` lines)."""

import contextlib
import io
import os
import re

import pytest

from conftest import REPO_ROOT


def python_blocks():
    text = (REPO_ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def shown_reprs(code):
    """The reprs the README shows: each `# <` comment line joined with its `#  ` continuations."""
    shown = []
    for line in code.splitlines():
        if line.startswith("# <"):
            shown.append(line[2:])
        elif line.startswith("#  ") and shown:
            shown[-1] += " " + line[3:]
    return shown


def test_readme_python_blocks_run_and_print_what_they_show(tmp_path, monkeypatch, shared_datasets):
    pytest.importorskip("matplotlib")
    pytest.importorskip("gtsam")
    blocks = python_blocks()
    assert len(blocks) >= 2
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("DATA", str(shared_datasets))
    (tmp_path / "datasets").symlink_to(REPO_ROOT / "datasets")
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for code in blocks:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(code, "README.md", "exec"), namespace)
        printed = [line for line in out.getvalue().splitlines() if line.startswith("<pgo.")]
        assert printed == shown_reprs(code)
    assert (tmp_path / "MIT.png").stat().st_size > 10_000
    assert (tmp_path / "MIT-opt.g2o").is_file()
    assert (tmp_path / "smallGrid3D-opt.g2o").is_file()
