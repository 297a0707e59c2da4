"""One options object for identification: defaults written once, checked once, saved and read back.

:class:`baseparams.ident.options.IdentOptions` is what the front door, the command line and the
fleet build and every path takes; these tests hold the places that spell an option (the front
door's signature, the parser, the saved file) to it.
"""

from __future__ import annotations

import inspect
import json
from dataclasses import fields, replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import baseparams
from baseparams.arguments import IDENTIFY
from baseparams.cli import build_parser, main
from baseparams.cli.parser import COMMANDS, flag_message, flag_notes, keyword_flags, switch_flags
from baseparams.errors import GO_ON, BaseparamsError, going_on
from baseparams.ident import IdentOptions, MotorCoupling, identify
from baseparams.ident.simulate import simulate_log
from baseparams.ident.stream import identify_stream
from baseparams.io.logs import LogStream, write_log
from baseparams.schema import OPTIONS, check


def test_the_defaults_are_written_once():
    """IdentOptions' fields are arguments.IDENTIFY's, in its order, with its defaults (where the front door and
    the parser read them)."""
    assert [(f.name, f.default) for f in fields(IdentOptions)] == list(IDENTIFY.items())
    assert IdentOptions().to_json() == {**IDENTIFY, "friction": list(IDENTIFY["friction"]), "couplings": []}


def test_the_front_door_defaults_are_the_options_defaults():
    """``bp.identify``'s keywords that are options default to IdentOptions' defaults, each one of them."""
    sig = inspect.signature(baseparams.identify).parameters
    names = {f.name for f in fields(IdentOptions)} - {"memory_mb"}  # no flag: the library's bound
    assert names <= set(sig)
    for f in fields(IdentOptions):
        if f.name in sig:
            assert sig[f.name].default == f.default, f.name


def test_the_parser_defaults_are_the_options_defaults():
    args = build_parser().parse_args(["identify", "puma560", "log.csv"])
    from baseparams.cli.identify import keywords

    names = {f.name for f in fields(IdentOptions)}
    assert IdentOptions(**{k: v for k, v in keywords(args).items() if k in names}) == IdentOptions()


def test_json_round_trip_and_an_older_file():
    opts = IdentOptions(method="physical", rotor=True, friction="viscous,coulomb", coulomb_width=0.05,
                        couplings=("m6:joint5=1,joint6=1",), holdout=2, cutoff=8.0, decimate=3, min_speed=0.01,
                        prior_weight=0.5, convention="paper", covariance="white", score_cutoff=4.0, allow_units=True,
                        literal=True, terms=("dahl", "tilt"), analysis_samples=300, seed=4, memory_mb=16.0)
    assert opts.friction == ("viscous", "coulomb") and opts.terms == "dahl,tilt"
    assert isinstance(opts.couplings[0], MotorCoupling)
    doc = json.loads(json.dumps(opts.to_json()))
    back = IdentOptions.from_json(check({**doc, "rows": "all"}, OPTIONS, "saved")[0])
    assert back.to_json() == opts.to_json()
    # a version-1 file of an earlier baseparams: the options it did not write take their defaults
    old = {"method": "ols", "convention": "khalil", "rows": "all", "rotor": False, "friction": ["viscous"],
           "coulomb_width": None, "couplings": [], "cutoff": 5.0, "decimate": 2, "min_speed": None}
    back = IdentOptions.from_json(check(old, OPTIONS, "old")[0])
    assert back == IdentOptions(method="ols", rotor=False, friction=("viscous",), cutoff=5.0, decimate=2)


@pytest.mark.parametrize("kw, words", [
    (dict(prior_weight=2.0), "prior_weight= applies to method=physical, not auto"),
    (dict(method="ols", prior_weight=2.0), "prior_weight= applies to method=physical, not ols"),
    (dict(method="nope"), "method= must be one of auto, ols, wls, physical"),
    (dict(holdout=-1.0), "holdout= must be a number in (0, 1e+09] s"),
    (dict(friction="viscous,sticky"), "unknown friction term(s) ['sticky']"),
    (dict(terms="dahl,wobble"), "unknown model term(s) ['wobble']"),
    (dict(couplings=("m6",)), "expected NAME:JOINT=WEIGHT"),
    (dict(rotor="yes"), "rotor= must be True, False or 'auto'"),
])
def test_one_check_per_rule(kw, words):
    with pytest.raises(BaseparamsError) as exc:
        IdentOptions(**kw)
    assert words in str(exc.value)


