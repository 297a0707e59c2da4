"""numba kernels of :mod:`baseparams.regressor.compiled` (importing this module imports numba).

Per sample: phase 1 walks the bodies in topological order (product of exponentials, as
:func:`baseparams.kinematics.tree.forward_kinematics`) and builds each body's ten swapped bar
lines ``X[i, k] = swap(bar(E_m v ddE_n))`` (as ``tp._bar_lines_swapped``); phase 2 writes the
output rows in order, ``Y[j, 10 i + k] = L_j . X[i, k]`` where coordinate ``j`` moves body
``i`` and zero elsewhere. Samples are processed in blocks in parallel (``prange``), each block
with its own scratch arrays.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

_BLOCK = 64


def _cache_usable() -> bool:
    """Whether numba can cache these kernels on disk.

    A read-only install with an unwritable HOME or ``NUMBA_CACHE_DIR`` has no cache locator:
    ``njit(cache=True)`` then raises at decoration. Without one, the kernels are compiled in
    memory, once per process (:func:`baseparams.regressor.compiled._kernels` says so).
    """
    try:
        njit(cache=True)(_probe)
    except RuntimeError:  # "cannot cache function ...: no locator available"
        return False
    return True


def _probe():  # pragma: no cover - never compiled: only its cache locator is looked up
    return 0


#: the kernels are cached on disk (False: compiled in memory in each process)
CACHE = _cache_usable()


@njit(cache=CACHE, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=CACHE, inline="always")
def _exp_screw(sw, theta, er, et):
    """``exp(screw^ theta)``: rotation ``er (3, 3)``, translation ``et (3,)`` (``|omega|`` = 1 or 0).

    Rodrigues: ``R = I + s K + c K^2``, ``t = theta v + c (w x v) + (theta - s) w x (w x v)``
    with ``K = [w]x``, ``K^2 = w w^T - |w|^2 I``, ``s = sin(theta)``, ``c = 1 - cos(theta)``.
    """
    w0, w1, w2, v0, v1, v2 = sw[0], sw[1], sw[2], sw[3], sw[4], sw[5]
    if w0 == 0.0 and w1 == 0.0 and w2 == 0.0:
        er[0, 0], er[0, 1], er[0, 2] = 1.0, 0.0, 0.0
        er[1, 0], er[1, 1], er[1, 2] = 0.0, 1.0, 0.0
        er[2, 0], er[2, 1], er[2, 2] = 0.0, 0.0, 1.0
        et[0], et[1], et[2] = theta * v0, theta * v1, theta * v2
        return
    s, c = math.sin(theta), 1.0 - math.cos(theta)
    ww = w0 * w0 + w1 * w1 + w2 * w2
    er[0, 0] = 1.0 + c * (w0 * w0 - ww)
    er[1, 1] = 1.0 + c * (w1 * w1 - ww)
    er[2, 2] = 1.0 + c * (w2 * w2 - ww)
    er[0, 1], er[1, 0] = c * w0 * w1 - s * w2, c * w0 * w1 + s * w2
    er[0, 2], er[2, 0] = c * w0 * w2 + s * w1, c * w0 * w2 - s * w1
    er[1, 2], er[2, 1] = c * w1 * w2 - s * w0, c * w1 * w2 + s * w0
    x0, x1, x2 = _cross(w0, w1, w2, v0, v1, v2)
    y0, y1, y2 = _cross(w0, w1, w2, x0, x1, x2)
    ts = theta - s
    et[0] = theta * v0 + c * x0 + ts * y0
    et[1] = theta * v1 + c * x1 + ts * y1
    et[2] = theta * v2 + c * x2 + ts * y2


@njit(cache=CACHE, inline="always")
def _exp_twist(q, smp, j0, rot, pos, i):
    """``exp(xi^)`` of the twist ``xi = q[smp, j0:j0 + 6]`` into ``rot[i], pos[i]`` (series near 0)."""
    w0, w1, w2 = q[smp, j0], q[smp, j0 + 1], q[smp, j0 + 2]
    v0, v1, v2 = q[smp, j0 + 3], q[smp, j0 + 4], q[smp, j0 + 5]
    th2 = w0 * w0 + w1 * w1 + w2 * w2
    th = math.sqrt(th2)
    if th < 1e-6:
        a = 1.0 - th2 / 6.0 + th2 * th2 / 120.0
        b = 0.5 - th2 / 24.0 + th2 * th2 / 720.0
        c = 1.0 / 6.0 - th2 / 120.0 + th2 * th2 / 5040.0
    else:
        a = math.sin(th) / th
        b = (1.0 - math.cos(th)) / th2
        c = (th - math.sin(th)) / (th2 * th)
    # R = I + a K + b K^2; t = v + b (w x v) + c w x (w x v), K^2 = w w^T - th2 I
    rot[i, 0, 0] = 1.0 + b * (w0 * w0 - th2)
    rot[i, 1, 1] = 1.0 + b * (w1 * w1 - th2)
    rot[i, 2, 2] = 1.0 + b * (w2 * w2 - th2)
    rot[i, 0, 1], rot[i, 1, 0] = b * w0 * w1 - a * w2, b * w0 * w1 + a * w2
    rot[i, 0, 2], rot[i, 2, 0] = b * w0 * w2 + a * w1, b * w0 * w2 - a * w1
    rot[i, 1, 2], rot[i, 2, 1] = b * w1 * w2 - a * w0, b * w1 * w2 + a * w0
    x0, x1, x2 = _cross(w0, w1, w2, v0, v1, v2)
    y0, y1, y2 = _cross(w0, w1, w2, x0, x1, x2)
    pos[i, 0] = v0 + b * x0 + c * y0
    pos[i, 1] = v1 + b * x1 + c * y1
    pos[i, 2] = v2 + b * x2 + c * y2


@njit(cache=CACHE, inline="always")
def _body(i, smp, parent, q_index, ndofs, floating, screws, q, dq, ddq, rot, pos, vel, acc, lines, er, et):
    """Kinematics of body ``i`` for sample ``smp``: pose, twist, acceleration, its joint lines."""
    p = parent[i]
    j0, k = q_index[i], ndofs[i]
    if floating[i]:
        _exp_twist(q, smp, j0, rot, pos, i)
        for c in range(6):
            for d in range(6):
                lines[j0 + c, d] = 1.0 if c == d else 0.0
            vel[i, c] = dq[smp, j0 + c] + (vel[p, c] if p >= 0 else 0.0)
            acc[i, c] = ddq[smp, j0 + c] + (acc[p, c] if p >= 0 else 0.0)
        return
    if p >= 0:
        for x in range(3):
            for y in range(3):
                rot[i, x, y] = rot[p, x, y]
            pos[i, x] = pos[p, x]
        for c in range(6):
            vel[i, c] = vel[p, c]
            acc[i, c] = acc[p, c]
    else:
        for x in range(3):
            for y in range(3):
                rot[i, x, y] = 1.0 if x == y else 0.0
            pos[i, x] = 0.0
        for c in range(6):
            vel[i, c] = 0.0
            acc[i, c] = 0.0
    for jj in range(j0, j0 + k):
        for x in range(3):  # line = Ad_(r, t) screw: d = r w, m = r v + t x d
            lines[jj, x] = rot[i, x, 0] * screws[jj, 0] + rot[i, x, 1] * screws[jj, 1] + rot[i, x, 2] * screws[jj, 2]
            lines[jj, 3 + x] = (rot[i, x, 0] * screws[jj, 3] + rot[i, x, 1] * screws[jj, 4]
                                + rot[i, x, 2] * screws[jj, 5])
        d0, d1, d2 = lines[jj, 0], lines[jj, 1], lines[jj, 2]
        m0, m1, m2 = _cross(pos[i, 0], pos[i, 1], pos[i, 2], d0, d1, d2)
        m0, m1, m2 = lines[jj, 3] + m0, lines[jj, 4] + m1, lines[jj, 5] + m2
        lines[jj, 3], lines[jj, 4], lines[jj, 5] = m0, m1, m2
        u, uu = dq[smp, jj], ddq[smp, jj]
        w0, w1, w2 = vel[i, 0] + d0 * u, vel[i, 1] + d1 * u, vel[i, 2] + d2 * u
        u0, u1, u2 = vel[i, 3] + m0 * u, vel[i, 4] + m1 * u, vel[i, 5] + m2 * u
        vel[i, 0], vel[i, 1], vel[i, 2], vel[i, 3], vel[i, 4], vel[i, 5] = w0, w1, w2, u0, u1, u2
        # commutator(line, V) = (w x d, w x m + u x d) with V = (w, u)
        c0, c1, c2 = _cross(w0, w1, w2, d0, d1, d2)
        e0, e1, e2 = _cross(w0, w1, w2, m0, m1, m2)
        f0, f1, f2 = _cross(u0, u1, u2, d0, d1, d2)
        acc[i, 0] += c0 * u + d0 * uu
        acc[i, 1] += c1 * u + d1 * uu
        acc[i, 2] += c2 * u + d2 * uu
        acc[i, 3] += (e0 + f0) * u + m0 * uu
        acc[i, 4] += (e1 + f1) * u + m1 * uu
        acc[i, 5] += (e2 + f2) * u + m2 * uu
        _exp_screw(screws[jj], q[smp, jj], er, et)  # (r, t) <- (r, t) exp(screw q)
        n0 = rot[i, 0, 0] * et[0] + rot[i, 0, 1] * et[1] + rot[i, 0, 2] * et[2] + pos[i, 0]
        n1 = rot[i, 1, 0] * et[0] + rot[i, 1, 1] * et[1] + rot[i, 1, 2] * et[2] + pos[i, 1]
        n2 = rot[i, 2, 0] * et[0] + rot[i, 2, 1] * et[1] + rot[i, 2, 2] * et[2] + pos[i, 2]
        pos[i, 0], pos[i, 1], pos[i, 2] = n0, n1, n2
        for x in range(3):
            r0, r1, r2 = rot[i, x, 0], rot[i, x, 1], rot[i, x, 2]
            for y in range(3):
                rot[i, x, y] = r0 * er[0, y] + r1 * er[1, y] + r2 * er[2, y]


@njit(cache=CACHE, inline="always")
def _bar(i, rot, pos, vel, acc, gravity, pair_m, pair_n, pts, pacc, xs):
    """Swapped bar lines ``xs[i] (6, 10)`` of body ``i`` (component first) from its motion.

    Points ``E_m = (e_m, w_m)``: the rotation's columns (directions, ``w = 0``) and the origin
    (``w = 1``); accelerations ``a = alpha x e + omega x (omega x e + w v) + w (dv - g)``.
    ``E_m v ddE_n = (w_m a_n, e_m x a_n)``, swapped: ``(e_m x a_n, w_m a_n)``.
    """
    w0, w1, w2, v0, v1, v2 = vel[i, 0], vel[i, 1], vel[i, 2], vel[i, 3], vel[i, 4], vel[i, 5]
    for m in range(4):
        if m < 3:
            e0, e1, e2, w = rot[i, 0, m], rot[i, 1, m], rot[i, 2, m], 0.0
        else:
            e0, e1, e2, w = pos[i, 0], pos[i, 1], pos[i, 2], 1.0
        pts[m, 0], pts[m, 1], pts[m, 2] = e0, e1, e2
        x0, x1, x2 = _cross(w0, w1, w2, e0, e1, e2)
        x0, x1, x2 = x0 + w * v0, x1 + w * v1, x2 + w * v2
        y0, y1, y2 = _cross(w0, w1, w2, x0, x1, x2)
        z0, z1, z2 = _cross(acc[i, 0], acc[i, 1], acc[i, 2], e0, e1, e2)
        pacc[m, 0] = y0 + z0 + w * (acc[i, 3] - gravity[0])
        pacc[m, 1] = y1 + z1 + w * (acc[i, 4] - gravity[1])
        pacc[m, 2] = y2 + z2 + w * (acc[i, 5] - gravity[2])
    for k in range(10):
        m, n = pair_m[k], pair_n[k]
        c0, c1, c2 = _cross(pts[m, 0], pts[m, 1], pts[m, 2], pacc[n, 0], pacc[n, 1], pacc[n, 2])
        d0 = d1 = d2 = 0.0
        if n == 3:
            d0, d1, d2 = pacc[m, 0], pacc[m, 1], pacc[m, 2]
        if m != n:
            f0, f1, f2 = _cross(pts[n, 0], pts[n, 1], pts[n, 2], pacc[m, 0], pacc[m, 1], pacc[m, 2])
            c0, c1, c2 = c0 + f0, c1 + f1, c2 + f2
            if m == 3:
                d0, d1, d2 = d0 + pacc[n, 0], d1 + pacc[n, 1], d2 + pacc[n, 2]
        xs[i, 0, k], xs[i, 1, k], xs[i, 2, k], xs[i, 3, k], xs[i, 4, k], xs[i, 5, k] = c0, c1, c2, d0, d1, d2


@njit(cache=CACHE, inline="always")
def _sample(smp, parent, q_index, ndofs, floating, screws, gravity, pair_m, pair_n, q, dq, ddq,
            rot, pos, vel, acc, lines, xs, er, et, pts, pacc):
    """Phase 1 for sample ``smp``: every body's kinematics and swapped bar lines."""
    for i in range(parent.shape[0]):
        _body(i, smp, parent, q_index, ndofs, floating, screws, q, dq, ddq, rot, pos, vel, acc, lines, er, et)
        _bar(i, rot, pos, vel, acc, gravity, pair_m, pair_n, pts, pacc, xs)


