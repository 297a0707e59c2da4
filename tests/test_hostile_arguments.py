"""Absurd numbers on the command line and wrong types in Python: one line naming the argument, at once.

The numeric flags are found from the parser itself (every ``type=int``/``float`` action of every
command), so a flag added later without a range in ``baseparams.arguments.RANGES`` fails here.
"""

from __future__ import annotations

import argparse
import inspect
import math
import time

import numpy as np
import pytest

import baseparams as bp
from baseparams.arguments import RANGES, ArgumentError, ArgumentTypeError, check_value
from baseparams.cli import build_parser, main
from baseparams.errors import BaseparamsError
from hostile import api_error, one_line_error

#: flags that are numbers but not ranges: the deprecated alias of --analysis-samples (same check)
EXEMPT = {"old_samples"}
#: text options holding numbers, each checked by its own parser
TEXT_NUMBERS = {"acceleration": ["excite", "puma560", "--acceleration"], "keepout": ["excite", "puma560", "--keepout"],
                "values": ["analyze", "scara-symbolic", "--values"],
                "weld": ["identify", "puma560", "LOG", "--joints", "joint1", "--weld"],
                "coupling": ["identify", "puma560", "LOG", "--coupling"]}


def _numeric_flags():
    """``(command, option string, dest, type)`` of every numeric flag of every command."""
    p = build_parser()
    sub = next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))
    for cmd, sp in sub.choices.items():
        for a in sp._actions:
            if a.type in (int, float) and a.option_strings:
                yield cmd, a.option_strings[0], a.dest, a.type, a.nargs


FLAGS = list(_numeric_flags())


def test_every_numeric_flag_has_a_range():
    missing = sorted({dest for _, _, dest, _, _ in FLAGS if dest not in RANGES and dest not in EXEMPT})
    assert not missing, f"numeric flags without a range in baseparams.arguments.RANGES: {missing}"
    assert len(FLAGS) > 30


BAD = ["nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-300", "99999999999999999999"]


def _valid(dest: str, text: str) -> bool:
    r = RANGES.get(dest) or RANGES["samples"]
    try:
        value = float(text) if not r.integer else int(float(text))
        check_value([0.0, 0.0, value] if r.count == 3 else value, dest, r=r)
    except (BaseparamsError, OverflowError, ValueError):
        return False
    return not r.integer or float(text) == int(float(text))


CASES = [(cmd, opt, dest, t, n, v) for cmd, opt, dest, t, n in FLAGS for v in BAD if not _valid(dest, v)]


def _argv(cmd, opt, nargs, value, tmp_path):
    head = {"analyze": ["analyze", "puma560"], "regressor": ["regressor", "puma560"], "excite": ["excite", "puma560"],
            "identify": ["identify", "puma560", str(tmp_path / "log.csv")],
            "predict": ["predict", "puma560", str(tmp_path / "r.json"), str(tmp_path / "log.csv")],
            "simulate": ["simulate", "puma560", str(tmp_path / "out.csv")],
            "payload": ["payload", "puma560", str(tmp_path / "log.csv"), "--link", "link6"]}[cmd]
    values = [value] if nargs is None else ["0", "0", value]
    return head + [opt, *values]


@pytest.mark.parametrize("cmd, opt, dest, typ, nargs, value", CASES,
                         ids=[f"{c}{o}={v}" for c, o, _, _, _, v in CASES])
def test_absurd_numbers_on_the_command_line_are_one_line_at_once(cmd, opt, dest, typ, nargs, value, tmp_path,
                                                                 capsys):
    (tmp_path / "log.csv").write_text("t,q_joint1,tau_joint1\n0,0,0\n0.1,0,0\n")
    argv = _argv(cmd, opt, nargs, value, tmp_path)
    t0 = time.perf_counter()
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse: not a number of the flag's type (one line, exit 2)
        code = exc.code
    err = [e for e in capsys.readouterr().err.strip().splitlines() if "deprecated" not in e]  # --samples' note
    assert code == 2 and len(err) == 1 and err[0].startswith("baseparams: error:"), (argv, err)
    flag = "--analysis-samples" if dest == "old_samples" else opt
    assert flag in err[0] or opt in err[0], (argv, err)
    assert time.perf_counter() - t0 < 5, argv  # checked before any work


@pytest.mark.parametrize("name", list(TEXT_NUMBERS))
@pytest.mark.parametrize("value", ["nan", "inf", "1e308", "-1e308"])
def test_numbers_inside_text_options(name, value, tmp_path, capsys):
    pytest.importorskip("sympy") if name == "values" else None
    log = tmp_path / "log.csv"
    log.write_text("t,q_joint1,tau_joint1\n0,0,0\n0.1,0,0\n")
    arg = {"acceleration": value, "keepout": f"link2:{value}", "values": f"D3={value}", "weld": f"joint2={value}",
           "coupling": f"m:joint1={value},joint2=1"}[name]
    argv = [str(log) if a == "LOG" else a for a in TEXT_NUMBERS[name]] + [arg]
    err = one_line_error(argv, capsys, seconds=30)
    assert value in err or "finite" in err or "must be" in err or "expected one argument" in err, err


