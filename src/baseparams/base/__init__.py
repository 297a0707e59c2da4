"""Base parameters: bases of Null^perp, regrouped expressions, maps to and from them."""

from .regroup import BaseParameters, base_parameters, paper_from, parameter_names

__all__ = ["BaseParameters", "base_parameters", "paper_from", "parameter_names"]
