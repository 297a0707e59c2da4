"""The main job: DRNG, certification/completion, base parameters, and their report.

JSON schema (``baseparams analyze MODEL --json``), one object:

=====================  ===================================================================
model                  robot name
n_bodies, n_params     moving bodies, 10 x bodies
gravity                [gx, gy, gz] m/s^2, world frame
floating               true for a floating (F) root
rows                   measured generalized forces: all | joints | base
nullity                certified nullspace dimension (DRNG's rank when --no-verify)
n_base                 number of base parameters = n_params - nullity
drng                   {columns, rank, seconds, extended, by_principle{shared points, fixed
                       points, planar rotations}, by_rule{shared points, fixed points, planar
                       rotations, R-A fixed vectors, R-B sliding points, R-L1 parallelograms,
                       R-L2 level chains, numerical}, complete}: rank added by each source in that order (the
                       paper's principles, the extended rules, numerical completion); complete:
                       the geometric span equals the certified nullspace (null if unverified)
numerical              {nullity, rank, samples, sv_gap, tolerance, rtol, seconds, sampling{
                       requested, kept, and for loops not_converged, branch_jumps,
                       ill_conditioned, max_loop_residual}} or null
certified              true when the numerics confirm the (completed) nullspace
status, message        certified | completed | undecided | failed | unverified, and why
completed              directions added from the numerical nullspace (marked numerical)
residual               ||W B_drng||_F / ||W||_F with orthonormal B_drng (null if unverified)
convention             parameter convention of base_parameters (khalil: link frames)
base_parameters        [{name, expression}] regrouped base parameters
base_parameters_paper  the same in the paper's spatial convention (world frame at q = 0)
unidentifiable         standard parameters that no base parameter sees
=====================  ===================================================================
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TextIO

import numpy as np

from .base import BaseParameters, base_parameters
from .model.robot import Robot
from .nullspace import PRINCIPLES, drng
from .model import inertia as _inertia
from .nullspace.drng import PAPER, UNMEASURED
from .nullspace.certify import Certificate, certify


@dataclass(frozen=True)
class Analysis:
    robot: Robot
    rows: str
    drng_seconds: float
    drng_columns: int
    drng_rank: int
    by_principle: dict[str, int]
    certificate: Certificate | None
    basis: np.ndarray
    base: BaseParameters
    base_paper: BaseParameters
    seconds: float
    extended: bool = True

    @property
    def nullity(self) -> int:
        return self.basis.shape[1]

    def to_json(self) -> dict:
        r, c = self.robot, self.certificate
        num = None
        if c is not None:
            nm = c.numerical
            num = {"nullity": nm.nullity, "rank": nm.rank, "samples": nm.samples,
                   "sv_gap": None if not np.isfinite(nm.gap) else nm.gap, "tolerance": nm.tol,
                   "rtol": nm.rtol, "seconds": nm.seconds, "sampling": c.sampling}
        return {
            "model": r.name, "n_bodies": r.n, "n_params": 10 * r.n, "gravity": r.gravity.tolist(),
            "floating": r.floating, "rows": self.rows, "nullity": self.nullity,
            "n_base": 10 * r.n - self.nullity,
            "drng": {"columns": self.drng_columns, "rank": self.drng_rank, "seconds": self.drng_seconds,
                     "extended": self.extended,
                     "by_principle": {k: v for k, v in self.by_principle.items() if k in PAPER},
                     "by_rule": {**self.by_principle, "numerical": 0 if c is None else c.completed},
                     "complete": None if c is None else bool(c.status == "certified")},
            "numerical": num,
            "certified": bool(c is not None and c.certified),
            "status": "unverified" if c is None else c.status,
            "message": "not verified (--no-verify)" if c is None else c.message,
            "completed": 0 if c is None else c.completed,
            "residual": None if c is None else c.residual,
            "convention": self.base.convention,
            "base_parameters": self.base.expressions(),
            "base_parameters_paper": self.base_paper.expressions(),
            "unidentifiable": [self.base.names[i] for i in self.base.unidentifiable],
        }


def analyze(robot: Robot, samples: int | None = None, seed: int = 0, verify: bool = True, rows: str = "all",
            convention: str = "khalil", progress: TextIO | None = None, extended: bool = True) -> Analysis:
    """DRNG -> (certify, complete) -> regroup. ``progress``: a stream for progress lines;
    ``extended``: the extended rules as well as the paper's principles."""
    t0 = time.perf_counter()

    def say(msg: str) -> None:
        if progress is not None:
            print(f"[baseparams] {msg}", file=progress, flush=True)

    say(f"{robot.name}: {robot.n} bodies, {robot.dof} dofs; running DRNG")
    res = drng(robot, extended=extended, rows=rows)
    by = res.by_principle()
    cert = None
    if verify:
        say(f"certifying with {samples or 'the default number of'} random samples (seed {seed}, rows: {rows})")
        cert = certify(robot, samples, seed, rows, result=res)
        basis = cert.basis
    else:
        basis = res.orthonormal()
    say("regrouping base parameters")
    base = base_parameters(robot, basis, convention)
    base_paper = base_parameters(robot, basis, "paper")
    return Analysis(robot, rows, res.seconds, res.n_columns, res.rank, by, cert, basis, base, base_paper,
                    time.perf_counter() - t0, extended)


