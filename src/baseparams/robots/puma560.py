"""Puma560: standard Denavit-Hartenberg parameters and inertias as in Corke's Robotics Toolbox.

As Corke's ``mdl_puma560``, with link 1 given a mass (Corke leaves it at 0 kg, which hides
nothing from the base-parameter analysis but is not physical).

Standard DH: joint ``i`` rotates about ``z_{i-1}``; link ``i``'s frame is
``T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. The link inertias are given in
the DH link frames (centre of mass ``r``, principal inertias ``I`` about the centre of mass).
Reference configuration: q = 0 (all DH angles zero). Default gravity: along joint 1
(``-z``), for which the paper and Khalil give 36 base parameters (24 nullspace directions).
"""

from __future__ import annotations

import numpy as np

from ..model import Inertia, Robot, RobotBuilder

#: (a [m], alpha [rad], d [m]) per joint, standard DH (Corke).
DH = (
    (0.0, np.pi / 2, 0.0),
    (0.4318, 0.0, 0.0),
    (0.0203, -np.pi / 2, 0.15005),
    (0.0, np.pi / 2, 0.4318),
    (0.0, -np.pi / 2, 0.0),
    (0.0, 0.0, 0.0),
)
#: mass [kg], centre of mass [m] and principal inertias [kg m^2] in the DH link frame.
LINKS = (
    (13.0, (0.0, 0.0, 0.0), (0.35, 0.35, 0.35)),  # Corke: m = 0, Iyy = 0.35 only
    (17.4, (-0.3638, 0.006, 0.2275), (0.13, 0.524, 0.539)),
    (4.8, (-0.0203, -0.0141, 0.070), (0.066, 0.086, 0.0125)),
    (0.82, (0.0, 0.019, 0.0), (1.8e-3, 1.3e-3, 1.8e-3)),
    (0.34, (0.0, 0.0, 0.0), (0.3e-3, 0.4e-3, 0.3e-3)),
    (0.09, (0.0, 0.0, 0.032), (0.15e-3, 0.15e-3, 0.04e-3)),
)


def dh_offset(a: float, alpha: float, d: float) -> np.ndarray:
    """``Tz(d) Tx(a) Rx(alpha)``: link frame ``i`` in joint ``i``'s frame (theta applied by the joint).

    Parameters
    ----------
    a : float
        Link length [m] (along the new x).
    alpha : float
        Link twist [rad] (about the new x).
    d : float
        Link offset [m] (along the joint's z).

    Returns
    -------
    ndarray, shape ``(4, 4)``
        The homogeneous transform.
    """
    ca, sa = np.cos(alpha), np.sin(alpha)
    return np.array([[1, 0, 0, a], [0, ca, -sa, 0], [0, sa, ca, d], [0, 0, 0, 1.0]])


def puma560(gravity=(0.0, 0.0, -9.81)) -> Robot:
    """The Puma560 arm (6 R joints, 6 bodies, 60 parameters).

    Parameters
    ----------
    gravity : array_like, shape ``(3,)``
        Gravity [m/s^2] in the world frame. The default, along joint 1 (``-z``), gives 36 base
        parameters (24 nullspace directions).

    Returns
    -------
    Robot
        Bodies ``link1`` ... ``link6`` (joints ``joint1`` ... ``joint6``), inertias in the DH
        link frames.
    """
    b = RobotBuilder("puma560", gravity=gravity)
    parent, origin = None, np.eye(4)
    for i, ((a, alpha, d), (m, r, inertia)) in enumerate(zip(DH, LINKS), start=1):
        off = dh_offset(a, alpha, d)
        b.add_link(f"link{i}", parent=parent, joint="R", origin=origin, axis=(0, 0, 1),
                   inertia=Inertia(m, com=r, inertia=inertia, frame=off), joint_name=f"joint{i}")
        parent, origin = f"link{i}", off
    return b.build()
