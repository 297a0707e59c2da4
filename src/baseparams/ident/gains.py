"""What a result identified from motor currents holds beyond its parameters: gains, scale, groups.

:class:`CurrentGains` is kept by an :class:`~baseparams.ident.result.Identification` made from
currents (:mod:`baseparams.ident.fromcurrents`), saved with it, and read back. What such a result
predicts: the **joint-side torque** a joint-torque sensor after the gear would read, ``Y_b beta``
(the rigid body; the motor side's rotor inertia and friction excluded, except where the model
regroups them into a base parameter: those groups are named), and the **currents**
``(C^-1 A theta)_r / k_r``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..display import summary_repr
from .currents import Transmission


@dataclass(frozen=True, eq=False)
class CurrentGains:
    """What a result identified from currents holds beyond the parameters: gains, scale, groups.

    Parameters
    ----------
    transmission : Transmission
        Which motor's current reaches which joints.
    gains : ndarray, shape ``(m,)``
        ``k_r`` [N m/A at the joint side] per motor.
    std : ndarray, shape ``(m,)``
        Their standard deviations at the anchor's scale (0 for the anchor).
    anchor : str
        What fixed the scale: ``joint2=12.5`` (a given gain; several, comma-separated: their
        geometric mean), or ``model file`` (its masses and centres of mass,
        :func:`~baseparams.ident.currents.file_scale`).
    scale_std : float
        The scale's relative standard deviation (0 for one given gain: its error is the user's).
    sigma : ndarray, shape ``(m,)``
        Current noise per motor [A] (the fit's weights' inverse).
    undetermined : tuple of str
        Motors whose gain the currents do not determine (their rows left out of the parameters'
        fit, the gain regressed afterwards: not meaningful beyond its large std).
    groups : tuple of dict
        What currents cannot separate: ``{"kind", "members", "note"}`` per group (``scale``,
        ``regrouped`` drive terms, ``undetermined`` gains, ``weak`` directions).
    rotor_split : dict of str to float
        Per base parameter a rotor inertia is regrouped into, the part the model file's armature
        states (``K armature``): taken out of the joint-side torque (:meth:`joint_side`); empty
        when the file states none.
    """

    transmission: Transmission
    gains: np.ndarray
    std: np.ndarray
    anchor: str
    scale_std: float = 0.0
    sigma: np.ndarray | None = None
    undetermined: tuple = ()
    groups: tuple = ()
    rotor_split: dict = field(default_factory=dict)

    __repr__ = summary_repr

    @property
    def motors(self) -> tuple[str, ...]:
        """The motors ``(m,)`` (named after the joint whose current column each logs)."""
        return self.transmission.motors

    def joint_side(self, model, theta: np.ndarray) -> np.ndarray:
        """The parameters of the joint-side torque: the drive terms (motor side) set to zero.

        Parameters
        ----------
        model : IdentModel
            The model.
        theta : ndarray, shape ``(p,)``
            Model parameters.

        Returns
        -------
        ndarray, shape ``(p,)``
            ``theta`` with every drive parameter 0; a base parameter a rotor inertia is regrouped
            into keeps it, less the model file's armature where it states one
            (:attr:`rotor_split`, :attr:`groups`).
        """
        nb = len(model.analysis.base_names)
        out = np.array(theta, dtype=float)
        out[np.asarray(model.regrouping.independent) >= nb] = 0.0
        where = {n: k for k, n in enumerate(model.names)}
        for name, value in self.rotor_split.items():
            out[where[name]] -= value
        return out

    def currents(self, tau: np.ndarray) -> np.ndarray:
        """The currents that make joint-side torques (the model's, motor terms included).

        Parameters
        ----------
        tau : ndarray, shape ``(S, m)``
            ``A theta`` [N m or N].

        Returns
        -------
        ndarray, shape ``(S, m)``
            ``(C^-1 tau)_r / k_r`` [A], columns the motors.
        """
        return self.transmission.motor_rows(np.asarray(tau, dtype=float)) / self.gains

    def to_json(self) -> dict:
        """The gains, scale and groups as JSON types (a saved result's ``currents``).

        Returns
        -------
        dict
            ``motors, matrix, gains{motor: k}, std{motor: s}, anchor, scale_std, sigma{motor: A},
            undetermined, groups, rotor_split{base parameter: value}, scale_note``.
        """
        m = self.motors
        return {"motors": list(m), "matrix": self.transmission.matrix.tolist(),
                "gains": dict(zip(m, map(float, self.gains))), "std": dict(zip(m, map(float, self.std))),
                "anchor": self.anchor, "scale_std": float(self.scale_std),
                "sigma": None if self.sigma is None else dict(zip(m, map(float, self.sigma))),
                "undetermined": list(self.undetermined), "groups": [dict(g) for g in self.groups],
                "rotor_split": {k: float(v) for k, v in self.rotor_split.items()}, "scale_note": self.scale_note()}

    @classmethod
    def from_json(cls, doc: dict) -> CurrentGains:
        """The gains of a saved result (:meth:`to_json`).

        Parameters
        ----------
        doc : dict
            The saved ``currents`` (checked against :data:`baseparams.schema.CURRENTS`).

        Returns
        -------
        CurrentGains
            The gains.
        """
        m = tuple(doc["motors"])
        tx = Transmission(m, np.array(doc["matrix"], dtype=float))
        sigma = None if doc.get("sigma") is None else np.array([doc["sigma"][k] for k in m], dtype=float)
        return cls(tx, np.array([doc["gains"][k] for k in m], dtype=float),
                   np.array([doc["std"][k] for k in m], dtype=float), doc["anchor"], float(doc["scale_std"]),
                   sigma, tuple(doc.get("undetermined") or ()), tuple(doc.get("groups") or ()),
                   dict(doc.get("rotor_split") or {}))

    @property
    def anchors(self) -> tuple[str, ...]:
        """The anchored motors (none when the model file gave the scale)."""
        return () if self.anchor == "model file" else tuple(a.split("=")[0] for a in self.anchor.split(","))

    def scale_note(self) -> str:
        """One line: what fixed the gains' common scale and what its error does to every figure.

        Returns
        -------
        str
            The note.
        """
        tail = ("a relative error e of it scales every gain, base parameter, drive term and predicted torque by "
                "(1 + e); the standard deviations are at its scale")
        if len(self.anchors) == 1:
            return f"scale: the anchor {self.anchor} N m/A (given; exact here): {tail}"
        if self.anchors:
            return (f"scale: the anchors {self.anchor} N m/A, their geometric mean (the fitted gains' ratios to "
                    f"them agree to {100 * self.scale_std:.2g} %, the mean's std): {tail}")
        return (f"scale: the model file's masses and centres of mass (no --gain-anchor: the common factor that brings "
                f"the identified gravity torques along the motion closest to the file's; the joints' own factors "
                f"spread {100 * self.scale_std:.2g} %, a lower bound: a mass the file lacks on every joint's load, a "
                f"tool, scales them alike): {tail}; --gain-anchor JOINT=K gives the scale from a catalogue gain")


def joint_side_fit(fit, gains: CurrentGains):
    """The fit whose predictions are the joint-side torques (:meth:`CurrentGains.joint_side`).

    Parameters
    ----------
    fit : Fit
        A fit from currents.
    gains : CurrentGains
        Its gains.

    Returns
    -------
    Fit
        ``fit`` with the drive terms zero (its terms and statistics unchanged).
    """
    return replace(fit, theta=gains.joint_side(fit.model, fit.theta))
