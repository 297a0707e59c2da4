"""The identified model written into its file: a physical identification's bodies and drive terms.

The conversions of an :class:`~baseparams.ident.Identification` to the model-file writers
of :mod:`baseparams.io` (which know nothing of identification): :func:`identified_drives` gives the
drive terms as :func:`baseparams.io.urdf.write_urdf` takes them, :func:`identified_mjcf` writes a
copy of the MJCF model through :func:`baseparams.io.mjcf_write.write_mjcf`, checked on the log's
samples.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import BaseparamsError


def identified_drives(ident) -> tuple[dict, list]:
    """The drive terms of a physical identification, as :func:`~baseparams.io.urdf.write_urdf` takes them.

    Parameters
    ----------
    ident : Identification
        A physically consistent identification (``method="physical"``): its drive values are
        the physical fit's (every modelled drive parameter has one, also those the data regroup
        with base parameters).

    Returns
    -------
    drives : dict
        ``{joint: {"Ia", "Fv", "Fc", "Fo": float or None}}`` (None: not modelled).
    couplings : list of dict
        ``{"name", "joints", "Iam", "Fvm", "Fcm"}`` per coupled motor.
    """
    d = ident.model.drives
    values = dict(zip(d.names, np.asarray(ident.fit.physical.delta, dtype=float).tolist()))
    drives = {j: {k: values.get(f"{k}_{j}") for k in ("Ia", "Fv", "Fc", "Fo")} for j in d.joints}
    couplings = [{"name": c.name, "joints": dict(zip(c.joints, c.weights)),
                  **{k: values.get(f"{k}_{c.name}") for k in ("Iam", "Fvm", "Fcm")}} for c in d.couplings]
    return drives, couplings


def identified_mjcf(ident, source: str | Path, dest: str | Path, log, *, inputs=(),
                    max_samples: int = 20000) -> list[str]:
    """Write a physical identification into a copy of its MJCF model, checked on the log's samples.

    :func:`~baseparams.io.mjcf_write.write_mjcf` with the physical fit's inertias and drive terms
    (:func:`identified_drives`), checked at the log's states (filtered as
    :meth:`~baseparams.ident.Identification.predict` filters them; at most
    ``max_samples``, evenly spaced). After writing, the file is reloaded and its ``mj_inverse``
    (``frictionloss`` on) compared with the identification's own prediction and with the log's
    measured torques; both relative RMS differences are in the notes.

    Parameters
    ----------
    ident : Identification
        A ``method="physical"`` identification of every joint of the robot read from ``source``.
    source : str or Path
        The MJCF (or URDF) file the robot was read from.
    dest : str or Path
        The file written.
    log : JointLog
        The log identified (``S`` samples; ``tau`` used for the last comparison when present).
    inputs : iterable of str or Path
        Further input files ``dest`` must not overwrite.
    max_samples : int
        Most samples checked.

    Returns
    -------
    list of str
        Notes (:func:`~baseparams.io.mjcf_write.write_mjcf`'s, then the two comparisons).

    Raises
    ------
    BaseparamsError
        Not a physical identification, a sub-chain, coupled motors, or anything
        :func:`~baseparams.io.mjcf_write.write_mjcf` refuses (nothing is written then).
    """
    from ..io.mjcf_write import mjcf_inverse, write_mjcf
    from .preprocess import log_states

    if ident.fit.physical is None:
        raise BaseparamsError("--mjcf needs --method physical: least squares gives base parameters, not bodies")
    robot = ident.model.robot
    if list(ident.model.coords) != list(range(robot.dof)):
        raise BaseparamsError("--mjcf: every joint of the robot must be identified (a sub-chain's values are not "
                              "the whole model's)")
    drives, couplings = identified_drives(ident)
    if any(c.get(k) is not None for c in couplings for k in ("Iam", "Fvm", "Fcm")):
        raise BaseparamsError("--mjcf: coupled motors (--coupling) have no MJCF joint attribute; --urdf keeps "
                              "their values in comments")
    q, dq, ddq, _ = log_states(log, None if ident.options is None else ident.options.cutoff, True)
    cols = [list(log.joints).index(j) for j in ident.joints]
    rows = np.unique(np.linspace(0, len(q) - 1, min(len(q), max_samples)).astype(int))
    q, dq, ddq = (x[rows][:, cols] for x in (q, dq, ddq))
    tilt = next((t for t in ident.fit.terms if t.name == "tilt"), None)
    extra = 0.0 if tilt is None else tilt.adjust_model(ident.fit, q, q, dq, ddq, np.zeros_like(q))
    notes = write_mjcf(source, dest, robot, ident.fit.physical.pi, "paper", drives=drives, states=(q, dq, ddq),
                       expected=_held_prediction(ident, q, dq, ddq) + extra, inputs=inputs,
                       base_rotation=None if tilt is None else tilt.base_rotation())
    notes += [f"--mjcf: not written: {x}" for t in ident.fit.terms for x in t.export().get("not", [])]
    got = mjcf_inverse(dest, robot, q, dq, ddq, frictionloss=True)
    offsets = np.array([float((drives.get(j) or {}).get("Fo") or 0.0) for j in robot.joint_names])
    pred = ident.fit.predict(q, dq, ddq) + extra - offsets  # Fo: not in MJCF

    def rel(a, b):
        return float(np.sqrt(np.mean((a - b) ** 2)) / (np.sqrt(np.mean(b**2)) or 1.0))

    without = " (without Fo)" if any(d.get("Fo") for d in drives.values()) else ""
    notes.append(f"--mjcf: {dest} reloaded: MuJoCo's mj_inverse (frictionloss on; contacts, limits off) vs the "
                 f"identification's own prediction{without} on {len(q)} log samples: relative RMS difference "
                 f"{rel(got, pred):.2g}")
    if log.tau is not None:
        tau = np.asarray(log.tau, dtype=float)[rows][:, cols]
        notes.append(f"--mjcf: MuJoCo's mj_inverse of {dest} vs the log's measured torques: relative RMS "
                     f"difference {rel(got, tau):.3g}")
    return notes


def _held_prediction(ident, q, dq, ddq) -> np.ndarray:
    """The identification's own prediction ``(S, m)`` of the terms MJCF holds exactly: rigid body, ``Ia``, ``Fv``.

    Its model regressor times ``theta = G [pi; delta]`` with the other drive kinds (``Fc``, ``Fo``)
    zeroed; computed in chunks of 5000 samples.
    """
    phys = ident.fit.physical
    kinds = np.array(ident.model.drives.param_kinds, dtype=object)
    held = np.where(np.isin(kinds, ["Ia", "Fv"]), np.asarray(phys.delta, dtype=float), 0.0) if kinds.size else \
        np.zeros(0)
    theta = ident.model.full_map() @ np.concatenate([np.asarray(phys.pi, dtype=float), held])
    return np.concatenate([ident.model.regressor(q[k:k + 5000], dq[k:k + 5000], ddq[k:k + 5000]) @ theta
                           for k in range(0, len(q), 5000)])
