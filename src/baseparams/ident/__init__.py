"""Identification from measured data: logs, preprocessing, drive model, estimators.

Layer: above the analysis (:mod:`baseparams.analysis`) and the readers of files
(:mod:`baseparams.io`, which a path given to :meth:`Identification.predict` is read by), below the
workflow and the CLI.
"""