def test_the_same_rule_refuses_in_python_and_on_the_command_line(tmp_path, capsys):
    """``prior_weight`` without ``method="physical"``: one check, named as a keyword or as a flag."""
    with pytest.raises(BaseparamsError, match=r"identify: prior_weight= applies to method=physical, not auto"):
        baseparams.identify("puma560", tmp_path / "nonexistent.csv", prior_weight=5.0)
    assert main(["identify", "puma560", str(tmp_path / "nonexistent.csv"), "--prior-weight", "5"]) == 2
    err = capsys.readouterr().err
    assert "baseparams: error: --prior-weight applies to --method physical, not auto (the default estimate" in err
    assert flag_message("identify: couplings= and analysis_samples= and method=wls", "identify") == \
        "--coupling and --analysis-samples and --method wls"


def _parsed(command: str, tokens: list[str]):
    """The command's parsed arguments for ``tokens`` (its required arguments given as placeholders)."""
    sub = next(a for a in build_parser()._actions if a.dest == "command")  # noqa: SLF001
    parser = sub.choices[command]
    places = []
    for a in parser._actions:  # noqa: SLF001
        if a.required or (not a.option_strings and a.nargs not in ("?", "*")):
            places += [a.option_strings[0], "x"] if a.option_strings else ["x"]
    return parser, parser.parse_args(places + tokens)


@pytest.mark.parametrize("command", COMMANDS)
def test_a_switch_named_in_a_message_is_the_flag_that_sets_it(command):
    """A library message's ``name=True`` / ``name=False`` for a switch reads as the flag (or its absence) that gives
    that value: parsed, the keyword has it (``allow_units=True`` was ``--allow-units True``, not a valid line)."""
    for key, (on, off) in switch_flags(command).items():
        for value in (True, False):
            text = flag_message(f"{command}: {key}={value}", command)
            flag = text.removeprefix("without ")
            assert flag in (on, off) and " " not in flag, text
            parser, ns = _parsed(command, [] if text.startswith("without ") else [flag])
            action = next(a for a in parser._actions if flag in a.option_strings)  # noqa: SLF001
            got = getattr(ns, action.dest)
            assert (got if action.dest == key else not got) is value, (command, key, value, text)


@pytest.mark.parametrize("command", COMMANDS)
def test_a_switch_at_its_third_value_is_neither_flag(command):
    """``rotor=auto`` (neither forced in nor out) reads as the two flags left out, which parse to that value."""
    for key, (on, off) in switch_flags(command).items():
        if on is None or off is None:
            continue
        assert flag_message(f"{command}: ({key}=auto, ...)", command) == f"(neither {on} nor {off}, ...)"
        parser, ns = _parsed(command, [])
        action = next(a for a in parser._actions if on in a.option_strings)  # noqa: SLF001
        assert getattr(ns, action.dest) not in (True, False), (command, key)  # the third value: neither flag given


#: words of a note without an option in them (no ``=``, no keyword)
_PLAIN = st.text(st.sampled_from("abc xyz.:;,()0123456789%"), min_size=1, max_size=40)


@settings(max_examples=60, deadline=None)
@given(topic=st.sampled_from(["units", "rate", "positions"]), problem=_PLAIN)
def test_a_going_on_note_names_the_keyword_in_python_and_the_flag_on_the_command_line(topic, problem):
    """Issue 51: the CLI printed "going on (allow_units)", the library's keyword. The note says the keyword (what an
    API user passes); every command that takes the switch prints its flag, once, and nothing else changes."""
    note = going_on(topic, problem + GO_ON)  # a refusal let through: its advice to go on left out
    assert note == f"{topic}: WARNING, going on (allow_units=True): {problem}"
    commands = [c for c in COMMANDS if "allow_units" in switch_flags(c)]
    assert {"identify", "predict"} <= set(commands)
    for command in commands:
        assert flag_message(note, command) == f"{topic}: WARNING, going on (--allow-units): {problem}"
        assert flag_message(problem + GO_ON, command) == problem + "; --allow-units to go on anyway"


@settings(max_examples=60, deadline=None)
@given(lines=st.lists(st.tuples(st.sampled_from(["", "  ", "x "]), st.sampled_from(["note: ", "", "WARNING "]),
                                st.sampled_from(["method=ols", "rotor=False", "cutoff=", "plain"]), _PLAIN),
                      min_size=1, max_size=6))
def test_a_report_prints_its_notes_with_flags_and_its_other_lines_as_they_are(lines):
    """:func:`flag_notes`: a note line (``note: ``, indented or not) and a WARNING line through
    :func:`flag_message`, every other line of the report (a table that may hold ``=``) unchanged."""
    text = "\n".join(a + b + c + d for a, b, c, d in lines)
    for line, (a, b, c, d) in zip(flag_notes(text, "identify").split("\n"), lines, strict=True):
        if b == "note: " and not a.strip():
            assert line == a + b + flag_message(c + d, "identify")
        elif "WARNING" in a + b + c + d:
            assert line == flag_message(a + b + c + d, "identify")
        else:
            assert line == a + b + c + d
    assert flag_notes("note: rotor=False", "identify") == "note: --no-rotor"  # the test's own check: it changes


