"""Static figures (``--plot``, matplotlib): the analysis figure read back from the SVG written."""

import re
import sys

import pytest

import baseparams
from baseparams.cli import main
from baseparams.report.plots import CLASS_COLORS, analysis_figure, analysis_plot
from test_html import _expected_classes


def _cell_fills(svg: str) -> dict[tuple[int, int], str]:
    """``(body, parameter) -> fill colour`` of the grid's cells (``<g id="cell-i-k">``) in an SVG."""
    out = {}
    for m in re.finditer(r'<g id="cell-(\d+)-(\d+)">(.*?)</g>', svg, re.S):
        fill = re.search(r"fill: (#[0-9a-f]{6})", m.group(3))
        out[int(m.group(1)), int(m.group(2))] = fill.group(1)
    return out


@pytest.mark.parametrize("name", ["puma560", "pkm-2rru-1rrs"])
def test_analysis_figure_grid_colours_match_the_json(name, tmp_path, capsys):
    """``analyze --plot F.svg``: the grid's cell colours in the file are the JSON's classes."""
    svg = tmp_path / "a.svg"
    assert main(["analyze", name, "--json", "--plot", str(svg)]) == 0
    assert "plot written to" in capsys.readouterr().err
    result = baseparams.analyze(baseparams.load(name))
    fills = _cell_fills(svg.read_text())
    assert len(fills) == 10 * result.robot.n
    colour_class = {c: k for k, c in CLASS_COLORS.items()}
    got = [colour_class[fills[i, k]] for i in range(result.robot.n) for k in range(10)]
    assert got == _expected_classes(result.to_json(), list(result.names))
    assert len(set(got)) >= 2  # a grid of one colour would not test much


def test_analysis_figure_parts(tmp_path):
    result = baseparams.analyze(baseparams.load("pkm-2rru-1rrs"))
    fig = analysis_figure(result)
    robot_ax, grid_ax, sv_ax = fig.axes[:3]
    assert robot_ax.name == "3d"
    # links (one per body), joint axes (one per R/P/U joint) and two dashed sides per loop joint
    assert len(robot_ax.lines) == result.robot.n + sum(t in "RPU" for t in result.robot.jtype) + 2 * len(
        result.robot.loops)
    assert len(grid_ax.patches) == 10 * result.robot.n
    sv = sv_ax.get_lines()[0].get_ydata()
    assert len(sv) == len(result.certificate.numerical.singular_values)
    assert any(abs(ln.get_ydata()[0] - result.certificate.numerical.tol) < 1e-18 for ln in sv_ax.get_lines()[1:])
    png = analysis_plot(result, tmp_path / "a.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_without_matplotlib_is_one_line(tmp_path, monkeypatch, capsys):
    for mod in ("matplotlib", "matplotlib.pyplot"):
        monkeypatch.setitem(sys.modules, mod, None)  # import raises ImportError
    assert main(["analyze", "puma560", "--plot", str(tmp_path / "a.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["baseparams: error: --plot needs matplotlib: pip install 'baseparams[plot]'"]
    assert not (tmp_path / "a.png").exists()


def _svg_texts(path) -> list[str]:
    """The text elements of an SVG written with ``svg.fonttype = none`` (text kept as text)."""
    import html

    return [html.unescape(t) for t in re.findall(r"<text[^>]*>([^<]*)</text>", path.read_text())]


def _with_text_svg(fn, *args):
    import matplotlib

    with matplotlib.rc_context({"svg.fonttype": "none"}):
        return fn(*args)


def test_torque_plot_axes_have_units(tmp_path, capsys):
    """``identify --plot``: every joint's axis reads torque [N m], the time axis time [s]."""
    from baseparams.ident import identify
    from baseparams.io.logs import read_log
    from baseparams.report.plots import torque_plot

    log = tmp_path / "sim.npz"
    assert main(["simulate", "puma560", str(log), "--duration", "6", "--rate", "100", "--noise", "0.05"]) == 0
    robot = baseparams.load("puma560")
    result = identify(robot, read_log(log, robot), method="ols", holdout=2.0)
    svg = _with_text_svg(torque_plot, result, tmp_path / "t.svg")
    texts = _svg_texts(svg)
    assert texts.count("torque [N m]") == robot.dof
    assert "time [s]" in texts
    assert any(t.endswith("N m") and "train RMS" in t for t in texts)  # the title's RMS has its unit
    assert not any("nan" in t.lower().split() for t in texts)


def test_trajectory_plot_axes_have_units(tmp_path, capsys):
    """``excite --plot``: q [rad], dq [rad/s], ddq [rad/s^2] per joint, time [s]."""
    import matplotlib

    plot = tmp_path / "traj.svg"
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        assert main(["excite", "four-bar", "--harmonics", "3", "--period", "5", "--rate", "50", "--starts", "1",
                     "--grid", "40", "--plot", str(plot)]) == 0
    texts = _svg_texts(plot)
    for label in ("q [rad]", "dq [rad/s]", "ddq [rad/s^2]"):
        assert texts.count(label) == 1, (label, texts)
    assert texts.count("time [s]") == 3


def test_analysis_figure_axes_are_labelled():
    result = baseparams.analyze(baseparams.load("puma560"))
    robot_ax, grid_ax, sv_ax = analysis_figure(result).axes[:3]
    assert (robot_ax.get_xlabel(), robot_ax.get_ylabel(), robot_ax.get_zlabel()) == ("x [m]", "y [m]", "z [m]")
    assert grid_ax.get_xlabel().startswith("parameter") and grid_ax.get_ylabel() == "body"
    assert sv_ax.get_xlabel().startswith("index") and sv_ax.get_ylabel().startswith("singular value")
