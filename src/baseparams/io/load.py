"""Read a robot file by its suffix (URDF/URDF+, xacro, MJCF), assembling closed loops if needed."""

from __future__ import annotations

import warnings
from pathlib import Path

from ..errors import BaseparamsError, NoMotionError
from ..files import MODEL_MAX_BYTES, check_input
from ..model.robot import Robot


def load_file(path: str | Path, floating: bool = False, gravity=None, strict_inertia: bool = False,
              xacro_args=None, package_path=None, mocap_welds: str = "drop",
              edit=None) -> tuple[Robot, list[str]]:
    """``(robot, notes)`` from a ``.urdf``, ``.xacro`` or ``.xml``/``.mjcf`` file.

    Gravity defaults to ``(0, 0, -9.81)`` for URDF files and to the model's own for MJCF. Physically
    infeasible inertias are notes (one per link), or errors with ``strict_inertia``. Loop robots whose
    file is not assembled (or singular) at q = 0 are assembled and re-referenced; the notes say so,
    along with any warning raised while reading.

    Parameters
    ----------
    path : str or Path
        The robot file; its suffix (case-insensitive) picks the reader: ``.urdf``
        (:func:`~baseparams.io.urdf.load_urdf`), ``.xacro`` (``robot.urdf.xacro``: expanded by
        :func:`~baseparams.io.xacro_in.expand_xacro`, then read as URDF; messages name the xacro
        file) or ``.xml``/``.mjcf`` (:func:`~baseparams.io.mjcf.load_mjcf`).
    floating : bool, optional
        Attach the root link (MJCF: a top-level body without a joint) to the world by a floating
        (F) joint.
    gravity : array_like, shape ``(3,)``, optional
        Gravity in the world frame (m/s^2); the defaults are above.
    strict_inertia : bool, optional
        Physically infeasible inertias are errors instead of notes.
    xacro_args : mapping or iterable of str, optional
        Arguments of a xacro file: ``{"NAME": "VALUE"}`` or ``["NAME:=VALUE", ...]``.
    package_path : str, path or list of them, optional
        Folders searched for a xacro file's ``$(find PKG)`` and ``package://PKG`` (before
        ``BASEPARAMS_PACKAGE_PATH`` and ``ROS_PACKAGE_PATH``).
    mocap_welds : {'drop', 'keep'}, optional
        MJCF: the welds and connects to mocap bodies left out (default) or kept as loops to the
        world (:func:`~baseparams.io.mjcf.load_mjcf`).
    edit : callable, optional
        Called with the parsed document before the robot is built (URDF and xacro: the root
        element; MJCF: the ``MjSpec``): :mod:`baseparams.io.snapfile` re-reads a file with rounded
        right angles exact. Without it, the robot's ``source`` records the file and these options
        (:class:`~baseparams.model.snap.FileSource`).

    Returns
    -------
    robot : Robot
        The robot, assembled at its (possibly new) reference q = 0
        (:func:`~baseparams.kinematics.loops.assemble`).
    notes : list of str
        The reader's warnings and the assembly note (prefixed with the path).

    Raises
    ------
    BaseparamsError
        A missing file, not a regular file (a folder, a device, a FIFO), larger than
        :data:`~baseparams.files.MODEL_MAX_BYTES`, or an unknown suffix; xacro arguments or a package
        path for a file that is not xacro; the ``xacro`` package missing for a xacro file (naming the
        extra); :class:`~baseparams.errors.ModelError` (a subclass) for an invalid model or a failed
        expansion; :class:`~baseparams.errors.NoMotionError` (a subclass) when the constraints leave the mechanism
        no motion.
    """
    p = check_input(path, MODEL_MAX_BYTES)  # a regular file of at most 64 MB, refused before reading
    suffix = p.suffix.lower()
    if suffix != ".xacro" and (xacro_args or package_path):
        raise BaseparamsError(f"{p}: xacro arguments and a package path apply to .xacro files, not {suffix or 'this'}")
    try:
        return _read(p, suffix, floating, gravity, strict_inertia, xacro_args, package_path, mocap_welds, edit)
    except NoMotionError as exc:  # found where the file is no longer known: named here
        raise NoMotionError(f"{p}: {exc}") from None


def _read(p: Path, suffix: str, floating: bool, gravity, strict_inertia: bool, xacro_args, package_path,
          mocap_welds: str, edit) -> tuple[Robot, list[str]]:
    """:func:`load_file` once the file is checked: the reader of its suffix, then the loops' assembly."""
    notes = []
    # each reader is imported for its own suffix only (start-up time of a one-shot command)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if suffix == ".xacro":
            from .urdf import load_urdf
            from .xacro_in import expand_xacro

            data, notes = expand_xacro(p, xacro_args, package_path)
            g = (0.0, 0.0, -9.81) if gravity is None else gravity
            robot = load_urdf(p, floating=floating, gravity=g, strict_inertia=strict_inertia, data=data, edit=edit)
        elif suffix == ".urdf":
            from .urdf import load_urdf

            g = (0.0, 0.0, -9.81) if gravity is None else gravity
            robot = load_urdf(p, floating=floating, gravity=g, strict_inertia=strict_inertia, edit=edit)
        elif suffix in (".xml", ".mjcf"):
            from .mjcf import load_mjcf

            robot = load_mjcf(p, gravity=gravity, floating=floating, strict_inertia=strict_inertia,
                              mocap_welds=mocap_welds, edit=edit)
        else:
            raise BaseparamsError(f"{p}: unknown file type {suffix!r}; expected .urdf, .xacro, .xml or .mjcf")
    notes += [str(w.message) for w in caught]
    if robot.has_loops:  # a tree is returned unchanged by the assembly
        from ..kinematics.loops import assemble

        robot, _, note = assemble(robot)
        if note:
            notes.append(f"{p}: {note}")
    if edit is None:
        from ..model.snap import FileSource, geometry_fingerprint

        options = {"floating": floating, "gravity": gravity, "strict_inertia": strict_inertia,
                   "xacro_args": xacro_args, "package_path": package_path, "mocap_welds": mocap_welds}
        # set on the robot just built (validated once; a frozen dataclass): where it was read from
        object.__setattr__(robot, "source", FileSource(str(p), options, geometry_fingerprint(robot)))
    return robot, notes
