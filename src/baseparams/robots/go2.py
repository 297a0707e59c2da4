"""Unitree Go2 quadruped: floating base + 4 legs x (abduction, hip, knee) R joints.

Kinematics and inertias are read from MuJoCo Menagerie's ``unitree_go2/go2.xml`` (BSD-3,
licence beside the file in ``data/unitree_go2``). 13 bodies, 130 parameters, 18 dofs.
"""

from __future__ import annotations

import warnings

from ..model import Robot


def go2(gravity=(0.0, 0.0, -9.81)) -> Robot:
    """The Go2 (F root at the base body's frame, then four RRR legs).

    Parameters
    ----------
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame.

    Returns
    -------
    Robot
        13 bodies, 130 parameters, 18 dofs.
    """
    from importlib import resources

    from ..io.mjcf import MJCFWarning, load_mjcf  # the MJCF reader for this robot only (start-up time)

    with resources.as_file(resources.files(__package__) / "data" / "unitree_go2" / "go2.xml") as p, \
            warnings.catch_warnings():
        # the shipped file has no meshes on purpose: its inertias are explicit
        warnings.filterwarnings("ignore", message=".*missing asset files", category=MJCFWarning)
        return load_mjcf(p, name="go2", gravity=gravity)