@njit(cache=CACHE, inline="always")
def _dot_block(out, smp, r, i, l0, l1, l2, l3, l4, l5, xs):
    """``out[smp, r, 10 i + k] = (l0..l5) . xs[i, :, k]`` for the ten columns of body ``i``."""
    base = 10 * i
    for k in range(10):
        out[smp, r, base + k] = (l0 * xs[i, 0, k] + l1 * xs[i, 1, k] + l2 * xs[i, 2, k]
                                 + l3 * xs[i, 3, k] + l4 * xs[i, 4, k] + l5 * xs[i, 5, k])


@njit(cache=CACHE, inline="always")
def _zero_block(out, smp, r, i):
    """Zero the ten columns of body ``i``, reading first: a zero stays unwritten (no store)."""
    for k in range(10 * i, 10 * i + 10):
        if out[smp, r, k] != 0.0:
            out[smp, r, k] = 0.0


@njit(cache=CACHE, inline="always")
def _copy_block(out, smp, r, i, c, xs):
    """``out[smp, r, 10 i + k] = xs[i, c, k]``: a floating root's basis line ``e_c``."""
    base = 10 * i
    for k in range(10):
        out[smp, r, base + k] = xs[i, c, k]


@njit(cache=CACHE, inline="always")
def _unit(floating, q_index, dof):
    """``(dof,)``: for a floating root's coordinates the index of their basis line ``e_c``, else -1."""
    unit = np.full(dof, -1, dtype=np.int64)
    for i in range(floating.shape[0]):
        if floating[i]:
            for c in range(6):
                unit[q_index[i] + c] = c
    return unit


