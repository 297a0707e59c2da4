"""Identification from motor currents with unknown gains (issue 50): the acceptance's closest simulated analogue.

The acceptance is measured on recordings kept from us: a 7-DoF arm that logs its motor currents and
joint-torque sensors after the gears; trained on one recording from currents alone with one
catalogue gain as the anchor, the predicted joint-side torques of another recording must be at
least as close to its torque sensors as an OLS given all seven catalogue gains (2.41 N m there),
with no gain collapsed and every non-identifiable group named.

Simulated analogue (``tests/recordings.py``, written apart from the estimator): the KUKA iiwa 14 of
``../shared/models`` carrying a 1.5 kg tool the model file lacks, the file's inertial parameters
20 % off; per joint a reflected rotor inertia (0.08-0.4 kg m^2) and friction (viscous 0.5-2 N m
s/rad, Coulomb 0.8-3 N m, offset) before the torque sensor; currents = (rigid body + rotor + friction)
/ true gain + AR(0.9) noise (0.3 N m as torque); the sensor reads the rigid body + 0.2 N m white
noise; catalogue gains 5-10 % off the true ones, either sign. Recording A (30 s) trains, B (15 s,
another motion) is held out. Figures, per seed: the held-out RMS [N m] of the joint-side torques
against B's sensors, every sample and joint, for

* ``ours, one catalogue anchor``: our estimate from A's currents, each joint's catalogue gain as the
  anchor in turn (an anchor error ``e`` scales every prediction by ``1 + e`` exactly, tested: the
  median, best and worst anchor joint; joint 2, the shoulder, as a user would pick it);
* ``ours, every catalogue gain as an anchor``: the same information the OLS baseline has, used for
  the scale only (their geometric mean);
* ``ours, exact anchor``: the estimate without the anchor's error;
* ``OLS, catalogue gains``: the baseline (currents x catalogue gains as torques, OLS with rotor
  inertia and friction, the rigid-body part predicted);
* ``fit on the sensors``: the floor (what the torque sensors themselves give).

Also: the gains' ratios to the true ones (at the exact anchor), their z-scores (coverage), the
naive torque least squares' smallest gain ratio (the issue's collapse), and the real Stäubli TX40
log (``../shared/ident/staubli_tx40_figaroh``): its motor torques ``y`` as the currents, its gear
ratios ``N`` as the unknown gains, one anchored; the recovered ratios against ``N``, and the
held-out currents (last 30 %) against the torque-based fit's.

Run: ``python benchmarks/run.py --only currents`` (about 2 minutes; ``--quick``: 2 seeds).
"""

from __future__ import annotations

import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

#: the catalogue gains of the simulated 7-DoF arm [N m/A at the joint side]
CATALOGUE = np.array([28.0, 28.0, 18.0, 18.0, 10.0, 6.0, 6.0])
#: reflected rotor inertia per joint [kg m^2]
ROTOR = np.array([0.4, 0.4, 0.25, 0.25, 0.12, 0.08, 0.08])
#: the joint a user anchors (the shoulder: the largest gravity load)
SHOULDER = 1


def _shared() -> Path | None:
    for c in [HERE.parents[1] / "shared", *[p / "shared" for p in HERE.parents]]:
        if (c / "models").is_dir():
            return c
    return None


def arm_case(seed: int, shared: Path) -> dict:
    """One simulated plant, its two recordings, the file the user has, the true and catalogue gains."""
    import baseparams

    from recordings import Motors, Plant, motion, perturbed_file, record_currents, with_payload

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the MJCF's mesh assets are not stored: geoms stripped, inertials kept
        iiwa = baseparams.load(str(shared / "models" / "mjcf" / "kuka_iiwa_14" / "iiwa14.xml"))
    rng = np.random.default_rng(seed)
    true = with_payload(iiwa, 1.5, offset=(0.03, 0.02, 0.08))
    file = perturbed_file(iiwa, rng, 0.2)
    m = iiwa.dof
    k_true = CATALOGUE * (1 + rng.uniform(0.05, 0.10, m) * rng.choice([-1, 1], m))
    plant = Plant(true, Fv=rng.uniform(0.5, 2.0, m), Fc=rng.uniform(0.8, 3.0, m), Fo=rng.uniform(-0.3, 0.3, m))
    motors = Motors(k_true, rotor=ROTOR, noise=0.3, ar=0.9, sensor_noise=0.2)
    a = record_currents(plant, motors, *motion(m, 30.0, 500.0, rng, amplitude=1.0, base_frequency=0.1,
                                               harmonics=5), rng, "A")
    b = record_currents(plant, motors, *motion(m, 15.0, 500.0, rng, amplitude=1.0, base_frequency=0.1,
                                               harmonics=5), rng, "B")
    return {"seed": seed, "file": file, "train": a, "test": b, "k_true": k_true, "k_cat": CATALOGUE}


