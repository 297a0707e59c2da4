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

from ..analysis import analyze
from ..display import clip, data_frame, format_number, text_table
from ..errors import BaseparamsError
from ..model.robot import Robot
from ..numerics import blas_threads
from .model import IdentModel, ident_model


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
    selection : object, optional
        ``auto``: the cross-validated pull towards the model file
        (:class:`baseparams.ident.select.Selection`), or ``None``.
    """

    model: IdentModel
    method: str
    theta: np.ndarray
    estimate: object
    physical: object = None
    selection: object = None

    def __repr__(self) -> str:
        m = self.model
        how = self.method
        if self.physical is not None:
            how += " (feasible)" if getattr(self.physical, "feasible", False) else " (not feasible)"
        rms = getattr(self.estimate, "rms_total", None)
        tail = "" if rms is None else f", residual RMS {format_number(rms, 3)} {m.torque_unit}"
        return clip(f"<Fit {m.robot.name}: {how}, {m.n_base} base + {m.n_drive} drive terms{tail}>")

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
    from .estimate import RowAccumulator

    acc = RowAccumulator(len(model.coords), model.n_params)
    tau = np.asarray(tau, dtype=float)
    if transform is not None:
        return acc.add(transform(model.regressor(q, dq, ddq)), transform(tau))
    for k in range(0, len(tau), chunk):
        sl = slice(k, k + chunk)
        acc.add(model.regressor(q[sl], dq[sl], ddq[sl]), tau[sl])
    return acc


def fit(model: IdentModel, acc, method: str = "ols", prior_weight: float | None = None,
        mass_bounds=None, blocks=None) -> Fit:
    """Estimate the model parameters from accumulated data.

    Parameters
    ----------
    model : IdentModel
        The model.
    acc : RowAccumulator
        The data (:func:`accumulate`).
    method : {"auto", "ols", "wls", "physical"}
        The estimator. ``auto``: OLS or WLS with the model file's parameters as a prior
        (maximum a posteriori; terms the data determine keep their fitted values), the weighting
        and the prior's weight chosen by blocked cross-validation on ``blocks``
        (:mod:`baseparams.ident.select`; plain WLS without blocks). ``physical``: full parameters
        with every ``N_i`` positive semidefinite, rotor inertia and friction non-negative,
        pulled towards the model file's inertias (log-det divergence, weight ``prior_weight``),
        on the WLS-weighted compressed system.
    prior_weight : float, optional
        Weight of the prior (``physical`` only; default that of
        :func:`baseparams.ident.physical.physical_fit`).
    mass_bounds : ndarray, shape ``(n, 2)``, optional
        Mass bounds per body [kg] (``physical`` only).
    blocks : list of RowAccumulator, optional
        Time-ordered pieces of ``acc``'s rows (``auto`` only).

    Returns
    -------
    Fit
        The values and their statistics.

    Raises
    ------
    BaseparamsError
        An unknown method, or data that do not excite the model.
    """
    from .estimate import ols, wls

    if method not in ("auto", "ols", "wls", "physical"):
        raise BaseparamsError(f"unknown identification method {method!r}; choose auto, ols, wls or physical")
    first = ols(acc, model.names)
    est = first if method == "ols" else wls(acc, model.names, first)
    if method == "auto":
        return _auto(model, first, est, acc, blocks or [])
    if method != "physical":
        return Fit(model, method, est.theta, est)
    from .physical import physical_fit

    kwargs = {} if prior_weight is None else {"prior_weight": prior_weight}
    phys = physical_fit(est.R11, est.r12, model.full_map(), model.robot, model.drives.param_kinds,
                        mass_bounds=mass_bounds, **kwargs)
    return Fit(model, method, phys.theta, est, phys)


def _auto(model: IdentModel, first, est, acc, blocks: list) -> Fit:
    """OLS or WLS with the model file as a prior, as far as blocked cross-validation asks."""
    from dataclasses import replace

    from .select import prior_covariance, prior_precision, ridge, select, split_blocks

    if len(blocks) < 2:
        return Fit(model, "auto", est.theta, est)
    theta0 = model.theta(model.robot.parameters("paper"))
    s = prior_covariance(model)
    sel = select(split_blocks(blocks), {"ols": first.weights, "wls": est.weights}, theta0, prior_precision(model, s))
    if sel is None:
        return Fit(model, "auto", est.theta, est)
    base = first if sel.weighting == "ols" else est
    if sel.lam == 0:
        return Fit(model, "auto", base.theta, base, selection=sel)
    nb = model.n_base
    prior_cov = np.zeros((model.n_params, model.n_params))
    prior_cov[:nb, :nb] = s / sel.lam
    from .select import no_prior_bodies

    names = tuple(n for n, x in zip(model.robot.names, no_prior_bodies(model.robot)) if x)
    sel = replace(sel, theta0=theta0, prior_cov=prior_cov, no_prior=names)
    theta = ridge(base.R11, base.r12, theta0, sel.penalty)
    res = np.array([np.linalg.norm(f.r @ np.r_[theta, -1.0]) for f in acc.factors]) / np.sqrt(max(acc.samples, 1))
    # the least-squares statistics stay: pulled_covariance maps the covariance once it is chosen
    return Fit(model, "auto", theta, replace(base, method="auto", theta=theta, rms=res), selection=sel)


def pulled_covariance(f: Fit) -> Fit:
    """The covariance of the estimate with the model file's prior: its noise and the file's error.

    The estimate is ``theta = M theta_LS + (I - M) theta0`` with ``M = (H + P)^-1 H`` (``H =
    R11^T R11`` of the chosen weighting, ``P`` the prior's penalty,
    :class:`~baseparams.ident.select.Selection`), so its error is ``M (theta_LS - theta) + (I -
    M) (theta0 - theta)``: covariance ``M C M^T + (I - M) kappa Sigma0 (I - M)^T`` with ``C`` the
    least-squares covariance (HAC or white), ``Sigma0`` the prior's stated covariance and
    ``kappa >= 0`` its scale estimated from the file's distance to the least-squares estimate
    (maximum likelihood, :func:`~baseparams.ident.select.prior_error_scale`): a term taken from a
    file the data contradict is as uncertain as that file, not as certain as the prior's weight
    alone would say.

    Parameters
    ----------
    f : Fit
        The fit (``auto`` with a prior; others are returned as they are).

    Returns
    -------
    Fit
        The fit with the covariance ``(p, p)`` and its label.
    """
    from dataclasses import replace

    from .select import prior_error_scale
    from .uncertainty import psd, with_covariance

    sel, est = f.selection, f.estimate
    if sel is None or sel.penalty is None or getattr(est, "cov", None) is None:
        return f
    gram = est.R11.T @ est.R11
    m = np.linalg.solve(gram + sel.penalty, gram)
    nb = f.model.analysis.n_base
    cov = psd(est.cov)  # rounding on an ill-conditioned fit can make the sandwich indefinite
    kappa = float("nan")
    if sel.prior_cov is not None and sel.theta0 is not None:
        d = np.linalg.solve(est.R11, est.r12)[:nb] - sel.theta0[:nb]
        kappa = prior_error_scale(d, cov[:nb, :nb], sel.prior_cov[:nb, :nb])
    rest = np.eye(len(m)) - m
    if np.isfinite(kappa):
        how = f"the file's error as the data show it: about {np.sqrt(kappa / sel.lam):.2g} x each body's scales"
    else:
        how = "the file's error as the prior states it: the data are too ill-conditioned to measure it"
    prior_cov = sel.prior_cov if sel.prior_cov is not None else np.zeros_like(cov)
    cov = psd(m @ cov @ m.T + (kappa if np.isfinite(kappa) else 1.0) * rest @ prior_cov @ rest.T)
    label = f"{est.covariance}, with the model file's prior (weight {sel.lam:g}; {how})"
    return replace(f, estimate=with_covariance(est, f.theta, cov, label), selection=replace(sel, kappa=kappa))


#: a term is poorly determined when its std exceeds this percentage of its value ...
POORLY_DETERMINED_PCT = 100.0
#: ... and collinearity with the other terms inflates its std more than this factor
POORLY_DETERMINED_INFLATION = 10.0


def poorly_determined(est, names: list[str]) -> list[str]:
    """The terms the data do not determine: std above their value, inflated by collinearity.

    A term's inflation is ``std_k ||A_k|| / (sqrt(n_obs) rho)`` (``A_k`` its weighted regressor
    column, ``rho`` the weighted residual RMS): about ``sqrt(VIF_k)``, 1 for a column orthogonal
    to the others. A term whose value is near zero but known to within the noise (inflation
    near 1) is determined, whatever its %sigma.

    Parameters
    ----------
    est : Estimate
        The estimate (``std``, ``pct_sigma``, ``R11``, ``weights``, ``rms``, ``samples``).
    names : list of str, shape ``(p,)``
        The terms' names.

    Returns
    -------
    list of str
        The poorly determined terms, in model order.
    """
    w = np.asarray(est.weights, dtype=float)
    rho = float(np.sqrt(np.sum((np.asarray(est.rms) * w) ** 2) / max(len(w), 1)))
    n_obs = max(int(est.samples) * len(w), 1)
    infl = np.asarray(est.std) * np.linalg.norm(est.R11, axis=0) / np.sqrt(n_obs) / max(rho, np.finfo(float).tiny)
    pct = np.asarray(est.pct_sigma, dtype=float)
    return [n for n, s, i in zip(names, pct, infl)
            if not s <= POORLY_DETERMINED_PCT and not i <= POORLY_DETERMINED_INFLATION]
#: a body's identified mass "moved far" from the model file's beyond this factor either way
MASS_FACTOR = 2.0


def _masses_moved(robot: Robot, masses: np.ndarray) -> dict:
    """Bodies whose physically consistent mass is beyond :data:`MASS_FACTOR` of the model file's."""
    prior = robot.N_body[:, 3, 3]
    out = {}
    for name, m0, m in zip(robot.names, prior, masses):
        if m0 > 0 and not (m0 / MASS_FACTOR <= m <= m0 * MASS_FACTOR):
            out[name] = {"file": float(m0), "identified": float(m)}
    return out