@pytest.mark.parametrize("argv, words", [
    (["excite", "puma560", "--starts", "1000000"], "--starts must be an integer in [1, 1000]"),
    (["excite", "puma560", "--base-frequency", "1e-12"], "--base-frequency"),
    (["excite", "puma560", "--acceleration", "nan"], "--acceleration"),
    (["excite", "puma560", "--period", "3000", "--rate", "1000"], "samples"),
    (["identify", "puma560", "L", "--analysis-samples", "100000000"], "--analysis-samples"),
    (["identify", "puma560", "L", "--analysis-samples", "1e8"], "--analysis-samples"),
    (["analyze", "puma560", "--gravity", "0", "0", "1e308"], "--gravity"),
    (["simulate", "puma560", "OUT", "--robots", "1000000"], "--robots"),
    (["simulate", "puma560", "OUT", "--robots", "1000", "--duration", "1000", "--rate", "1000"], "in all"),
    (["simulate", "puma560", "OUT", "--duration", "100000", "--rate", "1000"], "samples"),
])
def test_the_listed_cases(argv, words, tmp_path, capsys):
    log = tmp_path / "log.csv"
    log.write_text("t,q_joint1,tau_joint1\n0,0,0\n0.1,0,0\n")
    argv = [str(log) if a == "L" else str(tmp_path / "out.csv") if a == "OUT" else a for a in argv]
    err = one_line_error(argv, capsys, seconds=5)
    assert words in err, err


# ---------------------------------------------------------------- Python: keywords out of range, wrong types
FRONT = {"excite": bp.excite, "simulate": bp.simulate, "identify": bp.identify, "analyze": bp.analyze, "load": bp.load}


def _accepted(keyword: str, value) -> bool:
    try:
        check_value(value, keyword)
    except BaseparamsError:
        return False
    return True


def _keyword_cases():
    for fname, f in FRONT.items():
        for k in inspect.signature(f).parameters:
            if k in RANGES:
                for v in (math.nan, math.inf, -1e308, 1e308, -1, 0, "1", True, [1, 2], 10**400):
                    if k == "gravity" and v == [1, 2] or not _accepted(k, v):
                        yield fname, k, v


KW = list(_keyword_cases())


@pytest.fixture(scope="module")
def puma():
    return bp.load("puma560")


@pytest.mark.parametrize("fname, keyword, value", KW, ids=[f"{f}-{k}-{str(v)[:12]}" for f, k, v in KW])
def test_front_door_keywords_out_of_range_or_of_the_wrong_type(fname, keyword, value, puma):
    args = ("puma560",) if fname == "load" else (puma,) if fname != "identify" else (puma, "log.csv")
    t0 = time.perf_counter()
    try:
        FRONT[fname](*args, **{keyword: value})
    except (ArgumentError, ArgumentTypeError) as exc:
        msg = str(exc)
    except Exception as exc:  # noqa: BLE001 - the test names what was raised instead
        raise AssertionError(f"{fname}({keyword}={value!r}): {type(exc).__name__}: {exc}") from None
    else:
        raise AssertionError(f"{fname}({keyword}={value!r:.40}) accepted")
    assert "\n" not in msg and keyword in msg, msg
    assert time.perf_counter() - t0 < 2


def _log(puma):
    return bp.simulate(puma, duration=2.0, rate=100.0, seed=1)[0]


