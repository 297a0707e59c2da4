"""Kinematics: body displacements, twists, accelerations, Jacobian lines (batched)."""

from .tree import TreeState, forward_kinematics, re_reference

__all__ = ["TreeState", "forward_kinematics", "re_reference"]
