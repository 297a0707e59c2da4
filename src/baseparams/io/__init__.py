"""Readers and writers of robot files and joint logs.

Layer: below identification (:mod:`baseparams.ident`, which converts its results for the writers
here: :mod:`baseparams.ident.export`); depends on the model, kinematics, regressor and the low
helpers (files, tables, schema, :class:`~baseparams.jointlog.JointLog`) only.
"""

__all__ = ["load_mjcf"]


def __getattr__(name: str):
    """``load_mjcf`` imported on first use: reading a URDF does not pay for the MJCF reader."""
    if name == "load_mjcf":
        from .mjcf import load_mjcf

        return load_mjcf
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
