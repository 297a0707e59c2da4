"""The HTML reports, rendered in headless Chromium (Debian's ``chromium``; CI installs it).

The checks read the page after its scripts ran (``--dump-dom``): the 3D view holds one ``g.body``
per body with projected coordinates, the grid has ten cells per body classed as the analysis JSON
says, the provenance groups drawn on the 3D view account for every DRNG column and their sources'
ranks are the JSON's, the identification plots have two series (measured, predicted) per joint and
part and one spectrum per joint. A screenshot of each report is saved in the test's temporary
folder; the page's own render time (``data-render-ms``) is read from the DOM.
"""

import json
import re
import shutil
import subprocess
import time
from html.parser import HTMLParser

import numpy as np
import pytest

import baseparams
from baseparams.report.html import analysis_html, identification_html

from paths import SHARED

pytestmark = pytest.mark.chromium

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


class _Dom(HTMLParser):
    """Elements as (tag, attributes) in document order; ``texts[k]``: element k's own text."""

    VOID = {"br", "meta", "img", "input", "hr", "link", "col", "wbr"}

    def __init__(self):
        super().__init__()
        self.elements = []
        self.texts = []
        self._open = []

    def handle_starttag(self, tag, attrs):
        self.elements.append((tag, dict(attrs)))
        self.texts.append("")
        if tag not in self.VOID:
            self._open.append(len(self.elements) - 1)

    def handle_startendtag(self, tag, attrs):
        self.elements.append((tag, dict(attrs)))
        self.texts.append("")

    def handle_endtag(self, tag):
        while self._open:
            k = self._open.pop()
            if self.elements[k][0] == tag:
                break

    def handle_data(self, data):
        if self._open:
            self.texts[self._open[-1]] += data

    def tables(self) -> dict[str, list[list[tuple[str, str]]]]:
        """Each table (by id) as rows of ``(cell tag, text)`` (nested elements' text included)."""
        out, current, row = {}, None, None
        for k, (tag, attrs) in enumerate(self.elements):
            if tag == "table":
                current = out.setdefault(attrs.get("id", f"table{k}"), [])
            elif tag == "tr" and current is not None:
                row = []
                current.append(row)
            elif tag in ("td", "th") and row is not None:
                row.append((tag, self.texts[k]))
            elif tag in ("b", "code", "span", "i", "a", "sub", "sup"):
                if row:
                    row[-1] = (row[-1][0], row[-1][1] + self.texts[k])
            elif tag not in ("svg", "rect", "tbody", "thead"):  # outside the table
                current, row = None, None
        return out


def _render(page: str, tmp_path, name: str):
    assert CHROMIUM, "chromium is required (apt-get install chromium; .ci/run installs it)"
    path = tmp_path / f"{name}.html"
    path.write_text(page)
    flags = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=3000"]
    t0 = time.perf_counter()
    dom = subprocess.run(flags + ["--dump-dom", path.as_uri()], capture_output=True, text=True, timeout=120).stdout
    seconds = time.perf_counter() - t0
    subprocess.run(flags + [f"--screenshot={tmp_path / (name + '.png')}", "--window-size=1200,900", path.as_uri()],
                   capture_output=True, timeout=120)
    assert (tmp_path / f"{name}.png").stat().st_size > 10_000
    parser = _Dom()
    parser.feed(dom)
    _render.last = parser
    return parser.elements, seconds, path.stat().st_size


def _visible_text(dom: _Dom) -> str:
    """The page's text (tables, headings, SVG labels), scripts and styles left out."""
    return " ".join(t for (tag, _), t in zip(dom.elements, dom.texts) if tag not in ("script", "style"))


def _check_tables(dom: _Dom) -> dict:
    """Every table starts with a row of headers; no cell, and no text of the page, reads ``nan``."""
    tables = dom.tables()
    for name, rows in tables.items():
        assert rows and rows[0] and all(tag == "th" for tag, _ in rows[0]), name
        assert all(text.strip() for _, text in rows[0]), name  # every column named
    assert not re.search(r"\bnan\b", _visible_text(dom), re.I)
    return tables


