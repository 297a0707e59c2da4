"""A mounting tilt: the direction of gravity in the robot's base frame, as two small angles.

A robot bolted to a table that is not quite level feels gravity a few tenths of a degree off its
file's direction. The torques are linear in gravity, so with ``g' = R(phi) g`` (``phi = alpha u1
+ beta u2`` a rotation vector, ``u1, u2`` perpendicular to ``g``) the model's torque becomes
``A theta + Y(q, 0, 0; g' - g) pi`` exactly: ``Y(q, 0, 0; v)`` the regressor with gravity ``v``
and no motion, ``pi`` the standard parameters. First order in the angles::

    tau = A theta + alpha Y(q, 0, 0; u1 x g) pi + beta Y(q, 0, 0; u2 x g) pi

``pi`` is not identified: its base part is (``theta``), the rest is taken from the model file
(:func:`~baseparams.ident.select.complete`: the standard parameters closest to the file's with the
identified base parameters). A tilt makes directions visible that the level robot does not see
(the first moments of a vertical first joint's link): they stay at the file's values. The
angles come from Gauss-Newton steps around the linear fit; predictions use the exact rotation.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ... import schema as sc
from .base import Term, TermContext, complete_docs, stack_rows

#: the tilt's weak prior: level to within this per angle [rad] (1 degree)
PRIOR_STD = np.radians(1.0)
#: the largest tilt per angle [rad] (10 degrees): a mounting tilt, not another gravity (fix the model's
#: ``gravity`` instead); the fit stays within it and a saved result beyond it is refused
MAX_ANGLE = np.radians(10.0)


def perpendicular_basis(g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``u1, u2`` with ``(u1, u2, g / |g|)`` right-handed.

    Parameters
    ----------
    g : ndarray, shape ``(3,)``
        Gravity [m/s^2], non-zero.

    Returns
    -------
    u1, u2 : ndarray, shape ``(3,)``
        For ``g = (0, 0, -9.81)``: ``u1 = (0, -1, 0)`` ... (a rotation about ``u1`` by ``alpha``
        tips gravity towards ``u2``).
    """
    gh = g / np.linalg.norm(g)
    e = np.eye(3)[int(np.argmin(np.abs(gh)))]
    u1 = np.cross(gh, e)
    u1 /= np.linalg.norm(u1)
    return u1, np.cross(gh, u1)


def rotation_vector(v: np.ndarray) -> np.ndarray:
    """The rotation matrix of a rotation vector (Rodrigues).

    Parameters
    ----------
    v : ndarray, shape ``(3,)``
        Axis times angle [rad].

    Returns
    -------
    ndarray, shape ``(3, 3)``
        The rotation.
    """
    th = float(np.linalg.norm(v))
    if th < 1e-15:
        return np.eye(3)
    k = v / th
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * kx + (1 - np.cos(th)) * kx @ kx


