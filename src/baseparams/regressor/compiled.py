"""The TP regressor as one fused compiled loop per sample (numba, cached on disk).

The same regressor as :func:`baseparams.regressor.tp.regressor` (the paper's Algorithm DR,
eq. "basic coeff" in matrix form), computed sample by sample in one pass over the bodies:
product-of-exponentials kinematics (:mod:`baseparams.kinematics.tree`), the accelerations of
the four tetrahedral points with gravity, the ten bar lines ``swap(bar(E_m v ddE_n))`` and
their contraction with the Jacobian lines, written straight into the output rows. Only the
blocks a coordinate moves are computed; the others are zero.

numba is an optional dependency (``pip install baseparams[fast]``): importing it and loading
the cached machine code costs ~0.3-0.5 s per process, so :func:`baseparams.regressor.tp.regressor`
loads the kernels only for batches of at least :data:`MIN_WORK` (samples x rows x bodies), or
when they are already loaded. The first call on a
machine compiles (~10-20 s) and caches the result next to this file (or in
``NUMBA_CACHE_DIR``); later processes load it. Where nothing can be cached (a read-only install
with an unwritable HOME / ``NUMBA_CACHE_DIR``) the kernels are compiled in memory in each process
and a :class:`CompileCacheWarning` says so once. A call that will compile (nothing in memory, nothing in
the disk cache: :func:`will_compile`) is announced in one line on stderr first, once per kernel and
process (:data:`COMPILE_NOTE`): otherwise the machine's first run is ~20 s of silence.
"""

from __future__ import annotations

import importlib.util
import sys
import warnings
from functools import lru_cache

import numpy as np

from ..model.inertia import HAT_INDEX
from ..model.robot import Robot

#: batch size (samples x rows x bodies) from which ``backend="auto"`` loads the compiled kernel:
#: below it the numpy path (~0.15 us per unit) costs less than loading numba (~0.3 s per process)
MIN_WORK = 2_000_000


def available() -> bool:
    """Whether numba can be imported (without importing it).

    Returns
    -------
    bool
        ``True`` when the ``numba`` package is installed.
    """
    return importlib.util.find_spec("numba") is not None


def loaded() -> bool:
    """Whether the kernels are already loaded in this process (then they cost nothing more).

    Returns
    -------
    bool
        ``True`` once :mod:`baseparams.regressor.kernels` has been imported.
    """
    return "baseparams.regressor.kernels" in sys.modules


class CompileCacheWarning(UserWarning):
    """numba cannot cache the compiled kernels on disk: they are compiled in memory in each process."""


@lru_cache(maxsize=1)
def _kernels():
    """Compile (or load from the on-disk cache) the kernels; imported lazily."""
    from . import kernels as k

    if not k.CACHE:
        warnings.warn("numba cannot cache its compiled code here (a read-only install, an unwritable HOME or "
                      "NUMBA_CACHE_DIR): the regressor kernels are compiled in memory in each run (~10-20 s); "
                      "set NUMBA_CACHE_DIR to a writable folder to keep them", CompileCacheWarning, stacklevel=2)
    return k


#: said once per process: compiling a kernel takes ~20 s on the machine's first run
COMPILE_NOTE = ("baseparams: compiling the regressor kernel {name} once (about 20 s); "
                "later runs load it from numba's cache")
_announced: set[str] = set()


def _kernel(name: str):
    """The kernel ``name``, after one line on stderr when calling it will compile it (not in the disk cache).

    numba compiles a kernel on its first call unless its on-disk cache holds it for this source
    and CPU; that first call is otherwise ~20 s of silence. Once per process, when the kernel is
    not compiled in memory and the cache's index for it is empty (or there is no cache), one line
    says so. Numba's cache index is read through its private ``_cache`` attribute; if that
    changes, nothing is said (the kernel works the same).
    """
    k = _kernels()
    fn = getattr(k, name)
    if name not in _announced:
        _announced.add(name)
        if will_compile(fn):
            print(COMPILE_NOTE.format(name=name), file=sys.stderr, flush=True)
    return fn


