"""Completeness of DRNG with measured joint sets: how often the rules alone give the nullspace.

Standalone (pytest does not collect it)::

    PYTHONPATH=src python3 benchmarks/measured_rows.py [--seeds 500] [--verbose]

For each family of random trees (2-7 bodies; ``random_robot`` R/P, R/P/U/S, R/P/U/S/C, floating
R/P; ``special_robot``), seeds ``0 .. seeds - 1``: each joint is measured with probability 0.6
(at least one; a floating base's wrench too with probability 0.3), DRNG is certified against
the regressor restricted to those rows, and the case is counted as complete (``certified``),
completed by no more than with every row measured (DRNG's gaps with all rows, compound joints),
or completed beyond that (the measured-rows rules' gaps: the directions are summed). A failed
certificate (a rule column outside the nullspace) is counted too; there should be none.
"""

from __future__ import annotations

import argparse
import collections
import time

import numpy as np

from baseparams.nullspace.certify import certify
from baseparams.robots.random import random_robot, special_robot

FAMILIES = {"R/P": ("RP", False), "R/P/U/S": ("RPUS", False), "R/P/U/S/C": ("RPUSC", False),
            "floating R/P": ("RP", True), "special": (None, False)}


def case(family: str, seed: int):
    """The robot and measured rows (a ``joints:`` or ``base+joints:`` form) of one case, or None."""
    types, floating = FAMILIES[family]
    rng = np.random.default_rng(seed)
    if types is None:
        robot = special_robot(rng)
    else:
        robot = random_robot(rng, int(rng.integers(2, 7)), types, floating=floating, branching=0.3)
    meas = [nm for i, nm in enumerate(robot.joint_names) if rng.random() < 0.6 and robot.jtype[i] != "F"]
    if not meas:
        return None
    rows = "joints:" + ",".join(meas)
    if robot.floating and rng.random() < 0.3:
        rows = "base+" + rows
    return robot, rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=500)
    ap.add_argument("--verbose", action="store_true", help="list the cases completed beyond all rows")
    args = ap.parse_args()
    for family in FAMILIES:
        t0, stats, extra, listed = time.perf_counter(), collections.Counter(), 0, []
        for seed in range(args.seeds):
            c = case(family, seed)
            if c is None:
                continue
            robot, rows = c
            cert = certify(robot, rows=rows)
            if cert.status == "failed":
                stats["failed"] += 1
                continue
            base = certify(robot).completed if cert.completed else 0
            if not cert.completed:
                stats["complete"] += 1
            elif cert.completed <= base:
                stats["as with all rows"] += 1
            else:
                stats["beyond all rows"] += 1
                extra += cert.completed - base
                listed.append((seed, "".join(robot.jtype), rows, cert.completed - base))
        print(f"{family:14s} {sum(stats.values()):4d} cases: {dict(stats)}; directions completed beyond all rows: "
              f"{extra} ({time.perf_counter() - t0:.0f} s)")
        if args.verbose:
            for item in listed:
                print("   ", item)


if __name__ == "__main__":
    main()
