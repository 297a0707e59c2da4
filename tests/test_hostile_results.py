"""Files read back, attacked: saved identifications, truth files, TOML column maps (``baseparams.schema``).

Property: whatever is changed in a file, reading it either refuses in one line naming the file
(and where in it), or gives exactly what the untouched file gives: never a traceback, never NaN or
otherwise different predictions, never unbounded memory or time.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

import baseparams
from baseparams.errors import BaseparamsError
from baseparams.ident import Identification, identify
from baseparams.ident.simulate import simulate_log
from baseparams.io.logs import read_log, write_log
from hostile import api_error, hostile_path, one_line_error, refused_in_a_subprocess


@pytest.fixture(scope="module")
def puma():
    return baseparams.load("puma560")


@pytest.fixture(scope="module")
def saved(puma, tmp_path_factory):
    """A saved identification, its log, the predictions of the untouched file, its truth."""
    folder = tmp_path_factory.mktemp("saved")
    log, truth = simulate_log(puma, duration=4.0, rate=100.0, noise=0.02, seed=5)
    res = identify(puma, log, method="ols", holdout=1.0)
    path = res.save(folder / "result.json")
    logfile = write_log(folder / "log.csv", log)
    (folder / "truth.json").write_text(json.dumps(truth))
    short = read_log(logfile, puma, require_tau=False)
    return {"folder": folder, "doc": json.loads(path.read_text()), "path": path, "log": logfile, "short": short,
            "pred": Identification.load(path, puma).predict(short), "truth": truth,
            "cmp": res.compare_truth(truth), "ident": res}


# ---------------------------------------------------------------- mutations
BIG = "@@BIG@@"  # placeholders for literals json.dumps does not write
HUGE_INT = "@@INT@@"
DEEP = "@@DEEP@@"
LITERALS = {BIG: "1e400", HUGE_INT: "1" * 5000, DEEP: "[" * 5000 + "]" * 5000}
REPLACEMENTS = [None, float("nan"), float("inf"), BIG, HUGE_INT, DEEP, True, False, "x", "", {}, [], 0, -1, 1e300,
                [1.0], {"a": 1}]


def _paths(doc, prefix=()):
    """Every path into the document (a few indices of long arrays)."""
    out = []
    items = (doc.items() if isinstance(doc, dict) else
             ((i, doc[i]) for i in sorted({0, len(doc) // 2, len(doc) - 1})) if isinstance(doc, list) and doc else ())
    for k, v in items:
        out.append(prefix + (k,))
        if isinstance(v, (dict, list)):
            out += _paths(v, prefix + (k,))
    return out


def _text(doc) -> str:
    text = json.dumps(doc)
    for key, lit in LITERALS.items():
        text = text.replace(json.dumps(key), lit)
    return text


def _mutate(doc, path, how, value=None):
    d = copy.deepcopy(doc)
    parent = d
    for k in path[:-1]:
        parent = parent[k]
    last = path[-1]
    if how == "replace":
        parent[last] = value
    elif how == "delete":
        del parent[last]
    elif how == "add":
        target = parent[last]
        if isinstance(target, dict):
            target["unexpected_key"] = 1.0
        else:
            target.append(target[-1] if target else 1.0)
    return d


def _mutations(doc, rng, count):
    paths = _paths(doc)
    out = []
    for _ in range(count):
        path = paths[rng.integers(len(paths))]
        how = rng.choice(["replace"] * 6 + ["delete", "add"])
        value = REPLACEMENTS[rng.integers(len(REPLACEMENTS))]
        if how == "add" and not isinstance(_get(doc, path), (dict, list)):
            how = "delete"
        out.append((path, how, value))
    return out


def _get(doc, path):
    for k in path:
        doc = doc[k]
    return doc


def _another_number(doc, path, how, value) -> bool:
    """A number replaced by another valid one (or a null by a number): may legitimately change results."""
    return (how == "replace" and isinstance(value, (int, float)) and not isinstance(value, bool)
            and np.isfinite(value) and isinstance(_get(doc, path), (int, float, type(None))))


def _where(path) -> str:
    return "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in path).lstrip(".")


# ---------------------------------------------------------------- saved identifications
@pytest.mark.parametrize("seed", range(4))
@pytest.mark.slow
def test_a_mutated_result_is_refused_in_one_line_or_predicts_exactly_the_same(saved, puma, tmp_path, seed):
    """600 random changes (a value replaced by null, NaN, 1e400, a boolean, a string, a 5 000-digit
    integer, deep nesting...; a key deleted; a key or an item added)."""
    rng = np.random.default_rng(seed)
    f = tmp_path / "mutated.json"
    refused = accepted = 0
    for path, how, value in _mutations(saved["doc"], rng, 150):
        f.write_text(_text(_mutate(saved["doc"], path, how, value)))
        try:
            back = Identification.load(f, puma)
        except (BaseparamsError, TypeError, ValueError) as exc:
            msg = str(exc)
            assert "\n" not in msg and str(f) in msg, (path, how, value, msg)
            refused += 1
            continue
        pred = back.predict(saved["short"])
        assert np.isfinite(pred).all(), (path, how, value)  # never NaN
        if not _another_number(saved["doc"], path, how, value):  # else: the same predictions
            assert np.array_equal(pred, saved["pred"]), (path, how, value)
        accepted += 1
    assert refused > 50 and accepted > 5, (refused, accepted)


@pytest.mark.parametrize("key", ["parameters", "options", "estimate", "robot", "samples", "train"])
def test_a_missing_section_names_it(saved, puma, tmp_path, key):
    f = tmp_path / "r.json"
    f.write_text(json.dumps(_mutate(saved["doc"], (key,), "delete")))
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: {key}: missing" in msg, msg


@pytest.mark.parametrize("where, value, words", [
    (("options", "cutoff"), True, "options.cutoff: expected a finite number in [0.001, 1e+06], got true"),
    (("options", "cutoff"), None, "options.cutoff: expected a finite number"),
    (("options", "rotor"), 1, "options.rotor: expected true or false, got 1"),
    (("parameters", "values", 3), None, "parameters.values[3]: expected a finite number in [-1e+24, 1e+24], got null"),
    (("parameters", "values", 3), float("nan"), "NaN is not a number JSON allows"),
    (("parameters", "values", 3), BIG, "1e400 is beyond floating point"),
    (("parameters", "values", 3), True, "parameters.values[3]: expected a finite number in [-1e+24, 1e+24], got true"),
    (("parameters", "values", 3), "1.5", "values[3]: expected a finite number in [-1e+24, 1e+24], got '1.5'"),
    (("parameters", "values"), {"a": 1}, "parameters.values: expected an array"),
    (("estimate", "samples"), HUGE_INT, "an integer of 5000 digits"),
    (("estimate", "R11", 2), [1.0], "estimate.R11[2]: expected"),
    (("notes",), DEEP, "nested 5001 levels deep"),
    (("robot", "joints", 0), 7, "robot.joints[0]: expected a string, got 7"),
])
def test_named_bad_values(saved, puma, tmp_path, where, value, words):
    f = tmp_path / "r.json"
    f.write_text(_text(_mutate(saved["doc"], where, "replace", value)))
    msg = api_error(Identification.load, f, puma)
    assert str(f) in msg and words in msg, msg


def test_extra_and_missing_values_in_arrays(saved, puma, tmp_path):
    f = tmp_path / "r.json"
    for path in (("parameters", "values"), ("parameters", "names"), ("estimate", "R11"), ("estimate", "theta")):
        f.write_text(json.dumps(_mutate(saved["doc"], path, "add")))
        msg = api_error(Identification.load, f, puma)
        assert "expected" in msg and _where(path) in msg or f"(as {_where(path)})" in msg, msg
        d = copy.deepcopy(saved["doc"])
        _get(d, path).pop()
        f.write_text(json.dumps(d))
        msg = api_error(Identification.load, f, puma)
        assert "expected" in msg, msg


def test_unknown_keys_refused_where_they_would_change_predictions_noted_elsewhere(saved, puma, tmp_path):
    f = tmp_path / "r.json"
    d = copy.deepcopy(saved["doc"])
    d["options"]["delay"] = 0.003  # a newer writer's model term: predicting without it would be wrong
    f.write_text(json.dumps(d))
    msg = api_error(Identification.load, f, puma)
    assert "options: unknown key 'delay'" in msg and "newer baseparams" in msg, msg
    d = copy.deepcopy(saved["doc"])
    d["comment"] = "from the lab"  # nothing is computed from it: read, and named in a note
    f.write_text(json.dumps(d))
    back = Identification.load(f, puma)
    assert np.array_equal(back.predict(saved["short"]), saved["pred"])
    assert any("keys not read: comment" in n for n in back.notes), back.notes


def test_load_needs_a_robot(saved):
    msg = api_error(Identification.load, saved["path"], "puma560")
    assert "robot" in msg


@pytest.mark.parametrize("kind", ["fifo", "dev_zero", "folder", "sparse_1gb"])
def test_predict_refuses_what_is_not_a_result_file_at_once(saved, tmp_path, capsys, kind):
    p = hostile_path(kind, tmp_path / "result.json")
    err = one_line_error(["predict", "puma560", p, saved["log"]], capsys, seconds=20)
    assert str(p) in err and ("not a regular file" in err or "larger than" in err), err


@pytest.mark.parametrize("text", ["[" * 100000 + "]" * 100000, '{"format": ' + "1" * 5000 + "}",
                                  " " * (33 * 2**20), "\xff\xfe"])
def test_hostile_result_files_in_a_bounded_subprocess(saved, tmp_path, text):
    """Deep nesting, a huge integer, 33 MB, bytes that are not UTF-8: one line, bounded memory and time."""
    p = tmp_path / "result.json"
    p.write_bytes(text.encode("latin-1"))
    err = refused_in_a_subprocess(["predict", "puma560", p, saved["log"]], seconds=60)
    assert str(p) in err, err


def test_cli_predict_on_mutations_is_one_line(saved, tmp_path, capsys):
    rng = np.random.default_rng(11)
    f = tmp_path / "m.json"
    done = 0
    for path, how, value in _mutations(saved["doc"], rng, 60):
        f.write_text(_text(_mutate(saved["doc"], path, how, value)))
        from baseparams.cli import main

        capsys.readouterr()
        code = main(["predict", "puma560", str(f), str(saved["log"])])
        err = capsys.readouterr().err.strip().splitlines()
        if code == 0:
            continue
        assert code == 2 and len(err) == 1 and str(f) in err[0], (path, how, value, err)
        done += 1
    assert done > 20


# ---------------------------------------------------------------- truth files
@pytest.mark.parametrize("seed", range(2))
def test_a_mutated_truth_is_refused_in_one_line_or_compares_the_same(saved, tmp_path, seed):
    rng = np.random.default_rng(100 + seed)
    ident, truth, expected = saved["ident"], saved["truth"], saved["cmp"]
    f = tmp_path / "truth.json"
    refused = 0
    for path, how, value in _mutations(truth, rng, 150):
        f.write_text(_text(_mutate(truth, path, how, value)))
        from baseparams.schema import read_truth

        try:
            cmp = ident.compare_truth(read_truth(f), str(f))
        except BaseparamsError as exc:
            assert "\n" not in str(exc) and str(f) in str(exc), (path, how, value, exc)
            refused += 1
            continue
        assert all(np.isfinite(t["true"]) for t in cmp["terms"]), (path, how, value)
        if not _another_number(truth, path, how, value):
            assert cmp["terms"] == [dict(t) for t in expected["terms"]], (path, how, value)
    assert refused > 60


@pytest.mark.parametrize("change, words", [
    (lambda t: t["parameters"].__setitem__(0, {"name": t["parameters"][0]["name"], "value": None}),
     "parameters[0].value: expected a finite number in [-1e+24, 1e+24], got null"),
    (lambda t: t["parameters"].__setitem__(1, {"name": t["parameters"][1]["name"], "value": True}),
     "parameters[1].value: expected a finite number in [-1e+24, 1e+24], got true"),
    (lambda t: t["parameters"].append(dict(t["parameters"][0])), "appears twice"),
    (lambda t: t.pop("parameters"), "parameters: missing"),
    (lambda t: t.__setitem__("parameters", {"x": 1}), "parameters: expected an array"),
])
def test_truth_given_in_python_is_checked_the_same(saved, change, words):
    truth = copy.deepcopy(saved["truth"])
    change(truth)
    msg = api_error(saved["ident"].compare_truth, truth)
    assert words in msg, msg


@pytest.mark.parametrize("kind", ["fifo", "dev_zero", "nan", "deep"])
def test_cli_truth_files(saved, tmp_path, capsys, kind):
    p = tmp_path / "t.json"
    if kind in ("fifo", "dev_zero"):
        hostile_path(kind, p)
    elif kind == "nan":
        t = copy.deepcopy(saved["truth"])
        t["parameters"][0]["value"] = float("nan")
        p.write_text(json.dumps(t))
    else:
        p.write_text('{"parameters": ' + "[" * 3000 + "]" * 3000 + "}")
    err = one_line_error(["identify", "puma560", saved["log"], "--truth", p], capsys, seconds=30)
    assert str(p) in err, err


# ---------------------------------------------------------------- TOML column maps
TOML_ATTACKS = [
    ("a = " + "[" * 5000 + "]" * 5000, "nested"),
    ("a = " + "{b = " * 3000 + "1" + "}" * 3000, "nested"),
    ("[joints.joint1]\ngear_ratio = 1" + "0" * 5000, "not a valid TOML mapping"),
    ("[joints.joint1]\ngear_ratio = 1" + "0" * 400, "gear_ratio: expected a finite nonzero number in [-1e+06, 1e+06]"),
    ("[joints.joint1]\ngear_ratio = 1e300", "gear_ratio: expected a finite nonzero number in [-1e+06, 1e+06]"),
    ("[joints.joint1]\ngear_ratio = inf", "beyond floating point"),
    ("[joints.joint1]\ngear_ratio = nan", "beyond floating point"),
    ("[joints.joint1]\ngear_ratio = 1e400", "beyond floating point"),
    ("[joints.joint1]\nsign = true", "sign: expected +1 or -1, got true"),
    ("[joints.joint1]\noffset = [1, 2]", "offset: expected a finite number in [-1e+06, 1e+06], got an array"),
    ("[joints.joint1]\nq = {a = 1}", "joints.joint1.q: expected a column name"),
    ("time_scale = 0", "time_scale: expected a finite number in [1e-12, 1e+06]"),
    ("time_scale = true", "time_scale: expected a finite number in [1e-12, 1e+06], got true"),
    ("joints = 3", "joints: expected an object"),
    ("[joints]\njoint1 = 3", "joints.joint1: expected an object"),
    ("\xff", "not UTF-8"),
]


@pytest.mark.parametrize("text, words", TOML_ATTACKS)
def test_hostile_column_maps(saved, puma, tmp_path, text, words):
    p = tmp_path / "map.toml"
    p.write_bytes(text.encode("latin-1"))
    msg = api_error(read_log, saved["log"], puma, columns=p)
    assert str(p) in msg and words in msg, msg


def test_column_maps_that_are_not_regular_files(saved, tmp_path, capsys):
    for kind in ("fifo", "dev_zero", "sparse_1gb"):
        p = hostile_path(kind, tmp_path / f"{kind}.toml")
        err = one_line_error(["identify", "puma560", saved["log"], "--columns", p], capsys, seconds=20)
        assert str(p) in err and ("not a regular file" in err or "larger than" in err), err


def test_a_mutated_column_map_is_refused_or_reads_the_same_log(saved, puma, tmp_path):
    mapping = {"time": "t", "time_scale": 1.0,
               "joints": {j: {"q": f"q_{j}", "tau": f"tau_{j}", "sign": 1, "gear_ratio": 1.0, "offset": 0.0}
                          for j in puma.joint_names}}
    base = read_log(saved["log"], puma, columns=mapping)
    rng = np.random.default_rng(7)
    refused = 0
    for path, how, value in _mutations(mapping, rng, 300):
        if value in (BIG, HUGE_INT, DEEP):
            continue  # TOML cannot carry these as values of a dict: tested as text above
        m = _mutate(mapping, path, how, value)
        try:
            log = read_log(saved["log"], puma, columns=m)
        except (BaseparamsError, TypeError, ValueError) as exc:
            assert "\n" not in str(exc) and "columns=" in str(exc) or "log.csv" in str(exc), (path, how, value, exc)
            refused += 1
            continue
        if how == "delete" or _another_number(mapping, path, how, value):
            continue  # a default taken or another valid number: another, valid, mapping
        assert np.array_equal(log.q, base.q) and np.array_equal(log.tau, base.tau), (path, how, value)
    assert refused > 100
