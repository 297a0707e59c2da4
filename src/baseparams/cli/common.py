"""What every ``baseparams`` subcommand needs: exit codes, progress lines, the robot, the outputs.

The modules of the subcommands (:mod:`baseparams.cli.identify`, ...) import from here, never from
:mod:`baseparams.cli` itself (which imports them for its parser).
"""

from __future__ import annotations

import itertools
import json
import sys
import threading
import time
from pathlib import Path

from ..enums import Status
from ..errors import BaseparamsError, NoMovingBodiesError
from .parser import flag_message

#: exit codes (see the module doc)
EXIT_OK, EXIT_INPUT, EXIT_UNDECIDED, EXIT_FAILED, EXIT_INTERRUPTED = 0, 2, 3, 4, 130


STATUS_EXIT = {Status.CERTIFIED: EXIT_OK, Status.COMPLETED: EXIT_OK, Status.UNVERIFIED: EXIT_OK,
                Status.UNDECIDED: EXIT_UNDECIDED, Status.FAILED: EXIT_FAILED}


#: seconds after which a run without ``-v`` starts showing its progress lines on stderr
PROGRESS_AFTER_S = 2.0


class Progress:
    """Progress lines on stderr (``baseparams: STEP [elapsed]``) for long runs.

    With ``verbose`` every line is printed. Otherwise the lines are held back until the run has
    taken :data:`PROGRESS_AFTER_S` seconds: then the current step is printed (a timer thread, so a
    long step shows even before the next line) and every later line as it comes; a short run stays
    quiet. Callable with one line, or usable as the text stream that
    :func:`baseparams.analysis.analyze` writes to (``write``, ``flush``). A context manager: leaving
    it stops the timer.

    Parameters
    ----------
    verbose : bool
        Print every line from the start (``-v``).
    after : float, optional
        Seconds before the lines show without ``verbose`` (default :data:`PROGRESS_AFTER_S`).
    """

    def __init__(self, verbose: bool, after: float | None = None):
        self.t0 = time.perf_counter()
        self.shown = bool(verbose)
        self.last: str | None = None
        self.lock = threading.Lock()
        self.timer = None
        if not verbose:
            self.timer = threading.Timer(PROGRESS_AFTER_S if after is None else after, self._late)
            self.timer.daemon = True
            self.timer.start()

    def _print(self, msg: str) -> None:
        print(f"baseparams: {msg} [{time.perf_counter() - self.t0:.1f} s]", file=sys.stderr, flush=True)

    def _late(self) -> None:
        with self.lock:
            self.shown = True
            if self.last is not None:
                self._print(f"{self.last} ...")

    def __call__(self, msg: str) -> None:
        """One progress line: printed now if lines show, else held as the current step."""
        with self.lock:
            self.last = msg
            if self.shown:
                self._print(msg)

    def write(self, text: str) -> int:
        """Take text written as to a stream: each non-empty line is a progress line.

        Parameters
        ----------
        text : str
            The text (``[baseparams]`` prefixes dropped).

        Returns
        -------
        int
            ``len(text)``, as a stream's ``write``.
        """
        for line in text.splitlines():
            if line.strip():
                self(line.removeprefix("[baseparams] ").strip())
        return len(text)

    def flush(self) -> None:
        """Nothing to flush: lines are printed as they come."""

    def close(self) -> None:
        """Stop the timer (no line is printed after this)."""
        with self.lock:
            self.shown = False
        if self.timer is not None:
            self.timer.cancel()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def load_robot(args) -> Robot:  # noqa: F821
    """The command's robot (``MODEL`` and its options), the loader's notes and a ``--floating`` hint on stderr.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    Robot
        The robot (a symbolic table's at its values).
    """
    from ..loading import load_model

    if is_symbolic(args.model):  # a DH table with symbols: analysed numerically at its values
        return symbolic_robot(args)
    robot, notes = load_model(args.model, floating=getattr(args, "floating", False), gravity=args.gravity,
                              strict_inertia=getattr(args, "strict_inertia", False),
                              xacro_args=getattr(args, "xacro_args", None),
                              package_path=getattr(args, "package_path", None),
                              mocap_welds=getattr(args, "mocap_welds", "drop"))
    for note in notes:
        print_note(note, args.command)
    hint = floating_hint(robot) if Path(args.model).is_file() and not getattr(args, "floating", False) else ""
    if hint:
        print_note(hint, args.command)
    return robot


