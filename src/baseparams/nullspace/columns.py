"""Nullspace columns in compact form: blocks on at most three bodies, with provenance.

A column is ``+h`` on one body's ten parameters and, usually, ``-h`` (or ``hp``) on another's
(paper convention: spatial pseudo-inertia at q = 0, ``hat`` order per body); a few (the coupled
groups of R-M) carry blocks on further bodies (``more``). :class:`Columns`
holds many at once; :func:`to_sparse` expands them to ``B (10 n, k)``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..display import summary_repr
from ..enums import Source
from ..model.inertia import hat as hat10
from ..pga.linalg import outer, sym

#: provenance of a column (:class:`~baseparams.enums.Source`, whose labels these are): the
#: paper's principles, the extended rules (:mod:`~baseparams.nullspace.rules`), unmeasured roots, numerics
PAPER = tuple(s.label for s in Source if s.is_paper)
EXTENDED = tuple(s.label for s in Source if s.is_extended)
#: columns that come from which generalized forces are measured, not from geometry
UNMEASURED = Source.UNMEASURED.label
PRINCIPLES = tuple(s.label for s in Source)


def sym_params(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Parameter block ``hat(a b^T + b a^T)`` of 4-vectors: ``(*, 4), (*, 4) -> (*, 10)``.

    The ``sym(a, b)`` terms of the paper's principles (eq. "null space cross" symmetrised) as
    ten-parameter blocks. For ``a == b`` this is ``hat(2 a a^T)``: use :func:`outer_params`.

    Parameters
    ----------
    a, b : ndarray, shape ``(*, 4)``
        Homogeneous 4-vectors (points: ``w = 1``, directions: ``w = 0``), world frame at q = 0,
        broadcast against each other.

    Returns
    -------
    ndarray, shape ``(*, 10)``
        ``hat(a b^T + b a^T)`` in the ``paper`` convention's ``hat`` order (``XX XY XZ YY YZ ZZ
        MX MY MZ M``).
    """
    return hat10(sym(a, b))


def outer_params(a: np.ndarray) -> np.ndarray:
    """Parameter block ``hat(a a^T)`` of 4-vectors: ``(*, 4) -> (*, 10)``.

    Parameters
    ----------
    a : ndarray, shape ``(*, 4)``
        Homogeneous 4-vectors (points: ``w = 1``, directions: ``w = 0``), world frame at q = 0.

    Returns
    -------
    ndarray, shape ``(*, 10)``
        ``hat(a a^T)`` in the ``paper`` convention's ``hat`` order (``XX XY XZ YY YZ ZZ MX MY
        MZ M``).
    """
    return hat10(outer(a))


FIELDS = ("h", "child", "parent", "principle", "joint", "label", "hp", "extra", "he", "more")


