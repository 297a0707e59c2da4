"""The tetrahedral-point (TP) regressor (the paper's Algorithm DR).

Coefficient (eq. "basic coeff"): ``R[j, i, m, n] = L_j^i ^ (E_m^i v ddE_n^i)`` with the
tetrahedral points ``E^i = g_i [x y z O]`` of body ``i`` (spatial assignment: the world
frame at q = 0) and their accelerations including gravity as an extra acceleration of
Euclidean points, ``ddE_n = (dV^ + V^ V^) E_n - w_n (gravity, 0)``.

Matrix form: ``Y[:, j, 10 i + k] = bar(R)[j, i, k]`` in the paper's hat/bar order, so that
``tau = Y @ pi`` with ``pi`` the spatial pseudo-inertia parameters at q = 0
(``Robot.parameters("paper")``).
"""

from __future__ import annotations

import numpy as np

from ..errors import BaseparamsError
from ..kinematics.tree import TreeState, as_states, forward_kinematics
from ..model.inertia import HAT_INDEX
from ..model.robot import Robot
from ..pga import hat, join, swap
from ..pga.linalg import cross3
from . import compiled

_M = np.array([m for m, _ in HAT_INDEX])
_N = np.array([n for _, n in HAT_INDEX])
_OFF = (_M != _N)[:, None]


