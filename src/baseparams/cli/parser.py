"""The ``baseparams`` command's parser: shared groups of flags, the subcommands, each flag's keyword.

:func:`build_parser` asks each command's module (:mod:`baseparams.cli.robots`, ``analyze``,
``regressor``, ``identify``, ``predict``, ``simulate``, ``excite``, ``payload``) for its subcommand
(``add_parser(sub)``); each module also says which front-door keyword each of its flags is
(``KEYWORDS``, the flags named otherwise; a flag not listed is the keyword of its name, or
``CLI_ONLY``: how the result is printed). :func:`keyword_flags` reads that back as one table,
keyword to flag, and :func:`flag_message` writes a library message (which names options by their
keywords, ``holdout=``) with the command's flags (``--holdout``): the only place the command
line's spelling of an option is decided.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import re

from ..arguments import CHOICES, IDENTIFY

#: the commands, in the order of ``baseparams --help``, each the module ``baseparams.cli.<name>``
COMMANDS = ("robots", "analyze", "regressor", "identify", "predict", "simulate", "excite", "payload")

#: the model's flags (every command that takes ``MODEL``): :func:`baseparams.load`'s keywords
MODEL_KEYWORDS = ("floating", "strict_inertia", "gravity", "mocap_welds", "xacro_args", "package_path")

#: each subcommand's help for its MODEL argument
_MODEL_FILES = ("built-in robot name (see 'baseparams robots') or a robot file: URDF / URDF+ (.urdf), ROS xacro "
                "(.xacro) or MJCF (.xml)")
MODEL_HELP = {
    "analyze": f"{_MODEL_FILES}, or a DH table (.dh, '*-symbolic'); a glob pattern ('models/*.urdf') runs a sweep "
               "over many files on Dask",
    "regressor": f"{_MODEL_FILES}: the robot whose TP regressor is computed",
    "identify": f"{_MODEL_FILES}: the robot the log was recorded on (--urdf needs a .urdf file, --mjcf a file)",
    "predict": f"{_MODEL_FILES}: the robot the saved identification belongs to (its fingerprint is checked)",
    "simulate": f"{_MODEL_FILES}: the robot simulated (its own inertias are the true parameters)",
    "excite": f"{_MODEL_FILES}: the robot (its joint limits are read from the file)",
    "payload": f"{_MODEL_FILES}: the robot without the payload (--urdf needs a .urdf file, --mjcf a file)",
}

#: the subcommands whose ``--samples`` was renamed ``--analysis-samples`` (it reads as log samples there)
RENAMED_SAMPLES = ("identify", "simulate", "excite", "payload")


class _Parser(argparse.ArgumentParser):
    """argparse's parser whose errors are one line, as every other error (``baseparams: error: ...``, exit 2)."""

    def error(self, message: str):
        """Print the error on one line (``--help`` shows the usage) and exit 2.

        Parameters
        ----------
        message : str
            argparse's message (``argument --starts: invalid int value: '1.5'``).
        """
        prog = self.prog.split(" ", 1)[1] + " " if " " in self.prog else ""
        self.exit(2, f"baseparams: error: {prog}{message} (see {self.prog} --help)\n")


class _Version(argparse.Action):
    """``--version``: the version looked up when asked for (:func:`baseparams.version.version`), not at start-up."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from ..version import version

        print(f"baseparams {version()}")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``baseparams`` command.

    Returns
    -------
    argparse.ArgumentParser
        Subcommands ``robots``, ``analyze``, ``regressor``, ``identify``, ``predict``, ``simulate``,
        ``excite`` and ``payload`` (:data:`COMMANDS`); each sets ``func`` to its module's ``run``.
    """
    p = _Parser(prog="baseparams", description=(
        "Which inertial parameters of a robot are identifiable (base parameters), why, and how "
        "they regroup: the tetrahedral-point model and DRNG, certified by exact numerics."))
    p.add_argument("--version", action=_Version, help="show program's version number and exit")
    sub = p.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        command_module(name).add_parser(sub)
    return p


