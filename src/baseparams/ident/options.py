"""How an identification is made: one validated object for every path (in memory, streamed, a fleet).

:class:`IdentOptions` holds every option of an identification (their defaults are written once, in
:data:`baseparams.arguments.IDENTIFY`, where the front door and the CLI's parser read them without
loading the identification) and checks them once, when it is made: numbers against
:data:`baseparams.arguments.RANGES`, the choices, the flags, friction terms, motor couplings and
model terms, and the rules across options (``prior_weight`` is the physical fit's). The front door
(:func:`baseparams.identify`, which the command line calls with its flags as keywords) and the fleet
build it; every path takes it whole; the result keeps it (the cutoff and
decimation as used) and its file saves it (:meth:`IdentOptions.to_json`, read back by
:meth:`IdentOptions.from_json`, what :func:`baseparams.predict` filters a log with).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from ..arguments import CHOICES, IDENTIFY
from ..errors import BaseparamsError
from .drives import MotorCoupling, friction_terms

#: the estimators (:func:`baseparams.ident.fit`)
METHODS = CHOICES["method"]
#: the standard deviations' covariances (:mod:`baseparams.ident.uncertainty`)
COVARIANCES = CHOICES["covariance"]
#: the options that are numbers, checked against :data:`baseparams.arguments.RANGES`
NUMBERS = ("holdout", "coulomb_width", "cutoff", "decimate", "prior_weight", "score_cutoff", "analysis_samples",
           "seed", "memory_mb")


@dataclass(frozen=True)
class IdentOptions:
    """Every option of an identification, checked when made (module docstring).

    Parameters
    ----------
    method : {"auto", "ols", "wls", "physical"}
        The estimator (:func:`baseparams.ident.fit`; ``physical`` needs the extra ``ident``).
    rotor : bool or "auto"
        Model each joint's rotor inertia ``Ia``: True forces it, False leaves it out; ``"auto"``
        (default) tries it and keeps it when blocked cross-validation on the training span asks for
        it (:func:`baseparams.ident.terms.fit.select_columns`, the model terms' rule; reported with
        the terms). In a result: True or False, as used.
    friction : str or iterable of str
        Friction terms: ``viscous``, ``coulomb``, ``offset`` (default all three; ``"none"``: none);
        kept as a tuple of names.
    coulomb_width : float, optional
        Smooth Coulomb friction's velocity scale [rad/s] (``tanh(dq / w)``).
    couplings : iterable of MotorCoupling or str
        Motors driving several joints (:class:`~baseparams.ident.drives.MotorCoupling`, or its
        text ``NAME:JOINT=W,JOINT=W``); kept as a tuple of MotorCoupling.
    holdout : float, optional
        Hold out the samples with ``t >= t_end - holdout`` [s] for validation.
    cutoff : float, optional
        Low-pass cutoff [Hz] (default from the log's excitation,
        :func:`baseparams.ident.preprocess.lowpass_design`); in a result: the cutoff used.
    decimate : int, optional
        Decimation factor (default from the rate and the cutoff); in a result: the factor used.
    min_speed : float or sequence of float, optional
        Remove samples where a joint moves slower than this [rad/s], or than its own (one per
        log column, kept as a tuple).
    prior_weight : float, optional
        ``method="physical"`` only: the weight of the model file's inertias.
    convention : str
        Convention of the base parameters' names and values.
    covariance : {"hac", "white"}
        The standard deviations' covariance (Newey-West, or the least-squares formula).
    score_cutoff : float, optional
        Also score the validation against the measured torques low-passed at this cutoff [Hz].
    allow_units : bool
        Go on when the log's units look wrong (a warning note), which otherwise refuses.
    literal : bool
        The model's geometry exactly as the file states it (:func:`baseparams.analyze`).
    terms : str or iterable of str
        Model terms beyond the linear core: ``"auto"``, ``"none"`` or names
        (:func:`baseparams.ident.terms.fit.parse_terms`); kept as a string (``"dahl,tilt"``).
    analysis_samples : int, optional
        Random states of the base-parameter analysis the model is built on.
    seed : int
        Seed of the analysis' random states.
    memory_mb : float
        Largest regressor formed at once [MB] (longer logs: chunks with overlapping filter edges).
    effort : {"auto", "torque", "current"}
        What the log's effort is: joint torques, or motor currents with unknown gains
        (:mod:`baseparams.ident.fromcurrents`); ``auto``: currents when the log has them and no
        torques.
    gain_anchor : str, optional
        Currents only: one motor's gain ``JOINT=K`` [N m/A at the joint side] fixing the gains'
        common scale, or several (``JOINT=K,JOINT=K``: their geometric mean; their disagreement
        the scale's std); default the model file's masses.

    Raises
    ------
    ArgumentTypeError, ArgumentError
        A value of the wrong type or out of its range (one line naming the keyword).
    BaseparamsError
        An unknown friction or model term, a bad coupling, ``prior_weight`` without
        ``method="physical"``.
    """

    method: str = IDENTIFY["method"]
    rotor: bool | str = IDENTIFY["rotor"]
    friction: tuple = IDENTIFY["friction"]
    coulomb_width: float | None = IDENTIFY["coulomb_width"]
    couplings: tuple = IDENTIFY["couplings"]
    holdout: float | None = IDENTIFY["holdout"]
    cutoff: float | None = IDENTIFY["cutoff"]
    decimate: int | None = IDENTIFY["decimate"]
    min_speed: float | None = IDENTIFY["min_speed"]
    prior_weight: float | None = IDENTIFY["prior_weight"]
    convention: str = IDENTIFY["convention"]
    covariance: str = IDENTIFY["covariance"]
    score_cutoff: float | None = IDENTIFY["score_cutoff"]
    allow_units: bool = IDENTIFY["allow_units"]
    literal: bool = IDENTIFY["literal"]
    terms: str = IDENTIFY["terms"]
    analysis_samples: int | None = IDENTIFY["analysis_samples"]
    seed: int = IDENTIFY["seed"]
    memory_mb: float = IDENTIFY["memory_mb"]
    effort: str = IDENTIFY["effort"]
    gain_anchor: str | None = IDENTIFY["gain_anchor"]

    def __post_init__(self):
        from ..arguments import check_choice, check_flags, check_keywords

        _rotor(self.rotor)
        check_flags("identify", allow_units=self.allow_units, literal=self.literal)
        check_choice("identify", "method", self.method, METHODS)
        check_choice("identify", "covariance", self.covariance, COVARIANCES)
        check_choice("identify", "effort", self.effort, CHOICES["effort"])
        _anchor(self.gain_anchor, self.effort)
        check_choice("identify", "convention", self.convention, CHOICES["convention"])
        check_keywords("identify", **{k: getattr(self, k) for k in NUMBERS})  # checked, kept as given
        for name, value in (("friction", friction_terms(self.friction)), ("couplings", _couplings(self.couplings)),
                            ("terms", _terms(self.terms)), ("min_speed", _speeds(self.min_speed))):
            object.__setattr__(self, name, value)
        if self.prior_weight is not None and self.method != "physical":
            raise BaseparamsError(f"identify: prior_weight= applies to method=physical, not {self.method} (the "
                                  f"default estimate chooses its own pull by cross-validation)")

    @property
    def rotor_columns(self) -> bool:
        """The model is built with rotor inertia (``rotor=True``; ``"auto"``: the pipeline adds it if kept)."""
        return not isinstance(self.rotor, str) and bool(self.rotor)

    def __repr__(self) -> str:
        changed = [f"{f.name}={getattr(self, f.name)!r}" for f in fields(self)
                   if getattr(self, f.name) != f.default]
        return f"IdentOptions({', '.join(changed)})"

    def to_json(self) -> dict:
        """The options as JSON types (what a saved result holds under ``options``).

        Returns
        -------
        dict
            One key per option; ``friction`` a list of names, ``couplings`` a list of
            ``{"name", "joints", "weights"}``.
        """
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["friction"] = list(self.friction)
        out["couplings"] = [{"name": c.name, "joints": list(c.joints), "weights": list(c.weights)}
                            for c in self.couplings]
        return out

    @classmethod
    def from_json(cls, doc: dict) -> IdentOptions:
        """The options of a saved result (:meth:`to_json`; an older file's missing options take their defaults).

        Parameters
        ----------
        doc : dict
            The saved ``options`` (checked against :data:`baseparams.schema.OPTIONS`); keys that
            are not options (``rows``) are left out.

        Returns
        -------
        IdentOptions
            The options, checked.
        """
        names = {f.name for f in fields(cls)}
        kw = {k: v for k, v in doc.items() if k in names}
        if "friction" in kw:
            kw["friction"] = tuple(kw["friction"])
        if "couplings" in kw:
            kw["couplings"] = tuple(MotorCoupling(c["name"], tuple(c["joints"]), tuple(c["weights"]))
                                    for c in kw["couplings"])
        return cls(**kw)


def options_of(options: IdentOptions | None = None, keywords: dict | None = None) -> IdentOptions:
    """Options given as an object, as keywords, or both (the keywords over the object's).

    Parameters
    ----------
    options : IdentOptions, optional
        The options (default: the defaults).
    keywords : dict, optional
        Options by name (:class:`IdentOptions`' fields).

    Returns
    -------
    IdentOptions
        The options, checked (:func:`baseparams.arguments.options_from`).
    """
    from ..arguments import options_from

    return options_from(IdentOptions, options, keywords)


def _anchor(text, effort: str) -> None:
    """``gain_anchor``: None or ``JOINT=K`` (:class:`~baseparams.ident.currents.GainAnchor`), not for torques."""
    if text is None:
        return
    if not isinstance(text, str):
        from ..arguments import ArgumentTypeError

        raise ArgumentTypeError(f"identify: gain_anchor= must be a string JOINT=K, got {type(text).__name__}")
    from .currents import parse_anchors

    parse_anchors(text)
    if effort == "torque":
        raise BaseparamsError("identify: gain_anchor= applies to motor currents (effort=current), not to torques")


def _couplings(couplings) -> tuple:
    """Couplings as MotorCoupling objects (from objects or ``NAME:JOINT=W,...`` texts)."""
    if isinstance(couplings, (str, MotorCoupling)):
        couplings = (couplings,)
    if not isinstance(couplings, (list, tuple)) or not all(isinstance(c, (str, MotorCoupling)) for c in couplings):
        from ..arguments import ArgumentTypeError

        raise ArgumentTypeError(f"identify: couplings= must be MotorCoupling objects or 'NAME:JOINT=W,...' texts, "
                                f"got {type(couplings).__name__}")
    return tuple(c if isinstance(c, MotorCoupling) else MotorCoupling.parse(c) for c in couplings)


def _speeds(min_speed):
    """``min_speed`` checked: None, a number (kept as given), or one number per joint (a tuple of floats)."""
    import numbers

    from ..arguments import check_keywords, check_value

    if min_speed is None or isinstance(min_speed, (numbers.Real, str, bytes)):
        check_keywords("identify", min_speed=min_speed)
        return min_speed
    try:
        items = list(min_speed)
    except TypeError:
        check_keywords("identify", min_speed=min_speed)  # not a number: named as such
        raise
    for k, v in enumerate(items):
        try:
            check_value(v, "min_speed")
        except BaseparamsError as exc:
            raise type(exc)(f"identify: {str(exc).replace('min_speed=', f'min_speed= (item {k})', 1)}") from None
    return tuple(float(v) for v in items)


def _terms(terms) -> str:
    """Model terms checked (:func:`~baseparams.ident.terms.fit.parse_terms`), as one string."""
    from .terms.fit import parse_terms

    parse_terms(terms)
    return terms if isinstance(terms, str) else ",".join(terms)


def _rotor(value) -> None:
    """``rotor=``: True, False or ``"auto"`` (one line naming it otherwise)."""
    import numpy as np

    from ..arguments import ArgumentTypeError, brief

    if isinstance(value, (bool, np.bool_)) or (isinstance(value, str) and value == "auto"):
        return
    raise ArgumentTypeError(f"identify: rotor= must be True, False or 'auto', got {type(value).__name__} "
                            f"{brief(value, 40)}")
