"""Identification from motor currents through both doors (issue 50): a streamed run, predict, the saved file, reports.

One simulated arm without joint-torque sensors (``tests/recordings.py``, as in ``test_currents.py``):
its training log holds currents alone, the other motion currents and the joint-torque sensors.
What is checked: a run asked to stream a log of currents reads it whole and says so in one line
(the same result), the refusals of the whole read are the streamed run's too; ``predict`` writes,
prints and scores the joint-side torques and the currents; the saved result predicts as the one
in memory, and a tampered one is refused in one line; the HTML report and the figure show the
currents in amperes and the gains; a fleet refuses currents.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

import baseparams
from baseparams.cli import main
from baseparams.errors import BaseparamsError
from baseparams.ident import Identification
from baseparams.io.logs import write_log
from test_currents import _recordings


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The training log (currents only), the other motion (currents and sensors), its parts; a CLI run saved."""
    d = tmp_path_factory.mktemp("currents")
    puma = baseparams.load("puma560")
    _, a, b, gains = _recordings(10, robot=puma, file_error=0.0, seconds=10.0)
    logs = {"a": replace(a, tau=None), "b": b, "bcur": replace(b, tau=None), "btau": replace(b, cur=None)}
    paths = {k: write_log(d / f"{k}.csv", log) for k, log in logs.items()}
    anchor = f"joint2={float(gains[1])!r}"
    argv = ["identify", "puma560", str(paths["a"]), "--gain-anchor", anchor, "--holdout", "2", "--score-cutoff", "3",
            "--save",
            str(d / "r.json"), "--html", str(d / "r.html"), "--json"]
    return d, paths, anchor, argv, b


def _one_error(argv, capsys) -> str:
    assert main([str(x) for x in argv]) == 2
    err = [e for e in capsys.readouterr().err.splitlines() if e.startswith("baseparams: error: ")]
    assert len(err) == 1, err
    return err[0]


@pytest.fixture(scope="module")
def saved(run):
    """The CLI run (read whole), its JSON and the saved result's path."""
    import contextlib
    import io

    d, _, _, argv, _ = run
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        assert main(argv) == 0
    return json.loads(out.getvalue()), d / "r.json"


@pytest.mark.slow
def test_a_streamed_run_of_currents_is_read_whole_and_says_so(run, saved, capsys):
    d, paths, anchor, argv, _ = run
    assert main([*argv[:-1], "--stream", "on", "--save", str(d / "s.json"), "--json"]) == 0
    captured = capsys.readouterr()
    notes = [e for e in captured.err.splitlines() if "--stream on" in e]
    assert len(notes) == 1 and "motor currents" in notes[0] and "read whole" in notes[0], captured.err
    assert "block by block" not in captured.err  # never said to stream what it read whole
    doc = json.loads(captured.out)
    assert doc["currents"]["gains"] == saved[0]["currents"]["gains"] and doc["validation"] == saved[0]["validation"]


@pytest.mark.parametrize("extra, words", [
    (["--effort", "current"], "{btau}: no motor currents (columns cur_<joint> [A], or cur = ... in a --columns map)"),
    (["--gain-anchor", "joint2=3"], "--gain-anchor applies to motor currents; this log is identified from its joint "
                                    "torques (--effort current to use its currents)"),
])
def test_a_streamed_run_refuses_what_the_whole_read_refuses(run, extra, words, capsys):
    _, paths, *_ = run
    lines = {_one_error(["identify", "puma560", paths["btau"], *extra, "--stream", stream], capsys)
             for stream in ("on", "off")}
    assert lines == {f"baseparams: error: {words.format(btau=paths['btau'])}"}


