"""A saved payload read back: :class:`SavedPayload` (``identify_payload(..., save=...)``, ``payload --save``).

The file is :meth:`Payload.document <.result.Payload.document>`'s JSON: ``{"format":
"baseparams-payload", "version": 1, "baseparams", "robot": {"name", "fingerprint"}, "options",
"payload": {"link", "mass", "com", "inertia_com", "sigma", "identifiable", "notes", ...}}``, every
quantity in LINK's frame (the inertia about the centre of mass, LINK's axes), None where the motion
did not identify it and no prior held it. Read back, it is checked (its format, the quantities'
shapes and numbers, a realizable body when every quantity is known) and, given the robot, belongs to
it (the robot fingerprint of :mod:`baseparams.ident.saved`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from ...errors import BaseparamsError

#: the saved payload's format name and version
FORMAT, VERSION = "baseparams-payload", 1
#: a saved payload's largest size read [bytes]
MAX_BYTES = 16 << 20


@dataclass(frozen=True)
class SavedPayload:
    """A payload read back from its file (module docstring).

    Parameters
    ----------
    link : str
        The link the payload is fixed to.
    mass : float or None
        Mass [kg] (None: not identified nor held at a prior).
    com : list
        Centre of mass ``(3,)`` [m] in LINK's frame (None per coordinate not known).
    inertia_com : list
        Inertia about the centre of mass ``(3, 3)`` [kg m^2] in LINK's axes (None where not known).
    sigma : dict
        ``{"mass", "com", "inertia_com"}``: standard deviations, None where not identified.
    identifiable : tuple of str
        The quantities the motion identified (:data:`~.result.QUANTITIES`).
    notes : tuple of str
        The identification's notes.
    robot : dict
        ``{"name", "fingerprint"}`` of the robot it was identified on.
    document : dict
        The whole file (:meth:`to_json` is its ``payload`` part).
    """

    link: str
    mass: float | None
    com: list
    inertia_com: list
    sigma: dict
    identifiable: tuple
    notes: tuple
    robot: dict
    document: dict

    def __repr__(self) -> str:
        mass = "mass not identified" if self.mass is None else f"{self.mass:.4g} kg"
        return f"<SavedPayload on {self.link}: {mass}, {len(self.identifiable)}/10 quantities identified>"

    def identified(self) -> list[str]:
        """The quantities the motion identified.

        Returns
        -------
        list of str
            E.g. ``["mass", "com_x", ...]`` (:data:`~.result.QUANTITIES`).
        """
        return list(self.identifiable)

    def to_json(self) -> dict:
        """``{"payload": {...}}``, as the identification's :meth:`Payload.to_json <.result.Payload.to_json>`.

        Returns
        -------
        dict
            The file's ``payload`` object under ``payload``.
        """
        return {"payload": self.document["payload"]}

    @classmethod
    def load(cls, path, robot=None) -> SavedPayload:
        """Read a saved payload, checked; with ``model``, for that robot.

        Parameters
        ----------
        path : str or path
            The file (``identify_payload(..., save=path)``).
        robot : Robot or Analysis, optional
            The robot it must belong to (its fingerprint is checked: ``baseparams.load(...)``).

        Returns
        -------
        SavedPayload
            The payload.

        Raises
        ------
        BaseparamsError
            Not a saved payload (not JSON, another format or version, a quantity of the wrong
            shape or not a finite number, a mass not positive), or a payload of another robot: one
            line naming the file.
        """
        import json

        from ...files import read_input_bytes

        where = os.fspath(path)
        try:
            doc = json.loads(read_input_bytes(where, MAX_BYTES))
        except (ValueError, UnicodeDecodeError) as exc:
            raise BaseparamsError(f"{where}: not a saved payload (not JSON: {exc})") from None
        out = _read(doc, where)
        if robot is not None:
            _check_robot(out, robot, where)
        return out


def _read(doc, where: str) -> SavedPayload:
    """The document checked, as a :class:`SavedPayload`."""
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise BaseparamsError(f"{where}: not a saved payload (format {FORMAT!r} expected: identify_payload save=)")
    if doc.get("version") != VERSION:
        raise BaseparamsError(f"{where}: saved payload version {doc.get('version')!r}; this baseparams reads "
                              f"version {VERSION}")
    p, robot = doc.get("payload"), doc.get("robot")
    if not isinstance(p, dict) or not isinstance(robot, dict) or not isinstance(p.get("link"), str):
        raise BaseparamsError(f"{where}: a saved payload needs 'robot' and 'payload' objects and the payload's link")
    mass = _number(p.get("mass"), f"{where}: payload.mass")
    if mass is not None and not mass > 0:
        raise BaseparamsError(f"{where}: payload.mass must be > 0 kg, got {mass:g}")
    com = _numbers(p.get("com"), (3,), f"{where}: payload.com")
    ic = _numbers(p.get("inertia_com"), (3, 3), f"{where}: payload.inertia_com")
    sigma = p.get("sigma")
    if not isinstance(sigma, dict):
        raise BaseparamsError(f"{where}: payload.sigma must be an object with mass, com and inertia_com")
    sigma = {"mass": _number(sigma.get("mass"), f"{where}: payload.sigma.mass"),
             "com": _numbers(sigma.get("com"), (3,), f"{where}: payload.sigma.com"),
             "inertia_com": _numbers(sigma.get("inertia_com"), (3, 3), f"{where}: payload.sigma.inertia_com")}
    ident, notes = p.get("identifiable", []), p.get("notes", [])
    if not (isinstance(ident, list) and all(isinstance(x, str) for x in ident)
            and isinstance(notes, list) and all(isinstance(x, str) for x in notes)):
        raise BaseparamsError(f"{where}: payload.identifiable and payload.notes must be lists of text")
    return SavedPayload(p["link"], mass, com, ic, sigma, tuple(ident), tuple(notes),
                        {"name": robot.get("name"), "fingerprint": robot.get("fingerprint")}, doc)


def _number(x, what: str) -> float | None:
    """A finite number or None (``null``)."""
    if x is None:
        return None
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        raise BaseparamsError(f"{what} must be a finite number or null, got {str(x)[:40]}")
    return float(x)


def _numbers(x, shape: tuple, what: str) -> list:
    """A nested list of ``shape`` of finite numbers or None."""
    if not isinstance(x, list) or len(x) != shape[0]:
        raise BaseparamsError(f"{what} must be a list of {shape[0]}")
    if len(shape) == 1:
        return [_number(v, what) for v in x]
    return [_numbers(v, shape[1:], what) for v in x]


def _check_robot(saved: SavedPayload, robot, where: str) -> None:
    """Refuse a payload saved for another robot (the fingerprints differ)."""
    from ...arguments import ArgumentTypeError
    from ...model.robot import Robot
    from ..saved import robot_fingerprint

    robot = getattr(robot, "robot", robot)  # an Analysis's
    if not isinstance(robot, Robot):
        raise ArgumentTypeError(f"SavedPayload.load: robot= must be a Robot or an Analysis, got {type(robot).__name__}")
    mine = robot_fingerprint(robot)
    if saved.robot["fingerprint"] != mine:
        raise BaseparamsError(f"{where}: a payload identified on robot {saved.robot['name']!r} (fingerprint "
                              f"{str(saved.robot['fingerprint'])[:12]}), not on {robot.name!r} ({mine[:12]})")
