"""The payload model: a rigid body added to one link of a known robot, and the torques it adds.

A payload fixed to link ``L`` changes only ``L``'s inertial parameters: the robot with the payload
is the robot with ``pi_L + phi`` (paper convention), so its joint torques are

``tau = tau_robot(q, dq, ddq) + Y_L(q, dq, ddq) phi``,

``Y_L`` the ten columns of ``L`` in the TP regressor (the paper's eq. "TP model", world frame at
q = 0). The payload's parameters are taken in ``L``'s own frame, about its origin, in the
``khalil`` order (``XX XY XZ YY YZ ZZ MX MY MZ M``: the inertia tensor about the origin, the first
moments ``m c``, the mass): ``phi_paper = T_L phi`` with ``T_L`` the congruence by ``L``'s pose at
q = 0 (:func:`link_frame_map`), so the columns are ``Y_L T_L``.

``tau_robot`` is the model file's rigid body (and its armature), or a saved identification's
prediction (base parameters, drive terms and model terms): the payload then changes its base
parameters by ``K_L phi`` (the regrouping of ``L``'s columns), which is ``Y_L phi`` again, so the
payload comes out of the regrouping and the robot is not identified again. The moving joints'
friction (viscous, Coulomb, offset) is fitted with the payload (:class:`PayloadModel`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...display import summary_repr
from ...errors import BaseparamsError, ModelError
from ...model import inertia as _inertia
from ...model.robot import Robot
from ..drives import Drives, drives_for

#: the payload's ten parameters: ``khalil`` order, LINK's frame, about its origin
NAMES = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")
#: what each parameter is, for messages
MEANING = {"XX": "inertia xx about LINK's origin", "XY": "inertia xy about LINK's origin",
           "XZ": "inertia xz about LINK's origin", "YY": "inertia yy about LINK's origin",
           "YZ": "inertia yz about LINK's origin", "ZZ": "inertia zz about LINK's origin",
           "MX": "first moment m cx", "MY": "first moment m cy", "MZ": "first moment m cz", "M": "mass"}
#: what each drive term is, for messages (``Ia_joint``, ``dFv_joint`` ...)
DRIVE_MEANING = {"Ia": "rotor inertia", "Fv": "viscous friction", "Fc": "Coulomb friction", "Fo": "torque offset"}


def link_frame_map(robot: Robot, body: int) -> np.ndarray:
    """``T (10, 10)``: ``phi_paper = T phi`` for a body's parameters in its own frame (``khalil`` order).

    Parameters
    ----------
    robot : Robot
        The robot.
    body : int
        The body.

    Returns
    -------
    ndarray, shape ``(10, 10)``
        Columns: the ``paper`` parameters (spatial pseudo-inertia entries, world frame at q = 0)
        of each unit ``khalil`` parameter of the body's frame (the congruence ``M0 N M0^T``).
    """
    t = np.empty((10, 10))
    for k in range(10):
        e = np.zeros(10)
        e[k] = 1.0
        t[:, k] = _inertia.hat(_inertia.transform(_inertia.from_convention(e, "khalil"), robot.M0[body]))
    return t


def body_of(robot: Robot, link: str) -> int:
    """The body index of a link name (or of its joint's name), or one line listing the links.

    Parameters
    ----------
    robot : Robot
        The robot (fixed base, no loops).
    link : str
        A body (link) name, or the name of the joint that moves it.

    Returns
    -------
    int
        The body.

    Raises
    ------
    ModelError
        A robot with a floating base, loops or coupled joints; an unknown link.
    """
    from ...arguments import ArgumentTypeError

    if not isinstance(link, str):
        raise ArgumentTypeError(f"payload: link= must be a link name, got {type(link).__name__}")
    what = f"robot {robot.name!r}"
    if robot.floating or robot.has_loops or robot.couplings:
        kind = "a floating base" if robot.floating else "loops" if robot.has_loops else "coupled joints"
        raise ModelError(f"{what}: payload identification supports fixed-base trees without couplings; this robot "
                         f"has {kind}")
    if link in robot.names:
        return robot.names.index(link)
    if link in robot.joint_names:
        return robot.joint_names.index(link)
    raise ModelError(f"{what}: no link {link!r} (links: {', '.join(robot.names)}; a link merged into its parent by a "
                     f"fixed joint is not one: name the link it is fixed to)")


@dataclass(frozen=True, eq=False)
class PayloadModel:
    """The columns of a payload on one link and the known robot's torques, on the fitted rows.

    ``tau[:, r] = known(...)[:, r] + regressor(...)[:, r] @ [phi; delta]`` on the fitted rows ``r``
    (the coordinates :attr:`rows`).

    Parameters
    ----------
    robot : Robot
        The robot (the model file's geometry and inertias).
    body : int
        The payload's link.
    rows : ndarray of int, shape ``(r,)``
        The coordinates whose torques are fitted (the moving joints that carry the link).
    drives : Drives
        The fitted drive terms of those rows (``Drives.rows`` index :attr:`rows`).
    armature : ndarray, shape ``(r,)``
        Known rotor inertia per fitted row (the file's; zero where fitted or with a result).
    result : Identification, optional
        A saved identification whose prediction is the known robot (else the model file).
    """

    robot: Robot
    body: int
    rows: np.ndarray
    drives: Drives
    armature: np.ndarray
    result: object = None

    __repr__ = summary_repr

    @property
    def link(self) -> str:
        """The payload's link name."""
        return self.robot.names[self.body]

    @property
    def names(self) -> list[str]:
        """Parameter names ``(10 + nd,)``: the payload's (:data:`NAMES`), then the drive terms (``Fv_joint``)."""
        return list(NAMES) + [("d" if self.result is not None else "") + n for n in self.drives.names]

    @property
    def n_params(self) -> int:
        """``10 + nd``."""
        return 10 + self.drives.n_params

    @property
    def joints(self) -> list[str]:
        """The joints of the fitted rows ``(r,)``."""
        return self.robot.coordinate_names(self.rows)

    def projection(self) -> np.ndarray:
        """``P (10 n, 11)``: the payload's ten columns (:func:`link_frame_map` at its body) and the robot's own torque.

        Returns
        -------
        ndarray, shape ``(10 n, 11)``
            ``Y @ P`` is ``[Y_L T_L | Y pi]`` (``pi`` the file's paper parameters).
        """
        p = np.zeros((10 * self.robot.n, 11))
        p[10 * self.body:10 * self.body + 10, :10] = link_frame_map(self.robot, self.body)
        p[:, 10] = self.robot.parameters("paper")
        return p

    def columns(self, q, dq, ddq) -> tuple[np.ndarray, np.ndarray]:
        """The model's columns and the file robot's torques on the fitted rows.

        Parameters
        ----------
        q, dq, ddq : ndarray, shape ``(S, dof)``
            Robot states (every coordinate).

        Returns
        -------
        a : ndarray, shape ``(S, r, 10 + nd)``
            The payload's columns (``khalil``, LINK's frame) and the drive terms'.
        rigid : ndarray, shape ``(S, r)``
            The file's rigid body and armature on the fitted rows (used without a result).
        """
        from ...regressor.tp import projected_regressor

        y = projected_regressor(self.robot, q, dq, ddq, P=self.projection(), rows=self.rows)
        d = self.drives.regressor(dq[:, self.rows], ddq[:, self.rows], len(self.rows))
        rigid = y[:, :, 10] + self.armature * ddq[:, self.rows]
        return np.concatenate([y[:, :, :10], d], axis=2), rigid

    def known(self, t, q_raw, q, dq, ddq, rigid: np.ndarray) -> np.ndarray:
        """The known robot's torques on the fitted rows: the file's (``rigid``) or the saved identification's.

        Parameters
        ----------
        t : ndarray, shape ``(S,)``
            Time [s] (a saved identification's delays shift along it).
        q_raw : ndarray, shape ``(S, dof)``
            Positions as logged (its pre-sliding friction's state).
        q, dq, ddq : ndarray, shape ``(S, dof)``
            The states.
        rigid : ndarray, shape ``(S, r)``
            :meth:`columns`' file torques.

        Returns
        -------
        ndarray, shape ``(S, r)``
            Torques [N m or N].
        """
        if self.result is None:
            return rigid
        from ..validation import model_torques

        f = self.result.fit
        where = {int(c): k for k, c in enumerate(f.model.coords)}
        tau = model_torques(f, t, q_raw[:, f.model.coords], q, dq, ddq)
        return tau[:, [where[int(c)] for c in self.rows]]

    def result_rows(self, q, dq, ddq) -> np.ndarray:
        """The saved identification's model regressor on the fitted rows (its covariance's propagation).

        Parameters
        ----------
        q, dq, ddq : ndarray, shape ``(S, dof)``
            The states.

        Returns
        -------
        ndarray, shape ``(S, r, p)``
            ``A(q, dq, ddq)`` of the result's model on the fitted rows.
        """
        m = self.result.fit.model
        where = {int(c): k for k, c in enumerate(m.coords)}
        return m.regressor(q, dq, ddq)[:, [where[int(c)] for c in self.rows]]


def payload_model(robot: Robot, body: int, rows: np.ndarray, options, result=None) -> tuple[PayloadModel, list[str]]:
    """The payload model of the fitted rows, as the options build it, with a note per choice.

    Parameters
    ----------
    robot : Robot
        The robot.
    body : int
        The payload's link.
    rows : ndarray of int
        The fitted coordinates.
    options : PayloadOptions
        ``friction``, ``rotor``, ``coulomb_width``.
    result : Identification, optional
        A saved identification (its drive terms are kept; friction corrections are fitted).

    Returns
    -------
    model : PayloadModel
        The model.
    notes : list of str
        Where the rotor inertia comes from, what the drive terms are.

    Raises
    ------
    BaseparamsError
        No fitted row.
    """
    rows = np.asarray(rows, dtype=int)
    if not len(rows):
        raise BaseparamsError(f"link {robot.names[body]!r}: no joint that carries it moves in the log: nothing "
                              f"identifies a payload there")
    arm = np.asarray(robot.armature, dtype=float)[rows]
    lacks = not np.any(robot.armature) if result is None else "Ia" not in result.fit.model.drives.kinds
    fit_rotor = options.rotor == "fit" or (options.rotor == "auto" and lacks)
    notes = []
    if result is not None:
        rotor = ("; rotor inertia fitted per moving joint (" + ("--rotor fit" if options.rotor == "fit" else
                 "the identification has none: a motor's inertia cannot regroup into the links") + ")"
                 if fit_rotor else "")
        notes.append("known robot: the saved identification's prediction (base parameters, drive terms, model "
                     "terms); friction fitted as corrections of its own (friction changes with the load)" + rotor)
        arm = np.zeros(len(rows))
    elif fit_rotor:
        why = "--rotor fit" if options.rotor == "fit" else "the model file states no armature"
        notes.append(f"known robot: the model file's rigid body; rotor inertia fitted per moving joint ({why})")
        arm = np.zeros(len(rows))
    else:
        notes.append("known robot: the model file's rigid body and armature "
                     f"({', '.join(f'{a:.3g}' for a in arm)} kg m^2 on the fitted joints)")
    drives = drives_for(robot, rows, rotor=fit_rotor, friction=options.friction, coulomb_width=options.coulomb_width)
    return PayloadModel(robot, body, rows, drives, arm, result), notes
