"""Identification from measured data: the values of a robot's base parameters and drive terms from a log.

The identification API (what users import: ``from baseparams.ident import identify``); the modules
behind it are its rooms, each answering one question.

:func:`identify`
    A log (:class:`JointLog`) to an :class:`Identification`: values, standard deviations,
    validation, notes; ``Identification.load`` reads a saved one back.
:class:`IdentModel`, :func:`ident_model`
    The model identified: base parameters plus drive terms (:class:`MotorCoupling` for motors
    driving several joints), regrouped.
:func:`accumulate`, :func:`accumulate_prepared`, :func:`log_columns`
    Regressor rows of states or of a prepared log, accumulated on a streaming QR.
:func:`fit`, :class:`Fit`, :func:`pulled_covariance`
    The estimators (OLS, WLS, the default estimate with the model file's prior, physically
    consistent) on accumulated rows.
:func:`predict_log`, :func:`validation_scores`, :func:`check_log_units`
    Predicted torques of a log, held-out scores, the log's units checked before a fit.
:class:`IdentOptions`
    Every option of an identification, checked once; what every path takes and a result keeps.

Layer: above the analysis (:mod:`baseparams.analysis`) and the readers of files
(:mod:`baseparams.io`, which a path given to :meth:`Identification.predict` is read by), below the
workflow and the CLI.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the names below, for readers and type checkers; at run time each on first use
    from ..jointlog import JointLog
    from .drives import MotorCoupling
    from .fitting import Fit, fit, pulled_covariance
    from .model import IdentModel, ident_model
    from .notes import check_log_units
    from .options import IdentOptions
    from .pipeline import identify
    from .result import Identification
    from .rows import accumulate, accumulate_prepared, log_columns
    from .validation import predict_log, validation_scores

#: the public name -> the module holding it (imported on first use: ``import baseparams.ident.options``
#: does not load the estimators)
API = {"identify": ".pipeline", "IdentOptions": ".options", "Identification": ".result", "Fit": ".fitting",
       "fit": ".fitting", "pulled_covariance": ".fitting", "accumulate": ".rows", "accumulate_prepared": ".rows",
       "log_columns": ".rows", "IdentModel": ".model", "ident_model": ".model", "MotorCoupling": ".drives",
       "JointLog": "..jointlog", "predict_log": ".validation", "validation_scores": ".validation",
       "check_log_units": ".notes"}

__all__ = ["API", "Fit", "IdentModel", "IdentOptions", "Identification", "JointLog", "MotorCoupling", "accumulate",
           "accumulate_prepared", "check_log_units", "fit", "ident_model", "identify", "log_columns", "predict_log",
           "pulled_covariance", "validation_scores"]


def __getattr__(name: str):
    """The public names on first use (:data:`API`)."""
    if name in API:
        return getattr(importlib.import_module(API[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(__all__) | {n for n in globals() if n.startswith("__")})