@dataclass(frozen=True, eq=False)
class Identification:
    """The result of :func:`identify`: values, statistics, validation, what was done to the data.

    Parameters
    ----------
    fit : Fit
        The identified values (and the model).
    samples : dict
        ``{"read": int, "used": int, "removed": {reason: count}}`` for the training data.
    train : dict
        ``{"rms": {joint: float}, "rms_total": float}`` on the training samples (filtered).
    validation : dict, optional
        The same on held-out data, or ``None``.
    notes : tuple of str
        Every decision taken on the data and the model, one line each.
    series : dict, optional
        ``{"train": {...}, "validation": {...} or None}``, each ``{"t" (S,), "tau" (S, m),
        "tau_hat" (S, m), "joints" (m,)}``: the filtered measured and predicted torques (plots);
        ``train`` also has ``"spectrum"``: the excitation spectrum of the training positions
        (:func:`position_spectrum`).
    options : dict, optional
        How the model was built and the data prepared, what :meth:`save` writes and
        :meth:`load` rebuilds the model from: ``{"method", "convention", "rows", "rotor",
        "friction" (tuple), "coulomb_width", "couplings" (tuple of MotorCoupling), "cutoff" [Hz],
        "decimate", "min_speed"}``.
    """

    fit: Fit
    samples: dict
    train: dict
    validation: dict | None
    notes: tuple[str, ...]
    series: dict | None = None
    options: dict | None = None

    def predict(self, log, smooth: bool = True) -> np.ndarray:
        """Predicted joint torques at every sample of a log (its own time stamps).

        ``smooth`` (default): the model's torques on the log's states low-passed with the
        identification's cutoff (zero-phase on the log's time base; rates it lacks derived from
        the filtered ``q``): the states the fit was computed from, without the measurement noise
        of the logged rates. The torques themselves are not filtered, so Coulomb friction keeps
        its steps. A function of the logged motion only (no torque enters). ``smooth=False``: the
        model's torques on the states as logged (rates it lacks derived as above).

        No sample is dropped: the first and last ``2 fs / cutoff`` samples carry the filter's
        edge transient (:func:`baseparams.ident.results.log_states`).

        Parameters
        ----------
        log : JointLog
            ``S`` samples of the model's measured joints (``tau`` may be ``None``), e.g.
            :func:`baseparams.io.logs.read_log` with ``require_tau=False``.
        smooth : bool
            Filtered states (default), or the states as logged.

        Returns
        -------
        ndarray, shape ``(S, m)``
            Predicted torques [N m or N]: columns the measured joints in the model's order
            (:attr:`joints`), rows the log's samples.

        Raises
        ------
        BaseparamsError
            A log missing a measured joint, too short or too slowly sampled for the cutoff.
        """
        from ..arguments import ArgumentTypeError, check_flags
        from .data import JointLog

        check_flags("predict", smooth=smooth)
        if not isinstance(log, JointLog):
            raise ArgumentTypeError(f"predict: log must be a JointLog (baseparams.io.logs.read_log(path, robot, "
                                    f"require_tau=False)), got {type(log).__name__}")
        return predict_log(self.fit, log.checked(), (self.options or {}).get("cutoff"), smooth)

    @property
    def joints(self) -> list[str]:
        """The measured joints ``(m,)``, the columns of :meth:`predict`."""
        r = self.model.robot
        return [r.joint_names[r.dof_body[c]] for c in self.model.coords]

    def compare_truth(self, truth: dict, source: str = "truth") -> dict:
        """Compare with the true parameters of a simulation (``OUT.truth.json``).

        Parameters
        ----------
        truth : dict
            :func:`~baseparams.ident.simulate.simulate_log`'s truth.
        source : str
            Its file, for messages.

        Returns
        -------
        dict
            Per term ``true, estimate, error, std, z`` (:func:`baseparams.ident.results.compare_truth`).
        """
        from .results import compare_truth

        return compare_truth(self.model.names, self.fit.theta, self.fit.estimate.std, truth, source)

    def document(self) -> dict:
        """The JSON object :meth:`save` writes (:mod:`baseparams.ident.results` describes it).

        Returns
        -------
        dict
            Format, version, the robot's name and fingerprint, the options, the model
            parameters' names, values and std, the readable tables, the estimate's statistics
            and triangular factor, the physical fit, counts and notes.
        """
        from dataclasses import fields

        from .. import __version__
        from .results import FORMAT, VERSION, numbers, robot_fingerprint

        r = self.model.robot
        opts = dict(self.options or {})
        opts["friction"] = list(opts.get("friction", ()))
        opts["couplings"] = [{"name": c.name, "joints": list(c.joints), "weights": list(c.weights)}
                             for c in opts.get("couplings", ())]
        est = self.fit.estimate
        phys = self.fit.physical
        body = self.to_json()
        doc = {"format": FORMAT, "version": VERSION, "baseparams": __version__,
               "robot": {"name": r.name, "fingerprint": robot_fingerprint(r), "bodies": r.n, "dof": r.dof,
                         "parameters": 10 * r.n, "joints": self.joints},
               "options": opts,
               "parameters": {"names": list(self.model.names), "values": numbers(self.fit.theta),
                              "std": numbers(est.std)},
               "base_parameters": body["base_parameters"], "drives": body["drives"], "couplings": body["couplings"],
               "estimate": {f.name: (numbers(getattr(est, f.name)) if isinstance(getattr(est, f.name), np.ndarray)
                                     else getattr(est, f.name)) for f in fields(est) if f.name != "pct_sigma"},
               "physical": None if phys is None else {
                   f.name: (numbers(getattr(phys, f.name)) if isinstance(getattr(phys, f.name), np.ndarray)
                            else list(getattr(phys, f.name)) if isinstance(getattr(phys, f.name), tuple)
                            else getattr(phys, f.name)) for f in fields(phys)},
               "samples": self.samples, "train": self.train, "validation": self.validation, "notes": list(self.notes)}
        return _plain(doc)

    def save(self, path, inputs=(), what: str = "output"):
        """Write the result to a JSON file (atomically; :func:`baseparams.files.write_text`).

        Parameters
        ----------
        path : str or path
            The file (``RESULT.json``).
        inputs : iterable of str or path
            The run's input files, which the output must not overwrite.
        what : str
            The output's role, for messages (``--save``).

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        BaseparamsError
            An output onto an input, a missing folder, a non-regular target.
        """
        import json

        from ..files import write_text

        return write_text(path, json.dumps(self.document(), indent=1, allow_nan=False) + "\n", inputs, what)

    @classmethod
    def load(cls, path, robot: Robot) -> Identification:
        """Read a saved result back, for the robot it was identified on.

        The model is rebuilt from the saved options (analysis, drive model and regrouping, as
        :func:`identify` built it) and its parameter names checked against the saved ones; the
        values, statistics, counts and notes are the saved ones (``series`` is not saved:
        ``None``).

        Parameters
        ----------
        path : str or path
            The file (:meth:`save`).
        robot : Robot
            The model: its structure's fingerprint must be the saved one.

        Returns
        -------
        Identification
            The result; :meth:`predict` gives the same torques as the saved object's.

        Raises
        ------
        BaseparamsError
            No such file, another format, another version, another robot (both fingerprints
            named), or a model whose rebuilt parameters differ from the saved ones.
        """
        from .drives import MotorCoupling
        from .estimate import Estimate
        from .physical import PhysicalFit
        from .results import array, check_robot, read_document

        doc = read_document(path)  # checked against baseparams.schema.RESULT: types, shapes, finite values
        check_robot(doc, robot, str(path))
        o = dict(doc["options"])
        o["friction"] = tuple(o.get("friction", ()))
        o["couplings"] = tuple(MotorCoupling(c["name"], tuple(c["joints"]), tuple(c["weights"]))
                               for c in o.get("couplings", ()))
        model = ident_model(analyze(robot, convention=o["convention"], rows=o.get("rows", "all")), o["rotor"],
                            o["friction"], o.get("coulomb_width"), couplings=o["couplings"])
        names = doc["parameters"]["names"]
        if list(model.names) != list(names):
            diff = next((f"{a} vs {b}" for a, b in zip(model.names, names) if a != b),
                        f"{len(model.names)} vs {len(names)} parameters")
            raise BaseparamsError(f"{path}: the model rebuilt for {robot.name!r} has other parameters than the "
                                  f"saved ones ({diff}); saved by another baseparams version?")
        theta = array(doc["parameters"]["values"])
        e = doc["estimate"]
        std = array(e["std"])
        with np.errstate(divide="ignore", invalid="ignore"):
            pct = 100 * std / np.abs(theta if e.get("cov") is not None else array(e["theta"]))
        extra = {k: e[k] for k in ("covariance",) if e.get(k) is not None}
        if e.get("cov") is not None:
            extra["cov"] = array(e["cov"])
        est = Estimate(e["method"], array(e["theta"]), std, pct, array(e["weights"]), array(e["rms"]),
                       float(e["rms_total"]), float(e["condition_number"]), int(e["samples"]), array(e["R11"]),
                       array(e["r12"]), **extra)
        phys = None
        if doc.get("physical") is not None:
            p = doc["physical"]
            phys = PhysicalFit(**{k: (array(v) if isinstance(v, list) and k != "notes" else
                                      tuple(v) if k == "notes" else v) for k, v in p.items()})
        f = Fit(model, o.get("method", e["method"]), theta, est, phys)
        return cls(f, doc["samples"], doc["train"], doc["validation"], (*doc["notes"], *doc["_notes"]), None, o)

    @property
    def model(self) -> IdentModel:
        """The identified model."""
        return self.fit.model

    def __repr__(self) -> str:
        m = self.model
        held = self.validation is not None
        rms = (self.validation if held else self.train)["rms_total"]
        return clip(f"<Identification {m.robot.name}: {self.fit.method}, {m.n_base} base + {m.n_drive} drive terms, "
                    f"{'held-out' if held else 'training'} RMS {format_number(rms, 3)} {m.torque_unit}>")

    @property
    def names(self) -> np.ndarray:
        """Names of every identified term ``(p,)``: base parameters, then drive terms.

        The order of :attr:`values`, :attr:`std`, :meth:`table` and :meth:`to_frame`; the names of
        :meth:`base_parameters` and (``<kind>_<joint>``) of :meth:`drives` and :meth:`couplings`.
        """
        return np.array(self.model.names, dtype=object)  # Python strings, as pandas holds them

    @property
    def values(self) -> np.ndarray:
        """The identified values ``(p,)`` in :attr:`names`' order (SI units, the analysis's convention)."""
        return np.array(self.fit.theta, dtype=float)

    @property
    def std(self) -> np.ndarray:
        """Standard deviations ``(p,)`` of :attr:`values` (the least-squares estimate's)."""
        return np.array(self.fit.estimate.std, dtype=float)

    def _columns(self) -> dict[str, list]:
        """Every identified term's name, kind, value, std, %sigma and expression, in :attr:`names`' order."""
        m = self.model
        nb = len(m.analysis.base_names)
        base = {b["name"]: b["expression"] for b in self.base_parameters()}
        exprs = m.regrouping.expressions()
        kinds = ["base" if i < nb else "drive" for i in m.regrouping.independent]
        names = list(m.names)
        return {"name": names, "kind": kinds, "value": self.values.tolist(), "std": self.std.tolist(),
                "pct_sigma": np.asarray(self.fit.estimate.pct_sigma, dtype=float).tolist(),
                "expression": [base[n] if k == "base" else e for n, k, e in zip(names, kinds, exprs)]}

    def table(self) -> str:
        """Every identified term as a text table.

        Returns
        -------
        str
            Columns ``name, kind, value, std, pct_sigma, expression``, one row per term in
            :attr:`names`' order (values at 6 significant digits, std and %sigma at 3).
        """
        return text_table(self._columns(), digits={"value": 6, "std": 3, "pct_sigma": 3})

    def to_frame(self):
        """Every identified term as a pandas DataFrame (pandas is optional).

        Returns
        -------
        pandas.DataFrame
            Columns ``name, kind`` (``base`` or ``drive``), ``value, std, pct_sigma,
            expression``; one row per term in :attr:`names`' order, values at full precision.

        Raises
        ------
        BaseparamsError
            pandas is not installed.
        """
        return data_frame(self._columns())

    def base_parameters(self) -> list[dict]:
        """The regrouped base parameters (drive terms regrouped into them included).

        Returns
        -------
        list of dict
            ``{"name", "expression", "value", "std", "pct_sigma"}`` per model parameter that is not
            a drive parameter; values in the analysis's convention (SI units).
        """
        m = self.model
        est = self.fit.estimate
        nb = len(m.analysis.base_names)
        exprs = dict(zip(m.analysis.base_names, (e["expression"] for e in m.analysis.expressions())))
        out = []
        for k, (i, extra) in enumerate(zip(m.regrouping.independent, m.regrouping.expressions())):
            if i >= nb:
                continue
            name = m.regrouping.names[i]
            tail = extra[len(name):]
            out.append({"name": name, "expression": exprs.get(name, name) + tail, "value": float(self.fit.theta[k]),
                        "std": float(est.std[k]), "pct_sigma": float(est.pct_sigma[k])})
        return out

    def drives(self) -> list[dict]:
        """Drive parameters per joint.

        Returns
        -------
        list of dict
            ``{"joint", "Ia", "Fv", "Fc", "Fo", "std"}``: a value, ``None`` when not modelled, or
            ``"regrouped into <base parameter>"`` when the data cannot separate it; ``std``: the
            standard deviation of each identified value (``{kind: float}``).
        """
        m = self.model
        return [self._terms({"joint": joint}, joint, ("Ia", "Fv", "Fc", "Fo"), m.drives.kinds)
                for joint in m.drives.joints]

    def couplings(self) -> list[dict]:
        """Coupled-motor parameters (:class:`~baseparams.ident.drives.MotorCoupling`).

        Returns
        -------
        list of dict
            ``{"name", "joints": {joint: weight}, "Iam", "Fvm", "Fcm", "std"}`` per coupling: a
            value, ``None`` when not modelled, or ``"regrouped into <parameter>"``; ``std``: the
            standard deviation of each identified value.
        """
        m = self.model
        return [self._terms({"name": c.name, "joints": dict(zip(c.joints, c.weights))}, c.name,
                            ("Iam", "Fvm", "Fcm"), m.drives.coupled_kinds) for c in m.drives.couplings]

    def _terms(self, entry: dict, owner: str, kinds, modelled) -> dict:
        """``entry`` with each drive term ``KIND_owner``: value and std, None or regrouped.

        ``None`` when the kind is not modelled, ``"regrouped into <base parameter>"`` when the
        data cannot separate it.
        """
        m = self.model
        pos = {name: k for k, name in enumerate(m.names)}
        absorbed = {m.regrouping.names[d]: m.regrouping.names[i]
                    for row, i in enumerate(m.regrouping.independent)
                    for col, d in enumerate(m.regrouping.dependent) if m.regrouping.K[row, col] != 0}
        entry["std"] = {}
        for kind in kinds:
            name = f"{kind}_{owner}"
            if kind not in modelled:
                entry[kind] = None
            elif name in pos:
                entry[kind] = float(self.fit.theta[pos[name]])
                entry["std"][kind] = float(self.fit.estimate.std[pos[name]])
            else:
                entry[kind] = f"regrouped into {absorbed.get(name, '?')}"
        return entry

    def to_json(self) -> dict:
        """One JSON-able object (schema in the README's identification section).

        Returns
        -------
        dict
            ``method, estimator, selection, covariance, model, convention, n_samples{read, used, removed},
            condition_number,
            excitation{condition_number, weak, poorly_determined, all_excited}, base_parameters,
            drives, couplings,
            train, validation, physical, notes``; ``weak`` names the parameters carrying
            directions whose singular value is below 1e-3 of the largest (column-scaled regressor);
            ``covariance`` says how every ``std`` was computed.
        """
        f = self.fit
        phys = None
        if f.physical is not None:
            p = f.physical
            phys = {"feasible": bool(p.feasible), "min_eigenvalue": float(np.min(p.min_eigenvalues)),
                    "masses": {b: float(v) for b, v in zip(self.model.robot.names, p.masses)},
                    "solver_status": str(p.solver_status)}
        from .estimate import excitation

        cond, weak = excitation(f.estimate.R11, self.model.names)
        loose = poorly_determined(f.estimate, self.model.names)
        if phys is not None:
            phys["masses_moved"] = _masses_moved(self.model.robot, f.physical.masses)
        sel = f.selection
        estimator = f.method if sel is None else (f"{f.method}: {sel.weighting.upper()}" + (
            f" with the model file's prior, weight {sel.lam:g}" if sel.lam else ""))
        return {"method": f.method, "estimator": estimator, "selection": None if sel is None else sel.to_json(),
                "covariance": f.estimate.covariance,
                "model": self.model.robot.name, "convention": self.model.analysis.convention,
                "n_samples": self.samples, "condition_number": float(f.estimate.condition_number),
                "excitation": {"condition_number": cond, "weak": weak, "poorly_determined": loose,
                               "all_excited": not weak and not loose},
                "base_parameters": self.base_parameters(), "drives": self.drives(),
                "couplings": self.couplings(), "train": self.train,
                "validation": self.validation, "physical": phys, "notes": list(self.notes)}


