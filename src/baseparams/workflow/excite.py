"""``baseparams.excite``: design an excitation trajectory (and the ``excite`` command's one implementation).

:func:`check_excite` holds every rule of its keywords that needs no model; :func:`excite` calls it
first and the command line's preflight calls it before the model loads (one rule, one message:
the keyword's, the command line naming the flag).
"""

from __future__ import annotations

from ..analysis import Analysis, analyze
from ..errors import BaseparamsError
from .inputs import input_files, robot_of
from .outputs import check_outputs

#: excite's numeric keywords (each in :data:`baseparams.arguments.RANGES`)
NUMBERS = ("harmonics", "period", "base_frequency", "rate", "margin", "starts", "grid", "seed", "analysis_samples",
           "max_iter", "payload_noise")
#: the keywords of a robot's design that a payload's (``payload=``) does not take: it designs the payload's
#: columns with the drive terms as nuisance, within the position and velocity limits
NOT_FOR_PAYLOAD = ("drives", "rotor", "torque", "effort", "limits", "analysis_samples", "plot", "base_frequency")
#: a payload design's period [s] unless given: a short motion
PAYLOAD_PERIOD = 5.0


def excite(model, *, harmonics: int = 5, period: float | None = None, base_frequency: float | None = None,
           rate: float = 1000.0, criterion: str | None = None, drives: bool = False, rotor: bool = False,
           position=None, velocity=None, acceleration=None, effort=None, torque: bool = False, keepout=None,
           margin: float = 0.0, starts: int = 4, grid: int = 200, seed: int = 0, analysis_samples: int | None = None,
           limits=None, max_iter: int = 150, out=None, plot=None, progress=None, payload: str | None = None,
           payload_noise: float | None = None):
    """Design an excitation trajectory: ``baseparams excite`` (:mod:`baseparams.excitation`).

    A finite Fourier series per designed coordinate, at rest at both ends, within the model's joint
    limits (or those given), optimised for the condition number of the identification regressor (or
    D-optimality).

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The robot (a built-in name or a robot file is loaded; its joint limits are the file's).
    harmonics, rate, criterion, drives, rotor, torque, margin, starts, grid, seed
        As the CLI's flags (:func:`baseparams.excitation.design_excitation`): harmonics per joint,
        the controller's rate [Hz], ``cond`` or ``logdet`` (default ``cond``; ``logdet`` with
        ``payload``), friction (and rotor) columns, the
        model's own torques within the effort limits, the fraction of each position range kept
        free, random starts, design-grid samples per period, the starts' seed.
    period, base_frequency : float, optional
        The period [s] or its inverse [Hz] (one of them; default 10 s).
    position : pair, sequence of pairs or dict, optional
        Position limits ``(lower, upper)`` [rad or m]: one pair for every designed joint, one per
        joint in order, or ``{joint: (lower, upper)}`` (``--position``); the model's elsewhere.
    velocity, acceleration, effort : float, sequence or dict, optional
        Velocity [rad/s], acceleration [rad/s^2] and effort [N m] limits, the same ways
        (``--velocity``, ``--acceleration``, ``--effort``; effort matters with ``torque``).
    keepout : tuple of (str, float), or sequence of them, optional
        ``(link, z_min)`` per link: its frame origin stays at or above ``z_min`` [m, world z] at
        every sample (``--keepout LINK:Z``, repeatable). Frame origins only: link geometry and
        self-collision are not checked.
    analysis_samples : int, optional
        Random states of the base-parameter analysis the model is built on.
    limits : array_like, shape ``(m, 4)``, optional
        ``[lower, upper, velocity, effort]`` per designed coordinate, overriding the model's
        (NaN keeps it); ``position``, ``velocity`` and ``effort`` override these.
    max_iter : int
        SLSQP iterations per start (Python only).
    out : str or path, optional
        Also write the trajectory there (``.csv``/``.tsv``: ``t, q_, dq_, ddq_``; checked before the
        design, written atomically).
    plot : str or path, optional
        Also plot ``q, dq, ddq`` per joint against the limits there (matplotlib, extra ``plot``).
    progress : callable, optional
        Called with one line of text per start.
    payload : str, optional
        Design instead a short motion that identifies a payload on this link best (``--payload``,
        :func:`baseparams.excitation.payload.excite_payload`): the joints that carry it, the criterion
        on the payload's columns with the drive terms as nuisance, period 5 s unless given;
        ``drives``, ``rotor``, ``torque``, ``effort``, ``limits``, ``analysis_samples``, ``plot`` and
        ``base_frequency`` do not apply (refused).
    payload_noise : float, optional
        With ``payload``: the torque noise [N m per sample] of the predicted standard deviations
        (default 0.1).

    Returns
    -------
    Excitation
        The trajectory at ``rate`` over one period (``.trajectory``, ``.save(path)``, ``.summary()``):
        what :func:`simulate` and a robot controller take.

    Raises
    ------
    BaseparamsError
        Bad options or model, infeasible limits (naming the constraint that binds), an output
        that cannot be written.
    """
    from ..excitation import design_excitation
    from ..excitation.limits import given_limits

    kw = {"harmonics": harmonics, "period": period, "base_frequency": base_frequency, "rate": rate,
          "criterion": criterion, "drives": drives, "rotor": rotor, "acceleration": acceleration, "torque": torque,
          "margin": margin, "starts": starts, "grid": grid, "seed": seed, "analysis_samples": analysis_samples,
          "max_iter": max_iter, "keepout": keepout, "out": out, "plot": plot, "progress": progress,
          "payload": payload, "payload_noise": payload_noise, "effort": effort, "limits": limits}
    inputs = check_excite(model, kw)
    robot = robot_of(model, "excite")
    criterion = criterion_of(criterion, payload)
    if payload is not None:
        return _payload_design(robot, kw, inputs, position, velocity)
    target = model if isinstance(model, Analysis) and analysis_samples is None else robot
    if analysis_samples is not None:
        target = analyze(robot, samples=analysis_samples, seed=seed)
    result = design_excitation(target, harmonics=harmonics, base_frequency=base_frequency_of(period, base_frequency),
                               rate=rate, criterion=criterion, drives=drives, rotor=rotor,
                               limits=given_limits(robot, limits, position, velocity, effort),
                               acceleration=acceleration, torque=torque, starts=starts, seed=seed, grid=grid,
                               max_iter=max_iter, keepout=keepout, margin=margin, progress=progress)
    if out is not None:
        result.save(out, inputs, "out=")
    if plot is not None:
        from ..report.plots import trajectory_plot

        trajectory_plot(result, plot, robot, inputs, "plot=")
    return result


