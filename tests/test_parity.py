"""Both doors, one rule: every option of every command accepted and refused alike by the CLI and ``bp.*``.

The options are found by walking the parser itself (every action of every subcommand), so an
option added later is tested here or has to be declared: a keyword of a front-door function
(:func:`baseparams.load` for the model's, the command's own function otherwise), an output, or
one of the command module's ``CLI_ONLY`` flags (how the result is printed). For each option,
values inside and outside its range (:data:`baseparams.arguments.RANGES`), its choices
(:data:`baseparams.arguments.CHOICES`), an output's formats (:data:`baseparams.workflow.outputs.SUFFIXES`),
or text cases of its own, are given once on the command line and once in Python: both must accept
(reach the work, which is stopped here) or both refuse, with the same one line modulo the option's
spelling (``holdout=`` / ``--holdout``: :func:`baseparams.cli.parser.flag_message`).
"""

from __future__ import annotations

import argparse
import math
import sys

import pytest

import baseparams as bp
from baseparams.arguments import CHOICES, RANGES
from baseparams.cli import build_parser, main
from baseparams.cli.parser import COMMANDS, MODEL_KEYWORDS, command_module, flag_message, keyword_flags
from baseparams.errors import BaseparamsError
from baseparams.workflow.outputs import OUTPUTS, SUFFIXES


class Accepted(Exception):  # noqa: N818 - a signal, not an error
    """Raised where the work would start: the call was accepted."""


def _stop(*args, **kwargs):
    raise Accepted


@pytest.fixture
def no_work(monkeypatch):
    """Every command's work replaced by :class:`Accepted` (the checks before it run as they do)."""
    monkeypatch.setattr("baseparams.analysis._analyze", _stop)  # analyze, and excite's analysis_samples
    monkeypatch.setattr("baseparams.excitation.design_excitation", _stop)
    monkeypatch.setattr(sys.modules["baseparams.workflow.simulate"], "_simulated", _stop)
    monkeypatch.setattr(sys.modules["baseparams.workflow.simulate"], "_fleet", _stop)
    monkeypatch.setattr(sys.modules["baseparams.workflow.identify"], "_run_identification", _stop)
    monkeypatch.setattr("baseparams.ident.Identification.load", _stop)
    monkeypatch.setattr("baseparams.analysis.regressor", _stop)
    monkeypatch.setattr(sys.modules["baseparams.workflow.payload"], "_run", _stop)  # payload: after the link's check
    monkeypatch.setattr("baseparams.excitation.payload.excite_payload", _stop)  # excite payload=


#: the token standing for a ``--no-FLAG`` spelling (an ``argparse.BooleanOptionalAction``: ``--no-rotor``)
NEGATED = "<negated>"

#: flags whose keyword is the negation of the flag (``--no-verify`` is ``verify=False``)
INVERTED = {"no_verify", "paper_only"}

#: text options: ``(Python value, command-line tokens)`` per case (a path "{d}" in the test's folder); keyed by
#: ``(command, keyword)`` where two commands' keywords of one name differ
TEXT = {
    "friction": [("viscous,offset", ["viscous,offset"]), ("sticky", ["sticky"]), ("none", ["none"])],
    "terms": [("none", ["none"]), ("wobble", ["wobble"]), ("dahl,tilt", ["dahl,tilt"])],
    "couplings": [(("m6:joint5=1,joint6=1",), ["m6:joint5=1,joint6=1"]), (("m6",), ["m6"])],
    "joints": [("joint1,joint2", ["joint1,joint2"]), (",", [","])],
    "weld": [(["joint3=0.1"], ["joint3=0.1"]), (["joint3"], ["joint3"]), (["joint3=nan"], ["joint3=nan"])],
    "rows": [("all", ["all"]), ("joints", ["joints"])],
    "truth": [("{d}/missing.json", ["{d}/missing.json"])],
    "columns": [("{d}/map.toml", ["{d}/map.toml"])],
    "validate": [("{d}/other.csv", ["{d}/other.csv"])],
    "trajectory": [("{d}/traj.csv", ["{d}/traj.csv"])],
    "xacro_args": [(["a:=1"], ["a:=1"])],
    "package_path": [(["{d}"], ["{d}"])],
    "states": [("{d}/states.csv", ["{d}/states.csv"])],
    "velocity": [(1.5, ["1.5"]), (-1.0, ["-1"]), (math.nan, ["nan"])],
    ("excite", "effort"): [(20.0, ["20"]), (math.inf, ["inf"])],  # identify's effort= is a choice
    "gain_anchor": [("joint2=12.5", ["joint2=12.5"]), ("joint2=12.5,joint3=8", ["joint2=12.5,joint3=8"]),
                    ("joint2", ["joint2"]), ("joint2=0", ["joint2=0"]), ("joint2=x", ["joint2=x"]),
                    ("joint2=1,joint2=2", ["joint2=1,joint2=2"])],
    "position": [((-1.0, 1.0), ["-1:1"]), ((1.0, -1.0), ["1:-1"])],
    "acceleration": [(5.0, ["5"]), (-1.0, ["-1"]), (math.nan, ["nan"])],
    "keepout": [([("link2", 0.1)], ["link2:0.1"]), ([("nolink", 0.1)], ["nolink:0.1"])],
    "link": [("link6", ["link6"]), ("joint3", ["joint3"]), ("nolink", ["nolink"])],
    "payload": [("link3", ["link3"]), ("nolink", ["nolink"])],
    "result": [("{d}/r.json", ["{d}/r.json"])],
    "prior": [("{d}/prior.json", ["{d}/prior.json"]), ("{d}/missing.json", ["{d}/missing.json"]),
              ("{d}/map.toml", ["{d}/map.toml"])],
}
#: the other options an option needs to mean anything (``weld`` with ``joints``), by option or by (command, option)
CONTEXT = {"weld": {"joints": "joint1,joint2"}, "predictions": {"holdout": 1.0},
           ("payload", "predictions"): {"validate": "{d}/other.csv"}, ("excite", "payload_noise"): {"payload": "link6"}}


