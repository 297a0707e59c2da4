"""A short excitation that identifies a payload best: ``excite --payload LINK``.

The designer of :mod:`baseparams.excitation` on the payload's model instead of the robot's base
parameters: the design coordinates are the joints that carry the link (the others are welded at
their reference, :func:`baseparams.model.weld.weld`: they do not move it), the columns the payload's
ten (:class:`~baseparams.ident.payload.model.PayloadModel`: LINK's frame) and the drive terms fitted
with it, which are nuisance parameters: the criterion is taken on the information left for the
payload's columns, the Schur complement of the drive block (:func:`~.criterion.criterion_terms`
with ``interest``; D_s-optimal for ``logdet``, the default here). The result carries the standard
deviations the design predicts (:func:`predicted_sigmas`) for a stated torque noise and a nominal
payload.
"""

from __future__ import annotations

import numpy as np

from ..errors import BaseparamsError
from ..model.robot import Robot

#: the default nominal payload of the predicted sigmas: 1 kg, 5 cm along LINK's z, a 10 cm cube's inertia
NOMINAL = {"mass": 1.0, "com": [0.0, 0.0, 0.05], "inertia_com": (np.eye(3) * 1.0 * 0.1**2 / 6).tolist()}


class DesignModel:
    """The designer's model of a payload: its ten columns of interest, the drive terms as nuisance.

    What :func:`~baseparams.excitation.design.design_excitation` takes instead of an
    :class:`~baseparams.ident.IdentModel`: ``robot``, ``names``, ``n_params``, ``interest``,
    :meth:`regressor`, :meth:`regressor_blocks`.

    Parameters
    ----------
    model : PayloadModel
        The payload's model on every coordinate of the (welded) robot.
    basis : ndarray, shape ``(10, f)``, optional
        The payload's identifiable directions (parameter coordinates): its columns are ``Y_L basis``
        (default every direction). Directions no motion of these joints identifies (regrouped with a
        rotor inertia, say) are left out: they would make the information singular.
    structure : Structure, optional
        The structural decision the basis comes from.
    """

    design_model = True

    def __init__(self, model, basis: np.ndarray | None = None, structure=None):
        self.model = model
        self.robot = model.robot
        self.basis = np.eye(10) if basis is None else np.asarray(basis, dtype=float)
        self.structure = structure
        self.interest = self.basis.shape[1]
        self.names = [f"payload{k}" for k in range(self.interest)] + model.names[10:]
        self.n_params = self.interest + model.n_params - 10

    def __repr__(self) -> str:
        return f"<DesignModel payload on {self.model.link}: 10 + {self.n_params - 10} drive columns>"

    def regressor(self, q, dq, ddq, closed=None, backend: str = "auto") -> np.ndarray:
        """The payload's and drive terms' columns ``(S, m, 10 + nd)`` at tree states ``(S, dof)``.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, dof)``
            States.
        closed : None
            Unused (trees only).
        backend : str
            Unused.

        Returns
        -------
        ndarray, shape ``(S, m, f + nd)``
            :meth:`~baseparams.ident.payload.model.PayloadModel.columns`, the payload's on
            :attr:`basis`.
        """
        q, dq, ddq = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, dq, ddq))
        a = self.model.columns(q, dq, ddq)[0]
        return np.concatenate([a[..., :10] @ self.basis, a[..., 10:]], axis=2)

    def regressor_blocks(self, q, dq, ddq, max_bytes: float | None = None, max_samples: int | None = None):
        """:meth:`regressor` a block of samples at a time.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, dof)``
            States.
        max_bytes : float, optional
            Unused (blocks of ``max_samples``).
        max_samples : int, optional
            Most samples per block (default 4000).

        Yields
        ------
        start : int
            The block's first sample.
        A : ndarray, shape ``(k, m, f + nd)``
            Its columns.
        """
        step = int(max_samples or 4000)
        for k in range(0, len(q), step):
            yield k, self.regressor(q[k:k + step], dq[k:k + step], ddq[k:k + step])

    def theta(self, pi_paper, delta=None):
        """Not available: a payload design keeps no torque limits (``torque``).

        Parameters
        ----------
        pi_paper : ndarray
            Unused.
        delta : ndarray, optional
            Unused.

        Raises
        ------
        BaseparamsError
            Always.
        """
        raise BaseparamsError("excite: payload= with torque=: torque limits are not supported in a payload's "
                              "design; the effort limits are not checked")


