"""Built-in robots: ``get("puma560")``, ``get("go2")``, and ``random_robot`` / ``special_robot`` for tests."""

from __future__ import annotations

from collections.abc import Callable

from ..errors import BaseparamsError
from ..model import Robot
from .go2 import go2
from .loops import four_bar, parallelogram, pkm_2prs_1psr, pkm_2rru_1rrs
from .puma560 import puma560
from .random import random_robot, special_robot

#: name -> (factory(gravity=...), one-line description)
BUILTINS: dict[str, tuple[Callable[..., Robot], str]] = {
    "puma560": (puma560, "Puma560 arm, 6R, standard DH (Corke), fixed base"),
    "go2": (go2, "Unitree Go2 quadruped, floating base + 4 x RRR legs (Menagerie MJCF)"),
    "pkm-2rru-1rrs": (pkm_2rru_1rrs, "2RRU-1RRS parallel kinematic machine (after Xu et al. 2023), 3 DOF"),
    "pkm-2prs-1psr": (pkm_2prs_1psr, "2PRS-1PSR parallel kinematic machine (after Shi et al. 2023), 3 DOF"),
    "pkm-2prs-1psr-symmetric": (lambda gravity=(0.0, 0.0, -9.81): pkm_2prs_1psr(True, gravity),
                                "2PRS-1PSR, mirror-symmetric: PRS limbs opposite (nullity 48)"),
    "four-bar": (four_bar, "planar four-bar linkage, crank actuated"),
    "parallelogram": (parallelogram, "planar parallelogram four-bar (a known gap of the principles)"),
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
