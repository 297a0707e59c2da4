"""The front door's arguments as the library's objects: a model as a Robot, a log as a JointLog, the input files.

Each coercion refuses what it cannot take in one line naming the argument by its keyword (the
command line names it by its flag: :mod:`baseparams.cli.parser`).
"""

from __future__ import annotations

import os
import warnings

from ..analysis import Analysis
from ..errors import BaseparamsError, ModelWarning
from ..model import Robot


def robot_of(model, what: str) -> Robot:
    """``model`` as a Robot: a Robot, an Analysis's robot, or a built-in name / robot file.

    Parameters
    ----------
    model : Robot, Analysis, str or path
        The model; a name or file is loaded (:func:`baseparams.loading.load_model`, its notes as
        :class:`~baseparams.errors.ModelWarning` warnings).
    what : str
        The calling function, for messages.

    Returns
    -------
    Robot
        The robot.

    Raises
    ------
    BaseparamsError
        Another type, or what loading raises.
    """
    if isinstance(model, Robot):
        return model
    if isinstance(model, Analysis):
        return model.robot
    if isinstance(model, (str, os.PathLike)):
        from ..loading import load_model

        robot, notes = load_model(os.fspath(model))
        for note in notes:
            warnings.warn(note, ModelWarning, stacklevel=3)
        return robot
    from ..arguments import ArgumentTypeError

    raise ArgumentTypeError(f"{what}: model must be a Robot, an Analysis, a built-in name or a robot file, "
                            f"got {type(model).__name__}")


def input_files(*items) -> list[str]:
    """The items that are existing files (the run's inputs, which outputs must not overwrite).

    Parameters
    ----------
    *items : object
        Anything; paths of existing files are kept.

    Returns
    -------
    list of str
        The existing files among ``items``; a model file's own inputs (includes, assets,
        meshes) when the first item is one.
    """
    out = [os.fspath(x) for x in items if isinstance(x, (str, os.PathLike)) and os.path.isfile(x)]
    if items and isinstance(items[0], (str, os.PathLike)) and os.path.isfile(items[0]):
        from ..io.sources import model_files  # a model file's own inputs: includes, assets, meshes

        out += [str(f) for f in model_files(items[0])[1:]]
    return out


def log_of(log, robot: Robot, columns, require_tau: bool = True, subset: bool = False, name: str = "log",
           allow_units: bool = False):
    """``log`` as a JointLog: a JointLog (values checked), or a log file read for ``robot``.

    Parameters
    ----------
    log : JointLog, str or path
        The log, or its file (:func:`baseparams.io.logs.read_log`).
    robot : Robot
        The robot the log was recorded on.
    columns : str, path or dict, optional
        A layout mapping for a log file (refused with a JointLog).
    require_tau : bool
        The log must have torques (a trajectory to predict torques of need not).
    subset : bool
        Accept a log of some of the robot's joints (a sub-chain's).
    name : str
        The argument's keyword, for messages.
    allow_units : bool
        Positions beyond the plausible bounds (degrees? millimetres?) a warning note, not a refusal.

    Returns
    -------
    JointLog
        The log, its values checked.

    Raises
    ------
    BaseparamsError
        Another type, a mapping with a JointLog, what reading raises.
    """
    from ..arguments import ArgumentTypeError
    from ..jointlog import JointLog

    if isinstance(log, (str, os.PathLike)):
        from ..io.logs import read_log

        return read_log(log, robot, columns=columns, allow_subset=subset or not require_tau, require_tau=require_tau,
                        allow_units=allow_units)
    if not isinstance(log, JointLog):
        raise ArgumentTypeError(f"{name} must be a JointLog or a log file's path, got {type(log).__name__}")
    if columns is not None:
        raise BaseparamsError(f"columns= maps the columns of a log file; {name} is a JointLog already")
    return log.checked()
