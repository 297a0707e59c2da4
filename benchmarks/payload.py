"""Payload identification (issue 49): the acceptance scenario, simulated by MuJoCo.

A 7-DoF arm (the Franka Panda of ``../shared/ident/panda_gaz2019``, read by MuJoCo's URDF import) with
armature, viscous damping and Coulomb friction loss on its joints; a 3.2 kg payload on its last link,
off-axis and rotated (a box of random sides, its centre up to 10 cm off the flange axis, its axes
rotated at random, per seed); a computed-torque servo on the nominal arm (it does not know the payload)
tracks a Fourier motion of every joint (full arm) or of the wrist's three (wrist only) for 10 s at
1 kHz; the torques carry AR(1) noise (coefficient 0.9) of 1.5 % of each joint's RMS torque
(``tests/mujoco_payload.py``: MuJoCo's forward dynamics, nothing of baseparams).

The robot is known four ways: its URDF (no armature: the rotor inertia is fitted with the payload),
an MJCF of the arm with its armature, and the project's own identification of a 30 s payload-free
full-arm log (``identify`` with its defaults, and with ``--rotor``). Figures per way and motion: the
mass error [%], the centre-of-mass error [mm] and the inertia error (Frobenius, relative [%]), worst
and median over the seeds; the share of the truth within 2 sigma (mass, centre of mass and the six
inertia entries: calibration); the payload identification's wall time (median).

Run: ``python benchmarks/run.py --only payload`` (about 2 minutes on 2 cores; ``--quick``: 2 seeds).
"""

from __future__ import annotations

import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

ARMATURE = np.array([0.3, 0.3, 0.2, 0.2, 0.1, 0.1, 0.05])
DAMPING = np.array([0.5, 0.5, 0.4, 0.4, 0.2, 0.2, 0.1])
FRICTION = np.array([1.0, 1.0, 0.8, 0.8, 0.4, 0.4, 0.3])
CENTRE = np.array([0, 0.3, 0, -1.8, 0, 1.9, 0.0])
MOTIONS = {"full-arm": None, "wrist-only": np.array([0, 0, 0, 0, 1, 1, 1], dtype=bool)}
WAYS = ("urdf", "mjcf", "result", "result-rotor")


def _urdf() -> Path | None:
    for c in [HERE.parents[1] / "shared", *[p / "shared" for p in HERE.parents]]:
        f = c / "ident" / "panda_gaz2019" / "panda_mdh_gaz2019.urdf"
        if f.is_file():
            return f
    return None


def _log(model, nominal, seed: int, move, seconds: float):
    from baseparams.jointlog import JointLog
    from mujoco_payload import fourier, simulate

    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * 1000)) * 1e-3
    qd, dqd, ddqd = fourier(t, 7, rng, amplitude=0.8 if move is None else 1.2, move=move, centre=CENTRE)
    t, q, dq, tau = simulate(model, nominal, qd, dqd, ddqd, rng, noise=0.015, ar=0.9)
    return JointLog(t, tuple(f"panda_joint{k}" for k in range(1, 8)), q, tau, dq=dq, source=f"mujoco seed {seed}")


def _scores(p, pl) -> dict:
    """Errors and the z-scores of mass, centre of mass and the six inertia entries."""
    ic_true = pl.inertia_com()
    ic = np.array(p.inertia_com, dtype=float)
    s = p.sigma()
    dc = np.array(p.com) - np.array(pl.com)
    z = [(p.mass - pl.mass) / s["mass"], *(dc / np.array(s["com"]))]
    z += list(((ic - ic_true) / np.array(s["inertia_com"], dtype=float))[np.triu_indices(3)])
    return {"mass_pct": 100 * abs(p.mass - pl.mass) / pl.mass, "com_mm": 1000 * float(np.linalg.norm(dc)),
            "inertia_pct": 100 * float(np.linalg.norm(ic - ic_true) / np.linalg.norm(ic_true)),
            "z": np.abs(np.array(z))}