@njit(cache=CACHE, inline="always")
def _moves(n, dof, anc_ptr, anc):
    """Dense ``(dof, n)`` mask: coordinate ``j`` moves body ``i``."""
    moves = np.zeros((dof, n), dtype=np.bool_)
    for i in range(n):
        for t in range(anc_ptr[i], anc_ptr[i + 1]):
            moves[anc[t], i] = True
    return moves


@njit(cache=CACHE, inline="always")
def _scratch(n, dof):
    """One thread's work arrays, carved from one allocation padded by 1 KiB on both sides.

    Small arrays allocated separately by two threads can share a cache line, and every write
    then bounces it between cores (false sharing: 2 threads ran 2.5x slower than 1).
    """
    pad = 128
    sizes = (9 * n, 3 * n, 6 * n, 6 * n, 6 * dof, 60 * n, 9, 3, 12, 12)
    buf = np.empty(sum(sizes) + 2 * pad)
    o = pad
    rot = buf[o:o + 9 * n].reshape((n, 3, 3))
    o += 9 * n
    pos = buf[o:o + 3 * n].reshape((n, 3))
    o += 3 * n
    vel = buf[o:o + 6 * n].reshape((n, 6))
    o += 6 * n
    acc = buf[o:o + 6 * n].reshape((n, 6))
    o += 6 * n
    lines = buf[o:o + 6 * dof].reshape((dof, 6))
    o += 6 * dof
    xs = buf[o:o + 60 * n].reshape((n, 6, 10))
    o += 60 * n
    er = buf[o:o + 9].reshape((3, 3))
    et = buf[o + 9:o + 12]
    pts = buf[o + 12:o + 24].reshape((4, 3))
    pacc = buf[o + 24:o + 36].reshape((4, 3))
    return rot, pos, vel, acc, lines, xs, er, et, pts, pacc


