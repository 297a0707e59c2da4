"""Identification from measured data: logs, preprocessing, drive model, estimators.

Layer: above the base parameters (:mod:`baseparams.base`), below the readers of files
(:mod:`baseparams.io`) and the CLI.
"""