def identify(robot: Robot, log, *, method: str = "auto", rotor: bool = False,
             friction=("viscous", "coulomb", "offset"), coulomb_width: float | None = None,
             holdout: float | None = None, validation=None, cutoff: float | None = None,
             decimate: int | None = None, min_speed=None, prior_weight: float | None = None,
             convention: str = "khalil", memory_mb: float = 128.0, couplings=(), progress=None,
             samples: int | None = None, score_cutoff: float | None = None, covariance: str = "hac",
             allow_units: bool = False) -> Identification:
    """Identify base-parameter and drive values from a joint log.

    Parameters
    ----------
    robot : Robot
        The model (fixed base, or loops closed by the actuated joints).
    log : JointLog
        The log (:func:`baseparams.io.logs.read_log`): positions and torques of the measured
        joints (every joint of a tree; the actuated joints of a robot with loops).
    method : {"auto", "ols", "wls", "physical"}
        The estimator (:func:`fit`).
    rotor : bool
        Model each joint's rotor inertia ``Ia``.
    friction : iterable of str
        Friction terms: ``viscous``, ``coulomb``, ``offset`` (empty: none).
    coulomb_width : float, optional
        Smooth Coulomb friction's velocity scale [rad/s].
    holdout : float, optional
        Hold out the samples with ``t >= t_end - holdout`` for validation (training: the
        samples before).
    validation : JointLog, optional
        Another log to validate on (exclusive with ``holdout``). Validation predicts every
        held-out sample (:meth:`Identification.predict`) and compares with the raw measured
        torques (:func:`validation_scores`).
    cutoff : float, optional
        Low-pass cutoff [Hz] (default :func:`baseparams.ident.preprocess.lowpass_design`'s).
    decimate : int, optional
        Decimation factor (default from the rate and the cutoff).
    min_speed : float, optional
        Remove samples where a joint moves slower than this [rad/s] (Coulomb friction).
    prior_weight : float, optional
        ``physical`` only: the weight of the model file's inertias.
    convention : str
        Convention of the base parameters' names and values.
    memory_mb : float
        Largest regressor formed at once for the parallel filter (the filter's copies make the
        peak about 4x this); longer logs are processed in chunks with overlapping filter edges,
        which gives the same estimate to rounding (:mod:`baseparams.ident.chunks`).
    couplings : iterable of MotorCoupling
        Motors driving several joints (:class:`~baseparams.ident.drives.MotorCoupling`, e.g. a
        coupled wrist): their rotor inertia and viscous and Coulomb friction ``Iam``, ``Fvm``,
        ``Fcm`` (those whose per-joint kind is modelled).
    score_cutoff : float, optional
        Also score the validation against the measured torques low-passed at this cutoff [Hz]
        (zero-phase Butterworth, order 4), labelled with it.
    progress : callable, optional
        Called with one line of text at each step (analysis, preprocessing, accumulation, fit,
        validation, report series).
    samples : int, optional
        Random states of the base-parameter analysis the model is built on (default: the
        analysis's own).
    covariance : {"hac", "white"}
        The standard deviations' covariance: ``hac`` (default) Newey-West, true under correlated
        residuals; ``white`` the least-squares formula (:mod:`baseparams.ident.uncertainty`).
    allow_units : bool
        Go on when the units look wrong (:mod:`baseparams.ident.plausibility`: velocities,
        time base, torques against the model file's, absurd samples), which otherwise refuses.

    Returns
    -------
    Identification
        Values, standard deviations, residuals, validation, counts and notes.

    Raises
    ------
    BaseparamsError
        A floating base, a log that misses a measured joint, ``holdout`` with ``validation``, bad
        data (:class:`~baseparams.errors.DataError`), a bad coupling or data that do not excite
        the model.
    """
    if robot.floating:
        raise BaseparamsError(f"robot {robot.name!r}: identification from a joint log needs a fixed base (a floating "
                              f"base's motion and wrench are not in a joint log); use the Python API with states")
    if holdout is not None and validation is not None:
        raise BaseparamsError("give either holdout seconds or a validation log, not both")
    log, validation = log.checked(), None if validation is None else validation.checked()  # finite, increasing
    with blas_threads():
        return _identify(robot, log, method, rotor, friction, coulomb_width, holdout, validation, cutoff, decimate,
                         min_speed, prior_weight, convention, memory_mb, tuple(couplings), progress, samples,
                         score_cutoff, covariance, allow_units)