def _check_provenance(els, result, view_bodies: set[str]) -> None:
    """The provenance groups on the 3D view and in the list against DRNG and the analysis JSON."""
    from baseparams.nullspace.drng import drng

    j = result.to_json()
    res = drng(result.robot, extended=result.extended, rows=result.rows)
    groups = [a for t, a in els if t == "g" and "prov" in a.get("class", "").split()]
    assert groups and sum(int(g["data-columns"]) for g in groups) == res.n_columns == j["drng"]["columns"]
    for g in groups:
        bodies = json.loads(g["data-bodies"])
        assert bodies and set(bodies) <= view_bodies, g
    dots = [a for t, a in els if t == "circle" and "data-p" in a]
    assert len(dots) >= len(groups) and all(np.isfinite(float(a["cx"])) for a in dots)  # projected by the script
    items = [a for t, a in els if t == "li" and "prov-item" in a.get("class", "")]
    assert [a["data-group"] for a in items] == [g["data-group"] for g in groups]
    assert [a["data-columns"] for a in items] == [g["data-columns"] for g in groups]
    ranks = {a["data-source"]: int(a["data-rank"]) for t, a in els if t == "li" and a.get("class") == "source"}
    numerical = next(a for t, a in els if a.get("id") == "numerical")
    assert {**ranks, "numerical": int(numerical["data-count"])} == j["drng"]["by_rule"]
    assert sum(ranks.values()) == j["drng"]["rank"] and sum(ranks.values()) + j["completed"] == j["nullity"]


def _expected_classes(j: dict, names: list[str]) -> list[str]:
    alone = {b["expression"] for b in j["base_parameters"] if " " not in b["expression"]}
    return ["unidentifiable" if n in j["unidentifiable"] else "identifiable" if n in alone else "regrouped"
            for n in names]


@pytest.mark.parametrize("name", ["puma560", "pkm-2rru-1rrs"])
@pytest.mark.slow
def test_analysis_report_in_a_browser(name, tmp_path):
    result = baseparams.analyze(baseparams.load(name))
    els, _, _ = _render(analysis_html(result), tmp_path, name)
    body = next(a for t, a in els if t == "body")
    assert body.get("data-ready") == "1"  # the viewer's script ran
    bodies = [a["data-body"] for t, a in els if t == "g" and "body" in a.get("class", "")]
    assert bodies == list(result.robot.names)
    lines = [a for t, a in els if t == "line" and "data-a" in a]
    assert lines and all("x1" in a and np.isfinite(float(a["x1"])) for a in lines)  # projected by the script
    cells = [a["class"] for t, a in els if t == "td" and a.get("class") in ("identifiable", "regrouped",
                                                                            "unidentifiable")]
    assert len(cells) == 10 * result.robot.n
    assert cells == _expected_classes(result.to_json(), list(result.names))
    assert sum(1 for t, a in els if t == "circle" and a.get("class") == "sv") == 10 * result.robot.n
    assert sum(1 for t, a in els if t == "line" and a.get("class") in ("tol", "gap")) == 2
    exprs = {b["name"]: b["expression"] for b in result.to_json()["base_parameters"]}
    for a in (a for t, a in els if t == "td" and a.get("class") == "regrouped"):
        into = a["data-into"].split()
        assert into and all(a["data-param"] in exprs[b].replace("*", " ").split() for b in into)
    _check_provenance(els, result, set(bodies))
    assert float(body["data-render-ms"]) < 2000
    dom = _render.last
    tables = _check_tables(dom)
    assert [t for _, t in tables["base"][0]] == ["name", "expression"]
    assert len(tables["base"]) == 1 + result.n_base
    labels = [t for (tag, a), t in zip(dom.elements, dom.texts) if "axis-label" in a.get("class", "")]
    assert "singular value" in labels and any(x.startswith("index") for x in labels)


@pytest.mark.shared
@pytest.mark.slow
def test_identification_report_in_a_browser(tmp_path):
    from baseparams.ident import identify
    from baseparams.io.logs import read_log

    panda = SHARED.parent / "ident" / "panda_gaz2019"
    robot = baseparams.load(str(panda / "panda_mdh_gaz2019.urdf"))
    sig = {k: np.loadtxt(panda / f"exciting_traj_{f}.txt").reshape(-1, 7)
           for k, f in (("q", "positions"), ("dq", "velocity"), ("tau", "torques"))}
    csv = tmp_path / "panda.csv"
    header = ["t"] + [f"{k}_{j}" for k in sig for j in robot.joint_names]
    np.savetxt(csv, np.column_stack([np.loadtxt(panda / "exciting_traj_time.txt"), *sig.values()]), delimiter=",",
               header=",".join(header), comments="", fmt="%.17g")
    ident = identify(robot, read_log(csv, robot), method="physical", holdout=6.0)
    els, _, _ = _render(identification_html(ident), tmp_path, "panda")
    series = [a for t, a in els if t == "polyline" and a.get("class") == "series"]
    assert len(series) == 2 * 7 * 2  # measured and predicted, 7 joints, training and held-out
    assert sum(1 for t, a in els if t == "rect" and a.get("class") == "pct") == len(ident.to_json()["base_parameters"])
    assert sum(1 for t, a in els if t == "table" and a.get("id") == "physical") == 1
    spectra = [a["data-joint"] for t, a in els if t == "polyline" and a.get("class") == "spectrum"]
    assert spectra == list(robot.joint_names)  # one amplitude spectrum per joint
    assert sum(1 for t, a in els if t == "line" and a.get("class") == "cutoff") == 1
    spec = ident.series["train"]["spectrum"]
    assert spec["amplitude"].shape == (len(spec["f"]), 7) and spec["cutoff"] > 0
    _check_report_axes_and_tables(_render.last, ident)


