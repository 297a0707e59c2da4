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

A saved result keeps each term's parameters; every field is declared once, on its term
(:attr:`Term.FIELDS`, :attr:`Term.STD`, :meth:`Term.rule`): type, shape, physical bounds, and for a
value per joint, exactly one per measured joint (:func:`per_joint`). :meth:`Term.schema` makes the
node the saved file is checked against when it is written and when it is read
(:func:`baseparams.ident.terms.registry.term_schema`); :meth:`Term.load` reads only what it
accepted.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ... import schema as sc
from ...display import summary_repr

#: why a saved term with an unknown key is refused
NEWER = " (written by a newer baseparams, or edited? it would predict without it)"


def per_joint(value: sc.Node) -> sc.Map:
    """A saved value per measured joint: keys exactly the result's ``robot.joints``.

    Parameters
    ----------
    value : Node
        Every joint's value.

    Returns
    -------
    Map
        Keyed by the names symbol ``joints``: a joint the robot lacks, or a measured joint left
        out, is refused naming it.
    """
    return sc.Map(value, keys="joints")


def per_row(value: sc.Node) -> sc.Arr:
    """A saved list with one value per measured joint, in ``robot.joints`` order (standard deviations).

    Parameters
    ----------
    value : Node
        Every item's node.

    Returns
    -------
    Arr
        Of length ``m`` (the size symbol of ``robot.joints``).
    """
    return sc.Arr(value, "m")


def stack_rows(parts: list) -> np.ndarray:
    """Per-recording rows stacked in recording order (one recording: its rows themselves).

    Parameters
    ----------
    parts : list of ndarray, each shape ``(S'_r, ...)``
        One array per recording, in the order of :attr:`TermContext.recordings`.

    Returns
    -------
    ndarray, shape ``(sum S'_r, ...)``
        The rows of every recording, in order.
    """
    return parts[0] if len(parts) == 1 else np.concatenate(parts, axis=0)


@dataclass(eq=False)
class TermContext:
    """The fitted rows of a log and the full-rate signals terms build their columns from.

    Several recordings of one robot (:meth:`stacked`): each keeps its own context (its filter,
    full-rate grid and unfiltered positions, :attr:`recordings`); the rows ``a`` and the folds are
    every recording's, stacked. Whatever runs along a recording's time (a derivative, a delay's
    interpolation, Dahl's state) runs on each recording's own context and the rows are stacked
    (:meth:`each`): nothing runs across the boundary between two recordings.

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
        The fitted rows of each contiguous cross-validation block (several recordings: of each recording).
    parts : list of TermContext
        Several recordings: each one's context (``prep``, ``raw_q`` and ``cols`` then None); empty for one.
    """

    __repr__ = summary_repr

    model: object
    a: np.ndarray
    prep: object
    raw_q: np.ndarray
    cols: np.ndarray
    folds: list = field(default_factory=list)
    parts: list = field(default_factory=list)

    @classmethod
    def stacked(cls, contexts: list[TermContext]) -> TermContext:
        """One context of several recordings of one robot, each recording one cross-validation fold.

        Parameters
        ----------
        contexts : list of TermContext
            Each recording's context (its rows ``a`` ``(S'_r, m, p)``, its ``prep``, ``raw_q``, ``cols``).

        Returns
        -------
        TermContext
            Rows ``(sum S'_r, m, p)`` in recording order; ``folds`` the rows of each recording.
        """
        ends = np.cumsum([0] + [len(c.a) for c in contexts])
        folds = [np.arange(s, e) for s, e in zip(ends[:-1], ends[1:])]
        return cls(contexts[0].model, stack_rows([c.a for c in contexts]), None, None, None, folds, list(contexts))

    @property
    def recordings(self) -> list[TermContext]:
        """Each recording's own context (one recording: this one)."""
        return self.parts or [self]

    @property
    def recording_rows(self) -> list[np.ndarray]:
        """The fitted rows of each recording, ``(S'_r,)`` each (one recording: every row)."""
        return self.folds if self.parts else [np.arange(len(self.a))]

    @property
    def fold_unit(self) -> str:
        """What a cross-validation fold is, for the notes: ``blocks`` (of one motion) or ``recordings``."""
        return "recordings" if self.parts else "blocks"

    def each(self, fn) -> np.ndarray:
        """``fn`` on each recording's own context, the rows stacked (:func:`stack_rows`).

        Parameters
        ----------
        fn : callable
            ``fn(ctx)`` of one recording's context: an array ``(S'_r, ...)`` of its fitted rows.

        Returns
        -------
        ndarray, shape ``(S', ...)``
            Every recording's rows, in order.
        """
        return stack_rows([fn(c) for c in self.recordings])

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
        if self.parts:
            return self.each(lambda c: c.tau)
        return self.prep.tau[:, self.cols[self.model.row_states]]

    @property
    def tau_full(self) -> np.ndarray:
        """The filtered measured torques at the full rate ``(S, m)``, measured-row order."""
        return self.prep.full.tau[:, self.cols[self.model.row_states]]

    @property
    def joints(self) -> list[str]:
        """The measured joints ``(m,)``."""
        return self.model.joints

    def apply(self, x) -> np.ndarray:
        """Full-rate signals filtered and decimated like the fitted rows.

        Parameters
        ----------
        x : array_like, shape ``(S, ...)``
            One row per full-rate sample.

        Returns
        -------
        ndarray, shape ``(S', ...)``
            :meth:`baseparams.ident.preprocess.Prepared.apply` of ``x``.
        """
        if self.parts:
            raise ValueError("apply() of several recordings: filter each one's rows on its own (each())")
        return self.prep.apply(x)