@njit(cache=CACHE, parallel=True)
def tree(parent, q_index, ndofs, floating, screws, gravity, anc_ptr, anc, pair_m, pair_n, q, dq, ddq, out):
    """TP regressor of a tree into ``out (S, dof, 10 n)`` (every entry right, zeros read before written)."""
    n, dof, s = parent.shape[0], screws.shape[0], q.shape[0]
    moves = _moves(n, dof, anc_ptr, anc)
    unit = _unit(floating, q_index, dof)
    nblocks = (s + _BLOCK - 1) // _BLOCK
    for blk in prange(nblocks):
        rot, pos, vel, acc, lines, xs, er, et, pts, pacc = _scratch(n, dof)
        for smp in range(blk * _BLOCK, min(s, (blk + 1) * _BLOCK)):
            _sample(smp, parent, q_index, ndofs, floating, screws, gravity, pair_m, pair_n, q, dq, ddq,
                    rot, pos, vel, acc, lines, xs, er, et, pts, pacc)
            for j in range(dof):
                c = unit[j]
                l0, l1, l2, l3, l4, l5 = lines[j, 0], lines[j, 1], lines[j, 2], lines[j, 3], lines[j, 4], lines[j, 5]
                for i in range(n):
                    if not moves[j, i]:
                        _zero_block(out, smp, j, i)
                    elif c >= 0:
                        _copy_block(out, smp, j, i, c, xs)
                    else:
                        _dot_block(out, smp, j, i, l0, l1, l2, l3, l4, l5, xs)


