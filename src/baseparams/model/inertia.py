"""Inertial parameters: the pseudo-inertia ``N`` and the parameter orderings users bring.

The library's own convention (``"paper"``) is the paper's hat operator applied to the
pseudo-inertia ``N = [[Sigma, h], [h^T, m]]`` (second moments ``Sigma``, first moments ``h``,
mass ``m``):

    paper: [N11 N12 N13 N22 N23 N33 N14 N24 N34 N44]
         = [MXX MXY MXZ MYY MYZ MZZ MX MY MZ M]

expressed in some frame (the spatial frame at the reference configuration for the
regressor; the body frame for link-frame conventions). The other conventions use the
rotational inertia tensor ``J`` about the frame origin (tensor entries, so ``Ixy`` is
``-int x y dm``), related by ``Sigma = tr(J)/2 * 1 - J``:

=========  ====================================================
khalil     XX XY XZ YY YZ ZZ MX MY MZ M   (SYMORO)
pinocchio  m mcx mcy mcz Ixx Ixy Iyy Ixz Iyz Izz
idyntree   m mcx mcy mcz Ixx Ixy Ixz Iyy Iyz Izz
rpna       m mcx mcy mcz Ixx Iyy Izz Iyz Ixz Ixy
=========  ====================================================
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..display import summary_repr
from ..enums import Convention, values
from ..errors import ModelError

#: Paper order of the ten entries of a symmetric 4x4 matrix (row, column), eq. "hat".
HAT_INDEX = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2), (0, 3), (1, 3), (2, 3), (3, 3))

#: what a parameter is, by field: mass ``m``, first moments ``hx hy hz`` (``m c``), entries
#: ``ixx ixy ...`` of the rotational inertia about the frame's origin (link-frame conventions)
#: or ``sxx sxy ...`` of the second moments ``Sigma`` (the paper's pseudo-inertia)
PARAMETER_FIELDS = ("m", "hx", "hy", "hz", "ixx", "ixy", "ixz", "iyy", "iyz", "izz",
                    "sxx", "sxy", "sxz", "syy", "syz", "szz")
#: names in the SYMORO style (khalil, and the paper's pseudo-inertia entries ``MXX`` written ``XX``)
_SYMORO = {"m": "M", "hx": "MX", "hy": "MY", "hz": "MZ",
           **{f"{k}{ab}": ab.upper() for k in "is" for ab in ("xx", "xy", "xz", "yy", "yz", "zz")}}
#: names in the ``m mcx ... Ixx`` style (pinocchio, iDynTree, RPNA)
_MC = {"m": "m", "hx": "mcx", "hy": "mcy", "hz": "mcz",
       **{f"i{ab}": f"I{ab}" for ab in ("xx", "xy", "xz", "yy", "yz", "zz")}}
_LINK = "link frame (each body's joint frame), inertia about its origin"
#: the regrouping's within-body candidate order (:func:`baseparams.base.regroup.base_parameters`):
#: mass, first moments z y x, then the second moments backwards
_BACK = ("m", "hz", "hy", "hx", "izz", "iyz", "iyy", "ixz", "ixy", "ixx")


@dataclass(frozen=True)
class ConventionSpec:
    """One parameter convention, the one table everything derives from.

    The converters (:func:`to_convention`, :func:`from_convention`), :data:`NAMES`,
    :data:`FRAMES`, :data:`LENGTH_POWER` and the CLI's ``--convention`` choices come from
    :data:`SPECS`, which holds one of these per convention.

    Parameters
    ----------
    convention : Convention
        The convention this table describes.
    fields : tuple of str, length 10
        What each of a body's ten parameters is, in the convention's order (entries of
        :data:`PARAMETER_FIELDS`).
    names : tuple of str, length 10
        The parameters' names as printed, in the same order.
    frame : str
        What the parameters are expressed in (e.g. the link frame, or the world frame at q = 0
        for ``paper``).
    regroup : tuple of str, length 10
        Fields in the order the regrouping tries them as dependent, within a body.
    """

    convention: Convention
    fields: tuple[str, ...]
    names: tuple[str, ...]
    frame: str
    regroup: tuple[str, ...]

    __repr__ = summary_repr

    @property
    def length_power(self) -> np.ndarray:
        """Length exponent ``u`` of each parameter: mass 0, first moments 1, second moments 2."""
        return np.array([0 if f == "m" else 1 if f[0] == "h" else 2 for f in self.fields])

    @property
    def regroup_order(self) -> tuple[int, ...]:
        """:attr:`regroup` as indices into the convention's order."""
        return tuple(self.fields.index(f) for f in self.regroup)


