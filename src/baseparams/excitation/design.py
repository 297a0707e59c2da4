"""The designer: seeded random starts, SLSQP on the design grid, the result at the controller's rate.

:func:`design_excitation` (the optimised design) and :func:`random_excitation` (the baseline it is
compared with: a design's random starting point within the same limits).
"""

from __future__ import annotations

import time
from contextlib import contextmanager

import numpy as np

from ..analysis import Analysis, analyze
from ..errors import BaseparamsError
from ..ident.drives import FRICTION_TERMS
from ..ident.model import IdentModel, ident_model
from ..model.robot import Robot
from .constraints import Evaluator, linear_constraints, n_nonlinear
from .criterion import trajectory_criterion
from .diagnose import binding, violation
from .fourier import coefficients, fourier_basis
from .limits import design_coordinates, loop_bound
from .options import DesignOptions
from .problem import (
    KEEPOUT_MARGIN,
    MARGIN,
    Problem,
    check_options,
    keepout_height,
    make_problem,
    shrunk_range,
    with_keepout,
)
from .result import Excitation

#: a start stops when its best value has not improved by STALL[0] (log cond, or logdet / p) in STALL[1] iterations
STALL = (1e-3, 20)


#: a design whose condition number is above this does not excite the model
COND_LIMIT = 1e8


def design_excitation(robot_or_analysis, options: DesignOptions | None = None, /, *, progress=None,
                      **keywords) -> Excitation:
    """Design a periodic excitation trajectory that identifies every base parameter (module doc).

    Parameters
    ----------
    robot_or_analysis : Robot, Analysis or IdentModel
        The robot (analysed here), its certified analysis, or an identification model (its
        columns are the criterion's: e.g. ``ident_model(analysis, friction=(...))``).
    options : DesignOptions, optional
        How (:class:`~baseparams.excitation.options.DesignOptions`: the series, the limits, the
        criterion, the starts); default its defaults.
    progress : callable, optional
        Called with one line of text per start (and every 25 iterations).
    **keywords
        Options as keywords, instead of or over ``options`` (``harmonics=5``, ``starts=1``).

    Returns
    -------
    Excitation
        The trajectory at ``rate`` over one period, its coefficients and criterion.

    Raises
    ------
    BaseparamsError
        Bad options; a floating base; a loop robot whose reference configuration is singular;
        limits that leave no room for motion; no start that satisfies the loops or torque limits;
        a result that does not excite every model parameter (the limits are too tight).
    """
    from ..arguments import options_from
    from ..numerics import blas_threads

    o = options_from(DesignOptions, options, keywords)
    t0 = time.perf_counter()
    model = _model(robot_or_analysis, o.drives, o.rotor)
    prob, notes = make_problem(model, o.criterion, o.harmonics, o.base_frequency, o.rate, o.grid, o.limits,
                               o.acceleration, o.torque, o.margin)
    if o.keepout is not None:
        prob, note = with_keepout(prob, o.keepout)
        notes.append(note)
    with blas_threads(), _kernel_threads():
        x, value = _multistart(prob, o.starts, o.seed, o.max_iter, progress or (lambda msg: None))
        notes.append(f"best of {o.starts} starts (seed {o.seed}): {_shown(prob, value)} on the {o.grid}-sample "
                     f"design grid; designed in {time.perf_counter() - t0:.1f} s")
        return _finish(prob, x, o.rate, notes)


