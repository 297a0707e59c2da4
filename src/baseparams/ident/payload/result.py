"""The identified payload as a value object: mass, centre of mass, inertia, their sigmas, what is identified.

:class:`Payload` holds the fit (:class:`~.fit.PayloadFit`), the model it was fitted with and the notes;
it says the payload's mass [kg], centre of mass [m] in LINK's frame and inertia about the centre of
mass [kg m^2] in LINK's axes, each with a standard deviation (the delta method through the fit's
covariance), which of them the motion identifies, and predicts a log's torques with the payload
(:meth:`Payload.predict`). What the motion does not identify is never a bare number: it is the
prior's value with a note saying so, or None (``null`` in JSON) without a prior.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...display import clip, format_number
from .fit import PayloadFit, link_pseudo
from .model import NAMES, PayloadModel
from .options import PayloadOptions
from .structure import describe

#: the payload's quantities, in the order of :func:`quantities`
QUANTITIES = ("mass", "com_x", "com_y", "com_z", "inertia_com_xx", "inertia_com_xy", "inertia_com_xz",
              "inertia_com_yy", "inertia_com_yz", "inertia_com_zz")
_PAIRS = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))


def quantities(phi: np.ndarray) -> np.ndarray:
    """Mass, centre of mass and inertia about it from the ten parameters (LINK's frame).

    Parameters
    ----------
    phi : ndarray, shape ``(10,)``
        ``XX XY XZ YY YZ ZZ MX MY MZ M`` (``khalil``: LINK's frame, about its origin).

    Returns
    -------
    ndarray, shape ``(10,)``
        :data:`QUANTITIES`: ``m`` [kg], ``c = h / m`` [m], the inertia tensor about ``c`` in
        LINK's axes [kg m^2] (``J_c = J_o - m (|c|^2 1 - c c^T)``); NaN but the mass when
        ``m <= 0``.
    """
    m, h, j = _split(phi)
    if not m > 0:
        return np.r_[m, np.full(9, np.nan)]
    c = h / m
    jc = j - m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.r_[m, c, [jc[a, b] for a, b in _PAIRS]]


def _split(phi):
    n = link_pseudo(phi)
    sigma = n[:3, :3]
    return n[3, 3], n[:3, 3], np.trace(sigma) * np.eye(3) - sigma


def jacobian(phi: np.ndarray) -> np.ndarray:
    """``d quantities / d phi (10, 10)`` by central differences (steps relative to each parameter's size).

    Parameters
    ----------
    phi : ndarray, shape ``(10,)``
        The parameters.

    Returns
    -------
    ndarray, shape ``(10, 10)``
        Row ``i``: the gradient of quantity ``i``.
    """
    phi = np.asarray(phi, dtype=float)
    size = np.r_[np.full(6, max(np.abs(phi[:6]).max(), 1e-6)), np.full(3, max(np.abs(phi[6:9]).max(), 1e-6)),
                 max(abs(phi[9]), 1e-6)]
    out = np.empty((10, 10))
    for k in range(10):
        d = np.zeros(10)
        d[k] = 1e-6 * size[k]
        out[:, k] = (quantities(phi + d) - quantities(phi - d)) / (2 * d[k])
    return out


@dataclass(frozen=True, eq=False)
class Payload:
    """An identified payload (module docstring).

    Parameters
    ----------
    model : PayloadModel
        The model fitted (the robot, the link, the fitted rows, the drive terms, the result).
    fit : PayloadFit
        The estimate, its covariance and what the motion identifies.
    options : PayloadOptions
        The options it was made with (``cutoff`` and ``decimate`` those used).
    notes : tuple of str
        Every decision, one line each.
    samples : dict
        ``{"read", "kept", "fitted"}``: the log's samples, those kept after the filter's edges and
        decimation, and the fitted entries (samples x rows, slow ones left out).
    moving : tuple of str
        The joints that move in the log.
    validation : dict, optional
        Held-out scores (another log), when given.
    """

    model: PayloadModel
    fit: PayloadFit
    options: PayloadOptions
    notes: tuple[str, ...]
    samples: dict
    moving: tuple[str, ...]
    validation: dict | None = None

    @property
    def link(self) -> str:
        """The link the payload is fixed to."""
        return self.model.link

    @property
    def parameters(self) -> np.ndarray:
        """The ten parameters ``(10,)``: ``khalil`` order (``XX .. M``), LINK's frame, about its origin."""
        return np.array(self.fit.x[:10])

    def _table(self) -> tuple[np.ndarray, np.ndarray, list[bool]]:
        """Quantities, their standard deviations and whether each is identified."""
        phi = self.parameters
        v = quantities(phi)
        if not np.isfinite(v).all():
            return v, np.full(10, np.nan), [False] * 10
        jac = jacobian(phi)
        cov = jac @ self.fit.cov[:10, :10] @ jac.T
        ok = [self.fit.structure.identified(g) for g in jac]
        return v, np.sqrt(np.maximum(np.diag(cov), 0.0)), ok

    def identified(self) -> list[str]:
        """The quantities the motion identifies (:data:`QUANTITIES`).

        Returns
        -------
        list of str
            E.g. ``["mass", "com_x", ...]``.
        """
        return [q for q, ok in zip(QUANTITIES, self._table()[2]) if ok]

    def _value(self, v: float, ok: bool):
        """A quantity as reported: the value, the prior's when held, None when neither identified nor held."""
        return float(v) if (ok or self.options.prior is not None) and np.isfinite(v) else None

    @property
    def mass(self) -> float | None:
        """Mass [kg] (None when the motion does not identify it and no prior holds it)."""
        v, _, ok = self._table()
        return self._value(v[0], ok[0])

    @property
    def com(self) -> list:
        """Centre of mass ``(3,)`` [m] in LINK's frame (None per coordinate not identified nor held)."""
        v, _, ok = self._table()
        return [self._value(v[k], ok[k]) for k in range(1, 4)]

    @property
    def inertia_com(self) -> list:
        """Inertia about the centre of mass ``(3, 3)`` [kg m^2] in LINK's axes (None where not identified nor held)."""
        v, _, ok = self._table()
        out = [[None] * 3 for _ in range(3)]
        for k, (a, b) in enumerate(_PAIRS):
            out[a][b] = out[b][a] = self._value(v[4 + k], ok[4 + k])
        return out

    def sigma(self) -> dict:
        """Standard deviations of the identified quantities (None where not identified).

        Returns
        -------
        dict
            ``{"mass": float, "com": [3], "inertia_com": [[3x3]]}`` [kg, m, kg m^2]: the delta
            method through the fit's covariance (HAC by default; with a saved identification its
            own covariance propagated too).
        """
        _, s, ok = self._table()
        val = [float(x) if k and np.isfinite(x) else None for x, k in zip(s, ok)]
        ic = [[None] * 3 for _ in range(3)]
        for k, (a, b) in enumerate(_PAIRS):
            ic[a][b] = ic[b][a] = val[4 + k]
        return {"mass": val[0], "com": val[1:4], "inertia_com": ic}

    def pseudo_inertia(self) -> np.ndarray:
        """The payload's pseudo-inertia in LINK's frame.

        Returns
        -------
        ndarray, shape ``(4, 4)``
            ``[[Sigma, h], [h^T, m]]`` of the reported values.
        """
        return link_pseudo(self.parameters)

    def drives(self) -> list[dict]:
        """The drive terms fitted with the payload (corrections of a saved identification's, with one).

        Returns
        -------
        list of dict
            ``{"name", "value", "std"}`` per term (``Fv_joint``, ``dFv_joint`` for a correction).
        """
        names = self.model.names[10:]
        return [{"name": n, "value": float(v), "std": float(s)}
                for n, v, s in zip(names, self.fit.x[10:], self.fit.std[10:])]

    def parameters_json(self) -> dict:
        """The ten parameters (LINK's frame, about its origin), each identified or not.

        Returns
        -------
        dict
            ``{"convention", "names", "values", "std", "identified"}``: ``values`` None where the
            motion does not identify the parameter and no prior holds it, ``std`` None where not
            identified.
        """
        st, held = self.fit.structure, self.options.prior is not None
        ok = st.parameters()
        return {"convention": "khalil: LINK's frame, about its origin", "names": list(NAMES),
                "values": [float(v) if k or held else None for v, k in zip(self.fit.x[:10], ok)],
                "std": [float(s) if k else None for s, k in zip(self.fit.std[:10], ok)], "identified": ok}

    def unidentified(self) -> list[str]:
        """The payload's directions the motion does not identify, in words.

        Returns
        -------
        list of str
            :func:`~.structure.describe`: one line per direction, empty when all ten are identified.
        """
        return describe(self.fit.structure, self.model.names[10:])

    def __repr__(self) -> str:
        m = self.mass
        mass = "mass not identified" if m is None else f"{format_number(m, 4)} kg"
        return clip(f"<Payload on {self.link}: {mass}, {len(self.identified())}/10 quantities identified, "
                    f"{self.fit.observations} fitted entries>")

    def to_json(self) -> dict:
        """``{"payload": {...}}``: link, mass, com, inertia_com, sigma, identifiable, notes, and the details.

        Returns
        -------
        dict
            ``payload``: ``link``, ``mass`` [kg], ``com`` [3] [m], ``inertia_com`` [[3x3]]
            [kg m^2] (LINK's frame; None where not identified and not held at a prior),
            ``sigma`` (``{"mass", "com", "inertia_com"}``), ``identifiable`` (the quantities the
            motion identifies), ``unidentified`` (the directions it leaves free, in words),
            ``prior``, ``parameters`` (the ten in LINK's frame, ``khalil``, with std and whether
            each is identified), ``drives``, ``physical``, ``joints`` (fitted, moving),
            ``structure``, ``samples``, ``fit_rms``, ``covariance``, ``validation``, ``notes``.
        """
        from .options import prior_dict

        f, st = self.fit, self.fit.structure
        return {"payload": {
            "link": self.link, "mass": self.mass, "com": self.com, "inertia_com": self.inertia_com,
            "sigma": self.sigma(), "identifiable": self.identified(), "unidentified": self.unidentified(),
            "prior": None if self.options.prior is None else prior_dict(self.options.prior),
            "parameters": self.parameters_json(),
            "drives": self.drives(), "physical": f.physical,
            "joints": {"fitted": self.model.joints, "moving": list(self.moving)},
            "structure": {"rank": int(st.rank), "columns": len(st.scale), "gap": _finite(st.gap),
                          "weak_in_log": int(st.weak), "log_gap": _finite(st.log_gap)},
            "samples": dict(self.samples), "fit_rms": dict(zip(self.model.joints, map(float, f.rms))),
            "covariance": f.covariance, "validation": self.validation, "notes": list(self.notes)}}

    def document(self) -> dict:
        """The JSON a saved payload holds (:meth:`save`; :meth:`SavedPayload.load <.saved.SavedPayload.load>` reads it).

        Returns
        -------
        dict
            ``{"format": "baseparams-payload", "version": 1, "baseparams", "robot": {"name",
            "fingerprint"}, "options", "payload": {...}}`` (:meth:`to_json`'s ``payload``);
            non-finite numbers as None.
        """
        from ...version import version
        from ..saved import plain, robot_fingerprint
        from .saved import FORMAT, VERSION

        robot = self.model.robot
        return plain({"format": FORMAT, "version": VERSION, "baseparams": version(),
                      "robot": {"name": robot.name, "fingerprint": robot_fingerprint(robot)},
                      "options": self.options.to_json(), **self.to_json()})

    def save(self, path, inputs=(), what: str = "save=") -> None:
        """Write :meth:`document` to ``path`` as JSON, atomically, never onto an input.

        Parameters
        ----------
        path : str or path
            The file.
        inputs : iterable of str or path
            The run's input files.
        what : str
            The option, for messages.
        """
        import json

        from ...files import write_text

        write_text(path, json.dumps(self.document(), indent=1, allow_nan=False) + "\n", inputs, what)

    def summary(self) -> str:
        """A text report: the quantities with their sigmas, what is not identified, the notes.

        Returns
        -------
        str
            Lines for a terminal.
        """
        v, s, ok = self._table()
        lines = [f"payload on {self.link} ({len(self.identified())} of 10 quantities identified; fitted joints "
                 f"{', '.join(self.model.joints)})"]
        held = self.options.prior is not None
        for name, x, sd, k in zip(QUANTITIES, v, s, ok):
            unit = "kg" if name == "mass" else "m" if name.startswith("com") else "kg m^2"
            if k and np.isfinite(x):
                lines.append(f"  {name:<16s} {x:12.6g} +- {sd:.3g} {unit}")
            elif held and np.isfinite(x):
                lines.append(f"  {name:<16s} {x:12.6g} {unit}  [not identified: from the prior where the motion "
                             f"leaves it free]")
            else:
                lines.append(f"  {name:<16s} {'not identified':>12s}")
        if not all(ok):
            par = self.parameters_json()
            shown = [f"{n} = {x:.6g} +- {sd:.3g}" for n, x, sd, k in zip(NAMES, par["values"], par["std"],
                                                                        par["identified"]) if k]
            if shown:
                lines.append("  identified (LINK's frame, about its origin): " + ", ".join(shown))
        for u in self.unidentified():
            lines.append(f"  not identified by this motion: {u}")
        if self.validation is not None:
            v = self.validation
            lines.append(f"  held-out ({v['source']}, {v['samples']} samples): RMS of predicted minus measured torques "
                         + ", ".join(f"{j} {x:.3g}" for j, x in v["rms"].items()))
        return "\n".join(lines + [f"note: {n}" for n in self.notes])

    def predict(self, log, smooth: bool = True) -> np.ndarray:
        """Joint torques of a log with the payload: the known robot, the payload and the fitted drive terms.

        Parameters
        ----------
        log : JointLog
            ``S`` samples of every joint (``tau`` may be None).
        smooth : bool
            States low-passed at the fit's cutoff (default), or as logged.

        Returns
        -------
        ndarray, shape ``(S, dof)``
            Predicted torques [N m or N], columns the robot's joints
            (:meth:`~baseparams.model.robot.Robot.coordinate_names`).
        """
        from .predict import payload_torques

        return payload_torques(self, log, smooth)


def _finite(x):
    return None if x is None or not np.isfinite(x) else float(x)