def command_module(name: str):
    """The module of a command (``baseparams.cli.<name>``: ``add_parser``, ``run``, ``KEYWORDS``, ``CLI_ONLY``).

    Parameters
    ----------
    name : str
        The command (one of :data:`COMMANDS`).

    Returns
    -------
    module
        Its module (light at import: the work's modules are imported when ``run`` runs).
    """
    return importlib.import_module(f"{__package__}.{name}")


def choices(name: str) -> str:
    """The metavar of a flag naming one of :data:`baseparams.arguments.CHOICES` (``{auto,ols,wls,physical}``).

    The value is checked by the library's rule (``check_choice``), not by argparse, so that both
    doors refuse it with one message.

    Parameters
    ----------
    name : str
        The option's keyword.

    Returns
    -------
    str
        ``{a,b,...}``.
    """
    return "{" + ",".join(CHOICES[name]) + "}"


def model_args(s, analysis: bool = True) -> None:
    """``MODEL`` and the model's flags (:data:`MODEL_KEYWORDS`), ``--analysis-samples``, ``--seed``, ``--json``.

    Parameters
    ----------
    s : argparse.ArgumentParser
        A subcommand's parser.
    analysis : bool
        The command analyses the model (``--analysis-samples``/``--samples`` and ``--seed``);
        ``predict`` rebuilds it from the saved result's options.
    """
    s.add_argument("model", help=MODEL_HELP[s.prog.split()[-1]])
    s.add_argument("--floating", action="store_true",
                   help="attach the file's root link to the world by a floating (free) joint")
    s.add_argument("--strict-inertia", action="store_true",
                   help="refuse files with physically infeasible inertias of moving links (by "
                        "default they are noted and the analysis goes on: the base-parameter "
                        "structure does not depend on the values)")
    s.add_argument("--allow-infeasible-inertia", action="store_true", help=argparse.SUPPRESS)
    _mocap_args(s)
    s.add_argument("--gravity", nargs=3, type=float, metavar=("GX", "GY", "GZ"),
                   help="gravity in the world frame [m/s^2] (default: the model's, 0 0 -9.81)")
    _xacro_args(s)
    if analysis:
        _samples_args(s)
        s.add_argument("--seed", type=int, default=0, help="random seed")
    s.add_argument("--json", action="store_true", help="print one JSON object")


def _mocap_args(s: argparse.ArgumentParser) -> None:
    """``--mocap-welds {drop,keep}``: an MJCF file's welds and connects to mocap bodies left out or kept."""
    s.add_argument("--mocap-welds", metavar=choices("mocap_welds"), default=CHOICES["mocap_welds"][0],
                   help="MJCF: the welds and connects to mocap bodies, control devices the simulation moves "
                        "(Meta-World's and Fetch's hands): drop (default: left out, with a note) or keep (loop "
                        "joints to the world)")
    s.add_argument("--drop-mocap-welds", dest="mocap_welds", action="store_const", const=CHOICES["mocap_welds"][0],
                   help=argparse.SUPPRESS)  # the previous flag: now the default


def _xacro_args(s) -> None:
    """``--xacro-arg`` and ``--package-path``: a .xacro model's arguments and ROS packages."""
    s.add_argument("--xacro-arg", action="append", dest="xacro_args", metavar="NAME:=VALUE",
                   help="an argument of a .xacro model (repeatable)")
    s.add_argument("--package-path", action="append", metavar="DIR",
                   help="a folder of ROS packages for a .xacro model's $(find PKG) and package:// (repeatable; "
                        "then BASEPARAMS_PACKAGE_PATH and ROS_PACKAGE_PATH, os.pathsep-separated)")