def test_the_excitation_limits_notes_name_an_option_both_doors_have():
    """The default position range's note named ``limits=``, which ``baseparams excite`` has no flag for: the
    keyword it names is the front door's and a flag of the command."""
    import re

    from baseparams.excitation.limits import excitation_limits

    _, notes = excitation_limits(baseparams.load("puma560"))  # no position limits in the file
    named = {k for n in notes for k in re.findall(r"(\w+)=", n)}
    assert named and named <= set(inspect.signature(baseparams.excite).parameters), notes
    printed = [flag_message(n, "excite") for n in notes]
    assert not any(re.search(r"\w=", n) for n in printed) and any("--position" in n for n in printed), printed


@pytest.mark.parametrize("command", COMMANDS)
def test_a_positional_argument_is_named_in_a_message_as_the_help_names_it(command):
    """Issue 51: ``simulate puma560 x.txt`` said "OUT x.txt: ..." where --help and the usage line say ``out``."""
    parser, _ = _parsed(command, [])
    usage = parser.format_usage().split()
    positional = [a for a in parser._actions if not a.option_strings]  # noqa: SLF001
    assert positional or command == "robots", command  # every command but the list of robots takes MODEL
    table = keyword_flags(command)
    for action in positional:
        key = next(k for k, v in table.items() if v == (action.metavar or action.dest))
        line = flag_message(f"{command}: {key}='x.csv': no such file", command)
        name = line.removesuffix(" x.csv: no such file")
        assert name in usage or f"{name}..." in usage or f"[{name}" in " ".join(usage), (command, line, usage)
        assert name.lower() == name and name in parser.format_help(), line


def test_simulate_names_its_out_argument_as_its_help_does(tmp_path, capsys):
    assert main(["simulate", "puma560", str(tmp_path / "x.txt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"baseparams: error: out {tmp_path / 'x.txt'}: the format comes from the suffix"), err


def test_a_message_that_spells_an_option_twice_names_the_flag_once():
    """The CLI's line for a message written for both doors: the flag once, a quoted value unquoted."""
    assert flag_message("identify: p.csv: 7 Hz; --allow-units (allow_units=True) to go on anyway",
                        "identify") == "p.csv: 7 Hz; --allow-units to go on anyway"
    assert flag_message("robot 'r': no motion; leave it out (mocap_welds='drop', --mocap-welds drop)",
                        "analyze") == "robot 'r': no motion; leave it out (--mocap-welds drop)"
    assert flag_message('identify: method="ols" and rotor=False', "identify") == "--method ols and --no-rotor"
    assert flag_message("left out (mocap_welds='keep', --mocap-welds keep, keeps it)", "analyze") == \
        "left out (--mocap-welds keep, keeps it)"  # the loader's note: the flag once, mid-sentence too
    assert flag_message("--method ols, --method olsen", "identify") == "--method ols, --method olsen"


def test_unknown_keywords_and_objects_are_refused():
    robot = baseparams.load("puma560")
    log, _ = simulate_log(robot, duration=2.0, rate=100.0, seed=1)
    with pytest.raises(TypeError, match=r"unknown option\(s\) \['samples'\]"):
        identify(robot, log, samples=10)
    with pytest.raises(TypeError, match="options must be IdentOptions, got dict"):
        identify(robot, log, {"method": "ols"})


@pytest.mark.slow
def test_every_path_keeps_the_options_it_was_given(tmp_path):
    """In memory and streamed from a file: one assembly, the same options (cutoff and decimation as used)."""
    robot = baseparams.load("puma560")
    log, _ = simulate_log(robot, duration=12.0, rate=200.0, noise=0.05, seed=2)
    path = write_log(tmp_path / "log.csv", log)
    opts = IdentOptions(method="wls", rotor=True, holdout=3.0, terms="none", covariance="white")
    whole = identify(robot, log, opts)
    streamed = identify_stream(robot, LogStream(path, robot), opts)
    assert whole.options == streamed.options == replace(opts, cutoff=whole.options.cutoff,
                                                        decimate=whole.options.decimate)
    assert whole.options.cutoff > 0 and whole.options.decimate >= 1
    np.testing.assert_allclose(streamed.values, whole.values, rtol=1e-6, atol=1e-9)
    # the notes in the same order, from one assembly: data, rows, model, terms, drives, estimate, covariance, units
    assert [n.split(":")[0] for n in whole.notes[-3:]] == [n.split(":")[0] for n in streamed.notes[-3:]]
    saved = json.loads(whole.save(tmp_path / "r.json").read_text())["options"]
    assert saved == {**whole.options.to_json(), "rows": "all"}
