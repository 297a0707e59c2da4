"""``baseparams robots``: the built-in robots, one line each."""

from __future__ import annotations

#: no option: nothing to map
KEYWORDS: dict = {}
CLI_ONLY: frozenset = frozenset()


def add_parser(sub) -> None:
    """The ``robots`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command's subparsers.
    """
    s = sub.add_parser("robots", help="list the built-in robots")
    s.set_defaults(func=run)


def run(args) -> int:
    """``baseparams robots``: list the built-in robots, one line each (bodies, dofs, description).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (unused: the command takes no options).

    Returns
    -------
    int
        The exit code, 0.
    """
    from ..robots import BUILTINS

    for name, (factory, text) in BUILTINS.items():
        r = factory()
        print(f"{name:<10s} {r.n:3d} bodies {r.dof:3d} dofs  {text}")
    try:
        from ..symbolic import builtin_tables, load_symbolic
    except ImportError:
        print("(symbolic robots: install the extra 'symbolic' (SymPy) to list them)")
        return 0
    print("\nsymbolic geometry ('baseparams analyze NAME --symbolic'; without --symbolic: at the listed values):")
    for name, text in builtin_tables().items():
        r = load_symbolic(name)
        print(f"{name:<24s} {r.n:3d} bodies  {text}")
    return 0