def _spec(convention: Convention, fields: str, names: dict[str, str], frame: str = _LINK,
          regroup: tuple[str, ...] = _BACK) -> ConventionSpec:
    f = tuple(fields.split())
    return ConventionSpec(convention, f, tuple(names[k] for k in f), frame, regroup)


#: every convention's table (:class:`ConventionSpec`), keyed by :class:`~baseparams.enums.Convention`
SPECS = {c.convention: c for c in (
    _spec(Convention.PAPER, "sxx sxy sxz syy syz szz hx hy hz m", _SYMORO,
          "spatial pseudo-inertia entries, world frame at q = 0",
          ("m", "hz", "hy", "hx", "szz", "syz", "syy", "sxz", "sxy", "sxx")),
    _spec(Convention.KHALIL, "ixx ixy ixz iyy iyz izz hx hy hz m", _SYMORO),
    _spec(Convention.PINOCCHIO, "m hx hy hz ixx ixy iyy ixz iyz izz", _MC),
    _spec(Convention.IDYNTREE, "m hx hy hz ixx ixy ixz iyy iyz izz", _MC),
    # RPNA tries ixx before the products of inertia (its historical order)
    _spec(Convention.RPNA, "m hx hy hz ixx iyy izz iyz ixz ixy", _MC,
          regroup=("m", "hz", "hy", "hx", "izz", "iyz", "iyy", "ixx", "ixz", "ixy")),
)}
assert tuple(SPECS) == tuple(Convention)

#: the conventions' names (plain strings; ``baseparams.CONVENTIONS``)
CONVENTIONS = values(Convention)
PAPER_NAMES = SPECS[Convention.PAPER].names
KHALIL_NAMES = SPECS[Convention.KHALIL].names

#: each convention's parameter names, in its order (names and reports derive from it)
NAMES = {c: s.names for c, s in SPECS.items()}

#: length exponent ``u`` of each parameter, per convention: second moments / inertia entries 2,
#: first moments 1, mass 0. ``K[i, d]`` has units ``L^(u_i - u_d)`` (the mass units cancel).
LENGTH_POWER = {c: s.length_power for c, s in SPECS.items()}

#: the frame each convention's parameters are expressed in
FRAMES = {c: s.frame for c, s in SPECS.items()}


def describe(convention: str) -> str:
    """One line: the convention's name, frame and per-body parameter order.

    Parameters
    ----------
    convention : str
        One of :data:`CONVENTIONS` (``paper``, ``khalil``, ``pinocchio``, ``idyntree``, ``rpna``).

    Returns
    -------
    str
        E.g. ``"khalil convention: link frame (...); per body XX XY XZ YY YZ ZZ MX MY MZ M"``.
    """
    return f"{convention} convention: {FRAMES[convention]}; per body {' '.join(NAMES[convention])}"


def check_convention(convention: str) -> Convention:
    """Check a convention's name.

    Parameters
    ----------
    convention : str
        A parameter convention's name.

    Returns
    -------
    Convention
        ``convention`` as a :class:`~baseparams.enums.Convention` if it is one of
        :data:`CONVENTIONS`.

    Raises
    ------
    ModelError
        ``convention`` is not one of :data:`CONVENTIONS` (the message names them).
    """
    if not isinstance(convention, str):
        raise ModelError(f"the parameter convention must be a name ({', '.join(CONVENTIONS)}), got "
                         f"{type(convention).__name__}")
    if convention not in CONVENTIONS:
        raise ModelError(f"unknown parameter convention {convention!r}; expected one of {', '.join(CONVENTIONS)}")
    return Convention(convention)


def _lookup(convention: str) -> ConventionSpec:
    if convention not in SPECS:
        raise ValueError(f"unknown parameter convention {convention!r}; expected one of {CONVENTIONS}")
    return SPECS[convention]


_ROWS = np.array([r for r, _ in HAT_INDEX])
_COLS = np.array([c for _, c in HAT_INDEX])


