"""How an excitation is designed: one checked object for the designer's options.

:class:`DesignOptions` holds every option of :func:`~baseparams.excitation.design.design_excitation`
with its default, checked once when made (:func:`~baseparams.excitation.problem.check_options` and
the ranges of :data:`baseparams.arguments.RANGES`); :func:`baseparams.excite` (the front door) and
the CLI's ``baseparams excite`` pass it, or its fields as keywords.
"""

from __future__ import annotations

from dataclasses import dataclass, fields


@dataclass(frozen=True, eq=False)
class DesignOptions:
    """Every option of an excitation design, checked when made (module docstring).

    Parameters
    ----------
    harmonics : int
        Harmonics ``L >= 2`` per coordinate.
    base_frequency : float
        ``f`` [Hz] (period ``1 / f``), rounded so that a period is a whole number of controller
        samples (a note says so).
    rate : float
        The controller's sampling rate [Hz] of the trajectory.
    criterion : {"cond", "logdet"}
        Minimise the condition number of the column-scaled regressor, or maximise ``log det`` of
        the information matrix (D-optimality).
    drives : bool
        Include the drive columns (viscous, Coulomb and offset friction per joint; rotor inertia
        with ``rotor``) besides the base parameters (ignored for an ``IdentModel``).
    rotor : bool
        With ``drives``: rotor inertia columns too.
    limits : array_like, shape ``(m, 4)``, optional
        ``[lower, upper, velocity, effort]`` per designed coordinate overriding the model's
        (:func:`~baseparams.excitation.limits.excitation_limits`; NaN keeps the model's).
    acceleration : float or array_like, shape ``(m,)``, optional
        Acceleration limits [rad/s^2 or m/s^2].
    torque : bool
        Keep the torques of the model's own inertial parameters within the effort limits.
    keepout : tuple of (str, float), or sequence of them, optional
        ``(link, z_min)`` per link: the named link's frame origin stays at or above the height
        ``z_min`` [m, world z] at every sample of the design grid and of the result (trees
        only; frame origins only).
    margin : float
        Fraction of each position range kept free at both ends.
    starts : int
        Random starts (SLSQP from each).
    seed : int
        Seed of the starts: the same seed gives the same design.
    grid : int
        Samples of one period on which the criterion and the constraints are optimised.
    max_iter : int
        SLSQP iterations per start.

    Raises
    ------
    BaseparamsError
        The first option that cannot give a design, named.
    """

    harmonics: int = 5
    base_frequency: float = 0.1
    rate: float = 1000.0
    criterion: str = "cond"
    drives: bool = False
    rotor: bool = False
    limits: object = None
    acceleration: object = None
    torque: bool = False
    keepout: object = None
    margin: float = 0.0
    starts: int = 4
    seed: int = 0
    grid: int = 200
    max_iter: int = 150

    def __repr__(self) -> str:
        changed = [f"{f.name}={getattr(self, f.name)!r:.60}" for f in fields(self)
                   if getattr(self, f.name) is not f.default and getattr(self, f.name) != f.default]
        return f"DesignOptions({', '.join(changed)})"

    def __post_init__(self):
        from ..arguments import check_keywords
        from .problem import check_options

        check_options(self.harmonics, self.base_frequency, self.rate, self.criterion, self.starts, self.grid)
        check_keywords("", seed=self.seed, max_iter=self.max_iter, margin=self.margin, acceleration=self.acceleration)
