"""Base parameters: an orthonormal basis of ``Null^perp`` and the regrouped form users know.

Regrouping (in a chosen parameter convention, e.g. ``khalil`` link-frame or ``paper``
spatial): the standard parameters split into identifiable ``pi_I`` and dependent ``pi_D``
with the nullspace basis ``B`` restricted to ``D`` invertible; then

    beta = pi_I + K pi_D,   K = -B_I B_D^{-1}

gives ``Y pi = Y_I beta`` for every ``pi``. ``D`` is chosen greedily from the last body's
parameters backwards (mass, first moments, then second moments), which regroups each body's
dependent parameters onto its predecessors as in Khalil's rules (``ZZ1R = ZZ1 + YY2 + ...``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..display import format_number
from ..errors import BaseparamsError
from ..model import inertia as _inertia
from ..model.inertia import LENGTH_POWER
from ..model.robot import Robot
from ..model.scale import NOISE_FACTOR, length_scale

_NAMES = _inertia.NAMES


def parameter_names(robot: Robot, convention: str) -> list[str]:
    """The standard parameters' names ``body.PARAM``, e.g. ``link2.ZZ``.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    convention : str
        The parameter convention (:data:`~baseparams.model.inertia.CONVENTIONS`); ``paper``
        names are the spatial pseudo-inertia entries ``MXX...M`` written ``XX...M`` (at q = 0,
        world frame).

    Returns
    -------
    list of str, length ``10 n``
        One name per parameter, bodies in order, each in the convention's order.
    """
    return [f"{b}.{p}" for b in robot.names for p in _NAMES[convention]]


def paper_from(robot: Robot, convention: str) -> np.ndarray:
    """Block-diagonal ``T (10 n, 10 n)``: paper parameters = ``T @`` convention parameters.

    Conventions other than ``paper`` are link-frame (the body frame), mapped by ``M0``.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies; its ``M0`` maps body frames to the world frame at q = 0).
    convention : str
        The convention of the parameters ``T`` multiplies.

    Returns
    -------
    T : ndarray, shape ``(10 n, 10 n)``
        One ``(10, 10)`` block per body; the identity for ``paper``.
    """
    n = robot.n
    t = np.zeros((10 * n, 10 * n))
    if convention == "paper":
        return np.eye(10 * n)
    eye = np.eye(10)
    per = _inertia.from_convention(eye, convention)  # (10, 4, 4) body-frame N of unit params
    for i in range(n):
        t[10 * i:10 * i + 10, 10 * i:10 * i + 10] = _inertia.hat(_inertia.transform(per, robot.M0[i])).T
    return t


#: a dimensionless coefficient ``K[i, d] L^(u_d - u_i)`` at most this, relative to the largest of
#: its row (and at least to the 1 of ``pi_I``), is rounding noise: zero
ZERO_TOL = 1e-9
# the tolerances grow to NOISE_FACTOR times ``eps * cond(L^-u T^-1)``: the rounding of a nullspace
# basis orthonormal in SI units (absolute, ``~eps``) as the dimensionless coordinates see it
#: coefficients snap to the shortest decimal within this relative distance
SNAP_RTOL = 1e-13

#: about how many terms :meth:`BaseParameters.iter_expressions` formats at once (the expanded form of a
#: 1 000-link chain has over ten million: their text is made and let go a block of rows at a time)
EXPRESSION_CHUNK_TERMS = 50_000


def clean(x: np.ndarray, rtol: float = SNAP_RTOL) -> np.ndarray:
    """Snap every entry to the shortest decimal within ``rtol`` relative of it.

    E.g. ``0.18645124000000003 -> 0.18645124``, ``0.9999999999999998 -> 1`` (1 to 17
    significant digits); no entry moves by more than ``rtol`` relative. Zeros stay zero;
    removing rounding noise (a relative matter) is the caller's job.

    Parameters
    ----------
    x : array_like
        Numbers, any shape; non-finite entries are kept as they are.
    rtol : float
        The largest relative move (:data:`SNAP_RTOL`).

    Returns
    -------
    ndarray
        A snapped copy, same shape.
    """
    x = np.array(x, dtype=float, order="C")  # C order: flat is a view (an F-ordered copy was never snapped)
    flat = x.reshape(-1)
    nz = np.flatnonzero(np.isfinite(flat) & (flat != 0))
    if not len(nz):
        return x
    v = flat[nz]
    a = np.abs(v)
    digits = np.full(len(v), 17)
    with np.errstate(all="ignore"):
        mag = np.floor(np.log10(a))
        mant = v / 10.0 ** mag  # in [1, 10) up to rounding; only decides the digits
        for p in range(1, 17):
            todo = (digits == 17) & np.isfinite(mant)
            if not todo.any():
                break
            ok = np.abs(np.round(mant[todo], p - 1) - mant[todo]) <= rtol * np.abs(mant[todo])
            digits[np.flatnonzero(todo)[ok]] = p
    short = np.flatnonzero(digits < 17)  # 17 significant digits: the value as it is
    snapped = v.copy()
    snapped[short] = [float(f"{c:.{k - 1}e}") for c, k in zip(v[short].tolist(), digits[short].tolist())]
    bad = np.abs(snapped - v) > rtol * a  # the decimal string decides; never lose more than rtol
    snapped[bad] = v[bad]
    flat[nz] = snapped
    return x


def format_coefficient(c: float) -> str:
    """A coefficient at the precision it has, without float-repr noise.

    Parameters
    ----------
    c : float
        A coefficient.

    Returns
    -------
    str
        The shortest decimal of ``c`` rounded to 12 significant digits
        (:func:`baseparams.display.format_number`): ``2`` for ``2.0``, ``0.00041209`` for
        ``0.0004120899999999``. A computed coefficient is not more precise than that; the
        arrays (``K``, ``E``) keep every bit.
    """
    return format_number(c)


@dataclass(frozen=True, eq=False)
class BaseParameters:
    """The base-parameter structure of a robot in one convention.

    ``beta = pi_I + K pi_D`` (module doc), built by :func:`base_parameters`; ``nb`` base
    parameters, ``k`` the nullity, ``n`` bodies.

    Parameters
    ----------
    convention : str
        The parameter convention of ``pi``, ``names`` and ``K``.
    names : list of str, length ``10 n``
        Names of all standard parameters (:func:`parameter_names`).
    independent : ndarray of int, shape ``(nb,)``
        Indices of ``pi_I``.
    dependent : ndarray of int, shape ``(k,)``
        Indices of ``pi_D``.
    K : ndarray or scipy.sparse.csr_matrix, shape ``(nb, k)``
        Regrouping coefficients (sparse from :func:`baseparams.base.sparse.tree_base_parameters`).
    E : ndarray or scipy.sparse.csr_matrix, shape ``(nb, 10 n)``
        ``beta = E @ pi`` (convention coordinates).
    unidentifiable : ndarray of int
        Indices of parameters that no base parameter sees.
    base_basis : ndarray, shape ``(10 n, nb)``, or None
        Orthonormal basis of ``Null^perp`` in the paper convention (``None`` from the sparse
        regrouping of a large tree: it would be dense).
    T : ndarray or scipy.sparse.csr_matrix, shape ``(10 n, 10 n)``
        :func:`paper_from`: paper parameters = ``T @`` convention parameters.
    recursive : RecursiveForm, optional
        The same regrouping in recursive form (:mod:`baseparams.base.recursive`: ``O(n)`` terms
        on a tree). When given, ``K`` and ``E`` may be ``None``: they are expanded from it when
        first read (``O(sum of depths)`` nonzeros), and :meth:`to_base` and the expressions do
        not read them.
    """

    convention: str
    names: list[str]
    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    E: np.ndarray
    unidentifiable: np.ndarray
    base_basis: np.ndarray
    T: np.ndarray
    recursive: object = None

    @property
    def n_base(self) -> int:
        """Number of base parameters ``nb``."""
        return len(self.independent)

    def __repr__(self) -> str:
        return (f"<BaseParameters {self.convention}: {self.n_base} base of {len(self.names)} standard parameters, "
                f"nullity {len(self.dependent)}, {len(self.unidentifiable)} unidentifiable>")

    def base_names(self) -> list[str]:
        """The base parameters' names.

        Returns
        -------
        list of str, length ``nb``
            ``NAMER`` when the parameter absorbs others (Khalil's suffix), else ``NAME``.
        """
        if self.__dict__.get("_K") is None and self.recursive is not None:
            r = self.recursive.R  # K's row is nonzero exactly where R's is ((I - S) is invertible)
            absorbs = np.diff(r.indptr) > 0 if _is_sparse(r) else (
                np.any(r != 0, axis=1) if r.shape[1] else np.zeros(len(self.independent), bool))
        elif _is_sparse(self.K):
            absorbs = np.diff(self.K.indptr) > 0
        else:
            absorbs = np.any(self.K != 0, axis=1) if self.K.shape[1] else np.zeros(len(self.independent), bool)
        return [self.names[i] + ("R" if a else "") for i, a in zip(self.independent, absorbs)]

    def expressions(self, form: str = "expanded") -> list[dict[str, str]]:
        """Each base parameter as a combination of standard ones.

        Parameters
        ----------
        form : {"expanded", "recursive"}
            ``expanded``: standard parameters only; ``recursive``: the body's own standard
            parameters and its children's regrouped dependent parameters (``link3.MR``, defined by
            :meth:`definitions`; needs :attr:`recursive`).

        Returns
        -------
        list of dict
            ``[{"name": ..., "expression": ...}]``, e.g. ``link1.ZZR`` and
            ``link1.ZZ + link2.YY + ...`` (coefficients written only when not 1).

        Raises
        ------
        BaseparamsError
            ``recursive`` without a recursive form, or an unknown form.
        """
        if form == "recursive":
            if self.recursive is None:
                raise BaseparamsError("these base parameters have no recursive form (a tree regrouped from compact "
                                      "nullspace columns has one: analyze(..., form='recursive'))")
            return self.recursive.base_expressions(self.base_names())
        return list(self.iter_expressions(form))

    def iter_expressions(self, form: str = "expanded", max_terms: int | None = None):
        """:meth:`expressions` one at a time: the expanded form's text made a block of rows at a time.

        The expanded form has ``O(sum of depths)`` terms on a tree (quadratic on a chain): written
        whole it would hold every term's text at once; here at most about ``max_terms`` terms'.

        Parameters
        ----------
        form : {"expanded", "recursive"}
            As :meth:`expressions`.
        max_terms : int, optional
            About how many terms are formatted together (a row is never split; default
            :data:`EXPRESSION_CHUNK_TERMS`).

        Yields
        ------
        dict
            ``{"name", "expression"}``, in :meth:`expressions`' order.

        Raises
        ------
        BaseparamsError
            As :meth:`expressions` (when the first item is asked for).
        """
        if form == "recursive":
            yield from self.expressions("recursive")
            return
        if form != "expanded":
            raise BaseparamsError(f"unknown form {form!r}; expected 'expanded' or 'recursive'")
        heads = [self.names[i] for i in self.independent.tolist()]
        names = self.base_names()
        terms = [self.names[d] for d in self.dependent.tolist()]
        for start, stop, indptr, indices, data in self._row_blocks(max_terms or EXPRESSION_CHUNK_TERMS):
            yield from format_rows(heads[start:stop], names[start:stop], indptr, indices, data, terms,
                                   self.dependent)

    def _row_blocks(self, max_terms: int):
        """``K``'s rows in blocks ``(start, stop, indptr, indices, data)``, at most about ``max_terms`` terms each.

        From ``K``, or from the recursive form when there is one
        (:meth:`~.recursive.RecursiveForm.expand_rows`: ``K`` is never held whole).
        """
        blocks = (self.recursive.expand_rows() if self.recursive is not None  # the same text whether K was made
                  else [(0, len(self.independent), *self._terms())])
        for first, last, indptr, indices, data in blocks:
            start = 0
            while start < last - first:  # rows [start, stop): at least one, about max_terms terms
                stop = max(start + 1, int(np.searchsorted(indptr, indptr[start] + max_terms, side="right")) - 1)
                stop = min(stop, last - first)
                lo, hi = indptr[start], indptr[stop]
                yield first + start, first + stop, indptr[start:stop + 1] - lo, indices[lo:hi], data[lo:hi]
                start = stop

    def expanded_size(self) -> tuple[int, float]:
        """The expanded form's size: ``K``'s nonzeros and largest magnitude (a pass over the rows, not held).

        Returns
        -------
        terms : int
            How many terms the expanded expressions write beyond each base parameter's own.
        largest : float
            The largest coefficient's magnitude (0 without one): past ``1 / eps`` (about
            ``4.5e15``) a base parameter ``beta = pi_I + K pi_D`` cannot be computed in double
            precision next to its own standard parameter.
        """
        cached = self.__dict__.get("_size")
        if cached is None:
            terms, largest = 0, 0.0
            for _, _, _, _, data in self._row_blocks(EXPRESSION_CHUNK_TERMS):
                terms += len(data)
                largest = max(largest, float(np.abs(data).max()) if len(data) else 0.0)
            cached = self.__dict__["_size"] = (terms, largest)
        return cached

    def definitions(self) -> list[dict[str, str]]:
        """The regrouped dependent parameters the recursive form's expressions use (``[]`` without one).

        Returns
        -------
        list of dict
            ``[{"name", "expression"}]``, e.g. ``link2.MR``: ``link2.M + link3.MR`` (root side
            first); a dependent parameter that absorbs nothing is written as itself.
        """
        return [] if self.recursive is None else self.recursive.definitions()

    def _terms(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``K``'s nonzeros row by row: ``(indptr (nb + 1,), column indices, values)``, dense or sparse."""
        if _is_sparse(self.K):
            return self.K.indptr, self.K.indices, self.K.data
        rows, cols = np.nonzero(self.K)  # row-major: row by row
        indptr = np.r_[0, np.cumsum(np.bincount(rows, minlength=self.K.shape[0]))]
        return indptr, cols, self.K[rows, cols]

    def _check(self, convention: str) -> None:
        _inertia.check_convention(convention)
        if convention != self.convention:
            raise BaseparamsError(
                f"parameter vector in the {convention!r} convention given to base parameters regrouped in the "
                f"{self.convention!r} convention; regroup in {convention!r} (base_parameters(..., {convention!r})) "
                f"or convert the vector first")

    def to_base(self, pi: np.ndarray, convention: str) -> np.ndarray:
        """Base parameters ``beta (nb,)`` from a full vector ``pi (10 n,)``.

        Parameters
        ----------
        pi : array_like, shape ``(10 n,)``
            Standard parameters.
        convention : str
            Required: names ``pi``'s convention; it must be this object's :attr:`convention`
            (a mismatch is an error, never a number).

        Returns
        -------
        beta : ndarray, shape ``(nb,)``
            ``E @ pi``.

        Raises
        ------
        BaseparamsError
            A convention mismatch or a wrong shape (:class:`ModelError`: an unknown convention).
        """
        self._check(convention)
        pi = np.asarray(pi, dtype=float)
        if pi.shape != (len(self.names),):
            raise BaseparamsError(f"expected a parameter vector of shape ({len(self.names)},), got {pi.shape}")
        if self.__dict__.get("_E") is None and self.recursive is not None:  # O(n): t = (I - S)^-1 pi_D
            rf = self.recursive
            return pi[self.independent] + rf.R @ rf.solve_t(pi[self.dependent])
        return self.E @ pi

    def from_base(self, beta: np.ndarray) -> np.ndarray:
        """The minimum-norm full vector with these base parameters.

        Parameters
        ----------
        beta : array_like, shape ``(nb,)``
            Base parameters.

        Returns
        -------
        pi : ndarray, shape ``(10 n,)``
            ``pinv(E) @ beta``, in this object's :attr:`convention`.

        Raises
        ------
        BaseparamsError
            A wrong shape.
        """
        beta = np.asarray(beta, dtype=float)
        if beta.shape != (self.n_base,):
            raise BaseparamsError(f"expected {self.n_base} base parameters, got shape {beta.shape}")
        if _is_sparse(self.E):  # E has full row rank: the minimum-norm solution E^T (E E^T)^-1 beta
            from scipy.sparse.linalg import spsolve

            return self.E.T @ np.atleast_1d(spsolve((self.E @ self.E.T).tocsc(), beta))
        return np.linalg.pinv(self.E) @ beta