def hat(n: np.ndarray) -> np.ndarray:
    """Paper's hat operator (eq. "hat"): symmetric ``(*, 4, 4)`` -> ``(*, 10)``.

    Parameters
    ----------
    n : array_like, shape ``(*, 4, 4)``
        Symmetric matrices, e.g. pseudo-inertias ``N``.

    Returns
    -------
    ndarray, shape ``(*, 10)``
        The entries in :data:`HAT_INDEX` order ``N11 N12 N13 N22 N23 N33 N14 N24 N34 N44``
        (entries, not doubled).
    """
    return np.asarray(n)[..., _ROWS, _COLS]


def unhat(p: np.ndarray) -> np.ndarray:
    """Inverse of :func:`hat`: ``(*, 10)`` -> symmetric ``(*, 4, 4)``.

    Parameters
    ----------
    p : array_like, shape ``(*, 10)``
        Entries in :data:`HAT_INDEX` order (the ``paper`` convention).

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        The symmetric matrices.
    """
    p = np.asarray(p, dtype=float)
    out = np.zeros(p.shape[:-1] + (4, 4))
    out[..., _ROWS, _COLS] = p
    out[..., _COLS, _ROWS] = p
    return out


def pseudo_inertia(mass: float, com: np.ndarray, inertia_com: np.ndarray) -> np.ndarray:
    """Pseudo-inertia from mass, centre of mass and rotational inertia about the centre of mass.

    All inputs are expressed in the same frame; the result is expressed in it too.

    Parameters
    ----------
    mass : float
        Mass ``m`` [kg].
    com : array_like, shape ``(3,)``
        Centre of mass ``c`` [m].
    inertia_com : array_like, shape ``(3, 3)``
        Rotational inertia tensor about the centre of mass [kg m^2].

    Returns
    -------
    ndarray, shape ``(4, 4)``
        The pseudo-inertia ``N = [[Sigma, h], [h^T, m]]`` with ``h = m c``.
    """
    com = np.asarray(com, dtype=float)
    j_com = np.asarray(inertia_com, dtype=float)
    j_o = j_com + mass * (np.dot(com, com) * np.eye(3) - np.outer(com, com))
    return pseudo_from_origin(mass, mass * com, j_o)


