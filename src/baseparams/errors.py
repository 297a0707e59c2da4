"""Errors the library raises on bad input; the CLI prints them as one line."""


class BaseparamsError(Exception):
    """Base class: a problem with the user's input, reported as one clear line."""


class ModelError(BaseparamsError, ValueError):
    """An invalid robot model (names the robot, body or joint and the problem)."""


class NoMovingBodiesError(ModelError):
    """A model whose links are all welded to the world.

    It has no inertial parameter that any measurement could see (the CLI reports this as an
    empty, trivially certified result).
    """


class NoMotionError(ModelError):
    """A mechanism its loop joints and couplings leave without any motion (one line naming them).

    Nothing moves, so no measurement sees any inertial parameter; unlike
    :class:`NoMovingBodiesError` this is refused: a file whose constraints lock every joint is more
    likely a constraint read wrongly (a control device's weld, a loop frame) than a robot.
    """


class DataError(BaseparamsError, ValueError):
    """Bad measured data: a log file or array (names the file, column, row and the problem)."""


class ModelWarning(UserWarning):
    """A note about a loaded model that does not stop the analysis.

    A physically infeasible inertia (the base-parameter structure does not depend on the
    values), a loop robot assembled or re-referenced because the file's q = 0 is not assembled
    (or is singular), or a warning of the file's reader.
    """


class ArgumentError(BaseparamsError, ValueError):
    """An argument out of its range (names the argument, the range and the value)."""


class ArgumentTypeError(BaseparamsError, TypeError):
    """An argument of the wrong type or shape (names the argument and what it should be)."""


#: the end of a refusal ``allow_units=True`` lets through (the keyword and the command line's flag: the command
#: line names the flag alone, :func:`baseparams.cli.parser.flag_message`)
GO_ON = "; --allow-units (allow_units=True) to go on anyway"


def going_on(topic: str, problem: object) -> str:
    """The WARNING note of a refusal ``allow_units=True`` let through: its line without "to go on anyway".

    The one wording of every such note (units, rate, positions), in the library's keyword (the
    command line prints ``--allow-units``).

    Parameters
    ----------
    topic : str
        What was checked (``units``, ``rate``).
    problem : str or Exception
        The refusal (its :data:`GO_ON` end left out).

    Returns
    -------
    str
        ``units: WARNING, going on (allow_units=True): ...``.
    """
    return f"{topic}: WARNING, going on (allow_units=True): {str(problem).removesuffix(GO_ON)}"