def payload_robot(robot: Robot, link: str) -> tuple[Robot, int, list[str]]:
    """The robot with every joint that does not carry ``link`` welded at its reference (q = 0).

    Parameters
    ----------
    robot : Robot
        The robot (a fixed-base tree).
    link : str
        The payload's link.

    Returns
    -------
    robot : Robot
        The welded robot (its joints: those that carry the link).
    body : int
        The link's body in it.
    notes : list of str
        The joints welded.
    """
    from ..ident.payload.model import body_of
    from ..model.weld import weld

    body = body_of(robot, link)
    carry = set(int(c) for c in robot.path_dofs(body))
    names = robot.coordinate_names()
    other = {names[c]: 0.0 for c in range(robot.dof) if c not in carry}
    if not other:
        return robot, body, []
    small = weld(robot, other)
    return small, small.names.index(robot.names[body]), [f"payload on {robot.names[body]!r}: the joints that do not "
                                                         f"carry it are not designed (welded at q = 0): "
                                                         f"{', '.join(other)}"]


def design_model(robot: Robot, body: int, friction=("viscous", "coulomb", "offset"),
                 rotor: str = "auto") -> DesignModel:
    """The designer's model of a payload on ``body``: every coordinate's row, its drive terms.

    Parameters
    ----------
    robot : Robot
        The (welded) robot.
    body : int
        The payload's link.
    friction : iterable of str
        The drive terms fitted with the payload (nuisance columns).
    rotor : {"auto", "file", "fit"}
        Rotor inertia columns: ``fit``, or ``auto`` when the file states no armature.

    Returns
    -------
    DesignModel
        The model.
    """
    from ..ident.drives import drives_for
    from ..ident.payload.model import PayloadModel
    from ..ident.payload.structure import structural

    rows = np.arange(robot.dof)
    fit_rotor = rotor == "fit" or (rotor == "auto" and not np.any(robot.armature))
    drives = drives_for(robot, rows, rotor=fit_rotor, friction=friction)
    pm = PayloadModel(robot, body, rows, drives, np.zeros(robot.dof) if fit_rotor else
                      np.asarray(robot.armature, dtype=float))
    st = structural(pm, np.zeros((2, robot.dof)), np.ones(robot.dof, dtype=bool), 200, 0)
    u = st.payload_null
    if u.shape[1] == 10:
        raise BaseparamsError(f"link {pm.link!r}: no motion of the joints that carry it identifies any payload "
                              f"parameter")
    full, _, _ = np.linalg.svd(u, full_matrices=True) if u.shape[1] else (np.eye(10), None, None)
    return DesignModel(pm, full[:, u.shape[1]:] / st.scale[:10, None], st)


def predicted_sigmas(model: DesignModel, q, dq, ddq, noise: float, nominal=None, repeats: int = 1) -> dict:
    """The standard deviations a trajectory predicts for a payload, white torque noise of ``noise`` per sample.

    ``cov = noise^2 (A^T A)^-1`` over the trajectory's samples (``repeats`` times), the payload's
    block; mass, centre of mass and inertia about it through the Jacobian at the ``nominal`` payload.
    Correlated noise and the slow samples the identification leaves out widen them.

    Parameters
    ----------
    model : DesignModel
        The design's model.
    q, dq, ddq : ndarray, shape ``(S, dof)``
        The trajectory at the controller's rate.
    noise : float
        Torque noise standard deviation per sample [N m or N].
    nominal : dict, optional
        ``{"mass", "com", "inertia_com"}`` (default :data:`NOMINAL`).
    repeats : int
        Periods recorded.

    Returns
    -------
    dict
        ``{"mass", "com" (3), "inertia_com" (3x3), "parameters" (10): std (NaN where not
        identified), "noise", "nominal", "unidentified"}``.
    """
    from ..ident.payload.options import prior_values
    from ..ident.payload.result import jacobian
    from ..model import inertia as _inertia
    from ..numerics import StreamingQR

    qr = StreamingQR(model.n_params)
    for _, a in model.regressor_blocks(q, dq, ddq):
        qr.add(a.reshape(-1, model.n_params))
    inv = np.linalg.inv(qr.r)
    k = model.interest
    cov = model.basis @ (noise**2 / repeats * (inv @ inv.T)[:k, :k]) @ model.basis.T
    nom = prior_values(NOMINAL if nominal is None else nominal)
    ic = np.array([[nom[4], nom[5], nom[6]], [nom[5], nom[7], nom[8]], [nom[6], nom[8], nom[9]]])
    phi = _inertia.to_convention(_inertia.pseudo_inertia(nom[0], np.array(nom[1:4]), ic), "khalil")
    jac = jacobian(phi)
    st = model.structure
    ok = np.array([st is None or st.identified(g) for g in jac])
    s = np.where(ok, np.sqrt(np.maximum(np.diag(jac @ cov @ jac.T), 0.0)), np.nan)
    pairs = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
    out_ic = np.zeros((3, 3))
    for k, (a, b) in enumerate(pairs):
        out_ic[a, b] = out_ic[b, a] = s[4 + k]
    return {"mass": float(s[0]), "com": s[1:4].tolist(), "inertia_com": out_ic.tolist(),
            "parameters": np.sqrt(np.maximum(np.diag(cov), 0.0)).tolist(), "noise": float(noise),
            "nominal": NOMINAL if nominal is None else nominal, "unidentified": describe_null(model)}