def _identify(robot, log, method, rotor, friction, coulomb_width, holdout, validation, cutoff, decimate, min_speed,
              prior_weight, convention, memory_mb, couplings=(), progress=None, samples=None,
              score_cutoff=None, covariance="hac", allow_units=False) -> Identification:
    """:func:`identify`'s steps (arguments as there)."""
    from .preprocess import prepare

    say = progress or (lambda msg: None)
    train, held = (split_log(log, holdout) if holdout is not None else (log, validation))
    say(f"analysing {robot.name} (base parameters, drive model)")
    model = ident_model(analyze(robot, samples=samples, convention=convention), rotor, tuple(friction), coulomb_width,
                        couplings=couplings)
    cols = log_columns(model, log)
    unit_notes = check_log_units(model, train, cols, allow_units)
    say(f"preprocessing {train.n_samples} training samples (resampling, low-pass, derivatives)")
    prep = _prepare_training(train, holdout, cutoff=cutoff, decimate=decimate, min_speed=min_speed)
    say(f"accumulating the regressor of {prep.n_samples} samples ({model.n_params} parameters)")
    parts: list = []
    kept: list = []
    acc, acc_note = accumulate_prepared(model, prep, cols, memory_mb, train, min_speed, parts_out=parts,
                                        keep=kept)
    say(f"fitting ({method})")
    f = fit(model, acc, method, prior_weight, blocks=parts)
    f, cov_note = _uncertainty(f, acc, covariance, kept, model, prep, cols, memory_mb, train, min_speed, say)
    f = pulled_covariance(f)
    say("predicted torques and excitation spectrum for the report")
    names = [model.robot.joint_names[model.robot.dof_body[c]] for c in model.coords]
    res = np.array([np.linalg.norm(fr.r @ np.r_[f.theta, -1.0]) for fr in acc.factors]) / np.sqrt(acc.samples)
    train_rms = {"rms": dict(zip(names, res.tolist())), "rms_total": float(np.sqrt(np.mean(res**2)))}
    val, series = None, {"train": report_series(model, prep, cols, f.theta, names, memory_mb), "validation": None}
    series["train"]["spectrum"] = position_spectrum(train, cols, prep.design.fs, prep.design.cutoff, prep.full.t)
    if held is not None:
        say(f"validating on {held.n_samples} held-out samples (every one, against the raw measured torques)")
        whole, mask = (log, log.t >= log.t[-1] - holdout) if holdout is not None else (held, None)
        pred = predict_log(f, whole, float(prep.design.cutoff))
        val = validation_scores(whole, pred, names, mask, score_cutoff)
        vprep = prepare(held, cutoff=prep.design.cutoff, decimate=prep.factor)
        series["validation"] = report_series(model, vprep, log_columns(model, held), f.theta, names, memory_mb)
    samples = {"read": int(train.n_samples), "used": int(acc.samples), "removed": dict(prep.removed)}
    notes = (*prep.notes, acc_note, *model_notes(model), *(f.physical.notes if f.physical is not None else ()),
             *((f.selection.note(),) if f.selection is not None else ()), cov_note, *unit_notes)
    options = {"method": method, "convention": convention, "rows": str(model.analysis.rows), "rotor": bool(rotor),
               "friction": tuple(friction), "coulomb_width": coulomb_width, "couplings": tuple(couplings),
               "cutoff": float(prep.design.cutoff), "decimate": int(prep.factor), "min_speed": min_speed}
    return Identification(f, samples, train_rms, val, tuple(notes), series, options)


