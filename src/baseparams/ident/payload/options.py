"""How a payload is identified: one validated object (:class:`PayloadOptions`).

Every option of :func:`baseparams.ident.payload.identify_payload` with its default, checked once
when made (numbers in their ranges, the choices, the friction terms, the prior payload); the front
door (:func:`baseparams.identify_payload`) and the CLI (``baseparams payload``) build it, the result
keeps it.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ...arguments import PAYLOAD, PAYLOAD_CHOICES, RANGES, Range
from ...errors import BaseparamsError
from ..drives import friction_terms

#: the estimators: physically consistent (cvxpy and Clarabel, the extra ``ident``), least squares, or the
#: first when installed
METHODS = PAYLOAD_CHOICES["method"]
#: where the rotor inertia of the fitted joints comes from
ROTORS = PAYLOAD_CHOICES["rotor"]
#: whether the moving joints' torque offsets are fitted: kept by cross-validation, or always
OFFSETS = PAYLOAD_CHOICES["offsets"]
#: the standard deviations' covariance (:mod:`baseparams.ident.uncertainty`)
COVARIANCES = PAYLOAD_CHOICES["covariance"]
#: the numeric options and their ranges (the others are choices, flags or the prior); the structural analysis
#: needs more random states than :data:`~baseparams.arguments.RANGES` allows an analysis
NUMBERS = {**{k: RANGES[k] for k in ("still", "min_speed", "slow_fraction", "coulomb_width", "cutoff", "decimate",
                                     "seed")},
           "analysis_samples": Range(20, 100_000, integer=True), "memory_mb": Range(1, 1e6, unit="MB")}
#: the numeric options whose None means "the default"
OPTIONAL = ("min_speed", "coulomb_width", "cutoff", "decimate")


@dataclass(frozen=True)
class PayloadOptions:
    """Every option of a payload identification, checked when made (module docstring).

    Parameters
    ----------
    method : {"auto", "physical", "ls"}
        ``physical``: least squares over physically consistent payloads (positive mass, the 4x4
        pseudo-inertia positive semidefinite; cvxpy with Clarabel, the extra ``ident``);
        ``ls``: least squares; ``auto`` (default): ``physical`` when cvxpy and Clarabel are
        installed, else ``ls`` with a note.
    friction : str or iterable of str
        Friction terms fitted per moving joint with the payload: ``viscous``, ``coulomb``,
        ``offset`` (default all three; ``"none"``); kept as a tuple of names. With a saved
        identification they are corrections of its own (friction changes with the load).
    rotor : {"auto", "file", "fit"}
        The moving joints' rotor inertia: ``file``, the model file's armature (zero where it has
        none) or the saved identification's; ``fit``, fitted with the payload (with a saved
        identification: a correction of its own); ``auto`` (default), the file's when it states
        any, the identification's when it models rotor inertia, else fitted (a motor's inertia on
        its joint does not regroup into the links: a robot known without it mispredicts every
        acceleration).
    offsets : {"auto", "fit"}
        With ``offset`` among ``friction``: ``auto`` (default), the moving joints' torque offsets
        kept when blocked cross-validation on the log says so (:mod:`~baseparams.ident.payload.offsets`:
        with only the wrist moving an offset takes up much of the mass's information); ``fit``,
        always fitted.
    coulomb_width : float, optional
        Smooth Coulomb friction ``tanh(dq / w)`` [rad/s] instead of ``sign(dq)``.
    min_speed : float, optional
        A moving joint's samples slower than this [rad/s or m/s] are not fitted on its row
        (Coulomb friction is not a step at a reversal: stiction, pre-sliding, a simulator's soft
        friction); default ``slow_fraction`` of the joint's peak speed in the log.
    slow_fraction : float
        The default ``min_speed`` as a fraction of each joint's peak (filtered) speed, in
        ``[0, 1)`` (default 0.1; 0 fits every sample).
    still : float
        A joint whose logged range is below this [rad or m] does not move: its row is not fitted
        (a servo holding it leaves an unknown static friction in its torque) and the structural
        analysis holds it at its median (default 0.02).
    cutoff, decimate : optional
        The low-pass cutoff [Hz] and decimation (as :func:`baseparams.identify`; default from
        the log).
    covariance : {"hac", "white"}
        The standard deviations: Newey-West (correlated residuals, default) or the least-squares
        formula.
    prior : dict, Inertia or None
        The payload held where the motion does not identify it: ``{"mass" [kg], "com" (3,) [m],
        "inertia_com" (3, 3) [kg m^2]}`` in LINK's frame, or a
        :class:`~baseparams.model.inertia.Inertia`; kept as ten numbers ``(mass, com, Ixx, Ixy,
        Ixz, Iyy, Iyz, Izz)``. None (default): what the motion does not identify is not fitted
        and not reported as a number.
    analysis_samples : int
        Random states of the structural analysis (which payload parameters the moving joints
        can identify).
    seed : int
        Their seed.
    memory_mb : float
        The largest regressor formed at once [MB] (the log is held whole: a longer log is refused
        with a line saying how long it may be).

    Raises
    ------
    ArgumentTypeError, ArgumentError
        A value of the wrong type or out of its range (one line naming the keyword).
    BaseparamsError
        An unknown friction term, a prior that is not a physical payload.
    """

    method: str = PAYLOAD["method"]
    friction: tuple = PAYLOAD["friction"]
    rotor: str = PAYLOAD["rotor"]
    offsets: str = PAYLOAD["offsets"]
    coulomb_width: float | None = PAYLOAD["coulomb_width"]
    min_speed: float | None = PAYLOAD["min_speed"]
    slow_fraction: float = PAYLOAD["slow_fraction"]
    still: float = PAYLOAD["still"]
    cutoff: float | None = PAYLOAD["cutoff"]
    decimate: int | None = PAYLOAD["decimate"]
    covariance: str = PAYLOAD["covariance"]
    prior: object = PAYLOAD["prior"]
    analysis_samples: int = PAYLOAD["analysis_samples"]
    seed: int = PAYLOAD["seed"]
    memory_mb: float = PAYLOAD["memory_mb"]

    def __post_init__(self):
        from ...arguments import check_choice, check_value

        for name, choices in (("method", METHODS), ("rotor", ROTORS), ("offsets", OFFSETS),
                              ("covariance", COVARIANCES)):
            check_choice("payload", name, getattr(self, name), choices)
        for name, r in NUMBERS.items():
            value = getattr(self, name)
            if value is None and name in OPTIONAL:
                continue
            try:
                object.__setattr__(self, name, check_value(value, name, r=r))
            except BaseparamsError as exc:
                raise type(exc)(f"payload: {exc}") from None
        object.__setattr__(self, "friction", friction_terms(self.friction))
        object.__setattr__(self, "prior", prior_values(self.prior))

    def __repr__(self) -> str:
        changed = [f"{f.name}={getattr(self, f.name)!r}" for f in fields(self) if getattr(self, f.name) != f.default]
        return f"PayloadOptions({', '.join(changed)})"

    def to_json(self) -> dict:
        """The options as JSON types (what a saved payload holds under ``options``).

        Returns
        -------
        dict
            One key per option; ``friction`` a list, ``prior`` None or ``{"mass", "com",
            "inertia_com"}``.
        """
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["friction"] = list(self.friction)
        out["prior"] = None if self.prior is None else prior_dict(self.prior)
        return out


def prior_values(prior) -> tuple | None:
    """A prior payload as ten numbers ``(mass, cx, cy, cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)``, checked.

    Parameters
    ----------
    prior : dict, Inertia, sequence of 10 numbers or None
        ``{"mass", "com", "inertia_com"}`` (LINK's frame; inertia about the centre of mass), an
        :class:`~baseparams.model.inertia.Inertia` (its ``frame`` applied), or the ten numbers.

    Returns
    -------
    tuple of float or None
        The ten numbers (None for None).

    Raises
    ------
    ArgumentTypeError
        Another type, missing keys, numbers that are not finite.
    BaseparamsError
        A mass that is not positive, an inertia that is not realizable (the pseudo-inertia not
        positive semidefinite).
    """
    from ...arguments import ArgumentTypeError, check_array
    from ...model.inertia import Inertia, pseudo_inertia, split

    if prior is None:
        return None
    if isinstance(prior, Inertia):
        n = prior.pseudo()
        m, h, j = split(n)
        c = h / m if m > 0 else np.zeros(3)
        prior = {"mass": float(m), "com": c, "inertia_com": j - m * (c @ c * np.eye(3) - np.outer(c, c))}
    if isinstance(prior, dict):
        missing = [k for k in ("mass", "com", "inertia_com") if k not in prior]
        if missing:
            raise ArgumentTypeError(f"payload: prior= needs the keys mass, com, inertia_com; missing {missing}")
        com = check_array(prior["com"], "payload: prior com", 1)
        ic = check_array(prior["inertia_com"], "payload: prior inertia_com", 2)
        if com.shape != (3,) or ic.shape != (3, 3):
            raise ArgumentTypeError(f"payload: prior com must be 3 numbers and inertia_com 3x3, got {com.shape} and "
                                    f"{ic.shape}")
        values = np.r_[float(prior["mass"]), com, ic[0, 0], ic[0, 1], ic[0, 2], ic[1, 1], ic[1, 2], ic[2, 2]]
    else:
        values = check_array(prior, "payload: prior", 1)
        if values.shape != (10,):
            raise ArgumentTypeError(f"payload: prior= must be a dict, an Inertia or 10 numbers, got shape "
                                    f"{values.shape}")
    if not np.all(np.isfinite(values)):
        raise ArgumentTypeError("payload: prior= numbers must be finite")
    if not values[0] > 0:
        raise BaseparamsError(f"payload: the prior's mass must be > 0 kg, got {values[0]:g}")
    lam = np.linalg.eigvalsh(pseudo_inertia(values[0], values[1:4], _sym(values[4:])))
    if lam[0] < -1e-9 * max(lam[-1], 1e-300):
        raise BaseparamsError("payload: the prior is not a realizable body (its pseudo-inertia has a negative "
                              f"eigenvalue {lam[0]:.3g}: principal moments that break the triangle inequality)")
    return tuple(float(v) for v in values)


def prior_dict(values) -> dict:
    """The ten prior numbers as ``{"mass", "com", "inertia_com"}``.

    Parameters
    ----------
    values : sequence of float, shape ``(10,)``
        ``(mass, cx, cy, cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)``.

    Returns
    -------
    dict
        ``mass`` [kg], ``com`` [m] (3), ``inertia_com`` [kg m^2] (3x3 nested lists).
    """
    v = np.asarray(values, dtype=float)
    return {"mass": float(v[0]), "com": v[1:4].tolist(), "inertia_com": _sym(v[4:]).tolist()}


def _sym(six) -> np.ndarray:
    """``(Ixx, Ixy, Ixz, Iyy, Iyz, Izz)`` as a symmetric 3x3 matrix."""
    xx, xy, xz, yy, yz, zz = six
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]], dtype=float)
