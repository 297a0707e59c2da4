"""Readers and writers of robot files (edge of the library: depends on the model only)."""

__all__ = ["load_mjcf"]


def __getattr__(name: str):
    """``load_mjcf`` imported on first use: reading a URDF does not pay for the MJCF reader."""
    if name == "load_mjcf":
        from .mjcf import load_mjcf

        return load_mjcf
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