def _wrong_calls(puma, log, tmp_path):
    """``(call, keyword the message must name)`` for wrong types and shapes of the public API."""
    from baseparams.ident import Identification
    from baseparams.io.logs import read_log, write_log

    ident = bp.identify(puma, log, method="ols")
    res = ident.save(tmp_path / "r.json")
    q = np.zeros((5, 6))
    return [
        (lambda: bp.load(123), "model"),
        (lambda: bp.load("puma560", gravity="down"), "gravity"),
        (lambda: bp.load("puma560", gravity=(0, 0)), "gravity"),
        (lambda: bp.load("puma560", floating="yes"), "floating"),
        (lambda: bp.analyze("puma560"), "Robot"),
        (lambda: bp.analyze(puma, samples=2.5), "samples"),
        (lambda: bp.analyze(puma, samples="100"), "samples"),
        (lambda: bp.analyze(puma, verify="no"), "verify"),
        (lambda: bp.analyze(puma, convention=3), "convention"),
        (lambda: bp.analyze(puma, samples=100_000_000), "samples"),
        (lambda: bp.regressor(puma, "q", q, q), "q"),
        (lambda: bp.regressor(puma, np.zeros((5, 5)), None, None), "q"),
        (lambda: bp.regressor(puma, np.full((5, 6), np.nan), q, q), "q"),
        (lambda: bp.regressor(puma, q, np.zeros((4, 6)), q), "dq"),
        (lambda: bp.regressor(puma, [[1, "a", 2, 3, 4, 5]], None, None), "q"),
        (lambda: bp.regressor("puma560", q, q, q), "robot"),
        (lambda: bp.excite(puma, harmonics=2.5), "harmonics"),
        (lambda: bp.excite(puma, limits=np.zeros((3, 4))), "limits"),
        (lambda: bp.excite(puma, keepout=("link2", "high")), "keepout"),
        (lambda: bp.excite(puma, acceleration=[np.nan] * 6), "acceleration"),
        (lambda: bp.excite(puma, drives="yes"), "drives"),
        (lambda: bp.excite(5), "model"),
        (lambda: bp.simulate(puma, trajectory=5), "trajectory"),
        (lambda: bp.simulate(puma, trajectory=(np.arange(3.0), q, q, q)), "trajectory"),
        (lambda: bp.simulate(puma, noise=-1), "noise"),
        (lambda: bp.simulate(puma, friction=5), "friction"),
        (lambda: bp.simulate(puma, rotor="no"), "rotor"),
        (lambda: bp.identify(puma, 5), "log"),
        (lambda: bp.identify(puma, log, method=3), "method"),
        (lambda: bp.identify(puma, log, method="best"), "method"),
        (lambda: bp.identify(puma, log, covariance="x"), "covariance"),
        (lambda: bp.identify(puma, log, couplings=5), "couplings"),
        (lambda: bp.identify(puma, log, joints=5), "joints"),
        (lambda: bp.identify(puma, log, columns=5), "columns"),
        (lambda: bp.identify(puma, log, friction=["viscous", "sticky"]), "friction"),
        (lambda: bp.predict(puma, 5, log), "result"),
        (lambda: bp.predict(puma, res, 5), "log"),
        (lambda: Identification.load(res, "puma560"), "robot"),
        (lambda: ident.predict("log.csv"), "log"),
        (lambda: ident.compare_truth([1, 2]), "truth"),
        (lambda: read_log(tmp_path / "x.csv", "puma560"), "robot"),
        (lambda: write_log(tmp_path / "x.csv", 5), "log"),
    ]


def test_wrong_types_and_shapes_in_python_name_the_argument(puma, tmp_path):
    log = _log(puma)
    failures = []
    for call, word in _wrong_calls(puma, log, tmp_path):
        try:
            call()
        except (TypeError, ValueError, BaseparamsError) as exc:
            msg = str(exc)
            if "\n" in msg or word not in msg:
                failures.append(f"{word}: {type(exc).__name__}: {msg[:200]}")
        except Exception as exc:  # noqa: BLE001 - a deep traceback's exception
            failures.append(f"{word}: {type(exc).__name__}: {str(exc)[:200]}")
        else:
            failures.append(f"{word}: accepted")
    assert not failures, "\n".join(failures)


def test_api_errors_are_typeerrors_or_valueerrors(puma):
    assert issubclass(ArgumentTypeError, TypeError) and issubclass(ArgumentError, ValueError)
    api_error(bp.excite, puma, starts=10**6, match="starts= must be an integer in [1, 1000]")
    api_error(bp.simulate, puma, duration=1e5, rate=1e3, match="samples")


def test_a_glob_over_the_whole_file_system_is_refused_in_seconds(capsys, monkeypatch):
    from baseparams.cli import common

    monkeypatch.setattr(common, "MAX_GLOB_SECONDS", 2.0)
    err = one_line_error(["identify", "puma560", "/**"], capsys, seconds=30)
    assert "the pattern" in err and ("files" in err or "s to list" in err), err


def test_a_local_cluster_of_a_thousand_workers_is_refused_before_starting(monkeypatch):
    pytest.importorskip("distributed")
    import os

    from baseparams import fleet

    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    with pytest.raises(BaseparamsError, match=r"--workers 1024: a local cluster of at most 8 worker processes"), \
            fleet.dask_client(None, None, 1024):
        pass


# ---------------------------------------------------------------- a property: junk in every argument of the front door
JUNK = ["x", object(), {"a": 1}, np.zeros((2, 2)), b"x", (1, "a"), math.nan, [math.inf]]
#: keywords for which a string is a valid value of its type (a path, a name, a message)
STRINGS_OK = {"out", "save", "mjcf", "source", "package_path", "path", "validate", "log", "result", "columns", "html",
              "plot", "predictions", "urdf"}
#: arguments that only label messages (any value is printed as it is)
LABELS = {"what"}