def _prepare_training(train, holdout, **kw):
    """:func:`~baseparams.ident.preprocess.prepare` of the training part; a too short one names ``--holdout``."""
    from ..errors import DataError
    from .preprocess import prepare

    try:
        return prepare(train, **kw)
    except DataError as exc:
        if holdout is None:
            raise
        span = float(train.t[-1] - train.t[0]) if train.n_samples else 0.0
        raise DataError(f"{exc}; --holdout {holdout:g} s leaves {span:.3g} s to train on "
                        "(a shorter --holdout)") from None


def check_log_units(model: IdentModel, log, cols, allow_units: bool) -> list[str]:
    """Units and plausibility of the log before any fit (:func:`~baseparams.ident.plausibility.check_units`).

    Parameters
    ----------
    model : IdentModel
        The model (its robot's own torques are the comparison).
    log : JointLog
        The (training) log.
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.
    allow_units : bool
        Go on with a warning note instead of refusing.

    Returns
    -------
    list of str
        Notes for the report.

    Raises
    ------
    DataError
        Units that look wrong, unless ``allow_units``.
    """
    from ..analysis import regressor
    from ..errors import DataError
    from .plausibility import check_units

    robot = model.robot
    params = robot.parameters("paper")
    coords = np.asarray(robot.actuated, dtype=int) if robot.has_loops else np.arange(robot.dof)
    revolute = np.array([robot.jtype[robot.dof_body[c]] == "R" for c in coords])
    try:
        limits = None if robot.limits is None else np.asarray(robot.limits, dtype=float)[coords]
        return check_units(log, cols, lambda q, dq, ddq: regressor(robot, q, dq, ddq) @ params, revolute, limits)
    except DataError as exc:
        if not allow_units:
            raise
        return [f"units: WARNING, going on (allow_units): {exc}"]


