"""Errors the library raises on bad input; the CLI prints them as one line."""


class BaseparamsError(Exception):
    """Base class: a problem with the user's input, reported as one clear line."""


class ModelError(BaseparamsError, ValueError):
    """An invalid robot model (names the robot, body or joint and the problem)."""
