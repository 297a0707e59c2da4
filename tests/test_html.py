"""The HTML reports, rendered in headless Chromium (Debian's ``chromium``; CI installs it).

The checks read the page after its scripts ran (``--dump-dom``): the 3D view holds one ``g.body``
per body with projected coordinates, the grid has ten cells per body classed as the analysis JSON
says, the identification plots have two series (measured, predicted) per joint and part. A
screenshot of each report is saved in the test's temporary folder.
"""

import json
import shutil
import subprocess
import time
from html.parser import HTMLParser

import numpy as np
import pytest

import baseparams
from baseparams.report.html import analysis_html, identification_html

from paths import SHARED

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


class _Dom(HTMLParser):
    """Elements as (tag, attributes) in document order."""

    def __init__(self):
        super().__init__()
        self.elements = []

    def handle_starttag(self, tag, attrs):
        self.elements.append((tag, dict(attrs)))


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
    return parser.elements, seconds, path.stat().st_size


def _expected_classes(j: dict, names: list[str]) -> list[str]:
    alone = {b["expression"] for b in j["base_parameters"] if " " not in b["expression"]}
    return ["unidentifiable" if n in j["unidentifiable"] else "identifiable" if n in alone else "regrouped"
            for n in names]


@pytest.mark.parametrize("name", ["puma560", "pkm-2rru-1rrs"])
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


def test_identification_report_in_a_browser(tmp_path):
    from baseparams.identify import identify
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
    assert size < 5e6 and seconds < 10  # headless start included; the page itself renders in well under 2 s
    assert sum(1 for t, a in els if t == "g" and "body" in a.get("class", "")) == robot.n
    assert json.loads(json.dumps(result.to_json()))["n_bodies"] == robot.n