def _rms(pred: np.ndarray, log) -> float:
    return float(np.sqrt(np.mean((pred - log.tau) ** 2)))


def _ols_catalogue(case: dict) -> float:
    """The baseline: currents x catalogue gains as torques, OLS with rotor and friction, the rigid part predicted."""
    from baseparams.ident import identify

    a, file = case["train"], case["file"]
    base = identify(file, replace(a, tau=a.cur * case["k_cat"], cur=None), method="ols", rotor=True, terms="none")
    theta = base.fit.theta.copy()
    nb = len(base.model.analysis.base_names)
    theta[np.asarray(base.model.regrouping.independent) >= nb] = 0.0
    return _rms(replace(base, fit=replace(base.fit, theta=theta)).predict(case["test"]), case["test"])


def _naive_smallest_ratio(case: dict) -> float:
    """The issue's collapse: ``A theta = diag(i) k`` in torques, the shoulder's gain fixed; the smallest k / k_true."""
    from baseparams.ident import IdentOptions
    from baseparams.ident.model import model_for
    from baseparams.ident.preprocess import prepare
    from baseparams.ident.rows import accumulate_prepared, log_columns

    a, k_true = case["train"], case["k_true"]
    model = model_for(case["file"], IdentOptions(rotor=True))
    ilog = replace(a, tau=a.cur, cur=None)
    kept: list = []
    accumulate_prepared(model, prepare(ilog), log_columns(model, a), 128.0, ilog, keep=kept)
    x, cur = kept[0]
    n, m, p = x.shape
    free = [r for r in range(m) if r != SHOULDER]
    big = np.zeros((n, m, p + m - 1))
    big[:, :, :p] = x
    for k, r in enumerate(free):
        big[:, r, p + k] = -cur[:, r]
    rhs = np.zeros((n, m))
    rhs[:, SHOULDER] = k_true[SHOULDER] * cur[:, SHOULDER]
    sol = np.linalg.lstsq(big.reshape(-1, p + m - 1), rhs.reshape(-1), rcond=None)[0]
    return float(np.min(np.abs(sol[p:] / k_true[free])))


def run_arm(case: dict) -> dict:
    """Every figure of one seed (module docstring)."""
    from baseparams.ident import identify

    a, b, file, k_true, k_cat = case["train"], case["test"], case["file"], case["k_true"], case["k_cat"]
    joints = [f"joint{j + 1}" for j in range(len(k_true))]
    t0 = time.perf_counter()
    exact = identify(file, replace(a, tau=None), gain_anchor=f"{joints[SHOULDER]}={k_true[SHOULDER]}")
    seconds = time.perf_counter() - t0
    pred = exact.predict(b)
    g = exact.currents
    live = np.array([m not in g.undetermined for m in g.motors]) & (g.std > 0)
    per_anchor = [_rms(pred * (k_cat[j] / k_true[j]), b) for j in range(len(k_true)) if g.motors[j] not in
                  g.undetermined]
    every = identify(file, replace(a, tau=None), gain_anchor=",".join(f"{j}={k}" for j, k in zip(joints, k_cat)))
    floor = identify(file, replace(a, cur=None))
    return {"seed": case["seed"], "seconds": seconds, "exact": _rms(pred, b),
            "one_shoulder": _rms(pred * (k_cat[SHOULDER] / k_true[SHOULDER]), b),
            "one_median": float(np.median(per_anchor)), "one_best": min(per_anchor), "one_worst": max(per_anchor),
            "every": _rms(every.predict(b), b), "ols_catalogue": _ols_catalogue(case),
            "sensor_fit": _rms(floor.predict(b), b), "ratio_error": float(np.max(np.abs(g.gains[live] / k_true[live]
                                                                                         - 1))),
            "z": ((g.gains[live] - k_true[live]) / g.std[live]).tolist(), "undetermined": list(g.undetermined),
            "groups": [x["kind"] for x in g.groups], "naive_smallest": _naive_smallest_ratio(case)}