def _uncertainty(f: Fit, acc, covariance, kept, model, prep, cols, memory_mb, train, min_speed, say):
    """The fit's standard deviations from the chosen covariance (a second pass for HAC)."""
    from .uncertainty import apply_covariance, fitted_rows

    if covariance == "hac":
        say("covariance (HAC: a second pass over the fitted rows)")
    rows = kept if kept else (lambda: fitted_rows(model, prep, cols, memory_mb, train, min_speed))
    return apply_covariance(f, acc, rows, covariance, prep.design.fs / prep.factor)


def report_series(model: IdentModel, prep, cols: np.ndarray, theta: np.ndarray, names: list[str], memory_mb: float):
    """Measured and predicted torques of a prepared log, as they were compared (filtered).

    Parameters
    ----------
    model : IdentModel
        The model.
    prep : Prepared
        The prepared log.
    cols : ndarray of int, shape ``(state_columns,)``
        Log column of each state column.
    theta : ndarray, shape ``(p,)``
        The identified values.
    names : list of str, shape ``(m,)``
        The measured joints.
    memory_mb : float
        Largest regressor formed at once (beyond, the predicted torques are not parallel-filtered).

    Returns
    -------
    dict
        ``{"t" (S',), "tau" (S', m), "tau_hat" (S', m), "joints" (m,)}`` at the kept samples.
    """
    full = prep.full
    q, dq, ddq = full.q[:, cols], full.dq[:, cols], full.ddq[:, cols]
    size_mb = full.n_samples * len(model.coords) * model.n_params * 8 / 1e6
    if size_mb <= memory_mb:
        tau_hat = prep.apply(model.regressor(q, dq, ddq)) @ theta
    else:
        idx = prep.index
        tau_hat = np.concatenate([model.regressor(q[idx[k:k + 20000]], dq[idx[k:k + 20000]],
                                                  ddq[idx[k:k + 20000]]) @ theta for k in range(0, len(idx), 20000)])
    return {"t": prep.t, "tau": prep.tau[:, cols], "tau_hat": tau_hat, "joints": names}