@njit(cache=CACHE, parallel=True)
def closed(parent, q_index, ndofs, floating, screws, gravity, anc_ptr, anc, pair_m, pair_n, q, dq, ddq, G,
           out):
    """Closed-loop TP regressor into ``out (S, na, 10 n)``: lines ``L~_a^i = sum_k L_k^i G[k, a]``."""
    n, dof, s, na = parent.shape[0], screws.shape[0], q.shape[0], G.shape[2]
    nblocks = (s + _BLOCK - 1) // _BLOCK
    for blk in prange(nblocks):
        rot, pos, vel, acc, lines, xs, er, et, pts, pacc = _scratch(n, dof)
        lt = np.empty(6 + 256)[128:134]  # padded: no cache line shared with another thread
        for smp in range(blk * _BLOCK, min(s, (blk + 1) * _BLOCK)):
            _sample(smp, parent, q_index, ndofs, floating, screws, gravity, pair_m, pair_n, q, dq, ddq,
                    rot, pos, vel, acc, lines, xs, er, et, pts, pacc)
            for a in range(na):
                for i in range(n):
                    lt[:] = 0.0
                    for t in range(anc_ptr[i], anc_ptr[i + 1]):
                        k = anc[t]
                        gk = G[smp, k, a]
                        for c in range(6):
                            lt[c] += lines[k, c] * gk
                    _dot_block(out, smp, a, i, lt[0], lt[1], lt[2], lt[3], lt[4], lt[5], xs)


