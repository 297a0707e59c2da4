"""``rotor="auto"`` (identify's default): each joint's rotor inertia kept by the data, never by the held-out part.

A log simulated with rotor inertia (the model's armature, else drawn) keeps the rotor inertia columns, one
without does not; either way the result says what was tried, kept or rejected and why (the model terms'
rule: blocked cross-validation on the training span), and ``rotor=True`` / ``False`` force it. A result
that kept it is saved, read back and predicts the same.
"""

import numpy as np
import pytest

import baseparams as bp
from baseparams.cli import main
from baseparams.cli.parser import flag_message

PUMA = bp.load("puma560")


def _choice(res) -> dict:
    return next(c for c in res.terms_json() if c["name"] == "rotor")


@pytest.mark.parametrize("seed", [1, 2])
def test_rotor_inertia_is_kept_when_the_log_has_it_and_not_otherwise(seed):
    for rotor in (True, False):
        log, truth = bp.simulate(PUMA, duration=20, rate=200, noise=0.02, seed=seed, rotor=rotor)
        res = bp.identify(PUMA, log)
        c = _choice(res)
        assert c["kept"] is rotor, (rotor, c)
        assert "cross-validated RMS" in c["why"] and np.isfinite(c["cv_rms"])
        assert res.options.rotor is rotor  # the options as used
        has = any(n.startswith("Ia") for n in res.fit.model.names)
        assert has is rotor
        assert any(n.startswith("rotor inertia (rotor=auto") and ("KEPT" if rotor else "rejected") in n
                   for n in res.notes)
        if rotor:  # the kept core predicts the truth's torques better than the one without it
            off = bp.identify(PUMA, log, rotor=False)
            assert res.train["rms_total"] < off.train["rms_total"]


def test_forced_either_way_no_choice_is_made():
    log, _ = bp.simulate(PUMA, duration=10, rate=200, noise=0.02, seed=3, rotor=True)
    on = bp.identify(PUMA, log, rotor=True, terms="none")
    off = bp.identify(PUMA, log, rotor=False, terms="none")
    assert any(n.startswith("Ia") for n in on.fit.model.names)
    assert not any(n.startswith("Ia") for n in off.fit.model.names)
    assert not any(c["name"] == "rotor" for r in (on, off) for c in r.terms_json())


def test_a_kept_rotor_is_saved_read_back_and_predicts_alike(tmp_path, capsys):
    log, _ = bp.simulate(PUMA, duration=20, rate=200, noise=0.02, seed=4, rotor=True, out=tmp_path / "log.csv")
    res = bp.identify(PUMA, log)
    assert _choice(res)["kept"]
    res.save(tmp_path / "r.json")
    back = bp.Identification.load(tmp_path / "r.json", PUMA)
    assert back.fit.model.names == res.fit.model.names
    np.testing.assert_allclose(back.predict(log), res.predict(log), rtol=1e-9, atol=1e-9)
    # the command line: the report lists it kept with its values; --no-rotor leaves it out, without a choice
    assert main(["identify", "puma560", str(tmp_path / "log.csv"), "--terms", "none"]) == 0
    text = capsys.readouterr().out
    assert any("rotor" in line and "KEPT" in line and "Ia_" in line for line in text.splitlines()), text
    assert main(["identify", "puma560", str(tmp_path / "log.csv"), "--no-rotor", "--terms", "none", "--json"]) == 0
    out = capsys.readouterr().out
    assert '"Ia_' not in out and '"name": "rotor"' not in out


@pytest.mark.slow
def test_rotor_is_tried_given_the_terms_and_not_kept_for_a_sensor_effect():
    """No rotor inertia in the plant, a 5 % torque-sensor scale and a 2 ms delay: the rotor columns could stand in
    for them on the linear core alone; tried after the terms, with those kept, they are not kept."""
    from recordings import Plant, friction_of, motion, record

    rng = np.random.default_rng(7)
    plant = Plant(PUMA, **friction_of(PUMA, rng), noise=0.05, ar=0.8, delay=np.r_[0, 0.002, 0, 0, 0, 0],
                  scale=np.r_[1, 1, 1.05, 1, 1, 1])
    log = record(plant, *motion(PUMA.dof, 20.0, 500.0, rng), rng, "A")
    res = bp.identify(PUMA, log)
    c = _choice(res)
    assert not c["kept"] and "cross-validated RMS" in c["why"], c
    assert not any(n.startswith("Ia") for n in res.fit.model.names)
    assert {t.name for t in res.fit.terms} >= {"scale"}


@pytest.mark.slow
@pytest.mark.parametrize("run", ["recordings", "stream"])
def test_a_run_that_does_not_try_rotor_inertia_says_so_and_rotor_forces_it(run, tmp_path, capsys):
    """Several recordings and a log streamed from its file do not try ``rotor="auto"``: one note in the text and the
    JSON says which run, that the model has none and which flag fits it; ``--rotor`` fits it (the planted rotor
    inertia then lowers the training RMS) and ``--no-rotor`` leaves it out, neither with the note."""
    import json

    paths = [tmp_path / f"r{k}.csv" for k in (1, 2)]
    for k, p in enumerate(paths):
        bp.simulate(PUMA, duration=4, rate=200, noise=0.02, seed=k + 1, rotor=True, out=p)
    logs = [str(p) for p in paths] if run == "recordings" else [str(paths[0]), "--stream", "on"]
    argv = ["identify", "puma560", *logs, "--terms", "none"]
    why = {"recordings": "not tried for several recordings in one identification",
           "stream": "not tried for a log streamed from its file"}[run]

    def notes(lines, auto="rotor=auto"):
        return [n for n in lines if f"rotor inertia ({auto})" in n]

    assert main(argv) == 0
    said = notes(capsys.readouterr().out.splitlines(), "neither --rotor nor --no-rotor")  # the text: the flags
    assert len(said) == 1 and said[0].startswith(f"note: rotor inertia (neither --rotor nor --no-rotor): {why}"), said
    assert "so the model has none; --rotor fits it" in said[0]
    runs = {}
    for flag in ("", "--rotor", "--no-rotor"):
        assert main([*argv, *([flag] if flag else []), "--json"]) == 0
        runs[flag] = json.loads(capsys.readouterr().out)
    assert [n.removeprefix("note: ") for n in said] == [flag_message(n, "identify") for n in notes(runs[""]["notes"])]
    assert not notes(runs["--rotor"]["notes"]) and not notes(runs["--no-rotor"]["notes"])
    assert all(d["Ia"] is None for r in ("", "--no-rotor") for d in runs[r]["drives"])
    assert sum(isinstance(d["Ia"], float) for d in runs["--rotor"]["drives"]) == 4  # joints 1-2 regroup
    assert runs["--rotor"]["train"]["rms_total"] < runs[""]["train"]["rms_total"]
