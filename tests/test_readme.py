"""Every line of the README runs: its shell blocks are executed, its example outputs checked.

* ```` ```bash ```` blocks: each line is run in order in one scratch folder (later lines use earlier
  lines' files), ``baseparams`` as ``python -m baseparams``; the exit status must be 0. The
  set-up block's ``pip install`` steps are what ``.ci/run`` does and are not repeated here.
  Placeholders for the user's own files are real files: ``panda.urdf`` is the shared Panda model,
  ``panda.csv`` / ``other.csv`` its real log split in two (the shared test data; those blocks skip
  without it), ``tcp://head:8786`` a scheduler this test starts.
* Blocks of ``$ command`` lines followed by output (```` ``` ```` and ```` ```console ````): each
  command is run and every output line shown must appear in what it prints (spaces normalised;
  ``...`` matches anything).
* ``>>>`` examples are doctests (``pyproject.toml``: README.md is in ``testpaths``).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from paths import HAVE_SHARED, IDENT, REPO

README = REPO / "README.md"
SRC = str(REPO / "src")
PANDA = IDENT / "panda_gaz2019"


def _blocks() -> list[tuple[str, int, list[str]]]:
    """``(language, first line number, lines)`` of every fenced block."""
    out, lang, start, body = [], None, 0, []
    for k, line in enumerate(README.read_text(encoding="utf-8").splitlines(), 1):
        if line.startswith("```"):
            if lang is None:
                lang, start, body = line[3:].strip() or "text", k, []
            else:
                out.append((lang, start, body))
                lang = None
        elif lang is not None:
            body.append(line)
    return out


SHELL = [(start, lines) for lang, start, lines in _blocks() if lang in ("bash", "sh", "shell")]
SESSIONS = [(start, lines) for lang, start, lines in _blocks()
            if lang in ("text", "console") and lines and lines[0].startswith("$ ")]


def _env() -> dict:
    return {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}


def _argv(command: str, subst: dict[str, str]) -> list[str] | None:
    """A README command as argv (``baseparams`` as this Python's module), or None for install steps."""
    for old, new in subst.items():
        command = command.replace(old, new)
    words = shlex.split(command, comments=True)
    if not words or words[0] == "pip":
        return None
    if words[0] == "baseparams":
        return [sys.executable, "-m", "baseparams", *words[1:]]
    if words[:3] == ["python", "-m", "pytest"]:
        return None  # the test command itself: what is running now
    return [sys.executable if words[0] == "python" else words[0], *words[1:]]


def _commands(lines: list[str]) -> list[str]:
    out = []
    for line in lines:
        out += [part.strip() for part in line.split("&&") if part.strip()]
    return out


def _panda_files(folder: Path) -> None:
    """The user's files the README names: the Panda model and its real log, split in two."""
    import baseparams

    (folder / "panda.urdf").symlink_to(PANDA / "panda_mdh_gaz2019.urdf")
    robot = baseparams.load(str(PANDA / "panda_mdh_gaz2019.urdf"))
    sig = [np.loadtxt(PANDA / f"exciting_traj_{f}.txt").reshape(-1, 7) for f in ("positions", "velocity", "torques")]
    t = np.loadtxt(PANDA / "exciting_traj_time.txt")
    header = ",".join(["t"] + [f"{k}_{j}" for k in ("q", "dq", "tau") for j in robot.joint_names])
    table = np.column_stack([t, *sig])
    split = t < t[-1] - 6.0
    for name, rows in (("panda.csv", table[split]), ("other.csv", table[~split])):
        np.savetxt(folder / name, rows, delimiter=",", header=header, comments="", fmt="%.17g")


def _needs_panda(lines: list[str]) -> bool:
    return any("panda" in line for line in lines)


@pytest.fixture(scope="module")
def scheduler():
    """A local Dask cluster standing in for the README's ``tcp://head:8786``."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    yield cluster.scheduler_address
    cluster.close()


@pytest.mark.slow
@pytest.mark.parametrize("start, lines", [pytest.param(s, ls, id=f"line{s}",
                                                       marks=[pytest.mark.shared] if _needs_panda(ls) else [])
                                          for s, ls in SHELL])
def test_readme_shell_block_runs(start, lines, tmp_path, request):
    subst = {}
    if any("tcp://head:8786" in line for line in lines):
        subst["tcp://head:8786"] = request.getfixturevalue("scheduler")
    if _needs_panda(lines) and HAVE_SHARED:
        _panda_files(tmp_path)
    ran = 0
    for k, command in enumerate(_commands(lines)):
        argv = _argv(command, subst)
        if argv is None:
            continue
        r = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=900, env=_env())
        assert r.returncode == 0, f"README line {start + 1 + k}: {command}\n{r.stderr[-2000:]}"
        ran += 1
    assert ran > 0


def _pattern(expected: str) -> re.Pattern:
    parts = [re.escape(" ".join(p.split())) for p in expected.split("...")]
    return re.compile(".*".join(parts))


@pytest.mark.parametrize("start, lines", [pytest.param(s, ls, id=f"line{s}") for s, ls in SESSIONS])
@pytest.mark.slow
def test_readme_example_outputs_are_what_the_program_prints(start, lines):
    runs, current = [], None
    for line in lines:
        if line.startswith("$ "):
            current = (line[2:], [])
            runs.append(current)
        elif current is not None and line.strip() and line.strip() != "...":
            current[1].append(line)
    for command, expected in runs:
        argv = _argv(command, {})
        r = subprocess.run(argv, capture_output=True, text=True, timeout=600, env=_env())
        assert r.returncode == 0, f"README line {start}: {command}\n{r.stderr[-2000:]}"
        printed = [" ".join(x.split()) for x in r.stdout.splitlines()]
        for want in expected:
            pat = _pattern(want.strip())
            assert any(pat.fullmatch(x) for x in printed), f"README ({command}): not printed: {want.strip()!r}"