def _actions(command: str):
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))  # noqa: SLF001
    return sub.choices[command]._actions  # noqa: SLF001


def _numbers(keyword: str, typ) -> list:
    """Values inside and outside the keyword's range (integers only for an integer flag: a fraction is a parse)."""
    r = RANGES[keyword]
    lo = r.lo + (1 if r.integer else 1e-6 * max(1.0, abs(r.lo))) if r.lo_open else r.lo
    hi = r.hi - (1 if r.integer else 1e-6 * abs(r.hi)) if r.hi_open else r.hi
    inside = [lo, hi, (lo + hi) / 2]
    outside = [r.lo - 1, r.hi * 10 + 1] + ([r.lo] if r.lo_open else []) + ([r.hi] if r.hi_open else [])
    values = [int(v) if r.integer else float(v) for v in inside + outside]
    if not r.integer:
        values += [math.nan, math.inf]
    return values


def _text(value) -> str:
    return str(value) if isinstance(value, int) else repr(float(value))


def _cases():
    """``(command, keyword, dest, Python value, command-line tokens)`` for every option of every command."""
    out, undeclared = [], []
    for command in COMMANDS[1:]:
        module = command_module(command)
        renamed = getattr(module, "KEYWORDS", {})
        outputs = OUTPUTS.get(command, {})
        choices = {**CHOICES, **getattr(module, "CHOICES", {})}  # a command's own over the shared (payload --method ls)
        for a in _actions(command):
            if a.help == argparse.SUPPRESS or a.dest in ("help", "func") or not a.option_strings and a.dest in (
                    "model", "data", "result", "log"):
                continue
            key = renamed.get(a.dest, a.dest)
            if a.dest in module.CLI_ONLY:
                continue
            if key in outputs:
                kind = outputs[key]
                good = (SUFFIXES[kind] or (".txt",))[0]
                values = [f"{{d}}/o{good}", "{d}/o.weird", "{d}/missing/o" + good]
                out += [(command, key, a.dest, v, [v]) for v in values]
            elif isinstance(a, argparse._StoreTrueAction):  # noqa: SLF001
                out.append((command, key, a.dest, a.dest not in INVERTED, []))
            elif isinstance(a, argparse.BooleanOptionalAction):  # --rotor / --no-rotor: both spellings
                out += [(command, key, a.dest, True, []), (command, key, a.dest, False, [NEGATED])]
            elif key in RANGES and a.type in (int, float):
                for v in _numbers(key, a.type):
                    tokens = [_text(v)] if a.nargs is None else ["0", "0", _text(v)]
                    out.append((command, key, a.dest, v if a.nargs is None else (0.0, 0.0, v), tokens))
            elif (command, key) in TEXT:
                out += [(command, key, a.dest, v, list(t)) for v, t in TEXT[command, key]]
            elif key in choices:
                out += [(command, key, a.dest, v, [v]) for v in (*choices[key], "nope")]
            elif key in TEXT:
                out += [(command, key, a.dest, v, list(t)) for v, t in TEXT[key]]
            else:
                undeclared.append(f"{command} {a.option_strings or a.dest}")
    return out, undeclared