@njit(cache=CACHE, inline="always")
def _emit_projected(out, smp, r, i, l0, l1, l2, l3, l4, l5, c, xs, y10, cptr, ccol, cmat):
    """``out[smp, r, ccol[t]] += (L . xs[i])[k] cmat[t, k]`` over the projected columns of body ``i``."""
    for k in range(10):
        if c >= 0:
            y10[k] = xs[i, c, k]
        else:
            y10[k] = (l0 * xs[i, 0, k] + l1 * xs[i, 1, k] + l2 * xs[i, 2, k]
                      + l3 * xs[i, 3, k] + l4 * xs[i, 4, k] + l5 * xs[i, 5, k])
    for t in range(cptr[i], cptr[i + 1]):
        v = 0.0
        for k in range(10):
            v += y10[k] * cmat[t, k]
        out[smp, r, ccol[t]] += v


@njit(cache=CACHE, parallel=True)
def tree_projected(parent, q_index, ndofs, floating, screws, gravity, anc_ptr, anc, pair_m, pair_n, q, dq, ddq,
                   rowsel, cptr, ccol, cmat, out):
    """``out (S, len(rowsel), m) = Y[:, rowsel] @ P`` without forming ``Y``.

    ``P (10 n, m)`` is given per body in CSR form: body ``i``'s ten rows of column ``ccol[t]`` are
    ``cmat[t]`` for ``t`` in ``cptr[i]:cptr[i + 1]`` (zero elsewhere).
    """
    n, dof, s = parent.shape[0], screws.shape[0], q.shape[0]
    moves = _moves(n, dof, anc_ptr, anc)
    unit = _unit(floating, q_index, dof)
    nblocks = (s + _BLOCK - 1) // _BLOCK
    for blk in prange(nblocks):
        rot, pos, vel, acc, lines, xs, er, et, pts, pacc = _scratch(n, dof)
        y10 = np.empty(10 + 256)[128:138]  # padded: no cache line shared with another thread
        for smp in range(blk * _BLOCK, min(s, (blk + 1) * _BLOCK)):
            _sample(smp, parent, q_index, ndofs, floating, screws, gravity, pair_m, pair_n, q, dq, ddq,
                    rot, pos, vel, acc, lines, xs, er, et, pts, pacc)
            out[smp] = 0.0
            for r in range(rowsel.shape[0]):
                j = rowsel[r]
                l0, l1, l2, l3, l4, l5 = lines[j, 0], lines[j, 1], lines[j, 2], lines[j, 3], lines[j, 4], lines[j, 5]
                for i in range(n):
                    if moves[j, i] and cptr[i + 1] > cptr[i]:
                        _emit_projected(out, smp, r, i, l0, l1, l2, l3, l4, l5, unit[j], xs, y10, cptr, ccol, cmat)


@njit(cache=CACHE, parallel=True)
def closed_projected(parent, q_index, ndofs, floating, screws, gravity, anc_ptr, anc, pair_m, pair_n, q, dq, ddq,
                     G, cptr, ccol, cmat, out):
    """``out (S, na, m) = Y_closed @ P`` without forming the closed-loop regressor.

    ``P`` in CSR form as in :func:`tree_projected`.
    """
    n, dof, s, na = parent.shape[0], screws.shape[0], q.shape[0], G.shape[2]
    nblocks = (s + _BLOCK - 1) // _BLOCK
    for blk in prange(nblocks):
        rot, pos, vel, acc, lines, xs, er, et, pts, pacc = _scratch(n, dof)
        y10 = np.empty(10 + 256)[128:138]
        lt = np.empty(6 + 256)[128:134]
        for smp in range(blk * _BLOCK, min(s, (blk + 1) * _BLOCK)):
            _sample(smp, parent, q_index, ndofs, floating, screws, gravity, pair_m, pair_n, q, dq, ddq,
                    rot, pos, vel, acc, lines, xs, er, et, pts, pacc)
            out[smp] = 0.0
            for a in range(na):
                for i in range(n):
                    if cptr[i + 1] == cptr[i]:
                        continue
                    lt[:] = 0.0
                    for t in range(anc_ptr[i], anc_ptr[i + 1]):
                        k = anc[t]
                        gk = G[smp, k, a]
                        for c in range(6):
                            lt[c] += lines[k, c] * gk
                    _emit_projected(out, smp, a, i, lt[0], lt[1], lt[2], lt[3], lt[4], lt[5], -1, xs, y10,
                                    cptr, ccol, cmat)


