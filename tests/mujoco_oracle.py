"""An independent reference for MJCF models: MuJoCo's own inverse dynamics as a regressor.

For every body that moves (``body_weldid != 0``), 10 point-mass probes at generic points (the
pseudo-inertia of a unit point mass at ``p`` is ``[p;1][p;1]^T``; 10 generic points span all
symmetric 4x4) are set on that body alone (all other bodies massless); with armature, damping,
stiffness, friction loss, gravity compensation, fluid forces, contacts and limits off,
``mj_inverse`` at random states gives the regressor columns (MuJoCo's compile-time shortcuts
that assume the file's inertias, ``body_sameframe``/``body_simple``/``dof_simplenum``, are off).
Models with equality constraints
whose Jacobian is constant (joint and fixed-tendon couplings): states on the constraint manifold
(Newton on MuJoCo's own ``efc_J``/``efc_pos``), velocities and accelerations in the nullspace of
``efc_J``, and the rows projected onto that nullspace (the constraint-consistent motions). With
joint equalities alone (a ``polycoef`` of degree up to 4: a Jacobian that changes with ``q``) the
acceleration also carries ``-J^+ (dJ/dt) v``, the second derivative of MuJoCo's residual along
``q + t v`` (a polynomial of degree 4 in ``t``, interpolated exactly at five points).
Uses only ``mujoco`` and numpy, nothing of ``baseparams``.
"""

from __future__ import annotations

import numpy as np


def _random_state(mujoco, m, rng):
    q = m.qpos0.copy()
    for j in range(m.njnt):
        a, t = m.jnt_qposadr[j], m.jnt_type[j]
        if t == mujoco.mjtJoint.mjJNT_FREE:
            q[a:a + 3] += rng.uniform(-1, 1, 3)
            v = rng.normal(size=4)
            q[a + 3:a + 7] = v / np.linalg.norm(v)
        elif t == mujoco.mjtJoint.mjJNT_BALL:
            v = rng.normal(size=4)
            q[a:a + 4] = v / np.linalg.norm(v)
        else:
            q[a] += rng.uniform(-1.5, 1.5)
    return q


def _equality_rows(mujoco, m, d):
    mujoco.mj_forward(m, d)
    nefc = d.nefc
    j = np.array(d.efc_J).reshape(-1, m.nv)[:nefc]
    eq = np.array(d.efc_type[:nefc]) == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    return j[eq], np.array(d.efc_pos[:nefc])[eq]


def mujoco_rank(path, samples=None, seed=0, rtol=1e-9, only=None):
    """``(rank, gap)`` of MuJoCo's probe regressor (see the module doc)."""
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    dis = mujoco.mjtDisableBit
    flags = dis.mjDSBL_CONTACT | dis.mjDSBL_LIMIT | dis.mjDSBL_FRICTIONLOSS | dis.mjDSBL_SPRING | dis.mjDSBL_DAMPER
    m.opt.disableflags |= int(flags)
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    m.opt.density, m.opt.viscosity = 0.0, 0.0
    m.dof_armature[:] = 0
    m.dof_damping[:] = 0
    m.dof_frictionloss[:] = 0
    m.jnt_stiffness[:] = 0
    m.body_gravcomp[:] = 0
    # compile-time shortcuts that assume the file's inertias (inertial frame = body frame, ...)
    m.body_sameframe[:] = 0
    m.body_simple[:] = 0
    m.dof_simplenum[:] = 0
    constrained = m.neq > 0
    # joint equalities only (MJCF polycoef, degree <= 4): a Jacobian that may change with q, handled exactly
    polynomial = constrained and all(int(t) == int(mujoco.mjtEq.mjEQ_JOINT) for t in m.eq_type)
    if not constrained:
        m.opt.disableflags |= int(dis.mjDSBL_CONSTRAINT)
    bodies = [b for b in range(1, m.nbody) if m.body_weldid[b] != 0 and (only is None or m.body(b).name in only)]
    m.body_mass[:] = 0
    m.body_inertia[:] = 0
    points = rng.normal(scale=0.3, size=(10, 3))
    ncols = 10 * len(bodies)
    samples = samples or max(12, int(np.ceil(3 * ncols / max(1, m.nv))))
    rows = []
    j_ref = None
    for _ in range(samples):
        q = _random_state(mujoco, m, rng)
        g = np.eye(m.nv)
        if constrained:  # onto the constraint manifold; motions in the nullspace of efc_J
            for _ in range(50):
                d.qpos[:] = q
                jac, pos = _equality_rows(mujoco, m, d)
                if np.abs(pos).max(initial=0) < 1e-12:
                    break
                dq = -np.linalg.lstsq(jac, pos, rcond=None)[0]
                mujoco.mj_integratePos(m, q, dq, 1.0)
            assert np.abs(pos).max(initial=0) < 1e-10, "could not close the equality constraints"
            if j_ref is None:
                j_ref = jac
            assert polynomial or np.allclose(jac, j_ref), "equality Jacobian not constant: no sound reference here"
            _, s, vt = np.linalg.svd(jac)
            g = vt[int(np.sum(s > 1e-10)):].T  # (nv, nv - r)
        v = g @ rng.uniform(-1, 1, g.shape[1])
        a = g @ rng.uniform(-1, 1, g.shape[1])
        if constrained and polynomial:  # J a + (dJ/dt) v = 0: the residual along q + t v is a polynomial in t
            ts = np.array([-2.0, -1.0, 0.0, 1.0, 2.0]) * 0.05
            vals = []
            for t in ts:
                d.qpos[:] = q + t * v
                vals.append(_equality_rows(mujoco, m, d)[1])
            bias = 2.0 * np.polyfit(ts, np.array(vals), 4)[2]  # d^2/dt^2 at t = 0 (degree <= 4: exact)
            a = a - np.linalg.pinv(jac) @ bias
        cols = np.empty((g.shape[1], ncols))
        m.opt.disableflags |= int(dis.mjDSBL_CONSTRAINT)  # no constraint forces in mj_inverse
        for k, b in enumerate(bodies):
            for p in range(10):
                m.body_mass[b], m.body_ipos[b], m.body_iquat[b] = 1.0, points[p], (1, 0, 0, 0)
                d.qpos[:], d.qvel[:], d.qacc[:] = q, v, a
                mujoco.mj_inverse(m, d)
                cols[:, 10 * k + p] = g.T @ d.qfrc_inverse
            m.body_mass[b] = 0.0
        if constrained:
            m.opt.disableflags &= ~int(dis.mjDSBL_CONSTRAINT)
        rows.append(cols)
    w = np.concatenate(rows)
    s = np.linalg.svd(w, compute_uv=False)
    r = int(np.sum(s > rtol * s[0]))
    gap = s[r - 1] / s[r] if r < len(s) else np.inf
    return r, gap