def random_excitation(robot_or_analysis, harmonics: int = 5, base_frequency: float = 0.1, rate: float = 1000.0,
                      drives: bool = False, limits=None, acceleration=None, torque: bool = False, seed: int = 0,
                      rotor: bool = False, margin: float = 0.0) -> Excitation:
    """A random excitation within the same limits, not optimised: the baseline a design is compared with.

    Random normal coefficients (at rest at both ends), offsets near the middle of the ranges (loops:
    the reference), each coordinate's oscillation scaled until its tightest limit is reached (then
    shrunk, if needed, for the loops and torques), exactly as a design's starting point.

    Parameters
    ----------
    robot_or_analysis : Robot, Analysis or IdentModel
        As :func:`design_excitation`.
    harmonics, base_frequency, rate, drives, limits, acceleration, torque, rotor, margin
        As :func:`design_excitation`.
    seed : int
        Seed of the coefficients.

    Returns
    -------
    Excitation
        The trajectory and its criteria (``criterion`` is ``cond``).

    Raises
    ------
    BaseparamsError
        As :func:`design_excitation`.
    """
    from ..arguments import check_keywords
    from ..numerics import blas_threads

    check_keywords("", harmonics=harmonics)
    check_options(harmonics, base_frequency, rate, "cond", 1, 8 * harmonics)
    check_keywords("", seed=seed, margin=margin, acceleration=acceleration)
    model = _model(robot_or_analysis, drives, rotor)
    prob, notes = make_problem(model, "cond", harmonics, base_frequency, rate, 200, limits, acceleration, torque,
                               margin)
    with blas_threads(), _kernel_threads():
        x = _start(prob, np.random.default_rng(seed), fill=1.0 / MARGIN)
        return _finish(prob, x, rate, notes + [f"random coefficients (seed {seed}), not optimised"])


def _model(obj, drives: bool, rotor: bool) -> IdentModel:
    """The identification model of a robot, an analysis or a model (checked: fixed base, loops regular).

    A payload's design model (:class:`~baseparams.excitation.payload.DesignModel`, ``design_model``
    set) is taken as an :class:`IdentModel` is: its columns are the criterion's.
    """
    given = isinstance(obj, IdentModel) or getattr(obj, "design_model", False)
    if given:
        robot = obj.robot
    else:
        robot = obj.robot if isinstance(obj, Analysis) else obj
        if not isinstance(robot, Robot):
            raise BaseparamsError(f"design_excitation needs a Robot, an Analysis or an IdentModel, "
                                  f"got {type(obj).__name__}")
    if robot.floating:
        raise BaseparamsError(f"robot {robot.name!r}: no actuated coordinate moves its floating base; the excitation "
                              f"designer needs a fixed base (every designed coordinate driven by a joint)")
    if robot.loops:
        loop_bound(robot)
    if given:
        return obj
    analysis = obj if isinstance(obj, Analysis) else analyze(robot)
    friction = FRICTION_TERMS if drives else ()
    return ident_model(analysis, rotor=bool(drives and rotor), friction=friction)


@contextmanager
def _kernel_threads():
    """The compiled regressor kernels loaded (numba installed), on one thread inside the block.

    A design evaluates the regressor hundreds of times on small batches (a grid, its perturbations):
    the kernels beat numpy there, but their thread pool's start-up costs about 10 ms a call on two
    cores, ten times the work; one thread was faster at every batch size measured (200 to 13000
    samples).
    """
    from ..regressor import compiled

    if not compiled.available():
        yield
        return
    import numba

    from ..regressor import kernels  # noqa: F401  (loading them makes backend="auto" use them)

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def _multistart(prob: Problem, starts: int, seed: int, max_iter: int, say) -> tuple[np.ndarray, float]:
    """The best feasible design ``(x (m k,), value)`` of ``starts`` seeded random starts."""
    rng = np.random.default_rng(seed)
    best, last = (np.inf, None), None
    for s in range(starts):
        ts = time.perf_counter()
        value, x, nit, last = _optimise(prob, _start(prob, rng), max_iter,
                                        lambda msg: say(f"start {s + 1}/{starts}: {msg}"))
        say(f"start {s + 1}/{starts}: {_shown(prob, value)} on the design grid after {nit} iterations "
            f"({time.perf_counter() - ts:.1f} s)")
        if x is not None and value < best[0]:
            best = (value, x)
    if best[1] is None:
        raise BaseparamsError(f"robot {prob.model.robot.name!r}: no start reached a feasible design that excites every "
                              f"model parameter: {binding(prob, last)}")
    return best[1], best[0]


