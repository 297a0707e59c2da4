"""Kinematics: body displacements, twists, accelerations, Jacobian lines (batched)."""

from .tree import TreeState, forward_kinematics, re_reference, wrench_forces

__all__ = ["TreeState", "forward_kinematics", "re_reference", "wrench_forces"]
