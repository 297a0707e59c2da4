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


# ---------------------------------------------------------------- saved model terms (issue 51)
@pytest.fixture(scope="module")
def termed(puma, saved):
    """A saved identification with every model term kept (forced), and the predictions of the untouched file."""
    log, _ = simulate_log(puma, duration=4.0, rate=100.0, noise=0.02, seed=5)
    res = identify(puma, log, method="ols", holdout=1.0, terms="dahl,tilt,delay,scale")
    assert [t.name for t in res.fit.terms] == ["dahl", "tilt", "delay", "scale"]
    path = res.save(saved["folder"] / "termed.json")
    return {"ident": res, "path": path, "doc": json.loads(path.read_text()),
            "pred": Identification.load(path, puma).predict(saved["short"])}


def _per_joint_fields():
    """``(term, field)`` of every saved term field declared as one value per measured joint."""
    from baseparams.ident.terms.registry import registry
    from baseparams.schema import Map

    return [(name, f) for name, cls in registry().items() for f, node in cls.FIELDS.items()
            if isinstance(node, Map) and node.keys == "joints"]


def test_every_term_declares_its_joint_keyed_fields():
    assert {("dahl", "delta"), ("delay", "seconds"), ("scale", "factors")} <= set(_per_joint_fields())


@pytest.mark.parametrize("name, field", _per_joint_fields())
def test_a_joint_the_robot_lacks_or_a_joint_left_out_is_refused(termed, puma, tmp_path, name, field):
    """Issue 51: a delay keyed by a joint the robot lacks was silently ignored (and a missing one read as 0)."""
    k = [t["name"] for t in termed["doc"]["terms"]].index(name)
    f = tmp_path / "r.json"
    d = copy.deepcopy(termed["doc"])
    values = d["terms"][k]["values"][field]
    values["elbow"] = values["joint2"]
    f.write_text(json.dumps(d))
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: terms[{k}].values.{field}: key 'elbow' is not one of robot.joints (joint1," in msg, msg
    del values["elbow"], values["joint3"]
    f.write_text(json.dumps(d))
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: terms[{k}].values.{field}: missing 'joint3'" in msg, msg


@pytest.mark.parametrize("where, value, words", [
    (("values", "angles", 0), 1e300, "terms[1].values.angles[0]: expected a finite number in [-0.174533, 0.174533]"),
    (("values", "angles", 1), 0.9, "terms[1].values.angles[1]: expected a finite number in [-0.174533, 0.174533]"),
    (("values", "pi", 19), 1e300, "terms[1].values.pi[19]: expected a finite number in [-1e+24, 1e+24]"),
    (("values", "degrees"), 1e300, "terms[1].values.degrees: expected a finite number in [0, 14.1421]"),
    (("values", "degrees"), 3.0, "terms[1].values: degrees 3.0 is not the angles' magnitude"),
    (("values", "pi"), None, "terms[1].values: a tilt without the standard parameters it acts on"),
    (("std", "angles"), "x", "terms[1].std.angles: expected an array (each item a finite number >= 0), got 'x'"),
    (("values", "pi"), {"a": 1}, "terms[1].values.pi: expected an array (each item a finite number in "
                                 "[-1e+24, 1e+24]), got an object of 1 key"),
    (("values", "seconds"), {"joint1": 0.01}, "terms[1].values: unknown key 'seconds'"),
])
def test_tilt_fields_out_of_their_bounds(termed, puma, tmp_path, where, value, words):
    """Issue 51: a tilt of 1e300 predicted torques of 7e298 N m with exit 0."""
    f = tmp_path / "r.json"
    f.write_text(_text(_mutate(termed["doc"], ("terms", 1, *where), "replace", value)))
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: {words}" in msg, msg


@pytest.mark.parametrize("k, where, value, words", [
    (0, ("values", "delta", "joint1"), None, "terms[0].values.delta.joint1: expected a finite number in [1e-08, 0.05]"),
    (0, ("values", "delta", "joint1"), 1e-300, "terms[0].values.delta.joint1: expected a finite number in [1e-08"),
    (2, ("values", "seconds", "joint4"), 0.5, "terms[2].values.seconds.joint4: expected a finite number in [-0.05, 0"),
    (2, ("values",), {}, "terms[2].values.seconds: missing"),
    (2, ("std", "seconds"), [0.1], "terms[2].std.seconds: expected 6 items"),
    (3, ("values", "factors", "joint5"), 7.0, "terms[3].values.factors.joint5: expected a finite number in [0.5, 2]"),
    (3, ("values", "reference"), "wrist", "terms[3].values.reference: expected one of joint1, joint2"),
    (3, ("values", "reference"), "joint1", "terms[3].values: factors.joint1 is "),
    (3, ("name",), "shift", "terms[3].name: expected one of 'dahl', 'tilt', 'delay', 'scale', got 'shift'"),
])
def test_other_term_fields_out_of_their_bounds(termed, puma, tmp_path, k, where, value, words):
    f = tmp_path / "r.json"
    f.write_text(_text(_mutate(termed["doc"], ("terms", k, *where), "replace", value)))
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: {words}" in msg, msg


@pytest.mark.parametrize("k", range(4))
def test_a_term_listed_twice_is_refused(termed, puma, tmp_path, k):
    """Issue 51: the same term listed twice was accepted and changed the predictions (0.066 -> 0.149 N m)."""
    f = tmp_path / "r.json"
    d = copy.deepcopy(termed["doc"])
    d["terms"].append(copy.deepcopy(d["terms"][k]))
    f.write_text(json.dumps(d))
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: terms[4].name: '{d['terms'][k]['name']}' appears twice (items {k} and 4)" in msg, msg


def test_a_key_twice_in_one_object_is_refused(termed, puma, tmp_path):
    """JSON readers keep the first or the last of two equal keys: neither is silently chosen."""
    f = tmp_path / "r.json"
    text = json.dumps(termed["doc"])
    at = text.index('"seconds": {') + len('"seconds": {')
    f.write_text(text[:at] + '"joint1": 0.04, ' + text[at:])
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: not a saved identification: the key 'joint1' appears twice in one object" in msg, msg


def test_a_kept_term_its_options_did_not_try_is_refused(termed, puma, tmp_path):
    f = tmp_path / "r.json"
    f.write_text(json.dumps(_mutate(termed["doc"], ("options", "terms"), "replace", "delay")))
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: terms[0]: 'dahl' is not among the terms options.terms tried ('delay')" in msg, msg


@pytest.mark.parametrize("seed", range(2))
def test_mutated_terms_are_refused_in_one_line_or_predict_the_same(termed, saved, puma, tmp_path, seed):
    """Random changes inside the saved terms: one line naming the file and the term, or the same predictions
    (another valid number: finite predictions)."""
    rng = np.random.default_rng(200 + seed)
    f = tmp_path / "mutated.json"
    paths = [("terms", *p) for p in _paths(termed["doc"]["terms"])]
    refused = 0
    for _ in range(120):
        path = paths[rng.integers(len(paths))]
        how = rng.choice(["replace"] * 6 + ["delete", "add"])
        value = REPLACEMENTS[rng.integers(len(REPLACEMENTS))]
        if how == "add" and not isinstance(_get(termed["doc"], path), (dict, list)):
            how = "delete"
        f.write_text(_text(_mutate(termed["doc"], path, how, value)))
        try:
            back = Identification.load(f, puma)
        except (BaseparamsError, TypeError, ValueError) as exc:
            msg = str(exc)
            assert "\n" not in msg and str(f) in msg and ("terms" in msg or "nested" in msg or "JSON" in msg
                                                           or "integer" in msg), (path, how, value, msg)
            refused += 1
            continue
        pred = back.predict(saved["short"])
        assert np.isfinite(pred).all(), (path, how, value)
        if not _another_number(termed["doc"], path, how, value) and path[-1] not in ("std", "forced"):
            assert np.array_equal(pred, termed["pred"]), (path, how, value)
    assert refused > 60, refused


def _valid(node, rng):
    """A random value within a Num node's bounds."""
    return float(rng.uniform(max(node.lo, -1e3), min(node.hi, 1e3)))


@pytest.mark.parametrize("seed", range(3))
def test_any_term_value_within_its_declared_bounds_reads_back_bit_for_bit(termed, saved, puma, tmp_path, seed):
    """Property: delays, scales, distances and angles drawn within the declared bounds are saved, read back
    and predict the same as the result in memory; one beyond a bound is refused by save (nothing written)."""
    from dataclasses import replace

    from baseparams.ident.terms.delay import Delay
    from baseparams.ident.terms.scale import Scale
    from baseparams.ident.terms.tilt import Tilt

    rng = np.random.default_rng(seed)
    dahl, tilt, delay, scale = (t.copy() for t in termed["ident"].fit.terms)
    delay.seconds = np.array([_valid(Delay.FIELDS["seconds"].value, rng) for _ in range(6)])
    scale.factors = np.array([_valid(Scale.FIELDS["factors"].value, rng) for _ in range(6)])
    scale.factors[scale.reference] = 1.0
    tilt.angles = np.array([_valid(Tilt.FIELDS["angles"].item, rng) for _ in range(2)])
    dahl.delta = np.exp(rng.uniform(np.log(1e-6), np.log(0.05), 6))
    res = replace(termed["ident"], fit=replace(termed["ident"].fit, terms=(dahl, tilt, delay, scale)))
    path = res.save(tmp_path / "r.json")
    back = Identification.load(path, puma)
    assert np.array_equal(back.predict(saved["short"]), res.predict(saved["short"]))
    delay.seconds = delay.seconds.copy()
    delay.seconds[rng.integers(6)] = 0.2
    msg = api_error(res.save, tmp_path / "beyond.json")
    assert "beyond.json (not written): terms[2].values.seconds.joint" in msg and "[-0.05, 0.05]" in msg, msg
    assert not (tmp_path / "beyond.json").exists()


def test_cli_predict_refuses_the_issue_files_in_one_line(termed, saved, tmp_path, capsys):
    for k, change in enumerate([lambda d: d["terms"][2]["values"]["seconds"].update(elbow=0.01),
                                lambda d: d["terms"][1]["values"]["angles"].__setitem__(0, 1e300),
                                lambda d: d["terms"].append(copy.deepcopy(d["terms"][1]))]):
        d = copy.deepcopy(termed["doc"])
        change(d)
        f = tmp_path / f"r{k}.json"
        f.write_text(json.dumps(d))
        err = one_line_error(["predict", "puma560", f, saved["log"], "--out", tmp_path / f"p{k}.csv"], capsys)
        assert str(f) in err and "terms[" in err, err
        assert not (tmp_path / f"p{k}.csv").exists()


@pytest.mark.parametrize("change", ["delete a term", "delete its choice", "not kept"])
def test_a_term_left_out_or_added_against_the_choices_is_refused(termed, puma, tmp_path, change):
    f = tmp_path / "r.json"
    d = copy.deepcopy(termed["doc"])
    if change == "delete a term":
        del d["terms"][0]
    elif change == "delete its choice":
        d["term_choices"] = [c for c in d["term_choices"] if c["name"] != "delay"]
    else:
        next(c for c in d["term_choices"] if c["name"] == "scale")["kept"] = False
    f.write_text(json.dumps(d))
    msg = api_error(Identification.load, f, puma)
    assert f"{f}: terms: " in msg and "term_choices says" in msg, msg