def _check_report_axes_and_tables(dom: _Dom, ident) -> None:
    """Units on every axis; base parameters with std and expression; one row per drive term."""
    j = ident.to_json()
    texts = list(zip(dom.elements, dom.texts))
    for svg_id in [a["id"] for (tag, a), _ in texts if tag == "svg" and a.get("class") == "plot"]:
        k = next(i for i, ((tag, a), _) in enumerate(texts) if a.get("id") == svg_id)
        end = next((i for i in range(k + 1, len(texts)) if texts[i][0][0] == "svg"), len(texts))
        labels = [t for (_, a), t in texts[k:end] if a.get("class") == "axis-label"]
        ticks = [t for (_, a), t in texts[k:end] if a.get("class") == "tick"]
        assert labels[:2] == ["time [s]", "torque [N m]"], (svg_id, labels)
        assert len(ticks) >= 4 and all(re.fullmatch(r"-?[\d.]+(e[-+]?\d+)?", t) for t in ticks), ticks
    labels = [t for (_, a), t in texts if a.get("class") == "axis-label"]
    assert labels.count("residual [N m]") == labels.count("count") == 2 * 7
    assert "frequency [Hz]" in labels and "amplitude [rad]" in labels
    tables = _check_tables(dom)
    head = [t for _, t in tables["values"][0]]
    assert {"name", "value", "unit", "std", "%sigma", "expression"} <= set(head)
    rows = tables["values"][1:]
    assert len(rows) == len(j["base_parameters"])
    for row, b in zip(rows, j["base_parameters"]):
        cells = dict(zip(head, (t for _, t in row)))
        assert cells["name"] == b["name"] and cells["expression"] == b["expression"]
        assert np.isclose(float(cells["value"]), b["value"], rtol=1e-5) and np.isclose(float(cells["std"]), b["std"],
                                                                                        rtol=1e-2)
        assert cells["unit"] in ("kg", "kg m", "kg m^2")
    drives = [(a["data-owner"], a["data-kind"]) for (tag, a), _ in texts if tag == "tr" and a.get("class") == "drive"]
    expected = [(d["joint"], k) for d in j["drives"] for k in ("Ia", "Fv", "Fc", "Fo") if d[k] is not None]
    assert drives == expected and len(expected) == 7 * 3  # viscous, Coulomb, offset per joint
    head = [t for _, t in tables["drives"][0]]
    assert {"term", "value", "std", "unit"} <= set(head)
    units = {t[head.index("term")].split()[0]: t[head.index("unit")] for t in
             ([x for _, x in row] for row in tables["drives"][1:])}
    assert units == {"Fv": "N m s/rad", "Fc": "N m", "Fo": "N m"}
    for row, (joint, kind) in zip(tables["drives"][1:], expected):
        value = next(d[kind] for d in j["drives"] if d["joint"] == joint)
        assert np.isclose(float(row[head.index("value")][1]), value, rtol=1e-5, atol=1e-12)
    assert [t for _, t in tables["rms"][0]] == ["joint", "train RMS", "validation RMS", "unit"]


@pytest.mark.slow
def test_talos_report_is_small_and_opens_fast(tmp_path):
    import warnings

    from baseparams.loading import load_model

    from erd import urdf_files

    talos = next(f for f in urdf_files() if f.name == "talos_full_v2.urdf")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot, _ = load_model(str(talos), floating=True, strict_inertia=False)
    result = baseparams.analyze(robot)
    els, seconds, size = _render(analysis_html(result), tmp_path, "talos")
    assert size < 5e6 and seconds < 10  # headless start included
    body = next(a for t, a in els if t == "body")
    assert float(body["data-render-ms"]) < 2000  # the page's own time: navigation start to its scripts' end
    bodies = [a["data-body"] for t, a in els if t == "g" and "body" in a.get("class", "")]
    assert bodies == list(robot.names) and robot.n == 45
    _check_provenance(els, result, set(bodies))
    assert int(next(a for t, a in els if a.get("id") == "numerical")["data-count"]) == result.certificate.completed
