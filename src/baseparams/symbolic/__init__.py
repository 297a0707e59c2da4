"""Symbolic base parameters: the regrouping as formulas in a robot's dimensions (SymPy).

A robot whose reference geometry is given in symbols (a DH table, :func:`read_table`; or
:class:`SymbolicBuilder`) is analysed by DRNG's rules on that geometry and exact elimination
(:func:`symbolic_analysis`); the formulas are checked against the certified numerical analysis
at random values, and the conditions under which they change are found and probed. Needs the
optional extra ``symbolic`` (SymPy).
"""

from __future__ import annotations

try:
    import sympy  # noqa: F401  (the symbolic geometry is SymPy's)
except ImportError:  # pragma: no cover - exercised without the extra
    raise ImportError("baseparams.symbolic needs SymPy: pip install 'baseparams[symbolic]' "
                      "(from a clone: pip install '.[symbolic]')") from None

from .analyze import base_regressor, symbolic_analysis
from .check import check, probe
from .geometry import SymbolicBuilder, SymbolicRobot, rot, trans, transform
from .solve import Condition, SymbolicAnalysis, regroup
from .tables import builtin_tables, from_dh, load_symbolic, mdh, read_table, sdh

__all__ = ["Condition", "SymbolicAnalysis", "SymbolicBuilder", "SymbolicRobot", "base_regressor", "builtin_tables",
           "check", "from_dh", "load_symbolic", "mdh", "probe", "read_table", "regroup", "rot", "sdh",
           "symbolic_analysis", "trans", "transform"]
