"""Robots whose geometry is symbolic: SymPy transforms, DH tables, numbers substituted back.

A :class:`SymbolicRobot` is a :class:`~baseparams.model.robot.Robot` whose joint poses at the
reference configuration (q = 0) are SymPy matrices in some symbols (link lengths, offsets).
Joint axes and rotations must be exact numbers (e.g. DH twists that are multiples of ``pi/2``
give exact 0 and +-1); positions may be any polynomial in the symbols. Built by
:class:`SymbolicBuilder` (the :class:`~baseparams.model.builder.RobotBuilder` API, SymPy
entries) or from a Denavit-Hartenberg table (:func:`from_dh`, :mod:`~baseparams.symbolic.tables`).

Frames: every body's frame is its joint frame (as in the numeric model); the parameters of
the link-frame conventions (``khalil``) are expressed in :attr:`SymbolicRobot.param_frames`
(the DH link frame ``j``: the joint frame for modified DH, the distal frame for standard DH).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import sympy as sp
from sympy.polys.polyerrors import CoercionFailed, GeneratorsError

from ..display import summary_repr
from ..errors import ModelError
from ..model import Inertia, Robot, RobotBuilder
from .angles import angle_of, cos_sin


def rot(axis: str, angle) -> sp.Matrix:
    """Homogeneous rotation ``(4, 4)`` about ``x``, ``y`` or ``z`` by an exact angle.

    Parameters
    ----------
    axis : {"x", "y", "z"}
        The rotation axis.
    angle : sympy expression or number
        The angle [rad]; multiples of ``pi/2`` give exact 0 and +-1; ``+-a + c`` for an angle
        symbol ``a`` gives rational functions of ``tan(a/2)`` (:mod:`.angles`).

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        The rotation.
    """
    c, s = cos_sin(angle)
    i = "xyz".index(axis)
    j, k = (i + 1) % 3, (i + 2) % 3
    m = sp.eye(4)
    m[j, j], m[j, k], m[k, j], m[k, k] = c, -s, s, c
    return m


def trans(axis: str, length) -> sp.Matrix:
    """Homogeneous translation ``(4, 4)`` along ``x``, ``y`` or ``z``.

    Parameters
    ----------
    axis : {"x", "y", "z"}
        The direction.
    length : sympy expression or number
        The distance [m] (a symbol, a number or a polynomial).

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        The translation.
    """
    m = sp.eye(4)
    m["xyz".index(axis), 3] = length
    return m


def transform(rotation=None, translation=(0, 0, 0)) -> sp.Matrix:
    """Homogeneous transform ``(4, 4)`` from an exact rotation ``(3, 3)`` and a translation ``(3,)``.

    Parameters
    ----------
    rotation : array_like, shape ``(3, 3)``, optional
        Exact rotation matrix (default identity).
    translation : array_like, shape ``(3,)``
        Position of the frame [m]: numbers, symbols or polynomials.

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        The pose.
    """
    m = sp.eye(4)
    if rotation is not None:
        m[:3, :3] = sp.Matrix(rotation)
    m[:3, 3] = sp.Matrix(list(translation))
    return m


def inverse(m: sp.Matrix) -> sp.Matrix:
    """Inverse ``(4, 4)`` of a rigid transform with an exact rotation: ``[R^T, -R^T p]``.

    Parameters
    ----------
    m : sympy.Matrix, shape ``(4, 4)``
        The transform.

    Returns
    -------
    sympy.Matrix, shape ``(4, 4)``
        Its inverse, polynomial when ``m`` is.
    """
    r = m[:3, :3].T
    return transform(r, matmul(-r, m[:3, 3]))


def _field_of(*mats: sp.Matrix):
    """``ZZ(symbols)`` of the matrices' symbols (``QQ`` without any)."""
    syms = sorted(set().union(*(m.free_symbols for m in mats)), key=lambda x: x.name)
    return sp.ZZ.frac_field(*syms) if syms else sp.QQ