def will_compile(dispatcher) -> bool:
    """Whether calling a numba dispatcher will compile it: nothing in memory, nothing in its disk cache.

    Parameters
    ----------
    dispatcher : numba dispatcher
        A kernel of :mod:`baseparams.regressor.kernels`.

    Returns
    -------
    bool
        ``True`` when no overload is compiled in this process and the on-disk cache index for this
        source has no entry (or caching is off); ``False`` when unsure.
    """
    try:
        if dispatcher.overloads:
            return False
        cache = getattr(dispatcher, "_cache", None)
        index = getattr(getattr(cache, "_cache_file", None), "_load_index", None)
        return True if index is None else not index()
    except Exception:  # noqa: BLE001 - a private numba API: when it changes, say nothing
        return False


class Layout:
    """A robot's static data in the arrays the kernels take.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies, ``dof`` coordinates).

    Attributes
    ----------
    parent, q_index, ndofs : ndarray of int64, shape ``(n,)``
        Parent body (``-1`` the world), first coordinate and number of coordinates of each joint.
    floating : ndarray of bool, shape ``(n,)``
        The body's joint is a floating (F) root.
    screws : ndarray, shape ``(dof, 6)``
        Joint lines at q = 0, world frame (:attr:`Robot.screws`).
    gravity : ndarray, shape ``(3,)``
        Gravity [m/s^2], world frame.
    anc_ptr, anc : ndarray of int64
        CSR lists: the coordinates moving body ``i`` are ``anc[anc_ptr[i]:anc_ptr[i + 1]]``.
    pair_m, pair_n : ndarray of int64, shape ``(10,)``
        The paper's hat/bar order of the tetrahedral point pairs (:data:`HAT_INDEX`).
    """

    def __init__(self, robot: Robot):
        self.n, self.dof = robot.n, robot.dof
        self.parent = np.asarray(robot.parent, dtype=np.int64)
        self.q_index = np.asarray(robot.q_index, dtype=np.int64)
        self.ndofs = np.asarray(robot.ndofs, dtype=np.int64)
        self.floating = np.array([t == "F" for t in robot.jtype], dtype=np.bool_)
        self.screws = np.ascontiguousarray(robot.screws, dtype=float)
        self.gravity = np.asarray(robot.gravity, dtype=float).copy()
        paths: list[np.ndarray] = []  # each body's path coordinates: its parent's, then its own (O(sum of depths),
        for i in range(self.n):  # not the (dof, n) support matrix)
            own = np.arange(robot.q_index[i], robot.q_index[i] + robot.ndofs[i])
            p = robot.parent[i]
            paths.append(own if p < 0 else np.concatenate([paths[p], own]))
        self.anc_ptr = np.concatenate([[0], np.cumsum([len(p) for p in paths])]).astype(np.int64)
        self.anc = np.concatenate(paths).astype(np.int64)
        self.pair_m = np.array([m for m, _ in HAT_INDEX], dtype=np.int64)
        self.pair_n = np.array([n for _, n in HAT_INDEX], dtype=np.int64)

    def args(self) -> tuple:
        """The kernels' leading arguments.

        Returns
        -------
        tuple
            ``(parent, q_index, ndofs, floating, screws, gravity, anc_ptr, anc, pair_m, pair_n)``.
        """
        return (self.parent, self.q_index, self.ndofs, self.floating, self.screws, self.gravity,
                self.anc_ptr, self.anc, self.pair_m, self.pair_n)


def tree_regressor(robot: Robot, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray,
                   out: np.ndarray | None = None) -> np.ndarray:
    """TP regressor of a tree ``Y (S, dof, 10 n)``, compiled.

    Parameters
    ----------
    robot : Robot
        The robot (a tree: loops are not closed here).
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Joint positions, velocities and accelerations (float64, validated by the caller); a
        floating root's six coordinates are its twist coordinates and quasi-velocities.
    out : ndarray, shape ``(S, dof, 10 n)``, optional
        A C-contiguous float64 buffer (checked by the caller); every entry is set.

    Returns
    -------
    Y : ndarray, shape ``(S, dof, 10 n)``
        Columns in the ``paper`` convention (spatial pseudo-inertia entries
        ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at q = 0), gravity included.
    """
    lay = Layout(robot)
    s = q.shape[0]
    out = np.zeros((s, lay.dof, 10 * lay.n)) if out is None else out
    _kernel("tree")(*lay.args(), _c(q), _c(dq), _c(ddq), out)
    return out