def _samples_args(s) -> None:
    """``--samples`` (analyze, regressor) or ``--analysis-samples`` (identify, simulate, excite)."""
    if s.prog.split()[-1] not in RENAMED_SAMPLES:
        s.add_argument("--samples", type=int, default=None,
                       help="random samples for the numerical method (default: 100 for trees, "
                            "5000 actuated samples for closed loops, as the paper)")
        return
    s.add_argument("--analysis-samples", dest="samples", type=int, default=None, metavar="N",
                   help="random states of the base-parameter analysis the model is built on (default: 100 for "
                        "trees, 5000 actuated samples for closed loops); not the log's samples")
    s.add_argument("--samples", dest="old_samples", type=int, default=None, help=argparse.SUPPRESS)


def ident_args(s, rotor_auto: bool = False) -> None:
    """Options shared by ``identify`` and ``simulate``: friction, rotor, convention.

    Parameters
    ----------
    s : argparse.ArgumentParser
        A subcommand's parser.
    rotor_auto : bool
        ``identify``: ``--rotor`` / ``--no-rotor`` force the rotor inertia in or out, neither leaves it to
        the training data's cross-validation (``rotor="auto"``); otherwise ``--rotor`` alone.
    """
    s.add_argument("--friction", default=",".join(IDENTIFY["friction"]),
                   help="friction terms per joint: any of viscous, coulomb, offset, comma-separated, or none "
                        "(default all three)")
    if rotor_auto:
        s.add_argument("--rotor", action=argparse.BooleanOptionalAction, default=IDENTIFY["rotor"],
                       help="model each joint's rotor inertia Ia (MJCF armature): --rotor forces it, --no-rotor "
                            "leaves it out; default: tried, kept when blocked cross-validation on the training "
                            "data asks for it (reported with the model terms)")
    else:
        s.add_argument("--rotor", action="store_true", help="model each joint's rotor inertia Ia (MJCF armature)")
    s.add_argument("--convention", metavar=choices("convention"), default=IDENTIFY["convention"],
                   help="convention of the base parameters' names and values (default khalil)")


#: flags no front-door keyword stands for, on every command: help, a hidden older spelling, the parsed command
_NOT_KEYWORDS = {"help", "old_samples", "allow_infeasible_inertia", "func", "command"}


@functools.cache
def keyword_flags(command: str) -> dict[str, str]:
    """Each front-door keyword of a command and the flag (or argument) that gives it.

    Parameters
    ----------
    command : str
        The command (one of :data:`COMMANDS`).

    Returns
    -------
    dict of str to str
        ``{keyword: flag}``: ``{"holdout": "--holdout", "couplings": "--coupling", "out": "out"}``
        (the command module's ``KEYWORDS`` for flags named otherwise, :data:`MODEL_KEYWORDS`,
        and the others under their own names; a positional argument as ``--help`` and the usage
        line name it, argparse's metavar or its name: ``simulate``'s ``out``).
    """
    sub = next(a for a in build_parser()._actions if a.dest == "command")  # noqa: SLF001  (argparse's own)
    renamed = getattr(command_module(command), "KEYWORDS", {})
    out = {}
    for action in sub.choices[command]._actions:  # noqa: SLF001
        if action.dest in _NOT_KEYWORDS or action.help == argparse.SUPPRESS:
            continue
        longs = [s for s in action.option_strings if s.startswith("--")]
        flag = longs[0] if longs else action.metavar or action.dest  # a positional: named as its help names it
        out[renamed.get(action.dest, action.dest)] = flag
    return out