def _lazy(name: str, doc: str) -> property:
    """``K`` or ``E``: stored, or made when first read (``None`` given): from the recursive form, ``E`` from ``K``."""
    key = "_" + name

    def get(self):
        v = self.__dict__.get(key)
        if v is None and (self.recursive is not None or (key == "_E" and self.__dict__.get("_K") is not None)):
            v = _expand(self, name)
            self.__dict__[key] = v
        return v

    def put(self, value):
        self.__dict__[key] = value

    return property(get, put, doc=doc)


def _expand(bp: BaseParameters, name: str):
    """``K = R (I - S)^-1`` from the recursive form, or ``E = [I | K]`` on the independent and dependent columns."""
    k = bp.__dict__.get("_K")
    if k is None:
        k = bp.recursive.expand()
        bp.__dict__["_K"] = k
    if name == "K":
        return k
    nb, n10 = len(bp.independent), len(bp.names)
    if not _is_sparse(k):
        e = np.zeros((nb, n10))
        e[np.arange(nb), bp.independent] = 1.0
        e[:, bp.dependent] = k
        return e
    import scipy.sparse as sp

    kc = k.tocoo()
    return sp.csr_matrix((np.r_[np.ones(nb), kc.data], (np.r_[np.arange(nb), kc.row],
                                                         np.r_[bp.independent, bp.dependent[kc.col]])),
                         shape=(nb, n10))


