"""One design problem: the identification model, the design grid and its bases, the limits.

The optimiser's margins (the limits used while optimising are a fraction of the given ones, so
that the check at the controller's rate rarely has to scale anything), the options' checks and the
keep-out height of a named link.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import BaseparamsError
from ..ident.model import IdentModel
from .fourier import fourier_basis
from .limits import design_coordinates, excitation_limits, loop_bound

#: the criteria: ``cond`` (column-scaled condition number) and ``logdet`` (D-optimality)
CRITERIA = ("cond", "logdet")


#: the limits used while optimising are this fraction of the given ones (the controller-rate check
#: then rarely has to scale anything)
MARGIN = 0.99


#: the bound on cond(J_p) while optimising is this fraction of the one checked at the controller's rate
LOOP_MARGIN = 0.9


#: position, velocity and acceleration limits are imposed on every LIMIT_STRIDE-th sample of the design grid
LIMIT_STRIDE = 2


#: a point counts as feasible while optimising when no constraint row (fractions of the limits; log
#: cond(J_p)) is violated by more than this (inside the margins above)
FEAS_TOL = 5e-3


#: the keep-out height is raised by this [m] while optimising (the controller-rate check then rarely scales)
KEEPOUT_MARGIN = 0.01


@dataclass(frozen=True, eq=False)
class Problem:
    """One design: the model, the grid and its bases, the limits and the constraints' data.

    Parameters
    ----------
    model : IdentModel
        The identification model (the criterion's columns).
    criterion : str
        ``cond`` or ``logdet``.
    harmonics : int
        ``L``.
    omega : float
        ``w = 2 pi f`` [rad/s].
    t : ndarray, shape ``(G,)``
        The design grid [s].
    bases : tuple of ndarray, each shape ``(G, k)``
        ``Bq, Bv, Ba`` (:func:`~baseparams.excitation.fourier.fourier_basis`), ``k = 2 L - 1``.
    limits : ndarray, shape ``(m, 5)``
        ``lower, upper, velocity, acceleration, effort`` (NaN: none).
    theta : ndarray, shape ``(p,)``, or None
        The prior model parameters whose torques stay within the effort limits, or None.
    cond_max : float or None
        Loops: the bound on ``cond(J_p)``; None for a tree.
    keepout : tuple of tuple of (int, float), optional
        ``((body, lowest height of its frame origin [m]), ...)``, one pair per kept-out link, or None.
    """

    model: IdentModel
    criterion: str
    harmonics: int
    omega: float
    t: np.ndarray  # (G,) the design grid
    bases: tuple[np.ndarray, np.ndarray, np.ndarray]  # Bq, Bv, Ba (G, k)
    limits: np.ndarray  # (m, 5)
    theta: np.ndarray | None  # (p,) prior model parameters (torque limits), or None
    cond_max: float | None  # loops: the bound on cond(J_p), else None
    keepout: tuple[tuple[int, float], ...] | None = None  # ((body, lowest height of its origin [m]), ...), or None

    @property
    def keepout_min(self) -> np.ndarray:
        """The kept-out links' lowest heights ``(K,)`` [m] (empty without a keep-out)."""
        return np.array([z for _, z in self.keepout or ()], dtype=float)

    def __repr__(self) -> str:
        loops = "" if self.cond_max is None else f", cond(J_p) <= {self.cond_max:.3g}"
        return (f"<Problem {self.model.robot.name}: {self.m} coordinates, {self.harmonics} harmonics, "
                f"{self.t.size}-sample grid, {self.criterion}, {self.model.n_params} parameters{loops}>")

    @property
    def m(self) -> int:
        """Designed coordinates."""
        return self.limits.shape[0]

    @property
    def k(self) -> int:
        """Variables per coordinate."""
        return 2 * self.harmonics - 1

    def states(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The states on the grid of the variables.

        Parameters
        ----------
        x : ndarray, shape ``(m k,)``
            Per coordinate ``[q0, a_2..a_L, b_2..b_L]``, concatenated.

        Returns
        -------
        q, dq, ddq : ndarray, shape ``(G, m)``
            Positions, velocities, accelerations.
        """
        xm = x.reshape(self.m, self.k)
        return tuple(b @ xm.T for b in self.bases)


def shrunk_range(lim: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The position range used while optimising: ``MARGIN`` of the width, centred.

    Parameters
    ----------
    lim : ndarray, shape ``(m, 5)``
        The limits (:attr:`Problem.limits`).

    Returns
    -------
    lo, hi : ndarray, shape ``(m,)``
        Lower and upper positions [rad or m].
    """
    pad = 0.5 * (1 - MARGIN) * (lim[:, 1] - lim[:, 0])
    return lim[:, 0] + pad, lim[:, 1] - pad


def keepout_height(prob: Problem, q: np.ndarray) -> np.ndarray:
    """Heights of the kept-out bodies' frame origins (world z) at tree states.

    Parameters
    ----------
    prob : Problem
        The design problem (with a keep-out).
    q : ndarray, shape ``(S, dof)``
        Tree positions.

    Returns
    -------
    ndarray, shape ``(S, K)``
        The height [m] of each kept-out link (``prob.keepout``'s order).
    """
    from ..kinematics.tree import forward_kinematics

    bodies = [b for b, _ in prob.keepout]
    robot = prob.model.robot
    g = forward_kinematics(robot, q).g[:, bodies]  # (S, K, 4, 4)
    return np.einsum("skj,kj->sk", g[:, :, 2, :], robot.M0[bodies][:, :, 3])


def check_options(harmonics, base_frequency, rate, criterion, starts, grid) -> None:
    """Raise on options that cannot give a design.

    Parameters
    ----------
    harmonics : int
        ``L >= 2``.
    base_frequency, rate : float
        ``f`` and the controller's rate [Hz]; ``rate >= 4 L f``.
    criterion : str
        One of :data:`CRITERIA`.
    starts : int
        Random starts, ``>= 1``.
    grid : int
        Design-grid samples, ``>= 8 L``.

    Raises
    ------
    BaseparamsError
        The first option that cannot give a design, named.
    """
    from ..arguments import check_keywords, check_samples

    check_keywords("", harmonics=harmonics, base_frequency=base_frequency, rate=rate, starts=starts, grid=grid)
    check_samples(rate / base_frequency, 16, "one period (1 / base_frequency) at the rate")
    if criterion not in CRITERIA:
        raise BaseparamsError(f"unknown criterion {criterion!r}; choose {' or '.join(CRITERIA)}")
    if int(harmonics) != harmonics or harmonics < 2:
        raise BaseparamsError(f"harmonics must be an integer >= 2 (the first harmonic brings the motion to rest), "
                              f"got {harmonics}")
    if not (base_frequency > 0 and rate > 0):
        raise BaseparamsError(f"base frequency and rate must be > 0, got {base_frequency} Hz and {rate} Hz")
    if rate < 4 * harmonics * base_frequency:
        raise BaseparamsError(f"rate {rate:g} Hz is too slow for {harmonics} harmonics of {base_frequency:g} Hz "
                              f"(at least {4 * harmonics * base_frequency:g} Hz)")
    if starts < 1 or grid < 8 * harmonics:
        raise BaseparamsError(f"need starts >= 1 and grid >= {8 * harmonics} samples, got {starts} and {grid}")


def make_problem(model: IdentModel, criterion, harmonics, base_frequency, rate, grid, limits, acceleration,
             torque, margin=0.0) -> tuple[Problem, list[str]]:
    """The design problem and the notes of its defaults.

    Parameters
    ----------
    model : IdentModel
        The identification model.
    criterion : str
        ``cond`` or ``logdet``.
    harmonics : int
        ``L``.
    base_frequency, rate : float
        ``f`` (rounded to a whole number of controller samples per period) and the controller's rate [Hz].
    grid : int
        Design-grid samples per period.
    limits, acceleration, margin
        As :func:`~baseparams.excitation.limits.excitation_limits`.
    torque : bool
        Keep the model's own torques within the effort limits.

    Returns
    -------
    prob : Problem
        The problem.
    notes : list of str
        The defaults taken, the rounding, the loops' bound.

    Raises
    ------
    BaseparamsError
        A loop robot whose reference is outside its limits, torque limits asked without an effort
        limit, limits that leave no room.
    """
    robot = model.robot
    lim, notes = excitation_limits(robot, limits, acceleration, margin)
    outside = [j for j in range(len(lim)) if not lim[j, 0] < 0 < lim[j, 1]]
    if robot.loops and outside:  # couplings alone close anywhere: no reference needed
        names = robot.coordinate_names(design_coordinates(robot))
        raise BaseparamsError(f"robot {robot.name!r}: the loops are assembled at the reference configuration q = 0, "
                              f"outside the position range of joint "
                              + ", ".join(f"{names[j]!r} [{lim[j, 0]:.6g}, {lim[j, 1]:.6g}]" for j in outside)
                              + "; re-reference the model inside the limits (baseparams.kinematics.loops.assemble) or "
                                "widen them")
    per = max(1, int(round(rate / base_frequency)))
    f = rate / per
    if abs(f - base_frequency) > 1e-12 * base_frequency:
        notes.append(f"base frequency {base_frequency:.6g} Hz rounded to {f:.8g} Hz: a period of {per} samples "
                     f"at {rate:g} Hz")
    omega = 2 * np.pi * f
    t = (np.arange(grid) + 0.5) / (grid * f)
    theta = None
    if torque:
        if not np.isfinite(lim[:, 4]).any():
            raise BaseparamsError(f"robot {robot.name!r}: torque limits asked, but no effort limit is known")
        theta = model.theta(robot.parameters("paper"))
    cond_max = loop_bound(robot) if robot.loops else None  # couplings alone: exact, linear, never singular
    if cond_max is not None:
        notes.append(f"loops: cond(J_p) <= {cond_max:.3g} at every sample (continuation from the reference assembly)")
    elif robot.couplings:
        notes.append("coupled joints: designed in the actuated coordinates, the coupled ones set by their couplings")
    return Problem(model, criterion, int(harmonics), omega, t, fourier_basis(t, int(harmonics), omega), lim, theta,
                    cond_max), notes


def keepout_pairs(keepout) -> list[tuple[str, float]]:
    """``(link, z)`` or a sequence of such pairs, as a list of pairs.

    Parameters
    ----------
    keepout : tuple of (str, float), or sequence of them
        One link's keep-out, or several.

    Returns
    -------
    list of tuple of (str, float)
        The pairs.

    Raises
    ------
    BaseparamsError
        Anything else, or a height that is not a finite number within 1e6 m.
    """
    from ..arguments import brief

    try:
        items = [keepout] if isinstance(keepout, tuple) and len(keepout) == 2 and isinstance(keepout[0], str) \
            else list(keepout)
    except TypeError:
        items = [keepout]
    out = []
    for item in items:
        try:
            link, z_min = item
            out.append((str(link), float(z_min)))
        except (TypeError, ValueError):
            raise BaseparamsError(f"keepout= must be (link name, lowest height in m) or a list of them, got "
                                  f"{brief(keepout)}") from None
        if not abs(out[-1][1]) <= 1e6:
            raise BaseparamsError(f"keepout= {link}:{z_min}: the height must be a finite number in [-1e6, 1e6] m")
    if not out:
        raise BaseparamsError("keepout=: no (link name, lowest height) pair given")
    return out


def with_keepout(prob: Problem, keepout) -> tuple[Problem, str]:
    """The problem with a keep-out height for one or more named links.

    Whether the links can stay above their heights is decided by the design (offsets where they
    rest above, then every grid and controller-rate sample): not at q = 0.

    Parameters
    ----------
    prob : Problem
        The design problem.
    keepout : tuple of (str, float), or sequence of them
        ``(link name, lowest height of its frame origin [m, world z])`` per link.

    Returns
    -------
    prob : Problem
        The problem with ``keepout`` set.
    note : str
        The line the design's notes carry (what is and is not kept out).

    Raises
    ------
    BaseparamsError
        Not pairs, a loop robot, an unknown link, a link named twice.
    """
    from dataclasses import replace

    robot = prob.model.robot
    pairs = keepout_pairs(keepout)
    if robot.has_loops:
        raise BaseparamsError(f"robot {robot.name!r}: a Cartesian keep-out is supported for trees only")
    for link, _ in pairs:
        if link not in robot.names:
            raise BaseparamsError(f"robot {robot.name!r}: no link {link!r} for the keep-out; links: "
                                  f"{', '.join(robot.names)}")
    names = [link for link, _ in pairs]
    if len(set(names)) < len(names):
        raise BaseparamsError(f"keep-out: a link named twice ({names})")
    prob = replace(prob, keepout=tuple((robot.names.index(link), z) for link, z in pairs))
    what = ", ".join(f"{link!r} z >= {z:.4g} m" for link, z in pairs)
    return prob, (f"keep-out: the frame origins of {what} (world) at every sample; link geometry between frames and "
                  f"self-collision are not checked")
