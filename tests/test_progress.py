"""Progress lines of long runs on stderr (``baseparams.cli.Progress``)."""

import time

import pytest

from baseparams import cli
from baseparams.cli import common, main


@pytest.fixture(scope="module")
def small_log(tmp_path_factory):
    out = tmp_path_factory.mktemp("progress") / "sim.csv"
    assert main(["simulate", "puma560", str(out), "--duration", "10", "--rate", "200", "--seed", "1"]) == 0
    return out


def _progress_lines(err: str) -> list[str]:
    return [ln for ln in err.splitlines() if ln.startswith("baseparams: ") and ln.endswith(" s]")]


def test_identify_shows_its_steps_once_the_run_is_long(small_log, monkeypatch, capsys):
    """A run past the threshold (0 s here) prints each step of the identification on stderr."""
    monkeypatch.setattr(common, "PROGRESS_AFTER_S", 0.0)
    assert main(["identify", "puma560", str(small_log), "--json"]) == 0
    lines = _progress_lines(capsys.readouterr().err)
    steps = ["reading", "analysing", "preprocessing", "accumulating", "fitting", "identified in"]
    for step in steps:
        assert any(ln.startswith(f"baseparams: {step}") for ln in lines), (step, lines)
    order = [next(k for k, ln in enumerate(lines) if ln.startswith(f"baseparams: {s}")) for s in steps]
    assert order == sorted(order)


@pytest.mark.slow
def test_short_runs_stay_quiet_and_verbose_shows_all(small_log, monkeypatch, capsys):
    monkeypatch.setattr(common, "PROGRESS_AFTER_S", 1e6)
    assert main(["identify", "puma560", str(small_log), "--json"]) == 0
    assert _progress_lines(capsys.readouterr().err) == []
    assert main(["identify", "puma560", str(small_log), "--json", "-v"]) == 0
    assert len(_progress_lines(capsys.readouterr().err)) >= 6
    assert main(["analyze", "pkm-2rru-1rrs", "--json", "-v"]) == 0
    lines = _progress_lines(capsys.readouterr().err)
    assert any("certifying" in ln for ln in lines) and any("regrouping" in ln for ln in lines)


def test_a_long_step_shows_before_the_next_line(capsys):
    """The timer prints the current step when the threshold passes, then every later line."""
    with cli.Progress(verbose=False, after=0.05) as progress:
        progress("first step")
        assert _progress_lines(capsys.readouterr().err) == []
        time.sleep(0.3)
        progress("second step")
    progress("after the run")  # closed: nothing more
    lines = _progress_lines(capsys.readouterr().err)
    assert [ln.split(" [")[0] for ln in lines] == ["baseparams: first step ...", "baseparams: second step"]
