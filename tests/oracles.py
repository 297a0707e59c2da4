"""Independent references for the tests.

``rnea``: recursive Newton-Euler in body-local frames with 6x6 spatial transforms
(Featherstone's formulation, (omega, v) ordering), written apart from the TP code: it
uses only the model's raw data (frames, axes, parents, inertias) and scipy's ``expm``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm


def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def Ad(t):
    """6x6 motion transform of pose t: child-frame twist -> parent-frame twist."""
    r, p = t[:3, :3], t[:3, 3]
    x = np.zeros((6, 6))
    x[:3, :3] = r
    x[3:, 3:] = r
    x[3:, :3] = skew(p) @ r
    return x


def crm(v):
    out = np.zeros((6, 6))
    out[:3, :3] = skew(v[:3])
    out[3:, 3:] = skew(v[:3])
    out[3:, :3] = skew(v[3:])
    return out


def crf(v):
    return -crm(v).T


def spatial_inertia(n):
    """6x6 spatial inertia about the frame origin from a pseudo-inertia N (same frame)."""
    sigma, h, m = n[:3, :3], n[:3, 3], n[3, 3]
    j = np.trace(sigma) * np.eye(3) - sigma
    out = np.zeros((6, 6))
    out[:3, :3] = j
    out[:3, 3:] = skew(h)
    out[3:, :3] = -skew(h)
    out[3:, 3:] = m * np.eye(3)
    return out


def _sub_joints(robot, i):
    """Local unit twists of the 1-dof sub-joints of joint i (S: x, y, z; C: its twists)."""
    t = robot.jtype[i]
    if t in ("R", "U", "S"):
        return [np.r_[a, 0, 0, 0] for a in robot.axes[i]]
    if t == "P":
        return [np.r_[0, 0, 0, robot.axes[i][0]]]
    if t == "C":  # raw (omega, v) twists of the joint frame, applied in order
        return [np.asarray(a, dtype=float) for a in robot.axes[i]]
    raise AssertionError


def rnea(robot, q, dq, ddq):
    """Generalized forces (dof,) for one state; F root quasi-velocities in world coords."""
    n = robot.n
    grav = np.r_[0, 0, 0, -np.asarray(robot.gravity)]  # spatial acceleration of the world
    qi = robot.q_index
    pose, vel, acc, frc = [None] * n, [None] * n, [None] * n, [None] * n
    sub = [None] * n  # per body: list of (X_child<-prev (6x6), s_local)
    for i in range(n):
        p = robot.parent[i]
        j0 = qi[i]
        if robot.jtype[i] == "F":
            u, du = dq[j0:j0 + 6], ddq[j0:j0 + 6]
            tw = q[j0:j0 + 6]
            xi = np.zeros((4, 4))
            xi[:3, :3] = skew(tw[:3])
            xi[:3, 3] = tw[3:]
            t = expm(xi) @ robot.M0[i]
            xinv = Ad(np.linalg.inv(t))
            pose[i] = t
            vel[i] = xinv @ u
            acc[i] = xinv @ (du + grav)
            sub[i] = xinv
            continue
        tp = np.eye(4) if p < 0 else pose[p]
        mp = np.eye(4) if p < 0 else robot.M0[p]
        vp = np.zeros(6) if p < 0 else vel[p]
        ap = grav.copy() if p < 0 else acc[p]
        # parent frame -> joint frame (fixed), expressed with the parent's local frame
        t = tp @ np.linalg.inv(mp) @ robot.M0[i]
        x = Ad(np.linalg.inv(np.linalg.inv(mp) @ robot.M0[i]))
        v, a = x @ vp, x @ ap
        chain = []
        for k, s in enumerate(_sub_joints(robot, i)):
            xi = np.zeros((4, 4))
            xi[:3, :3] = skew(s[:3])
            xi[:3, 3] = s[3:]
            tj = expm(xi * q[j0 + k])
            xj = Ad(np.linalg.inv(tj))
            v = xj @ v + s * dq[j0 + k]
            a = xj @ a + s * ddq[j0 + k] + crm(v) @ s * dq[j0 + k]
            t = t @ tj
            chain.append((xj, s))
        pose[i], vel[i], acc[i], sub[i] = t, v, a, (x, chain)
    tau = np.zeros(robot.dof)
    for i in range(n):
        inert = spatial_inertia(robot.N_body[i])
        frc[i] = inert @ acc[i] + crf(vel[i]) @ inert @ vel[i]
    for i in reversed(range(n)):
        f = frc[i]
        p = robot.parent[i]
        j0 = qi[i]
        if robot.jtype[i] == "F":
            tau[j0:j0 + 6] = sub[i].T @ f
            continue
        x, chain = sub[i]
        for k in reversed(range(len(chain))):
            xj, s = chain[k]
            tau[j0 + k] = s @ f
            f = xj.T @ f
        f = x.T @ f
        if p >= 0:
            frc[p] = frc[p] + f
    return tau


def lowpass_score(t, measured, predicted, mask, cutoff: float = 5.0, trim_end: float = 0.5) -> float:
    """The Panda measure of the identification issue, computed as an outsider would.

    Measured torques of the whole log low-passed by ``scipy.signal.filtfilt`` with a 4th-order
    Butterworth at ``cutoff`` Hz (normalised cutoff from the median rate of the raw, non-uniform
    samples, no resampling); RMS of predicted minus that over the held-out samples ``mask``
    except the last ``trim_end`` seconds, all joints.
    """
    from scipy.signal import butter, filtfilt

    t = np.asarray(t, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    b, a = butter(4, cutoff / (fs / 2))
    lp = filtfilt(b, a, np.asarray(measured, dtype=float), axis=0)
    keep = np.asarray(mask, dtype=bool) & (t <= t[-1] - trim_end)
    e = np.asarray(predicted, dtype=float)[keep[np.asarray(mask, dtype=bool)]] - lp[keep]
    return float(np.sqrt(np.mean(e**2)))


# ---------------------------------------------------------------- an outsider's plain least squares
def _outsider_states(t, q, cutoff: float, dq=None):
    """States as an outsider computes them: q (and the logged dq, when there is one) interpolated onto a uniform
    grid at the median rate, low-passed by ``filtfilt`` (4th-order Butterworth at ``cutoff``), differentiated by
    ``np.gradient`` there (dq only where the log has none), and the three interpolated back to the stamps as they
    are (uneven stamps stay where they were)."""
    from scipy.signal import butter, filtfilt

    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    dt = float(np.median(np.diff(t)))
    grid = t[0] + dt * np.arange(int(np.floor((t[-1] - t[0]) / dt)) + 1)
    qg = np.column_stack([np.interp(grid, t, q[:, j]) for j in range(q.shape[1])])
    b, a = butter(4, min(cutoff * 2 * dt, 0.99))
    qf = filtfilt(b, a, qg, axis=0)
    if dq is None:
        dq = np.gradient(qf, dt, axis=0)
    else:
        dq = filtfilt(b, a, np.column_stack([np.interp(grid, t, np.asarray(dq, dtype=float)[:, j])
                                             for j in range(q.shape[1])]), axis=0)
    ddq = np.gradient(dq, dt, axis=0)
    back = [np.column_stack([np.interp(t, grid, x[:, j]) for j in range(q.shape[1])]) for x in (qf, dq, ddq)]
    return tuple(back)


def _outsider_rows(pin_model, t, q, cutoff: float, dq=None):
    """Pinocchio's joint-torque regressor at every sample, then viscous, Coulomb and offset columns per joint:
    shape ``(S, m, 10 n + 3 m)``."""
    import pinocchio as pin

    qf, dq, ddq = _outsider_states(t, q, cutoff, dq)
    data = pin_model.createData()
    m = pin_model.nv
    rows = []
    for k in range(len(t)):
        y = pin.computeJointTorqueRegressor(pin_model, data, qf[k], dq[k], ddq[k]).copy()
        fr = np.zeros((m, 3 * m))
        fr[np.arange(m), np.arange(m)] = dq[k]
        fr[np.arange(m), m + np.arange(m)] = np.sign(dq[k])
        fr[np.arange(m), 2 * m + np.arange(m)] = 1.0
        rows.append(np.hstack([y, fr]))
    return np.asarray(rows)


def outsider_ols(pin_model, train, test, cutoff: float = 5.0, trim: float = 1.0) -> float:
    """An independent plain OLS trained on one recording and scored on another, as an outsider would do it.

    Pinocchio's regressor (``pin_model``: the model file as Pinocchio reads it, fixed base, the
    logs' joint order) at **every** sample of ``train`` with states low-passed at ``cutoff`` Hz
    (:func:`_outsider_states`; the logged velocities where there are some), plus viscous, Coulomb
    and offset columns per joint; the raw
    torques; minimum-norm least squares (``lstsq``). Scored on ``test`` (its states filtered the
    same way) against its measured torques low-passed at ``cutoff`` Hz, ``trim`` seconds left out at
    each end (:func:`outsider_score`). Returns the RMS [N m] over every joint and kept sample.
    """
    w = _outsider_rows(pin_model, train.t, train.q, cutoff, train.dq)
    m = w.shape[1]
    theta, *_ = np.linalg.lstsq(w.reshape(-1, w.shape[2]), np.asarray(train.tau, dtype=float).reshape(-1),
                                rcond=None)
    pred = _outsider_rows(pin_model, test.t, test.q, cutoff, test.dq) @ theta
    assert pred.shape[1] == m
    return outsider_score(test.t, test.tau, pred, cutoff, trim)


def outsider_score(t, measured, predicted, cutoff: float = 5.0, trim: float = 1.0) -> float:
    """RMS [N m] of predicted torques against the measured ones low-passed at ``cutoff`` Hz by ``filtfilt``
    (4th-order Butterworth, median rate, no resampling), every joint, every sample but ``trim`` seconds at each
    end: the figure of merit of the cross-recording issue, computed apart from the project."""
    from scipy.signal import butter, filtfilt

    t = np.asarray(t, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    b, a = butter(4, min(cutoff / (fs / 2), 0.99))
    lp = filtfilt(b, a, np.asarray(measured, dtype=float), axis=0)
    keep = (t >= t[0] + trim) & (t <= t[-1] - trim)
    e = np.asarray(predicted, dtype=float)[keep] - lp[keep]
    return float(np.sqrt(np.mean(e**2)))
