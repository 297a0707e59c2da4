"""Built-in robots: ``get("puma560")``, ``get("go2")``, and ``random_robot`` / ``special_robot`` for tests."""

from __future__ import annotations

import importlib
from collections.abc import Callable

from ..errors import BaseparamsError
from ..model import Robot
from .go2 import go2  # light: it imports the MJCF reader when called
from .puma560 import puma560

#: the other robots' modules are imported when first used (start-up time of a one-shot command)
_LAZY = {"four_bar": "loops", "parallelogram": "loops", "pkm_2prs_1psr": "loops",
         "pkm_2rru_1rrs": "loops", "random_robot": "random", "special_robot": "random"}


def __getattr__(name: str):
    """The loop robots and the random-robot generators, imported on first use."""
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _factory(name: str, *args) -> Callable[..., Robot]:
    """A factory ``f(gravity=...)``: ``name(*args, gravity=...)`` of its module, imported on the call.

    Without ``gravity`` the robot's own default applies.
    """

    def make(**kw) -> Robot:
        return __getattr__(name)(*args, **kw)

    make.__name__ = name
    return make


#: name -> (factory(gravity=...), one-line description)
BUILTINS: dict[str, tuple[Callable[..., Robot], str]] = {
    "puma560": (puma560, "Puma560 arm, 6R, standard DH (Corke), fixed base"),
    "go2": (go2, "Unitree Go2 quadruped, floating base + 4 x RRR legs (Menagerie MJCF)"),
    "pkm-2rru-1rrs": (_factory("pkm_2rru_1rrs"), "2RRU-1RRS parallel kinematic machine (after Xu et al. 2023), 3 DOF"),
    "pkm-2prs-1psr": (_factory("pkm_2prs_1psr", False),
                      "2PRS-1PSR parallel kinematic machine (after Shi et al. 2023), 3 DOF"),
    "pkm-2prs-1psr-symmetric": (_factory("pkm_2prs_1psr", True),
                                "2PRS-1PSR, mirror-symmetric: PRS limbs opposite (nullity 48)"),
    "four-bar": (_factory("four_bar"), "planar four-bar linkage, crank actuated"),
    "parallelogram": (_factory("parallelogram"), "planar parallelogram four-bar (a known gap of the principles)"),
}


def get(name: str, gravity=None) -> Robot:
    """A built-in robot by name.

    Parameters
    ----------
    name : str
        A key of :data:`BUILTINS` (any case), e.g. ``puma560``, ``go2``, ``four-bar``.
    gravity : array_like, shape ``(3,)``, optional
        Gravity [m/s^2] in the world frame; overrides the robot's default.

    Returns
    -------
    Robot
        The robot.

    Raises
    ------
    BaseparamsError
        Not a built-in robot (the message lists them).
    """
    key = name.lower()
    if key not in BUILTINS:
        raise BaseparamsError(f"unknown robot {name!r}; built-in robots: {', '.join(BUILTINS)}")
    factory = BUILTINS[key][0]
    return factory() if gravity is None else factory(gravity=gravity)


__all__ = ["BUILTINS", "four_bar", "get", "go2", "parallelogram", "pkm_2prs_1psr", "pkm_2rru_1rrs", "puma560",
           "random_robot", "special_robot"]