def complete_docs(klass):
    """Class decorator: each override's docstring gets the base method's sections (parameters, returns).

    A term's method says what it does in its own summary; its arguments and result are the
    interface's (:class:`Term`), written once there.

    Parameters
    ----------
    klass : type
        A subclass of :class:`Term`.

    Returns
    -------
    type
        ``klass``, its overrides' docstrings completed.
    """
    import inspect

    for name, member in vars(klass).items():
        base = getattr(Term, name, None)
        if name.startswith("_") or not inspect.isfunction(member) or base is None or not base.__doc__:
            continue
        own = inspect.cleandoc(member.__doc__ or "").split("\n\n")
        sections = inspect.cleandoc(base.__doc__).split("\n\n")
        rest = [p for p in sections if p.lstrip().split("\n")[0] in ("Parameters", "Returns", "Raises")
                or (len(p.split("\n")) > 1 and set(p.split("\n")[1].strip()) == {"-"})]
        member.__doc__ = "\n\n".join([*(own if own != [""] else sections[:1]), *rest])
    return klass


class Term:
    """One model term (module docstring). Subclasses set :attr:`name` and override what they use.

    Parameters
    ----------
    forced : bool
        Kept whatever the cross-validation says (the user asked for it).

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
    #: its saved parameters (``values`` of :meth:`to_json`): field -> schema node, each required
    FIELDS: dict = {}
    #: its saved standard deviations (``std``): field -> schema node, each optional
    STD: dict = {}

    @classmethod
    def rule(cls, values: dict) -> str | None:
        """A check across its saved fields (each already within its own bounds).

        Parameters
        ----------
        values : dict
            The checked ``values`` of a saved term.

        Returns
        -------
        str or None
            What is wrong, in one phrase, or None.
        """
        return None

    @classmethod
    def schema(cls) -> sc.Obj:
        """The node a saved term of this kind is checked against, on save and on load.

        Returns
        -------
        Obj
            ``{"name", "forced", "values": FIELDS (all required, checked by rule), "std": STD}``;
            unknown keys refused.
        """
        return sc.Obj({"name": sc.Enum((cls.name,)), "forced": sc.Field(sc.Bool(), False),
                       "values": sc.Obj(dict(cls.FIELDS), extra="refuse", rule=cls.rule, hint=NEWER),
                       "std": sc.Field(sc.Obj({k: sc.Field(v, None) for k, v in cls.STD.items()}, extra="refuse",
                                              hint=NEWER), {})}, extra="refuse", hint=NEWER)

    def __init__(self, forced: bool = False):
        self.forced = bool(forced)
        self.std: dict = {}

    def available(self, ctx: TermContext) -> str | None:
        """Why the term cannot be used on this model and log, or None.

        Parameters
        ----------
        ctx : TermContext
            The rows.

        Returns
        -------
        str or None
            One phrase, or None when the term can be used.
        """
        return None

    def prepare(self, ctx: TermContext) -> None:
        """Precompute what does not depend on the parameters (full-rate columns).

        Parameters
        ----------
        ctx : TermContext
            The rows.
        """

    def reset(self, ctx: TermContext) -> None:
        """Start values of its parameters.

        Parameters
        ----------
        ctx : TermContext
            The rows.
        """

    def copy(self) -> Term:
        """An independent copy (its parameters; precomputed columns shared).

        Returns
        -------
        Term
            The copy.
        """
        import copy

        return copy.copy(self)

    # roles -------------------------------------------------------------------------------------------------
    def core(self, ctx: TermContext, x: np.ndarray) -> np.ndarray:
        """The core rows with the term's columns replaced (core role).

        Parameters
        ----------
        ctx : TermContext
            The rows.
        x : ndarray, shape ``(S', m, p)``
            The core rows.

        Returns
        -------
        ndarray, shape ``(S', m, p)``
            The rows (``x`` itself when nothing is replaced).
        """
        return x

    def delays(self, m: int) -> np.ndarray:
        """Delay of each measured channel (measured role).

        Parameters
        ----------
        m : int
            Number of measured rows.

        Returns
        -------
        ndarray, shape ``(m,)``
            [s]; zeros unless a delay term.
        """
        return np.zeros(m)

    def scales(self, m: int) -> np.ndarray:
        """Scale of each measured channel (measured role).

        Parameters
        ----------
        m : int
            Number of measured rows.

        Returns
        -------
        ndarray, shape ``(m,)``
            Ones unless a scale term.
        """
        return np.ones(m)

    def columns(self, ctx: TermContext, state: dict) -> tuple[np.ndarray, list[str]]:
        """Linear columns of this Gauss-Newton step and their names (additive and measured roles).

        Parameters
        ----------
        ctx : TermContext
            The rows.
        state : dict
            ``theta`` (core), ``pi`` (standard parameters, paper convention), ``x`` (core rows
            after replacements), ``y`` (transformed measured rows), ``model`` (``x @ theta``
            plus the additive terms), ``dy`` (time derivative of the shifted measured rows).

        Returns
        -------
        columns : ndarray, shape ``(S', m, k)``
            The columns.
        names : list of str, shape ``(k,)``
            Their coefficients' names.
        """
        return np.zeros(ctx.a.shape[:2] + (0,)), []

    def prior(self) -> tuple[np.ndarray, np.ndarray] | None:
        """A weak prior on the coefficients of :meth:`columns`.

        In the coefficients' units; the fit multiplies the precision by the residual variance
        (like every prior of the default estimate), so a term the data determine keeps its fitted
        value and one they do not stays near the target.

        Returns
        -------
        tuple of ndarray or None
            ``(precision (k,), target (k,))``, or None for no prior.
        """
        return None

    def absorb(self, coefs: np.ndarray, std: np.ndarray | None = None) -> float:
        """Take a Gauss-Newton step's coefficients of :meth:`columns`.

        Parameters
        ----------
        coefs : ndarray, shape ``(k,)``
            The coefficients.
        std : ndarray, shape ``(k,)``, optional
            Their standard deviations (kept in :attr:`std`).

        Returns
        -------
        float
            The largest change, in units of the term's resolution (below 1: converged).
        """
        return 0.0

    def at_bound(self) -> bool:
        """Whether a parameter sits at its bound (the last step was cut there: the core's step assumed more).

        Returns
        -------
        bool
            False unless a bounded parameter is at its bound.
        """
        return False

    def search(self, ctx: TermContext, trial) -> None:
        """A nonlinear search of the term's parameters (none by default).

        Parameters
        ----------
        ctx : TermContext
            The rows.
        trial : callable
            The fit's evaluation of a candidate (the term's own protocol, e.g. Dahl's).
        """

    # prediction ----------------------------------------------------------------------------------------------
    def adjust_model(self, fit, q_raw, q, dq, ddq, tau: np.ndarray) -> np.ndarray:
        """Model torques with this term's contribution (core and additive roles).

        Parameters
        ----------
        fit : Fit
            The identification's fit.
        q_raw : ndarray, shape ``(S, m)``
            The measured coordinates' positions as logged (Dahl's state follows them).
        q, dq, ddq : ndarray, shape ``(S, state_columns)``
            The states the core's torques came from.
        tau : ndarray, shape ``(S, m)``
            The torques so far.

        Returns
        -------
        ndarray, shape ``(S, m)``
            With this term's contribution.
        """
        return tau

    def adjust_measured(self, t: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Model torques as the sensors would measure them (measured role).

        Parameters
        ----------
        t : ndarray, shape ``(S,)``
            Time stamps [s].
        tau : ndarray, shape ``(S, m)``
            The model's torques.

        Returns
        -------
        ndarray, shape ``(S, m)``
            As measured.
        """
        return tau

    # reporting -------------------------------------------------------------------------------------------------
    def values(self, joints: list[str]) -> dict:
        """Its fitted values.

        Parameters
        ----------
        joints : list of str, shape ``(m,)``
            The measured joints.

        Returns
        -------
        dict
            JSON types.
        """
        return {}

    def describe(self, joints: list[str]) -> str:
        """Its values in one phrase.

        Parameters
        ----------
        joints : list of str, shape ``(m,)``
            The measured joints.

        Returns
        -------
        str
            The phrase.
        """
        return self.name

    def export(self) -> dict:
        """What model files can carry of it.

        Returns
        -------
        dict
            ``{"not": [phrases]}`` for what they cannot hold, and what they can
            (``base_rotation`` for a tilt).
        """
        return {"not": [f"{self.label} (not representable in URDF or MJCF)"]}

    def to_json(self, joints: list[str]) -> dict:
        """Its parameters, to save and load.

        Parameters
        ----------
        joints : list of str, shape ``(m,)``
            The measured joints.

        Returns
        -------
        dict
            ``{"name", "forced", "values", "std"}``.
        """
        return {"name": self.name, "forced": self.forced, "values": self.values(joints), "std": self.std}

    def load(self, doc: dict, joints: list[str], model) -> None:
        """Set its parameters from :meth:`to_json`'s output (a saved result).

        Parameters
        ----------
        doc : dict
            The saved term, checked against :meth:`schema` (every field present, in bounds,
            one value per measured joint).
        joints : list of str, shape ``(m,)``
            The measured joints.
        model : IdentModel
            The model it belongs to.
        """
