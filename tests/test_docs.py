"""Every line of the documentation runs: README.md and every page of docs/.

* ```` ```bash ```` blocks: each line is run in order in one scratch folder (later lines use earlier
  lines' files), ``baseparams`` as ``python -m baseparams``; the exit status must be 0. The
  set-up block's ``pip install`` steps are what ``.ci/run`` does and are not repeated here.
  Placeholders for the user's own files are real files: ``panda.urdf`` is the shared Panda model,
  ``panda.csv`` / ``other.csv`` its real log split in two (the shared test data; those blocks skip
  without it), ``tcp://head:8786`` a scheduler this test starts.
* Blocks of ``$ command`` lines followed by output (```` ``` ```` and ```` ```console ````): each
  command is run and every output line shown must appear in what it prints (spaces normalised;
  ``...`` matches anything).
* ``>>>`` examples are doctests (``pyproject.toml``: README.md and docs/ are in ``testpaths``,
  ``--doctest-glob=*.md``; ``docs/conftest.py`` runs them in a scratch folder).
* The site builds strictly (``sphinx-build -W --keep-going -n``: a warning or a broken reference
  fails), its command-line reference is generated from the parser and its API reference from the
  package; the README stays a front page (the two set-up commands first, under 250 lines).
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
DOCS = REPO / "docs"
#: the README, then every page of the site
PAGES = [README, *sorted(DOCS.rglob("*.md"))]
SRC = str(REPO / "src")
PANDA = IDENT / "panda_gaz2019"


def _blocks(page: Path) -> list[tuple[str, int, list[str]]]:
    """``(language, first line number, lines)`` of every fenced block of a page."""
    out, lang, start, body = [], None, 0, []
    for k, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        if line.startswith("```"):
            if lang is None:
                lang, start, body = line[3:].strip() or "text", k, []
            else:
                out.append((lang, start, body))
                lang = None
        elif lang is not None:
            body.append(line)
    return out


def _where(page: Path, start: int) -> str:
    return f"{page.relative_to(REPO)}:{start}"


SHELL = [(_where(page, start), lines) for page in PAGES for lang, start, lines in _blocks(page)
         if lang in ("bash", "sh", "shell")]
SESSIONS = [(_where(page, start), lines) for page in PAGES for lang, start, lines in _blocks(page)
            if lang in ("text", "console") and lines and lines[0].startswith("$ ")]


def _env() -> dict:
    return {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}


def _argv(command: str, subst: dict[str, str]) -> list[str] | None:
    """A documented command as argv (``baseparams`` as this Python's module), or None for install steps."""
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
@pytest.mark.parametrize("where, lines", [pytest.param(w, ls, id=w, marks=[pytest.mark.shared] * _needs_panda(ls))
                                          for w, ls in SHELL])
def test_shell_block_runs(where, lines, tmp_path, request):
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
        assert r.returncode == 0, f"{where} (command {k + 1}): {command}\n{r.stderr[-2000:]}"
        ran += 1
    assert ran > 0


def _pattern(expected: str) -> re.Pattern:
    parts = [re.escape(" ".join(p.split())) for p in expected.split("...")]
    return re.compile(".*".join(parts))


@pytest.mark.parametrize("where, lines", [pytest.param(w, ls, id=w) for w, ls in SESSIONS])
@pytest.mark.slow
def test_example_outputs_are_what_the_program_prints(where, lines):
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
        assert r.returncode == 0, f"{where}: {command}\n{r.stderr[-2000:]}"
        printed = [" ".join(x.split()) for x in r.stdout.splitlines()]
        for want in expected:
            pat = _pattern(want.strip())
            assert any(pat.fullmatch(x) for x in printed), f"{where} ({command}): not printed: {want.strip()!r}"


# ---------------------------------------------------------------- the README is a front page
def test_readme_is_a_front_page_with_the_two_set_up_commands_first():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) < 250
    lang, start, body = _blocks(README)[0]
    assert (lang, body) == ("bash", ['pip install . && baseparams analyze puma560',
                                     'pip install -e ".[test]" && python -m pytest -q'])
    assert all(not line.strip() or line.startswith("# ") for line in lines[:start - 1]), "only the title before them"


def test_every_page_is_in_the_site_and_every_readme_link_resolves():
    """The README's links into docs/ name pages that exist (the site itself checks its own links)."""
    links = re.findall(r"\]\((docs/[^)#]+)", README.read_text(encoding="utf-8"))
    assert links and all((REPO / link).exists() for link in links), [x for x in links if not (REPO / x).exists()]


