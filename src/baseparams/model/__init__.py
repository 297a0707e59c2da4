"""Robot model: bodies, tree joints, loop joints, gravity, inertial parameters."""

from .builder import RobotBuilder, joint_type, pose, quat_pose
from .inertia import CONVENTIONS, Inertia
from .robot import JOINT_TYPES, LoopJoint, Robot

__all__ = ["CONVENTIONS", "Inertia", "JOINT_TYPES", "LoopJoint", "Robot", "RobotBuilder",
           "joint_type", "pose", "quat_pose"]