def gravity_regressor(robot, coords, q: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``Y(q, 0, 0; g)`` of the measured rows: the torques of gravity ``g`` alone, per standard parameter.

    Parameters
    ----------
    robot : Robot
        The robot (a tree).
    coords : array_like of int, shape ``(m,)``
        The measured coordinates.
    q : ndarray, shape ``(S, dof)``
        Positions.
    g : ndarray, shape ``(3,)``
        The gravity vector [m/s^2], world frame.

    Returns
    -------
    ndarray, shape ``(S, m, 10 n)``
        ``paper`` convention columns.
    """
    from ...analysis import regressor

    z = np.zeros_like(q)
    return regressor(replace(robot, gravity=np.asarray(g, dtype=float)), q, z, z)[:, np.asarray(coords)]


def gravity_torques(robot, coords, q: np.ndarray | None, g: np.ndarray, pi: np.ndarray, state=None) -> np.ndarray:
    """``Y(q, 0, 0; g) pi`` without forming the regressor: the generalized forces holding the bodies against ``g``.

    Each body's first moment ``h = m c`` (``paper`` convention: world frame at q = 0) moved by its
    displacement, the gravity wrench ``(h x g, m g)`` about the world origin summed up the tree,
    paired with each joint's current line ``(omega, v)``: ``tau_k = -(omega . M + v . F)``.

    Parameters
    ----------
    robot : Robot
        The robot (a tree).
    coords : array_like of int, shape ``(m,)``
        The measured coordinates.
    q : ndarray, shape ``(S, dof)``
        Positions.
    g : ndarray, shape ``(3,)``
        Gravity [m/s^2], world frame.
    pi : ndarray, shape ``(10 n,)``
        Standard parameters, ``paper`` convention.
    state : TreeState, optional
        ``forward_kinematics(robot, q)`` when already computed (``q`` is then not used).

    Returns
    -------
    ndarray, shape ``(S, m)``
        Equal to ``gravity_regressor(robot, coords, q, g) @ pi`` (tested).
    """
    from ...kinematics.tree import forward_kinematics

    st = forward_kinematics(robot, q) if state is None else state
    p = np.asarray(pi, dtype=float).reshape(robot.n, 10)
    mass, h0 = p[:, 9], p[:, 6:9]
    g = np.asarray(g, dtype=float)
    rot, tr = st.g[:, :, :3, :3], st.g[:, :, :3, 3]
    h = np.einsum("snij,nj->sni", rot, h0) + tr * mass[None, :, None]  # (S, n, 3) world first moments
    moment = np.cross(h, g)
    force = mass[None, :, None] * g[None, None, :]
    w = np.concatenate([moment, np.broadcast_to(force, moment.shape)], axis=2).copy()  # (S, n, 6)
    for i in range(robot.n - 1, -1, -1):  # subtree sums, children after parents
        par = robot.parent[i]
        if par >= 0:
            w[:, par] += w[:, i]
    body = np.asarray(robot.dof_body)[np.asarray(coords)]
    lines = st.lines[:, np.asarray(coords)]
    return -np.einsum("smk,smk->sm", lines, w[:, body])


def gravity_basis(robot, coords, g: np.ndarray, state) -> np.ndarray:
    """The gravity torques per body's first moment and mass: :func:`gravity_torques` as a matrix.

    ``gravity_torques(robot, coords, q, g, pi) = gravity_basis(...) @ pi[k]`` with ``k`` each body's
    entries ``6:10`` (``h0``, ``m``: paper convention); the inertia entries do not act in a robot at
    rest. Body ``b`` acts on joint ``j`` when ``b`` is in the subtree of ``j``'s body.

    Parameters
    ----------
    robot : Robot
        The robot (a tree).
    coords : array_like of int, shape ``(m,)``
        The measured coordinates.
    g : ndarray, shape ``(3,)``
        Gravity [m/s^2], world frame.
    state : TreeState
        ``forward_kinematics(robot, q)``.

    Returns
    -------
    ndarray, shape ``(S, m, 4 n)``
        Columns ordered body by body: ``h0_x, h0_y, h0_z, m``.
    """
    g = np.asarray(g, dtype=float)
    rot, tr = state.g[:, :, :3, :3], state.g[:, :, :3, 3]
    s, n = rot.shape[:2]
    w = np.zeros((s, n, 4, 6))
    w[:, :, :3, :3] = np.cross(np.swapaxes(rot, 2, 3), g)  # unit h0_i: h = R e_i, wrench (h x g, 0)
    w[:, :, 3, :3] = np.cross(tr, g)  # unit mass: h = t, wrench (t x g, g)
    w[:, :, 3, 3:] = g
    coords = np.asarray(coords)
    inside = robot.support[coords]  # (m, n): coordinate j moves body b (a small robot: the basis' own size)
    lines = state.lines[:, coords]
    out = -np.einsum("smk,snik->smni", lines, w) * inside[None, :, :, None]
    return out.reshape(s, len(coords), 4 * n)


#: the tilt's columns from a filtered basis (:func:`gravity_basis`) up to this many numbers, else per step
BASIS_MAX = 2e7


@complete_docs
class Tilt(Term):
    """A mounting tilt (module docstring): two angles [rad].

    Parameters
    ----------
    forced : bool
        Kept whatever the cross-validation says.
    angles : array_like, shape ``(2,)``
        The rotation vector's components along ``u1, u2`` [rad].
    pi : array_like, shape ``(10 n,)``, optional
        The standard parameters it acts on (paper convention).
    """

    name = "tilt"
    label = "mounting tilt"
    FIELDS = {"angles": sc.Arr(sc.Num(lo=-MAX_ANGLE, hi=MAX_ANGLE), 2),
              "degrees": sc.Num(lo=0.0, hi=float(np.degrees(np.sqrt(2.0) * MAX_ANGLE))),
              "pi": sc.Opt(sc.Arr(sc.Num(lo=-sc.MAX_VALUE, hi=sc.MAX_VALUE), "npar"))}
    STD = {"angles": sc.Arr(sc.Num(lo=0.0), 2)}

    @classmethod
    def rule(cls, values: dict) -> str | None:
        """``degrees`` is the angles' magnitude; a tilt acts through the parameters ``pi`` it was fitted with."""
        deg = float(np.degrees(np.hypot(*values["angles"])))
        if abs(values["degrees"] - deg) > 1e-9 * max(1.0, deg):
            return f"degrees {values['degrees']!r} is not the angles' magnitude ({deg!r})"
        if values["pi"] is None and any(values["angles"]):
            return "a tilt without the standard parameters it acts on (pi is null): it would predict nothing"
        return None

    def __init__(self, forced: bool = False, angles=(0.0, 0.0), pi=None):
        super().__init__(forced)
        self.angles = np.asarray(angles, dtype=float)
        self.pi = None if pi is None else np.asarray(pi, dtype=float)

    def available(self, ctx: TermContext) -> str | None:
        """Trees only (with loops, not implemented), and gravity must be given."""
        r = ctx.model.robot
        if r.has_loops:
            return "robots with loops: not implemented"
        if not np.linalg.norm(r.gravity) > 0:
            return "no gravity in the model"
        return None

    def prepare(self, ctx: TermContext) -> None:
        """The kinematics the gravity torques are computed from (:func:`gravity_torques`), at ``prep.grid``.

        Several recordings: each on its own grid, through its own filter (:meth:`_each`).
        """
        from ...kinematics.tree import forward_kinematics

        r = ctx.model.robot
        self._u = perpendicular_basis(r.gravity)
        # gravity torques are smooth in the filtered q: at the regressor's stride
        self._fk = [forward_kinematics(r, c.prep.full.q[c.prep.grid][:, c.cols]) for c in ctx.recordings]
        self._cache = (None, None)
        self._basis_cols = None
        points = sum(len(c.prep.grid) for c in ctx.recordings)
        if 8 * r.n * len(ctx.model.coords) * points <= BASIS_MAX:  # linear in pi: filtered once
            self._basis_cols = [self._each(ctx, lambda c, fk, u=u: c.prep.apply_strided(
                gravity_basis(r, ctx.model.coords, np.cross(u, r.gravity), fk))) for u in self._u]
            self._entries = (np.arange(r.n)[:, None] * 10 + np.arange(6, 10)[None, :]).ravel()

    def _each(self, ctx: TermContext, fn) -> np.ndarray:
        """``fn(recording's context, its kinematics)`` of each recording, the fitted rows stacked."""
        return stack_rows([fn(c, fk) for c, fk in zip(ctx.recordings, self._fk)])

    def reset(self, ctx: TermContext) -> None:
        """A level mounting."""
        self.angles = np.zeros(2)

    def columns(self, ctx: TermContext, state: dict) -> tuple[np.ndarray, list[str]]:
        """``Y(q, 0, 0; u_k x g) pi``, filtered and decimated, for ``k = 1, 2``."""
        self.pi = np.asarray(state["pi"], dtype=float)
        if self._basis_cols is not None:  # linear in the first moments and masses: filtered once (prepare)
            pk = self.pi[self._entries]
            return np.stack([b @ pk for b in self._basis_cols], axis=2), ["tilt_1", "tilt_2"]
        key, cols = self._cache
        if key is None or not np.array_equal(key, self.pi):
            r = ctx.model.robot
            cols = self._each(ctx, lambda c, fk: c.prep.apply_strided(np.stack(
                [gravity_torques(r, ctx.model.coords, None, np.cross(u, r.gravity), self.pi, state=fk)
                 for u in self._u], axis=2)))
            self._cache = (self.pi.copy(), cols)
        return cols, ["tilt_1", "tilt_2"]

    def prior(self) -> tuple[np.ndarray, np.ndarray]:
        """Level to within :data:`PRIOR_STD` [rad] per angle."""
        return np.full(2, 1.0 / PRIOR_STD**2), np.zeros(2)

    def absorb(self, coefs: np.ndarray, std: np.ndarray | None = None) -> float:
        """The angles are the coefficients (a total, not a step), within :data:`MAX_ANGLE`."""
        new = np.clip(np.asarray(coefs, dtype=float), -MAX_ANGLE, MAX_ANGLE)
        change = float(np.max(np.abs(new - self.angles))) / 1e-3
        self.angles = new
        if std is not None:
            self.std = {"angles": [float(s) for s in std]}
        return change

    def at_bound(self) -> bool:
        """An angle at :data:`MAX_ANGLE`."""
        return bool(np.any(np.abs(self.angles) >= MAX_ANGLE))

    def gravity(self, robot) -> np.ndarray:
        """The tilted gravity ``R(alpha u1 + beta u2) g``.

        Parameters
        ----------
        robot : Robot
            The robot (its gravity is the file's).

        Returns
        -------
        ndarray, shape ``(3,)``
            [m/s^2], world frame.
        """
        u1, u2 = perpendicular_basis(robot.gravity)
        return rotation_vector(self.angles[0] * u1 + self.angles[1] * u2) @ robot.gravity

    def adjust_model(self, fit, q_raw, q, dq, ddq, tau: np.ndarray) -> np.ndarray:
        """``+ Y(q, 0, 0; g' - g) pi``, exact in the angles."""
        r = fit.model.robot
        dg = self.gravity(r) - r.gravity
        if self.pi is None or not np.any(dg):
            return tau
        return tau + gravity_torques(r, fit.model.coords, q, dg, self.pi)

    def tilt_degrees(self) -> float:
        """The tilt's magnitude.

        Returns
        -------
        float
            [degree].
        """
        return float(np.degrees(np.linalg.norm(self.angles)))

    def values(self, joints: list[str]) -> dict:
        """Angles [rad], magnitude [degree] and the standard parameters it acted on."""
        return {"angles": [float(a) for a in self.angles], "degrees": self.tilt_degrees(),
                "pi": None if self.pi is None else [float(v) for v in self.pi]}

    def describe(self, joints: list[str]) -> str:
        """E.g. ``0.25 degree``."""
        s = self.std.get("angles")
        tail = "" if not s else f" (std {np.degrees(np.linalg.norm(s)):.2g} degree)"
        if np.any(np.abs(self.angles) >= MAX_ANGLE):
            tail += f"; at the {np.degrees(MAX_ANGLE):.0f} degree bound: check the model's gravity"
        return f"{self.tilt_degrees():.3g} degree from the file's gravity{tail}"

    def export(self) -> dict:
        """The tilt as the base's orientation: the rotation to apply to the robot in the world."""
        return {"base_rotation": [[float(v) for v in row] for row in self.base_rotation()]}

    def base_rotation(self) -> np.ndarray:
        """The robot's rotation in a world with the file's gravity that gives the tilted gravity.

        Returns
        -------
        ndarray, shape ``(3, 3)``
            ``R^T``.
        """
        return np.eye(3) if self._basis is None else self._rot().T

    @property
    def _basis(self):
        return getattr(self, "_u", None)

    def _rot(self) -> np.ndarray:
        u1, u2 = self._u
        return rotation_vector(self.angles[0] * u1 + self.angles[1] * u2)

    def load(self, doc: dict, joints: list[str], model) -> None:
        """The angles and parameters of a saved result (a tree with gravity: :meth:`available`)."""
        from ...errors import BaseparamsError

        r = model.robot
        if r.has_loops or not np.linalg.norm(r.gravity) > 0:
            raise BaseparamsError(f"a mounting tilt cannot act on robot {r.name!r} "
                                  f"({'it has loops' if r.has_loops else 'its model has no gravity'})")
        v = doc["values"]
        self.angles = np.asarray(v["angles"], dtype=float)
        self.pi = None if v["pi"] is None else np.asarray(v["pi"], dtype=float)
        self._u = perpendicular_basis(model.robot.gravity)
