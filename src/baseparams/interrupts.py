"""SIGINT and SIGTERM honoured cleanly, wherever a run is (a pass over a log, a solver, a write).

The command line (:func:`baseparams.cli.main`) runs every subcommand inside :class:`Interrupts`,
and a streamed identification checks it at every block (:mod:`baseparams.ident.stream`): Ctrl-C
raises :class:`KeyboardInterrupt`, SIGTERM :class:`Terminated`, and both unwind through every open
output, whose temporary file is removed (:func:`baseparams.files.atomic_path`): an interrupted run
leaves no partial file.
"""

from __future__ import annotations


class Terminated(SystemExit):
    """SIGTERM received: the run stops as Python stops on ``sys.exit`` (status :data:`EXIT_TERMINATED`)."""


#: the exit status of a run stopped by SIGTERM (128 + 15, as a shell reports a process it terminated)
EXIT_TERMINATED = 143


class Interrupts:
    """SIGINT and SIGTERM honoured cleanly: the command line's whole run, every pass of a streamed identification.

    Within ``with Interrupts() as guard``, SIGINT raises :class:`KeyboardInterrupt` at once (as
    Python's own handler does) and SIGTERM :class:`Terminated` (Python's default would end the
    process at once, leaving an output's temporary file behind), and either is remembered:
    :meth:`check`, called at every block of every pass and at every step of a streamed run, raises it
    again when the first one was caught by code between (a C extension's blanket error handling,
    a lazy import's fallback), and so does leaving the block. The exception unwinds every open
    output (their temporary files removed: :func:`baseparams.files.atomic_path`). A handler
    installed before (``SIG_IGN`` aside: then none is installed for that signal) is called as
    well (so guards nest: the command line's and a stream's); outside the main thread (no
    signals there) nothing is installed.
    """

    def __init__(self):
        self.pending: BaseException | None = None
        self.previous: dict = {}

    def __enter__(self) -> Interrupts:
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                previous = signal.getsignal(sig)
                if previous is not signal.SIG_IGN:
                    self.previous[sig] = previous
                    signal.signal(sig, self._handler)
        return self

    def _handler(self, signum, frame):
        import signal

        stop = KeyboardInterrupt() if signum == signal.SIGINT else Terminated(EXIT_TERMINATED)
        self.pending = stop
        previous = self.previous.get(signum)
        if callable(previous) and previous is not signal.default_int_handler:
            previous(signum, frame)
        raise stop

    def check(self) -> None:
        """Raise the interrupt again if a signal came (and was swallowed since).

        Raises
        ------
        KeyboardInterrupt
            After a SIGINT.
        Terminated
            After a SIGTERM (status :data:`EXIT_TERMINATED`).
        """
        if self.pending is not None:
            raise self.pending

    def __exit__(self, kind, value, tb) -> None:
        import signal

        for sig, previous in self.previous.items():
            signal.signal(sig, previous if previous is not None else signal.SIG_DFL)
        self.previous = {}
        if kind is None:
            self.check()