def _in_field(m: sp.Matrix, dom):
    """``m`` as a ``DomainMatrix`` over ``dom``, or None outside it (e.g. ``sqrt(2)``)."""
    from sympy.polys.matrices import DomainMatrix

    try:
        if dom == sp.QQ:
            rows = [[dom.from_sympy(e) for e in m.row(r)] for r in range(m.rows)]
        else:
            ring, new = dom.get_ring(), dom.field.raw_new
            rows = [[new(*to_fraction(e, ring)) for e in m.row(r)] for r in range(m.rows)]
        return DomainMatrix(rows, m.shape, dom)
    except (CoercionFailed, GeneratorsError):
        return None


def to_fraction(e: sp.Expr, ring) -> tuple:
    """``e = num / den`` over ``ring`` (``ZZ[symbols]``), built term by term without cancelling.

    Denominators are combined by their lcm (small: products of ``1 + t^2``), numerators are never
    divided by a gcd (the expensive step of field arithmetic on large numerators).

    Parameters
    ----------
    e : sympy.Expr
        Rational in the ring's symbols, rational coefficients.
    ring : sympy.polys.domains.Domain
        A polynomial ring ``ZZ[symbols]``.

    Returns
    -------
    tuple
        ``(num, den)`` ring elements.

    Raises
    ------
    sympy.polys.polyerrors.CoercionFailed
        ``e`` is not rational in the ring's symbols (e.g. ``sqrt(2)``, an unknown symbol).
    """
    one = ring.one
    if e.is_Rational:
        return ring.convert(e.p), ring.convert(e.q)
    if e.is_Symbol:
        return ring.from_sympy(e), one
    if e.is_Add:
        terms = [to_fraction(a, ring) for a in e.args]
        den = one
        for _, d in terms:
            den = den if d in (den, one) else (d if den == one else den.lcm(d))
        return sum((n * (den if d == one else den.exquo(d)) for n, d in terms), ring.zero), den
    if e.is_Mul:
        num, den = one, one
        for a in e.args:
            n, d = to_fraction(a, ring)
            num, den = num * n, den * d
        return num, den
    if e.is_Pow and e.exp.is_Integer:
        n, d = to_fraction(e.base, ring)
        k = int(e.exp)
        return (n**k, d**k) if k >= 0 else (d**-k, n**-k)
    raise CoercionFailed(f"not rational in the symbols: {e}")


def normal(m: sp.Matrix) -> sp.Matrix:
    """``m`` with every entry in a canonical form: an expanded polynomial or one cancelled fraction.

    Computed over the field of rational functions of the symbols (sparse polynomials, gcds
    cancelled as they arise), which keeps the size of the entries in check where symbolic angles
    bring their half-angle denominators (expanding sums of fractions does not cancel them);
    entries outside that field (``sqrt(2)`` of an angle ``pi/4``) are expanded.

    Parameters
    ----------
    m : sympy.Matrix
        Any shape, entries rational in the symbols.

    Returns
    -------
    sympy.Matrix
        Same shape and values.
    """
    if not m.free_symbols:
        return m.applyfunc(sp.expand)
    dm = _in_field(m, _field_of(m))
    return m.applyfunc(sp.expand) if dm is None else dm.to_Matrix()


def matmul(*mats: sp.Matrix) -> sp.Matrix:
    """The product of the matrices, entries in :func:`normal` form (multiplied in the field).

    Parameters
    ----------
    *mats : sympy.Matrix
        Conformable matrices, entries rational in the symbols.

    Returns
    -------
    sympy.Matrix
        Their product.
    """
    dom = _field_of(*mats)
    dms = [_in_field(m, dom) for m in mats]
    if any(d is None for d in dms):
        out = mats[0]
        for m in mats[1:]:
            out = out * m
        return out.applyfunc(sp.expand)
    out = dms[0]
    for d in dms[1:]:
        out = out * d
    return out.to_Matrix()


def at_point(m: sp.Matrix, point: dict):
    """``m`` at rational values of its symbols, exactly: a ``DomainMatrix`` over QQ.

    Parameters
    ----------
    m : sympy.Matrix
        Entries rational in the symbols.
    point : dict
        ``{symbol: Rational}``.

    Returns
    -------
    sympy.polys.matrices.DomainMatrix
        Over ``QQ``; ``.rref()[1]`` are the pivots (generic ranks decided at random points).
    """
    from sympy.polys.matrices import DomainMatrix

    return DomainMatrix.from_Matrix(m.xreplace(point)).convert_to(sp.QQ)  # exact numbers: no pattern matching


