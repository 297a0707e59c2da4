"""The identification model: base parameters and drive terms of the measured joints.

:class:`IdentModel` (its regressor, parameter names and the map back to full parameters),
:func:`ident_model` and the measured coordinates of a robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..analysis import Analysis, analyze
from ..display import clip, counted
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..numerics import StreamingQR, closed_samples, row_mask, sample_states
from .drives import FRICTION_TERMS, DriveRegrouping, Drives, drives_for, regroup_drives

#: bytes of regressor formed at once where the states are many (:meth:`IdentModel.regressor_blocks`)
REGRESSOR_BYTES = 32e6


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
    log_base : bool
        A floating base's six state columns are a log's base coordinates (position and Z-Y-X
        angles and their time derivatives, :mod:`baseparams.kinematics.floating`), mapped to the
        robot's own (twist coordinates, spatial twist) in :meth:`regressor`; default the robot's own.
    """

    analysis: Analysis
    drives: Drives
    regrouping: DriveRegrouping
    coords: np.ndarray
    log_base: bool = False

    @property
    def robot(self) -> Robot:
        """The robot."""
        return self.analysis.robot

    @property
    def names(self) -> list[str]:
        """Model parameter names ``(p,)``: regrouped base parameters, then drive parameters."""
        return self.regrouping.model_names

    @property
    def joints(self) -> list[str]:
        """The measured joints ``(m,)``: the joint of each coordinate of :attr:`coords` (a log's rows)."""
        return self.robot.coordinate_names(self.coords)

    @property
    def n_params(self) -> int:
        """Number of model parameters ``p``."""
        return len(self.regrouping.independent)

    @property
    def n_base(self) -> int:
        """Model parameters that are base parameters (drive terms regrouped into them included)."""
        return int(np.count_nonzero(self.regrouping.independent < len(self.analysis.base_names)))

    @property
    def n_drive(self) -> int:
        """Model parameters that are drive terms (those not regrouped into base parameters)."""
        return self.n_params - self.n_base

    @property
    def torque_unit(self) -> str:
        """Unit of the measured generalized forces: ``N m`` (revolute), ``N`` (prismatic) or both."""
        r = self.robot
        kinds = {"N" if r.jtype[r.dof_body[c]] == "P" else "N m" for c in self.coords}
        return kinds.pop() if len(kinds) == 1 else "N m or N"

    def __repr__(self) -> str:
        d = self.drives
        terms = f"{self.n_base} base + {self.n_drive} drive terms"
        if d.kinds:
            terms += f" ({' '.join(d.kinds)} on {counted(len(d.joints), 'joint')}"
            terms += f", {len(self.regrouping.dependent)} regrouped)" if len(self.regrouping.dependent) else ")"
        return clip(f"<IdentModel {self.robot.name}: {terms}, {len(self.coords)} measured rows>")

    @property
    def state_columns(self) -> int:
        """Columns of the states this model takes: ``robot.dof``, or ``len(robot.actuated)`` with loops."""
        r = self.robot
        return len(r.actuated) if r.has_loops else r.dof

    @property
    def row_states(self) -> np.ndarray:
        """The state column of each measured row ``(m,)``: where its ``q``, ``dq`` and its torque's log column are."""
        return self.coords if not self.robot.has_loops else np.arange(len(self.coords))

    def regressor_blocks(self, q, dq, ddq, max_bytes: float | None = None, max_samples: int | None = None):
        """The model regressor of many states, formed a bounded block at a time.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States.
        max_bytes : float, optional
            Largest block of regressor [bytes] (default :data:`REGRESSOR_BYTES`: a large robot's
            rows are wide, 60 links and 596 columns take 0.3 MB per sample).
        max_samples : int, optional
            Most samples per block.

        Yields
        ------
        start : int
            The block's first sample.
        A : ndarray, shape ``(k, m, p)``
            :meth:`regressor` of samples ``start .. start + k``.
        """
        q, dq, ddq = np.atleast_2d(q), np.atleast_2d(dq), np.atleast_2d(ddq)
        per_sample = 8 * max(len(self.coords), 1) * max(self.n_params, 1)
        step = max(1, int((REGRESSOR_BYTES if max_bytes is None else max_bytes) // per_sample))
        step = step if max_samples is None else max(1, min(step, int(max_samples)))
        for k in range(0, len(q), step):
            yield k, self.regressor(q[k:k + step], dq[k:k + step], ddq[k:k + step])

    def regressor(self, q, dq, ddq, closed=None, backend: str = "auto") -> np.ndarray:
        """The model regressor ``A`` of the measured rows.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States (a tree's coordinates; a loop robot's actuated coordinates).
        closed : ClosedStates, optional
            A loop robot's states already closed: :func:`~baseparams.kinematics.loops.close_loops`
            of these ``q, dq, ddq`` with every sample kept (not closed again).
        backend : {"auto", "numpy", "compiled"}
            The regressor's kernel (:func:`~baseparams.regressor.tp.regressor`'s ``backend``),
            e.g. ``compiled`` for the windows of a long streamed log, each below the size at
            which ``auto`` loads the compiled kernel.

        Returns
        -------
        A : ndarray, shape ``(S, m, p)``
            ``tau = A @ theta`` on the measured rows.
        """
        from ..analysis import checked_states
        from ..regressor.tp import closed_projected_regressor, projected_regressor

        if self.log_base and self.robot.floating:
            from ..kinematics.floating import robot_states

            q, dq, ddq = robot_states(self.robot, q, dq, ddq)
        if closed is None:
            q, dq, ddq, cs = checked_states(self.robot, q, dq, ddq)
        else:
            q, dq, ddq, cs = np.atleast_2d(q), np.atleast_2d(dq), np.atleast_2d(ddq), closed
        p_map = self._column_map()
        if cs is not None:
            out = closed_projected_regressor(self.robot, cs, P=p_map, backend=backend)
        else:
            out = projected_regressor(self.robot, q, dq, ddq, P=p_map, rows=self.coords, backend=backend)
        sel = self.row_states
        self._drive_columns(dq[:, sel], ddq[:, sel], out)
        return out

    def _column_map(self):
        """``(10 n, p)``: the base map on the kept base columns, zero on the drive columns (cached).

        Dense for a small model; a ``scipy.sparse`` CSR matrix where the analysis's regrouping is
        sparse (a large tree: a dense map would take ``80 n p`` bytes).
        """
        p_map = self.__dict__.get("_pmap")
        if p_map is None:
            nb = len(self.analysis.base_names)
            ind = self.regrouping.independent
            base_cols = np.flatnonzero(ind < nb)
            t = self.analysis.base.T
            if hasattr(t, "tocsr"):
                import scipy.sparse as sp

                sub = t.tocsc()[:, self.analysis.base.independent[ind[base_cols]]].tocoo()
                p_map = sp.csr_matrix((sub.data, (sub.row, base_cols[sub.col])), shape=(10 * self.robot.n, len(ind)))
            else:
                p_map = np.zeros((10 * self.robot.n, len(ind)))
                p_map[:, base_cols] = self.analysis.base_map[:, ind[base_cols]]
            object.__setattr__(self, "_pmap", p_map)
        return p_map

    def broadband_entries(self, q, dq, ddq) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The regressor's entries that are not smooth in the states: the Coulomb friction columns.

        A regressor evaluated at a stride and filtered there (:func:`~baseparams.ident.chunks.parallel_rows`)
        takes these at the full rate: ``sign(dq)`` (or a steep ``tanh``) has content at every frequency.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, state_columns)``
            States, as for :meth:`regressor`.

        Returns
        -------
        rows, cols : ndarray of int, shape ``(e,)``
            The entries' measured row and column.
        values : ndarray, shape ``(S, e)``
            ``regressor(q, dq, ddq)[:, rows, cols]``.
        """
        nb = len(self.analysis.base_names)
        picks = []
        for col, i in enumerate(self.regrouping.independent):
            if i >= nb and self.drives.param_kind(int(i - nb)) in ("Fc", "Fcm"):
                picks.append((col, int(i - nb)))
        if not picks:
            return np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros((np.shape(q)[0], 0))
        if self.log_base and self.robot.floating:
            from ..kinematics.floating import robot_states

            q, dq, ddq = robot_states(self.robot, q, dq, ddq)
        sel = self.row_states
        dq = np.atleast_2d(np.asarray(dq, dtype=float))[:, sel]
        ddq = np.atleast_2d(np.asarray(ddq, dtype=float))[:, sel]
        rows, cols, values = [], [], []
        for col, k in picks:
            r, v = self.drives.param_column(k, dq, ddq)
            rows += [int(x) for x in r]
            cols += [col] * len(r)
            values.append(v)
        return np.array(rows), np.array(cols), np.concatenate(values, axis=1)

    def _drive_columns(self, dq: np.ndarray, ddq: np.ndarray, out: np.ndarray) -> None:
        """Write the kept drive parameters' columns into ``out (S, m, p)`` in place."""
        nb = len(self.analysis.base_names)
        for col, i in enumerate(self.regrouping.independent):
            if i < nb:
                continue
            rows, values = self.drives.param_column(int(i - nb), dq, ddq)
            out[:, rows, col] = values

    def full_map(self) -> np.ndarray:
        """``G (p, 10 n + nd)``: ``theta = G [pi_paper; delta]``.

        Returns
        -------
        ndarray, shape ``(p, 10 n + nd)``
            ``pi_paper`` in the ``paper`` convention (``robot.parameters("paper")``).
        """
        g = self.sparse_full_map()
        return g.toarray() if hasattr(g, "toarray") else g

    def sparse_full_map(self):
        """:meth:`full_map` as a ``scipy.sparse`` CSR matrix where the regrouping is sparse (a large tree).

        ``G = E_drive [E_base T^-1, 0; 0, I]``: ``T`` (:func:`~baseparams.base.regroup.paper_from`) is
        block diagonal, inverted body by body; nothing ``(10 n, 10 n)`` is formed dense.

        Returns
        -------
        ndarray or scipy.sparse.csr_matrix, shape ``(p, 10 n + nd)``
            Dense when the analysis's regrouping matrices are.
        """
        from ..base.sparse import body_transforms

        base, robot, nd = self.analysis.base, self.robot, self.drives.n_params
        inv_blocks = np.linalg.inv(body_transforms(robot, base.convention))  # (n, 10, 10): T^-1 body by body
        if not hasattr(base.E, "tocsr") and not hasattr(base.T, "tocsr"):
            e = np.asarray(base.E).reshape(base.E.shape[0], robot.n, 10)
            beta_of_paper = np.einsum("bnk,nkl->bnl", e, inv_blocks).reshape(base.E.shape[0], -1)
            blk = np.zeros((beta_of_paper.shape[0] + nd, beta_of_paper.shape[1] + nd))
            blk[: beta_of_paper.shape[0], : beta_of_paper.shape[1]] = beta_of_paper
            blk[beta_of_paper.shape[0]:, beta_of_paper.shape[1]:] = np.eye(nd)
            return self.regrouping.matrix() @ blk
        import scipy.sparse as sp

        inv_t = sp.bsr_matrix((inv_blocks, np.arange(robot.n), np.arange(robot.n + 1)),
                              shape=(10 * robot.n, 10 * robot.n)).tocsr()
        blk = sp.block_diag([sp.csr_matrix(base.E) @ inv_t, sp.identity(nd)], format="csr")
        return (self.regrouping.sparse_matrix() @ blk).tocsr()

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
            ``theta = G [pi_paper; delta]``: the base parameters by the analysis's own map
            (:meth:`~baseparams.Analysis.to_base`, ``O(n)`` in the recursive form), then the drive regrouping.
        """
        from ..base.sparse import body_transforms

        nd = self.drives.n_params
        delta = np.zeros(nd) if delta is None else np.asarray(delta, dtype=float)
        base, n = self.analysis.base, self.robot.n
        inv_blocks = np.linalg.inv(body_transforms(self.robot, base.convention))  # paper -> convention, per body
        pi = np.einsum("nkl,nl->nk", inv_blocks, np.asarray(pi_paper, dtype=float).reshape(n, 10)).reshape(-1)
        phi = np.r_[self.analysis.to_base(pi, base.convention), delta]
        reg = self.regrouping
        return phi[reg.independent] + np.asarray(reg.K).reshape(len(reg.independent), -1) @ phi[reg.dependent]


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


#: the drive-regrouping probe's regressor above this many bytes takes 3 p rows (fewer states), in pieces
PROBE_BYTES = 64e6

#: the most floating-point operations an identification's dense least squares may take, counted before any
#: of it runs (:func:`check_size`): about half an hour at the 5-10 GFLOP/s LAPACK's QR reaches on one core of
#: the development machine. A 220-link chain's 2 196 parameters on 22 000 rows take about 1.5e12; a 1 000-link
#: chain's 10 000 parameters 1e14 at the least (its drive probe alone 6e12)
MAX_FLOPS = 1e13
#: ... and the drive-regrouping probe (:func:`probe_cost`), which a simulation runs too: a few minutes
PROBE_FLOPS = 2e12

#: what helps an identification too large for the machine (:func:`check_size`)
SMALLER = ("identify part of the robot (--joints A,B,...: the others welded), fewer drive terms (--friction none, "
           "no --rotor) or fewer fitted samples (a larger --decimate, a shorter log)")
#: ... and one whose parameters alone are too many, whatever the log (:func:`model_for`)
SMALLER_MODEL = "identify part of the robot (--joints A,B,...: the others welded)"


def fit_cost(p: int, m: int, rows: int) -> tuple[float, float]:
    """What fitting ``p`` parameters on ``rows`` observations costs: floating-point operations and bytes.

    The row factors hold ``min(rows / m, p + 1)`` rows of ``p + 1`` numbers per measured row
    (:class:`~baseparams.ident.estimate.RowAccumulator`), about twice over (the cross-validation's
    blocks and the fitted rows kept); each weighting stacks them once (``2 rows p^2`` flops a QR), and
    the estimators' dense ``p x p`` work (the blocks' complements, inverses, singular values) is
    about ``100 p^3``.

    Parameters
    ----------
    p : int
        Model parameters.
    m : int
        Measured rows per sample.
    rows : int
        Observations (samples x ``m``).

    Returns
    -------
    flops : float
        Floating-point operations, roughly.
    nbytes : float
        Peak memory [bytes], roughly.
    """
    held = min(rows, m * (p + 1))
    return 4.0 * held * p**2 + 100.0 * float(p) ** 3, 16.0 * held * (p + 1) + 160.0 * (p + 1) ** 2


def probe_cost(p: int, m: int) -> tuple[float, float]:
    """What :func:`ident_model`'s drive-regrouping probe costs: floating-point operations and bytes.

    Parameters
    ----------
    p : int
        Columns of ``[Yb | D]`` (base and drive parameters).
    m : int
        Measured rows per sample.

    Returns
    -------
    flops : float
        A QR of about ``3 p`` rows of ``p`` columns.
    nbytes : float
        Its factor, one step of rows and the regressor pieces.
    """
    rows = max(20, math.ceil(3 * p / max(m, 1))) * m
    return 2.0 * rows * p**2, 8.0 * 3 * (p + 1) ** 2 + PROBE_BYTES


def check_size(robot: Robot, what: str, cost: tuple[float, float], helps: str = SMALLER,
               max_flops: float | None = None) -> None:
    """Refuse at once, in one line, work the machine cannot do: more memory than it has, or beyond ``max_flops``.

    Parameters
    ----------
    robot : Robot
        The model (named in the message).
    what : str
        The work, e.g. ``"fitting 2196 parameters on 22000 rows"``.
    cost : tuple of float
        ``(flops, bytes)`` (:func:`fit_cost`, :func:`probe_cost`).
    helps : str
        What would help (default :data:`SMALLER`).
    max_flops : float, optional
        The most work allowed (default :data:`MAX_FLOPS`, read when called).

    Raises
    ------
    BaseparamsError
        The memory needed exceeds what is available (:func:`~baseparams.numerics.available_bytes`), or
        the work ``max_flops``.
    """
    from ..numerics import available_bytes

    flops, need = cost
    max_flops = MAX_FLOPS if max_flops is None else max_flops
    have = available_bytes()
    if have is not None and need > have:
        raise BaseparamsError(f"robot {robot.name!r}: {what} needs about {need / 1e9:.2g} GB of memory and "
                              f"{have / 1e9:.2g} GB are available; would help: {helps}")
    if flops > max_flops:
        raise BaseparamsError(f"robot {robot.name!r}: {what} needs about {flops:.1g} floating-point operations "
                              f"(dense least squares: the cost grows with the cube of the parameters), beyond the "
                              f"{max_flops:.0g} allowed; would help: {helps}")


def ident_model(analysis: Analysis, rotor: bool = True, friction=FRICTION_TERMS,
                coulomb_width: float | None = None, samples: int = 200, seed: int = 0,
                couplings=(), log_base: bool = False) -> IdentModel:
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
    couplings : iterable of MotorCoupling
        Motors driving several joints (:class:`~baseparams.ident.drives.MotorCoupling`): their
        ``Iam``, ``Fvm``, ``Fcm`` (with ``rotor``, viscous, Coulomb friction).
    log_base : bool
        A floating base's states are a log's base coordinates (:attr:`IdentModel.log_base`).

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
    drives = drives_for(robot, coords, rotor, friction, coulomb_width, couplings)
    rng = np.random.default_rng(seed)
    if not drives.n_params:  # nothing to regroup: no probe (a large tree's would be a p^3 QR for nothing)
        return checked_values(IdentModel(analysis, drives, _identity_regrouping(analysis, drives), coords, log_base),
                              rng)
    if robot.has_loops:  # positions that close the loops; rates of both signs (sign(dq) != 1)
        q = closed_samples(robot, samples, rng).q[:, robot.actuated]
    else:
        q = sample_states(robot, samples, rng)[0]
    dq, ddq = rng.uniform(-1.0, 1.0, (2,) + q.shape)
    probe = IdentModel(analysis, drives, _identity_regrouping(analysis, drives), coords, log_base)
    p = len(analysis.base_names) + drives.n_params
    check_size(robot, f"deciding which of its {drives.n_params} drive parameters regroup with its "
                      f"{len(analysis.base_names)} base parameters", probe_cost(p, len(coords)),
               "fewer drive terms (--friction none and no --rotor: nothing to decide)", PROBE_FLOPS)
    if len(q) * len(coords) * p * 8 > PROBE_BYTES:  # a large tree: 3 p rows are plenty (p unknowns)
        keep = max(20, math.ceil(3 * p / max(len(coords), 1)))
        q, dq, ddq = q[:keep], dq[:keep], ddq[:keep]
    qr = StreamingQR(p)
    step = max(1, int(PROBE_BYTES // (8 * len(coords) * p)) // 4)  # states per regressor evaluated at once
    for k in range(0, len(q), step):
        qr.add(probe.regressor(q[k:k + step], dq[k:k + step], ddq[k:k + step]).reshape(-1, p))
    factor = qr.r
    regrouping = regroup_drives(factor, analysis.base_names, drives)
    if not regrouping.decided:
        raise BaseparamsError(f"robot {robot.name!r}: whether the drive parameters regroup is not decided "
                              f"(singular-value gap {regrouping.gap:.3g}); try another seed or more samples")
    return checked_values(IdentModel(analysis, drives, regrouping, coords, log_base), rng)


#: the robot's own parameters, regrouped, must give its torques to this relative accuracy (:func:`checked_values`)
VALUES_RTOL = 1e-4


def checked_values(model: IdentModel, rng: np.random.Generator, samples: int = 4) -> IdentModel:
    """The model, after checking that its parameter values can be computed: ``A theta(pi)`` gives ``Y pi``.

    A base parameter is ``pi_I + K pi_D``; on a long chain in a link-frame convention the regrouping's
    coefficients can grow with each body (a 220-link chain of random axes: ``K`` to 3e18 in ``khalil``),
    and the values, computed in double precision, then lose every digit: a simulation's truth, a fit's
    prior and a saved result would be numbers that do not give the torques. Checked on a few random states
    of a tree (``O(n)`` each: :func:`~baseparams.regressor.tp.generalized_forces`).

    Parameters
    ----------
    model : IdentModel
        The model.
    rng : numpy.random.Generator
        Source of the states.
    samples : int
        States checked.

    Returns
    -------
    IdentModel
        ``model``.

    Raises
    ------
    BaseparamsError
        The robot's own parameters, regrouped, miss its torques by more than :data:`VALUES_RTOL`.
    """
    from ..kinematics.floating import robot_states
    from ..regressor.tp import generalized_forces

    robot = model.robot
    if robot.has_loops:
        return model
    q = sample_states(robot, samples, rng)[0][:, :model.state_columns]
    dq, ddq = rng.uniform(-1.0, 1.0, (2,) + q.shape)
    native = robot_states(robot, q, dq, ddq) if model.log_base else (q, dq, ddq)  # as model.regressor reads them
    tau = generalized_forces(robot, *native, rows=model.coords)
    err = float(np.abs(model.regressor(q, dq, ddq) @ model.theta(robot.parameters("paper")) - tau).max())
    scale = float(np.abs(tau).max())
    if not err <= VALUES_RTOL * scale:
        k = model.analysis.base.K
        big = float(np.abs(k.data if hasattr(k, "tocsr") else np.asarray(k)).max(initial=0.0))
        convention = model.analysis.convention
        other = ("--convention khalil (each body's own link frame: no world-frame moments of bodies far from the "
                 "origin)" if convention == "paper" else
                 "--convention paper (world frame at q = 0) regroups without the link frames' transforms")
        raise BaseparamsError(
            f"robot {robot.name!r}: its {convention} base parameters cannot be computed in double "
            f"precision: the regrouping's coefficients reach {big:.1g}, and its own parameters, regrouped, miss its "
            f"torques by {err / max(scale, 1e-300):.1g} of their size; might help: {other}")
    return model


def log_rows(robot: Robot) -> str:
    """The generalized forces a joint log measures: ``"joints"`` with a floating base (no base wrench), else all.

    Parameters
    ----------
    robot : Robot
        The model.

    Returns
    -------
    str
        ``"joints"`` or ``"all"``.
    """
    return "joints" if robot.floating else "all"


def model_for(robot: Robot, options, rows: str | None = None) -> IdentModel:
    """The identification model of a robot's log, as the options build it (every path's, and a saved result's).

    Parameters
    ----------
    robot : Robot
        The model the log was recorded on.
    options : IdentOptions
        Its ``convention``, ``literal``, ``analysis_samples`` and ``seed`` build the analysis,
        ``rotor``, ``friction``, ``coulomb_width`` and ``couplings`` the drive model (``rotor="auto"``:
        without rotor inertia; the pipeline tries it, :func:`baseparams.ident.pipeline.identify`).
    rows : str, optional
        The measured rows (default :func:`log_rows`; a saved result's own).

    Returns
    -------
    IdentModel
        The model (:func:`ident_model`; a floating base's states are the log's base coordinates).

    Raises
    ------
    BaseparamsError
        As :func:`baseparams.analyze` and :func:`ident_model`.
    """
    analysis = analyze(robot, samples=options.analysis_samples, seed=options.seed, convention=options.convention,
                       rows=log_rows(robot) if rows is None else rows, literal=options.literal)
    coords = measured_coords(robot, analysis.rows)
    rotor = options.rotor_columns
    nd = drives_for(robot, coords, rotor, options.friction, options.coulomb_width, options.couplings).n_params
    p = len(analysis.base_names) + nd
    helps = SMALLER_MODEL + (", fewer drive terms (--friction none, no --rotor)" if nd else "")
    check_size(robot, f"identifying {p} parameters (at least as many observations)", fit_cost(p, len(coords), p),
               helps)  # the fewest rows: only fewer parameters help
    return ident_model(analysis, rotor, options.friction, options.coulomb_width, couplings=options.couplings,
                       log_base=robot.floating)


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

