"""Joint torques of a log with an identified payload: the known robot, the payload, the fitted drive terms."""

from __future__ import annotations

import numpy as np

from ..drives import drives_for
from .model import PayloadModel
from .rows import log_columns


def payload_torques(payload, log, smooth: bool = True) -> np.ndarray:
    """Predicted torques of every joint of a log for the robot carrying the payload (:meth:`Payload.predict`).

    The known robot (the model file's rigid body and armature, or the saved identification's
    prediction), plus the payload's torques ``Y_L phi`` on every joint, plus the drive terms fitted
    with the payload on their joints. States as :meth:`baseparams.ident.Identification.predict`
    derives them: low-passed at the fit's cutoff (``smooth``), or as logged.

    Parameters
    ----------
    payload : Payload
        The identified payload.
    log : JointLog
        ``S`` samples of every joint (``tau`` may be None).
    smooth : bool
        Filtered states (default), or as logged.

    Returns
    -------
    ndarray, shape ``(S, dof)``
        Torques [N m or N], columns the robot's coordinates in order.
    """
    from ...jointlog import JointLog
    from ..preprocess import log_states

    m = payload.model
    robot = m.robot
    if not isinstance(log, JointLog):
        from ...arguments import ArgumentTypeError

        raise ArgumentTypeError(f"predict: log must be a JointLog, got {type(log).__name__}")
    log = log.checked()
    cols = log_columns(robot, log)
    q, dq, ddq, _ = log_states(log, payload.options.cutoff, smooth)
    q, dq, ddq = q[:, cols], dq[:, cols], ddq[:, cols]
    rows = np.arange(robot.dof)
    arm = np.zeros(robot.dof) if m.result is not None else np.asarray(robot.armature, dtype=float).copy()
    arm[m.rows] = m.armature
    whole = PayloadModel(robot, m.body, rows, drives_for(robot, rows, rotor=False, friction=()), arm, m.result)
    a, rigid = whole.columns(q, dq, ddq)
    tau = whole.known(np.asarray(log.t, dtype=float), np.asarray(log.q, dtype=float)[:, cols], q, dq, ddq, rigid)
    tau = tau + a @ payload.parameters
    tau[:, m.rows] += m.drives.regressor(dq[:, m.rows], ddq[:, m.rows], len(m.rows)) @ payload.fit.x[10:]
    return tau
