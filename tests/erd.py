"""The URDFs shipped by the example-robot-data package, and Pinocchio's rank deficiency on them."""

from __future__ import annotations

import sysconfig
from pathlib import Path

import numpy as np

ROOT = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"

#: fixed-base robots (arms, hands, pendulums); every other file gets a free-flyer root
FIXED_DIRS = {"ur_description", "panda_description", "kinova_description", "xarm_description", "z1_description",
              "so_arm_description", "double_pendulum_description", "finger_edu_description",
              "asr_twodof_description", "allegro_hand_description", "baxter_description"}
FIXED_FILES = {"talos_left_arm.urdf"}


def urdf_files() -> list[Path]:
    return sorted(ROOT.rglob("*.urdf")) if ROOT.is_dir() else []


def is_floating(path: Path) -> bool:
    return not (path.name in FIXED_FILES or any(part in FIXED_DIRS for part in path.parts))


def pinocchio_model(path: Path, floating: bool):
    import pinocchio as pin

    try:
        if floating:
            return pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
        return pin.buildModelFromUrdf(str(path))
    except Exception:  # noqa: BLE001 - a file Pinocchio cannot load is not in the comparison
        return None


def pinocchio_nullity(model, path: Path, samples: int, seed: int = 0, rtol: float = 1e-9) -> tuple[int, float]:
    """Rank deficiency of Pinocchio's stacked regressor (gravity included), with URDF
    ``<mimic>`` joints imposed as couplings on its coordinates; returns (nullity, gap)."""
    import xml.etree.ElementTree as ET

    import pinocchio as pin

    rng = np.random.default_rng(seed)
    data = model.createData()
    nb = model.njoints - 1
    if nb == 0:
        return 0, np.inf
    # couplings from <mimic>, in Pinocchio's velocity coordinates
    root = ET.parse(path).getroot()
    gmap = np.eye(model.nv)
    keep = np.ones(model.nv, dtype=bool)
    mimic = []
    for jt in root.findall("joint"):
        m = jt.find("mimic")
        if m is None or not model.existJointName(jt.get("name")) or not model.existJointName(m.get("joint")):
            continue
        f = model.joints[model.getJointId(jt.get("name"))]
        lead = model.joints[model.getJointId(m.get("joint"))]
        mult = float(m.get("multiplier", "1"))
        off = float(m.get("offset", "0"))
        gmap[f.idx_v, :] = 0.0
        gmap[f.idx_v, lead.idx_v] = mult
        keep[f.idx_v] = False
        mimic.append((f, lead, mult, off))
    g = gmap[:, keep]
    rows = []
    for _ in range(samples):
        q = pin.integrate(model, pin.neutral(model), rng.uniform(-1, 1, model.nv))
        for f, lead, mult, off in mimic:
            if f.nq == 1 and lead.nq == 1:
                q[f.idx_q] = mult * q[lead.idx_q] + off
        v = g @ rng.uniform(0, 1, g.shape[1])
        a = g @ rng.uniform(0, 1, g.shape[1])
        y = pin.computeJointTorqueRegressor(model, data, q, v, a)
        rows.append(g.T @ y)
    w = np.concatenate(rows)
    # no column scaling: columns that vanish identically are ~1e-16, not 0, and scaling them
    # up turns rounding noise into spurious rank
    s = np.linalg.svd(w, compute_uv=False)
    rank = int(np.sum(s > rtol * s[0]))
    gap = s[rank - 1] / s[rank] if rank < len(s) else np.inf
    return 10 * nb - rank, gap
