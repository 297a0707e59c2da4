"""Independent test oracle: Khalil's symbolic regrouping of the inertial parameters.

Base inertial parameters of a serial robot in modified Denavit-Hartenberg (Khalil &
Kleinfinger) notation, derived in SymPy from the rules of Gautier & Khalil (1990, "Direct
calculation of minimum set of inertial parameters of serial robots") and Khalil & Dombre
("Modeling, Identification and Control of Robots", the chapter on base inertial parameters).
Nothing here uses the project's symbolic code; every grouping coefficient is re-derived from
the transformation of a link's inertia into its antecedent's frame (:func:`transfer_matrix`).

Notation
--------
``T(j-1, j) = Rot(x, alpha_j) Trans(x, d_j) Rot(z, theta_j) Trans(z, r_j)``; a revolute joint
(``sigma = 0``) adds ``q_j`` to ``theta_j``, a prismatic one (``sigma = 1``) to ``r_j``. The
parameters of link ``j`` are SymPy symbols ``XXj XYj XZj YYj YZj ZZj MXj MYj MZj Mj``: the
inertia tensor about the origin of frame ``j`` (tensor entries, ``XY = -int x y dm``), the
first moments ``m c`` and the mass, all in frame ``j``. The base is fixed; gravity is along
``z0`` when ``gravity_vertical``, else taken as not parallel to the first revolute axis (the
rules see gravity only through that: rule P-2).

Rules implemented (applied from ``j = n`` down to ``1``, so that grouped values carry down)
------------------------------------------------------------------------------------------
G-R, general rule, revolute joint ``j``
    The part ``YYj diag(1, 1, 0)`` of the inertia tensor, the first moment ``MZj z_j`` and the
    mass ``Mj`` form a body that is symmetric about ``z_j``: its kinetic and potential
    energies do not depend on ``q_j``, so it is carried by link ``j-1``. ``YYj``, ``MZj`` and
    ``Mj`` are eliminated: ``XXRj = XXj - YYj`` and link ``j-1``'s ten parameters receive the
    transform of ``(XX, YY, MZ, M) = (YYj, YYj, MZj, Mj)`` into frame ``j-1`` (checked here to
    be free of ``q_j``): e.g. ``XXR(j-1) = XX(j-1) + YYj + 2 rj MZj + rj^2 Mj``,
    ``MXR(j-1) = MX(j-1) + dj Mj``, ``MR(j-1) = M(j-1) + Mj``. For ``j = 1`` they move to
    the base and have no effect.
G-P, general rule, prismatic joint ``j``
    Link ``j`` rotates with link ``j-1``: its whole inertia tensor ``XXj .. ZZj`` is carried by
    link ``j-1`` through the constant rotation, ``J(j-1) += R J_j R^T``.
Particular rules near the base. ``r1`` is the first revolute joint, ``u`` its axis and
``r2`` the first revolute joint not parallel to ``u`` (``n + 1`` when there is none).
P-1, revolute ``j`` with ``r1 <= j < r2``
    Link ``j`` rotates about ``u = z_j`` only, so ``XXRj``, ``XYRj``, ``XZRj`` and ``YZRj``
    have no effect; ``ZZRj`` stays.
P-2, same links, origin on the axis of ``r1``
    When ``O_j`` lies on the axis of ``r1`` for every configuration (always for ``j = r1 = 1``,
    the first link; also for joints coaxial with it) and gravity is parallel to ``u``,
    ``MXRj`` and ``MYRj`` have no effect (the origin's velocity is along ``u`` and the
    potential energy does not see them): for the usual vertical first axis only ``ZZR1`` is
    left of link 1.
P-3, prismatic ``j`` with ``r1 < j < r2`` and ``z_j`` parallel to ``u`` (SCARA)
    ``MZj`` has no effect, and ``MXj``, ``MYj`` are carried by link ``j-1`` as first moments
    at the origin of frame ``j`` at ``q_j = 0`` (the translation along ``u`` changes neither
    their kinetic nor their potential energy); ``Mj`` stays (``MRj``).
P-4, prismatic ``j`` with ``r1 < j < r2`` and ``z_j`` not parallel to ``u``
    The component of ``MS_j`` along ``u`` (``a = u`` in frame ``j``) has no effect: ``MZj`` is
    eliminated, ``MXRj = MXj - a_x / a_z MZj``, ``MYRj = MYj - a_y / a_z MZj`` (``MYj`` is
    eliminated instead when ``a_z = 0``, then ``MXj`` when ``a_y = 0`` too).

Not implemented (:class:`NotImplementedError` rather than a guess)
-----------------------------------------------------------------
* robots without a revolute joint, and prismatic joints before the first revolute one
  (the textbook's rules for links ``j < r1``, where masses of a Cartesian chain group);
* trees, closed loops and floating bases (``rows`` is a serial chain; :func:`read_dh`
  rejects ``ant != j - 1``);
* rotor inertias ``Ia_j`` (their particular groupings with ``ZZR_r1``, ``ZZR_r2`` or ``MR``);
* gravity parallel to a first revolute axis that is not ``z0`` (the flag cannot say it);
* geometries whose parallelism SymPy cannot decide. Symbolic twist angles are generic: an
  axis is parallel to another only when it is for every value of the symbols.

Beyond ``r2`` only the general rules are applied: they give the base parameters of the usual
industrial geometries (Puma, Stanford, SCARA, 6R with a spherical wrist), but particular
geometries that the textbook leaves to a numerical method (parallelograms, links whose
parameters cancel for special values of the lengths) are not detected.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import sympy as sp

#: a link's parameters, in this (Khalil / SYMORO) order
PARAMS = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")
_XX, _XY, _XZ, _YY, _YZ, _ZZ, _MX, _MY, _MZ, _M = range(10)
_J = range(6)


@dataclass(frozen=True)
class DHTable:
    """A robot read from a ``.dh`` text table (:func:`read_dh`).

    Parameters
    ----------
    name : str
        The table's ``name`` line.
    gravity : tuple of float
        The ``gravity`` line, frame 0.
    values : dict of sympy.Symbol to float
        The ``values`` line: a number for each length symbol.
    rows : list of tuple
        ``(sigma, alpha, d, theta, r)`` per joint, SymPy entries.
    """

    name: str
    gravity: tuple[float, float, float]
    values: dict
    rows: list


def read_dh(path) -> DHTable:
    """Read a modified-DH table (``j ant sigma alpha d theta r`` and header lines).

    Parameters
    ----------
    path : str or Path
        The ``.dh`` file: ``#`` comments, ``name``, ``description``, ``convention modified``,
        ``gravity gx gy gz``, ``values S=v ...``, the column header, one row per joint.

    Returns
    -------
    DHTable
        The table, entries through :func:`sympy.sympify`.

    Raises
    ------
    ValueError
        Another convention, a malformed row, or a tree (``ant != j - 1``).
    """
    name, gravity, values, rows = "", (0.0, 0.0, -9.81), {}, []
    for line in Path(path).read_text().splitlines():
        tok = line.split("#", 1)[0].split()
        if not tok or tok[0] in ("description", "j"):
            continue
        key, rest = tok[0], tok[1:]
        if key == "name":
            name = " ".join(rest)
        elif key == "convention":
            if rest != ["modified"]:
                raise ValueError(f"{path}: convention {rest}, expected modified")
        elif key == "gravity":
            gravity = tuple(float(x) for x in rest)
        elif key == "values":
            values = {sp.Symbol(k): float(x) for k, x in (t.split("=") for t in rest)}
        elif key.isdigit():
            if len(rest) != 6 or int(key) != len(rows) + 1 or int(rest[0]) != len(rows):
                raise ValueError(f"{path}: row {line!r}: expected joint {len(rows) + 1} after joint {len(rows)}")
            rows.append(tuple(sp.sympify(x) for x in rest[1:]))
        else:
            raise ValueError(f"{path}: unknown line {line!r}")
    return DHTable(name, gravity, values, rows)


def parameter_symbols(j: int) -> list[sp.Symbol]:
    """The ten standard parameters of link ``j``.

    Parameters
    ----------
    j : int
        Link index, from 1.

    Returns
    -------
    list of sympy.Symbol
        ``XXj XYj XZj YYj YZj ZZj MXj MYj MZj Mj``.
    """
    return [sp.Symbol(f"{p}{j}") for p in PARAMS]


def rot_x(a) -> sp.Matrix:
    """Rotation about ``x`` by ``a``.

    Parameters
    ----------
    a : sympy.Expr
        Angle.

    Returns
    -------
    sympy.Matrix, shape ``(3, 3)``
        ``Rot(x, a)``.
    """
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_z(a) -> sp.Matrix:
    """Rotation about ``z`` by ``a``.

    Parameters
    ----------
    a : sympy.Expr
        Angle.

    Returns
    -------
    sympy.Matrix, shape ``(3, 3)``
        ``Rot(z, a)``.
    """
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def link_transform(row, q=0) -> tuple[sp.Matrix, sp.Matrix]:
    """Rotation and origin of frame ``j`` in frame ``j-1``.

    Parameters
    ----------
    row : tuple
        ``(sigma, alpha, d, theta, r)`` of joint ``j``.
    q : sympy.Expr
        The joint coordinate (added to ``theta`` or ``r``).

    Returns
    -------
    R : sympy.Matrix, shape ``(3, 3)``
        ``Rot(x, alpha) Rot(z, theta)``.
    P : sympy.Matrix, shape ``(3, 1)``
        ``(d, -sin(alpha) r, cos(alpha) r)``.
    """
    sigma, alpha, d, theta, r = row
    theta = theta + q if sigma == 0 else theta
    r = r + q if sigma == 1 else r
    rot = rot_x(alpha) * rot_z(theta)
    pos = sp.Matrix([d, 0, 0]) + rot_x(alpha) * sp.Matrix([0, 0, r])
    return rot, pos


def _tensor(p) -> sp.Matrix:
    return sp.Matrix([[p[_XX], p[_XY], p[_XZ]], [p[_XY], p[_YY], p[_YZ]], [p[_XZ], p[_YZ], p[_ZZ]]])


def transfer_matrix(rot: sp.Matrix, pos: sp.Matrix) -> sp.Matrix:
    """The linear map of a body's parameters from frame ``j`` to frame ``j-1``.

    For a body with inertia tensor ``J`` about ``O_j``, first moments ``MS`` and mass ``M``
    (frame ``j``), fixed in a frame ``j`` at ``(R, P)`` in frame ``j-1``, its parameters in
    frame ``j-1`` are

        J' = R J R^T + M (|P|^2 1 - P P^T) + 2 (P . MS') 1 - (MS' P^T + P MS'^T),
        MS' = R MS (then + M P),   M' = M,

    from ``J_O' = int (|P + y|^2 1 - (P + y)(P + y)^T) dm``.

    Parameters
    ----------
    rot : sympy.Matrix, shape ``(3, 3)``
        ``R``, frame ``j`` in frame ``j-1``.
    pos : sympy.Matrix, shape ``(3, 1)``
        ``P``, the origin of frame ``j`` in frame ``j-1``.

    Returns
    -------
    sympy.Matrix, shape ``(10, 10)``
        ``Lambda`` with ``params(j-1 frame) = Lambda @ params(j frame)`` in :data:`PARAMS` order.
    """
    p = sp.symbols("p0:10")
    eye = sp.eye(3)
    ms = rot * sp.Matrix(p[_MX:_M])
    jj = (rot * _tensor(p) * rot.T + p[_M] * ((pos.T * pos)[0] * eye - pos * pos.T)
          + 2 * (pos.T * ms)[0] * eye - (ms * pos.T + pos * ms.T))
    out = [jj[0, 0], jj[0, 1], jj[0, 2], jj[1, 1], jj[1, 2], jj[2, 2], *(ms + p[_M] * pos), p[_M]]
    lam = sp.Matrix(out).jacobian(sp.Matrix(p))
    return lam.applyfunc(lambda e: sp.trigsimp(sp.expand(e)))


def _is_zero(e) -> bool:
    """Whether ``e`` vanishes identically (in the joint coordinates and lengths).

    SymPy decides; when it leaves an expression that vanishes at three arbitrary points
    anyway, the question is left open rather than answered ``False``.
    """
    e = sp.simplify(sp.expand_trig(sp.expand(e)))
    if e == 0:
        return True
    syms = sorted(e.free_symbols, key=str)
    points = ([sp.Rational(3 + 7 * k + 2 * i, 11 + k) for i in range(len(syms))] for k in range(3))
    if all(abs(complex(e.subs(dict(zip(syms, pt))).evalf())) < 1e-12 for pt in points):
        raise NotImplementedError(f"cannot decide whether {e} vanishes identically")
    return False


def _parallel(a: sp.Matrix, b: sp.Matrix) -> bool:
    return all(_is_zero(c) for c in a.cross(b))


def _chain(rows, qs):
    """Rotations and origins of every frame in frame 0 as functions of ``qs``."""
    rot, pos = sp.eye(3), sp.zeros(3, 1)
    out = []
    for row, q in zip(rows, qs):
        r, p = link_transform(row, q)
        pos = pos + rot * p
        rot = rot * r
        out.append((rot, pos))
    return out


def _check_rows(rows) -> None:
    for j, row in enumerate(rows, start=1):
        if len(row) != 5 or row[0] not in (0, 1):
            raise ValueError(f"row {j}: expected (sigma in {{0, 1}}, alpha, d, theta, r), got {row!r}")
    sig = [row[0] for row in rows]
    if 0 not in sig:
        raise NotImplementedError("no revolute joint: the particular rules of a Cartesian chain are not implemented")
    if sig[0] != 0:
        raise NotImplementedError("prismatic joints before the first revolute one (links j < r1) are not implemented")


def khalil_base_parameters(rows, gravity_vertical: bool = True) -> dict[str, sp.Expr]:
    """Base inertial parameters of a serial robot by Khalil's rules (module doc).

    Parameters
    ----------
    rows : sequence of tuple
        ``(sigma, alpha, d, theta, r)`` per joint ``j = 1..n`` (SymPy entries), a serial chain
        in modified DH; ``sigma`` 0 revolute, 1 prismatic.
    gravity_vertical : bool
        Gravity along ``z0``; ``False``: gravity not parallel to the first revolute axis.

    Returns
    -------
    dict of str to sympy.Expr
        ``{name: expression}`` in link order then :data:`PARAMS` order: ``"ZZR1"`` (``P R j``)
        when other parameters are grouped into ``Pj``, ``"XY2"`` when it stands alone.
        Eliminated parameters and those with no effect are absent.

    Raises
    ------
    NotImplementedError
        A geometry outside the implemented rules (module doc).
    ValueError
        A malformed row.
    """
    rows = [tuple(sp.sympify(e) for e in row) for row in rows]
    _check_rows(rows)
    n = len(rows)
    qs = sp.symbols(f"q1:{n + 1}", real=True)
    frames = _chain(rows, qs)
    r1 = 1  # _check_rows: joint 1 is revolute
    u = frames[0][0][:, 2]  # the axis of r1 in frame 0 (constant: no joint before it)
    gravity_along_u = gravity_vertical and _parallel(u, sp.Matrix([0, 0, 1]))
    r2 = next((j for j in range(r1 + 1, n + 1)
               if rows[j - 1][0] == 0 and not _parallel(frames[j - 1][0][:, 2], u)), n + 1)

    vals = {j: list(parameter_symbols(j)) for j in range(1, n + 1)}
    gone: dict[int, set[int]] = {j: set() for j in range(1, n + 1)}

    def carry(j: int, lam: sp.Matrix, x: list) -> None:
        """``vals[j-1] += lam @ x`` (nothing for the base)."""
        if j > 1:
            add = lam * sp.Matrix(x)
            vals[j - 1] = [sp.expand(a + b) for a, b in zip(vals[j - 1], add)]

    for j in range(n, 0, -1):
        row, v = rows[j - 1], vals[j]
        if row[0] == 0:
            # G-R: (YY, YY, MZ, M) of link j move to link j-1
            rot, pos = link_transform(row, qs[j - 1])
            lam = transfer_matrix(rot, pos)
            cols = [c.applyfunc(sp.trigsimp) for c in (lam[:, _XX] + lam[:, _YY], lam[:, _MZ], lam[:, _M])]
            if any(qs[j - 1] in c.free_symbols for col in cols for c in col):
                raise AssertionError(f"joint {j}: the grouped part depends on q{j}")  # pragma: no cover
            carry(j, sp.Matrix.hstack(*cols), [v[_YY], v[_MZ], v[_M]])
            v[_XX] = sp.expand(v[_XX] - v[_YY])
            gone[j] |= {_YY, _MZ, _M}
            if r1 <= j < r2:  # P-1
                gone[j] |= {_XX, _XY, _XZ, _YZ}
                on_axis = _parallel(frames[j - 1][1] - frames[r1 - 1][1], u)
                if on_axis and gravity_along_u:  # P-2
                    gone[j] |= {_MX, _MY}
        else:
            # G-P: the inertia tensor of link j moves to link j-1 through the constant rotation
            rot, pos = link_transform(row)
            lam = transfer_matrix(rot, pos)
            carry(j, lam[:, :6], v[:6])
            gone[j] |= set(_J)
            if r1 < j < r2:
                a = (frames[j - 1][0].T * u).applyfunc(sp.simplify)  # u in frame j
                if any(q in e.free_symbols for e in a for q in qs):
                    raise AssertionError(f"joint {j}: the axis of r1 seen from frame {j} moves")  # pragma: no cover
                if _parallel(a, sp.Matrix([0, 0, 1])):  # P-3
                    carry(j, lam[:, _MX:_MZ], v[_MX:_MZ])
                    gone[j] |= {_MX, _MY, _MZ}
                else:  # P-4: MS_j + t a has the same effect for every t
                    k = next(i for i in (2, 1, 0) if not _is_zero(a[i]))
                    for i in range(k):
                        v[_MX + i] = sp.expand(v[_MX + i] - a[i] / a[k] * v[_MX + k])
                    gone[j].add(_MX + k)
    out = {}
    for j in range(1, n + 1):
        for i, p in enumerate(PARAMS):
            if i in gone[j]:
                continue
            e = sp.expand(vals[j][i])
            out[f"{p}{'R' if e != sp.Symbol(f'{p}{j}') else ''}{j}"] = e
    return out