@dataclass(frozen=True, eq=False)
class Columns:
    """A set of nullspace columns in compact form (``k`` columns).

    Column ``j`` is ``h[j]`` on body ``child[j]``'s ten parameters, plus ``hp[j]`` on body
    ``parent[j]`` and ``he[j]`` on body ``extra[j]`` where those are ``>= 0``; :func:`to_sparse`
    expands the set to ``B (10 n, k)``. Blocks are in the ``paper`` convention (spatial
    pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at q = 0).
    ``len(columns)`` is ``k``.

    Parameters
    ----------
    h : ndarray, shape ``(k, 10)``
        The block on body ``child`` (the column's highest body).
    child : ndarray of int, shape ``(k,)``
        The body carrying ``h``: the column's highest body.
    parent : ndarray of int, shape ``(k,)``
        The other body (``-1``: none), whose block is ``hp``.
    principle : ndarray of int, shape ``(k,)``
        Provenance: a :class:`~baseparams.enums.Source` (index into :data:`PRINCIPLES`).
    joint : ndarray of int, shape ``(k,)``
        The joint the column comes from (``n + l`` for loop joint ``l``; a body for the
        extended rules).
    label : ndarray of object, shape ``(k,)``
        Which points or vectors (a string, or an object formatted on ``str``).
    hp : ndarray, shape ``(k, 10)``, optional
        The block on ``parent``; default ``-h``: the principles' "``+h`` on the child, ``-h``
        on the parent" (eq. "null space", E1 fixed).
    extra : ndarray of int, shape ``(k,)``, optional
        An optional third body (``-1``: none, lower than ``child``); default all ``-1``.
    he : ndarray, shape ``(k, 10)``, optional
        The block on ``extra``; default zeros.
    more : ndarray of object, shape ``(k,)``, optional
        Blocks on further bodies: ``None`` (the default, every column but R-M's widest) or a
        pair ``(bodies (m,) int, blocks (m, 10))``, each body lower than ``child``.
    """

    h: np.ndarray
    child: np.ndarray
    parent: np.ndarray
    principle: np.ndarray
    joint: np.ndarray
    label: np.ndarray
    hp: np.ndarray | None = None
    extra: np.ndarray | None = None
    he: np.ndarray | None = None
    more: np.ndarray | None = None

    __repr__ = summary_repr

    def __post_init__(self) -> None:
        if self.hp is None:
            object.__setattr__(self, "hp", -np.asarray(self.h))
        if self.extra is None:
            object.__setattr__(self, "extra", -np.ones(len(self.child), dtype=int))
        if self.he is None:
            object.__setattr__(self, "he", np.zeros_like(np.asarray(self.h)))
        if self.more is None:
            object.__setattr__(self, "more", np.full(len(self.child), None, dtype=object))

    def has_more(self) -> np.ndarray:
        """Which columns carry blocks beyond ``child``, ``parent`` and ``extra``.

        Returns
        -------
        ndarray of bool, shape ``(k,)``
            True where :attr:`more` is not ``None``.
        """
        return ~np.equal(self.more, None)

    def scaled(self, inv: np.ndarray) -> Columns:
        """The columns for parameters ``pi / d``: every block multiplied by ``inv = 1 / d``.

        Parameters
        ----------
        inv : ndarray, shape ``(10,)``
            Per-entry factors of a body block (``paper`` ``hat`` order), the same for all bodies.

        Returns
        -------
        Columns
            Same bodies and provenance, blocks scaled.
        """
        more = np.array([None if m is None else (m[0], m[1] * inv) for m in self.more] + [None], dtype=object)[:-1]
        return replace(self, h=self.h * inv, hp=self.hp * inv, he=self.he * inv, more=more)

    def transformed(self, f: np.ndarray) -> Columns:
        """The columns in per-body coordinates ``f[b] @ pi_b``: each block on body ``b`` (``more`` too) times ``f[b]``.

        Parameters
        ----------
        f : ndarray, shape ``(n, 10, 10)``
            Per body, an invertible map of its ten parameters (e.g.
            :func:`baseparams.model.scale.decision_frames`), rows and columns in ``hat`` order.

        Returns
        -------
        Columns
            Same bodies and provenance; a block on no body (``parent`` or ``extra`` ``-1``) as it is.
        """
        def blk(bodies: np.ndarray, h: np.ndarray) -> np.ndarray:
            out = np.einsum("kij,kj->ki", f[np.maximum(bodies, 0)], h)
            return np.where((bodies >= 0)[:, None], out, h)

        more = np.array([None if m is None else (m[0], np.einsum("kij,kj->ki", f[np.asarray(m[0], dtype=int)],
                                                                 np.asarray(m[1], dtype=float).reshape(-1, 10)))
                         for m in self.more] + [None], dtype=object)[:-1]
        return replace(self, h=blk(self.child, self.h), hp=blk(self.parent, self.hp), he=blk(self.extra, self.he),
                       more=more)

    def norms(self) -> np.ndarray:
        """Each column's Euclidean norm over all its blocks (``more`` included).

        Returns
        -------
        ndarray, shape ``(k,)``
            ``||B[:, j]||`` (blocks on the same body not summed first: an upper bound then).
        """
        n2 = (np.sum(self.h ** 2, 1) + np.sum(self.hp ** 2, 1) * (self.parent >= 0)
              + np.sum(self.he ** 2, 1) * (self.extra >= 0))
        for j in np.flatnonzero(self.has_more()):
            n2[j] += float(np.sum(np.asarray(self.more[j][1], dtype=float) ** 2))
        return np.sqrt(n2)

    def times(self, s: np.ndarray) -> Columns:
        """Column ``j`` multiplied by ``s[j]``: every block of it, ``more`` included.

        Parameters
        ----------
        s : ndarray, shape ``(k,)``
            One factor per column.

        Returns
        -------
        Columns
            Same bodies and provenance.
        """
        s = np.asarray(s, dtype=float)
        more = np.array([None if m is None else (m[0], np.asarray(m[1], dtype=float) * s[j])
                         for j, m in enumerate(self.more)] + [None], dtype=object)[:-1]
        return replace(self, h=self.h * s[:, None], hp=self.hp * s[:, None], he=self.he * s[:, None], more=more)

    def reindexed(self, bodies: np.ndarray, loops: np.ndarray, n: int) -> Columns:
        """The columns of a related robot as columns of this one: bodies and loop joints renumbered.

        Parameters
        ----------
        bodies : ndarray of int, shape ``(m,)``
            The other robot's body ``k`` is body ``bodies[k]`` here (``-1``: none; no block may sit there).
        loops : ndarray of int, shape ``(l,)``
            Its loop joint ``k`` is loop joint ``loops[k]`` here.
        n : int
            Bodies of this robot (``joint`` of a loop joint ``l`` is ``n + l``).

        Returns
        -------
        Columns
            The same blocks and provenance, on the renumbered bodies.
        """
        m = len(bodies)

        def body(b):
            return np.where(b >= 0, bodies[np.clip(b, 0, m - 1)], -1)

        more = np.array([None if x is None else (bodies[np.asarray(x[0])], x[1]) for x in self.more] + [None],
                        dtype=object)[:-1]
        lp = n + loops[np.clip(self.joint - m, 0, max(len(loops) - 1, 0))] if len(loops) else self.joint
        joint = np.where(self.joint >= m, lp, body(self.joint))
        return replace(self, child=body(self.child), parent=body(self.parent), extra=body(self.extra), more=more,
                       joint=joint)

    @staticmethod
    def empty() -> Columns:
        """No columns (``k = 0``).

        Returns
        -------
        Columns
            An empty set: ``h (0, 10)`` and empty index arrays.
        """
        z = np.zeros(0, dtype=int)
        return Columns(np.zeros((0, 10)), z, z, z, z, np.zeros(0, dtype=object))

    @staticmethod
    def concat(parts: list[Columns]) -> Columns:
        """Columns of several sets, one after the other (empty sets skipped).

        Parameters
        ----------
        parts : list of Columns
            The sets, in order.

        Returns
        -------
        Columns
            Their columns concatenated in order (:meth:`empty` when every part is empty).
        """
        parts = [p for p in parts if len(p.child)]
        if not parts:
            return Columns.empty()
        return Columns(*(np.concatenate([getattr(p, f) for p in parts]) for f in FIELDS))

    def subset(self, keep: np.ndarray) -> Columns:
        """The columns selected by ``keep``, every field indexed alike.

        Parameters
        ----------
        keep : ndarray
            A boolean mask ``(k,)`` or integer indices into the ``k`` columns.

        Returns
        -------
        Columns
            The selected columns, with their provenance.
        """
        return Columns(*(getattr(self, f)[keep] for f in FIELDS))

    def __len__(self) -> int:
        return len(self.child)