@pytest.mark.slow
def test_junk_in_every_argument_is_a_typeerror_or_valueerror_naming_it(puma, tmp_path, monkeypatch):
    """Every argument of the front door and of the result objects, eight values of the wrong kind each: a
    TypeError or ValueError (or BaseparamsError) of one line, never another exception, within seconds."""
    monkeypatch.chdir(tmp_path)  # a string is a path to some keywords: whatever one writes stays in the test's folder
    from baseparams.ident import Identification
    from baseparams.io.logs import read_log, write_log

    log = bp.simulate(puma, duration=4.0, rate=100.0, noise=0.01)[0]
    ident = bp.identify(puma, log, method="ols")
    res = ident.save(tmp_path / "r.json")
    csv = write_log(tmp_path / "x.csv", log)
    calls = {
        "load": (bp.load, ("puma560",)), "analyze": (bp.analyze, (puma,)),
        "regressor": (bp.regressor, (puma, np.zeros((3, 6)), np.zeros((3, 6)), np.zeros((3, 6)))),
        "excite": (bp.excite, (puma,)), "simulate": (bp.simulate, (puma,)), "identify": (bp.identify, (puma, log)),
        "predict": (bp.predict, (puma, res, log)), "Identification.load": (Identification.load, (res, puma)),
        "Identification.predict": (ident.predict, (log,)), "compare_truth": (ident.compare_truth, ({},)),
        "read_log": (read_log, (csv, puma)), "write_log": (write_log, (tmp_path / "y.csv", log)),
        "save": (ident.save, (tmp_path / "s.json",)),
    }
    failures, count = [], 0
    for name, (f, args) in calls.items():
        params = list(inspect.signature(f).parameters)
        for kw in params:
            for junk in JUNK:
                valid = isinstance(junk, str) and kw in STRINGS_OK or kw == "inputs" and isinstance(junk, dict)
                if valid or kw in LABELS or kw.startswith("_"):  # private keywords: the CLI's own
                    continue
                a, kwargs = list(args), {}
                if kw in params[:len(a)]:
                    a[params.index(kw)] = junk
                else:
                    kwargs[kw] = junk
                count += 1
                t0 = time.perf_counter()
                try:
                    f(*a, **kwargs)
                except (TypeError, ValueError, BaseparamsError) as exc:
                    if "\n" in str(exc) or not str(exc):
                        failures.append(f"{name}({kw}={junk!r:.20}): several lines: {str(exc)[:80]!r}")
                except Exception as exc:  # noqa: BLE001 - the failure this test looks for
                    failures.append(f"{name}({kw}={junk!r:.20}): {type(exc).__name__}: {str(exc)[:100]}")
                else:
                    if name != "compare_truth" or kw != "source":
                        failures.append(f"{name}({kw}={junk!r:.20}): accepted")
                if time.perf_counter() - t0 > 10:
                    failures.append(f"{name}({kw}={junk!r:.20}): {time.perf_counter() - t0:.0f} s")
    assert count > 500 and not failures, f"{len(failures)} of {count}:\n" + "\n".join(failures[:40])


@pytest.mark.parametrize("given", [("duration",), ("rate",), ("amplitude",), ("duration", "rate"),
                                   ("duration", "rate", "amplitude")])
def test_options_of_the_random_motion_with_a_given_trajectory_are_refused(given, tmp_path, capsys):
    """``simulate --trajectory FILE --duration 5 --rate 200`` wrote the trajectory's own 10 s at its own rate with
    exit 0: the options were dropped without a word. Both doors refuse them in one line naming each; without a
    trajectory they make the log they say."""
    robot = bp.load("puma560")
    log, _ = bp.simulate(robot, duration=1.0, rate=100.0)
    assert log.n_samples == 100 and log.t[1] - log.t[0] == pytest.approx(0.01)
    names = [f"{k}_{j}" for k in ("q", "dq", "ddq") for j in log.joints]
    traj = tmp_path / "traj.csv"
    np.savetxt(traj, np.c_[log.t, log.q, log.dq, np.gradient(log.dq, log.t, axis=0)], delimiter=",",
               header=",".join(["t"] + names), comments="")
    values = {"duration": 5.0, "rate": 200.0, "amplitude": 0.3}
    msg = api_error(bp.simulate, robot, traj, **{n: values[n] for n in given})
    names = " and ".join(f"{n}=" for n in given)
    assert msg.startswith(f"simulate: {names} set") and "not a given trajectory=" in msg, msg
    argv = ["simulate", "puma560", tmp_path / "out.csv", "--trajectory", traj]
    err = one_line_error(argv + [x for n in given for x in (f"--{n}", values[n])], capsys)
    assert " and ".join(f"--{n}" for n in given) + " set" in err and "not a given --trajectory" in err, err
    assert not (tmp_path / "out.csv").exists()
    assert bp.simulate(robot, traj)[0].n_samples == 100  # the trajectory's own samples