def test_ci_installs_with_the_readme_command_and_builds_the_site_in_its_test_run():
    """``.ci/run`` installs with the README's second set-up command as written, and that install holds the
    documentation tools (the ``test`` extra reaches every requirement of the ``docs`` extra), so the run of
    every test it makes (slow ones too, skips as failures) builds the site strictly."""
    import tomllib

    ci = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    install = _blocks(README)[0][2][1].split("&&")[0].strip()
    assert re.search(rf"^{re.escape(install)}$", ci, re.M), f".ci/run does not run the README's {install!r}"
    assert re.search(r'^python -m pytest -q -m "slow or not slow"$', ci, re.M)
    assert re.search(r"^export BASEPARAMS_REQUIRE_ALL=1$", ci, re.M)
    extras = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]["optional-dependencies"]
    extra = re.search(r"\[(\w+)\]", install).group(1)

    def reached(name: str, seen=()) -> set[str]:
        out = set()
        for req in extras[name]:
            inner = re.fullmatch(r"baseparams\[([\w,]+)\]", req)
            if inner:
                for sub in set(inner.group(1).split(",")) - set(seen):
                    out |= {sub} | reached(sub, (*seen, name))
            else:
                out.add(re.split(r"[<>=\[;]", req)[0].strip().lower())
        return out

    got = reached(extra)
    assert {"sphinx", "myst-parser", "numpydoc", "sphinx-argparse", "furo"} <= got, got
    assert reached("docs") - {"docs"} <= got, reached("docs") - got


# ---------------------------------------------------------------- the site builds strictly
@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built as CI builds it: ``sphinx-build -W --keep-going -n`` (warnings are errors), from a copy
    of docs/ (the generated API pages are written beside the sources, never into the clone)."""
    import shutil

    root = tmp_path_factory.mktemp("site")
    shutil.copytree(DOCS, root / "docs", ignore=shutil.ignore_patterns("_build", "generated", "__pycache__"))
    out = root / "html"
    r = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-E", "-q", "-b", "html",
                        str(root / "docs"), str(out)], capture_output=True, text=True, timeout=1800, env=_env())
    assert r.returncode == 0, f"sphinx-build -W -n failed:\n{r.stderr[-6000:]}"
    return out


@pytest.mark.slow
@pytest.mark.docs
def test_the_cli_reference_is_the_parser(site):
    """Every command and every flag of ``baseparams.cli.build_parser`` is on the CLI page."""
    import argparse
    import html

    from baseparams.cli import build_parser

    page = html.unescape(re.sub(r"<[^>]+>", "", (site / "reference" / "cli.html").read_text(encoding="utf-8")))
    parser = build_parser()
    commands = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)][0].choices
    assert {"analyze", "identify", "excite", "simulate", "predict"} <= set(commands)
    for name, sub in commands.items():
        assert f"baseparams {name}" in page, name
        for action in sub._actions:
            if action.help == argparse.SUPPRESS:  # hidden on purpose (--help does not show them either)
                continue
            for flag in action.option_strings:
                assert flag in page, f"{name} {flag}"


@pytest.mark.slow
@pytest.mark.docs
def test_the_api_reference_is_the_package(site):
    """The front door's names, each documented subpackage's face and every module behind them have pages."""
    import html
    import importlib
    import inspect
    import pkgutil

    import baseparams

    api = site / "reference" / "api" / "generated"
    door = (api / "baseparams.html").read_text(encoding="utf-8")
    for name in baseparams.__all__:
        if not name.startswith("_"):
            assert f'id="baseparams.{name}"' in door, name
    faces = [n for n in dir(baseparams) if not n.startswith("_") and n not in baseparams.__all__
             and isinstance(getattr(baseparams, n), type(baseparams))]
    assert {"ident", "io", "excitation", "symbolic"} <= set(faces)
    for face in faces:
        assert (api / f"baseparams.{face}.html").exists(), face
    ident = html.unescape(re.sub(r"<[^>]+>", "", (api / "baseparams.ident.html").read_text(encoding="utf-8")))
    for name in importlib.import_module("baseparams.ident").__all__:
        assert f"baseparams.ident.{name}" in ident, name
    exported = {id(getattr(m, n)) for m in [baseparams, *(getattr(baseparams, f) for f in faces)]
                for n in getattr(m, "__all__", ())}
    for module in pkgutil.walk_packages(baseparams.__path__, "baseparams."):
        if module.name != "baseparams.__main__":
            name = module.name
            assert (api / f"{name}.html").exists() or (api / "internals" / f"{name}.html").exists(), name
            page = (api / f"{name}.html") if (api / f"{name}.html").exists() else (api / "internals" / f"{name}.html")
            text = page.read_text(encoding="utf-8")
            # what a module defines has its anchor on the module's page (a class a face exports: on the face's),
            # a module whose name its package gives to a function too (baseparams.workflow.identify)
            for attr, obj in vars(importlib.import_module(name)).items():
                if (not attr.startswith("_") and (inspect.isclass(obj) or inspect.isfunction(obj))
                        and obj.__module__ == name and id(obj) not in exported):
                    assert f'id="{name}.{attr}"' in text, f"{name}.{attr}: no entry on {page.name}"


@pytest.mark.slow
@pytest.mark.docs
def test_the_existing_notes_and_pictures_are_in_the_site(site):
    for name in ("extended-rules.html", "paper-corrections.html", "explanation/conventions.html"):
        assert (site / name).exists(), name
    pictures = {p.name for p in (site / "_images").iterdir()}
    assert {p.name for p in DOCS.glob("*.png")} <= pictures