def closed_regressor(robot: Robot, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, G: np.ndarray,
                     out: np.ndarray | None = None) -> np.ndarray:
    """TP regressor of a closed-loop robot w.r.t. its actuated coordinates, compiled.

    Parameters
    ----------
    robot : Robot
        The robot with loops (its spanning tree's kinematics).
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Closed-loop states of all tree coordinates.
    G : ndarray, shape ``(S, dof, na)``
        ``dq / dq_a`` of each state (:class:`baseparams.kinematics.loops.ClosedStates`).
    out : ndarray, shape ``(S, na, 10 n)``, optional
        A C-contiguous float64 buffer (checked by the caller); every entry is set.

    Returns
    -------
    Y : ndarray, shape ``(S, na, 10 n)``
        Columns in the ``paper`` convention; Jacobian lines ``L~_a^i = sum_k L_k^i G[k, a]``
        (paper eq. "jacobian line").
    """
    lay = Layout(robot)
    s, na = G.shape[0], G.shape[2]
    out = np.empty((s, na, 10 * lay.n)) if out is None else out
    _kernel("closed")(*lay.args(), _c(q), _c(dq), _c(ddq), _c(G), out)
    return out


def _c(x: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=float)


def projection_csr(P: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A column map ``P (10 n, m)`` per body in CSR form, for the projected kernels.

    Parameters
    ----------
    P : ndarray or scipy.sparse matrix, shape ``(10 n, m)``
        Rows in the ``paper`` convention (ten per body).
    n : int
        Number of bodies.

    Returns
    -------
    cptr : ndarray of int64, shape ``(n + 1,)``
        Body ``i``'s entries are ``cptr[i]:cptr[i + 1]``.
    ccol : ndarray of int64
        The column of each entry.
    cmat : ndarray, shape ``(entries, 10)``
        Body ``i``'s ten rows of that column (only columns not zero on body ``i`` are listed).
    """
    if hasattr(P, "tocoo"):  # sparse: the entries of each (body, column) pair, no dense (10 n, m) array
        c = P.tocoo()
        body, col = c.row // 10, c.col
        key = body.astype(np.int64) * P.shape[1] + col
        uk, inv = np.unique(key, return_inverse=True)
        cmat = np.zeros((len(uk), 10))
        np.add.at(cmat, (inv, c.row % 10), c.data)
        ub = uk // P.shape[1]
        cptr = np.concatenate([[0], np.cumsum(np.bincount(ub, minlength=n))]).astype(np.int64)
        return cptr, (uk % P.shape[1]).astype(np.int64), cmat
    blocks = np.asarray(P, dtype=float).reshape(n, 10, -1)
    nz = np.any(blocks != 0.0, axis=1)  # (n, m)
    body, col = np.nonzero(nz)
    cptr = np.concatenate([[0], np.cumsum(nz.sum(axis=1))]).astype(np.int64)
    cmat = np.ascontiguousarray(blocks[body, :, col])
    return cptr, col.astype(np.int64), cmat


def tree_projected(robot: Robot, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, P: np.ndarray,
                   rowsel: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``Y[:, rowsel] @ P`` of a tree without forming ``Y``, compiled.

    Parameters
    ----------
    robot : Robot
        The robot (a tree).
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Validated states.
    P : ndarray, shape ``(10 n, m)``
        Column map, rows in the ``paper`` convention.
    rowsel : ndarray of int, shape ``(rows,)``
        The coordinates whose rows are kept, in order.
    out : ndarray, shape ``(S, rows, m)``, optional
        A C-contiguous float64 buffer (checked by the caller); every entry is set.

    Returns
    -------
    ndarray, shape ``(S, rows, m)``
        The projected regressor.
    """
    lay = Layout(robot)
    cptr, ccol, cmat = projection_csr(P, robot.n)
    rowsel = np.ascontiguousarray(rowsel, dtype=np.int64)
    out = np.empty((q.shape[0], len(rowsel), P.shape[1])) if out is None else out
    _kernel("tree_projected")(*lay.args(), _c(q), _c(dq), _c(ddq), rowsel, cptr, ccol, cmat, out)
    return out


def tree_forces(robot: Robot, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, pi: np.ndarray,
                rowsel: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``Y[:, rowsel] @ pi`` of a tree without forming ``Y``, compiled: ``O(n)`` work and memory per sample.

    Parameters
    ----------
    robot : Robot
        The robot (a tree).
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Validated states.
    pi : ndarray, shape ``(10 n,)``
        Standard parameters, ``paper`` convention.
    rowsel : ndarray of int, shape ``(rows,)``
        The coordinates whose generalized forces are returned, in order.
    out : ndarray, shape ``(S, rows)``, optional
        A C-contiguous float64 buffer; every entry is set.

    Returns
    -------
    ndarray, shape ``(S, rows)``
        The generalized forces, gravity included.
    """
    lay = Layout(robot)
    rowsel = np.ascontiguousarray(rowsel, dtype=np.int64)
    out = np.empty((q.shape[0], len(rowsel))) if out is None else out
    pi = np.ascontiguousarray(np.asarray(pi, dtype=float).reshape(lay.n, 10))
    _kernel("tree_forces")(*lay.args(), _c(q), _c(dq), _c(ddq), pi, rowsel, out)
    return out


def closed_projected(robot: Robot, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, G: np.ndarray, P: np.ndarray,
                     out: np.ndarray | None = None) -> np.ndarray:
    """``Y_closed @ P`` of a closed-loop robot without forming ``Y_closed``, compiled.

    Parameters
    ----------
    robot : Robot
        The robot with loops.
    q, dq, ddq : ndarray, shape ``(S, dof)``
        Closed-loop states of all tree coordinates.
    G : ndarray, shape ``(S, dof, na)``
        ``dq / dq_a`` of each state.
    P : ndarray, shape ``(10 n, m)``
        Column map, rows in the ``paper`` convention.
    out : ndarray, shape ``(S, na, m)``, optional
        A C-contiguous float64 buffer (checked by the caller); every entry is set.

    Returns
    -------
    ndarray, shape ``(S, na, m)``
        The projected closed-loop regressor.
    """
    lay = Layout(robot)
    cptr, ccol, cmat = projection_csr(P, robot.n)
    out = np.empty((G.shape[0], G.shape[2], P.shape[1])) if out is None else out
    _kernel("closed_projected")(*lay.args(), _c(q), _c(dq), _c(ddq), _c(G), cptr, ccol, cmat, out)
    return out


def edge_extended(flat: np.ndarray, pad: int, curved: bool = True) -> np.ndarray:
    """Signals extended by ``pad`` samples at each end, for a zero-phase filter without an edge transient.

    scipy's odd extension (``2 x[0] - x[k]`` before the start, likewise after the end) keeps a
    signal's value and slope at the end but flips its even-order terms, so the second derivative of
    the filtered signal is pulled towards zero within a cutoff period of each end; and it doubles the
    end sample into every extended one, so a filtered end carries that one sample's noise (~100 x the
    interior's variance with a cutoff at a twentieth of the rate). ``curved`` extends oddly about
    ``c0``, not ``x[0]``, and adds ``2 (c2 k^2 + c4 k^4)`` to the ``k``-th extended sample:
    ``c0, c2, c4`` the coefficients of the least-squares polynomial of degree :data:`EDGE_DEGREE`
    through the ``pad // 4 + 1`` samples at that end, the even terms over the far half of the
    extension tapered (a half cosine) to the odd extension: a quartic is extended exactly (value,
    slope and curvature continuous) and the end's noise is averaged over a cutoff period. With
    :func:`baseparams.ident.preprocess.zero_phase`'s extension of four cutoff periods, a motion at a
    tenth of the cutoff keeps its second derivative to ~1 % at the very end. The extension is linear
    in the signal, so a filter through it stays one linear map, the same for the torques and every
    regressor column.

    Parameters
    ----------
    flat : ndarray, shape ``(S, C)``
        Signals along axis 0.
    pad : int
        Samples added at each end (``0 <= pad < S``).
    curved : bool
        Add the curvature term (False: scipy's odd extension exactly).

    Returns
    -------
    ndarray, shape ``(S + 2 pad, C)``
        The extended signals.
    """
    s = flat.shape[0]
    ext = np.empty((s + 2 * pad, flat.shape[1]))
    ext[pad:pad + s] = flat
    if not pad:
        return ext
    # scipy's odd_ext: 2 x[0] - x[pad:0:-1], ..., 2 x[-1] - x[-2:-(pad+2):-1]
    ext[:pad] = 2 * flat[:1] - flat[pad:0:-1]
    ext[pad + s:] = 2 * flat[-1:] - flat[-2:-(pad + 2):-1]
    w = pad // 4 + 1  # the polynomial's samples: a quarter of the extension (one cutoff period in zero_phase's)
    if curved and w > EDGE_DEGREE:
        k = np.arange(pad + 1, dtype=float) / (w - 1)  # scaled: the Vandermonde matrix stays well conditioned
        fit = np.linalg.pinv(np.vander(k[:w], EDGE_DEGREE + 1, increasing=True))  # (degree + 1, w)
        even = np.arange(2, EDGE_DEGREE + 1, 2)
        j = np.arange(1, pad + 1)
        half = pad // 2
        taper = np.where(j <= half, 1.0, 0.5 * (1.0 + np.cos(np.pi * (j - half) / max(pad - half, 1))))
        terms = np.r_[0, even]  # odd about the polynomial's value at the end c0 (not the end sample: its noise
        # doubled into every extended one), plus the even terms tapered
        powers = np.column_stack([np.ones(pad), taper[:, None] * k[1:, None] ** even[None, :]])  # (pad, 1 + even)
        ext[:pad] = 2 * (powers @ (fit[terms] @ flat[:w]))[::-1] - flat[pad:0:-1]
        ext[pad + s:] = 2 * powers @ (fit[terms] @ flat[-1:-(w + 1):-1]) - flat[-2:-(pad + 2):-1]
    return ext


#: degree of the polynomial whose even terms :func:`edge_extended` keeps (4: exact for a quartic; a motion a tenth
#: of the cutoff extended over two cutoff periods, the default, stays within ~1 % of its second derivative)
EDGE_DEGREE = 4


def sosfiltfilt(sos: np.ndarray, x: np.ndarray, pad: int, curved: bool = True) -> np.ndarray:
    """``scipy.signal.sosfiltfilt(sos, x, axis=0, padtype="odd", padlen=pad)``, compiled, columns in parallel.

    The same steps as scipy's (odd extension, here with its curvature kept: :func:`edge_extended`;
    the steady-state initial conditions scaled by the first sample of each direction, forward then
    backward) with the same arithmetic per sample and section; one padded copy of ``x``, filtered in
    place.

    Parameters
    ----------
    sos : ndarray, shape ``(n_sections, 6)``
        The filter (``a0 = 1``).
    x : ndarray, shape ``(S, ...)``
        Signals along axis 0 (other axes: independent columns), ``S > pad``.
    pad : int
        Samples of odd extension at each end (``0 <= pad < S``).
    curved : bool
        Keep the curvature at the ends (:func:`edge_extended`; False: scipy's odd extension).

    Returns
    -------
    ndarray, same shape as ``x``
        The zero-phase filtered signals.
    """
    from scipy.signal import sosfilt_zi

    s = x.shape[0]
    flat = np.reshape(x, (s, -1))
    ext = edge_extended(flat, pad, curved)
    sos = np.ascontiguousarray(sos, dtype=np.float64)
    z0 = sosfilt_zi(sos)  # (n_sections, 2)
    kernel = _kernel("sosfilt_rows")
    zi = np.ascontiguousarray(z0[:, :, None] * ext[0][None, None, :])  # (n_sections, 2, C)
    kernel(sos, ext, zi, False)
    zi = np.ascontiguousarray(z0[:, :, None] * ext[-1][None, None, :])
    kernel(sos, ext, zi, True)
    return ext[pad:pad + s].reshape(x.shape)