def exact(x) -> sp.Expr:
    """A number or expression as an exact SymPy object (floats through their shortest decimal).

    Parameters
    ----------
    x : number, str or sympy expression
        The entry.

    Returns
    -------
    sympy.Expr
        ``0.15 -> 3/20``; symbols and exact expressions unchanged.
    """
    if isinstance(x, float | np.floating):
        return sp.Rational(repr(float(x)))
    if isinstance(x, str):  # text is read by the allow-list grammar, never evaluated (sympify would)
        from .expr import parse

        return parse(x)
    e = sp.sympify(x, rational=True)
    floats = e.atoms(sp.Float)  # SymPy Floats (e.g. from sp.Matrix([0.5])): their shortest decimal
    return e.xreplace({f: sp.Rational(repr(float(f))) for f in floats}) if floats else e


def _as_matrix(m, shape: tuple[int, int], what: str) -> sp.Matrix:
    try:
        out = sp.Matrix(m).applyfunc(exact)
    except (TypeError, ValueError, sp.SympifyError) as e:
        raise ModelError(f"{what}: not a matrix of numbers or SymPy expressions ({e})") from None
    if out.shape != shape:
        raise ModelError(f"{what}: expected shape {shape}, got {out.shape}")
    return out


@dataclass(frozen=True, eq=False)
class SymbolicLoop:
    """A loop (cut) joint of a :class:`SymbolicRobot`.

    Parameters
    ----------
    name : str
        The loop joint's name.
    type : str
        ``R P U S fixed``.
    parent, child : int
        Predecessor and successor bodies (``-1``: the world), ``parent < child``.
    frame : sympy.Matrix, shape ``(4, 4)``
        The loop frame in the world at q = 0 (the robot must be assembled there for every
        value of the symbols).
    axes : tuple of sympy.Matrix
        Axes ``(3, 1)`` in the loop frame (R, P: one; U: the predecessor's, then the
        successor's).
    """

    name: str
    type: str
    parent: int
    child: int
    frame: sp.Matrix
    axes: tuple

    __repr__ = summary_repr


