"""Self-contained HTML reports of an analysis and of an identification (no network at view time).

Everything is inlined: the data as JSON in a ``<script type="application/json">`` element, the
styles and a small vanilla-JavaScript viewer. The analysis report draws the robot at q = 0 in 3D
(links as segments between joint frames, joint axes, loop joints marked; drag to rotate), a grid of
each body's ten standard parameters classed ``identifiable`` / ``regrouped`` /
``unidentifiable`` (clicking a body highlights its row), the regrouped base parameters and the
certification's singular values on a log scale with the tolerance. The identification report
plots measured and predicted torques per joint, residual histograms, the base parameters with
their %sigma as bars, the condition number and, for a physical fit, each body's mass and the
smallest eigenvalue of its pseudo-inertia.
"""

from __future__ import annotations

import html
import json

import numpy as np

_STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222;max-width:1200px}
h1{font-size:1.4em} h2{font-size:1.15em;margin-top:1.6em}
table{border-collapse:collapse;font-size:12px} td,th{border:1px solid #ccc;padding:2px 5px}
td.identifiable{background:#cfe8cf} td.regrouped{background:#ffe9b3} td.unidentifiable{background:#f4c7c7}
tr.hl td{outline:2px solid #1f5fbf}
.expr{font-family:monospace;font-size:12px;white-space:pre-wrap}
svg{background:#fafafa;border:1px solid #ddd}
.legend span{display:inline-block;padding:0 6px;margin-right:6px}
"""

_VIEWER = """
(function(){
const data = JSON.parse(document.getElementById('robot-data').textContent);
const svg = document.getElementById('view3d'); const W = svg.clientWidth || 480, H = 420;
let ax = -0.5, az = 0.6, drag = null;
function project(p){
  const ca=Math.cos(az), sa=Math.sin(az), cb=Math.cos(ax), sb=Math.sin(ax);
  const x = ca*p[0] - sa*p[1], y = sa*p[0] + ca*p[1], z = p[2];
  const y2 = cb*y - sb*z, z2 = sb*y + cb*z;
  return [W/2 + data.scale*x, H/2 - data.scale*z2];
}
function draw(){
  for (const el of svg.querySelectorAll('line[data-a]')) {
    const a = project(JSON.parse(el.dataset.a)), b = project(JSON.parse(el.dataset.b));
    el.setAttribute('x1', a[0]); el.setAttribute('y1', a[1]); el.setAttribute('x2', b[0]); el.setAttribute('y2', b[1]);
  }
}
svg.addEventListener('mousedown', e => drag = [e.clientX, e.clientY, ax, az]);
window.addEventListener('mouseup', () => drag = null);
window.addEventListener('mousemove', e => { if (!drag) return;
  az = drag[3] + (e.clientX - drag[0]) / 150; ax = drag[2] + (e.clientY - drag[1]) / 150; draw(); });
for (const g of svg.querySelectorAll('g.body')) g.addEventListener('click', () => {
  for (const r of document.querySelectorAll('tr.hl')) r.classList.remove('hl');
  const row = document.querySelector('tr[data-body="' + g.dataset.body + '"]'); if (row) row.classList.add('hl');
});
draw(); document.body.dataset.ready = '1';
})();
"""


def _page(title: str, body: str, script: str = "") -> str:
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{_STYLE}</style></head><body>{body}<script>{script}</script></body></html>")


def parameter_classes(result) -> dict[str, str]:
    """Each standard parameter's class in the analysis.

    Parameters
    ----------
    result : Analysis
        The analysis.

    Returns
    -------
    dict of str to str
        ``name -> "identifiable" | "regrouped" | "unidentifiable"``: unidentifiable when no
        measurement sees it; identifiable when it is a base parameter on its own; regrouped when
        it appears in a base parameter with others.
    """
    j = result.to_json()
    unid = set(j["unidentifiable"])
    out = {}
    alone = {b["expression"] for b in j["base_parameters"] if " " not in b["expression"]}
    for name in result.names:
        out[name] = ("unidentifiable" if name in unid else "identifiable" if name in alone else "regrouped")
    return out


def _robot_svg(robot) -> tuple[str, dict]:
    """The 3D view's SVG (one ``g.body`` per body) and its data (scale)."""
    pos = robot.M0[:, :3, 3]
    span = float(np.ptp(np.vstack([pos, np.zeros((1, 3))]), axis=0).max()) or 1.0
    parts = []
    for i, name in enumerate(robot.names):
        p = robot.parent[i]
        a = np.zeros(3) if p < 0 else pos[p]
        z = robot.M0[i, :3, :3] @ np.asarray(robot.axes[i]).reshape(-1, 3)[0][:3] if robot.jtype[i] in "RPU" else None
        lines = [f"<line data-a='{json.dumps(a.round(6).tolist())}' data-b='{json.dumps(pos[i].round(6).tolist())}' "
                 f"stroke='#333' stroke-width='3'/>"]
        if z is not None and np.linalg.norm(z) > 0:
            tip = pos[i] + 0.08 * span * z / np.linalg.norm(z)
            lines.append(f"<line data-a='{json.dumps(pos[i].round(6).tolist())}' "
                         f"data-b='{json.dumps(tip.round(6).tolist())}' stroke='#c33' stroke-width='2'/>")
        parts.append(f"<g class='body' data-body='{html.escape(name)}'><title>{html.escape(name)} "
                     f"({robot.jtype[i]})</title>{''.join(lines)}</g>")
    for lj in robot.loops:
        m = lj.M[:3, 3]
        parts.append(f"<g class='loop' data-loop='{html.escape(lj.name)}'><line data-a='{json.dumps(m.tolist())}' "
                     f"data-b='{json.dumps((m + 0.02 * span).tolist())}' stroke='#1f5fbf' stroke-width='6'/></g>")
    return (f"<svg id='view3d' width='480' height='420'>{''.join(parts)}</svg>",
            {"scale": 0.8 * 420 / span / 1.6})


def _grid(result) -> str:
    cls = parameter_classes(result)
    from ..model import inertia

    head = "".join(f"<th>{html.escape(str(p))}</th>" for p in inertia.NAMES.get(result.convention, range(10)))
    rows = []
    for i, body in enumerate(result.robot.names):
        cells = "".join(f"<td class='{cls[n]}' title='{html.escape(n)}: {cls[n]}'>{html.escape(n.split('.')[-1])}</td>"
                        for n in result.names[10 * i:10 * i + 10])
        rows.append(f"<tr data-body='{html.escape(body)}'><th>{html.escape(body)}</th>{cells}</tr>")
    legend = ("<p class='legend'><span class='identifiable' style='background:#cfe8cf'>identifiable alone</span>"
              "<span style='background:#ffe9b3'>regrouped</span><span style='background:#f4c7c7'>unidentifiable"
              "</span></p>")
    return f"{legend}<table id='grid'><tr><th>body</th>{head}</tr>{''.join(rows)}</table>"


def _log_plot(values: np.ndarray, tol: float | None, plot_id: str, width: int = 600, height: int = 220) -> str:
    """An SVG of positive values on a log scale (one ``circle.sv`` each), a dashed tolerance line."""
    v = np.asarray(values, dtype=float)
    v = np.where(v > 0, v, np.nan)
    finite = v[np.isfinite(v)]
    lo, hi = (np.log10(finite.min()) - 0.5, np.log10(finite.max()) + 0.5) if finite.size else (-1, 1)
    if tol:
        lo = min(lo, np.log10(tol) - 0.5)

    def y(val):
        return height - 10 - (np.log10(val) - lo) / (hi - lo) * (height - 20)

    pts = "".join(f"<circle class='sv' cx='{10 + k * (width - 20) / max(len(v) - 1, 1):.1f}' "
                  f"cy='{(y(val) if np.isfinite(val) else height - 5):.1f}' r='2'/>" for k, val in enumerate(v))
    line = (f"<line class='tol' x1='0' x2='{width}' y1='{y(tol):.1f}' y2='{y(tol):.1f}' stroke='#c33' "
            f"stroke-dasharray='4'/>") if tol else ""
    return f"<svg id='{plot_id}' width='{width}' height='{height}'>{pts}{line}</svg>"


def analysis_html(result) -> str:
    """The analysis report (module doc) as one self-contained HTML page.

    Parameters
    ----------
    result : Analysis
        The analysis (:func:`baseparams.analyze`).

    Returns
    -------
    str
        The page.
    """
    j = result.to_json()
    view, data = _robot_svg(result.robot)
    exprs = "".join(f"<tr><td>{html.escape(b['name'])}</td><td class='expr'>{html.escape(b['expression'])}</td></tr>"
                    for b in j["base_parameters"])
    cert = result.certificate
    sv = ""
    if cert is not None:
        num = cert.numerical
        sv = (f"<h2>Certification: {html.escape(str(cert.status))}</h2><p>{html.escape(cert.message)}</p>"
              f"<p>Singular values of the sampled regressor (log scale), tolerance dashed "
              f"({num.tol:.3g}), gap {num.gap:.3g}:</p>{_log_plot(num.singular_values, num.tol, 'svplot')}"
              f"<p>Sampling: {html.escape(json.dumps(cert.sampling))}</p>")
    prov = "".join(f"<li>{html.escape(str(k))}: rank {v}</li>" for k, v in result.by_principle.items())
    body = (f"<h1>{html.escape(result.robot.name)}: {result.n_base} base parameters, nullity {result.nullity} "
            f"({html.escape(str(result.status))})</h1>"
            f"<p>{result.robot.n} bodies, {10 * result.robot.n} standard parameters ({html.escape(result.convention)} "
            f"convention), rows: {html.escape(str(result.rows))}. Drag the view to rotate; click a body.</p>"
            f"<div style='display:flex;gap:1em;flex-wrap:wrap'><div>{view}</div><div>{_grid(result)}</div></div>"
            f"<h2>Nullspace directions by source</h2><ul>{prov}</ul>"
            f"<h2>Base parameters</h2><table id='base'>{exprs}</table>{sv}"
            f"<script type='application/json' id='robot-data'>{json.dumps(data)}</script>")
    return _page(f"{result.robot.name}: base parameters", body, _VIEWER)


def _series_svg(t: np.ndarray, ys: list[np.ndarray], plot_id: str, width: int = 560, height: int = 120,
                colors=("#555", "#1f5fbf")) -> str:
    """Polylines (one ``polyline.series`` per array in ``ys``) over ``t``, at most 1500 points each."""
    step = max(1, len(t) // 1500)
    t = t[::step]
    lo = min(float(np.min(y[::step])) for y in ys)
    hi = max(float(np.max(y[::step])) for y in ys)
    hi = hi if hi > lo else lo + 1.0
    span = float(t[-1] - t[0]) or 1.0
    lines = []
    for k, y in enumerate(ys):
        xs = 5 + (t - t[0]) / span * (width - 10)
        yy = height - 5 - (y[::step] - lo) / (hi - lo) * (height - 10)
        pts = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(xs, yy))
        lines.append(f"<polyline class='series' points='{pts}' fill='none' stroke='{colors[k % 2]}' stroke-width='1'/>")
    return f"<svg class='plot' id='{plot_id}' width='{width}' height='{height}'>{''.join(lines)}</svg>"


def _histogram(e: np.ndarray, width: int = 200, height: int = 120) -> str:
    counts, _ = np.histogram(e, bins=30)
    top = max(int(counts.max()), 1)
    bars = "".join(f"<rect x='{k * width / 30:.1f}' y='{height - c / top * height:.1f}' width='{width / 30 - 1:.1f}' "
                   f"height='{c / top * height:.1f}' fill='#888'/>" for k, c in enumerate(counts))
    return f"<svg class='hist' width='{width}' height='{height}'>{bars}</svg>"


def identification_html(ident) -> str:
    """The identification report (module doc) as one self-contained HTML page.

    Parameters
    ----------
    ident : Identification
        The result of :func:`baseparams.identify.identify`.

    Returns
    -------
    str
        The page.
    """
    j = ident.to_json()
    blocks = []
    for part in ("train", "validation"):
        s = (ident.series or {}).get(part)
        if not s:
            continue
        for k, joint in enumerate(s["joints"]):
            e = s["tau"][:, k] - s["tau_hat"][:, k]
            blocks.append(f"<div class='joint' data-part='{part}' data-joint='{html.escape(joint)}'><b>{part}: "
                          f"{html.escape(joint)}</b> (RMS {np.sqrt(np.mean(e**2)):.4g})<br>"
                          f"{_series_svg(s['t'], [s['tau'][:, k], s['tau_hat'][:, k]], f'{part}-{k}')}"
                          f"{_histogram(e)}</div>")
    pct = [b["pct_sigma"] for b in j["base_parameters"]]
    top = max([p for p in pct if np.isfinite(p)] + [1.0])
    bars = "".join(f"<tr><td>{html.escape(b['name'])}</td><td>{b['value']:.6g}</td><td>{b['pct_sigma']:.3g}</td>"
                   f"<td><svg width='200' height='10'><rect class='pct' "
                   f"width='{min(200, 200 * b['pct_sigma'] / top):.1f}' height='10' fill='#1f5fbf'/></svg></td></tr>"
                   for b in j["base_parameters"])
    phys = ""
    if j["physical"] is not None:
        rows = "".join(f"<tr><td>{html.escape(b)}</td><td>{m:.4g}</td><td>{e:.3g}</td></tr>" for b, m, e in
                       zip(j["physical"]["masses"], j["physical"]["masses"].values(),
                           ident.fit.physical.min_eigenvalues))
        phys = (f"<h2>Physical consistency: feasible {j['physical']['feasible']}</h2><table id='physical'>"
                f"<tr><th>body</th><th>mass [kg]</th><th>smallest eigenvalue of N_i</th></tr>{rows}</table>")
    val = j["validation"]
    body = (f"<h1>{html.escape(j['model'])}: identification ({html.escape(j['method'])})</h1>"
            f"<p>{j['n_samples']['used']} samples used of {j['n_samples']['read']}; condition number "
            f"{j['condition_number']:.4g}; train RMS {j['train']['rms_total']:.4g}"
            + (f"; validation RMS {val['rms_total']:.4g}" if val else "") + "</p>"
            f"<h2>Measured (grey) and predicted (blue) torques, residual histograms</h2>{''.join(blocks)}"
            f"<h2>Base parameters and %sigma</h2><table id='values'><tr><th>name</th><th>value</th><th>%sigma</th>"
            f"<th></th></tr>{bars}</table>{phys}")
    return _page(f"{j['model']}: identification", body, "document.body.dataset.ready='1';")