@functools.cache
def switch_flags(command: str) -> dict[str, tuple[str | None, str | None]]:
    """Each front-door keyword of a command given by a switch (a flag without a value) and its two spellings.

    Parameters
    ----------
    command : str
        The command (one of :data:`COMMANDS`).

    Returns
    -------
    dict of str to (str or None, str or None)
        ``{keyword: (on, off)}``: ``{"allow_units": ("--allow-units", None), "rotor": ("--rotor",
        "--no-rotor"), "verify": (None, "--no-verify")}`` (None: leaving the other flag out).
    """
    sub = next(a for a in build_parser()._actions if a.dest == "command")  # noqa: SLF001  (argparse's own)
    renamed = getattr(command_module(command), "KEYWORDS", {})
    out = {}
    for action in sub.choices[command]._actions:  # noqa: SLF001
        longs = [s for s in action.option_strings if s.startswith("--")]
        if action.nargs != 0 or not longs or action.dest in _NOT_KEYWORDS or action.help == argparse.SUPPRESS:
            continue
        key = renamed.get(action.dest, action.dest)
        if isinstance(action, argparse.BooleanOptionalAction):
            out[key] = (longs[0], longs[1])
        elif longs[0] == "--no-" + key.replace("_", "-") and action.const is True:  # --no-verify: verify=False
            out[key] = (None, longs[0])
        elif key == action.dest and (action.const is True or action.const is False):  # store_true, store_false
            out[key] = (longs[0], None) if action.const else (None, longs[0])
    return out


def flag_message(message: str, command: str | None) -> str:
    """A library message with the command's flags for the keywords it names.

    Parameters
    ----------
    message : str
        E.g. ``identify: prior_weight= applies to method=physical, not auto``.
    command : str or None
        The command run (None: the message as it is).

    Returns
    -------
    str
        E.g. ``--prior-weight applies to --method physical, not auto``: ``name=value`` (a value
        quoted or not) as ``--name value``, ``name=`` as ``--name`` (:func:`keyword_flags`), a
        switch's ``name=True`` as ``--name`` and ``name=False`` as ``--no-name`` (or ``without
        --name``: :func:`switch_flags`), a switch of both spellings at its third value (``rotor=auto``)
        as ``neither --rotor nor --no-rotor``, the command's own ``identify:`` prefix left out. A
        message that gives both spellings (``--allow-units (allow_units=True)``, ``(mocap_welds='keep',
        --mocap-welds keep, ...)``) names the flag once.
    """
    if not command or command not in COMMANDS:
        return message
    table = keyword_flags(command)
    text = message.removeprefix(f"{command}: ")
    if not table:
        return text
    names = "|".join(re.escape(k) for k in sorted(table, key=len, reverse=True))
    switches = switch_flags(command)

    def flag(m):
        key, value = m.group(1), m.group(2).strip("'\"")
        if key in switches and value in ("True", "False"):
            on, off = switches[key]
            return (on or f"without {off}") if value == "True" else (off or f"without {on}")
        if key in switches and value and all(switches[key]):  # rotor=auto: the flag left out either way
            return "neither {} nor {}".format(*switches[key])
        return table[key] + (f" {value}" if value else "")

    text = re.sub(rf"(?<![\w.-])({names})=('[^'\s]*'|\"[^\"\s]*\"|\w*)", flag, text)
    one = r"(--[\w-]+(?: [\w.]+)?)"  # a flag and its value, named twice: once
    return re.sub(rf"{one}, \1(?=[,;)]|$)", r"\1", re.sub(rf"{one} \(\1\)", r"\1", text))


def flag_notes(text: str, command: str | None) -> str:
    """A library's text report as the command prints it: its notes with the command's flags.

    Parameters
    ----------
    text : str
        The report (lines; a note is a line ``note: ...``, indented or not, or one with a
        ``WARNING``).
    command : str or None
        The command run (None: the text as it is).

    Returns
    -------
    str
        The same lines, each note through :func:`flag_message` (the report's other lines, tables
        of names and numbers, as they are).
    """
    def line(x: str) -> str:
        head, sep, note = x.partition("note: ")
        if sep and not head.strip():
            return head + sep + flag_message(note, command)
        return flag_message(x, command) if "WARNING" in x else x

    return "\n".join(line(x) for x in text.split("\n"))