@dataclass(frozen=True, eq=False)
class SymbolicRobot:
    """A robot whose reference geometry (q = 0) is given in symbols.

    Parameters
    ----------
    name : str
        The robot's name.
    names : tuple of str
        Body names, parents before children.
    labels : tuple of str
        Short labels of the bodies used in parameter names (``"3"`` gives ``XX3``; ``"a"``
        gives ``XX_a``).
    parent : tuple of int
        Parent body of each body (``-1``: the fixed base).
    jtype : tuple of str
        Joint type of each body (``R P U S``).
    origins : tuple of sympy.Matrix
        Each joint frame's pose ``(4, 4)`` in its parent body's frame at q = 0.
    axes : tuple of tuple of sympy.Matrix
        Each joint's axes ``(3, 1)`` in the joint frame (exact, unit).
    param_frames : tuple of sympy.Matrix
        Each body's parameter (link) frame ``(4, 4)`` in its body frame.
    gravity : sympy.Matrix, shape ``(3, 1)``
        Gravity in the world frame [m/s^2] (exact numbers).
    loops : tuple of SymbolicLoop
        Loop joints.
    values : dict
        Default numbers for the symbols (a table's ``values`` line), possibly empty.
    actuated : tuple
        Per body: ``True``, ``False`` or ``None`` (as :meth:`RobotBuilder.add_link`).
    q_box : ndarray or None
        Sampling box of the actuated coordinates (loops), as :class:`Robot`.
    description : str
        One line.
    convention : str
        How the geometry was given (e.g. ``modified DH``), for reports.
    source : str
        Where :func:`~baseparams.symbolic.load_symbolic` finds it again (a built-in name or a
        table file), or empty.
    """

    name: str
    names: tuple
    labels: tuple
    parent: tuple
    jtype: tuple
    origins: tuple
    axes: tuple
    param_frames: tuple
    gravity: sp.Matrix
    loops: tuple = ()
    values: dict = field(default_factory=dict)
    actuated: tuple = ()
    q_box: np.ndarray | None = None
    description: str = ""
    convention: str = "poses"
    source: str = ""

    __repr__ = summary_repr

    @property
    def n(self) -> int:
        """Number of moving bodies."""
        return len(self.names)

    @cached_property
    def symbols(self) -> tuple:
        """The geometry's symbols, sorted by name."""
        s = set()
        for m in (*self.origins, *self.param_frames, *(lp.frame for lp in self.loops)):
            s |= m.free_symbols
        return tuple(sorted(s, key=lambda x: x.name))

    def display(self, s: sp.Symbol) -> sp.Symbol:
        """The symbol as users write it: an angle for its half-angle tangent, else itself.

        Parameters
        ----------
        s : sympy.Symbol
            One of :attr:`symbols`.

        Returns
        -------
        sympy.Symbol
            The angle ``a`` for ``tan(a/2)``'s symbol, else ``s``.
        """
        a = angle_of(s)
        return s if a is None else a

    @cached_property
    def M0(self) -> tuple:
        """World pose ``(4, 4)`` of every body (joint) frame at q = 0, entries in :func:`normal` form."""
        out = []
        for i in range(self.n):
            p = self.parent[i]
            out.append(normal(self.origins[i]) if p < 0 else matmul(out[p], self.origins[i]))
        return tuple(out)

    @cached_property
    def link_frames(self) -> tuple:
        """World pose ``(4, 4)`` at q = 0 of each body's parameter (link) frame."""
        return tuple(matmul(m, f) for m, f in zip(self.M0, self.param_frames))

    def world_axes(self, i: int) -> list:
        """Body ``i``'s joint axes ``(3, 1)`` in the world frame at q = 0.

        Parameters
        ----------
        i : int
            The body.

        Returns
        -------
        list of sympy.Matrix
            One per axis of the joint (none for S).
        """
        r = self.M0[i][:3, :3]
        return [matmul(r, a) for a in self.axes[i]]

    def complete_values(self, values: dict | None) -> dict:
        """``values`` (symbol or name -> number) completed by the table's defaults; every symbol needed.

        Parameters
        ----------
        values : dict, optional
            Numbers for some symbols (keys: symbols or their names).

        Returns
        -------
        dict
            ``{symbol: sympy number}`` for every symbol of the geometry.

        Raises
        ------
        ModelError
            A symbol has no value, or a key is not a symbol of the robot.
        """
        by_name = {self.display(s).name: s for s in self.symbols}

        def value(sym, v):  # an angle's number goes in as its half-angle tangent
            return exact(np.tan(float(v) / 2)) if angle_of(sym) is not None and not isinstance(v, sp.Rational) \
                else exact(v)

        out = {by_name[k]: value(by_name[k], v) for k, v in self.values.items() if k in by_name}
        for k, v in (values or {}).items():
            key = k.name if isinstance(k, sp.Symbol) else str(k)
            if key in {s.name for s in self.symbols}:  # a half-angle tangent itself (internal)
                out[next(s for s in self.symbols if s.name == key)] = exact(v)
                continue
            if key not in by_name:
                raise ModelError(f"robot {self.name!r}: {key!r} is not one of its symbols "
                                 f"({', '.join(by_name) or 'none'})")
            out[by_name[key]] = value(by_name[key], v)
        missing = [self.display(s).name for s in self.symbols if s not in out]
        if missing:
            raise ModelError(f"robot {self.name!r}: no value for {', '.join(missing)} "
                             f"(give them, e.g. {missing[0]}=0.3)")
        return out

    def to_robot(self, values: dict | None = None, inertias=None) -> Robot:
        """The numeric :class:`Robot` at these values of the symbols.

        Parameters
        ----------
        values : dict, optional
            Numbers for the symbols (default: the table's ``values``).
        inertias : list of Inertia, optional
            One per body, in its parameter frame; default: distinct plausible inertias.

        Returns
        -------
        Robot
            Body ``i`` is ``names[i]``, its frame the joint frame, as :class:`RobotBuilder` builds.
        """
        vals = self.complete_values(values)

        def num(m):
            return np.array(m.subs(vals).evalf(17).tolist(), dtype=float)

        b = RobotBuilder(self.name, gravity=np.array(self.gravity.evalf(17).tolist(), dtype=float).ravel())
        for i in range(self.n):
            axes = [np.array(a.evalf(17).tolist(), dtype=float).ravel() for a in self.axes[i]]
            frame = num(self.param_frames[i])
            inertia = inertias[i] if inertias is not None else Inertia(
                1.0 + 0.1 * i, com=(0.01 * i, 0.02, 0.05 + 0.01 * i),
                inertia=(0.02 + 0.001 * i, 0.03, 0.01 + 0.002 * i), frame=frame)
            b.add_link(self.names[i], parent=None if self.parent[i] < 0 else self.names[self.parent[i]],
                       joint=self.jtype[i], origin=num(self.origins[i]), axis=axes[0] if axes else (0, 0, 1),
                       axis2=axes[1] if len(axes) > 1 else None, inertia=inertia, joint_name=f"joint{self.labels[i]}",
                       actuated=self.actuated[i] if self.actuated else None)
        for lp in self.loops:
            pm = sp.eye(4) if lp.parent < 0 else self.M0[lp.parent]
            axes = [np.array(a.evalf(17).tolist(), dtype=float).ravel() for a in lp.axes]
            b.add_loop(lp.name, lp.type, None if lp.parent < 0 else self.names[lp.parent], self.names[lp.child],
                       origin=num(pm.inv() * lp.frame), axis=axes[0] if axes else (0, 0, 1),
                       axis2=axes[1] if len(axes) > 1 else None)
        b.q_box = self.q_box
        return b.build()


