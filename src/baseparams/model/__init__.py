"""Robot model: bodies, tree joints, loop joints, gravity, inertial parameters."""

from .builder import RobotBuilder, joint_type, pose, quat_pose
from .inertia import CONVENTIONS, Inertia
from .robot import JOINT_TYPES, Coupling, LoopJoint, Robot

__all__ = ["CONVENTIONS", "Coupling", "Inertia", "JOINT_TYPES", "LoopJoint", "Robot", "RobotBuilder",
           "joint_type", "pose", "quat_pose"]