def describe_null(model: DesignModel) -> list[str]:
    """The payload directions no motion of the designed joints identifies, in words (empty: none).

    Parameters
    ----------
    model : DesignModel
        The design's model.

    Returns
    -------
    list of str
        :func:`baseparams.ident.payload.structure.describe`.
    """
    from ..ident.payload.structure import describe

    return [] if model.structure is None else describe(model.structure, model.model.names[10:])


def sigma_note(s: dict, period: float, repeats: int) -> str:
    """One line of the predicted standard deviations (:func:`predicted_sigmas`).

    Parameters
    ----------
    s : dict
        :func:`predicted_sigmas`.
    period : float
        The period [s].
    repeats : int
        Periods recorded.

    Returns
    -------
    str
        The mass, centre of mass and principal inertia sigmas, and what they assume.
    """
    ic = np.array(s["inertia_com"])
    free = "" if not s["unidentified"] else (f"; no motion of these joints identifies: "
                                             f"{'; '.join(s['unidentified'])} (NaN)")
    return (f"predicted standard deviations ({repeats} x {period:.3g} s, white torque noise {s['noise']:g} N m per "
            f"sample, nominal payload {s['nominal']['mass']:g} kg): mass {s['mass']:.3g} kg, centre of mass "
            f"{', '.join(f'{1000 * v:.3g}' for v in s['com'])} mm, inertia about it (diagonal) "
            f"{', '.join(f'{v:.3g}' for v in np.diag(ic))} kg m^2 (correlated noise and the slow samples left out "
            f"widen them){free}")


def excite_payload(robot: Robot, link: str, *, period: float = 5.0, payload_noise: float = 0.1,
                   friction=("viscous", "coulomb", "offset"), nominal=None, repeats: int = 1, position=None,
                   velocity=None, **design):
    """A short excitation that identifies a payload on ``link`` best: ``excite --payload LINK`` (module docstring).

    Parameters
    ----------
    robot : Robot
        The robot without the payload.
    link : str
        The payload's link.
    period : float
        The period [s] (default 5: a short motion).
    payload_noise : float
        Torque noise [N m per sample] of the predicted standard deviations.
    friction : iterable of str
        The drive terms fitted with the payload (their columns are nuisance parameters).
    nominal : dict, optional
        The nominal payload of the predicted sigmas (``{"mass", "com", "inertia_com"}``).
    repeats : int
        Periods recorded, for the predicted sigmas.
    position, velocity : optional
        Position and velocity limits (:func:`baseparams.excitation.limits.given_limits`).
    **design
        :func:`~baseparams.excitation.design.design_excitation`'s options: ``harmonics``, ``rate``,
        ``criterion``, ``acceleration``, ``keepout``, ``margin``, ``starts``, ``grid``, ``seed``,
        ``max_iter``, ``progress``.

    Returns
    -------
    Excitation
        The trajectory of the joints that carry the link; its notes end with the predicted
        standard deviations (:func:`predicted_sigmas`).

    Raises
    ------
    BaseparamsError
        An unknown link, limits that leave no room, a design that does not excite the payload's
        columns (a robot design's options are refused by :func:`baseparams.excite` before).
    """
    from dataclasses import replace

    from ..arguments import check_keywords
    from ..ident.drives import friction_terms
    from .design import design_excitation
    from .limits import given_limits

    check_keywords("excite", period=period, payload_noise=payload_noise, robots=repeats)
    small, body, notes = payload_robot(robot, link)
    dm = design_model(small, body, friction_terms(friction))
    result = design_excitation(dm, base_frequency=1.0 / period, limits=given_limits(small, None, position, velocity,
                                                                                    None), **design)
    s = predicted_sigmas(dm, result.q, result.dq, result.ddq, payload_noise, nominal, int(repeats))
    return replace(result, notes=result.notes + tuple(notes) + (sigma_note(s, result.period, int(repeats)),))
