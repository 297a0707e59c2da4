"""The regressor nullspace: DRNG (corrected) and its numerical certification/completion."""

from .drng import PRINCIPLES, Columns, DRNGResult, block_rank, drng, drng_columns, planar_rotations

__all__ = ["PRINCIPLES", "Columns", "DRNGResult", "block_rank", "drng", "drng_columns", "planar_rotations"]