def print_note(line: str, command: str) -> None:
    """A note of the run on stderr (``baseparams: note: ...``; an output written: ``baseparams: ... written to``).

    Parameters
    ----------
    line : str
        The note (options named by their keywords: printed as the command's flags, :func:`flag_message`).
    command : str
        The command, whose flags name the options.
    """
    line = flag_message(line, command)
    print(f"baseparams: {'' if ' written to ' in line else 'note: '}{line}", file=sys.stderr)


#: names of joints on a fixed root that suggest the base moves (a leg's hip, a wheel)
_MOBILE_WORDS = ("wheel", "leg", "hip", "haa", "hfe", "foot", "caster")


def floating_hint(robot) -> str:
    """A hint to pass ``--floating`` when a fixed root carries legs or wheels ('' when not).

    Parameters
    ----------
    robot : Robot
        A robot read with a fixed base.

    Returns
    -------
    str
        One line when the root link carries three or more chains, or chains whose joints are
        named like legs or wheels; else ''.
    """
    if robot.floating or robot.n == 0:
        return ""
    roots = [k for k in range(robot.n) if robot.parent[k] < 0]
    names = [robot.joint_names[k].lower() for k in roots]
    mobile = [n for n in names if any(w in n for w in _MOBILE_WORDS)]
    if len(roots) < 3 and not mobile:
        return ""
    return (f"the fixed root link carries {len(roots)} chains ({', '.join(robot.joint_names[k] for k in roots[:4])}"
            f"{', ...' if len(roots) > 4 else ''}): if they are legs or wheels the base moves: pass --floating to "
            f"attach it by a free joint")


def no_moving_bodies(args, exc: NoMovingBodiesError) -> int:
    """A model whose links are all welded to the world: an empty, trivially certified result.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    exc : NoMovingBodiesError
        The loader's error.

    Returns
    -------
    int
        :data:`EXIT_OK`.
    """
    name = Path(args.model).stem
    hint = "" if getattr(args, "floating", False) else "; --floating attaches the root link by a free joint"
    msg = (f"{exc}: every link is welded to the world, so no measurement sees any inertial parameter "
           f"(0 standard, 0 base parameters){hint}")
    if args.json:
        emit(args, json.dumps({"model": name, "n_bodies": 0, "n_params": 0, "nullity": 0, "n_base": 0,
                                "certified": True, "status": Status.CERTIFIED, "message": msg,
                                "base_parameters": [], "unidentifiable": []}, indent=2))
    else:
        emit(args, f"{name}: {msg}")
    return EXIT_OK


def emit(args, text) -> None:
    """The report: on stdout, or written to ``--output`` (atomically, never onto an input).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    text : str or iterable of str
        The report, or its consecutive pieces (written as they are made: a large report is
        never held whole).
    """
    pieces = (text,) if isinstance(text, str) else text
    out = getattr(args, "output", None)
    if not out:
        for piece in pieces:
            sys.stdout.write(piece)
        sys.stdout.write("\n")
        sys.stdout.flush()
        return
    from ..files import write_pieces

    try:
        write_pieces(out, itertools.chain(pieces, ("\n",)), input_files(args), "--output")
    except OSError as exc:
        raise BaseparamsError(f"--output {out}: cannot write ({exc.strerror or exc})") from None
    if not args.json:
        print(f"report written to {out}")


def write_html(path: str, page: str, inputs=()) -> None:
    """``--html FILE``: write a self-contained report (atomically, never onto an input), or one line saying why not.

    Parameters
    ----------
    path : str
        The output file.
    page : str
        The HTML page.
    inputs : sequence of str, optional
        The run's input files (never overwritten).
    """
    from ..files import write_text

    try:
        write_text(path, page, inputs, "--html")
    except OSError as exc:
        raise BaseparamsError(f"--html {path}: cannot write ({exc.strerror or exc})") from None
    print(f"baseparams: HTML report written to {path}", file=sys.stderr)