def _optimise(prob: Problem, x0: np.ndarray, max_iter: int, say) -> tuple[float, np.ndarray | None, int, np.ndarray]:
    """SLSQP from ``x0``: ``(best value, best feasible x or None, iterations, the last point evaluated)``."""
    from scipy.optimize import minimize

    lin = linear_constraints(prob)
    ev = Evaluator(prob, lin)
    lo, hi = shrunk_range(prob.limits)
    bounds = [(lo[j], hi[j]) if i == 0 else (None, None) for j in range(prob.m) for i in range(prob.k)]
    cons = [{"type": "ineq", "fun": lambda x: lin[0] @ x + lin[1], "jac": lambda x: lin[0]}]
    if n_nonlinear(prob):
        cons.append({"type": "ineq", "fun": lambda x: ev(x)["cons"], "jac": lambda x: ev(x, True)["jac"]})
    it, seen = [0], [(np.inf, 0)]

    def callback(xk):
        it[0] += 1
        if it[0] % 25 == 0:
            say(f"iteration {it[0]}: {_shown(prob, ev.best[0])}")
        if ev.best[0] < seen[0][0] - STALL[0]:
            seen[0] = (ev.best[0], it[0])
        elif it[0] - seen[0][1] >= STALL[1]:
            raise StopIteration  # no progress: the next start is worth more

    ev(x0)
    minimize(lambda x: ev(x)["value"], x0, jac=lambda x: ev(x, True)["grad"], method="SLSQP", bounds=bounds,
             constraints=cons, callback=callback, options={"maxiter": max_iter, "ftol": 1e-7})
    return ev.best[0], ev.best[1], it[0], ev.x


def _shown(prob: Problem, value: float) -> str:
    """The internal value as the user reads it: ``cond 12.3`` or ``logdet -4.5``."""
    if not np.isfinite(value):
        return f"{prob.criterion} not finite"
    p = prob.model.n_params
    return f"cond {np.exp(value):.6g}" if prob.criterion == "cond" else f"logdet {-value * p:.6g}"


def _start(prob: Problem, rng: np.random.Generator, fill: float = 0.5) -> np.ndarray:
    """A random feasible start ``(m k,)``.

    Offsets near the range's centre (loops: the reference), random coefficients filling ``fill`` of
    the limits, shrunk until the loops and torques are satisfied.
    """
    lim = prob.limits
    lo, hi = shrunk_range(lim)
    off = 0.5 * (lo + hi) + rng.uniform(-0.15, 0.15, prob.m) * (hi - lo)
    if prob.cond_max is not None and prob.model.robot.loops:  # q = 0 is known feasible (the loops' reference)
        off = np.clip(0.0, lo, hi)
    elif prob.keepout is not None:
        off = _keepout_offsets(prob, off)
    x = np.column_stack([off, rng.normal(size=(prob.m, prob.k - 1))])
    x = _scaled(x, prob.bases, np.column_stack([lo, hi, MARGIN * lim[:, 2:4]]), fill, grow=True).reshape(-1)
    if prob.theta is None and prob.cond_max is None and prob.keepout is None:
        return x
    ev = Evaluator(prob, (np.zeros((0, x.size)), np.zeros(0)))
    for _ in range(40):
        out = ev(x)
        if out["valid"] and np.all(out["cons"] >= 0):
            return x
        x = x.reshape(prob.m, prob.k)
        x[:, 1:] *= 0.7
        x = x.reshape(-1)
    raise BaseparamsError(f"robot {prob.model.robot.name!r}: no feasible start: even at rest at the offsets "
                          f"{binding(prob, x, at_rest=True)}")