def on_bodies(bodies: list[int], x: np.ndarray, principle: int, label) -> Columns:
    """Columns ``x (d, 10 len(bodies))`` over several bodies: the highest body's ``h``, then ``hp``, ``he``, ``more``.

    Parameters
    ----------
    bodies : list of int, shape ``(b,)``
        Distinct bodies (``>= 0``) whose blocks ``x`` holds, in that order.
    x : ndarray, shape ``(d, 10 b)``
        The columns, body ``bodies[i]``'s block in ``x[:, 10 i: 10 i + 10]`` (``paper``
        convention).
    principle : int
        Provenance (a :class:`~baseparams.enums.Source`).
    label : str or object
        Provenance label, shared by the ``d`` columns.

    Returns
    -------
    Columns
        ``d`` columns, ``joint`` their highest body.
    """
    order = np.argsort(bodies)[::-1]
    d = len(x)
    blk = [x[:, 10 * i: 10 * i + 10] for i in order]
    bs = [int(bodies[i]) for i in order]
    none, zero = np.full(d, -1), np.zeros((d, 10))
    more = None
    if len(bs) > 3:
        rest = np.array(bs[3:])
        more = np.array([(rest, np.stack([b[c] for b in blk[3:]])) for c in range(d)] + [None], dtype=object)[:-1]
    return Columns(blk[0], np.full(d, bs[0]), np.full(d, bs[1]) if len(bs) > 1 else none, np.full(d, principle),
                   np.full(d, bs[0]), np.full(d, label, dtype=object), hp=blk[1] if len(bs) > 1 else zero,
                   extra=np.full(d, bs[2]) if len(bs) > 2 else none, he=blk[2] if len(bs) > 2 else zero, more=more)