def point_accelerations(robot: Robot, state: TreeState) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedral points and their accelerations, gravity included.

    Parameters
    ----------
    robot : Robot
        The robot (its gravity, world frame [m/s^2]).
    state : TreeState
        Kinematics of ``S`` samples.

    Returns
    -------
    E : ndarray, shape ``(S, n, 4, 4)``
        Each body's tetrahedral points as columns ``x, y, z, O`` (world frame; the spatial
        assignment: the identity at q = 0).
    ddE : ndarray, shape ``(S, n, 4, 4)``
        Their accelerations ``(dV^ + V^ V^) E`` minus gravity on the point ``O`` (last row zero).
    """
    e = state.g
    vh = hat(state.V)
    acc = (hat(state.dV) + vh @ vh) @ e
    acc[..., :3, 3] -= robot.gravity
    return e, acc


def bar_lines(e: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """The ten lines ``bar(E_m v ddE_n)`` per body, in the paper's bar order.

    Parameters
    ----------
    e, acc : ndarray, shape ``(S, n, 4, 4)``
        Points and accelerations (:func:`point_accelerations`).

    Returns
    -------
    ndarray, shape ``(S, n, 10, 6)``
        Lines ``(direction, moment)`` in the basis ``e23 e31 e12 e01 e02 e03``.
    """
    return swap(_bar_lines_swapped(e, acc))


def _bar_lines_swapped(e: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """``swap(bar(E_m v ddE_n))`` ``(S, n, 10, 6)``, built from the 16 products ``e_m x a_n``.

    With ``E_m = (e_m, w_m)`` (w = 0, 0, 0, 1) and ``ddE_n = (a_n, 0)``:
    ``E_m v ddE_n = (w_m a_n, e_m x a_n)``; only pairs with O carry a direction part.
    """
    pts = np.swapaxes(e[..., :3, :], -1, -2)  # (S, n, 4, 3)
    accs = np.swapaxes(acc[..., :3, :], -1, -2)
    c = cross3(pts[..., :, None, :], accs[..., None, :, :])  # (S, n, 4, 4, 3): e_m x a_n
    out = np.zeros(e.shape[:-2] + (10, 6))
    out[..., :3] = c[..., _M, _N, :]
    out[..., _OFF[:, 0], :3] += c[..., _N[_OFF[:, 0]], _M[_OFF[:, 0]], :]
    out[..., 6:9, 3:] = accs[..., :3, :]  # (m, O) pairs: direction a_m
    out[..., 9, 3:] = accs[..., 3, :]  # (O, O): direction a_O
    return out


def _subtree_slices(robot: Robot) -> list[tuple[int, int]] | None:
    """Per coordinate, the contiguous range of bodies it moves, or None if not contiguous."""
    end = robot.subtree_end  # O(n): the support matrix's rows, without forming it
    body = robot.dof_body
    if np.any(end[body] < 0):
        return None
    return [(int(b), int(end[b])) for b in body.tolist()]


#: regressor backends: ``auto`` (compiled for large batches when numba is installed, see
#: :func:`use_compiled`), ``numpy``, ``compiled`` (numba required)
BACKENDS = ("auto", "numpy", "compiled")


def use_compiled(backend: str, work: int) -> bool:
    """Whether a batch goes to the compiled kernel.

    Parameters
    ----------
    backend : {"auto", "numpy", "compiled"}
        The caller's choice (:data:`BACKENDS`).
    work : int
        Size of the batch: samples x rows x bodies (the numpy path costs ~0.1-0.3 us per unit).

    Returns
    -------
    bool
        ``True`` for ``compiled``; for ``auto``, when numba is installed and either the kernels
        are already loaded in this process or ``work >= compiled.MIN_WORK`` (where the numpy path
        would cost more than loading them, ~0.3 s per process).

    Raises
    ------
    BaseparamsError
        An unknown backend, or ``compiled`` without numba (names the extra that installs it).
    """
    if not isinstance(backend, str) or backend not in BACKENDS:
        raise BaseparamsError(f"unknown regressor backend {str(backend)[:40]!r}; choose one of {', '.join(BACKENDS)}")
    if backend == "numpy":
        return False
    if backend == "compiled":
        if not compiled.available():
            raise BaseparamsError("the compiled regressor needs numba: pip install 'baseparams[fast]'")
        return True
    return compiled.available() and (compiled.loaded() or work >= compiled.MIN_WORK)


def regressor(robot: Robot, q, dq=None, ddq=None, *, state: TreeState | None = None, chunk: int = 1024,
              out: np.ndarray | None = None, backend: str = "auto") -> np.ndarray:
    """TP regressor of a tree in matrix form (the paper's Algorithm DR).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies, ``dof`` coordinates); loops, if any, are cut (the spanning
        tree's regressor: :func:`closed_regressor` closes them).
    q : array_like, shape ``(S, dof)`` or ``(dof,)``
        Positions (a floating root's six first: its twist coordinates).
    dq, ddq : array_like, shape ``(S, dof)`` or ``(dof,)``, optional
        Velocities and accelerations (a floating root's: quasi-velocities); default zero.
    state : TreeState, optional
        Precomputed kinematics of ``q, dq, ddq`` (numpy path; ``q, dq, ddq`` are then ignored).
    chunk : int
        Samples per numpy batch (memory, cache).
    out : ndarray, shape ``(S, dof, 10 n)``, optional
        A C-contiguous float64 buffer to fill and return, e.g. the previous call's output:
        every entry is set (the compiled kernel reads the zero blocks and writes only those not
        already zero).
    backend : {"auto", "numpy", "compiled"}
        ``auto``: the compiled kernel (:mod:`baseparams.regressor.compiled`, numba) for large
        batches when numba is installed (:func:`use_compiled`), numpy for small ones (the
        compiled path costs ~0.3 s of import per process).

    Returns
    -------
    Y : ndarray, shape ``(S, dof, 10 n)``
        ``tau = Y @ pi``, gravity included; columns in the ``paper`` convention (spatial
        pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at
        q = 0: ``robot.parameters("paper")``); ``Y[:, j, 10 i + k] = bar(R)[j, i, k]``.

    Raises
    ------
    BaseparamsError
        Wrong shapes, NaN or inf in the states, an unknown backend or a wrong ``out``.

    Notes
    -----
    numpy path: each coordinate's row is built only over the bodies it moves; the floating
    root's lines are the constant basis lines, so its rows are the bar lines themselves.
    """
    if state is None:
        q, dq, ddq = as_states(robot.dof, q, dq, ddq)
        s = q.shape[0]
        if use_compiled(backend, s * robot.dof * robot.n):
            return compiled.tree_regressor(robot, q, dq, ddq, out=_checked_out(out, (s, robot.dof, 10 * robot.n)))
        if s > chunk:
            out = _checked_out(out, (s, robot.dof, 10 * robot.n)) if out is not None else \
                np.empty((s, robot.dof, 10 * robot.n))
            for k in range(0, s, chunk):
                out[k:k + chunk] = regressor(robot, q[k:k + chunk], dq[k:k + chunk], ddq[k:k + chunk],
                                             chunk=chunk, backend="numpy")
            return out
        state = forward_kinematics(robot, q, dq, ddq)
    y = _regressor_numpy(robot, state)
    if out is None:
        return y
    out = _checked_out(out, y.shape)
    out[...] = y
    return out


def _checked_out(out: np.ndarray | None, shape: tuple[int, ...]) -> np.ndarray | None:
    """``out`` after checking it is a writeable C-contiguous float64 array of ``shape``."""
    if out is None:
        return None
    if (not isinstance(out, np.ndarray) or out.shape != shape or out.dtype != np.float64
            or not out.flags.c_contiguous or not out.flags.writeable):
        got = f"{out.dtype} {out.shape}" if isinstance(out, np.ndarray) else type(out).__name__
        raise BaseparamsError(f"out must be a writeable C-contiguous float64 array of shape {shape}, got {got}")
    return out


def _regressor_numpy(robot: Robot, state: TreeState) -> np.ndarray:
    """The numpy regressor ``(S, dof, 10 n)`` of one batch of states."""
    e, acc = point_accelerations(robot, state)
    xs = _bar_lines_swapped(e, acc)  # (S, n, 10, 6): wedge(L, X) = L . swap(X)
    s, n = xs.shape[:2]
    slices = _subtree_slices(robot)
    if slices is None:  # general topological order: dense product, masked
        y = np.matmul(state.lines, xs.reshape(s, n * 10, 6).transpose(0, 2, 1)).reshape(s, -1, n, 10)
        y *= state.support[None, :, :, None]
        return y.reshape(s, -1, n * 10)
    xc = np.ascontiguousarray(np.moveaxis(xs, -1, 1))  # (S, 6, n, 10)
    y = np.zeros((s, robot.dof, n, 10))
    is_f = [robot.jtype[b] == "F" for b in robot.dof_body]
    for j, (a, b) in enumerate(slices):
        if is_f[j]:  # constant basis line e_j: the row is one coordinate of the bar lines
            y[:, j, a:b] = xc[:, j % 6, a:b]
            continue
        line = state.lines[:, j, :, None, None]
        row = y[:, j, a:b]
        np.multiply(line[:, 0], xc[:, 0, a:b], out=row)
        for c in range(1, 6):
            row += line[:, c] * xc[:, c, a:b]
    return y.reshape(s, -1, n * 10)


def regressor_tensor(robot: Robot, q, dq=None, ddq=None) -> np.ndarray:
    """TP regressor in tensor form, coefficient by coefficient (eq. "basic coeff").

    ``R[s, j, i, m, n] = L_j^i ^ (E_m^i v ddE_n^i)``: a slow, literal reference for tests.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies, ``dof`` coordinates).
    q : array_like, shape ``(S, dof)`` or ``(dof,)``
        Positions.
    dq, ddq : array_like, shape ``(S, dof)`` or ``(dof,)``, optional
        Velocities and accelerations; default zero.

    Returns
    -------
    R : ndarray, shape ``(S, dof, n, 4, 4)``
        ``bar(R)`` is the matrix form (:func:`regressor`).
    """
    from ..pga import wedge

    state = forward_kinematics(robot, q, dq, ddq)
    e, acc = point_accelerations(robot, state)
    pts = np.swapaxes(e, -1, -2)
    accs = np.swapaxes(acc, -1, -2)
    lines4 = join(pts[:, :, :, None, :], accs[:, :, None, :, :])  # (S, n, 4, 4, 6)
    jl = state.jacobian_lines()  # (S, dof, n, 6)
    return wedge(jl[:, :, :, None, None, :], lines4[:, None])


def bar(r: np.ndarray) -> np.ndarray:
    """The paper's bar operator (off-diagonal pairs summed), in the hat/bar order.

    Parameters
    ----------
    r : ndarray, shape ``(*, 4, 4)``
        A tensor-form coefficient block (:func:`regressor_tensor`).

    Returns
    -------
    ndarray, shape ``(*, 10)``
        ``r[m, n] + r[n, m]`` for ``m != n``, ``r[m, m]`` on the diagonal.
    """
    out = r[..., _M, _N]
    return out + np.where(_OFF[:, 0], r[..., _N, _M], 0.0)


def generalized_forces(robot: Robot, q, dq=None, ddq=None, params=None, *, rows=None, backend: str = "auto",
                       max_bytes: float = 32e6) -> np.ndarray:
    """Inverse dynamics ``tau = Y pi`` of a tree without forming the regressor ``Y``.

    Each body's wrench line ``W_i = X_i pi_i`` (its ten swapped bar lines, weighted by its ten
    parameters), summed up the tree, paired with each coordinate's current line:
    ``tau_j = L_j . sum_{i moved by j} W_i``, the rows of eq. "basic coeff" contracted with
    ``pi`` body by body. Work and memory ``O(S n)``, not the regressor's ``O(S dof n)``.

    Parameters
    ----------
    robot : Robot
        The robot (a tree; loops, if any, cut).
    q : array_like, shape ``(S, dof)`` or ``(dof,)``
        Positions (a floating root's six first: its twist coordinates).
    dq, ddq : array_like, shape ``(S, dof)`` or ``(dof,)``, optional
        Velocities and accelerations (a floating root's: quasi-velocities); default zero.
    params : array_like, shape ``(10 n,)``, optional
        Parameters in the ``paper`` convention; default the robot's own.
    rows : array_like of int, optional
        The coordinates whose generalized forces are returned, in order (default all ``dof``).
    backend : {"auto", "numpy", "compiled"}
        As for :func:`regressor` (``auto``: the compiled kernel for large batches).
    max_bytes : float
        Largest batch of kinematics formed at once by the numpy path [bytes] (about 1 kB per
        body and sample).

    Returns
    -------
    tau : ndarray, shape ``(S, len(rows))``
        Generalized forces [N m or N], gravity included; equal to ``regressor(...)[:, rows] @ pi``.

    Raises
    ------
    BaseparamsError
        Wrong shapes, NaN or inf in the states or parameters, rows out of range.
    """
    q, dq, ddq = as_states(robot.dof, q, dq, ddq)
    pi = robot.parameters("paper") if params is None else np.asarray(params, dtype=float).reshape(-1)
    if pi.shape != (10 * robot.n,) or not np.all(np.isfinite(pi)):
        raise BaseparamsError(f"params must be {10 * robot.n} finite numbers (paper convention), got {pi.shape}")
    rowsel = np.arange(robot.dof) if rows is None else np.asarray(rows, dtype=np.int64).reshape(-1)
    if rowsel.size and (rowsel.min() < 0 or rowsel.max() >= robot.dof):
        raise BaseparamsError(f"rows must be coordinates 0..{robot.dof - 1}, got {rowsel.tolist()[:10]}")
    s = q.shape[0]
    if use_compiled(backend, s * robot.dof * robot.n):
        return compiled.tree_forces(robot, q, dq, ddq, pi, rowsel)
    out = np.empty((s, len(rowsel)))
    step = max(1, int(max_bytes // (1024 * max(robot.n, 1))))
    p = pi.reshape(robot.n, 10)
    body = np.asarray(robot.dof_body)[rowsel]
    for k in range(0, s, step):
        sl = slice(k, k + step)
        state = forward_kinematics(robot, q[sl], dq[sl], ddq[sl])
        w = np.einsum("snkc,nk->snc", _bar_lines_swapped(*point_accelerations(robot, state)), p)  # (S, n, 6)
        for i in range(robot.n - 1, 0, -1):  # subtree sums: children after parents
            if robot.parent[i] >= 0:
                w[:, robot.parent[i]] += w[:, i]
        out[sl] = np.einsum("sjc,sjc->sj", state.lines[:, rowsel], w[:, body])
    return out


def closed_regressor(robot: Robot, closed, *, out: np.ndarray | None = None, backend: str = "auto") -> np.ndarray:
    """TP regressor of a closed-loop robot with respect to its actuated coordinates.

    The Jacobian lines include ``dq_k/dq_a`` (paper eq. "jacobian line"):
    ``L~_a^i = sum_k L_k^i G[k, a]``.

    Parameters
    ----------
    robot : Robot
        The robot with loops (``n`` bodies, ``dof`` tree coordinates, ``na`` actuated).
    closed : ClosedStates
        Closed-loop states and their ``G = dq/dq_a`` (:class:`baseparams.kinematics.loops.ClosedStates`).
    out : ndarray, shape ``(S, na, 10 n)``, optional
        A C-contiguous float64 buffer to fill and return.
    backend : {"auto", "numpy", "compiled"}
        As for :func:`regressor`.

    Returns
    -------
    Y : ndarray, shape ``(S, na, 10 n)``
        Columns in the ``paper`` convention, gravity included.
    """
    s, na = closed.G.shape[0], closed.G.shape[2]
    shape = (s, na, 10 * robot.n)
    if use_compiled(backend, s * na * robot.n):
        return compiled.closed_regressor(robot, closed.q, closed.dq, closed.ddq, closed.G,
                                         out=_checked_out(out, shape))
    state = forward_kinematics(robot, closed.q, closed.dq, closed.ddq)
    e, acc = point_accelerations(robot, state)
    xs = _bar_lines_swapped(e, acc)  # (S, n, 10, 6): wedge(L, X) = L . swap(X)
    n = robot.n
    # L~[s, a, i] = sum_k G[s, k, a] support[k, i] L[s, k]: one batched matmul
    moved = state.lines[:, :, None, :] * state.support[None, :, :, None]  # (S, dof, n, 6)
    lines = np.matmul(np.swapaxes(closed.G, 1, 2), moved.reshape(s, -1, n * 6)).reshape(s, na, n, 6)
    out = np.empty(shape) if out is None else _checked_out(out, shape)
    y = out.reshape(s, na, n, 10)
    xt = np.swapaxes(xs, -1, -2)  # (S, n, 6, 10)
    for i in range(n):  # per body: (S, na, 6) @ (S, 6, 10), written in place (a loop over bodies)
        np.matmul(lines[:, :, i, :], xt[:, i], out=y[:, :, i, :])
    return out


#: columns from which a map's product dominates the numpy path (:func:`projected_regressor`)
WIDE_MAP = 128


def projected_regressor(robot: Robot, q, dq=None, ddq=None, *, P: np.ndarray, rows=None,
                        out: np.ndarray | None = None, backend: str = "auto", chunk: int = 1024) -> np.ndarray:
    """``Y[:, rows] @ P``: the TP regressor mapped to other columns (e.g. base parameters).

    The compiled kernel never forms the ``10 n``-column regressor: each body's ten columns are
    projected as they are computed, so a base regressor costs about as much as the regressor
    itself and its memory is that of its own output.

    Parameters
    ----------
    robot : Robot
        The robot (a tree: loops cut; :func:`closed_projected_regressor` closes them).
    q : array_like, shape ``(S, dof)`` or ``(dof,)``
        Positions.
    dq, ddq : array_like, shape ``(S, dof)`` or ``(dof,)``, optional
        Velocities and accelerations; default zero.
    P : ndarray or scipy.sparse matrix, shape ``(10 n, m)``
        Column map; its rows in the ``paper`` convention (spatial pseudo-inertia entries of each
        body, world frame at q = 0), e.g. the base-parameter map of
        :meth:`baseparams.Analysis.base_regressor` (sparse for a large tree: no ``(10 n, m)``
        array is formed).
    rows : array_like of int, optional
        Coordinates whose rows are kept, in order (default all ``dof``).
    out : ndarray, shape ``(S, len(rows), m)``, optional
        A C-contiguous float64 buffer to fill and return.
    backend : {"auto", "numpy", "compiled"}
        As for :func:`regressor`.
    chunk : int
        Samples per numpy batch (memory).

    Returns
    -------
    ndarray, shape ``(S, len(rows), m)``
        ``Y[:, rows] @ P`` with ``Y`` the regressor of :func:`regressor` (gravity included).

    Raises
    ------
    BaseparamsError
        Wrong shapes of the states, of ``P`` or of ``out``; rows out of range.
    """
    q, dq, ddq = as_states(robot.dof, q, dq, ddq)
    P = _checked_map(P, robot.n)
    rowsel = np.arange(robot.dof) if rows is None else np.asarray(rows, dtype=np.int64).reshape(-1)
    if rowsel.size and (rowsel.min() < 0 or rowsel.max() >= robot.dof):
        raise BaseparamsError(f"rows must be coordinates 0..{robot.dof - 1}, got {rowsel.tolist()}")
    s = q.shape[0]
    shape = (s, len(rowsel), P.shape[1])
    out = _checked_out(out, shape)
    # the numpy path's product with P costs about P.shape[1] / 8 regressors (a 60-link chain's 596 columns:
    # 28 us per sample, row and body, not 0.15): wide maps go compiled sooner (not an arm's 54 columns: the
    # compiler's 100 MB would be most of a short log's identification)
    wide = P.shape[1] // 8 if P.shape[1] >= WIDE_MAP else 1
    if use_compiled(backend, s * len(rowsel) * robot.n * wide):
        return compiled.tree_projected(robot, q, dq, ddq, P, rowsel, out=out)
    out = np.empty(shape) if out is None else out
    for k in range(0, s, chunk):
        sl = slice(k, k + chunk)
        y = regressor(robot, q[sl], dq[sl], ddq[sl], backend="numpy")[:, rowsel]
        if hasattr(P, "tocsr"):  # a sparse map (a large tree's base map): P^T y^T
            out[sl] = (P.T @ y.reshape(-1, y.shape[-1]).T).T.reshape(y.shape[0], y.shape[1], -1)
        else:
            out[sl] = y @ P
    return out


def closed_projected_regressor(robot: Robot, closed, *, P: np.ndarray, out: np.ndarray | None = None,
                               backend: str = "auto") -> np.ndarray:
    """``Y_closed @ P``: the closed-loop regressor mapped to other columns (e.g. base parameters).

    Parameters
    ----------
    robot : Robot
        The robot with loops (``n`` bodies, ``na`` actuated coordinates).
    closed : ClosedStates
        Closed-loop states (:func:`baseparams.kinematics.loops.close_loops`).
    P : ndarray, shape ``(10 n, m)``
        Column map, rows in the ``paper`` convention.
    out : ndarray, shape ``(S, na, m)``, optional
        A C-contiguous float64 buffer to fill and return.
    backend : {"auto", "numpy", "compiled"}
        As for :func:`regressor`.

    Returns
    -------
    ndarray, shape ``(S, na, m)``
        ``closed_regressor(robot, closed) @ P``.

    Raises
    ------
    BaseparamsError
        A wrong ``P`` or ``out``.
    """
    P = _checked_map(P, robot.n)
    s, na = closed.G.shape[0], closed.G.shape[2]
    out = _checked_out(out, (s, na, P.shape[1]))
    if use_compiled(backend, s * na * robot.n):
        return compiled.closed_projected(robot, closed.q, closed.dq, closed.ddq, closed.G, P, out=out)
    y = closed_regressor(robot, closed, backend="numpy") @ P
    if out is None:
        return y
    out[...] = y
    return out


def _checked_map(P, n: int) -> np.ndarray:
    """``P`` as a float ``(10 n, m)`` array (a scipy.sparse matrix stays sparse, CSR), or one clear error."""
    if hasattr(P, "tocsr"):
        P = P.tocsr().astype(float)
        if P.shape[0] != 10 * n:
            raise BaseparamsError(f"P must have shape (10 n, m) = ({10 * n}, m), got {P.shape}")
        if not np.all(np.isfinite(P.data)):
            raise BaseparamsError("P contains NaN or inf")
        return P
    P = np.asarray(P, dtype=float)
    if P.ndim != 2 or P.shape[0] != 10 * n:
        raise BaseparamsError(f"P must have shape (10 n, m) = ({10 * n}, m), got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise BaseparamsError("P contains NaN or inf")
    return P
