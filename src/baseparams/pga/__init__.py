"""Projective geometric algebra G(3,0,1): batched points, lines and motors (see :mod:`.core`)."""

from .core import (
    adjoint,
    commutator,
    direction,
    hat,
    identity_motor,
    inverse_transform,
    join,
    line_through,
    matrix_to_motor,
    motor_exp,
    motor_log,
    motor_product,
    motor_to_matrix,
    point,
    reverse,
    sandwich,
    se3_exp,
    se3_log,
    swap,
    wedge,
)

__all__ = [
    "adjoint", "commutator", "direction", "hat", "identity_motor", "inverse_transform", "join",
    "line_through", "matrix_to_motor", "motor_exp", "motor_log", "motor_product",
    "motor_to_matrix", "point", "reverse", "sandwich", "se3_exp", "se3_log", "swap", "wedge",
]