@njit(cache=CACHE, parallel=True)
def tree_forces(parent, q_index, ndofs, floating, screws, gravity, anc_ptr, anc, pair_m, pair_n, q, dq, ddq,
                pi, rowsel, out):
    """``out (S, len(rowsel)) = Y[:, rowsel] @ pi`` without forming ``Y``: ``O(n)`` per sample.

    Each body's wrench line ``W_i = X_i pi_i`` (its ten swapped bar lines weighted by its ten
    parameters ``pi (n, 10)``), summed up the tree (children after parents, so backwards), then
    ``tau_j = L_j . W_body(j)`` (a floating root's basis line ``e_c``: component ``c``).
    """
    n, dof, s = parent.shape[0], screws.shape[0], q.shape[0]
    unit = _unit(floating, q_index, dof)
    body_of = np.empty(dof, dtype=np.int64)
    for i in range(n):
        for j in range(q_index[i], q_index[i] + ndofs[i]):
            body_of[j] = i
    nblocks = (s + _BLOCK - 1) // _BLOCK
    for blk in prange(nblocks):
        rot, pos, vel, acc, lines, xs, er, et, pts, pacc = _scratch(n, dof)
        w = np.zeros((n + 32, 6))[16:16 + n]  # padded: no cache line shared with another thread
        for smp in range(blk * _BLOCK, min(s, (blk + 1) * _BLOCK)):
            for i in range(n):
                _body(i, smp, parent, q_index, ndofs, floating, screws, q, dq, ddq, rot, pos, vel, acc, lines, er, et)
                _bar(i, rot, pos, vel, acc, gravity, pair_m, pair_n, pts, pacc, xs)
                for c in range(6):
                    v = 0.0
                    for k in range(10):
                        v += xs[i, c, k] * pi[i, k]
                    w[i, c] = v
            for i in range(n - 1, -1, -1):
                p = parent[i]
                if p >= 0:
                    for c in range(6):
                        w[p, c] += w[i, c]
            for r in range(rowsel.shape[0]):
                j = rowsel[r]
                b = body_of[j]
                if unit[j] >= 0:
                    out[smp, r] = w[b, unit[j]]
                else:
                    out[smp, r] = (lines[j, 0] * w[b, 0] + lines[j, 1] * w[b, 1] + lines[j, 2] * w[b, 2]
                                   + lines[j, 3] * w[b, 3] + lines[j, 4] * w[b, 4] + lines[j, 5] * w[b, 5])


#: columns one thread filters at a time (:func:`sosfilt_rows`)
_FILTER_COLUMNS = 32


@njit(cache=CACHE, parallel=True)
def sosfilt_rows(sos, x, zi, backward):
    """Second-order sections along axis 0 of ``x (S, C)``, in place, column blocks in parallel.

    ``zi (n_sections, 2, C)``: the sections' states, updated in place. ``backward``: the samples
    from last to first. Per sample and section the arithmetic of ``scipy.signal.sosfilt``
    (transposed direct form II, in its order), so the result is scipy's.
    """
    s, c = x.shape
    nsec = sos.shape[0]
    nblocks = (c + _FILTER_COLUMNS - 1) // _FILTER_COLUMNS
    for blk in prange(nblocks):
        c0, c1 = blk * _FILTER_COLUMNS, min(c, (blk + 1) * _FILTER_COLUMNS)
        for k in range(s):
            n = s - 1 - k if backward else k
            for j in range(nsec):
                b0, b1, b2, a1, a2 = sos[j, 0], sos[j, 1], sos[j, 2], sos[j, 4], sos[j, 5]
                for col in range(c0, c1):
                    xn = x[n, col]
                    y = b0 * xn + zi[j, 0, col]
                    zi[j, 0, col] = b1 * xn - a1 * y + zi[j, 1, col]
                    zi[j, 1, col] = b2 * xn - a2 * y
                    x[n, col] = y
