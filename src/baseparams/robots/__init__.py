"""Built-in robots: ``get("puma560")``, ``get("go2")``, and ``random_robot`` for tests."""

from __future__ import annotations

from collections.abc import Callable

from ..errors import BaseparamsError
from ..model import Robot
from .go2 import go2
from .puma560 import puma560
from .random import random_robot

#: name -> (factory(gravity=...), one-line description)
BUILTINS: dict[str, tuple[Callable[..., Robot], str]] = {
    "puma560": (puma560, "Puma560 arm, 6R, standard DH (Corke), fixed base"),
    "go2": (go2, "Unitree Go2 quadruped, floating base + 4 x RRR legs (Menagerie MJCF)"),
}


def get(name: str, gravity=None) -> Robot:
    """A built-in robot by name (``gravity`` [m/s^2] overrides its default)."""
    key = name.lower()
    if key not in BUILTINS:
        raise BaseparamsError(f"unknown robot {name!r}; built-in robots: {', '.join(BUILTINS)}")
    factory = BUILTINS[key][0]
    return factory() if gravity is None else factory(gravity=gravity)


__all__ = ["BUILTINS", "get", "go2", "puma560", "random_robot"]