CASES, UNDECLARED = _cases()


def test_every_option_of_every_command_is_tested_or_declared():
    assert not UNDECLARED, f"options with no case and not CLI_ONLY: {UNDECLARED}"
    assert len({(c, k) for c, k, *_ in CASES}) > 80


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A states file and a trajectory (real ones: the regressor and simulate read them before the work)."""
    d = tmp_path_factory.mktemp("parity")
    bp.simulate("puma560", duration=0.82, rate=100.0, out=d / "states.csv")  # identify's shortest log
    bp.excite("puma560", harmonics=2, period=2, rate=50, starts=1, grid=40, out=d / "traj.csv")
    (d / "map.toml").write_text("")
    (d / "prior.json").write_text('{"mass": 1.0, "com": [0, 0, 0.05], "inertia_com": [[0.01, 0, 0], [0, 0.01, 0], '
                                  '[0, 0, 0.01]]}')
    return d


def _fill(value, d):
    if isinstance(value, str):
        return value.replace("{d}", str(d))
    if isinstance(value, list):
        return [_fill(v, d) for v in value]
    return value


DOORS = {"analyze": bp.analyze, "identify": bp.identify, "predict": bp.predict, "simulate": bp.simulate,
         "excite": bp.excite, "payload": bp.identify_payload}


def _python(command: str, keywords: dict, d):
    """The front door's call for ``keywords`` (the model's keywords go to ``bp.load``; an output the command line
    writes itself, the report, to the outputs' rule)."""
    import inspect

    from baseparams.workflow.outputs import check_outputs

    load = {k: keywords.pop(k) for k in list(keywords) if k in MODEL_KEYWORDS}
    if load:
        return bp.load("puma560", **load)
    own = {k: keywords[k] for k in keywords if k in OUTPUTS.get(command, {}) and command in DOORS
           and k not in inspect.signature(DOORS[command]).parameters}
    if own:
        check_outputs(command, [], **own)
        raise Accepted
    log, res = str(d / "log.csv"), str(d / "r.json")
    if command == "analyze":
        return bp.analyze(bp.load("puma560"), **keywords)
    if command == "regressor":
        from baseparams.workflow.states import states_regressor

        samples = {k: keywords.pop(k) for k in ("samples", "seed") if k in keywords}
        if samples:  # the random states' count and seed: no Python function times the regressor
            from baseparams.arguments import check_keywords

            return check_keywords("regressor", **samples)
        states = keywords.pop("states", str(d / "states.csv"))
        return states_regressor("puma560", states, **keywords)
    if command == "identify":
        return bp.identify("puma560", log, **keywords)
    if command == "predict":
        return bp.predict("puma560", res, log, **keywords)
    if command == "simulate":
        return bp.simulate("puma560", **{"out": str(d / "sim.csv"), **keywords})
    if command == "payload":
        return bp.identify_payload("puma560", log, **{"link": "link6", **keywords})
    return bp.excite("puma560", **keywords)


def _argv(command: str, tokens: dict, d) -> list[str]:
    head = {"analyze": ["analyze", "puma560"], "regressor": ["regressor", "puma560"], "excite": ["excite", "puma560"],
            "identify": ["identify", "puma560", str(d / "log.csv")],
            "predict": ["predict", "puma560", str(d / "r.json"), str(d / "log.csv")],
            "simulate": ["simulate", "puma560"], "payload": ["payload", "puma560", str(d / "log.csv")]}[command]
    flags = keyword_flags(command)
    argv = list(head)
    if command == "simulate":
        argv.append(tokens.pop("out", [str(d / "sim.csv")])[0])
    if command == "regressor" and "states" not in tokens and "out" in tokens:
        tokens["states"] = [str(d / "states.csv")]
    if command == "payload" and "link" not in tokens:
        tokens["link"] = ["link6"]
    for key, toks in tokens.items():  # a value starting with '-' after '=' (--position=-1:1)
        if toks == [NEGATED]:
            argv.append("--no-" + flags[key].removeprefix("--"))
            continue
        argv += [f"{flags[key]}={toks[0]}"] if len(toks) == 1 and toks[0].startswith("-") else [flags[key], *toks]
    return argv


def _python_outcome(command, keywords, d):
    try:
        _python(command, dict(keywords), d)
    except Accepted:
        return "accepted", ""
    except BaseparamsError as exc:
        return "refused", flag_message(str(exc), command)
    return "accepted", ""


