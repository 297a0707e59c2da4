"""Several recordings of one robot in one identification (issue 48): one system of rows, each recording a block."""

from __future__ import annotations

import json

import numpy as np
import pytest

import baseparams
from baseparams.errors import BaseparamsError
from baseparams.ident import IdentOptions, accumulate_prepared, identify, log_columns
from baseparams.ident.model import model_for
from baseparams.ident.preprocess import prepare
from baseparams.ident.simulate import simulate_log
from baseparams.robots import random_robot


def _logs(robot, seeds, seconds=6.0, rate=200.0):
    return [simulate_log(robot, duration=seconds, rate=rate, noise=0.05, seed=s)[0] for s in seeds]


@pytest.mark.parametrize("seed", [0, 1])
def test_several_recordings_are_one_least_squares_system(seed):
    """Plain OLS of two recordings = the least-squares solution of both recordings' rows stacked (computed apart)."""
    robot = random_robot(np.random.default_rng(seed), 3, "R", False, branching=0.0)
    a, b = _logs(robot, [10 + seed, 20 + seed])
    opts = IdentOptions(method="ols", terms="none", cutoff=8.0)
    res = identify(robot, [a, b], opts)
    model = model_for(robot, opts)
    rows, taus = [], []
    for x in (a, b):
        prep = prepare(x, cutoff=8.0)
        cols = log_columns(model, x)
        kept: list = []
        accumulate_prepared(model, prep, cols, 128.0, x, keep=kept)
        rows.append(np.concatenate([k[0] for k in kept]))
        taus.append(np.concatenate([k[1] for k in kept]))
    w = np.concatenate(rows).reshape(-1, model.n_params)
    theta = np.linalg.lstsq(w, np.concatenate(taus).reshape(-1), rcond=None)[0]
    np.testing.assert_allclose(res.fit.theta, theta, rtol=1e-6, atol=1e-8 * np.abs(theta).max())
    assert res.samples["read"] == a.n_samples + b.n_samples
    assert res.train["samples"] == a.n_samples + b.n_samples and len(res.train["recordings"]) == 2


def test_the_default_cross_validates_with_each_recording_one_block():
    robot = baseparams.load("puma560")
    a, b, c = _logs(robot, [1, 2, 3], seconds=5.0)
    res = identify(robot, [a, b, c])
    sel = res.to_json()["selection"]
    assert sel["rule"] == "recordings" and sel["folds"] == 3
    assert any("each recording one fold" in n for n in res.notes)
    assert any(n.startswith("several recordings: 3") for n in res.notes)
    # one recording alone: its blocks are pieces of one motion (5 s, too short: the structure rule)
    one = identify(robot, a).to_json()["selection"]
    assert one["rule"] == "structure" and one["estimator"] in ("physical", "least squares")


def test_several_recordings_refuse_a_holdout_and_an_empty_list():
    robot = baseparams.load("puma560")
    a, b = _logs(robot, [1, 2], seconds=3.0)
    with pytest.raises(BaseparamsError, match="holdout with several recordings"):
        identify(robot, [a, b], holdout=1.0)
    with pytest.raises(BaseparamsError, match="no log given"):
        identify(robot, [])


# ---------------------------------------------------------------- the front door: identify MODEL A B ..., predict
def test_identify_several_files_from_the_command_line_and_the_front_door(tmp_path, capsys):
    """``identify MODEL A.csv B.csv`` (or a glob) and ``baseparams.identify(robot, [a, b])``: several recordings in
    one identification, in memory (no fleet); ``predict --score-cutoff`` prints the low-passed figure in text."""
    from baseparams.cli import main

    paths = []
    for k in (1, 2):
        p = tmp_path / f"rec{k}.csv"
        assert main(["simulate", "puma560", str(p), "--duration", "5", "--rate", "200", "--noise", "0.05",
                     "--seed", str(k)]) == 0
        paths.append(p)
    capsys.readouterr()
    save = tmp_path / "res.json"
    assert main(["identify", "puma560", *map(str, paths), "--json", "--save", str(save)]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["selection"]["rule"] == "recordings" and j["n_samples"]["read"] == 2000
    assert main(["identify", "puma560", str(tmp_path / "rec*.csv"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["selection"]["folds"] == 2
    res = baseparams.identify("puma560", [str(p) for p in paths])
    assert res.to_json()["selection"]["rule"] == "recordings"
    assert main(["predict", "puma560", str(save), str(paths[0]), "--score-cutoff", "5"]) == 0
    text = capsys.readouterr().out
    assert "low-passed at 5 Hz (--score-cutoff) at every sample:" in text
    value = float(text.split("(--score-cutoff) at every sample: ")[1].split()[0])
    assert main(["predict", "puma560", str(save), str(paths[0]), "--score-cutoff", "5", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["rms_lowpassed"]["total"] == pytest.approx(value, rel=1e-3)


def test_several_recordings_refused_alike_by_both_doors(tmp_path, capsys):
    """holdout= / --holdout and stream=on / --stream on with several recordings: one rule (the workflow's), the same
    line from ``baseparams.identify`` and ``baseparams identify``, before the model loads; one file in a list is
    one log."""
    from baseparams.cli import main
    from baseparams.cli.parser import flag_message

    paths = []
    for k in (1, 2):
        p = tmp_path / f"r{k}.csv"
        baseparams.simulate("puma560", duration=3.0, rate=100.0, seed=k, out=p)
        paths.append(str(p))
    for kw, flags in (({"holdout": 1.0}, ["--holdout", "1"]), ({"stream": "on"}, ["--stream", "on"])):
        with pytest.raises(BaseparamsError, match="with several recordings") as exc:
            baseparams.identify("no-such-model.urdf", paths, **kw)
        capsys.readouterr()
        assert main(["identify", "no-such-model.urdf", *paths, *flags]) == 2
        err = capsys.readouterr().err.strip()
        assert err == f"baseparams: error: {flag_message(str(exc.value), 'identify')}", err
    with pytest.raises(BaseparamsError, match="no log given"):
        baseparams.identify("puma560", [])
    one = baseparams.identify("puma560", paths[:1], method="ols", terms="none")
    assert "recordings" not in one.train and one.samples["read"] == 300


@pytest.mark.slow
def test_the_report_names_the_folds_as_they_were():
    """Several recordings: the report's heading, the terms' and the default's notes name each recording one fold, and
    nothing says "blocked cross-validation" (a selection of another method, without the default's rule, too); one
    log long enough for the terms still says blocked cross-validation (its contiguous blocks)."""
    from baseparams.ident.report import format_identification

    robot = baseparams.load("puma560")
    a, b = _logs(robot, [4, 5], seconds=5.0)
    for method in ("auto", "ols"):  # ols: no default's selection, the terms' folds still the recordings
        two = identify(robot, [a, b], method=method)
        text, j = format_identification(two), two.to_json()
        assert "model terms (cross-validation with each recording one fold):" in text, (method, text)
        assert "blocked" not in text and not any("blocked" in n for n in j["notes"]), method
        assert any(n.startswith("model terms (cross-validation with each recording one fold") for n in j["notes"])
        assert (j["selection"] or {}).get("rule", "recordings") == "recordings"
        if method == "auto":
            assert "chosen by 2-fold cross-validation with each recording one fold" in text
    one = identify(robot, _logs(robot, [6], seconds=14.0)[0], rotor=False)
    text = format_identification(one)
    assert one.to_json()["selection"]["rule"] == "blocks" and one.fit.term_choices
    assert "model terms (blocked cross-validation on the training data):" in text and "each recording" not in text