def pseudo_from_origin(mass: float, h: np.ndarray, j_origin: np.ndarray) -> np.ndarray:
    """Pseudo-inertia from mass, first moment ``h = m c`` and inertia about the origin.

    Uses ``Sigma = tr(J)/2 * 1 - J``; broadcasts over leading axes.

    Parameters
    ----------
    mass : float or array_like, shape ``(*)``
        Mass ``m`` [kg].
    h : array_like, shape ``(*, 3)``
        First moment ``m c`` [kg m].
    j_origin : array_like, shape ``(*, 3, 3)``
        Rotational inertia tensor ``J`` about the frame origin [kg m^2].

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        The pseudo-inertias ``N = [[Sigma, h], [h^T, m]]``, in the frame of the inputs.
    """
    n = np.zeros(np.shape(mass) + (4, 4))
    n[..., :3, :3] = 0.5 * np.trace(j_origin, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - j_origin
    n[..., :3, 3] = h
    n[..., 3, :3] = h
    n[..., 3, 3] = mass
    return n


def split(n: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, first moment and inertia about the origin from pseudo-inertias.

    Parameters
    ----------
    n : ndarray, shape ``(*, 4, 4)``
        Pseudo-inertias.

    Returns
    -------
    m : ndarray, shape ``(*)``
        Masses.
    h : ndarray, shape ``(*, 3)``
        First moments ``m c``.
    J_origin : ndarray, shape ``(*, 3, 3)``
        Rotational inertia tensors about the frame origin, ``J = tr(Sigma) * 1 - Sigma``.
    """
    sigma = n[..., :3, :3]
    j = np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - sigma
    return n[..., 3, 3], n[..., :3, 3], j


def transform(n: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Express pseudo-inertias in another frame: ``T N T^T``.

    Parameters
    ----------
    n : ndarray, shape ``(*, 4, 4)``
        Pseudo-inertias in the old frame.
    t : ndarray, shape ``(*, 4, 4)``
        Homogeneous transforms mapping old to new coordinates (the old frame's pose in the new one).

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        The pseudo-inertias in the new frame.
    """
    return t @ n @ np.swapaxes(t, -1, -2)


def to_convention(n: np.ndarray, convention: str) -> np.ndarray:
    """Parameter vectors ``(*, 10)`` in ``convention`` from pseudo-inertias ``(*, 4, 4)``.

    The frame is the one ``n`` is expressed in (no change of frame here).

    Parameters
    ----------
    n : array_like, shape ``(*, 4, 4)``
        Pseudo-inertias.
    convention : str
        One of :data:`CONVENTIONS`.

    Returns
    -------
    ndarray, shape ``(*, 10)``
        Ten parameters per body in the convention's order (:data:`NAMES`).

    Raises
    ------
    ValueError
        Unknown convention.
    """
    n = np.asarray(n, dtype=float)
    if convention == "paper":
        return hat(n)
    fields = _lookup(convention).fields
    m, h, j = split(n)
    v = {"m": m, "hx": h[..., 0], "hy": h[..., 1], "hz": h[..., 2]}
    v.update({f"i{'xyz'[r]}{'xyz'[c]}": j[..., r, c] for r in range(3) for c in range(r, 3)})
    return np.stack([v[f] for f in fields], axis=-1)


def from_convention(p: np.ndarray, convention: str) -> np.ndarray:
    """Pseudo-inertias ``(*, 4, 4)`` from parameter vectors ``(*, 10)`` in ``convention``.

    The inverse of :func:`to_convention` (no change of frame here).

    Parameters
    ----------
    p : array_like, shape ``(*, 10)``
        Ten parameters per body in the convention's order (:data:`NAMES`).
    convention : str
        One of :data:`CONVENTIONS`.

    Returns
    -------
    ndarray, shape ``(*, 4, 4)``
        The pseudo-inertias, in the frame the parameters are expressed in.

    Raises
    ------
    ValueError
        ``p`` does not have 10 entries per body, or an unknown convention.
    """
    p = np.asarray(p, dtype=float)
    if p.shape[-1] != 10:
        raise ValueError(f"parameter vectors must have 10 entries per body, got shape {p.shape}")
    if convention == "paper":
        return unhat(p)
    v = {k: p[..., i] for i, k in enumerate(_lookup(convention).fields)}
    j = np.empty(p.shape[:-1] + (3, 3))
    j[..., 0, 0], j[..., 1, 1], j[..., 2, 2] = v["ixx"], v["iyy"], v["izz"]
    j[..., 0, 1] = j[..., 1, 0] = v["ixy"]
    j[..., 0, 2] = j[..., 2, 0] = v["ixz"]
    j[..., 1, 2] = j[..., 2, 1] = v["iyz"]
    h = np.stack([v["hx"], v["hy"], v["hz"]], axis=-1)
    return pseudo_from_origin(v["m"], h, j)


def convert(p: np.ndarray, src: str, dst: str) -> np.ndarray:
    """Convert parameter vectors ``(*, 10)`` between conventions (same frame).

    Parameters
    ----------
    p : array_like, shape ``(*, 10)``
        Parameter vectors in convention ``src``.
    src, dst : str
        The source and destination conventions (:data:`CONVENTIONS`).

    Returns
    -------
    ndarray, shape ``(*, 10)``
        The same parameters in convention ``dst``, expressed in the same frame (``dst="paper"``
        from link-frame parameters gives the link frame's pseudo-inertia entries, not the world
        frame at q = 0 of :meth:`~baseparams.model.robot.Robot.parameters`).
    """
    return to_convention(from_convention(p, src), dst)


@dataclass(frozen=True, eq=False)
class Inertia:
    """Rigid-body inertia, all expressed in ``frame``.

    Parameters
    ----------
    mass : float
        Mass [kg].
    com : tuple of float, shape ``(3,)``
        Centre of mass [m] in ``frame``.
    inertia : array_like, shape ``(3, 3)``, ``(3,)`` or ``(6,)``
        Rotational inertia [kg m^2] about the centre of mass, in ``frame``: a 3x3 tensor, the
        principal moments ``(ixx, iyy, izz)`` or ``(ixx, iyy, izz, ixy, ixz, iyz)`` (URDF
        attribute order); see :meth:`inertia_matrix`.
    frame : ndarray, shape ``(4, 4)``, optional
        Pose of the inertia frame relative to the body frame; ``None`` (identity) = the
        body/joint frame, as in URDF ``<inertial>``.
    """

    mass: float
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: tuple[tuple[float, float, float], ...] | tuple[float, ...] = ((0, 0, 0), (0, 0, 0), (0, 0, 0))
    frame: np.ndarray | None = None

    __repr__ = summary_repr

    def inertia_matrix(self) -> np.ndarray:
        """The rotational inertia about the centre of mass as a tensor.

        Returns
        -------
        ndarray, shape ``(3, 3)``
            :attr:`inertia` [kg m^2] in ``frame``: as given when 3x3, diagonal from
            ``(ixx, iyy, izz)``, symmetric from ``(ixx, iyy, izz, ixy, ixz, iyz)``.

        Raises
        ------
        ValueError
            :attr:`inertia` has another shape.
        """
        i = np.asarray(self.inertia, dtype=float)
        if i.shape == (3, 3):
            return i
        if i.shape == (3,):
            return np.diag(i)
        if i.shape == (6,):  # ixx iyy izz ixy ixz iyz (URDF attribute order)
            ixx, iyy, izz, ixy, ixz, iyz = i
            return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        raise ValueError(f"inertia must be 3x3, (ixx, iyy, izz) or (ixx, iyy, izz, ixy, ixz, iyz); got shape {i.shape}")

    def pseudo(self) -> np.ndarray:
        """Pseudo-inertia in the body frame.

        Returns
        -------
        ndarray, shape ``(4, 4)``
            The pseudo-inertia ``N`` in the body (joint) frame (:attr:`frame` applied).
        """
        n = pseudo_inertia(float(self.mass), np.asarray(self.com, dtype=float), self.inertia_matrix())
        if self.frame is not None:
            n = transform(n, np.asarray(self.frame, dtype=float))
        return n


def is_physically_consistent(n: np.ndarray, tol: float = 0.0) -> np.ndarray:
    """True where the pseudo-inertia is positive semidefinite (Wensing et al. 2018).

    Parameters
    ----------
    n : array_like, shape ``(*, 4, 4)``
        Pseudo-inertias.
    tol : float
        Allowed negative eigenvalue (absolute).

    Returns
    -------
    ndarray of bool, shape ``(*)``
        True where the smallest eigenvalue is at least ``-tol``.
    """
    return np.linalg.eigvalsh(np.asarray(n)).min(axis=-1) >= -tol


class InertiaWarning(UserWarning):
    """A physically infeasible inertia in a file, accepted (the default outside ``strict``)."""


def check_inertia(mass: float, inertia_com: np.ndarray, what: str, rtol: float = 1e-6,
                  strict: bool = False) -> bool:
    """Physical feasibility: mass >= 0, principal moments >= 0 and the triangle inequality.

    A violation is an :class:`InertiaWarning` (one line naming ``what``): the base-parameter
    structure does not depend on the inertia values, so the analysis goes on. With ``strict``
    it is a :class:`ModelError` instead (identification, where a prior must be feasible, or
    ``strict_inertia`` in the readers).

    Parameters
    ----------
    mass : float
        Mass [kg].
    inertia_com : array_like, shape ``(3, 3)``
        Rotational inertia [kg m^2] about the centre of mass (any frame).
    what : str
        What the inertia belongs to, for the message (e.g. the file and link).
    rtol : float
        Tolerance on the principal moments, relative to the largest.
    strict : bool
        Raise instead of warning.

    Returns
    -------
    bool
        True when feasible, False when infeasible (and not ``strict``).

    Raises
    ------
    ModelError
        With ``strict``: the inertia is not feasible (or not symmetric).

    Warns
    -----
    InertiaWarning
        Without ``strict``: the inertia is not feasible (or not symmetric).
    """
    try:
        if mass < 0:
            raise ModelError(f"{what}: inertia not physically feasible (negative mass {mass:.3g})")
        _check_moments(np.asarray(inertia_com, dtype=float), what, rtol)
    except ModelError as exc:
        if strict:
            raise ModelError(f"{exc} (strict inertia checking)") from None
        warnings.warn(f"{exc}; the base-parameter structure does not depend on it", InertiaWarning,
                      stacklevel=3)
        return False
    return True


def _check_moments(inertia_com: np.ndarray, what: str, rtol: float) -> None:
    j = inertia_com
    if np.abs(j - j.T).max() > 1e-12 * (1 + np.abs(j).max()):
        raise ModelError(f"{what}: inertia matrix is not symmetric")
    lam = np.linalg.eigvalsh(j)
    tol = rtol * max(float(np.abs(lam).max()), 1e-300) + 1e-12
    if lam.min() < -tol:
        raise ModelError(f"{what}: inertia not physically feasible (negative principal moment {lam.min():.3g})")
    a, b, c = lam
    if a + b < c - tol:
        raise ModelError(f"{what}: inertia not physically feasible (principal moments {a:.3g}, {b:.3g}, "
                         f"{c:.3g} violate the triangle inequality)")
