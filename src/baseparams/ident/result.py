"""The result of an identification as a value object, and its views (tables, per-joint drives, JSON).

:class:`Identification` holds the fit, what was done to the data, the validation, the notes and the
options it was made with; it predicts a log's torques (:meth:`Identification.predict`), and says its
values as a table, a DataFrame, base parameters, drive and coupled-motor terms, or one JSON object.
Its file (:meth:`Identification.save`, :meth:`Identification.load`) is :mod:`baseparams.ident.saved`'s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..display import clip, data_frame, format_number, text_table
from ..errors import BaseparamsError
from ..model.robot import Robot
from .fitting import POORLY_DETERMINED_PCT, Fit, poorly_determined
from .model import IdentModel
from .options import IdentOptions
from .validation import predict_log

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
    """The result of :func:`~baseparams.ident.identify`: values, statistics, validation, what was done to the data.

    Parameters
    ----------
    fit : Fit
        The identified values (and the model).
    samples : dict
        ``{"read": int, "used": int, "removed": {reason: count}}`` for the training data.
    train : dict
        ``{"rms": {joint: float}, "rms_total": float, "samples", "t_start", "t_end", "source",
        "measure"}``: predicted minus raw measured torques at every training sample (the
        validation's measure); ``fit_rms``, ``fit_rms_total``: the same on the fit's own rows
        (filtered and decimated as fitted), when computed.
    validation : dict, optional
        The same on held-out data, or ``None``.
    notes : tuple of str
        Every decision taken on the data and the model, one line each.
    series : dict, optional
        ``{"train": {...}, "validation": {...} or None}``, each ``{"t" (S,), "tau" (S, m),
        "tau_hat" (S, m), "joints" (m,)}``: the filtered measured and predicted torques (plots);
        ``train`` also has ``"spectrum"``: the excitation spectrum of the training positions
        (:func:`~baseparams.ident.validation.position_spectrum`).
    options : IdentOptions, optional
        The options it was made with (:class:`~baseparams.ident.options.IdentOptions`), the
        ``cutoff`` [Hz] and ``decimate`` those used: how the model was built and the data
        prepared, what :meth:`save` writes, :meth:`load` rebuilds the model from and
        :meth:`predict` filters a log with.
    motion : dict, optional
        ``{"condition_number", "samples"}``: the condition number of the training motion's model
        regressor at the log's (filtered) states, unweighted, every sample, column-scaled: the
        measure ``excite`` reports for a design (:func:`baseparams.ident.estimate.motion_factor`);
        None when not computed (a streamed log).
    truth : dict, optional
        The comparison with a simulation's true parameters (:meth:`compare_truth`), when
        :func:`baseparams.identify` was given ``truth``; in :meth:`to_json` as ``truth``.
    currents : CurrentGains, optional
        Identified from motor currents (:mod:`baseparams.ident.fromcurrents`): the motors' gains,
        the anchor and what currents cannot separate; :meth:`predict` then gives the joint-side
        torques and :meth:`predict_currents` the currents. ``None`` for torques.
    """

    fit: Fit
    samples: dict
    train: dict
    validation: dict | None
    notes: tuple[str, ...]
    series: dict | None = None
    options: IdentOptions | None = None
    motion: dict | None = None
    truth: dict | None = None
    currents: object = None

    def predict(self, log, smooth: bool = True, columns=None) -> np.ndarray:
        """Predicted joint torques at every sample of a log (its own time stamps).

        ``smooth`` (default): the model's torques on the log's states low-passed with the
        identification's cutoff (zero-phase on the log's time base; rates it lacks derived from
        the filtered ``q``): the states the fit was computed from, without the measurement noise
        of the logged rates. The torques themselves are not filtered, so Coulomb friction keeps
        its steps. A function of the logged motion only (no torque enters). ``smooth=False``: the
        model's torques on the states as logged (rates it lacks derived as above).

        No sample is dropped: the first and last ``2 fs / cutoff`` samples carry the filter's
        edge transient (:func:`baseparams.ident.preprocess.log_states`).

        Parameters
        ----------
        log : JointLog, str or path
            ``S`` samples of the model's measured joints (``tau`` may be ``None``), or a log or
            trajectory file (read for this robot by :func:`baseparams.io.logs.read_log`, ``tau``
            columns optional).
        smooth : bool
            Filtered states (default), or the states as logged.
        columns : str, path or dict, optional
            A layout mapping for a log file (docs/guides/log-layout.md).

        Returns
        -------
        ndarray, shape ``(S, m)``
            Predicted torques [N m or N]: columns the measured joints in the model's order
            (:attr:`joints`), rows the log's samples. Identified from currents: the joint-side
            torques a joint-torque sensor after the gear reads (no motor-side friction or rotor
            inertia, :class:`~baseparams.ident.fromcurrents.CurrentGains`).

        Raises
        ------
        BaseparamsError
            A log missing a measured joint, too short or too slowly sampled for the cutoff.
        """
        f = self.fit
        if self.currents is not None:
            from .gains import joint_side_fit

            f = joint_side_fit(f, self.currents)
        return predict_log(f, self._log_of(log, columns, smooth), self._cutoff, smooth)

    def predict_currents(self, log, smooth: bool = True, columns=None) -> np.ndarray:
        """Predicted motor currents at every sample of a log (a result identified from currents).

        Parameters
        ----------
        log : JointLog, str or path
            As :meth:`predict`.
        smooth : bool
            As :meth:`predict`.
        columns : str, path or dict, optional
            As :meth:`predict`.

        Returns
        -------
        ndarray, shape ``(S, m)``
            Currents [A], columns the motors (named after the measured joints), with every
            drive term (rotor inertia, friction) at the identified gains.

        Raises
        ------
        BaseparamsError
            A result identified from torques (no gains), or as :meth:`predict`.
        """
        if self.currents is None:
            raise BaseparamsError("predict_currents: this result was identified from torques; it has no motor gains")
        tau = predict_log(self.fit, self._log_of(log, columns, smooth), self._cutoff, smooth)
        return self.currents.currents(tau)

    @property
    def _cutoff(self) -> float | None:
        return None if self.options is None else self.options.cutoff

    def _log_of(self, log, columns, smooth):
        """A log to predict: a JointLog, or a file read for this robot; checked."""
        import os

        from ..arguments import ArgumentTypeError, check_flags
        from ..jointlog import JointLog

        check_flags("predict", smooth=smooth)
        if columns is not None and not isinstance(columns, (str, os.PathLike, dict)):
            raise ArgumentTypeError(f"predict: columns= must be a TOML file, a dict or a topic, got "
                                    f"{type(columns).__name__}")
        if columns is not None and not isinstance(log, (str, os.PathLike)):
            raise BaseparamsError("predict: columns= maps the columns of a log file; log is a JointLog already")
        if isinstance(log, (str, os.PathLike)):
            from ..io.logs import read_log

            log = read_log(log, self.model.robot, columns=columns, allow_subset=True, require_tau=False)
        elif not isinstance(log, JointLog):
            raise ArgumentTypeError(f"predict: log must be a log file's path or a JointLog, got {type(log).__name__}")
        return log.checked()

    @property
    def joints(self) -> list[str]:
        """The measured joints ``(m,)``, the columns of :meth:`predict`."""
        return self.model.joints

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
            Per term ``true, estimate, error, std, z`` (:func:`baseparams.ident.saved.compare_truth`).
        """
        from .saved import compare_truth

        return compare_truth(self.model.names, self.fit.theta, self.fit.estimate.std, truth, source)

    def document(self) -> dict:
        """The JSON object :meth:`save` writes (:func:`baseparams.ident.saved.document`).

        Returns
        -------
        dict
            Format, version, the robot's name and fingerprint, the options, the model
            parameters' names, values and std, the readable tables, the estimate's statistics
            and triangular factor, the physical fit, counts and notes.
        """
        from .saved import document

        return document(self)

    def save(self, path, inputs=(), what: str = "output"):
        """Write the result to a JSON file (atomically; :func:`baseparams.ident.saved.save`).

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
        from .saved import save

        return save(self, path, inputs, what)

    @classmethod
    def load(cls, path, robot: Robot) -> Identification:
        """Read a saved result back, for the robot it was identified on (:func:`baseparams.ident.saved.read`).

        The model is rebuilt from the saved options (analysis, drive model and regrouping, as
        :func:`~baseparams.ident.identify` built it) and its parameter names checked against the
        saved ones; the values, statistics, counts and notes are the saved ones (``series`` is not
        saved: ``None``).

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
        from .saved import read

        return cls(**read(path, robot))

    @property
    def model(self) -> IdentModel:
        """The identified model."""
        return self.fit.model

    def __repr__(self) -> str:
        m = self.model
        held = self.validation is not None
        rms = (self.validation if held else self.train)["rms_total"]
        unit = m.torque_unit if self.currents is None else "A (currents)"
        return clip(f"<Identification {m.robot.name}: {self.fit.method}, {m.n_base} base + {m.n_drive} drive terms, "
                    f"{'held-out' if held else 'training'} RMS {format_number(rms, 3)} {unit}>")

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
        """One JSON-able object (schema: docs/guides/identification.md, "JSON output").

        Returns
        -------
        dict
            ``method, estimator, selection, covariance, model, convention, n_samples{read, used, removed},
            condition_number,
            excitation{condition_number, of, fitted_condition_number, weak, poorly_determined,
            above_100, all_excited}, base_parameters, drives, couplings,
            train, validation, physical, notes, terms``; ``condition_number`` is the training motion's
            (:attr:`motion`: the measure ``excite`` reports, ``of`` says ``"motion"``; ``"fitted
            rows"`` when not computed), ``fitted_condition_number`` the fitted rows' (filtered,
            decimated, weighted as fitted); ``weak`` names the parameters carrying directions whose
            singular value is below 1e-3 of the largest (column-scaled fitted rows); ``above_100``
            the terms whose %sigma exceeds 100 (``all_excited`` needs none); ``covariance`` says how
            every ``std`` was computed.
        """
        f = self.fit
        phys = None
        if f.physical is not None:
            p = f.physical
            phys = {"feasible": bool(p.feasible), "min_eigenvalue": float(np.min(p.min_eigenvalues)),
                    "masses": {b: float(v) for b, v in zip(self.model.robot.names, p.masses)},
                    "solver_status": str(p.solver_status)}
        from .estimate import excitation

        fitted, weak = excitation(f.estimate.R11, self.model.names)
        cond = fitted if self.motion is None else float(self.motion["condition_number"])
        loose = poorly_determined(f.estimate, self.model.names)
        pct = np.asarray(f.estimate.pct_sigma, dtype=float)
        above = [n for n, x in zip(self.model.names, pct) if not x <= POORLY_DETERMINED_PCT]
        if phys is not None:
            phys["masses_moved"] = _masses_moved(self.model.robot, f.physical.masses)
        sel = f.selection
        estimator = f.method if sel is None else (f"{f.method}: {sel.weighting.upper()}" + (
            f" with the model file's prior, weight {sel.lam:g}" if sel.lam else ""))
        if sel is not None and sel.rule == "structure":
            what = "physically consistent" if sel.estimator == "physical" else sel.weighting.upper()
            estimator = (f"{f.method}: {what} with the file's prior, weight {sel.lam:g} (the rule for short motions: "
                         f"blocks too short to cross-validate)")
        elif sel is not None and sel.estimator == "physical":
            estimator = f"{f.method}: physically consistent (cross-validated against {sel.weighting.upper()}"
            estimator += f" with the file's prior, weight {sel.lam:g})" if sel.lam else ")"
        return {"method": f.method, "estimator": estimator, "selection": None if sel is None else sel.to_json(),
                "covariance": f.estimate.covariance,
                "model": self.model.robot.name, "convention": self.model.analysis.convention,
                "n_samples": self.samples, "condition_number": cond,
                "excitation": {"condition_number": cond, "of": "fitted rows" if self.motion is None else "motion",
                               "fitted_condition_number": fitted, "weak": weak, "poorly_determined": loose,
                               "above_100": above, "all_excited": not weak and not loose and not above},
                "base_parameters": self.base_parameters(), "drives": self.drives(),
                "couplings": self.couplings(), "train": self.train,
                "validation": self.validation, "physical": phys, "notes": list(self.notes),
                "terms": self.terms_json(), **({"truth": self.truth} if self.truth is not None else {}),
                **({"currents": self.currents.to_json()} if self.currents is not None else {})}

    def terms_json(self) -> list[dict]:
        """Every model term tried: kept or rejected, why, its cross-validated figure, values and std.

        Returns
        -------
        list of dict
            ``{"name", "kept", "why", "cv_rms", "values", "std", "description"}`` per term tried
            (``values``, ``std`` and ``description`` for the kept ones), in the order tried. A kept
            term of the linear core (``rotor``): its parameters' values and std (``Ia_<joint>``; a
            rotor inertia regrouped into a base parameter is in that parameter's value).
        """
        kept = {t.name: t for t in self.fit.terms}
        out = []
        for c in self.fit.term_choices:
            entry = {"name": c.name, "kept": c.kept, "why": c.why,
                     "cv_rms": None if not np.isfinite(c.cv_rms) else float(c.cv_rms)}
            t = kept.get(c.name)
            if t is not None:
                entry.update(values=t.values(self.joints), std=t.std, description=t.describe(self.joints))
            elif c.kept and c.name == "rotor":  # the core's own term: its values are parameters of the core
                own = [k for k, n in enumerate(self.names) if str(n).startswith("Ia")]
                entry.update(values={str(self.names[k]): float(self.values[k]) for k in own},
                             std={str(self.names[k]): float(self.std[k]) for k in own},
                             description="rotor inertia of the driven joints in the linear core: "
                                         + ", ".join(f"{self.names[k]} {self.values[k]:.4g}" for k in own))
            out.append(entry)
        return out