def _payload_design(robot, kw: dict, inputs: list[str], position, velocity):
    """``excite(payload=LINK)``: :func:`baseparams.excitation.payload.excite_payload`, written to ``out``."""
    from ..excitation.payload import excite_payload

    design = {k: kw[k] for k in ("harmonics", "rate", "acceleration", "keepout", "margin", "starts", "seed", "grid",
                                 "max_iter", "progress")}
    noise = 0.1 if kw["payload_noise"] is None else kw["payload_noise"]
    result = excite_payload(robot, kw["payload"], period=kw["period"] or PAYLOAD_PERIOD, payload_noise=noise,
                            position=position, velocity=velocity, criterion=criterion_of(kw["criterion"], True),
                            **design)
    if kw["out"] is not None:
        result.save(kw["out"], inputs, "out=")
    return result


def criterion_of(criterion: str | None, payload) -> str:
    """The design's criterion: as given, else ``cond`` (``logdet`` for a payload's).

    Parameters
    ----------
    criterion : str or None
        ``cond``, ``logdet`` or None (the default).
    payload : object
        The payload's link, or None (or a bool: a payload's design).

    Returns
    -------
    str
        ``cond`` or ``logdet``.
    """
    if criterion is not None:
        return criterion
    return "logdet" if payload not in (None, False) else "cond"


def base_frequency_of(period: float | None, base_frequency: float | None) -> float:
    """The base frequency [Hz] of a period or a base frequency (one of them, or neither: 0.1 Hz, 10 s).

    Parameters
    ----------
    period : float or None
        The period [s].
    base_frequency : float or None
        Its inverse [Hz].

    Returns
    -------
    float
        The base frequency [Hz].
    """
    return 1.0 / period if period is not None else (0.1 if base_frequency is None else base_frequency)


def check_excite(model, keywords: dict) -> list[str]:
    """Every rule of :func:`excite`'s keywords that needs no model: their types, ranges, the outputs.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The model as given (a file's inputs are never overwritten).
    keywords : dict
        :func:`excite`'s keywords (the joint limits are checked with the model: they need its
        joints); those missing take their defaults.

    Returns
    -------
    list of str
        The run's input files.

    Raises
    ------
    BaseparamsError
        The first keyword refused, in one line naming it (its type, its range, a choice, an
        output's suffix, folder or clash with an input, one period that holds too many samples).
    """
    from ..arguments import CHOICES, check_choice, check_flags, check_keywords, check_progress, check_samples

    k = {"period": None, "base_frequency": None, "rate": 1000.0, "criterion": None, "payload": None, **keywords}
    acceleration = k.get("acceleration")
    check_keywords("excite", **{n: k[n] for n in NUMBERS if n in k and k[n] is not None},
                   **({} if isinstance(acceleration, dict) else {"acceleration": acceleration}))
    check_flags("excite", **{n: k[n] for n in ("drives", "rotor", "torque") if n in k})
    check_choice("excite", "criterion", criterion_of(k["criterion"], k["payload"]), CHOICES["criterion"])
    _check_payload(k)
    check_progress(k.get("progress"), "excite")
    if k["period"] is not None and k["base_frequency"] is not None:
        raise BaseparamsError("excite: give period= or base_frequency=, not both")
    if k.get("keepout") is not None:
        from ..excitation.problem import keepout_pairs

        keepout_pairs(k["keepout"])
    period = k["period"] if k["period"] is not None or k["payload"] is None else PAYLOAD_PERIOD
    check_samples(k["rate"] / base_frequency_of(period, k["base_frequency"]), 16,
                  f"excite: {'period=' if k['period'] is not None else 'base_frequency='} and rate= (one period at "
                  f"the rate)")
    inputs = input_files(model)
    check_outputs("excite", inputs, out=k.get("out"), plot=k.get("plot"))
    return inputs


def _check_payload(k: dict) -> None:
    """``payload=``: a link's name and none of :data:`NOT_FOR_PAYLOAD`; without it, no ``payload_noise``."""
    from ..arguments import ArgumentTypeError

    if k["payload"] is None:
        if k.get("payload_noise") is not None:
            raise BaseparamsError("excite: payload_noise= applies to payload= (a payload's design), not given")
        return
    if not isinstance(k["payload"], str):
        raise ArgumentTypeError(f"excite: payload= must be a link name, got {type(k['payload']).__name__}")
    given = [f"{n}=" for n in NOT_FOR_PAYLOAD if k.get(n) is not None and k.get(n) is not False]
    if given:
        raise BaseparamsError(f"excite: payload= designs the payload's columns with the drive terms as nuisance: "
                              f"{', '.join(given)} do not apply (period= does)")