def _scaled(x: np.ndarray, bases, lim: np.ndarray, fill: float, grow: bool) -> np.ndarray:
    """``x (m, k)`` with each coordinate's oscillation scaled to ``fill`` of its tightest limit.

    Positions are scaled about the offset (inside the range); ``grow=False`` only shrinks.
    """
    q, dq, ddq = (b @ x.T for b in bases)
    dev = q - x[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(dev > 0, (lim[:, 1] - x[:, 0]) / dev, np.where(dev < 0, (lim[:, 0] - x[:, 0]) / dev, np.inf))
        ratios = np.vstack([room.min(axis=0), lim[:, 2] / np.abs(dq).max(axis=0), lim[:, 3] / np.abs(ddq).max(axis=0)])
    s = fill * np.nanmin(np.where(np.isnan(ratios), np.inf, ratios), axis=0)
    s = np.where(np.isfinite(s), s, 1.0)
    out = x.copy()
    out[:, 1:] *= s[:, None] if grow else np.minimum(s, 1.0)[:, None]
    return out


#: random rest configurations searched for offsets above the keep-out heights
KEEPOUT_CANDIDATES = 4000


def _keepout_offsets(prob: Problem, off: np.ndarray) -> np.ndarray:
    """Offsets ``(m,)`` at which every kept-out link rests above its height, with room to move every joint.

    ``off`` (near the ranges' middle) when it will do; else, among the middle, q = 0 and
    :data:`KEEPOUT_CANDIDATES` seeded random points of the ranges' inner halves (a quarter of each
    range kept on either side), the one nearest to ``off`` (in fractions of the ranges) with every
    link at least ``2 KEEPOUT_MARGIN`` above its height; else the one with the most room.
    """
    lim = prob.limits
    lo, hi = shrunk_range(lim)
    mid, width = 0.5 * (lo + hi), hi - lo
    rng = np.random.default_rng(0)
    inner = lo + width * rng.uniform(0.25, 0.75, (KEEPOUT_CANDIDATES, prob.m))
    cands = np.vstack([off, mid, np.clip(0.0, lo, hi), inner])
    room = (keepout_height(prob, cands) - prob.keepout_min).min(axis=1)  # the lowest link's room [m]
    ok = np.flatnonzero(room >= 2 * KEEPOUT_MARGIN)
    if ok.size:
        return cands[ok[np.argmin(np.abs((cands[ok] - off) / width).sum(axis=1))]]
    if room.max() > 0:
        return cands[int(np.argmax(room))]  # the most room there is
    robot = prob.model.robot
    body, z_min = prob.keepout[int(np.argmin(keepout_height(prob, cands[[int(np.argmax(room))]])[0]
                                             - prob.keepout_min))]
    raise BaseparamsError(f"robot {robot.name!r}: the keep-out binds: at rest anywhere among {len(cands)} points of "
                          f"the joint ranges some link is below its height (best: {robot.names[body]!r} "
                          f"{-room.max():.3g} m below z = {z_min:.4g} m); lower the keep-out heights or widen the "
                          f"position limits")


def _finish(prob: Problem, x: np.ndarray, rate: float, notes: list[str]) -> Excitation:
    """The design at the controller's rate: scaled into the limits, checked, its criterion computed."""
    model, robot = prob.model, prob.model.robot
    f = prob.omega / (2 * np.pi)
    t = np.arange(int(round(rate / f)) + 1) / rate
    bases = fourier_basis(t, prob.harmonics, prob.omega)
    xm = _scaled(x.reshape(prob.m, prob.k), bases, prob.limits, 1.0, grow=False)
    shrunk = 1.0 - np.abs(xm[:, 1:]).sum(axis=1) / np.maximum(np.abs(x.reshape(prob.m, prob.k)[:, 1:]).sum(axis=1),
                                                               1e-300)
    for _ in range(30):
        q, dq, ddq = (b @ xm.T for b in bases)
        why = violation(prob, q, dq, ddq)
        if not why:
            break
        xm[:, 1:] *= 0.95
        shrunk = 1.0 - (1.0 - shrunk) * 0.95
    else:
        raise BaseparamsError(f"robot {robot.name!r}: the design fails at the controller's rate ({why})")
    if shrunk.max() > 1e-12:
        notes.append(f"oscillations scaled down by up to {100 * shrunk.max():.2g} % to meet every limit at {rate:g} Hz")
    cond, logdet = trajectory_criterion(model, q, dq, ddq)
    if not cond < COND_LIMIT:
        from ..ident.estimate import excitation
        from ..numerics import StreamingQR

        weak = excitation(StreamingQR(model.n_params).add(model.regressor(q, dq, ddq)).r, model.names)[1]
        raise BaseparamsError(f"robot {robot.name!r}: within these limits the trajectory does not excite {weak[:5]} "
                              f"(condition number {cond:.3g}): {binding(prob, xm.reshape(-1))}")
    if prob.cond_max is not None and robot.loops:
        from ..kinematics.loops import close_loops

        notes.append(f"loops: every sample closed on the reference assembly mode, cond(J_p) <= "
                     f"{close_loops(robot, q, cond_max=np.inf).cond.max():.3g}")
    offsets, a, b = coefficients(xm, prob.harmonics)
    joints = tuple(robot.coordinate_names(design_coordinates(robot)))
    return Excitation(robot.name, joints, prob.harmonics, f, float(rate), offsets, a, b, t, q, dq, ddq, prob.criterion,
                      cond if prob.criterion == "cond" else logdet, cond, prob.limits.copy(), tuple(model.names),
                      tuple(notes))
