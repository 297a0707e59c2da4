"""Identification: base-parameter and drive values from measured joint torques.

The pipeline (:func:`identify`):

1. the base-parameter analysis of the robot (:func:`baseparams.analyze`, certified);
2. the drive model (rotor inertia, friction) of the measured joints and which of its
   parameters regroup with base parameters (:class:`IdentModel`, decided on sampled states);
3. the log (:class:`~baseparams.ident.data.JointLog`) preprocessed: resampled, zero-phase
   low-pass filtered, velocities and accelerations derived, the same filter applied to the
   torques and to every regressor column (parallel filtering), decimated
   (:mod:`baseparams.ident.preprocess`);
4. the model regressor accumulated row by row on a streaming QR
   (:class:`~baseparams.ident.estimate.RowAccumulator`): memory independent of the log length;
5. OLS, WLS (per-joint weights) or the physically consistent estimate (every body's
   pseudo-inertia ``N_i`` positive semidefinite, rotor inertia and friction non-negative, a
   log-det pull towards the model file's inertias; :mod:`baseparams.ident.physical`);
6. validation on held-out data: per-joint RMS of the predicted torques.

Parameters keep their conventions: base parameters are named and valued in the analysis's
convention (``khalil`` by default); full parameter vectors say theirs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .analysis import Analysis, analyze
from .errors import BaseparamsError
from .ident.drives import DriveRegrouping, Drives, drives_for, regroup_drives
from .model.robot import Robot
from .numerics import StreamingQR, closed_samples, row_mask, sample_states


@dataclass(frozen=True, eq=False)
class IdentModel:
    """The linear model identified: base parameters and drive parameters, regrouped.

    ``tau = A(q, dq, ddq) theta`` on the measured rows, ``theta = E phi`` with
    ``phi = [beta (nb); delta (nd)]``: ``beta`` the analysis's base parameters (its
    convention), ``delta`` the drive parameters (:class:`~baseparams.ident.drives.Drives`).

    Parameters
    ----------
    analysis : Analysis
        The certified base-parameter analysis.
    drives : Drives
        The drive model of the measured rows.
    regrouping : DriveRegrouping
        Which drive parameters regroup into base parameters.
    coords : ndarray of int, shape ``(m,)``
        The coordinate of each measured row (a tree's ``q`` index; for a robot with loops the
        actuated coordinates, in ``robot.actuated`` order).
    """

    analysis: Analysis
    drives: Drives
    regrouping: DriveRegrouping
    coords: np.ndarray

    @property
    def robot(self) -> Robot:
        """The robot."""
        return self.analysis.robot

    @property
    def names(self) -> list[str]:
        """Model parameter names ``(p,)``: regrouped base parameters, then drive parameters."""
        return self.regrouping.model_names

    @property
    def n_params(self) -> int:
        """Number of model parameters ``p``."""
        return len(self.regrouping.independent)

    @property
    def state_columns(self) -> int:
        """Columns of the states this model takes: ``robot.dof``, or ``len(robot.actuated)`` with loops."""
        r = self.robot
        return len(r.actuated) if r.has_loops else r.dof

    def regressor(self, q, dq, ddq) -> np.ndarray:
        """The model regressor ``A`` of the measured rows.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States (a tree's coordinates; a loop robot's actuated coordinates).

        Returns
        -------
        A : ndarray, shape ``(S, m, p)``
            ``tau = A @ theta`` on the measured rows.
        """
        yb = self.analysis.base_regressor(q, dq, ddq)
        sel = self.coords if not self.robot.has_loops else np.arange(len(self.coords))
        dq = np.atleast_2d(np.asarray(dq, dtype=float))[:, sel]
        ddq = np.atleast_2d(np.asarray(ddq, dtype=float))[:, sel]
        d = self.drives.regressor(dq, ddq, len(self.coords))
        return np.concatenate([yb, d], axis=2)[:, :, self.regrouping.independent]

    def full_map(self) -> np.ndarray:
        """``G (p, 10 n + nd)``: ``theta = G [pi_paper; delta]``.

        Returns
        -------
        ndarray, shape ``(p, 10 n + nd)``
            ``pi_paper`` in the ``paper`` convention (``robot.parameters("paper")``).
        """
        base = self.analysis.base
        beta_of_paper = base.E @ np.linalg.inv(base.T)  # (nb, 10 n): paper -> convention -> base
        nd = self.drives.n_params
        blk = np.zeros((beta_of_paper.shape[0] + nd, beta_of_paper.shape[1] + nd))
        blk[: beta_of_paper.shape[0], : beta_of_paper.shape[1]] = beta_of_paper
        blk[beta_of_paper.shape[0]:, beta_of_paper.shape[1]:] = np.eye(nd)
        return self.regrouping.matrix() @ blk

    def theta(self, pi_paper: np.ndarray, delta: np.ndarray | None = None) -> np.ndarray:
        """Model parameters of full parameters.

        Parameters
        ----------
        pi_paper : ndarray, shape ``(10 n,)``
            Inertial parameters, ``paper`` convention.
        delta : ndarray, shape ``(nd,)``, optional
            Drive parameters (default zero).

        Returns
        -------
        ndarray, shape ``(p,)``
            ``theta = G [pi_paper; delta]``.
        """
        nd = self.drives.n_params
        delta = np.zeros(nd) if delta is None else np.asarray(delta, dtype=float)
        return self.full_map() @ np.r_[np.asarray(pi_paper, dtype=float), delta]


def measured_coords(robot: Robot, rows: str) -> np.ndarray:
    """The coordinate of each measured row.

    Parameters
    ----------
    robot : Robot
        The robot.
    rows : {"all", "joints", "base"}
        The measured generalized forces (loops: the actuated ones).

    Returns
    -------
    ndarray of int, shape ``(m,)``
        Indices into the tree coordinates ``q``.
    """
    if robot.has_loops:
        return np.asarray(robot.actuated, dtype=int)
    return np.flatnonzero(row_mask(robot, rows))


def ident_model(analysis: Analysis, rotor: bool = True, friction=("viscous", "coulomb", "offset"),
                coulomb_width: float | None = None, samples: int = 200, seed: int = 0) -> IdentModel:
    """The identification model of an analysed robot: base parameters plus drives, regrouped.

    Parameters
    ----------
    analysis : Analysis
        The base-parameter analysis (:func:`baseparams.analyze`).
    rotor : bool
        Include each driven joint's rotor inertia ``Ia``.
    friction : iterable of str
        Friction terms: any of ``viscous``, ``coulomb``, ``offset``.
    coulomb_width : float, optional
        Smooth Coulomb velocity scale (``tanh(dq / w)``); ``None``: ``sign(dq)``.
    samples : int
        Random states deciding which drive parameters regroup.
    seed : int
        Their seed.

    Returns
    -------
    IdentModel
        The model; drive parameters that regroup are absorbed by base parameters.

    Raises
    ------
    BaseparamsError
        An analysis that is not certified or completed (its base set is not trustworthy), or a
        drive regrouping without a clear rank decision.
    """
    if not analysis.status.ok and analysis.status != "unverified":
        raise BaseparamsError(f"robot {analysis.robot.name!r}: the base-parameter analysis is {analysis.status}; "
                              f"identification needs a certified base set")
    robot = analysis.robot
    coords = measured_coords(robot, analysis.rows)
    drives = drives_for(robot, coords, rotor, friction, coulomb_width)
    rng = np.random.default_rng(seed)
    if robot.has_loops:  # positions that close the loops; rates of both signs (sign(dq) != 1)
        q = closed_samples(robot, samples, rng).q[:, robot.actuated]
    else:
        q = sample_states(robot, samples, rng)[0]
    dq, ddq = rng.uniform(-1.0, 1.0, (2,) + q.shape)
    probe = IdentModel(analysis, drives, _identity_regrouping(analysis, drives), coords)
    a = probe.regressor(q, dq, ddq)
    factor = StreamingQR(a.shape[2]).add(a.reshape(-1, a.shape[2])).r
    regrouping = regroup_drives(factor, analysis.base_names, drives)
    if not regrouping.decided:
        raise BaseparamsError(f"robot {robot.name!r}: whether the drive parameters regroup is not decided "
                              f"(singular-value gap {regrouping.gap:.3g}); try another seed or more samples")
    return IdentModel(analysis, drives, regrouping, coords)


def _identity_regrouping(analysis: Analysis, drives: Drives) -> DriveRegrouping:
    names = list(analysis.base_names) + drives.names
    p = len(names)
    return DriveRegrouping(names, np.arange(p), np.zeros(0, dtype=int), np.zeros((p, 0)), True, np.inf)


def analyze_for_identification(robot: Robot, rows: str = "all", **kwargs) -> Analysis:
    """The base-parameter analysis an identification starts from.

    Parameters
    ----------
    robot : Robot
        The robot.
    rows : {"all", "joints", "base"}
        The measured generalized forces.
    **kwargs
        Passed to :func:`baseparams.analyze` (``convention``, ``samples``, ``seed``).

    Returns
    -------
    Analysis
        Certified (or completed) analysis.
    """
    return analyze(robot, rows=rows, **kwargs)


@dataclass(frozen=True, eq=False)
class Fit:
    """Identified values of an :class:`IdentModel`.

    Parameters
    ----------
    model : IdentModel
        The model identified.
    method : str
        ``ols``, ``wls`` or ``physical``.
    theta : ndarray, shape ``(p,)``
        Model parameter values (regrouped base parameters in the analysis's convention, then
        drive parameters).
    estimate : Estimate
        The least-squares estimate (OLS, or WLS for ``wls`` and as the physical fit's
        statistics).
    physical : object, optional
        The physically consistent fit (:class:`baseparams.ident.physical.PhysicalFit`), or
        ``None``.
    """

    model: IdentModel
    method: str
    theta: np.ndarray
    estimate: object
    physical: object = None

    def predict(self, q, dq, ddq) -> np.ndarray:
        """Predicted generalized forces of the measured rows.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States.

        Returns
        -------
        ndarray, shape ``(S, m)``
            ``A(q, dq, ddq) @ theta``.
        """
        return self.model.regressor(q, dq, ddq) @ self.theta

    def rms(self, q, dq, ddq, tau) -> tuple[np.ndarray, float]:
        """Prediction error on (held-out) data.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States.
        tau : array_like, shape ``(S, m)``
            Measured generalized forces of the measured rows.

        Returns
        -------
        rms : ndarray, shape ``(m,)``
            Per-row RMS of ``tau - predict(...)``.
        total : float
            RMS over all rows.
        """
        e = np.asarray(tau, dtype=float) - self.predict(q, dq, ddq)
        return np.sqrt(np.mean(e**2, axis=0)), float(np.sqrt(np.mean(e**2)))


def accumulate(model: IdentModel, q, dq, ddq, tau, chunk: int = 20000, transform=None):
    """The model regressor and torques accumulated row by row (streaming QR).

    Parameters
    ----------
    model : IdentModel
        The model.
    q, dq, ddq : ndarray, shape ``(S, state_columns)``
        States.
    tau : ndarray, shape ``(S, m)``
        Measured generalized forces of the measured rows.
    chunk : int
        Samples per block (memory ``chunk * m * p`` floats).
    transform : callable, optional
        Applied to the whole regressor ``(S, m, p)`` and to ``tau`` before accumulation (the
        parallel filter and decimation); the blocks are then the transformed arrays' (the whole
        regressor is formed once).

    Returns
    -------
    RowAccumulator
        The accumulated factors.
    """
    from .ident.estimate import RowAccumulator

    acc = RowAccumulator(len(model.coords), model.n_params)
    tau = np.asarray(tau, dtype=float)
    if transform is not None:
        return acc.add(transform(model.regressor(q, dq, ddq)), transform(tau))
    for k in range(0, len(tau), chunk):
        sl = slice(k, k + chunk)
        acc.add(model.regressor(q[sl], dq[sl], ddq[sl]), tau[sl])
    return acc


def fit(model: IdentModel, acc, method: str = "ols", prior_weight: float | None = None,
        mass_bounds=None) -> Fit:
    """Estimate the model parameters from accumulated data.

    Parameters
    ----------
    model : IdentModel
        The model.
    acc : RowAccumulator
        The data (:func:`accumulate`).
    method : {"ols", "wls", "physical"}
        The estimator. ``physical``: full parameters with every ``N_i`` positive semidefinite,
        rotor inertia and friction non-negative, pulled towards the model file's inertias
        (log-det divergence, weight ``prior_weight``), on the WLS-weighted compressed system.
    prior_weight : float, optional
        Weight of the prior (``physical`` only; default that of
        :func:`baseparams.ident.physical.physical_fit`).
    mass_bounds : ndarray, shape ``(n, 2)``, optional
        Mass bounds per body [kg] (``physical`` only).

    Returns
    -------
    Fit
        The values and their statistics.

    Raises
    ------
    BaseparamsError
        An unknown method, or data that do not excite the model.
    """
    from .ident.estimate import ols, wls

    if method not in ("ols", "wls", "physical"):
        raise BaseparamsError(f"unknown identification method {method!r}; choose ols, wls or physical")
    est = ols(acc, model.names) if method == "ols" else wls(acc, model.names)
    if method != "physical":
        return Fit(model, method, est.theta, est)
    from .ident.physical import physical_fit

    kwargs = {} if prior_weight is None else {"prior_weight": prior_weight}
    phys = physical_fit(est.R11, est.r12, model.full_map(), model.robot, model.drives.param_kinds,
                        mass_bounds=mass_bounds, **kwargs)
    return Fit(model, method, phys.theta, est, phys)
