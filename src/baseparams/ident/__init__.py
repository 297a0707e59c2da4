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

Layer: above the analysis (:mod:`baseparams.analysis`) and the readers of files
(:mod:`baseparams.io`, which a path given to :meth:`Identification.predict` is read by), below the
workflow and the CLI.
"""

from ..jointlog import JointLog
from .drives import MotorCoupling
from .fitting import Fit, fit, pulled_covariance
from .model import IdentModel, ident_model
from .notes import check_log_units
from .pipeline import identify
from .result import Identification
from .rows import accumulate, accumulate_prepared, log_columns
from .validation import predict_log, validation_scores

__all__ = ["Fit", "IdentModel", "Identification", "JointLog", "MotorCoupling", "accumulate", "accumulate_prepared",
           "check_log_units", "fit", "ident_model", "identify", "log_columns", "predict_log", "pulled_covariance",
           "validation_scores"]
