"""The model terms by name: :data:`TERMS` (the order model selection tries them) and :func:`make_term`."""

from __future__ import annotations

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
