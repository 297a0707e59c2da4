"""Regrouping in recursive form: each base parameter from its body's own and its children's regrouped ones.

Khalil's regrouping of a chain is recursive (``MR_j = M_j + MR_{j+1}``, ``ZZR_j = ZZ_j + YY_{j+1} +
d^2 MR_{j+1} + ...``): a base parameter is its own standard parameters plus a few terms of its
children's *regrouped* parameters. Written out (``K``, :func:`~.sparse.tree_base_parameters`) the
same expressions collect every descendant, ``O(sum of depths)`` terms: quadratic on a chain. The
recursive form has ``O(n)`` terms and is what a person reads.

From a basis in compact form, each column with a highest body ``c`` and a block ``H_c`` of full
column rank there (:func:`baseparams.nullspace.rank.leading_spans`), with ``D_c`` the dependent
parameters chosen on ``c`` (the same greedy choice as :func:`~.sparse.tree_base_parameters`) and
``N_c = columns(c) H_c[D_c]^-1`` (identity on ``D_c``), reducing ``pi`` modulo the nullspace from
the leaves to the root gives (``t_c`` the *regrouped dependent parameters* of body ``c``, named
``link.MR`` etc.):

* ``t_c = pi_c[D_c] - sum_{c'} N_{c'}[body c, D_c] t_{c'}``,
* ``beta[I_c] = pi_c[I_c] - N_c[body c, I_c] t_c - sum_{c'} N_{c'}[body c, I_c] t_{c'}``,

the sums over the bodies ``c'`` whose columns reach body ``c`` (its children, a grandchild for a
three-body column). In matrices: ``t = pi_D + S t`` and ``beta = pi_I + R t``, so the expanded
``K = R (I - S)^-1`` (:meth:`RecursiveForm.expand`). ``S`` is nilpotent (a body's ``t`` uses
higher bodies' only); ``R`` and ``S`` have ``O(n)`` nonzeros. Tolerances, the dimensionless
decisions and the snapping of coefficients are those of :func:`~.sparse.tree_base_parameters`,
applied to ``R`` and ``S``'s entries (each relative to its row).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..model import inertia as _inertia
from ..model.inertia import LENGTH_POWER
from ..model.robot import Robot
from ..model.scale import body_rounding, length_scale
from ..nullspace.columns import Columns
from .regroup import SNAP_RTOL, ZERO_TOL, BaseParameters, format_rows, parameter_names
from .sparse import SNAP_ROUNDING, choose_all, csr_or_dense, lower_blocks, scaled_blocks, snap_short

#: :meth:`RecursiveForm.expand_rows`: about the most one dense block of expanded rows takes [bytes]
EXPAND_BLOCK_BYTES = 8e6


@dataclass(frozen=True, eq=False)
class RecursiveForm:
    """``beta = pi_I + R t`` with ``t = pi_D + S t`` (module doc); ``nb`` base, ``k`` dependent parameters.

    Parameters
    ----------
    names : list of str, length ``10 n``
        The standard parameters' names.
    independent : ndarray of int, shape ``(nb,)``
        Indices of ``pi_I``.
    dependent : ndarray of int, shape ``(k,)``
        Indices of ``pi_D`` (last body first).
    R : ndarray or scipy.sparse.csr_matrix, shape ``(nb, k)``
        Coefficients of the regrouped dependent parameters ``t`` in the base parameters.
    S : ndarray or scipy.sparse.csr_matrix, shape ``(k, k)``
        Coefficients of ``t`` in ``t`` (row ``d``: the higher bodies' ``t`` that body ``d``'s absorbs).
    """

    __repr__ = summary_repr

    names: list[str]
    independent: np.ndarray
    dependent: np.ndarray
    R: np.ndarray
    S: np.ndarray

    def _csr(self, a):
        import scipy.sparse as sp

        return a.tocsr() if hasattr(a, "tocsr") else sp.csr_matrix(a)

    def regrouped(self) -> np.ndarray:
        """Which dependent parameters absorb others (a row of ``S`` with a term).

        Returns
        -------
        ndarray of bool, shape ``(k,)``
            ``True`` where ``t_d`` differs from ``pi_d`` (written ``NAMER``).
        """
        s = self.S
        if hasattr(s, "indptr"):
            return np.diff(s.indptr) > 0
        return np.any(s != 0, axis=1) if s.shape[1] else np.zeros(s.shape[0], dtype=bool)

    def term_names(self) -> list[str]:
        """How each ``t_d`` is written: ``NAMER`` when it absorbs others, else the standard ``NAME``.

        Returns
        -------
        list of str, length ``k``
        """
        return [self.names[d] + ("R" if r else "") for d, r in zip(self.dependent.tolist(), self.regrouped().tolist())]

    def base_expressions(self, base_names: list[str]) -> list[dict[str, str]]:
        """Each base parameter as its own standard parameter plus terms of regrouped ones.

        Parameters
        ----------
        base_names : list of str, length ``nb``
            The base parameters' names.

        Returns
        -------
        list of dict
            ``[{"name", "expression"}]``, e.g. ``link1.ZZR``: ``link1.ZZ + link2.YY + 0.09*link2.MR``.
        """
        r = self._csr(self.R)
        return format_rows([self.names[i] for i in self.independent.tolist()], base_names, r.indptr, r.indices,
                           r.data, self.term_names(), self.dependent)

    def definitions(self) -> list[dict[str, str]]:
        """The regrouped dependent parameters that absorb others, each from its own and higher bodies' ones.

        Returns
        -------
        list of dict
            ``[{"name", "expression"}]``, e.g. ``link2.MR``: ``link2.M + link3.MR``, root side first.
        """
        s = self._csr(self.S)
        tn = self.term_names()
        rows = np.flatnonzero(self.regrouped())[::-1]  # dependent is last body first: root side first
        sub = s[rows] if len(rows) else s[:0]
        return format_rows([self.names[d] for d in self.dependent[rows].tolist()], [tn[d] for d in rows.tolist()],
                           sub.indptr, sub.indices, sub.data, tn, self.dependent)

    def solve_t(self, pi_d: np.ndarray) -> np.ndarray:
        """The regrouped dependent parameters ``t = (I - S)^-1 pi_D``.

        Parameters
        ----------
        pi_d : ndarray, shape ``(k,)`` or ``(k, m)``
            The dependent standard parameters (or several columns).

        Returns
        -------
        ndarray, same shape
        """
        k = len(self.dependent)
        if not k:
            return np.asarray(pi_d, dtype=float)
        if not hasattr(self.S, "indptr"):
            return np.linalg.solve(np.eye(k) - self.S, pi_d)
        import scipy.sparse as sp
        from scipy.sparse.linalg import spsolve_triangular

        # dependent is last body first: t_d uses higher bodies' t, earlier in this order (lower triangular)
        a = (sp.identity(k, format="csr") - self.S).tocsr()
        return spsolve_triangular(a, np.asarray(pi_d, dtype=float), lower=True)

    def expand(self):
        """The expanded regrouping ``K = R (I - S)^-1`` (``nb x k``), dense or CSR as ``R``.

        Returns
        -------
        ndarray or scipy.sparse.csr_matrix, shape ``(nb, k)``
            What :func:`~.sparse.tree_base_parameters` computes, up to the last digits of the
            coefficients (products of snapped ones).
        """
        k = len(self.dependent)
        if not hasattr(self.R, "indptr") and not hasattr(self.S, "indptr"):
            return np.linalg.solve((np.eye(k) - self.S).T, self.R.T).T if k else self.R.copy()
        import scipy.sparse as sp

        # column d of K = R[:, d] + sum_{d'} S[d', d] K[:, d'], d' on lower bodies: later in dependent's order
        sc = self._csr(self.S).tocsc()
        rc = self._csr(self.R).tocsc()
        cols: list = [None] * k
        for d in range(k - 1, -1, -1):
            col = rc[:, d]
            lo, hi = sc.indptr[d], sc.indptr[d + 1]
            for dp, v in zip(sc.indices[lo:hi].tolist(), sc.data[lo:hi].tolist()):
                col = col + v * cols[dp]
            cols[d] = col
        out = sp.hstack(cols, format="csr") if k else rc.tocsr()
        out.eliminate_zeros()
        out.sort_indices()
        return out


    def expand_rows(self, max_bytes: float | None = None):
        """:meth:`expand`'s ``K`` a block of rows at a time, never whole (bounded memory).

        Each row is computed with the same operations in the same order as :meth:`expand`'s
        (the column recursion restricted to the block's rows): the same numbers, except that
        what cancelled to rounding (at most ``ZERO_TOL`` of the row's largest, or of 1) is zero,
        as :func:`~.sparse.tree_base_parameters` writes it.

        Parameters
        ----------
        max_bytes : float, optional
            About the most a dense block (rows x ``k``) takes; at least one row (default
            :data:`EXPAND_BLOCK_BYTES`).

        Yields
        ------
        tuple
            ``(start, stop, indptr (stop - start + 1,), column indices, values)``: rows
            ``start:stop`` of ``K`` in CSR form (sorted, no zeros), consecutive blocks covering
            ``0:nb``.
        """
        nb, k = len(self.independent), len(self.dependent)
        step = max(1, int((max_bytes or EXPAND_BLOCK_BYTES) // (8 * max(k, 1))))
        users = _column_entries(self.S)
        for start in range(0, nb, step):
            stop = min(nb, start + step)
            r = self.R[start:stop]  # (m, k): R's rows, then K's, column by column from the leaves
            block = r.toarray() if hasattr(r, "toarray") else np.array(r, dtype=float)
            for d in range(k - 1, -1, -1):
                dps, vs = users[d]
                col = block[:, d]
                for dp, v in zip(dps.tolist(), vs):
                    col = col + v * block[:, dp]
                block[:, d] = col
            # what cancels to rounding (relative to the row, and to the 1 of pi_I) is zero, as tree_base_parameters
            block[np.abs(block) <= ZERO_TOL * np.maximum(1.0, np.abs(block).max(axis=1, initial=0.0))[:, None]] = 0.0
            rows, cols = np.nonzero(block)
            indptr = np.r_[0, np.cumsum(np.bincount(rows, minlength=stop - start))]
            yield start, stop, indptr, cols, block[rows, cols]


def recursive_base_parameters(robot: Robot, cols: Columns, convention: str) -> BaseParameters:
    """Regroup into base parameters in recursive form (module doc), ``O(n)`` memory and time.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    cols : Columns
        ``k`` linearly independent columns spanning the nullspace, SI ``paper`` convention, each
        independent on its highest body (as :func:`~.sparse.tree_base_parameters` takes).
    convention : str
        The parameter convention to regroup in.

    Returns
    -------
    BaseParameters
        With :attr:`~.regroup.BaseParameters.recursive` set; ``K`` and ``E`` are expanded from it
        when first used (``O(sum of depths)``): :meth:`~.regroup.BaseParameters.to_base` and the
        expressions do not need them.

    Raises
    ------
    RuntimeError
        The columns are not independent on their highest bodies.
    """
    n, n10 = robot.n, 10 * robot.n
    hc, hp, he, hm, t, noise = scaled_blocks(robot, cols, convention)
    tol = np.maximum(1e-8, noise)
    order, bounds, dep_local, ainv = choose_all(hc, cols.child, n, _inertia.SPECS[convention].regroup_order, tol)
    dep = np.array([10 * c + w for c in reversed(range(n)) for w in dep_local[c]], dtype=int)
    keep = np.ones(n10, dtype=bool)
    keep[dep] = False
    ind = np.flatnonzero(keep)
    pos_d = np.full(n10, -1)
    pos_d[dep] = np.arange(len(dep))
    tg_a, sr_a, v = _local_terms(cols, (hc, hp, he, hm), order, bounds, dep_local, ainv)
    # sum duplicates (two columns' blocks on one body), then zero what is rounding, relative to the row
    key = tg_a.astype(np.int64) * n10 + sr_a
    uk, inv = np.unique(key, return_inverse=True)
    v = np.bincount(inv, weights=v, minlength=len(uk)) if len(uk) else np.zeros(0)
    tg_a, sr_a = uk // n10, uk % n10
    rowmax = np.ones(n10)
    np.maximum.at(rowmax, tg_a, np.abs(v))
    level = np.maximum(noise[tg_a // 10], noise[sr_a // 10])  # either body's rounding
    ok = np.abs(v) > np.maximum(ZERO_TOL, level) * rowmax[tg_a]
    tg_a, sr_a, v = tg_a[ok], sr_a[ok], v[ok]
    power = np.tile(LENGTH_POWER[convention], n).astype(float)
    rounding = SNAP_ROUNDING * body_rounding(robot)
    snap = np.maximum(SNAP_RTOL, np.maximum(rounding[tg_a // 10], rounding[sr_a // 10]))  # the rounding it carries
    v = snap_short(v * length_scale(robot) ** (power[tg_a] - power[sr_a]), snap)
    pos_i = np.full(n10, -1)
    pos_i[ind] = np.arange(len(ind))
    isd = pos_d[tg_a] >= 0
    rmat = csr_or_dense(v[~isd], pos_i[tg_a[~isd]], pos_d[sr_a[~isd]], (len(ind), len(dep)))
    smat = csr_or_dense(v[isd], pos_d[tg_a[isd]], pos_d[sr_a[isd]], (len(dep), len(dep)))
    form = RecursiveForm(parameter_names(robot, convention), ind, dep, rmat, smat)
    unid = _unseen(form, dep)
    tb = np.asarray(t, dtype=float).reshape(n, 10, 10)
    tr = (10 * np.arange(n)[:, None, None] + np.arange(10)[None, :, None]) + np.zeros((1, 1, 10), dtype=int)
    tmat = csr_or_dense(tb.ravel(), tr.ravel(), np.transpose(tr, (0, 2, 1)).ravel(), (n10, n10))
    return BaseParameters(convention, form.names, ind, dep, None, None, unid, None, tmat, recursive=form)


def _local_terms(cols: Columns, scaled: tuple, order: np.ndarray, bounds: np.ndarray, dep_local: list,
                 ainv: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(target parameter, source dependent parameter, dimensionless value)`` of ``-N_c``'s entries, every body.

    ``scaled``: ``(hc, hp, he, hm)`` of :func:`~.sparse.scaled_blocks` (every block of every column).
    """
    hc, hp, he, hm = scaled
    tg, sr, vals = [], [], []  # target parameter (global), source dependent (global), dimensionless value
    ar10 = np.arange(10)
    for c in range(len(dep_local)):
        if not dep_local[c]:
            continue
        idx = order[bounds[c]:bounds[c + 1]]
        a = ainv[c]
        src = 10 * c + np.array(dep_local[c], dtype=int)
        own = hc[idx].T @ a  # (10, l): the identity on D_c (the pivot), N_c[body c, I_c] elsewhere
        own[dep_local[c]] = 0.0
        for j, blk in [(c, own), *lower_blocks(cols, hp, he, hm, idx, a)]:
            r, s = np.nonzero(blk)
            tg.append(10 * j + ar10[r])
            sr.append(src[s])
            vals.append(-blk[r, s])
    if not tg:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros(0)
    return np.concatenate(tg), np.concatenate(sr), np.concatenate(vals)


def _column_entries(a) -> list[tuple[np.ndarray, list[float]]]:
    """Each column's nonzeros ``(row indices ascending, values)`` of a dense or CSR matrix (no scipy for dense)."""
    if hasattr(a, "tocsc"):
        c = a.tocsc()
        c.sort_indices()
        return [(c.indices[c.indptr[d]:c.indptr[d + 1]], c.data[c.indptr[d]:c.indptr[d + 1]].tolist())
                for d in range(c.shape[1])]
    a = np.asarray(a)
    return [(np.flatnonzero(a[:, d]), a[np.flatnonzero(a[:, d]), d].tolist()) for d in range(a.shape[1])]


def _unseen(form: RecursiveForm, dep: np.ndarray) -> np.ndarray:
    """The dependent parameters no base parameter sees: no path of nonzero coefficients to ``R``, sorted."""
    seen = np.zeros(len(dep), dtype=bool)
    rseen = np.array([len(rows) > 0 for rows, _ in _column_entries(form.R)], dtype=bool)
    users = _column_entries(form.S)
    # t_d is seen when it feeds R, or the t of a lower body that is seen (S[d', d] != 0, d' later in
    # this order): root side first
    for d in range(len(dep) - 1, -1, -1):
        seen[d] = rseen[d] or bool(np.any(seen[users[d][0]]))
    return np.sort(dep[~seen]) if len(dep) else np.zeros(0, dtype=int)
