"""baseparams: base inertial parameters of robots from geometry (PGA / TP model / DRNG)."""

__version__ = "0.1.0"
