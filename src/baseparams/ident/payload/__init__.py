"""Payload identification: what a robot carries on one link, from a short log, the robot already known.

A payload fixed to a link changes only that link's ten inertial parameters, so the torques of the
robot carrying it are the known robot's plus the link's ten TP-regressor columns times the payload's
parameters (:mod:`.model`). Which of the ten a motion identifies is decided as the project decides
base parameters: structurally for the joints that move, then at a gap of the log's own spectrum
(:mod:`.structure`); the estimate is weighted least squares on those directions with HAC standard
deviations, physically consistent (:mod:`.fit`); the result says the mass, centre of mass and inertia
about it in the link's frame, each with a sigma, and names what is not identified (:mod:`.result`).

:func:`identify_payload`
    A robot, a log and a link to a :class:`Payload`.
:class:`PayloadOptions`
    Every option, checked once.
:class:`Payload`
    The result: ``mass``, ``com``, ``inertia_com``, ``sigma()``, ``identified()``, ``to_json()``,
    ``summary()``, ``predict(log)``, ``save(path)``.
:class:`SavedPayload`
    A saved payload read back (``SavedPayload.load(path, robot)``).

Layer: part of :mod:`baseparams.ident`; the front door is :func:`baseparams.identify_payload`
(files, exports), the command ``baseparams payload``.
"""

from __future__ import annotations

from .options import PayloadOptions
from .pipeline import identify_payload
from .result import Payload
from .saved import SavedPayload

__all__ = ["Payload", "PayloadOptions", "SavedPayload", "identify_payload"]