def data_files(pattern: str) -> list[str]:
    """``DATA``: a file, a folder (a ROS 2 bag), or a glob pattern (``**`` recursive), sorted.

    Parameters
    ----------
    pattern : str or list of str
        The ``DATA`` argument (or several).

    Returns
    -------
    list of str
        The files.
    """
    import glob

    if isinstance(pattern, (list, tuple)):  # identify's DATA...: each a file or a pattern
        return [f for p in pattern for f in data_files(p)]
    if any(ch in pattern for ch in "*?["):
        files, t0 = [], time.monotonic()
        for f in glob.iglob(pattern, recursive=True):  # bounded: '/**' would walk the whole file system
            files.append(f)
            if len(files) > MAX_GLOB_FILES or time.monotonic() - t0 > MAX_GLOB_SECONDS:
                why = f"matches more than {MAX_GLOB_FILES} files" if len(files) > MAX_GLOB_FILES else \
                    f"takes more than {MAX_GLOB_SECONDS:g} s to list"
                raise BaseparamsError(f"{pattern!r}: the pattern {why}; narrow it")
        if not files:
            raise BaseparamsError(f"no file matches {pattern!r}")
        return sorted(files)
    return [pattern]


#: a glob pattern's bounds (``DATA``, a sweep's ``MODEL``): files matched and seconds spent listing
MAX_GLOB_FILES = 100_000
MAX_GLOB_SECONDS = 20.0


def input_files(args) -> list[str]:
    """The run's input files (model, logs, mapping, trajectory): outputs must not overwrite them.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    list of str
        The input files.
    """
    out = []
    model = getattr(args, "model", None)
    if model and Path(model).exists():
        out.append(model)
        from ..io.sources import model_files  # what the model includes: MJCF includes and assets, xacro files

        out += [str(f) for f in _model_files(model, model_files, getattr(args, "xacro_args", None),
                                             getattr(args, "package_path", None))[1:]]
    if getattr(args, "data", None):
        out += data_files(args.data)
    out += [getattr(args, k) for k in ("validate", "columns", "trajectory", "truth", "result", "log", "states")
            if isinstance(getattr(args, k, None), str)]
    return out


#: the files of the models seen in this process: ``{(path, mtime, args): files}`` (a run asks several times)
_MODEL_FILES: dict = {}


def _model_files(model: str, lister, xacro_args, package_path) -> list:
    """:func:`baseparams.io.sources.model_files`, once per model file and state."""
    st = Path(model).stat()
    key = (str(Path(model).resolve()), st.st_mtime_ns, st.st_size, tuple(xacro_args or ()), tuple(package_path or ()))
    if key not in _MODEL_FILES:
        _MODEL_FILES[key] = lister(model, xacro_args, package_path)
    return _MODEL_FILES[key]


def is_symbolic(model: str) -> bool:
    """A DH table file or a built-in symbolic robot's name (``*-symbolic``).

    Parameters
    ----------
    model : str
        The ``MODEL`` argument.

    Returns
    -------
    bool
        Whether it is a symbolic robot.
    """
    return model.endswith(".dh") or (model.lower().endswith("-symbolic") and not Path(model).exists())


def load_symbolic_table(args):
    """The symbolic robot of ``MODEL`` (a DH table or a ``*-symbolic`` built-in), or one line saying why not.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    SymbolicRobot
        The symbolic robot.
    """
    try:
        from ..symbolic import load_symbolic
    except ImportError:
        raise BaseparamsError("symbolic robots need SymPy: pip install 'baseparams[symbolic]'") from None
    robot = load_symbolic(args.model)
    if args.gravity is not None:
        raise BaseparamsError(f"{args.model}: a symbolic robot's gravity is in its table (the 'gravity' line)")
    return robot


def symbolic_robot(args):
    """The numeric robot of a symbolic table at its ``values`` (``--values`` overrides).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    Robot
        The numeric robot.
    """
    vals = dict(v.split("=", 1) for v in (args.values or []) if "=" in v)
    bad = [v for v in (args.values or []) if "=" not in v]
    if bad:
        raise BaseparamsError(f"--values {bad[0]}: expected NAME=NUMBER")
    robot = load_symbolic_table(args)
    try:
        vals = {k: float(v) for k, v in vals.items()}
    except ValueError as exc:
        raise BaseparamsError(f"--values: {exc}") from None
    bad = [f"{k}={v}" for k, v in vals.items() if not abs(v) <= 1e6]
    if bad:
        raise BaseparamsError(f"--values {bad[0]}: a finite number within [-1e6, 1e6] (lengths in m, angles in rad)")
    return robot.to_robot(vals)