def format_report(a: Analysis) -> str:
    """Human-readable report."""
    r, c, j = a.robot, a.certificate, a.to_json()
    loops = f", {len(r.loops)} loop joints, {len(r.actuated)} actuated" if r.has_loops else ""
    out = [f"{r.name}: {r.n} bodies, {10 * r.n} standard parameters, {r.dof} dofs{loops}, "
           f"{'floating' if r.floating else 'fixed'} base, gravity {r.gravity.tolist()} m/s^2, rows: {a.rows}",
           f"nullspace dimension {a.nullity}  ->  {j['n_base']} base parameters",
           f"DRNG: {a.drng_columns} columns of rank {a.drng_rank} in {a.drng_seconds * 1e3:.2f} ms"]
    for name in PRINCIPLES[:-1]:
        if name in a.by_principle:
            kind = ("paper" if name in PAPER else "measured rows: joint torques only" if name == UNMEASURED
                    else "extended rule")
            out.append(f"  {name:<22s} {a.by_principle[name]:4d}  ({kind})")
    if c is None:
        out.append("certification: skipped (--no-verify); the nullity above is DRNG's rank, unverified")
        if a.rows == "base" and r.floating:
            out.append("  measured rows: the base wrench alone sees every direction the full dynamics see "
                       "(Ayusawa et al. 2014); unverified here")
    else:
        nm = c.numerical
        out.append(f"  {'numerical':<22s} {c.completed:4d}  (completed from the numerical nullspace)")
        out.append("  geometric span complete: " + ("yes" if c.status == "certified" else "no"))
        out.append(f"numerical method: {nm.samples} samples, rank {nm.rank}, nullity {nm.nullity}, "
                   f"tolerance {nm.tol:.3g}, singular-value gap {nm.gap:.3g}, {nm.seconds * 1e3:.1f} ms")
        if r.has_loops and c.sampling:
            sm = c.sampling
            out.append(f"  loop sampling: {sm['kept']} of {sm['requested']} actuated samples kept "
                       f"({sm['not_converged']} outside the workspace, {sm['branch_jumps']} left the assembly "
                       f"mode, {sm['ill_conditioned']} with cond(J_p) >= {sm['cond_max']:.3g}); max loop residual "
                       f"{sm['max_loop_residual']:.1e}")
        out.append(f"certification: {c.status.upper()} - {c.message}")
        out.append(f"  residual ||W B||/||W|| = {c.residual:.2e}, worst column {c.max_column_residual:.2e}")
    out.append("")
    out.append(f"base parameters ({_inertia.describe(a.base.convention)}):")
    for e in a.base.expressions():
        out.append(f"  {e['name']} = {e['expression']}")
    if len(a.base.unidentifiable):
        out.append("unidentifiable standard parameters: " + ", ".join(j["unidentifiable"]))
    out.append("")
    out.append(f"the same in the paper's convention ({_inertia.describe('paper')}):")
    for e in a.base_paper.expressions():
        out.append(f"  {e['name']} = {e['expression']}")
    out.append(f"\ntotal {a.seconds * 1e3:.1f} ms")
    return "\n".join(out)
