"""The regressor nullspace: DRNG (corrected) and its numerical certification/completion."""

from .columns import PRINCIPLES, Columns
from .drng import DRNGResult, drng
from .principles import drng_columns, planar_rotations
from .rank import block_rank

__all__ = ["PRINCIPLES", "Columns", "DRNGResult", "block_rank", "drng", "drng_columns", "planar_rotations"]
