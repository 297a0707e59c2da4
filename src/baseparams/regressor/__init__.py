"""The tetrahedral-point (TP) regressor, tensor and matrix forms."""

from .tp import bar, closed_regressor, generalized_forces, regressor, regressor_tensor

__all__ = ["bar", "closed_regressor", "generalized_forces", "regressor", "regressor_tensor"]
