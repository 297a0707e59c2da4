"""Reference implementation of the full geometric algebra G(3,0,1).

A multivector is an array ``(*, 16)`` over the canonical basis blades, indexed by
bitmask (bit k set <=> e_k is a factor, k = 0..3), e.g. index 0b0110 = e12.
Metric: e0^2 = 0, e1^2 = e2^2 = e3^2 = 1 (the paper's eq. "inner product").

This module is the slow, obviously-correct oracle: every fast formula in
:mod:`baseparams.pga.core` is derived from it and checked against it in tests.
It is not used in hot paths.
"""

from __future__ import annotations

import numpy as np

_METRIC = (0.0, 1.0, 1.0, 1.0)


def blade_product(a: int, b: int) -> tuple[float, int]:
    """Sign and bitmask of the product of basis blades ``a`` and ``b``.

    Parameters
    ----------
    a, b : int
        Basis blades as bitmasks (bit k set <=> e_k is a factor, k = 0..3), in canonical order.

    Returns
    -------
    sign : float
        +1 or -1 from the reordering, times the metric of the shared factors (0 when both
        contain e0).
    index : int
        Bitmask of the product, ``a ^ b``.
    """
    # count swaps needed to bring b's factors past a's (canonical reordering)
    sign = 1.0
    x = a >> 1
    swaps = 0
    while x:
        swaps += bin(x & b).count("1")
        x >>= 1
    if swaps % 2:
        sign = -1.0
    common = a & b
    for k in range(4):
        if common >> k & 1:
            sign *= _METRIC[k]
    return sign, a ^ b


def _build_tables() -> tuple[np.ndarray, np.ndarray]:
    gp = np.zeros((16, 16, 16))
    wedge = np.zeros((16, 16, 16))
    for a in range(16):
        for b in range(16):
            s, c = blade_product(a, b)
            gp[a, b, c] = s
            if a & b == 0:
                # outer product: same reordering sign, no metric involved
                x = a >> 1
                swaps = 0
                while x:
                    swaps += bin(x & b).count("1")
                    x >>= 1
                wedge[a, b, a | b] = -1.0 if swaps % 2 else 1.0
    return gp, wedge