# K and E as properties after the dataclass is made (its __init__ stores through the setters)
BaseParameters.K = _lazy("K", "Regrouping coefficients ``(nb, k)`` (expanded from the recursive form when needed).")
BaseParameters.E = _lazy("E", "``beta = E @ pi`` ``(nb, 10 n)`` (expanded from the recursive form when needed).")


def format_rows(heads: list[str], row_names: list[str], indptr: np.ndarray, indices: np.ndarray,
                data: np.ndarray, term_names: list[str], order_key: np.ndarray | None = None) -> list[dict[str, str]]:
    """Rows ``head + sum coefficient * term`` as text: every coefficient formatted once, rows joined.

    Parameters
    ----------
    heads : list of str, length ``r``
        Each row's leading term (coefficient 1).
    row_names : list of str, length ``r``
        Each row's name.
    indptr : ndarray of int, shape ``(r + 1,)``
        CSR row pointers of the terms.
    indices : ndarray of int
        Each term's index into ``term_names``.
    data : ndarray
        Each term's coefficient.
    term_names : list of str
        The terms' names.
    order_key : ndarray of int, optional
        A sort key per term name (terms are written in its order within a row; default: the index).

    Returns
    -------
    list of dict
        ``[{"name", "expression"}]``; a coefficient of 1 is not written.
    """
    indptr = np.asarray(indptr)
    indices = np.asarray(indices, dtype=int)
    data = np.asarray(data, dtype=float)
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    keyv = indices if order_key is None else np.asarray(order_key)[indices]
    order = np.lexsort((keyv, rows))  # row by row, terms in parameter order
    vals = data[order]
    mags = np.abs(vals)
    # '%.12g' is format_coefficient's text where it writes positional numbers (1e-4 <= c < 1e6;
    # a margin below 1e6, where rounding could reach it)
    uniq, inv = np.unique(mags, return_inverse=True)
    shared = len(uniq) < len(mags) // 2  # many repeated magnitudes: format each distinct one once
    each = uniq if shared else mags
    fast = (each >= 1e-4) & (each < 9e5)
    text = ["" if m == 1 else (f"{m:.12g}*" if f else f"{format_coefficient(m)}*")
            for m, f in zip(each.tolist(), fast.tolist())]
    coef = [text[j] for j in inv.tolist()] if shared else text
    terms = [f"{'-' if c < 0 else '+'} {t}{term_names[d]}"
             for c, t, d in zip(vals.tolist(), coef, indices[order].tolist())]
    return [{"name": name, "expression": " ".join([head] + terms[indptr[r]:indptr[r + 1]])}
            for r, (head, name) in enumerate(zip(heads, row_names))]