class SymbolicBuilder:
    """Build a :class:`SymbolicRobot` link by link (the :class:`RobotBuilder` API with SymPy poses).

    Parameters
    ----------
    name : str
        The robot's name.
    gravity : array_like, shape ``(3,)``
        Gravity in the world frame [m/s^2] (numbers).
    values : dict, optional
        Default numbers for the symbols.
    description : str
        One line.

    Examples
    --------
    >>> import sympy as sp
    >>> from baseparams.symbolic import SymbolicBuilder, trans
    >>> L = sp.Symbol("L", positive=True)
    >>> b = SymbolicBuilder("2R", gravity=(0, -9.81, 0))
    >>> b = b.add_link("upper", joint="R").add_link("lower", parent="upper", joint="R", origin=trans("x", L))
    >>> b.build().symbols
    (L,)
    """

    def __init__(self, name: str, gravity=(0.0, 0.0, -9.81), values: dict | None = None, description: str = ""):
        self.name = name
        self.gravity = _as_matrix(list(gravity), (3, 1), f"robot {name!r}: gravity")
        if self.gravity.free_symbols:
            raise ModelError(f"robot {name!r}: gravity must be numbers (its direction decides the nullspace)")
        self.values = dict(values or {})
        self.description = description
        self.convention = "poses"
        self._bodies: list[dict] = []
        self._loops: list[tuple] = []
        self.q_box = None

    def _index(self, name: str | None) -> int:
        if name is None or name == "world":
            return -1
        for i, b in enumerate(self._bodies):
            if b["name"] == name:
                return i
        raise ModelError(f"robot {self.name!r}: unknown link {name!r}")

    def _axes(self, jt: str, axis, axis2, what: str) -> tuple:
        if jt == "S":
            return ()
        if jt not in ("R", "P", "U"):
            raise ModelError(f"{what}: joint type {jt!r} is not supported symbolically (R, P, U, S)")
        out = [_as_matrix(list(axis), (3, 1), f"{what}: axis")]
        if jt == "U":
            if axis2 is None:
                raise ModelError(f"{what}: a universal joint needs axis2")
            out.append(_as_matrix(list(axis2), (3, 1), f"{what}: axis2"))
        for a in out:
            if a.free_symbols or sp.simplify(a.dot(a) - 1) != 0:
                raise ModelError(f"{what}: axes must be exact unit vectors without symbols, got {list(a)}")
        return tuple(out)

    def add_link(self, name: str, parent: str | None = None, joint: str = "R", origin=None, axis=(0, 0, 1),
                 axis2=None, actuated: bool | None = None, label: str | None = None,
                 param_frame=None) -> SymbolicBuilder:
        """Attach link ``name`` to ``parent`` (default: the fixed base) by a joint.

        Parameters
        ----------
        name : str
            The link's name (unique).
        parent : str, optional
            An earlier link; ``None`` or ``"world"``: the fixed base.
        joint : {"R", "P", "U", "S"}
            Joint type.
        origin : array_like, shape ``(4, 4)``, optional
            The joint frame's pose in the parent link's frame at q = 0: exact rotation,
            translation in numbers or symbols. Default identity.
        axis : array_like, shape ``(3,)``
            Joint axis in the joint frame (exact unit vector).
        axis2 : array_like, shape ``(3,)``, optional
            A U joint's second axis.
        actuated : bool, optional
            As :meth:`RobotBuilder.add_link`.
        label : str, optional
            Short label for parameter names (default ``name``).
        param_frame : array_like, shape ``(4, 4)``, optional
            The frame of the link-frame parameters in the joint frame (default identity).

        Returns
        -------
        SymbolicBuilder
            ``self``, for chaining.
        """
        what = f"robot {self.name!r}, link {name!r}"
        if any(b["name"] == name for b in self._bodies):
            raise ModelError(f"{what}: duplicate link name")
        jt = {"revolute": "R", "prismatic": "P", "universal": "U", "spherical": "S"}.get(joint, joint)
        self._bodies.append({
            "name": name, "parent": self._index(parent), "type": jt, "label": label or name,
            "origin": sp.eye(4) if origin is None else _as_matrix(origin, (4, 4), f"{what}: origin"),
            "axes": self._axes(jt, axis, axis2, what), "actuated": actuated,
            "frame": sp.eye(4) if param_frame is None else _as_matrix(param_frame, (4, 4), f"{what}: param_frame")})
        return self

    def add_loop(self, name: str, type: str, parent: str | None, child: str, origin=None, axis=(0, 0, 1),
                 axis2=None, in_world: bool = False) -> SymbolicBuilder:
        """Record a loop (cut) joint between two links (assembled at q = 0 by construction).

        Parameters
        ----------
        name : str
            The loop joint's name.
        type : {"R", "P", "U", "S", "fixed"}
            Joint type.
        parent : str or None
            The predecessor link (``None``: the world).
        child : str
            The successor link.
        origin : array_like, shape ``(4, 4)``, optional
            The loop frame in the predecessor's frame at q = 0.
        axis, axis2 : array_like, shape ``(3,)``
            Axes in the loop frame (as :meth:`add_link`).
        in_world : bool
            ``origin`` is the loop frame in the world at q = 0 instead.

        Returns
        -------
        SymbolicBuilder
            ``self``, for chaining.
        """
        what = f"robot {self.name!r}, loop joint {name!r}"
        origin = sp.eye(4) if origin is None else _as_matrix(origin, (4, 4), f"{what}: origin")
        axes = () if type == "fixed" else self._axes(type, axis, axis2, what)
        self._loops.append((name, type, self._index(parent), self._index(child), origin, axes, in_world))
        return self

    def build(self) -> SymbolicRobot:
        """The :class:`SymbolicRobot`.

        Returns
        -------
        SymbolicRobot
            Bodies in the order added.

        Raises
        ------
        ModelError
            No links.
        """
        if not self._bodies:
            raise ModelError(f"robot {self.name!r}: no moving links")
        bs = self._bodies
        robot = SymbolicRobot(
            self.name, tuple(b["name"] for b in bs), tuple(b["label"] for b in bs), tuple(b["parent"] for b in bs),
            tuple(b["type"] for b in bs), tuple(b["origin"] for b in bs), tuple(b["axes"] for b in bs),
            tuple(b["frame"] for b in bs), self.gravity, (), self.values, tuple(b["actuated"] for b in bs),
            self.q_box, self.description, self.convention)
        loops = []
        for name, jt, p, c, origin, axes, in_world in self._loops:
            pm = sp.eye(4) if p < 0 or in_world else robot.M0[p]
            frame = matmul(pm, origin)
            if p > c:
                p, c = c, p
                axes = axes[::-1]
            loops.append(SymbolicLoop(name, jt, p, c, frame, axes))
        object.__setattr__(robot, "loops", tuple(loops))
        return robot
