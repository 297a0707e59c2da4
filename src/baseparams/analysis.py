"""The main job: DRNG, certification/completion, base parameters, and their report.

:func:`analyze` returns an :class:`Analysis` (``baseparams.analyze``); :func:`regressor` is
``baseparams.regressor`` (the TP regressor, loops closed for robots with loops);
:func:`format_report` is the CLI's text report and ``Analysis.to_json`` its ``--json``.

JSON schema (``baseparams analyze MODEL --json``), one object:

============================  ===================================================================
model                         robot name
n_bodies, n_params            moving bodies, 10 x bodies
gravity                       [gx, gy, gz] m/s^2, world frame
floating                      true for a floating (F) root
rows                          measured generalized forces: all | joints | base | a set of joints
                              (joints:NAME,... | base+joints:NAME,... | passive:NAME,...)
nullity                       certified nullspace dimension (DRNG's rank when --no-verify; when the
                              status is undecided, DRNG's span: a lower bound, no decided count)
n_base                        number of base parameters = n_params - nullity (undecided: an upper
                              bound; rank_decision says why no gap decides)
drng                          {columns, rank, seconds, extended, by_principle{shared points, fixed
                              points, planar rotations}, by_rule{shared points, fixed points, planar
                              rotations, R-A fixed vectors, R-B sliding points, R-L1 parallelograms,
                              R-L2 level chains, R-L3 planar loops, R-M coupled joints, numerical},
                              complete, notes}: rank added
                              by each source in that order (the paper's principles, the extended
                              rules, then, when some rows are not measured, unmeasured root,
                              unmeasured body and passive joint (those present), numerical
                              completion); complete:
                              the geometric span equals the certified nullspace (null if unverified);
                              notes: a rule whose columns failed the check against the regressor
                              (left out, named), or why the check could not run ([] normally)
numerical                     {nullity, rank, samples, sv_gap, tolerance, rtol, seconds, sampling{
                              requested, kept, and for loops not_converged, branch_jumps,
                              ill_conditioned, max_loop_residual}} or null; for a tree checked
                              body by body (40 bodies or more): rank proven block by block, sv_gap
                              the smallest kept block singular value over the worst column residual
certified                     true when the numerics confirm the (completed) nullspace
status, message               certified | completed | undecided | failed | unverified, and why
completed                     directions added from the numerical nullspace (marked numerical)
residual                      ||W B_drng||_F / ||W||_F with orthonormal B_drng (null if unverified)
convention                    parameter convention of base_parameters (khalil: link frames)
form                          expanded | recursive: how the expressions are written (expanded: standard
                              parameters only; recursive: a body's own standard parameters and its
                              children's regrouped dependent parameters NAMER, defined in
                              regrouped_parameters; O(n) terms on a tree)
base_parameters               [{name, expression}] regrouped base parameters
base_parameters_paper         the same in the paper's spatial convention (world frame at q = 0)
regrouped_parameters          [{name, expression}] the recursive form's regrouped dependent parameters,
                              root side first ([] in the expanded form)
regrouped_parameters_pa       per  the same in the paper's convention
unidentifiable                standard parameters that no base parameter sees
practical                     null, or {literal_n_base (null: not decided), counted_out, tolerance, size,
                              candidates, snaps[{joint, element, what, component, literal, text, special,
                              new, deviation}], note}: values the file writes to within rounding of a
                              right angle or zero (each named by its element), taken as that value
                              because the directions they add are not identifiable in practice
                              (``literal=True`` / ``--literal``: the file as stated)
practical_rank                null, or {threshold, decided, rank, nullity, counted_out, largest_out,
                              smallest_kept, gap, literal_rank, literal_gap, min_gap, length, rate,
                              samples, borderline, clusters, candidates[{rank, meaning}], note}: the
                              literal singular-value gap did not decide the rank, which was decided by
                              each direction's effect on the torques at the model's own scales
                              (directions below threshold of the torque scale counted out, only where
                              the threshold lies in a gap of those effects; otherwise undecided, with
                              the clusters and the candidate counts; :mod:`baseparams.nullspace.practical`);
                              ``--literal``: the literal decision (``undecided``)
rank_decision                 null (unverified), or {by: literal | practical | structured, decided,
                              rank, gap, smallest_kept, largest_out, bound, clusters[{first, count, top,
                              bottom, spread, gap_below}], snapped}: the gap of the spectrum the count
                              was stated at (a count is stated only at a gap: neighbouring singular
                              values >= 100x apart and 10x the ratios inside the clusters around them,
                              :func:`baseparams.numerics.spectrum`), values relative to the largest
============================  ===================================================================
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, TextIO

import numpy as np

from .arguments import CHOICES, ArgumentTypeError
from .display import data_frame, summary_repr, text_table
from .enums import Source, Status, values
from .errors import BaseparamsError
from .model.robot import Robot
from .numerics import available_bytes as _available_bytes
from .numerics import decision_lines

if TYPE_CHECKING:  # the heavy modules (DRNG imports scipy.sparse) load when analyze() runs
    from .base import BaseParameters
    from .nullspace.certify import Certificate

#: what ``Analysis.status`` can be (``unverified``: ``verify=False``)
STATUSES = values(Status)

#: the pipeline's steps, imported when first used (DRNG imports scipy.sparse): ``import
#: baseparams`` stays light; they remain attributes of this module (tests patch them here)
_LAZY = {"drng": "baseparams.nullspace", "certify": "baseparams.nullspace.certify",
         "base_parameters": "baseparams.base"}


def _step(name: str):
    if name not in globals():
        globals()[name] = getattr(importlib.import_module(_LAZY[name]), name)
    return globals()[name]


def __getattr__(name: str):
    if name in _LAZY:
        return _step(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def regressor(robot: Robot, q, dq=None, ddq=None, *, backend: str = "auto",
              out: np.ndarray | None = None) -> np.ndarray:
    """The TP regressor: ``tau = regressor(robot, q, dq, ddq) @ robot.parameters("paper")``.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    q, dq, ddq : array_like, shape ``(S, m)`` or ``(m,)``
        Joint positions, velocities and accelerations of ``S`` states (``dq``, ``ddq``
        default to zero). ``m`` is ``robot.dof`` for a tree (a floating root's six
        coordinates first: its quasi-velocities are the base's spatial twist). For a robot
        with loops, ``m = len(robot.actuated)``: the states are the **actuated**
        coordinates, the loops are closed from the reference assembly (q = 0) and the rows
        are the actuated generalized forces.
    backend : {"auto", "numpy", "compiled"}
        ``compiled``: the numba kernel (the ``fast`` extra); ``numpy``: batched numpy; ``auto``
        (default): the kernel for large batches when numba is installed, numpy otherwise. Both
        give the same matrix to rounding.
    out : ndarray, shape ``(S, m, 10 n)``, optional
        A C-contiguous float64 buffer to fill and return (e.g. the previous call's output, to
        reuse across chunks of a log).

    Returns
    -------
    Y : ndarray, shape ``(S, m, 10 n)``
        Gravity (``robot.gravity``) included; columns in the ``paper`` convention (spatial
        pseudo-inertia entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at
        q = 0).

    Raises
    ------
    BaseparamsError
        Wrong shapes, an unknown backend, a wrong ``out`` (shape, dtype, layout), a compiled
        backend without numba, or (loops) a state that does not close its loops on the reference
        assembly mode. The spanning tree's regressor (loops cut, tree coordinates) is
        ``baseparams.regressor.tp.regressor``.
    """
    from .regressor.tp import closed_regressor
    from .regressor.tp import regressor as tree_regressor

    q, dq, ddq, cs = checked_states(robot, q, dq, ddq)
    if cs is None:
        return tree_regressor(robot, q, dq, ddq, out=out, backend=backend)
    return closed_regressor(robot, cs, out=out, backend=backend)


def checked_states(robot: Robot, q, dq=None, ddq=None):
    """States checked against the robot, and closed when it has loops.

    Parameters
    ----------
    robot : Robot
        The robot.
    q, dq, ddq : array_like, shape ``(S, m)``
        ``m = robot.dof`` for a tree; the actuated coordinates for a robot with loops
        (``dq``, ``ddq`` default to zero).

    Returns
    -------
    q, dq, ddq : ndarray, shape ``(S, m)``
        The states as float arrays.
    closed : ClosedStates or None
        For a robot with loops, the states closed from the reference assembly; else ``None``.

    Raises
    ------
    BaseparamsError
        Wrong shapes, or states that do not close the loops.
    """
    from .arguments import check_array

    if not isinstance(robot, Robot):
        raise ArgumentTypeError(f"robot must be a Robot (baseparams.load(...)), got {type(robot).__name__}")
    q = np.atleast_2d(check_array(q, "q", (0, 1, 2)))  # numbers, finite: NaN states give NaN regressors
    dq = np.zeros_like(q) if dq is None else np.atleast_2d(check_array(dq, "dq", (0, 1, 2)))
    ddq = np.zeros_like(q) if ddq is None else np.atleast_2d(check_array(ddq, "ddq", (0, 1, 2)))
    m = len(robot.actuated) if robot.has_loops else robot.dof
    what = "actuated coordinates (the robot has loops)" if robot.has_loops else "coordinates"
    for name, x in (("q", q), ("dq", dq), ("ddq", ddq)):
        if x.ndim != 2 or x.shape[1] != m or x.shape[0] != q.shape[0]:
            raise BaseparamsError(f"robot {robot.name!r}: {name} must have shape ({q.shape[0]}, {m}) ({m} {what}); "
                                  f"got {x.shape}")
    if not robot.has_loops:
        return q, dq, ddq, None
    from .kinematics.loops import close_loops

    cs = close_loops(robot, q, dq, ddq, cond_max=np.inf)
    if cs.kept != q.shape[0]:
        raise BaseparamsError(
            f"robot {robot.name!r}: {q.shape[0] - cs.kept} of {q.shape[0]} actuated states do not close the loops "
            f"({cs.not_converged} outside the workspace, {cs.branch_jumps} leave the reference assembly mode); "
            f"pick states nearer the reference q = 0 (baseparams.numerics.closed_samples draws valid "
            f"ones: its .q[:, robot.actuated])")
    return q, dq, ddq, cs


@dataclass(frozen=True, eq=False)
class Analysis:
    """The base-parameter analysis of one robot, as returned by :func:`analyze`.

    The nullspace ``N`` of the TP regressor (the inertial-parameter directions no
    measurement sees) found by DRNG with provenance, certified (and, where no rule finds a
    direction, completed) by the numerical method, and regrouped into base parameters
    ``beta = pi_I + K pi_D`` in :attr:`convention` (Khalil's rules for serial chains).

    Parameters
    ----------
    robot : Robot
        The analysed robot (``n`` moving bodies, ``10 n`` standard parameters).
    rows : str
        Measured generalized forces: ``all``, ``joints``, ``base`` or a set of joints
        (``joints:NAME,...``, ``base+joints:NAME,...``, ``passive:NAME,...``;
        :func:`baseparams.numerics.row_mask`).
    drng_seconds : float
        DRNG's wall time [s].
    drng_columns : int
        Number of columns DRNG generated.
    drng_rank : int
        Rank of DRNG's columns (the nullity when unverified).
    by_principle : dict of str to int
        Rank added by each principle / extended rule (keyed by
        :attr:`~baseparams.enums.Source.label`).
    certificate : Certificate or None
        The numerical check (``None`` with ``verify=False``).
    basis : ndarray, shape ``(10 n, nullity)``, or None
        Orthonormal nullspace basis in the ``paper`` convention, DRNG's span first, then the
        numerically completed directions; ``None`` for a large tree certified body by body
        (``certificate.columns`` spans the nullspace, and ``base`` is regrouped from it).
    base, base_paper : BaseParameters
        The regrouping in :attr:`convention` and in ``paper``.
    seconds : float
        The whole analysis' wall time [s].
    extended : bool
        Whether the extended geometric rules were used as well as the paper's three principles.
    practical : Practical, optional
        Directions counted out as not identifiable in practice: the model file states some
        geometry to within rounding of a special value and the analysis is that of the model with
        the special value (:mod:`baseparams.model.snap`); ``robot`` is then that model and
        ``practical.source`` the file's. ``None``: the literal model was analysed.
    form : {"expanded", "recursive"}
        How :meth:`expressions` are written (:func:`analyze`'s ``form``, resolved).
    drng_notes : tuple of str
        :attr:`baseparams.nullspace.result.DRNGResult.notes`: a rule whose columns were not in the
        nullspace of the regressor (left out, named), or why they could not be checked.

    Notes
    -----
    Not equal-comparable (``==`` is identity): compare ``nullity``, ``expressions()`` or
    ``to_json()`` instead. ``to_json()`` follows the schema in this module's docstring.
    """

    robot: Robot
    rows: str
    drng_seconds: float
    drng_columns: int
    drng_rank: int
    by_principle: dict[str, int]
    certificate: Certificate | None
    basis: np.ndarray
    base: BaseParameters
    base_paper: BaseParameters
    seconds: float
    extended: bool = True
    practical: Practical | None = None
    form: str = "expanded"
    drng_notes: tuple[str, ...] = ()

    @property
    def nullity(self) -> int:
        """Dimension of the (certified) nullspace; DRNG's rank when unverified."""
        return self.basis.shape[1] if self.basis is not None else 10 * self.robot.n - self.base.n_base

    @property
    def source_robot(self) -> Robot:
        """The model as given (:attr:`robot` unless geometry was snapped, :attr:`practical`)."""
        return self.robot if self.practical is None else self.practical.source

    @property
    def n_base(self) -> int:
        """Number of base parameters, ``10 n - nullity``."""
        return 10 * self.robot.n - self.nullity

    @property
    def status(self) -> Status:
        """The certification's outcome.

        ``certified``, ``completed``, ``undecided``, ``failed`` or ``unverified`` (a
        :class:`~baseparams.enums.Status`, equal to those strings).
        """
        return Status.UNVERIFIED if self.certificate is None else self.certificate.status

    @property
    def certified(self) -> bool:
        """True when the numerics confirm the (completed) nullspace."""
        return self.certificate is not None and self.certificate.certified

    @property
    def convention(self) -> str:
        """Parameter convention of :meth:`expressions`, :meth:`to_base` and :meth:`from_base`."""
        return self.base.convention

    @property
    def names(self) -> list[str]:
        """The ``10 n`` standard parameter names (``body.PARAM``) in :attr:`convention`."""
        return list(self.base.names)

    @property
    def base_names(self) -> list[str]:
        """The ``n_base`` base parameter names (suffix ``R``: it absorbs others)."""
        return self.base.base_names()

    @property
    def base_values(self) -> np.ndarray:
        """The robot's own base-parameter values ``(n_base,)``, named by :attr:`base_names`.

        ``to_base(robot.parameters(convention), convention)``: what an identification of this
        model should find (SI units, :attr:`convention`).
        """
        return self.to_base(self.robot.parameters(self.convention), self.convention)

    def _columns(self) -> dict[str, list]:
        """Each base parameter's name, expression and model value."""
        exprs = self.expressions()
        return {"name": [e["name"] for e in exprs], "expression": [e["expression"] for e in exprs],
                "value": self.base_values.tolist()}

    def table(self) -> str:
        """The base parameters as a text table.

        Returns
        -------
        str
            Columns ``name, value, expression`` (:attr:`base_names`, :attr:`base_values` at 6
            significant digits, :meth:`expressions`), one row per base parameter.
        """
        c = self._columns()
        return text_table({"name": c["name"], "value": c["value"], "expression": c["expression"]})

    def to_frame(self):
        """The base parameters as a pandas DataFrame (pandas is optional).

        Returns
        -------
        pandas.DataFrame
            Columns ``name, expression, value`` (:attr:`base_names`, :meth:`expressions`,
            :attr:`base_values`), one row per base parameter.

        Raises
        ------
        BaseparamsError
            pandas is not installed.
        """
        return data_frame(self._columns())

    def expressions(self) -> list[dict[str, str]]:
        """Each base parameter as a combination of standard parameters in :attr:`convention`.

        Returns
        -------
        list of dict
            ``[{"name", "expression"}]``, e.g. ``link1.ZZR = link1.ZZ + link2.YY + ...``
            gives ``{"name": "link1.ZZR", "expression": "link1.ZZ + link2.YY + ..."}``. In the
            recursive :attr:`form` the terms are the body's own standard parameters and its
            children's regrouped dependent parameters (``link2.MR``, :meth:`regrouped`).
        """
        return self.base.expressions(self.form)

    def regrouped(self) -> list[dict[str, str]]:
        """The regrouped dependent parameters of the recursive form (``[]`` in the expanded form).

        Returns
        -------
        list of dict
            ``[{"name", "expression"}]``, root side first, e.g. ``{"name": "link2.MR",
            "expression": "link2.M + link3.MR"}``: each in terms of its own standard parameter and
            the higher bodies' regrouped ones.
        """
        return self.base.definitions() if self.form == "recursive" else []

    def expanded_expressions(self) -> list[dict[str, str]]:
        """:meth:`expressions` written out in standard parameters only, whatever the :attr:`form`.

        Returns
        -------
        list of dict
            ``[{"name", "expression"}]``; ``O(sum of depths)`` terms on a tree.
        """
        return self.base.expressions("expanded")

    def to_base(self, params, convention: str) -> np.ndarray:
        """Base parameters of a standard parameter vector.

        Parameters
        ----------
        params : array_like, shape ``(10 n,)``
            Standard parameters, ten per body in ``convention``'s order
            (``robot.parameters(convention)`` gives the robot's own).
        convention : str
            The convention of ``params`` (required): it must be :attr:`convention`; a
            mismatch raises :class:`BaseparamsError`, never a number.

        Returns
        -------
        beta : ndarray, shape ``(n_base,)``
            ``beta = pi_I + K pi_D``, named by :attr:`base_names`.
        """
        return self.base.to_base(params, convention)

    def from_base(self, beta) -> np.ndarray:
        """A standard parameter vector with the given base parameters.

        Parameters
        ----------
        beta : array_like, shape ``(n_base,)``
            Base parameters, named by :attr:`base_names`.

        Returns
        -------
        params : ndarray, shape ``(10 n,)``
            The minimum-norm vector in :attr:`convention` with
            ``to_base(params, convention) == beta``: any other differs by a nullspace
            direction, invisible to every measurement.
        """
        return self.base.from_base(beta)

    def base_regressor(self, q, dq=None, ddq=None, *, out: np.ndarray | None = None,
                       backend: str = "auto") -> np.ndarray:
        """The regressor of the base parameters.

        Parameters
        ----------
        q, dq, ddq : array_like, shape ``(S, m)``
            States as for :func:`regressor`: ``m = robot.dof`` for a tree; for a robot with
            loops the actuated coordinates (``m = len(robot.actuated)``), loops closed from
            the reference assembly.
        out : ndarray, shape ``(S, rows, n_base)``, optional
            A C-contiguous float64 buffer to fill and return (reuse it across chunks of a log).
        backend : {"auto", "numpy", "compiled"}
            The regressor's backend (:func:`baseparams.regressor.tp.regressor`): the compiled
            kernel projects each body's columns as it computes them, never forming the
            ``10 n``-column regressor.

        Returns
        -------
        Yb : ndarray, shape ``(S, rows, n_base)``
            The measured rows (:attr:`rows`: all, the joints' or the floating base's) of the
            full regressor in :attr:`convention`, independent columns: for every standard
            vector ``pi`` in :attr:`convention` (``pi_paper`` the same in ``paper``),
            ``Yb @ to_base(pi, convention)`` equals ``regressor(robot, q, dq, ddq) @ pi_paper``
            on those rows.
        """
        from .numerics import row_mask
        from .regressor.tp import closed_projected_regressor, projected_regressor

        q, dq, ddq, cs = checked_states(self.robot, q, dq, ddq)
        if cs is not None:
            return closed_projected_regressor(self.robot, cs, P=self.base_map, out=out, backend=backend)
        rows = np.flatnonzero(row_mask(self.robot, self.rows))
        t = self.base.T
        p = t[:, self.base.independent] if hasattr(t, "tocsr") else self.base_map  # a large tree: sparse
        return projected_regressor(self.robot, q, dq, ddq, P=p, rows=rows, out=out, backend=backend)

    @property
    def base_map(self) -> np.ndarray:
        """The map ``P (10 n, n_base)`` from ``paper`` columns to base-parameter columns.

        ``Yb = Y @ P`` (:meth:`base_regressor`): ``P`` is ``paper_from(convention)`` restricted
        to the independent parameters; rows in the ``paper`` convention.

        Returns
        -------
        ndarray, shape ``(10 n, n_base)``
            Read-only.
        """
        p = self.__dict__.get("_base_map")
        if p is None:
            t = self.base.T[:, self.base.independent]
            p = np.ascontiguousarray(t.toarray() if hasattr(t, "toarray") else t)
            p.flags.writeable = False
            object.__setattr__(self, "_base_map", p)
        return p

    def __repr__(self) -> str:
        return (f"<Analysis {self.robot.name}: nullity {self.nullity}, {self.n_base} base parameters "
                f"({self.convention}), {self.status}>")

    def to_json(self) -> dict:
        """The result as one JSON-able dict.

        Returns
        -------
        dict
            The schema in this module's docstring (what ``baseparams analyze MODEL --json``
            prints).
        """
        return self._json(True)

    def _json(self, expressions: bool) -> dict:
        """:meth:`to_json`; without ``expressions`` the four lists of expressions are None (:func:`json_chunks`)."""
        from .nullspace.drng import PAPER

        r, c = self.robot, self.certificate
        num = None
        if c is not None:
            nm = c.numerical
            num = {"nullity": nm.nullity, "rank": nm.rank, "samples": nm.samples,
                   "sv_gap": None if not np.isfinite(nm.gap) else nm.gap, "tolerance": nm.tol,
                   "rtol": nm.rtol, "seconds": nm.seconds, "sampling": c.sampling}
        return {
            "model": r.name, "n_bodies": r.n, "n_params": 10 * r.n, "gravity": r.gravity.tolist(),
            "floating": r.floating, "rows": self.rows, "nullity": self.nullity,
            "n_base": self.n_base,
            "drng": {"columns": self.drng_columns, "rank": self.drng_rank, "seconds": self.drng_seconds,
                     "extended": self.extended,
                     "by_principle": {k: v for k, v in self.by_principle.items() if k in PAPER},
                     "by_rule": {**self.by_principle, Source.NUMERICAL.label: 0 if c is None else c.completed},
                     "complete": None if c is None else bool(c.status == Status.CERTIFIED),
                     "notes": list(self.drng_notes)},
            "numerical": num,
            "certified": self.certified,
            "status": self.status,
            "message": "not verified (--no-verify)" if c is None else c.message,
            "completed": 0 if c is None else c.completed,
            "residual": None if c is None else c.residual,
            "convention": self.base.convention,
            "form": self.form,
            "base_parameters": self.base.expressions(self.form) if expressions else None,
            "base_parameters_paper": self.base_paper.expressions(self.form) if expressions else None,
            "regrouped_parameters": self.regrouped() if expressions else None,
            "regrouped_parameters_paper": (self.base_paper.definitions() if self.form == "recursive" else [])
            if expressions else None,
            "unidentifiable": [self.base.names[i] for i in self.base.unidentifiable],
            "practical": None if self.practical is None else self.practical.to_json(self.n_base),
            "practical_rank": None if c is None or c.practical is None else c.practical.to_json(),
            "rank_decision": self.rank_decision(),
        }

    def rank_decision(self) -> dict | None:
        """The gap that decided the count (or the clusters when none did): ``None`` when unverified.

        Returns
        -------
        dict or None
            ``by`` (``literal``: the certification's singular values at its tolerance;
            ``practical``: each direction's effect on the torques; ``structured``: body by body),
            ``decided``, ``rank`` (None when not decided), ``gap`` (the ratio across the cut at the
            tolerance, None when infinite),
            ``smallest_kept`` and ``largest_out`` (relative to the largest), ``bound`` (the
            tolerance the cut had to fall at), ``clusters`` ``[{first, count, top, bottom, spread,
            gap_below}]``, ``snapped`` (the count is that of the file with the values
            :attr:`practical` names exact).
        """
        c = self.certificate
        if c is None:
            return None
        snapped = self.practical is not None
        if c.practical is not None:
            p = c.practical.to_json()
            return {"by": "practical", "decided": p["decided"], "rank": p["rank"] if p["decided"] else None,
                    "gap": p["gap"],
                    "smallest_kept": p["smallest_kept"], "largest_out": p["largest_out"], "bound": p["threshold"],
                    "clusters": p["clusters"], "snapped": snapped}
        nm = c.numerical
        spec = nm.spectrum
        if spec is None:  # the structured check: the smallest kept block value over the worst residual
            return {"by": "structured", "decided": bool(c.status.ok), "rank": nm.rank,
                    "gap": None if not np.isfinite(nm.gap) else nm.gap, "smallest_kept": None, "largest_out": None,
                    "bound": nm.rtol, "clusters": [], "snapped": snapped}
        v = spec.values
        return {"by": "literal", "decided": bool(nm.decided), "rank": nm.rank if nm.decided else None,
                "gap": None if not np.isfinite(nm.gap) else nm.gap,
                "smallest_kept": float(v[nm.rank - 1]) if nm.rank else None,
                "largest_out": float(v[nm.rank]) if nm.rank < len(v) else None, "bound": nm.rtol,
                "clusters": [{"first": k.first, "count": k.count, "top": k.top, "bottom": k.bottom, "spread": k.spread,
                              "gap_below": None if not np.isfinite(spec.gap(k.stop)) else spec.gap(k.stop)}
                             for k in spec.clusters], "snapped": snapped}


def analyze(robot: Robot, *, samples: int | None = None, seed: int = 0, verify: bool = True, rows="all",
            convention: str = "khalil", extended: bool = True, progress: TextIO | None = None,
            literal: bool = False, form: str = "auto") -> Analysis:
    """Base parameters of ``robot``: DRNG, then certification (and completion), then regrouping.

    Parameters
    ----------
    robot : Robot
        E.g. from :func:`baseparams.load` or :class:`baseparams.RobotBuilder`.
    samples : int, optional
        Random states for the numerical certification (default: 100 for trees, 5000
        actuated samples for closed loops, as the paper).
    seed : int
        Seed of those states: the result is deterministic.
    verify : bool
        Certify with the numerical method; ``False`` keeps DRNG's span unverified (status
        ``unverified``).
    rows : str or sequence of str
        Measured generalized forces: ``all``, the joint torques only (``joints``), a floating
        base's wrench only (``base``), or a set of joints: a list of the measured joints' names,
        ``"joints:NAME,NAME"`` (the same), ``"base+joints:NAME,..."`` (and the base wrench),
        ``"passive:NAME,..."`` (every row but these joints': an under-actuated robot). Robots
        with loops: ``all``, the actuated forces. See :func:`baseparams.numerics.row_mask`.
    convention : {"khalil", "paper", "pinocchio", "idyntree", "rpna"}
        Convention of the regrouped expressions and of ``to_base`` / ``from_base``
        (``baseparams.CONVENTIONS``; ``paper``: world frame at q = 0, the others link frames).
    extended : bool
        The extended geometric rules as well as the paper's three principles.
    progress : file-like, optional
        A stream for progress lines (e.g. ``sys.stderr``).
    literal : bool
        Analyse the model exactly as the file states it. By default (``False``) geometry the file
        states to within rounding of a special value (an angle within 1e-3 rad of a multiple of
        pi/2, an offset or axis component within 1e-3 of zero relative to the robot's size;
        :mod:`baseparams.model.snap`) is taken as that value **when** it changes the count: the
        directions it adds move the torques by less than 1e-3 of their scale and are not
        identifiable in practice. Such an analysis says so (``.practical``, a note in the
        report and JSON, the literal count); exact files are unaffected. Likewise, where the
        certification's singular-value gap cannot decide the rank, the rank is decided by each
        direction's effect on the torques at the model's own scales (below 1e-6 of the torque
        scale: counted out; :mod:`baseparams.nullspace.practical`, ``certificate.practical``);
        ``literal=True`` leaves such a rank ``undecided``.
    form : {"auto", "expanded", "recursive"}
        How the regrouped expressions are written and held. ``expanded``: each base parameter in
        standard parameters only (``O(sum of depths)`` terms on a tree: quadratic on a chain);
        ``recursive``: in its body's own standard parameters and its children's regrouped
        dependent parameters (``link3.MR``, :meth:`Analysis.regrouped`), ``O(n)`` terms, as
        Khalil writes them (a tree whose nullspace DRNG spans; ``expanded_expressions()`` writes
        them out). ``auto`` (default): recursive for trees of at least
        :data:`RECURSIVE_MIN_BODIES` bodies regrouped body by body, expanded otherwise.

    Returns
    -------
    Analysis
        ``.nullity``, ``.n_base``, ``.status``, ``.expressions()``, ``.basis``, the maps
        ``to_base`` / ``from_base`` / ``base_regressor`` and ``.to_json()``. An ``undecided``
        or ``failed`` certification is a status, not an exception.

    Raises
    ------
    BaseparamsError
        Bad input (unknown convention, rows or joint name, ``rows="base"`` without a floating
        base, loops that no sample closes).

    Examples
    --------
    >>> import baseparams
    >>> a = analyze(baseparams.load("puma560"))
    >>> a.nullity, a.n_base, a.status
    (24, 36, 'certified')
    >>> a.expressions()[0]["name"]
    'link1.ZZR'
    """
    from .arguments import check_progress

    if not isinstance(robot, Robot):
        raise ArgumentTypeError(f"analyze() takes a Robot (baseparams.load(NAME or PATH) makes one), "
                                f"not {type(robot).__name__}")
    check_analyze({"samples": samples, "seed": seed, "verify": verify, "rows": rows, "convention": convention,
                   "extended": extended, "literal": literal, "form": form})
    check_progress(progress, "analyze", stream=True)
    _check_samples_memory(robot, samples)
    kw = {"samples": samples, "seed": seed, "verify": verify, "rows": rows, "convention": convention,
          "extended": extended, "progress": progress, "form": form}
    lit = _analyze(robot, **kw)
    if literal:
        return lit
    # the file as written: a rank the literal gap cannot decide is decided by the directions' effect on
    # the torques (nullspace.practical), at a gap of those effects or not at all; then geometry near a
    # special value, taken exact where that states a lower count at a gap
    ref = _analyze(robot, **kw, practical=True) if lit.status == Status.UNDECIDED else lit
    return practical_analysis(lit, {**kw, "practical": True}, ref)


#: the forms of the regrouped expressions (:func:`analyze`)
FORMS = CHOICES["form"]


def check_analyze(keywords: dict) -> None:
    """Every rule of :func:`analyze`'s keywords that needs no robot (the command line's preflight asks it too).

    Parameters
    ----------
    keywords : dict
        :func:`analyze`'s keywords (``samples``, ``seed``, ``verify``, ``rows``, ``convention``,
        ``extended``, ``literal``, ``form``); those missing are not checked.

    Raises
    ------
    BaseparamsError
        The first keyword refused, in one line naming it: a number out of its range, a flag that
        is not a boolean, a convention or form that is none of the choices, rows of another type.
    """
    from .arguments import check_choice, check_flags, check_keywords

    check_keywords("analyze", **{k: keywords[k] for k in ("samples", "seed") if k in keywords})
    rows = keywords.get("rows", "all")
    if not isinstance(rows, (str, list, tuple)):
        raise ArgumentTypeError(f"analyze: rows= must be a string (all, joints, ...) or a list of joint names, got "
                                f"{type(rows).__name__}")
    check_flags("analyze", **{k: keywords[k] for k in ("verify", "extended", "literal") if k in keywords})
    for name in ("convention", "form"):
        if name in keywords:
            check_choice("analyze", name, keywords[name], CHOICES[name])

#: ``form="auto"``: the recursive form for a tree regrouped body by body with at least this many bodies
RECURSIVE_MIN_BODIES = 200


def _analyze(robot: Robot, *, samples: int | None, seed: int, verify: bool, rows, convention: str, extended: bool,
             progress: TextIO | None, form: str = "auto", practical: bool = False) -> Analysis:
    """:func:`analyze` of the model as given (arguments as there; ``practical``: an undecided gap decided by effect)."""
    from .model.inertia import check_convention

    drng, certify, base_parameters = _step("drng"), _step("certify"), _step("base_parameters")
    check_convention(convention)
    t0 = time.perf_counter()

    def say(msg: str) -> None:
        if progress is not None:
            print(f"[baseparams] {msg}", file=progress, flush=True)

    from .numerics import blas_threads, row_mask, rows_spec

    rows = rows_spec(rows)
    row_mask(robot, rows)  # a bad name or form is refused before any work
    _check_memory(robot, verify, rows, form)
    say(f"{robot.name}: {robot.n} bodies, {robot.dof} dofs; running DRNG")
    with blas_threads():  # small dense factorizations: one BLAS thread (numerics.blas_threads)
        res = drng(robot, extended=extended, rows=rows)
        by = res.by_principle()
        cert, columns = None, None
        if verify:
            say(f"certifying with {samples or 'the default number of'} random samples (seed {seed}, rows: {rows})")
            cert = certify(robot, samples, seed, rows, result=res, practical=practical)
            basis, span, columns = cert.basis, cert.span, cert.columns
        else:
            columns = _large_tree_columns(robot, rows, res)
            basis = span = res.orthonormal() if columns is None else None
        say("regrouping base parameters")
        use = _resolve_form(robot, form, columns)
        if use == "recursive" and columns is None:  # a small tree: DRNG's span in compact form
            columns = _recursive_columns(robot, rows, res, cert)
        if use == "recursive" or columns is not None:  # a large tree: O(n), expanded as it is written
            from .base.recursive import recursive_base_parameters

            base = recursive_base_parameters(robot, columns, convention)
            base_paper = recursive_base_parameters(robot, columns, "paper")
        else:
            base, base_paper = _dense_regroup(robot, span, res, cert, convention, base_parameters)
    return Analysis(robot, rows, res.seconds, res.n_columns, res.rank, by, cert, basis, base, base_paper,
                    time.perf_counter() - t0, extended, form=use, drng_notes=res.notes)


def _dense_regroup(robot: Robot, span: np.ndarray, res, cert, convention: str, regroup) -> tuple:
    """``regroup`` (:func:`~.base.regroup.base_parameters`) of the dense span in ``convention`` and ``paper``.

    A dense basis in world coordinates at q = 0 carries rounding ``~eps (D / L)^2`` on a body
    ``D`` from the origin (:func:`baseparams.model.scale.body_rounding`): far enough, it cannot
    tell the directions apart (fewer than the nullity, or a rank-deficient regrouping). A tree
    is then regrouped from DRNG's compact columns (each body's decisions about its own origin);
    anything else is refused in one line.
    """
    nullity = res.rank if cert is None else cert.nullity
    if span.shape[1] == nullity:
        try:
            return regroup(robot, span, convention), regroup(robot, span, "paper")
        except RuntimeError:
            pass
    from .base.sparse import tree_base_parameters
    from .model.scale import body_rounding, length_scale
    from .nullspace.structured import independent_columns

    compact = None if robot.has_loops or (cert is not None and cert.completed) else independent_columns(robot, res)
    if compact is not None:
        return tree_base_parameters(robot, compact, convention), tree_base_parameters(robot, compact, "paper")
    far = int(np.argmax(body_rounding(robot)))
    dist = float(np.linalg.norm(robot.M0[far][:3, 3]))
    raise BaseparamsError(f"robot {robot.name!r}: the nullspace basis cannot be regrouped: body "
                          f"{robot.names[far]!r} is {dist:.3g} m from the world origin, "
                          f"{dist / length_scale(robot):.3g} times the robot's length scale, and the basis (world "
                          f"frame at q = 0) carries rounding of ~{body_rounding(robot)[far]:.1g} there; put the "
                          f"model's origin near its bodies")


def _resolve_form(robot: Robot, form: str, columns) -> str:
    """``expanded`` or ``recursive`` for :func:`analyze`'s ``form`` (``auto``: by size, module constants)."""
    if form != "auto":
        return form
    return "recursive" if columns is not None and robot.n >= RECURSIVE_MIN_BODIES else "expanded"


def _recursive_columns(robot: Robot, rows: str, res, cert):
    """DRNG's span of a tree as independent compact columns, for ``form="recursive"``; or refuse in one line."""
    from .nullspace.structured import independent_columns

    why = None
    if robot.has_loops:
        why = "the robot has loops"
    elif cert is not None and cert.completed:
        why = f"{cert.completed} nullspace directions were completed numerically (no compact form)"
    cols = None if why else independent_columns(robot, res)
    if cols is None:
        why = why or "DRNG's columns have no echelon form body by body"
        raise BaseparamsError(f"robot {robot.name!r}: form='recursive' needs a tree whose nullspace DRNG spans in "
                              f"compact columns; here {why}: use form='expanded' (--form expanded)")
    return cols


@dataclass(frozen=True, eq=False)
class Practical:
    """Directions counted out of the base parameters as not identifiable in practice.

    The model file states some geometry to within rounding of a special value
    (:mod:`baseparams.model.snap`); taken literally it adds directions whose torques are below
    :data:`~baseparams.model.snap.SNAP_TOL` of the others' at the file's own scales. The analysis
    is that of the model with the special values, whose count is decided at a gap.

    Parameters
    ----------
    literal_n_base : int or None
        The count of the model exactly as the file states it (``analyze(..., literal=True)``);
        None when no gap decides it (``undecided``).
    snaps : tuple of Snap
        The values that change the count (each one's file element, literal and special value).
    candidates : int
        How many values within the tolerance were found (those that do not change the count
        are taken as the file states them).
    tol : float
        The tolerance (rad, or relative to the robot's size).
    size : float
        The robot's size the offsets are relative to [m].
    source : Robot
        The model as the file states it.
    """

    __repr__ = summary_repr

    literal_n_base: int | None
    snaps: tuple
    candidates: int
    tol: float
    size: float
    source: Robot

    def counted_out(self, n_base: int) -> int | None:
        """Directions counted out.

        Parameters
        ----------
        n_base : int
            The practical count.

        Returns
        -------
        int or None
            ``literal_n_base - n_base`` (None when the literal count is undecided).
        """
        return None if self.literal_n_base is None else self.literal_n_base - n_base

    def note(self, n_base: int) -> str:
        """One line: how many directions, which values of the file, why, and the flag for the literal count.

        Parameters
        ----------
        n_base : int
            The practical count.

        Returns
        -------
        str
            The note.
        """
        k = self.counted_out(n_base)
        what = "; ".join(s.describe() for s in self.snaps)
        many = f"{len(self.snaps)} value{'s' if len(self.snaps) != 1 else ''} of the file taken exact"
        head = (f"practical identifiability: the literal count is not decided (no gap), {n_base} base parameters with "
                f"{many}" if k is None else
                f"practical identifiability: {k} direction{'s' if k != 1 else ''} counted out "
                f"({self.literal_n_base} -> {n_base} base parameters) with {many}")
        return (f"{head}: {what}; geometry within {self.tol:g} (rad, or of the robot's {self.size:.3g} m size, or "
                f"of an axis' length) of a right angle or zero is taken as that value, the directions it adds moving "
                f"the torques by less than {self.tol:g} of their scale (not identifiable in practice); the literal "
                f"count: --literal")

    def to_json(self, n_base: int) -> dict:
        """The decision, machine-readable.

        Parameters
        ----------
        n_base : int
            The practical count.

        Returns
        -------
        dict
            ``literal_n_base, counted_out, tolerance, size, candidates, snaps[{joint, element, what,
            component, literal, text, special, new, deviation}], note``.
        """
        return {"literal_n_base": self.literal_n_base, "counted_out": self.counted_out(n_base),
                "tolerance": self.tol, "size": self.size, "candidates": self.candidates,
                "snaps": [s.to_json() for s in self.snaps], "note": self.note(n_base)}


def _decided(a: Analysis) -> bool:
    """Whether an analysis states its count at a gap (certified, completed, or DRNG's unverified span)."""
    return a.status.ok or a.status == Status.UNVERIFIED


def _snap_candidates(robot: Robot):
    """``(values near a special value, the robot with some of them exact)``: the file's, else the model's."""
    from .model.snap import file_source, near_special, snapped

    if file_source(robot) is not None:  # the readers only for a robot read from a file
        from .io.snapfile import file_snaps, reread

        found = file_snaps(robot)
        if found is not None:
            return found, lambda snaps: reread(robot, snaps)
    return near_special(robot), lambda snaps: snapped(robot, snaps)


def _quick_rank(robot: Robot, kw: dict):
    """The literal rank decision of ``robot`` alone (no DRNG): the stacked regressor on ``pi / d``, its SVD.

    Unless ``samples`` is given, three rows per parameter (and 20 states more): the bisection's many
    comparisons need no more (a loop robot's default, 5 000 actuated samples, took 0.5 s a comparison).
    """
    from .model.scale import decision_scale
    from .numerics import rank_decision, row_mask, stacked_regressor

    d = decision_scale(robot, "paper")
    rows = kw.get("rows", "all")
    per = len(robot.actuated) if robot.has_loops else int(row_mask(robot, rows).sum())
    samples = kw.get("samples") or 20 + int(np.ceil(30 * robot.n / max(per, 1)))
    return rank_decision(stacked_regressor(robot, samples, kw.get("seed", 0), rows) * d)


def _responsible(found: list, make, target: int, kw: dict) -> list:
    """The values (grouped by element) whose literal value raises the count above ``target`` (bisection)."""
    groups: dict = {}
    for s in found:
        groups.setdefault(s.key[:3] if s.key else s.body, []).append(s)
    keys = list(groups)

    def raises(group: list) -> bool:  # un-snapping these elements brings directions back (or no gap decides)
        num = _quick_rank(make([s for s in found if (s.key[:3] if s.key else s.body) not in group]), kw)
        return not num.decided or num.rank > target

    out: list = []

    def bisect(group: list) -> None:
        if not raises(group):
            return
        if len(group) == 1:
            out.extend(groups[group[0]])
            return
        half = len(group) // 2
        bisect(group[:half])
        bisect(group[half:])

    bisect(keys)
    return out


def practical_analysis(lit: Analysis, kw: dict, ref: Analysis | None = None) -> Analysis:
    """The analysis with geometry stated to within rounding of a special value taken as that value.

    The values are the file's own where the robot was read from a file and not changed since
    (:func:`baseparams.io.snapfile.file_snaps`, each named by its element), else the model's
    frames (:func:`baseparams.model.snap.near_special`). When the model with every such value
    exact states its count at a gap (certified or completed, literally or by effect) and that
    count is below the file's as written (``ref``; any count when that one is not decided), the
    values responsible are found by bisection over the file's elements (keeping a group as
    written: the count rises, or no gap decides) and the analysis of the model with them exact is
    returned with :class:`Practical`; otherwise ``ref``. Snapping that does not lower the count
    (a frame turned by a chance near-right angle that moves a designed axis) is not used.

    Parameters
    ----------
    lit : Analysis
        The literal analysis.
    kw : dict
        :func:`analyze`'s keywords (as the literal analysis ran).
    ref : Analysis, optional
        The file as written, decided by effect where the literal gap cannot (default ``lit``).

    Returns
    -------
    Analysis
        ``ref`` or the snapped model's analysis.
    """
    from dataclasses import replace

    from .model.snap import SNAP_TOL, robot_size

    ref = lit if ref is None else ref
    robot = lit.robot
    found, make = _snap_candidates(robot)
    if not found:
        return ref
    try:
        snap_all = _analyze(make(found), **kw)
    except BaseparamsError:  # the file read again with the values exact is refused: taken as it is
        return ref
    if not _decided(snap_all) or (_decided(ref) and snap_all.n_base >= ref.n_base):
        return ref
    snaps, final = tuple(found), snap_all
    quick = _quick_rank(snap_all.robot, kw)
    if quick.decided and quick.rank == snap_all.n_base and len(found) > 1:
        part = tuple(_responsible(found, make, snap_all.n_base, kw))
        if part and len(part) < len(found):
            trial = _analyze(make(part), **kw)
            if _decided(trial) and trial.n_base == snap_all.n_base:
                snaps, final = part, trial
    literal = lit.n_base if _decided(lit) else None
    return replace(final, practical=Practical(literal, snaps, len(found), SNAP_TOL, robot_size(robot), robot))


def _large_tree_columns(robot: Robot, rows: str, res):
    """Without certification, DRNG's span of a large tree as independent compact columns (or None)."""
    from .nullspace.certify import uses_structured
    from .nullspace.structured import independent_columns

    return independent_columns(robot, res) if uses_structured(robot, rows) else None


#: measured peak memory per squared body count [bytes]: certified analysis, and DRNG + regrouping
#: alone (random serial chains of 50-800 bodies on the benchmark machine; the dense factors of
#: the 10 n parameter columns dominate)
BYTES_PER_N2 = {True: 25e3, False: 8e3}


#: a tree certified body by body and regrouped in recursive form (``certify``'s structured path; the
#: expanded form is written from it a block of rows at a time): bytes per body (the sampled wrench
#: maps, the columns)
BYTES_PER_BODY = 200e3


#: the most the numerical method's sampled regressor may take [bytes] (samples x rows x 10 n numbers)
SAMPLES_MAX_BYTES = 1 << 30


def _check_samples_memory(robot: Robot, samples: int | None) -> None:
    """Refuse ``samples`` whose sampled regressor (samples x dof x 10 n numbers) exceeds :data:`SAMPLES_MAX_BYTES`."""
    if samples is None:
        return
    need = 8.0 * samples * max(robot.dof, 1) * 10 * robot.n * (3 if robot.has_loops else 1)
    if need > SAMPLES_MAX_BYTES:
        most = int(SAMPLES_MAX_BYTES / (need / samples))
        raise BaseparamsError(f"samples={samples}: the numerical method would hold {need / 2**30:.3g} GB for robot "
                              f"{robot.name!r} ({robot.dof} dofs, {robot.n} bodies); at most {most} samples here")


def _check_memory(robot: Robot, verify: bool, rows: str = "all", form: str = "auto") -> None:
    """Refuse, before allocating, a model whose analysis needs more memory than is available."""
    from .nullspace.certify import uses_structured

    structured = uses_structured(robot, rows)  # certified body by body (or not), regrouped in recursive form
    if structured:
        need = BYTES_PER_BODY * robot.n  # linear in either form: the expanded one is written as it is made
    else:
        need = BYTES_PER_N2[bool(verify)] * robot.n**2
    have = _available_bytes()
    if have is None or need <= have:
        return
    if structured:
        raise BaseparamsError(f"robot {robot.name!r}: {robot.n} bodies: the analysis needs about "
                              f"{need / 1e9:.2g} GB and {have / 1e9:.2g} GB are available")
    hint = ("; --no-verify gives DRNG's geometric answer without the numerical certificate "
            f"(about {BYTES_PER_N2[False] * robot.n**2 / 1e9:.2g} GB)" if verify else "")
    raise BaseparamsError(f"robot {robot.name!r}: {robot.n} bodies: the {'certified ' if verify else ''}analysis "
                          f"needs about {need / 1e9:.2g} GB (it grows with the square of the body count) and "
                          f"{have / 1e9:.2g} GB are available{hint}")


def format_report(a: Analysis) -> str:
    """Human-readable report (what ``baseparams analyze MODEL`` prints).

    Parameters
    ----------
    a : Analysis
        The result of :func:`analyze`.

    Returns
    -------
    str
        The text report: base parameters in ``a.convention`` and in ``paper`` (world frame at q = 0).
    """
    return "\n".join(report_lines(a))


def report_lines(a: Analysis) -> Iterator[str]:
    """:func:`format_report` line by line, the expressions made as they are written (bounded memory).

    Parameters
    ----------
    a : Analysis
        The result of :func:`analyze`.

    Yields
    ------
    str
        One line of the report (no newline).
    """
    r, c, j = a.robot, a.certificate, a._json(False)
    loops = (f", {len(r.couplings)} coupled joints (linear couplings), {len(r.actuated)} actuated" if r.only_couplings
             else f", {len(r.loops)} loop joints, {len(r.actuated)} actuated" if r.has_loops else "")
    out = [(f"{r.name}: {r.n} bodies, {10 * r.n} standard parameters, {r.dof} dofs{loops}, "
            f"{'floating' if r.floating else 'fixed'} base, gravity {r.gravity.tolist()} m/s^2, rows: {a.rows}"),
           (f"nullspace dimension {a.nullity}  ->  {j['n_base']} base parameters" if a.status != Status.UNDECIDED else
            f"nullspace dimension at least {a.nullity} (DRNG's span)  ->  at most {j['n_base']} base parameters: "
            f"no gap decides the count (UNDECIDED)"),
           *decision_lines(j["rank_decision"]),
           *([a.practical.note(a.n_base)] if a.practical is not None else []),
           *([c.practical.note()] if c is not None and c.practical is not None else []),
           f"DRNG: {a.drng_columns} columns of rank {a.drng_rank} in {a.drng_seconds * 1e3:.2f} ms",
           *(f"  note: {note}" for note in a.drng_notes)]
    for src in Source:
        if src is not Source.NUMERICAL and src.label in a.by_principle:
            kind = ("paper" if src.is_paper else "measured rows: joint torques only" if src is Source.UNMEASURED
                    else "measured rows: unmeasured joints" if src.is_rows else "extended rule")
            out.append(f"  {src.label:<27s} {a.by_principle[src.label]:4d}  ({kind})")
    if c is None:
        out.append("certification: skipped (--no-verify); the nullity above is DRNG's rank, unverified")
        if a.rows == "base" and r.floating:
            out.append("  measured rows: the base wrench alone sees every direction the full dynamics see "
                       "(Ayusawa et al. 2014); unverified here")
    else:
        nm = c.numerical
        out.append(f"  {Source.NUMERICAL.label:<27s} {c.completed:4d}  (completed from the numerical nullspace)")
        out.append("  geometric span complete: " + ("yes" if c.status == Status.CERTIFIED else "no"))
        out.append(f"numerical method: {nm.samples} samples, rank {nm.rank}, nullity {nm.nullity}, "
                   f"tolerance {nm.tol:.3g}, singular-value gap {nm.gap:.3g}, {nm.seconds * 1e3:.1f} ms")
        if r.only_couplings and c.sampling:
            out.append(f"  coupled joints: {c.sampling['requested']} samples of the actuated coordinates, the coupled "
                       f"ones set by their couplings (linear: none discarded)")
        elif r.has_loops and c.sampling:
            sm = c.sampling
            out.append(f"  loop sampling: {sm['kept']} of {sm['requested']} actuated samples kept "
                       f"({sm['not_converged']} outside the workspace, {sm['branch_jumps']} off the reference branch "
                       f"or past a singular configuration, {sm['ill_conditioned']} with cond(J_p) >= "
                       f"{sm['cond_max']:.3g}); max loop residual "
                       f"{sm['max_loop_residual']:.1e}")
            out.extend(f"  loop motion: {line}" for line in sm.get("motion", ()))
        out.append(f"certification: {c.status.upper()} - {c.message}")
        out.append(f"  residual ||W B||/||W|| = {c.residual:.2e}, worst column {c.max_column_residual:.2e}")
    yield from out
    yield from _expressions_section(a, j)
    yield f"\ntotal {a.seconds * 1e3:.1f} ms"


def _expressions_section(a: Analysis, j: dict) -> Iterator[str]:
    """The report's lines of base parameters (and the recursive form's regrouped ones), both conventions."""
    from .model import inertia as _inertia

    out: list[str] = [*size_notes(a)]
    out.append("")
    rec = a.form == "recursive"
    how = ("; recursive form: each in its body's own standard parameters and its children's regrouped "
           "dependent parameters NAMER, defined after the list (--form expanded writes them out)" if rec
           else "")  # the expanded form: today's header
    out.append(f"base parameters ({_inertia.describe(a.base.convention)}{how}):")
    yield from out
    yield from (f"  {e['name']} = {e['expression']}" for e in a.base.iter_expressions(a.form))
    if rec:
        yield "regrouped dependent parameters (root side first):"
        yield from (f"  {e['name']} = {e['expression']}" for e in a.regrouped())
    if len(a.base.unidentifiable):
        yield "unidentifiable standard parameters: " + ", ".join(j["unidentifiable"])
    yield ""
    yield f"the same in the paper's convention ({_inertia.describe('paper')}{'; recursive form' if rec else ''}):"
    yield from (f"  {e['name']} = {e['expression']}" for e in a.base_paper.iter_expressions(a.form))
    if rec:
        yield "regrouped dependent parameters (paper convention):"
        yield from (f"  {e['name']} = {e['expression']}" for e in a.base_paper.definitions())


def json_chunks(a: Analysis) -> Iterator[str]:
    """``json.dumps(a.to_json(), indent=2)`` in pieces, the lists of expressions made as they are written.

    Parameters
    ----------
    a : Analysis
        The result of :func:`analyze`.

    Yields
    ------
    str
        Consecutive pieces of the JSON text (joined: exactly ``json.dumps(a.to_json(), indent=2)``).
    """
    import json

    lists = {"base_parameters": lambda: a.base.iter_expressions(a.form),
             "base_parameters_paper": lambda: a.base_paper.iter_expressions(a.form),
             "regrouped_parameters": a.regrouped,
             "regrouped_parameters_paper": lambda: a.base_paper.definitions() if a.form == "recursive" else []}
    head = a._json(False)
    marks = {key: f"@@{key}@@" for key in lists}
    text = json.dumps({k: marks.get(k, v) for k, v in head.items()}, indent=2)
    for key, make in lists.items():
        before, text = text.split(json.dumps(marks[key]), 1)
        yield before
        first = True
        for item in make():
            yield ("[" if first else ",") + "\n    " + json.dumps(item, indent=2).replace("\n", "\n    ")
            first = False
        yield "[]" if first else "\n  ]"
    yield text


def size_notes(a: Analysis) -> list[str]:
    """One line each when the expressions are huge or carry coefficients double precision cannot.

    Parameters
    ----------
    a : Analysis
        The result of :func:`analyze`.

    Returns
    -------
    list of str
        ``note: ...`` lines (``[]`` for the usual robot): the expanded form's terms past
        :data:`EXPANDED_NOTE_TERMS` (with ``--form recursive`` named), and coefficients past
        ``1 / eps`` (:data:`COEFFICIENT_NOTE`) next to the unit coefficient of each base
        parameter's own standard parameter.
    """
    if a.form != "expanded":
        return []
    out = []
    terms = a.base.expanded_size()[0] + (a.base_paper.expanded_size()[0] if a.base.convention != "paper" else 0)
    if terms > EXPANDED_NOTE_TERMS:
        out.append(f"note: the expanded form writes {terms / 1e6:.3g} million terms ({a.robot.n} bodies: they grow "
                   f"with each body's depth in the tree); --form recursive writes the same regrouping in linear size")
    pairs = [(a.base.convention, a.base)] + ([("paper", a.base_paper)] if a.base.convention != "paper" else [])
    big = {name: b.expanded_size()[1] for name, b in pairs}
    over = [name for name, v in big.items() if v > COEFFICIENT_NOTE]
    if over:
        worst = max(big[name] for name in over)
        which = "both conventions" if len(over) == 2 else f"the {over[0]} convention"
        out.append(f"note: coefficients up to {worst:.2g} in {which}: past 1/eps = {1 / np.finfo(float).eps:.2g}, "
                   f"a base parameter's own standard parameter is lost next to them in double precision "
                   f"(values computed from these expressions carry no digits of it)")
    return out


#: the expanded form's terms (both conventions) past which :func:`size_notes` says so
EXPANDED_NOTE_TERMS = 1_000_000
#: a regrouping coefficient past this (``1 / eps``) is noted (:func:`size_notes`)
COEFFICIENT_NOTE = 1.0 / float(np.finfo(float).eps)
