"""Readers and writers of robot files (edge of the library: depends on the model only)."""

from .mjcf import load_mjcf

__all__ = ["load_mjcf"]
