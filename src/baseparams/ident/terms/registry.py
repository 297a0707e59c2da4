"""The model terms by name: :data:`TERMS` (the order model selection tries them), :func:`make_term`.

And :func:`term_schema`: what a saved result holds of each.
"""

from __future__ import annotations

from ... import schema as sc
from ...errors import BaseparamsError
from .base import Term
from .dahl import Dahl
from .delay import Delay
from .scale import Scale
from .tilt import Tilt


def registry() -> dict:
    """The terms by name.

    Returns
    -------
    dict
        ``{name: Term subclass}``.
    """
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
    reg = registry()
    if name not in reg:
        raise BaseparamsError(f"unknown model term {name!r}; choose from {', '.join(TERMS)}")
    return reg[name](forced=forced)


def term_schema() -> sc.Tagged:
    """The node of one saved term: by its ``name``, that term's own :meth:`~baseparams.ident.terms.base.Term.schema`.

    Returns
    -------
    Tagged
        Checked when a result is written and when it is read back
        (:data:`baseparams.ident.saved.RESULT`).
    """
    reg = registry()
    return sc.Tagged("name", {name: reg[name].schema() for name in TERMS})
