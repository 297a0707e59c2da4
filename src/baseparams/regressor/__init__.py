"""The tetrahedral-point (TP) regressor, tensor and matrix forms."""

from .tp import bar, generalized_forces, regressor, regressor_tensor

__all__ = ["bar", "generalized_forces", "regressor", "regressor_tensor"]