def position_spectrum(log, cols, fs: float, cutoff: float | None = None, t=None, bands: int = 300,
                      segment: int = 2**16, max_segments: int = 64) -> dict:
    """The amplitude spectrum of a log's positions per joint (the excitation spectrum).

    The raw (unfiltered) positions on a uniform grid, split into Hann-windowed segments of at most
    ``segment`` samples (half overlapping, at most ``max_segments`` spread over the log), their
    power averaged; then, for plotting on a log axis, the largest amplitude in each of ``bands``
    log-spaced frequency bands.

    Parameters
    ----------
    log : JointLog
        The log (``t (S,)``, ``q (S, joints)``).
    cols : array_like of int, shape ``(m,)``
        The log columns to analyse.
    fs : float
        The uniform grid's rate [Hz].
    cutoff : float, optional
        The low-pass cutoff [Hz] used on the log (recorded, for the plot).
    t : ndarray, optional
        The uniform grid (default: ``log.t``, taken as uniform); positions are interpolated on it.
    bands : int
        Log-spaced frequency bands of the result.
    segment : int
        Longest segment [samples]: the frequency resolution is ``fs / segment``.
    max_segments : int
        Most segments averaged (a very long log is sampled, not read whole).

    Returns
    -------
    dict
        ``{"f": ndarray (F,) [Hz], "amplitude": ndarray (F, m) [rad or m], "cutoff": float or None,
        "fs": float, "of": "q"}``: ``F <= bands`` band frequencies (mean of each band's bins) and
        the largest single-sided amplitude in the band (a sinusoid of amplitude ``A`` reads ``A``).
    """
    cols = np.asarray(cols, dtype=int)
    t = log.t if t is None else np.asarray(t, dtype=float)
    seg = int(min(len(t), segment))
    w = np.hanning(seg)
    starts = np.unique(np.linspace(0, len(t) - seg, min(max_segments, (len(t) - seg) // max(seg // 2, 1) + 1))
                       .astype(int))
    power = np.zeros((seg // 2 + 1, len(cols)))
    for k in starts:
        x = np.column_stack([np.interp(t[k:k + seg], log.t, log.q[:, c]) for c in cols])
        power += np.abs(np.fft.rfft((x - x.mean(axis=0)) * w[:, None], axis=0)) ** 2
    amp = (2 * np.sqrt(power / len(starts)) / w.sum())[1:]
    f = np.fft.rfftfreq(seg, 1.0 / fs)[1:]
    band = np.floor(np.log(f / f[0]) / np.log(max(f[-1] / f[0], 1.0 + 1e-12)) * bands).clip(0, bands - 1)
    first = np.flatnonzero(np.r_[True, np.diff(band) > 0])
    return {"f": np.add.reduceat(f, first) / np.diff(np.r_[first, len(f)]),
            "amplitude": np.maximum.reduceat(amp, first, axis=0), "cutoff": cutoff, "fs": float(fs), "of": "q"}


def split_log(log, seconds: float):
    """The log split into training and the last ``seconds`` held out.

    Parameters
    ----------
    log : JointLog
        The log.
    seconds : float
        Length of the held-out tail [s].

    Returns
    -------
    train, held : JointLog
        The two parts (each filtered on its own later: no information crosses the split).

    Raises
    ------
    BaseparamsError
        ``seconds`` not inside the log's duration.
    """
    from dataclasses import replace

    t = log.t
    if not 0 < seconds < t[-1] - t[0]:
        raise BaseparamsError(f"{log.source}: holdout {seconds} s must be inside the log's {t[-1] - t[0]:.6g} s")
    cut = int(np.searchsorted(t, t[-1] - seconds))

    def part(sl):
        rates = {k: None if getattr(log, k) is None else getattr(log, k)[sl] for k in ("dq", "ddq")}
        return replace(log, t=t[sl], q=log.q[sl], tau=log.tau[sl], **rates)

    return part(slice(0, cut)), replace(part(slice(cut, None)), source=f"{log.source} (last {seconds:g} s)")


def log_columns(model: IdentModel, log) -> np.ndarray:
    """The log column of each state column of the model.

    Parameters
    ----------
    model : IdentModel
        The model (its states: a tree's coordinates, or a loop robot's actuated ones).
    log : JointLog
        The log.

    Returns
    -------
    ndarray of int, shape ``(state_columns,)``
        Index into ``log.joints`` per state column.

    Raises
    ------
    BaseparamsError
        A state coordinate whose joint is not in the log (naming the joints).
    """
    r = model.robot
    coords = np.asarray(r.actuated, dtype=int) if r.has_loops else np.arange(r.dof)
    wanted = [r.joint_names[r.dof_body[c]] for c in coords]
    where = {j: k for k, j in enumerate(log.joints)}
    missing = [j for j in wanted if j not in where]
    if missing:
        what = "actuated joints" if r.has_loops else "joints"
        raise BaseparamsError(f"{log.source}: the log has no column for the {what} {missing} of {r.name!r}")
    return np.array([where[j] for j in wanted], dtype=int)


def accumulate_prepared(model: IdentModel, prep, cols: np.ndarray, memory_mb: float, log=None, min_speed=None,
                        parts_out: list | None = None, keep=None):
    """Rows accumulated from a prepared log, with parallel filtering.

    All at once when the regressor fits in ``memory_mb``, else chunk by chunk with overlaps
    (:mod:`baseparams.ident.chunks`), which gives the same factors to rounding.

    Parameters
    ----------
    model : IdentModel
        The model.
    prep : Prepared
        The log prepared (:func:`baseparams.ident.preprocess.prepare`).
    cols : ndarray of int
        Log column of each state column (:func:`log_columns`).
    memory_mb : float
        Largest regressor formed at once.
    log : JointLog, optional
        The unfiltered log ``prep`` came from (needed for the chunked path).
    min_speed : float, optional
        The slow-sample threshold ``prep`` used.
    parts_out : list, optional
        When given, receives time-ordered pieces of the rows (RowAccumulator each; their
        combination is ``acc``), for the blocked cross-validation of the default estimate.
    keep : list, optional
        When given, ``(A, tau)`` of the fitted samples are appended to it, in time order, when
        they fit in ``memory_mb`` (always on the at-once path; per chunk on the chunked path): the
        covariance's second pass (:mod:`baseparams.ident.uncertainty`) then needs no second
        regressor.

    Returns
    -------
    acc : RowAccumulator
        The row factors.
    note : str
        How the parallel filtering was done.
    """
    from .estimate import RowAccumulator

    full = prep.full
    size_mb = full.n_samples * len(model.coords) * model.n_params * 8 / 1e6
    if size_mb <= memory_mb or log is None:
        q, dq, ddq = full.q[:, cols], full.dq[:, cols], full.ddq[:, cols]
        a, tau = prep.apply(model.regressor(q, dq, ddq)), prep.tau[:, cols]
        if parts_out is None:
            acc = RowAccumulator(len(model.coords), model.n_params).add(a, tau)
        else:
            from . import chunks
            from .select import fold_parts

            parts_out.extend(fold_parts(a, tau))
            acc = chunks.combine(parts_out)
        if keep is not None:
            keep.append((a, tau))
        return acc, (f"parallel filtering: the regressor's {model.n_params} columns filtered like the torques "
                     f"({size_mb:.0f} MB at once)")
    from . import chunks
    from .preprocess import resample

    grid = chunks.Grid(full.n_samples, prep.design.pad, prep.factor, prep.design.cutoff, min_speed)
    margin = chunks.overlap(prep.design)
    per_sample_mb = len(model.coords) * model.n_params * 8 * 4 / 1e6  # the filter's copies: ~4x
    size = max(4 * margin, int(memory_mb / per_sample_mb) - 2 * margin)
    uniform = resample(log)  # the grid prepare() filtered on (it resamples with the same default)
    # the fitted (decimated) rows are kept for the covariance's second pass when they fit in memory_mb
    # (a fraction 1 / factor of the full-rate regressor); else that pass recomputes them
    fitted_mb = full.n_samples / max(prep.factor, 1) * len(model.coords) * (model.n_params + 1) * 8 / 1e6
    held = keep if keep is not None and fitted_mb <= memory_mb else None
    parts = [chunks.chunk_factors(uniform, c, grid, model.regressor, cols, model.n_params, held)[0]
             for c in chunks.plan(full.n_samples, size, margin)]
    if parts_out is not None and held:
        # the cross-validation's blocks from the fitted rows, split as the at-once path splits them
        from .select import fold_parts

        parts_out.extend(fold_parts(np.concatenate([x for x, _ in held]), np.concatenate([y for _, y in held])))
    elif parts_out is not None:
        parts_out.extend(parts)  # blocks at chunk boundaries (the fitted rows do not fit in memory_mb)
    return chunks.combine(parts), (f"parallel filtering in {len(parts)} chunks of {size} samples with "
                                   f"{margin}-sample overlaps (equal to the whole log's to rounding)")


def _plain(x):
    """Numpy scalars and tuples as JSON types; non-finite floats as ``None``."""
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    return x


def model_notes(model: IdentModel) -> list[str]:
    """One line per drive parameter regrouped into a base parameter.

    Parameters
    ----------
    model : IdentModel
        The model.

    Returns
    -------
    list of str
        ``regrouped: <expression>`` lines.
    """
    return [f"regrouped: {e}" for e in model.regrouping.expressions() if " + " in e or " - " in e]


def predict_log(f: Fit, log, cutoff: float | None, smooth: bool = True) -> np.ndarray:
    """Predicted torques ``(S, m)`` at every sample of ``log`` (:meth:`Identification.predict`).

    Parameters
    ----------
    f : Fit
        The identified values.
    log : JointLog
        ``S`` samples of the measured joints.
    cutoff : float or None
        The identification's low-pass cutoff [Hz] (None: the log's default).
    smooth : bool
        Filtered states (default), or the states as logged.

    Returns
    -------
    ndarray, shape ``(S, m)``
        Columns the measured joints in the model's order.
    """
    from .results import log_states

    cols = log_columns(f.model, log)
    q, dq, ddq, _ = log_states(log, cutoff, smooth)
    q, dq, ddq = q[:, cols], dq[:, cols], ddq[:, cols]
    with blas_threads():
        tau = np.concatenate([f.predict(q[k:k + 20000], dq[k:k + 20000], ddq[k:k + 20000])
                              for k in range(0, max(len(q), 1), 20000)])
    if not np.isfinite(tau).all():  # values or states beyond floating point: never NaN predictions
        from ..errors import DataError

        i = int(np.argmax(~np.isfinite(tau).all(axis=1)))
        raise DataError(f"{log.source}: the predicted torques are not finite from sample {i} on (t = {log.t[i]:.6g} "
                        f"s): the log's states or the values are beyond floating point")
    return tau


def validation_scores(log, pred: np.ndarray, names: list[str], mask=None, score_cutoff: float | None = None) -> dict:
    """Held-out error the way an outsider measures it: against the raw measured torques.

    Parameters
    ----------
    log : JointLog
        The log whose samples were predicted (``S`` samples, measured torques ``tau``).
    pred : ndarray, shape ``(S, m)``
        Predicted torques of the measured joints ``names`` (:func:`predict_log`).
    names : list of str, shape ``(m,)``
        The measured joints, in ``pred``'s column order.
    mask : ndarray of bool, shape ``(S,)``, optional
        The held-out samples (default: all).
    score_cutoff : float, optional
        Also score against the measured torques low-passed at this cutoff [Hz] (zero-phase
        Butterworth order 4 on the held-out samples).

    Returns
    -------
    dict
        ``rms`` (per joint), ``rms_total`` (over every held-out sample and joint), ``samples``,
        ``t_start``, ``t_end``, ``source``, ``measure``; with ``score_cutoff`` also
        ``score_cutoff``, ``rms_lowpassed`` and ``rms_lowpassed_total``.
    """
    from .results import lowpass_at

    mask = np.ones(log.n_samples, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    where = {j: k for k, j in enumerate(log.joints)}
    measured = log.tau[:, [where[j] for j in names]][mask]
    err = pred[mask] - measured
    out = {"rms": dict(zip(names, np.sqrt(np.mean(err**2, axis=0)).tolist())),
           "rms_total": float(np.sqrt(np.mean(err**2))), "samples": int(mask.sum()),
           "t_start": float(log.t[mask][0]), "t_end": float(log.t[mask][-1]), "source": log.source,
           "measure": "RMS of predicted minus raw measured torques at every held-out sample"}
    if score_cutoff is not None:
        try:
            lp = lowpass_at(log.t[mask], measured, float(score_cutoff))
        except BaseparamsError as exc:
            raise BaseparamsError(f"--score-cutoff {score_cutoff:g} Hz on {log.source}'s held-out samples: "
                                  f"{exc}") from None
        e2 = pred[mask] - lp
        out.update({"score_cutoff": float(score_cutoff),
                    "rms_lowpassed": dict(zip(names, np.sqrt(np.mean(e2**2, axis=0)).tolist())),
                    "rms_lowpassed_total": float(np.sqrt(np.mean(e2**2)))})
    return out