def _cli_outcome(argv, capsys):
    try:
        code = main(argv)
    except Accepted:
        return "accepted", ""
    except SystemExit as exc:  # argparse: not a number of the flag's type
        code = exc.code
    err = [e for e in capsys.readouterr().err.splitlines() if e.startswith("baseparams: error: ")]
    if code == 0:
        return "accepted", ""
    assert len(err) == 1, (argv, err)
    return "refused", err[0].removeprefix("baseparams: error: ")


def _tokens(command, key, dest, value, toks, d):
    """The case as Python keywords and command-line tokens, with the options it needs."""
    context = {k: _fill(v, d) for k, v in CONTEXT.get((command, key), CONTEXT.get(key, {})).items()}
    keywords = {**context, key: _fill(value, d)}
    tokens = {k: [_text(v) if not isinstance(v, str) else v] for k, v in context.items()}
    tokens[key] = _fill(toks, d)
    return keywords, tokens


@pytest.mark.parametrize("command, key, dest, value, toks", CASES,
                         ids=[f"{c}-{k}-{str(v)[:24]}" for c, k, _, v, _ in CASES])
def test_the_cli_and_python_accept_and_refuse_alike(command, key, dest, value, toks, files, no_work, capsys):
    keywords, tokens = _tokens(command, key, dest, value, toks, files)
    py = _python_outcome(command, keywords, files)
    cli = _cli_outcome(_argv(command, tokens, files), capsys)
    assert py == cli, f"Python {py} vs CLI {cli}"
    if py[0] == "refused":
        assert "\n" not in py[1] and "Traceback" not in py[1]


@pytest.mark.parametrize("command, keywords, words", [
    ("identify", {"save": "{d}/o.html", "html": "{d}/o.html"}, "name the same file"),
    ("identify", {"save": "{d}/p.csv", "predictions": "{d}/p.csv", "holdout": 1.0}, "name the same file"),
    ("identify", {"prior_weight": 5.0}, "applies to --method physical, not auto"),
    ("identify", {"prior_weight": 5.0, "method": "ols"}, "applies to --method physical, not ols"),
    ("identify", {"score_cutoff": 5.0}, "are about validation data"),
    ("excite", {"out": "{d}/t.csv", "plot": "{d}/t.csv"}, "format comes from the suffix"),
    ("excite", {"period": 5.0, "base_frequency": 0.2}, "give --period or --base-frequency, not both"),
    ("identify", {"holdout": 1.0, "validate": "{d}/other.csv"}, "give --holdout SECONDS or --validate LOG, not both"),
    ("payload", {"link": "link6", "predictions": "{d}/p.csv"}, "give --validate"),
    ("payload", {"link": "link6", "save": "{d}/p.json", "urdf": "{d}/p.json"}, "--urdf"),
    ("excite", {"payload": "link6", "base_frequency": 0.2}, "--base-frequency do not apply (--period does)"),
    ("excite", {"payload_noise": 0.5}, "--payload-noise applies to --payload"),
    ("identify", {"gain_anchor": "joint2=12.5", "effort": "torque"}, "--gain-anchor applies to motor currents "
                                                                     "(--effort current), not to torques"),
])
def test_the_issue_s_cases_refused_alike(command, keywords, words, files, no_work, capsys):
    """The issue's examples: two outputs onto one file, ``prior_weight`` without the physical fit (both doors)."""
    keywords = {k: _fill(v, files) for k, v in keywords.items()}
    py = _python_outcome(command, keywords, files)
    tokens = {k: [v if isinstance(v, str) else _text(v)] for k, v in keywords.items()}
    cli = _cli_outcome(_argv(command, tokens, files), capsys)
    assert py == cli and py[0] == "refused" and words in py[1], (py, cli)
    assert not any(p.name.startswith(("o.", "p.", "t.")) for p in files.iterdir())


def test_the_defaults_are_one():
    """Every option's default on the command line is its keyword's default in Python."""
    import inspect

    for command, fn in DOORS.items():
        sig = inspect.signature(fn).parameters
        renamed = getattr(command_module(command), "KEYWORDS", {})
        for a in _actions(command):
            key = renamed.get(a.dest, a.dest)
            if (key not in sig or a.dest in INVERTED or not a.option_strings or a.help == argparse.SUPPRESS
                    or a.required):
                continue
            default, cli_default = sig[key].default, a.default
            if key == "friction":  # the flag's text: "viscous,coulomb,offset"
                default = ",".join(default)
            if key == "couplings":  # a repeated flag: None when not given
                cli_default = () if a.default is None else a.default
            assert cli_default == default, (command, key, cli_default, default)
