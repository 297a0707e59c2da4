"""Everything a command line can be refused for, before the model loads or any work starts.

No rule lives here: the preflight asks the library's, under the front door's keywords, with the
values the flags parsed into (:func:`baseparams.cli.parser` maps each keyword to its flag in the
message): the numbers' ranges and the choices (:mod:`baseparams.arguments`), the model's options
(:func:`baseparams.loading.check_load`), each command's own checks (:func:`baseparams.analysis.check_analyze`,
:func:`~baseparams.workflow.excite.check_excite`, :func:`~baseparams.workflow.simulate.check_simulate`,
:func:`~baseparams.workflow.identify.plan_identify`, :func:`~baseparams.workflow.identify.check_fleet`,
:func:`~baseparams.workflow.identify.check_predict`, :func:`~baseparams.workflow.payload.check_payload`)
and every output
(:func:`baseparams.workflow.outputs.check_outputs`); what is not installed (:func:`baseparams.arguments.need`).
"""

from __future__ import annotations

import sys
from pathlib import Path

from .common import data_files, input_files, is_symbolic
from .parser import MODEL_KEYWORDS, command_module


def preflight(args) -> None:
    """Check flags, needed extras and output paths before any long work or write.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`baseparams.cli.build_parser`).

    Raises
    ------
    BaseparamsError
        A flag that cannot be honoured, a missing optional module (naming the extra), an
        output in a missing folder, onto a folder or onto an input, a suffix of no known format,
        two outputs onto one file (the options named by their keywords: the caller names the flags).
    """
    from ..arguments import check_keywords
    from ..workflow.outputs import OUTPUTS, check_outputs

    _deprecated_samples(args)
    module = command_module(args.command)
    check_keywords(args.command, **_numbers(args, module))
    if getattr(args, "model", None) is not None and not is_symbolic(args.model):
        from ..loading import check_load

        check_load({k: getattr(args, k) for k in MODEL_KEYWORDS if hasattr(args, k)})
    _check_extras(args)
    inputs = input_files(args)
    _check_command(args, module)
    outputs = {k: getattr(args, k, None) for k in OUTPUTS.get(args.command, ())}
    if args.command == "simulate" and args.robots:
        outputs.pop("out")  # a folder for the fleet's logs
    check_outputs(args.command, inputs, **outputs)


def _deprecated_samples(args) -> None:
    """``--samples`` where it is ``--analysis-samples``: a note, and its value taken."""
    if getattr(args, "old_samples", None) is not None:
        print(f"baseparams: note: {args.command} --samples is deprecated: it is --analysis-samples (the random states "
              f"of the base-parameter analysis, not log samples)", file=sys.stderr)
        if args.samples is None:
            args.samples = args.old_samples


def _numbers(args, module) -> dict:
    """Every numeric flag given, under its keyword (``--analysis-samples``: ``analysis_samples``)."""
    from ..arguments import RANGES

    renamed = getattr(module, "KEYWORDS", {})
    out = {}
    for dest, value in vars(args).items():
        key = renamed.get(dest, dest)
        if key in RANGES and key != "acceleration" and value is not None and not isinstance(value, str):
            out[key] = value  # excite's --acceleration: text, parsed by its command
    return out


def _check_command(args, module) -> None:
    """The command's own checks that need no model (the library's, with the flags as keywords)."""
    cmd = args.command
    if cmd == "analyze":
        from ..analysis import check_analyze

        check_analyze(module.keywords(args))
    elif cmd == "excite":
        from ..workflow.excite import check_excite

        check_excite(args.model, module.keywords(args))
    elif cmd == "simulate":
        from ..workflow.simulate import check_simulate

        kw = module.keywords(args)
        check_simulate(args.model, kw.pop("trajectory"), kw)
    elif cmd == "predict":
        from ..workflow.identify import check_predict

        check_predict(args.model, args.result, args.log, module.keywords(args))
    elif cmd == "payload":
        from ..workflow.payload import check_payload

        check_payload(args.model, args.log, module.keywords(args))
    elif cmd == "identify" and module.is_fleet(args):
        from ..workflow.identify import check_fleet

        check_fleet(module.keywords(args))
    elif cmd == "identify":
        from ..workflow.identify import Reporter, plan_identify

        plan_identify(args.model, module.log_argument(args), module.keywords(args), Reporter(source=args.model))


def _check_extras(args) -> None:
    """The optional modules the flags need, before any work."""
    from ..arguments import need

    cmd = args.command
    if getattr(args, "plot", None):
        need("matplotlib", "--plot")
    model = getattr(args, "model", None)
    if model and is_symbolic(model) or getattr(args, "symbolic", False):
        need("sympy", "a symbolic robot (DH table)")
    if model and Path(model).suffix.lower() == ".xacro":
        need("xacro", f"{model}: a xacro model")
    if cmd == "analyze" and model and any(ch in model for ch in "*?["):
        need("distributed", "a sweep over files (a glob MODEL)")
    if cmd != "identify":
        return
    if args.method == "physical":
        need("cvxpy", "--method physical")
        need("clarabel", "--method physical")
    files = data_files(args.data) + ([args.validate] if args.validate else [])
    if args.per_file or args.pooled:
        need("distributed", "identification over a fleet of logs (--per-file / --pooled)")
    for f in files:
        suffix = Path(f).suffix.lower()
        if suffix in (".parquet", ".pq"):
            need("pyarrow", f"{f}: reading Parquet")
        elif suffix in (".mcap", ".db3", ".bag") or Path(f).is_dir():
            need("rosbags", f"{f}: reading a ROS bag")