def _known(ways: dict, seeds: int, path: Path, tmp: Path) -> None:
    """The robot's four ways: its URDF, an MJCF with its armature, the project's identifications of a free log."""
    import baseparams as bp
    from mujoco_payload import arm, arm_spec

    xml = tmp / "panda_armature.xml"
    xml.write_text(arm_spec(path, ARMATURE, DAMPING, FRICTION).to_xml())
    ways["urdf"] = {"robot": bp.load(str(path)), "result": None}
    ways["mjcf"] = {"robot": bp.load(str(xml)), "result": None}
    robot = ways["urdf"]["robot"]
    free = _log(arm(path, ARMATURE, DAMPING, FRICTION), arm(path, ARMATURE, DAMPING, 0.0), 1000, None, 30.0)
    for key, kw in (("result", {}), ("result-rotor", {"rotor": True})):
        t0 = time.perf_counter()
        res = bp.identify(robot, free, **kw)
        ways[key] = {"robot": robot, "result": res, "identify_s": time.perf_counter() - t0}


def run(quick: bool = False, say=print) -> dict:
    """The figures (module docstring), or ``{}`` without the shared Panda file."""
    from baseparams.ident.payload import identify_payload
    from mujoco_payload import arm, random_payload

    path = _urdf()
    if path is None:
        say("  payload: no ../shared/ident/panda_gaz2019 (skipped)")
        return {}
    seeds = 2 if quick else 5
    out: dict = {"payload_seeds": seeds}
    with tempfile.TemporaryDirectory() as tmp:
        ways: dict = {}
        _known(ways, seeds, path, Path(tmp))
    for key in ("result", "result-rotor"):
        out[f"payload_identify_free_{key.replace('-', '_')}_s"] = ways[key]["identify_s"]
    nominal = arm(path, ARMATURE, DAMPING, 0.0)
    for motion, move in MOTIONS.items():
        rows = {w: [] for w in WAYS}
        for seed in range(seeds):
            rng = np.random.default_rng(10 + seed)
            pl = replace(random_payload("panda_link7", rng, mass=3.2), com=tuple(_com(rng)))
            log = _log(arm(path, ARMATURE, DAMPING, FRICTION, pl), nominal, seed, move, 10.0)
            for w in WAYS:
                t0 = time.perf_counter()
                p = identify_payload(ways[w]["robot"], log, "panda_link7", result=ways[w]["result"])
                r = _scores(p, pl)
                r["s"] = time.perf_counter() - t0
                rows[w].append(r)
        for w in WAYS:
            key = f"payload_{motion}_{w}".replace("-", "_")
            _figures(out, key, rows[w])
            say(f"  payload {motion:<10s} {w:<13s} mass {out[key + '_mass_pct_max']:.3g} %, com "
                f"{out[key + '_com_mm_max']:.3g} mm, inertia {out[key + '_inertia_pct_max']:.3g} % (worst of {seeds}); "
                f"{100 * out[key + '_within_2_sigma']:.0f} % within 2 sigma")
    return out


def _com(rng) -> np.ndarray:
    """An off-axis centre of mass in the flange's region: up to 10 cm across the axis, 5-15 cm along it."""
    return np.r_[rng.uniform(-0.1, 0.1, 2), rng.uniform(0.05, 0.15)]


def _figures(out: dict, key: str, rows: list[dict]) -> None:
    for f in ("mass_pct", "com_mm", "inertia_pct"):
        v = [r[f] for r in rows]
        out[f"{key}_{f}_max"], out[f"{key}_{f}_median"] = float(np.max(v)), float(np.median(v))
    z = np.concatenate([r["z"] for r in rows])
    out[f"{key}_within_2_sigma"] = float(np.mean(z < 2))
    out[f"{key}_s"] = float(np.median([r["s"] for r in rows]))
