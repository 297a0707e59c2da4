"""The interface of a model term and what terms build their columns from.

A term (:class:`Term`) plays one or more of these roles in the model of the measured torque of
joint ``j``, ``y_j(t) = s_j M_j(t - d_j)`` with ``M = A' theta + sum_k phi_k T_k``:

* **core** - it replaces columns of the linear core ``A`` (Dahl: the Coulomb columns);
* **additive** - it adds linear columns ``T_k`` whose coefficients are its parameters (tilt);
* **measured** - it changes how a measured torque relates to the model (delay ``d_j``, scale
  ``s_j``): the measured rows are transformed exactly (``y_j(t + d_j) / s_j``) and the
  linearised columns of a Gauss-Newton step are added.

Every term also predicts (:meth:`Term.adjust_model`, :meth:`Term.adjust_measured`), says what it
found (:meth:`Term.describe`, :meth:`Term.to_json`) and what a model file can carry of it
(:meth:`Term.export`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...errors import BaseparamsError


@dataclass(eq=False)
class TermContext:
    """The fitted rows of a log and the full-rate signals terms build their columns from.

    Parameters
    ----------
    model : IdentModel
        The linear core (rigid bodies and drive terms).
    a : ndarray, shape ``(S', m, p)``
        The core regressor's fitted rows: filtered like the torques, decimated
        (:meth:`baseparams.ident.preprocess.Prepared.apply`), in time order.
    prep : Prepared
        The prepared log (its ``full`` log: the filtered full-rate states and torques; ``index``:
        the fitted samples).
    raw_q : ndarray, shape ``(S, m)``
        Unfiltered positions of the measured coordinates (measured-row order) on the full-rate uniform grid
        (``prep.full.t``): Dahl's state follows the path as measured.
    cols : ndarray of int, shape ``(m,)``
        The log column of each state column.
    folds : list of ndarray of int
        The fitted rows of each contiguous cross-validation block.
    """

    model: object
    a: np.ndarray
    prep: object
    raw_q: np.ndarray
    cols: np.ndarray
    folds: list = field(default_factory=list)

    @property
    def t(self) -> np.ndarray:
        """Times of the fitted rows ``(S',)`` [s]."""
        return self.prep.t

    @property
    def t_full(self) -> np.ndarray:
        """Times of the full-rate grid ``(S,)`` [s]."""
        return self.prep.full.t

    @property
    def tau(self) -> np.ndarray:
        """The measured torques of the fitted rows ``(S', m)`` (filtered), measured-row order."""
        return self.prep.tau[:, self.cols[self.model.row_states]]

    @property
    def tau_full(self) -> np.ndarray:
        """The filtered measured torques at the full rate ``(S, m)``, measured-row order."""
        return self.prep.full.tau[:, self.cols[self.model.row_states]]

    @property
    def joints(self) -> list[str]:
        """The measured joints ``(m,)``."""
        r = self.model.robot
        return [r.joint_names[r.dof_body[c]] for c in self.model.coords]

    def apply(self, x) -> np.ndarray:
        """Full-rate signals ``(S, ...)`` filtered and decimated like the fitted rows ``(S', ...)``."""
        return self.prep.apply(x)


class Term:
    """One model term (module docstring). Subclasses set :attr:`name` and override what they use.

    Attributes
    ----------
    name : str
        The term's name (``dahl``, ``tilt``, ``delay``, ``scale``), as the ``terms`` option lists it.
    label : str
        What it is, for the report.
    forced : bool
        Kept whatever the cross-validation says (the user asked for it).
    """

    name = "term"
    label = "a model term"

    def __init__(self, forced: bool = False):
        self.forced = bool(forced)
        self.std: dict = {}

    def available(self, ctx: TermContext) -> str | None:
        """Why the term cannot be used on this model and log (one phrase), or None."""
        return None

    def prepare(self, ctx: TermContext) -> None:
        """Precompute what does not depend on the parameters (full-rate columns)."""

    def reset(self, ctx: TermContext) -> None:
        """Start values of its parameters."""

    def copy(self) -> Term:
        """An independent copy (its parameters and precomputed columns)."""
        import copy

        return copy.copy(self)

    # roles -------------------------------------------------------------------------------------------------
    def core(self, ctx: TermContext, x: np.ndarray) -> np.ndarray:
        """The core rows with its columns replaced (``x`` ``(S', m, p)``; returned, maybe the same)."""
        return x

    def delays(self, m: int) -> np.ndarray:
        """Delay of each measured channel ``(m,)`` [s] (0 unless a delay term)."""
        return np.zeros(m)

    def scales(self, m: int) -> np.ndarray:
        """Scale of each measured channel ``(m,)`` (1 unless a scale term)."""
        return np.ones(m)

    def columns(self, ctx: TermContext, state: dict) -> tuple[np.ndarray, list[str]]:
        """Linear columns ``(S', m, k)`` of this Gauss-Newton step and their names.

        ``state`` holds ``theta`` (core), ``pi`` (standard parameters, paper convention),
        ``x`` (core rows after replacements), ``y`` (transformed measured rows), ``model``
        (``x @ theta`` plus the additive terms), ``dy`` (time derivative of the shifted measured
        rows).
        """
        return np.zeros(ctx.a.shape[:2] + (0,)), []

    def prior(self) -> tuple[np.ndarray, np.ndarray] | None:
        """A weak prior on the coefficients of :meth:`columns`: ``(precision, target)`` or None.

        In the coefficients' units; the fit multiplies the precision by the residual variance
        (like every prior of the default estimate), so a term the data determine keeps its fitted
        value and one they do not stays near the target.
        """
        return None

    def absorb(self, coefs: np.ndarray, std: np.ndarray | None = None) -> float:
        """Take a step's coefficients of :meth:`columns`; return its largest relative change."""
        return 0.0

    def search(self, ctx: TermContext, score) -> None:
        """A nonlinear search (``score(term) -> float``, the training error with the term as it is)."""

    # prediction ----------------------------------------------------------------------------------------------
    def adjust_model(self, fit, q_raw, q, dq, ddq, tau: np.ndarray) -> np.ndarray:
        """Model torques ``(S, m)`` with this term's contribution (core and additive roles).

        ``q_raw (S, m)``: the measured coordinates' positions as logged (Dahl's state follows
        them); ``q, dq, ddq (S, state_columns)``: the states the core's torques ``tau`` came from.
        """
        return tau

    def adjust_measured(self, t: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Model torques ``(S, m)`` as the sensors would measure them (measured role)."""
        return tau

    # reporting -------------------------------------------------------------------------------------------------
    def values(self, joints: list[str]) -> dict:
        """Its fitted values (JSON types)."""
        return {}

    def describe(self, joints: list[str]) -> str:
        """Its values in one phrase."""
        return self.name

    def export(self) -> dict:
        """What model files can carry: ``{"mjcf": ..., "urdf": ..., "not": [phrases]}``."""
        return {"not": [f"{self.label} (not representable in URDF or MJCF)"]}

    def to_json(self, joints: list[str]) -> dict:
        """Its parameters, to save and load."""
        return {"name": self.name, "forced": self.forced, "values": self.values(joints), "std": self.std}

    def load(self, doc: dict, joints: list[str], model) -> None:
        """Set its parameters from :meth:`to_json`'s output (a saved result)."""


def _registry() -> dict:
    from .dahl import Dahl
    from .delay import Delay
    from .scale import Scale
    from .tilt import Tilt

    return {"dahl": Dahl, "tilt": Tilt, "delay": Delay, "scale": Scale}


#: the terms, in the order model selection tries them
TERMS = ("dahl", "tilt", "delay", "scale")


def make_term(name: str, forced: bool = False) -> Term:
    """A term by name.

    Parameters
    ----------
    name : str
        One of :data:`TERMS`.
    forced : bool
        Kept whatever the cross-validation says.

    Returns
    -------
    Term
        The term with its start values.

    Raises
    ------
    BaseparamsError
        An unknown name.
    """
    reg = _registry()
    if name not in reg:
        raise BaseparamsError(f"unknown model term {name!r}; choose from {', '.join(TERMS)}")
    return reg[name](forced=forced)
