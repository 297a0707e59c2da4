"""Nullspace columns in compact form: blocks on at most three bodies, with provenance.

A column is ``+h`` on one body's ten parameters and, usually, ``-h`` (or ``hp``) on another's
(paper convention: spatial pseudo-inertia at q = 0, ``hat`` order per body). :class:`Columns`
holds many at once; :func:`to_sparse` expands them to ``B (10 n, k)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..enums import Source
from ..model.inertia import hat as hat10
from ..pga.linalg import outer, sym

#: provenance of a column (:class:`~baseparams.enums.Source`, whose labels these are): the
#: paper's principles, the extended rules (:mod:`.rules`), unmeasured roots, numerics
PAPER = tuple(s.label for s in Source if s.is_paper)
EXTENDED = tuple(s.label for s in Source if s.is_extended)
#: columns that come from which generalized forces are measured, not from geometry
UNMEASURED = Source.UNMEASURED.label
PRINCIPLES = tuple(s.label for s in Source)


def sym_params(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Parameter block ``hat(a b^T + b a^T)`` of 4-vectors: ``(*, 4), (*, 4) -> (*, 10)``.

    For ``a == b`` this is ``hat(2 a a^T)``: use :func:`outer_params`.
    """
    return hat10(sym(a, b))


def outer_params(a: np.ndarray) -> np.ndarray:
    """Parameter block ``hat(a a^T)`` of 4-vectors: ``(*, 4) -> (*, 10)``."""
    return hat10(outer(a))


FIELDS = ("h", "child", "parent", "principle", "joint", "label", "hp", "extra", "he")


@dataclass(frozen=True, eq=False)
class Columns:
    """A set of nullspace columns in compact form (``k`` columns).

    ``h (k, 10)``: the block on body ``child (k,)`` (the column's highest body); ``parent (k,)``
    the other body (``-1``: none) whose block is ``hp (k, 10)`` (default ``-h``: the principles'
    "``+h`` on the child, ``-h`` on the parent"); ``principle (k,)`` a
    :class:`~baseparams.enums.Source` (index into :data:`PRINCIPLES`); ``joint (k,)`` the joint
    the column comes from (``n + l`` for loop joint ``l``; a body for the extended rules);
    ``label (k,)`` which points or vectors; ``extra (k,)`` an optional third body (``-1``: none,
    lower than ``child``) with block ``he (k, 10)``.
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

    def __post_init__(self) -> None:
        if self.hp is None:
            object.__setattr__(self, "hp", -np.asarray(self.h))
        if self.extra is None:
            object.__setattr__(self, "extra", -np.ones(len(self.child), dtype=int))
        if self.he is None:
            object.__setattr__(self, "he", np.zeros_like(np.asarray(self.h)))

    @staticmethod
    def empty() -> Columns:
        z = np.zeros(0, dtype=int)
        return Columns(np.zeros((0, 10)), z, z, z, z, np.zeros(0, dtype=object))

    @staticmethod
    def concat(parts: list[Columns]) -> Columns:
        parts = [p for p in parts if len(p.child)]
        if not parts:
            return Columns.empty()
        return Columns(*(np.concatenate([getattr(p, f) for p in parts]) for f in FIELDS))

    def subset(self, keep: np.ndarray) -> Columns:
        return Columns(*(getattr(self, f)[keep] for f in FIELDS))

    def __len__(self) -> int:
        return len(self.child)


def to_sparse(cols: Columns, n: int) -> sp.csc_matrix:
    """``B (10 n, k)`` as a sparse matrix (paper convention)."""
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
    b = sp.coo_matrix((np.r_[vals_c, vals_p], (np.r_[rows_c, rows_p], np.r_[cidx, cidx_p])), shape=(10 * n, k))
    return b.tocsc()