GP_TABLE, WEDGE_TABLE = _build_tables()
GRADE = np.array([bin(k).count("1") for k in range(16)])
REVERSE_SIGN = np.array([(-1.0) ** (g * (g - 1) // 2) for g in GRADE])


def blade(name: str) -> tuple[float, int]:
    """Sign and index of a named blade, e.g. ``blade("e032") == (-1.0, 0b1101)``.

    Parameters
    ----------
    name : str
        ``e`` followed by distinct digits 0..3 in any order (``"e032"``), or ``"1"`` / ``""`` for
        the scalar.

    Returns
    -------
    sign : float
        +1 or -1: the named blade is ``sign`` times the canonical basis blade.
    index : int
        The canonical basis blade's bitmask.

    Raises
    ------
    ValueError
        A repeated factor.
    """
    if name in ("1", ""):
        return 1.0, 0
    digits = [int(c) for c in name.lstrip("e")]
    sign, idx = 1.0, 0
    for d in digits:
        s, idx2 = blade_product(idx, 1 << d)
        if idx & (1 << d):
            raise ValueError(f"repeated factor in {name}")
        sign *= s
        idx = idx2
    return sign, idx


def gp(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Geometric product of full multivectors ``(*, 16)``.

    Parameters
    ----------
    a, b : ndarray, shape ``(*, 16)``
        Multivectors (broadcast against each other).

    Returns
    -------
    ndarray, shape ``(*, 16)``
        ``a b``.
    """
    return np.einsum("...i,...j,ijk->...k", a, b, GP_TABLE)


def wedge(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Outer product of full multivectors ``(*, 16)``.

    Parameters
    ----------
    a, b : ndarray, shape ``(*, 16)``
        Multivectors (broadcast against each other).

    Returns
    -------
    ndarray, shape ``(*, 16)``
        ``a ^ b`` (no metric involved).
    """
    return np.einsum("...i,...j,ijk->...k", a, b, WEDGE_TABLE)


def reverse(a: np.ndarray) -> np.ndarray:
    """Reverse ``~A`` of full multivectors ``(*, 16)``: grade ``k`` times ``(-1)^(k (k-1) / 2)``.

    Parameters
    ----------
    a : ndarray, shape ``(*, 16)``
        Multivectors.

    Returns
    -------
    ndarray, shape ``(*, 16)``
        ``~a``.
    """
    return a * REVERSE_SIGN


# --- named embeddings (the paper's coordinates) -------------------------------------------

POINT_BLADES = ("e032", "e013", "e021", "e123")
LINE_BLADES = ("e23", "e31", "e12", "e01", "e02", "e03")
MOTOR_BLADES = ("1",) + LINE_BLADES + ("e0123",)


def _embed(x: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    out = np.zeros(x.shape[:-1] + (16,))
    for k, name in enumerate(names):
        s, idx = blade(name)
        out[..., idx] += s * x[..., k]
    return out


def _extract(mv: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    out = np.zeros(mv.shape[:-1] + (len(names),))
    for k, name in enumerate(names):
        s, idx = blade(name)
        out[..., k] = s * mv[..., idx]
    return out


def from_point(p: np.ndarray) -> np.ndarray:
    """Point ``(*, 4)`` [x, y, z, w] -> multivector ``(*, 16)``.

    Parameters
    ----------
    p : array_like, shape ``(*, 4)``
        ``x e032 + y e013 + z e021 + w e123`` (the paper's coordinates, :mod:`baseparams.pga.core`).

    Returns
    -------
    ndarray, shape ``(*, 16)``
        The trivector.
    """
    return _embed(p, POINT_BLADES)


def to_point(mv: np.ndarray) -> np.ndarray:
    """Point ``(*, 4)`` [x, y, z, w] of a multivector ``(*, 16)``: the inverse of :func:`from_point`.

    Parameters
    ----------
    mv : ndarray, shape ``(*, 16)``
        Multivectors (only the trivector part is read).

    Returns
    -------
    ndarray, shape ``(*, 4)``
        The coefficients of ``e032, e013, e021, e123``.
    """
    return _extract(mv, POINT_BLADES)


def from_line(l: np.ndarray) -> np.ndarray:
    """Line ``(*, 6)`` in order e23 e31 e12 e01 e02 e03 -> multivector.

    Parameters
    ----------
    l : array_like, shape ``(*, 6)``
        Line (twist, wrench) coordinates ``(d, m)``.

    Returns
    -------
    ndarray, shape ``(*, 16)``
        The bivector.
    """
    return _embed(l, LINE_BLADES)


def to_line(mv: np.ndarray) -> np.ndarray:
    """Line ``(*, 6)`` (e23 e31 e12 e01 e02 e03) of a multivector: the inverse of :func:`from_line`.

    Parameters
    ----------
    mv : ndarray, shape ``(*, 16)``
        Multivectors (only the bivector part is read).

    Returns
    -------
    ndarray, shape ``(*, 6)``
        The coefficients of ``e23, e31, e12, e01, e02, e03``.
    """
    return _extract(mv, LINE_BLADES)


def from_motor(m: np.ndarray) -> np.ndarray:
    """Motor ``(*, 8)`` in order 1 e23 e31 e12 e01 e02 e03 e0123 -> multivector.

    Parameters
    ----------
    m : array_like, shape ``(*, 8)``
        Even elements (motors).

    Returns
    -------
    ndarray, shape ``(*, 16)``
        The even multivector.
    """
    return _embed(m, MOTOR_BLADES)


def to_motor(mv: np.ndarray) -> np.ndarray:
    """Motor ``(*, 8)`` (1 e23 e31 e12 e01 e02 e03 e0123) of a multivector: the inverse of :func:`from_motor`.

    Parameters
    ----------
    mv : ndarray, shape ``(*, 16)``
        Multivectors (only the even part is read).

    Returns
    -------
    ndarray, shape ``(*, 8)``
        The coefficients of ``1, e23, e31, e12, e01, e02, e03, e0123``.
    """
    return _extract(mv, MOTOR_BLADES)


def pseudoscalar(mv: np.ndarray) -> np.ndarray:
    """The pseudoscalar (``e0123``) coefficient of multivectors ``(*, 16)``.

    Parameters
    ----------
    mv : ndarray, shape ``(*, 16)``
        Multivectors.

    Returns
    -------
    ndarray, shape ``(*)``
        The coefficient of ``e0123`` (index ``0b1111``).
    """
    return mv[..., 15]


def dual(mv: np.ndarray) -> np.ndarray:
    """The paper's dual: e032 <-> e1, e013 <-> e2, e021 <-> e3, e123 <-> e0 (linear).

    Parameters
    ----------
    mv : ndarray, shape ``(*, 16)``
        Multivectors; only their vector and trivector parts are mapped.

    Returns
    -------
    ndarray, shape ``(*, 16)``
        The dual (other grades zero).
    """
    pairs = (("e032", "e1"), ("e013", "e2"), ("e021", "e3"), ("e123", "e0"))
    out = np.zeros_like(mv)
    for tri, vec in pairs:
        s1, i1 = blade(tri)
        s2, i2 = blade(vec)
        out[..., i2] += s1 * mv[..., i1] * s2
        out[..., i1] += s2 * mv[..., i2] * s1
    return out


def vee_points(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Join of two points via the paper's dual definition ``(P* ^ Q*)*``, as a line ``(*, 6)``.

    The dual of a bivector is taken as the complement that the paper's formula implies;
    only used to cross-check :func:`baseparams.pga.core.join`.

    Parameters
    ----------
    p, q : ndarray, shape ``(*, 4)``
        Points ``[x, y, z, w]``.

    Returns
    -------
    ndarray, shape ``(*, 6)``
        The line ``P v Q`` (e23 e31 e12 e01 e02 e03).
    """
    a = dual(from_point(p))
    b = dual(from_point(q))
    w = wedge(a, b)  # bivector e_ij with i, j in 0..3
    # map e_ij (plane-plane meet) to the joined line's coordinates
    out = np.zeros(w.shape[:-1] + (6,))
    comp = {"e01": "e23", "e02": "e31", "e03": "e12", "e23": "e01", "e31": "e02", "e12": "e03"}
    for k, name in enumerate(LINE_BLADES):
        src = [s for s, d in comp.items() if d == name][0]
        s, idx = blade(src)
        out[..., k] = s * w[..., idx]
    return out