def _is_sparse(a) -> bool:
    """True for a scipy.sparse matrix (without importing scipy)."""
    return hasattr(a, "tocsr")


def choose_dependent(b: np.ndarray, order: np.ndarray, rtol: float = 1e-8) -> np.ndarray:
    """Greedy rows of ``b (m, k)`` (in ``order``) spanning R^k: ``b[D]`` invertible.

    A row is taken when its component outside the span of the rows taken so far is above
    ``rtol`` times the largest row norm: with ``b`` an orthonormal basis (of dimensionless
    coordinates) the choice depends on its column space only, not on the basis chosen in it.

    Parameters
    ----------
    b : ndarray, shape ``(m, k)``
        A nullspace basis, one row per parameter.
    order : ndarray of int
        Candidate parameters, most preferred dependent first.
    rtol : float
        Relative threshold of a row's new component.

    Returns
    -------
    ndarray of int, shape ``(<= k,)``
        The dependent parameters chosen (``k`` of them when ``b`` has full column rank).
    """
    k = b.shape[1]
    basis = np.zeros((0, k))
    chosen = []
    scale = max(float(np.linalg.norm(b, axis=1).max()), 1e-300) if len(b) else 1.0
    for r in order:
        v = b[r].copy()
        for _ in range(2):  # Gram-Schmidt twice: orthogonal to working precision
            if len(basis):
                v -= basis.T @ (basis @ v)
        nv = np.linalg.norm(v)
        if nv > rtol * scale:
            basis = np.vstack([basis, v / nv])
            chosen.append(r)
            if len(chosen) == k:
                break
    return np.array(chosen, dtype=int)


