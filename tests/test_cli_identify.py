"""``baseparams simulate`` and ``baseparams identify`` end to end (in-process CLI)."""

import json

import numpy as np
import pytest

from baseparams.cli import main

from paths import SHARED

PANDA_URDF = SHARED.parent / "ident" / "panda_gaz2019" / "panda_mdh_gaz2019.urdf"


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    out = d / "sim.csv"
    assert main(["simulate", "puma560", str(out), "--duration", "30", "--rate", "200", "--noise", "0.05",
                 "--rotor", "--seed", "3"]) == 0
    return out, json.loads((d / "sim.csv.truth.json").read_text())


def test_identify_json_schema_and_truth(simulated, capsys):
    out, truth = simulated
    assert main(["identify", "puma560", str(out), "--rotor", "--holdout", "6", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    for key in ("method", "n_samples", "condition_number", "base_parameters", "drives", "train", "validation",
                "physical", "notes"):
        assert key in j
    assert j["method"] == "auto" and j["physical"] is None
    read = j["n_samples"]["read"]
    assert read in (4799, 4800) and 0 < j["n_samples"]["used"] < read  # 30 s at 200 Hz, the last 6 s held out
    assert sum(j["n_samples"]["removed"].values()) + j["n_samples"]["used"] == read  # every sample counted
    true = {p["name"]: p["value"] for p in truth["parameters"]}
    est = {b["name"]: b for b in j["base_parameters"]}
    assert set(est) <= set(true) and len(est) == 36
    z = [(est[n]["value"] - true[n]) / est[n]["std"] for n in est]
    assert np.sqrt(np.mean(np.square(z))) < 5  # std honest to the filter's small bias
    assert j["drives"][0]["Ia"] == "regrouped into link1.ZZR"
    fv = j["drives"][3]
    assert abs(fv["Fv"] - truth["drives"]["Fv_joint4"]) <= 3 * fv["std"]["Fv"]  # within 3 of its own sigma
    assert fv["Fv"] == pytest.approx(truth["drives"]["Fv_joint4"], rel=0.1)
    assert set(j["validation"]["rms"]) == {f"joint{k}" for k in range(1, 7)}
    # against the raw measured torques at every held-out sample: the noise (std 0.05) plus a small model error
    assert 0.045 < j["validation"]["rms_total"] < 0.055
    assert j["validation"]["samples"] == 1201  # t >= t_end - 6, exactly
    assert j["validation"]["t_start"] == pytest.approx(29.995 - 6)


@pytest.mark.shared
def test_identify_physical_writes_urdf_and_plot(tmp_path, capsys):
    """A URDF model: simulate, identify physically, write the identified URDF and the plot."""
    from baseparams import load

    model = str(PANDA_URDF)
    log = tmp_path / "panda.npz"
    assert main(["simulate", model, str(log), "--duration", "20", "--rate", "100", "--noise", "0.05"]) == 0
    urdf, png = tmp_path / "id.urdf", tmp_path / "t.png"
    assert main(["identify", model, str(log), "--method", "physical", "--urdf", str(urdf), "--plot", str(png),
                 "--json"]) == 0
    j = json.loads(capsys.readouterr().out.split("\n", 1)[1])  # after simulate's line
    assert j["physical"]["feasible"] and all(m > 0 for m in j["physical"]["masses"].values())
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    identified, original = load(str(urdf)), load(model)
    assert identified.n == original.n
    assert not np.allclose(identified.parameters("paper"), original.parameters("paper"))


@pytest.mark.parametrize("argv, words", [
    (["--method", "bogus"], "--method must be one of auto, ols, wls, physical, got 'bogus'"),
    (["--holdout", "99"], "holdout 99"),
    (["--friction", "sticky"], "unknown friction"),
    (["--urdf", "x.urdf"], "--urdf needs --method physical"),
])
def test_identify_bad_options_one_line(simulated, argv, words, capsys):
    out, _ = simulated
    try:
        code = main(["identify", "puma560", str(out), *argv])
    except SystemExit as exc:  # argparse's own usage errors
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and words in err
    assert "Traceback" not in err


def test_identify_missing_joint_names_the_joint(tmp_path, capsys):
    path = tmp_path / "bad.csv"
    t = np.arange(100) / 100
    cols = {"t": t, **{f"q_joint{k}": np.sin(t) for k in range(1, 6)}, **{f"tau_joint{k}": t for k in range(1, 6)}}
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="")
    assert main(["identify", "puma560", str(path)]) == 2
    err = capsys.readouterr().err
    assert "joint6" in err and err.count("\n") == 1


@pytest.mark.slow
def test_fleet_from_the_command_line(tmp_path, capsys):
    """``simulate --robots`` writes a fleet; ``identify 'glob' --per-file --pooled`` runs it on Dask."""
    out = tmp_path / "fleet"
    assert main(["simulate", "puma560", str(out), "--robots", "3", "--duration", "10", "--rate", "200",
                 "--noise", "0.05", "--friction", "viscous"]) == 0
    capsys.readouterr()
    assert main(["identify", "puma560", str(out / "*.npz"), "--per-file", "--pooled", "--workers", "2",
                 "--friction", "viscous", "--method", "ols", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert len(j["per_file"]) == 3 and j["pooled"] is not None and len(j["names"]) == 36 + 6
    truth = json.loads((out / "robot0000.npz.truth.json").read_text())["parameters"]
    est = j["per_file"][str(out / "robot0000.npz")]
    assert np.allclose(est[:2], [t["value"] for t in truth[:2]], rtol=0.02)  # link1.ZZR, link2.XXR
    assert main(["identify", "puma560", str(out / "*.npz"), "--pooled", "--workers", "1", "--friction", "viscous",
                 "--method", "ols"]) == 0
    text = capsys.readouterr().out.splitlines()
    head = next(k for k, line in enumerate(text) if line.startswith("pooled estimate (std: HAC")) + 1
    assert text[head].split() == ["name", "value", "std"]  # the pooled table's column headers
    assert len(text) - head - 1 == 36 + 6 and "nan" not in " ".join(text).lower().split()
    assert main(["identify", "puma560", str(out / "*.npz"), "--holdout", "2"]) == 2


@pytest.mark.shared
def test_analyze_sweep_over_model_files(capsys):
    """``analyze 'GLOB'``: every file on Dask, the same result as one by one."""
    pattern = str(SHARED / "urdfplus" / "*_bar.urdf")
    assert main(["analyze", pattern, "--workers", "2", "--json"]) == 0
    sweep = json.loads(capsys.readouterr().out)
    assert [r["path"].rsplit("/", 1)[1] for r in sweep] == ["four_bar.urdf", "six_bar.urdf"]
    for r in sweep:
        assert main(["analyze", r["path"], "--json"]) == 0
        one = json.loads(capsys.readouterr().out)
        assert (one["nullity"], one["status"], one["base_parameters"]) == (r["nullity"], r["status"],
                                                                           r["base_parameters"])
