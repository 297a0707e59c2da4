"""The tetrahedral-point (TP) regressor, tensor and matrix forms."""

from .tp import (
                 bar,
                 closed_projected_regressor,
                 closed_regressor,
                 generalized_forces,
                 projected_regressor,
                 regressor,
                 regressor_tensor,
)

__all__ = ["bar", "closed_projected_regressor", "closed_regressor", "generalized_forces", "projected_regressor",
           "regressor", "regressor_tensor"]