def test_predict_writes_prints_and_scores_torques_and_currents(run, saved, capsys):
    d, paths, _, _, b = run
    res = Identification.load(saved[1], baseparams.load("puma560"))
    assert main(["predict", "puma560", str(saved[1]), str(paths["bcur"]), "--out", str(d / "o.csv"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["rms"] is None and "joint side" in doc["torque"]  # no sensors in this log: the currents scored
    cur = res.predict_currents(b)
    expect = np.sqrt(np.mean((cur - b.cur) ** 2, axis=0))
    assert [doc["rms_currents"][m] for m in res.currents.motors] == pytest.approx(expect, rel=1e-9)
    assert doc["rms_currents"]["total"] < 0.05
    written = np.loadtxt(d / "o.csv", delimiter=",", skiprows=1)
    header = (d / "o.csv").read_text().splitlines()[0].split(",")
    assert header == ["t", *(f"tau_joint{k}" for k in range(1, 7)), *(f"cur_joint{k}" for k in range(1, 7))]
    np.testing.assert_allclose(written[:, 1:7], res.predict(b), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(written[:, 7:], cur, rtol=1e-12, atol=1e-12)
    assert main(["predict", "puma560", str(saved[1]), str(paths["b"])]) == 0
    text = capsys.readouterr().out.splitlines()
    assert "6 joint-side torques and motor currents at 1600 samples" in text[0]
    assert text[1].startswith("RMS vs the raw measured torques") and "RMS vs the measured currents" in text[2]
    assert text[3].startswith("torques: joint side") and "regrouped rotor inertias included" in text[3]


def test_the_front_door_predicts_the_joint_side_torques_and_the_currents(run, saved):
    from baseparams.workflow.identify import prediction

    _, paths, *_ = run
    res = Identification.load(saved[1], baseparams.load("puma560"))
    tau = baseparams.predict("puma560", str(saved[1]), str(paths["b"]))
    p = prediction("puma560", str(saved[1]), str(paths["b"]))
    np.testing.assert_array_equal(tau, p.tau)
    np.testing.assert_array_equal(p.cur, res.predict_currents(p.log))
    scores = p.scores()
    assert scores["rms"]["total"] > 0 and scores["rms_currents"]["total"] < 0.05
    torques = prediction("puma560", res, str(paths["btau"]))
    assert torques.current_scores()["rms_currents"] is None  # no currents logged: none scored, the torques are
    assert torques.scores()["rms"]["total"] == pytest.approx(scores["rms"]["total"])


def test_the_saved_result_reads_back_and_a_tampered_one_is_refused(run, saved, tmp_path):
    _, _, _, _, b = run
    puma = baseparams.load("puma560")
    back = Identification.load(saved[1], puma)
    assert back.currents is not None and back.to_json()["currents"] == saved[0]["currents"]
    from baseparams.ident.report import format_identification

    text = format_identification(back)
    assert "(anchor)" in text and " A against the measured currents low-passed at 3 Hz (--score-cutoff)" in text
    again = Identification.load(back.save(tmp_path / "again.json"), puma)
    np.testing.assert_array_equal(again.predict_currents(b), back.predict_currents(b))
    doc = json.loads(saved[1].read_text())
    del doc["currents"]["gains"]["joint3"]
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    with pytest.raises(BaseparamsError, match="gains.* must name every motor") as exc:
        Identification.load(tmp_path / "bad.json", puma)
    assert "bad.json" in str(exc.value) and "\n" not in str(exc.value)


def test_the_html_report_shows_currents_in_amperes_and_the_gains(run, saved):
    d, *_ = run
    page = (d / "r.html").read_text()
    assert "Motor gains [N m/A at the joint side]" in page and "<td>anchor</td>" in page
    assert "predicted (blue) currents" in page and "current [A]" in page
    rms = page[page.index("<table id='rms'>"):]
    rms = rms[:rms.index("</table>")]
    assert rms.count("<td>A</td>") == 6 and "N m" not in rms


@pytest.mark.slow
def test_the_figure_of_a_fit_from_currents(run, saved, tmp_path):
    pytest.importorskip("matplotlib")
    from baseparams.report.plots import torque_plot

    res = baseparams.identify("puma560", str(run[1]["a"]), gain_anchor=run[2], holdout=2.0)
    assert res.series["train"]["unit"] == "A" and res.series["validation"]["joints"] == list(res.currents.motors)
    s = res.series["train"]
    assert np.sqrt(np.mean((s["tau"] - s["tau_hat"]) ** 2)) < 0.05  # measured and predicted currents, as compared
    import matplotlib

    with matplotlib.rc_context({"svg.fonttype": "none"}):  # the labels as text
        torque_plot(res, tmp_path / "f.svg")
    svg = (tmp_path / "f.svg").read_text()
    assert svg.count("current [A]") == 6 and "torque [N m]" not in svg and "validation RMS" in svg


def test_a_fleet_refuses_currents():
    from baseparams.workflow.identify import check_fleet

    for kw, name in (({"effort": "current"}, "effort="), ({"gain_anchor": "joint2=3"}, "gain_anchor=")):
        with pytest.raises(BaseparamsError, match=f"{name} applies to one log, not to a fleet"):
            check_fleet(kw)


def test_torques_for_some_joints_of_a_log_of_currents_are_refused(run, tmp_path):
    """Currents for every joint and a torque column for one: refused in one line (was a KeyError deep in the reader)."""
    from baseparams.errors import DataError
    from baseparams.io.logs import LogStream, read_log

    _, paths, *_ = run
    lines = paths["bcur"].read_text().splitlines()
    rows = [f"{line},{'tau_joint1' if k == 0 else '0.5'}" for k, line in enumerate(lines)]
    (tmp_path / "mixed.csv").write_text("\n".join(rows) + "\n")
    puma = baseparams.load("puma560")
    for read in (read_log, LogStream):
        with pytest.raises(DataError, match="tau given for joints joint1 but not for joint2, joint3") as exc:
            read(tmp_path / "mixed.csv", puma)
        assert "\n" not in str(exc.value)


def test_a_sub_chain_keeps_the_currents_of_its_joints(run):
    """``joints=`` on a log of currents alone: the identified joints' currents go along (was: a TypeError on tau)."""
    from baseparams.ident.subchain import subchain

    *_, b = run
    q = b.q.copy()
    q[:, 3:] = 0.1  # the wrist held still
    log = replace(b, tau=None, q=q, dq=np.where(np.arange(6) < 3, b.dq, 0.0))
    small, sub, notes = subchain(baseparams.load("puma560"), log, ["joint1", "joint2", "joint3"], {})
    assert sub.joints == ("joint1", "joint2", "joint3") and sub.tau is None
    np.testing.assert_array_equal(sub.cur, b.cur[:, :3])
    np.testing.assert_array_equal(sub.dq, b.dq[:, :3])