def _triplets(cols: Columns) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(rows, column indices, values)`` of the entries of ``B``: child, parent, extra and further blocks."""
    k = len(cols)
    rows_c = (10 * cols.child[:, None] + np.arange(10)).ravel()
    cidx = np.repeat(np.arange(k), 10)
    vals_c = cols.h.ravel()
    has_p = cols.parent >= 0
    rows_p = (10 * cols.parent[has_p][:, None] + np.arange(10)).ravel()
    cidx_p = np.repeat(np.flatnonzero(has_p), 10)
    vals_p = cols.hp[has_p].ravel()
    has_e = cols.extra >= 0
    if has_e.any():
        rows_p = np.r_[rows_p, (10 * cols.extra[has_e][:, None] + np.arange(10)).ravel()]
        cidx_p = np.r_[cidx_p, np.repeat(np.flatnonzero(has_e), 10)]
        vals_p = np.r_[vals_p, cols.he[has_e].ravel()]
    for j in np.flatnonzero(cols.has_more()):
        bodies, blocks = cols.more[j]
        rows_p = np.r_[rows_p, (10 * np.asarray(bodies)[:, None] + np.arange(10)).ravel()]
        cidx_p = np.r_[cidx_p, np.full(10 * len(bodies), j)]
        vals_p = np.r_[vals_p, np.asarray(blocks).ravel()]
    return np.r_[rows_c, rows_p], np.r_[cidx, cidx_p], np.r_[vals_c, vals_p]


def to_dense(cols: Columns, n: int) -> np.ndarray:
    """``B (10 n, k)`` as a dense array (paper convention), without scipy.

    Parameters
    ----------
    cols : Columns
        ``k`` columns in compact form.
    n : int
        Number of moving bodies of the robot.

    Returns
    -------
    ndarray, shape ``(10 n, k)``
        As :func:`to_sparse`, dense (entries on the same position summed).
    """
    rows, cidx, vals = _triplets(cols)
    b = np.zeros((10 * n, len(cols)))
    np.add.at(b, (rows, cidx), vals)
    return b


def to_sparse(cols: Columns, n: int):
    """``B (10 n, k)`` as a sparse matrix (paper convention).

    Parameters
    ----------
    cols : Columns
        ``k`` columns in compact form.
    n : int
        Number of moving bodies of the robot.

    Returns
    -------
    scipy.sparse.csc_matrix, shape ``(10 n, k)``
        Column ``j`` holds ``h[j]`` in body ``child[j]``'s rows, ``hp[j]`` in ``parent[j]``'s and
        ``he[j]`` in ``extra[j]``'s (where ``>= 0``); rows in the ``paper`` convention (spatial
        pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at
        q = 0). scipy.sparse is imported here only (it costs ~80 ms of import).
    """
    import scipy.sparse as sp

    rows, cidx, vals = _triplets(cols)
    return sp.coo_matrix((vals, (rows, cidx)), shape=(10 * n, len(cols))).tocsc()