def tx40(shared: Path) -> dict | None:
    """The Stäubli TX40: motor torques as currents, gear ratios as the unknown gains (joint 2's anchored)."""
    import json
    import re

    import baseparams
    from baseparams.ident import identify
    from baseparams.ident.drives import MotorCoupling
    from baseparams.jointlog import JointLog

    folder = shared / "ident" / "staubli_tx40_figaroh"
    if not folder.is_dir():
        return None
    robot = baseparams.load(str(folder / "tx40_mdh_modified.urdf"))
    text = (folder / "T40X_config.yaml").read_text()

    def value(key):
        return json.loads(re.search(rf"^\s*-?\s*{key}\s*:\s*(.+)$", text, re.M).group(1).strip())

    ts, n, lim = value("ts"), np.array(value("N"), dtype=float), np.array(value("dq_lim_def"))
    q_motor = np.loadtxt(folder / "pos_read_data.csv", delimiter=",", skiprows=1)
    y = np.loadtxt(folder / "curr_data.csv", delimiter=",", skiprows=1)
    rq, rt = np.diag(n), np.diag(n)
    rq[5, 4], rt[4, 5] = n[5], n[5]  # motor 6 turns joints 5 and 6
    q = np.linalg.solve(rq, q_motor.T).T
    q[:, 1] -= np.pi / 2
    q[:, 2] += np.pi / 2
    t = np.arange(len(q)) * ts
    log = JointLog(t, tuple(robot.joint_names), q, y @ rt.T, source="TX40", cur=y)
    hold = 0.3 * float(t[-1] - t[0])
    common = dict(rotor=True, couplings=(MotorCoupling("joint_6", ("joint_5", "joint_6"), (1.0, 1.0)),), cutoff=15.0,
                  min_speed=lim, terms="none", holdout=hold)
    t0 = time.perf_counter()
    ours = identify(robot, log, effort="current", gain_anchor=f"joint_2={n[1]}", **common)
    seconds = time.perf_counter() - t0
    torque = identify(robot, replace(log, cur=None), method="ols", **common)
    mask = t >= t[-1] - hold
    y_torque = np.linalg.solve(rt, torque.predict(log).T).T  # the torque fit's motor torques
    g = ours.currents
    out = [m in g.undetermined for m in g.motors]  # not determined: no ratio, no std claimed
    return {"seconds": seconds, "ratio": [None if o else float(x) for o, x in zip(out, g.gains / n)],
            "rel_std": [None if o else float(x) for o, x in zip(out, g.std / np.abs(g.gains))],
            "undetermined": list(g.undetermined),
            "current_rms": [ours.validation["rms"][j] for j in robot.joint_names],
            "torque_fit_current_rms": np.sqrt(np.mean((y_torque - y)[mask] ** 2, axis=0)).tolist()}


def run(quick: bool = False) -> dict:
    """Every case: ``{"arm": [per seed], "tx40": {...} or None}`` (``{}`` without ``../shared``)."""
    shared = _shared()
    if shared is None:
        return {}
    seeds = range(2) if quick else range(6)
    return {"arm": [run_arm(arm_case(s, shared)) for s in seeds], "tx40": None if quick else tx40(shared)}


def table(result: dict) -> str:
    """The arm's figures as a Markdown table, one row per seed."""
    head = ("| seed | ours, shoulder anchor | ours, anchor median (best-worst) | ours, every catalogue gain | ours, "
            "exact anchor | OLS, catalogue gains | fit on sensors | max gain-ratio error | naive smallest k/k_true |\n"
            "|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    rows = "".join(f"| {r['seed']} | {r['one_shoulder']:.3f} | {r['one_median']:.3f} ({r['one_best']:.3f}-"
                   f"{r['one_worst']:.3f}) | {r['every']:.3f} | {r['exact']:.3f} | {r['ols_catalogue']:.3f} | "
                   f"{r['sensor_fit']:.3f} | {100 * r['ratio_error']:.1f} % | {r['naive_smallest']:.3f} |\n"
                   for r in result.get("arm", []))
    return head + rows
