"""The front door of the symbolic analysis: regroup exactly, then check against the numerics."""

from __future__ import annotations

import time

import numpy as np

from ..analysis import regressor
from .check import check as run_check
from .check import conversion, floats
from .geometry import SymbolicRobot
from .solve import SymbolicAnalysis, regroup

#: the command line's limit on the exact regrouping [s] (a 7-DoF arm with 9 symbols takes ~10 s)
TIME_LIMIT_S = 600.0


def symbolic_analysis(robot: SymbolicRobot, convention: str = "khalil", seed: int = 0,
                      check: bool = True, progress=None, max_seconds: float | None = None) -> SymbolicAnalysis:
    """Base parameters of ``robot`` as formulas in its symbols (DRNG on the symbolic geometry).

    Parameters
    ----------
    robot : SymbolicRobot
        The robot.
    convention : str, default "khalil"
        Parameter convention of the formulas: ``khalil`` (link frames, Khalil & Dombre) or
        ``paper`` (spatial pseudo-inertia entries at q = 0), or any of
        :data:`~baseparams.model.inertia.CONVENTIONS`.
    seed : int
        Seed of the random rational point that decides the column basis and the dependent
        parameters.
    check : bool, default True
        Compare with the certified numerical analysis at two random points and refuse a result
        whose count or formulas differ (:func:`.check.check`).
    progress : callable, optional
        Called with one line per step (``progress(str)``; the CLI prints them on stderr).
    max_seconds : float, optional
        Give up on the exact regrouping after this long, with a message saying what would help
        (the CLI: :data:`TIME_LIMIT_S`); default no limit.

    Returns
    -------
    SymbolicAnalysis
        The formulas, the conditions under which they hold, the checks.

    Raises
    ------
    BaseparamsError
        The rules do not span the whole nullspace (the numerical analysis finds more directions),
        or the formulas disagree with it.
    """
    t0 = time.perf_counter()
    out = regroup(robot, convention, seed, progress, max_seconds)
    if check:
        if progress is not None:
            progress("checking against the certified numerical analysis at 2 random points")
        run_check(out)
    out.seconds = time.perf_counter() - t0
    return out


def base_regressor(sa: SymbolicAnalysis, q, dq=None, ddq=None, values: dict | None = None) -> np.ndarray:
    """The family's base regressor at some dimensions: ``tau = W_b @ beta``.

    ``W_b = Y_c[..., independent]`` with ``Y_c`` the TP regressor in the result's convention
    (``beta = pi_I + K pi_D`` absorbs the rest), for the robot at ``values``.

    Parameters
    ----------
    sa : SymbolicAnalysis
        The symbolic result.
    q, dq, ddq : array_like, shape ``(S, m)``
        States, as :func:`baseparams.regressor` (loops: the actuated coordinates).
    values : dict, optional
        Numbers for the symbols (default: the table's).

    Returns
    -------
    ndarray, shape ``(S, m, n_base)``
        Columns in the order of ``sa.base``.
    """
    vals = sa.robot.complete_values(values)
    y = regressor(sa.robot.to_robot(vals), q, dq, ddq)  # paper convention
    paper_from_conv = np.linalg.inv(floats(conversion(sa).subs(vals)))
    return (y @ paper_from_conv)[..., sa.independent]