def base_parameters(robot: Robot, null_basis: np.ndarray, convention: str) -> BaseParameters:
    """Regroup into base parameters, given a nullspace basis.

    Decisions are made on dimensionless coordinates: with ``L`` the robot's
    :func:`length_scale` and ``u`` the length exponent of each parameter (:data:`LENGTH_POWER`),
    the nullspace rows are scaled by ``L^-u`` and orthonormalised before the dependent set is
    chosen, and a coefficient is zero when ``|K[i, d]| L^(u_d - u_i)`` is below
    :data:`ZERO_TOL` (relative to its row's largest, and to 1). Scaling every length of the
    robot by ``s`` (and masses by anything) thus gives the same names and structure, with
    ``K[i, d]`` scaled by ``s^(u_i - u_d)``. Coefficients are then snapped (:func:`clean`).

    The basis given is orthonormal in SI units, so its rounding (``~eps``, absolute) is
    ``~eps cond(L^-u T^-1)`` in the dimensionless coordinates: ``~1e-8`` for a robot drawn in
    millimetres. The tolerances grow with it (:data:`NOISE_FACTOR`), and so does the error of
    ``K``: such a basis cannot tell more.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    null_basis : ndarray, shape ``(10 n, k)``
        Nullspace basis in the paper convention: orthonormal, or any basis of full column rank
        such as :attr:`~baseparams.nullspace.certify.Certificate.span`, which is more precise.
    convention : str
        The parameter convention to regroup in (:data:`~baseparams.model.inertia.CONVENTIONS`).

    Returns
    -------
    BaseParameters
        ``10 n - k`` base parameters in ``convention``.

    Raises
    ------
    RuntimeError
        The basis is rank-deficient.
    """
    n10 = 10 * robot.n
    t = paper_from(robot, convention)
    tinv = np.linalg.inv(t)
    b = tinv @ null_basis  # nullspace in convention coordinates
    k = b.shape[1]
    power = np.tile(LENGTH_POWER[convention], robot.n)
    ell = length_scale(robot)
    # dimensionless nullspace rows, orthonormalised: the same subspace for every scaling
    scale = ell ** -power.astype(float)
    q, _ = np.linalg.qr(scale[:, None] * b) if k else (np.zeros((n10, 0)), None)
    # the input's absolute rounding, amplified by the map to dimensionless coordinates
    sv = np.linalg.svd((scale[:, None] * tinv).reshape(robot.n, 10, robot.n, 10)[
        np.arange(robot.n), :, np.arange(robot.n), :], compute_uv=False)
    noise = NOISE_FACTOR * np.finfo(float).eps * sv.max() / max(sv.min(), 1e-300)
    # candidate order: last body first; within a body the convention's regrouping order (M, MZ,
    # MY, MX, then second moments backwards: inertia.SPECS)
    within = _inertia.SPECS[convention].regroup_order
    order = np.array([10 * i + w for i in reversed(range(robot.n)) for w in within])
    dep = choose_dependent(q, order, max(1e-8, noise)) if k else np.zeros(0, dtype=int)
    if len(dep) < k:
        raise RuntimeError("nullspace basis is rank-deficient; orthonormalise it first")
    keep = np.ones(n10, dtype=bool)  # not np.setdiff1d: it imports numpy.ma (start-up time)
    keep[dep] = False
    ind = np.flatnonzero(keep)
    if k:
        kdim = -np.linalg.solve(q[dep].T, q[ind].T).T  # dimensionless K
        row = np.maximum(1.0, np.abs(kdim).max(axis=1, keepdims=True))
        kdim[np.abs(kdim) <= max(ZERO_TOL, noise) * row] = 0.0
        kmat = clean(kdim * ell ** (power[ind][:, None] - power[dep][None, :]).astype(float))
    else:
        kmat = np.zeros((len(ind), 0))
    e = np.zeros((len(ind), n10))
    e[np.arange(len(ind)), ind] = 1.0
    e[:, dep] = kmat
    # base space basis (paper convention): orthonormal complement of the nullspace
    if k:
        u, _, _ = np.linalg.svd(null_basis, full_matrices=True)
        base_basis = u[:, k:]
    else:
        base_basis = np.eye(n10)
    # a standard parameter is unidentifiable iff its unit vector lies in the nullspace (rows of
    # the orthonormal dimensionless basis of norm 1; a diagonal scaling keeps unit vectors)
    unid = np.flatnonzero(np.abs(np.einsum("ij,ij->i", q, q) - 1) < 1e-9) if k else np.zeros(0, dtype=int)
    return BaseParameters(convention, parameter_names(robot, convention), ind, dep, kmat, e, unid,
                          base_basis, t)
