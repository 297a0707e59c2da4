"""Self-contained HTML reports of an analysis and of an identification (no network at view time).

Everything is inlined: the data as JSON in a ``<script type="application/json">`` element, the
styles and a small vanilla-JavaScript viewer. The analysis report draws the robot at q = 0 in 3D
(links as segments between joint frames, joint axes, loop joints marked; drag to rotate), a grid of
each body's ten standard parameters classed ``identifiable`` / ``regrouped`` (into which base
parameter) / ``unidentifiable`` (clicking a body highlights its row and back), the nullspace
directions grouped by provenance (principle or rule, joint, points; hovering or clicking one shows
the joint's point and axis and the bodies involved on the 3D view), the regrouped base parameters
and the certification's singular values on a log scale with the tolerance and the gap. The
identification report plots measured and predicted torques per joint, residual histograms, the
base parameters with their %sigma as bars, the condition number, for a physical fit each body's
mass and the smallest eigenvalue of its pseudo-inertia, and the excitation spectrum of the
training positions with the low-pass cutoff.

Both pages write the time their scripts finished, ``performance.now()`` in milliseconds since
navigation started, into ``data-render-ms`` on ``<body>`` (and ``data-ready="1"``).
"""

from __future__ import annotations

import html
import json

import numpy as np

_STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222;max-width:1250px}
h1{font-size:1.4em} h2{font-size:1.15em;margin-top:1.6em}
table{border-collapse:collapse;font-size:12px} td,th{border:1px solid #ccc;padding:2px 5px}
td.identifiable{background:#cfe8cf} td.regrouped{background:#ffe9b3} td.unidentifiable{background:#f4c7c7}
tr.hl td,tr.hl th{outline:2px solid #1f5fbf} #grid tr[data-body]{cursor:pointer}
.expr{font-family:monospace;font-size:12px;white-space:pre-wrap} td.unit{white-space:nowrap}
svg{background:#fafafa;border:1px solid #ddd} svg text{font-size:10px;fill:#555}
#view3d{cursor:grab} g.body line.link{stroke:#333} g.body.sel line.link{stroke:#1f5fbf}
g.body.involved line.link{stroke:#e07000;stroke-width:5} g.body{cursor:pointer}
g.prov{display:none} g.prov.on{display:inline} g.prov circle{fill:#e07000;stroke:#fff}
g.prov line{stroke:#e07000;stroke-width:2;stroke-dasharray:6 3} g.prov text{fill:#a04000;font-size:11px}
#provenance li.prov-item{cursor:pointer;font-size:13px} #provenance li.prov-item.on{background:#ffe2c2}
#provenance li.source{margin-top:.4em} .muted{color:#777}
.legend span{display:inline-block;padding:0 6px;margin-right:6px}
#torques{display:flex;flex-wrap:wrap;gap:.3em 1.2em} div.joint{font-size:13px}
"""

_VIEWER = """
(function(){
const data = JSON.parse(document.getElementById('robot-data').textContent);
const svg = document.getElementById('view3d');
const W = +svg.getAttribute('width'), H = +svg.getAttribute('height'), C = data.center, S = data.scale;
let ax = -0.35, az = 0.6, drag = null, pinned = null;
const lines = Array.from(svg.querySelectorAll('line[data-a]'),
  el => [el, JSON.parse(el.dataset.a), JSON.parse(el.dataset.b)]);
const dots = Array.from(svg.querySelectorAll('[data-p]'), el => [el, JSON.parse(el.dataset.p)]);
function project(p){
  const x0 = p[0] - C[0], y0 = p[1] - C[1], z0 = p[2] - C[2];
  const ca = Math.cos(az), sa = Math.sin(az), cb = Math.cos(ax), sb = Math.sin(ax);
  const x = ca*x0 - sa*y0, y = sa*x0 + ca*y0, z = sb*y + cb*z0;
  return [(W/2 + S*x).toFixed(1), (H/2 - S*z).toFixed(1)];
}
function draw(){
  for (const [el, a, b] of lines) { const p = project(a), q = project(b);
    el.setAttribute('x1', p[0]); el.setAttribute('y1', p[1]);
    el.setAttribute('x2', q[0]); el.setAttribute('y2', q[1]); }
  for (const [el, a] of dots) { const p = project(a);
    if (el.tagName === 'circle') { el.setAttribute('cx', p[0]); el.setAttribute('cy', p[1]); }
    else { el.setAttribute('x', +p[0] + 7); el.setAttribute('y', +p[1] - 7); } }
}
svg.addEventListener('mousedown', e => { drag = [e.clientX, e.clientY, ax, az]; e.preventDefault(); });
window.addEventListener('mouseup', () => drag = null);
window.addEventListener('mousemove', e => { if (!drag) return;
  az = drag[3] + (e.clientX - drag[0]) / 150; ax = drag[2] + (e.clientY - drag[1]) / 150; draw(); });
const bodyEl = {}; for (const g of svg.querySelectorAll('g.body')) bodyEl[g.dataset.body] = g;
function select(name){
  for (const el of document.querySelectorAll('tr.hl, g.body.sel')) el.classList.remove('hl', 'sel');
  const row = document.querySelector('#grid tr[data-body="' + CSS.escape(name) + '"]');
  if (row) row.classList.add('hl'); if (bodyEl[name]) bodyEl[name].classList.add('sel');
}
for (const g of svg.querySelectorAll('g.body')) g.addEventListener('click', () => select(g.dataset.body));
for (const r of document.querySelectorAll('#grid tr[data-body]'))
  r.addEventListener('click', () => select(r.dataset.body));
const provs = {}; for (const g of svg.querySelectorAll('g.prov')) provs[g.dataset.group] = g;
function show(id, on){
  const g = provs[id]; if (!g) return; g.classList.toggle('on', on);
  for (const b of JSON.parse(g.dataset.bodies)) if (bodyEl[b]) bodyEl[b].classList.toggle('involved', on);
  const li = document.querySelector('li.prov-item[data-group="' + id + '"]'); if (li) li.classList.toggle('on', on);
}
for (const li of document.querySelectorAll('li.prov-item')) { const id = li.dataset.group;
  li.addEventListener('mouseenter', () => { if (pinned === null) show(id, true); });
  li.addEventListener('mouseleave', () => { if (pinned === null) show(id, false); });
  li.addEventListener('click', () => { const was = pinned; if (was !== null) show(was, false);
    pinned = was === id ? null : id; if (pinned !== null) show(id, true); });
}
const h = location.hash.match(/prov=(\\d+)/); if (h && provs[h[1]]) { pinned = h[1]; show(h[1], true); }
draw();
document.body.dataset.renderMs = performance.now().toFixed(1); document.body.dataset.ready = '1';
})();
"""

_DONE = "document.body.dataset.renderMs = performance.now().toFixed(1); document.body.dataset.ready = '1';"

#: line colours of per-joint series (matplotlib's tab10)
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
           "#17becf")


def _page(title: str, body: str, script: str = "") -> str:
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{_STYLE}</style></head><body>{body}<script>{script}</script></body></html>")


def _attr(value) -> str:
    """A JSON value as an HTML attribute's text (quoted with ``'``)."""
    return html.escape(json.dumps(value), quote=True)


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


def _form_note(j: dict) -> str:
    """One line saying how the expressions are written (the JSON's ``form``)."""
    if j.get("form") == "recursive":
        return ("<p class='form'>Recursive form: each base parameter in its body's own standard parameters and its "
                "children's regrouped dependent parameters (NAMER, defined in the next table); "
                "<code>--form expanded</code> writes them in standard parameters only.</p>")
    return "<p class='form'>Expanded form: standard parameters only.</p>"


def _regrouped_table(j: dict) -> str:
    """The recursive form's regrouped dependent parameters (nothing in the expanded form)."""
    if not j.get("regrouped_parameters"):
        return ""
    rows = "".join(f"<tr><td>{html.escape(b['name'])}</td><td class='expr'>{html.escape(b['expression'])}</td></tr>"
                   for b in j["regrouped_parameters"])
    return (f"<h3>Regrouped dependent parameters</h3><table id='regrouped'><tr><th>name</th><th>expression</th></tr>"
            f"{rows}</table>")


def regrouped_into(result) -> dict[str, list[str]]:
    """The base parameters each standard parameter appears in.

    Parameters
    ----------
    result : Analysis
        The analysis.

    Returns
    -------
    dict of str to list of str
        ``name -> [base parameter names]`` in :attr:`~baseparams.analysis.Analysis.convention`:
        empty for an unidentifiable parameter, its own name for one identifiable alone.
    """
    base = result.base
    names = base.base_names()
    if getattr(result, "form", "expanded") == "recursive":
        return _recursive_into(base, names)
    if hasattr(base.E, "tocsc"):  # sparse regrouping of a large tree
        e = base.E.tocsc()
        return {name: [names[r] for r in e.indices[e.indptr[k]:e.indptr[k + 1]]] for k, name in enumerate(base.names)}
    return {name: [names[r] for r in np.flatnonzero(base.E[:, k] != 0)] for k, name in enumerate(base.names)}


def _recursive_into(base, names: list[str]) -> dict[str, list[str]]:
    """:func:`regrouped_into` of the recursive form, in linear time: where each parameter is written.

    An independent parameter: its base parameter; a dependent one: its regrouped parameter when it
    has one (``link2.M`` into ``link2.MR``), else the base and regrouped parameters it appears in.
    """
    import scipy.sparse as sp

    rf = base.recursive
    tn = rf.term_names()
    r = sp.csc_matrix(rf.R) if not hasattr(rf.R, "tocsc") else rf.R.tocsc()
    sm = sp.csc_matrix(rf.S) if not hasattr(rf.S, "tocsc") else rf.S.tocsc()
    out = {name: [] for name in base.names}
    for k, i in enumerate(base.independent.tolist()):
        out[base.names[i]] = [names[k]]
    regrouped = rf.regrouped()
    for k, d in enumerate(base.dependent.tolist()):
        if regrouped[k]:
            out[base.names[d]] = [tn[k]]
        else:
            out[base.names[d]] = ([names[x] for x in r.indices[r.indptr[k]:r.indptr[k + 1]]]
                                  + [tn[x] for x in sm.indices[sm.indptr[k]:sm.indptr[k + 1]]])
    for u in base.unidentifiable.tolist():
        out[base.names[u]] = []
    return out


def _axis(robot, i: int) -> np.ndarray | None:
    """Body ``i``'s (first) joint axis in the world at q = 0, or None (S, F joints)."""
    if robot.jtype[i] not in "RPUC":
        return None
    z = robot.M0[i, :3, :3] @ np.asarray(robot.axes[i], dtype=float).reshape(-1, 3)[0][:3]
    return z / np.linalg.norm(z) if np.linalg.norm(z) > 0 else None


def _pt(p) -> str:
    return _attr(np.round(np.asarray(p, dtype=float), 6).tolist())


def _robot_parts(robot, span: float) -> list[str]:
    """One ``g.body`` per body (its link and joint axis) and one ``g.loop`` per loop joint."""
    pos = robot.M0[:, :3, 3]
    parts = []
    for i, name in enumerate(robot.names):
        p = robot.parent[i]
        a = np.zeros(3) if p < 0 else pos[p]
        lines = [f"<line class='link' data-a='{_pt(a)}' data-b='{_pt(pos[i])}' stroke-width='3'/>"]
        z = _axis(robot, i)
        if z is not None:
            lines.append(f"<line class='axis' data-a='{_pt(pos[i] - 0.04 * span * z)}' "
                         f"data-b='{_pt(pos[i] + 0.06 * span * z)}' stroke='#c33' stroke-width='2'/>")
        parts.append(f"<g class='body' data-body='{html.escape(name)}'><title>{html.escape(name)} "
                     f"(joint {html.escape(robot.joint_names[i])}, {robot.jtype[i]})</title>{''.join(lines)}</g>")
    for lj in robot.loops:  # the cut joint, and both sides' links to it (dashed)
        m = lj.M[:3, 3]
        ends = [(lj.parent, m), (lj.child, m if lj.M_child is None else lj.M_child[:3, 3])]
        sides = "".join(f"<line data-a='{_pt(np.zeros(3) if b < 0 else pos[b])}' data-b='{_pt(e)}' stroke='#1f5fbf' "
                        f"stroke-width='2' stroke-dasharray='5 3'/>" for b, e in ends)
        parts.append(f"<g class='loop' data-loop='{html.escape(lj.name)}'><title>loop joint {html.escape(lj.name)} "
                     f"({lj.type})</title>{sides}<circle data-p='{_pt(m)}' r='5' fill='#fff' stroke='#1f5fbf' "
                     f"stroke-width='2'/></g>")
    return parts


def _joint_place(robot, source, j: int) -> tuple[str, np.ndarray, np.ndarray | None]:
    """What a column's ``joint`` index names: its description, point O and axis (world, q = 0).

    A tree joint (the paper's principles), a body (the extended rules, unmeasured roots; drawn at
    its joint frame) or, for ``j >= n``, loop joint ``j - n``.
    """
    if j >= robot.n:
        lj = robot.loops[j - robot.n]
        axes = np.asarray(lj.axes, dtype=float).reshape(-1, 3)
        axis = lj.M[:3, :3] @ axes[0] if len(axes) else None
        return f"loop joint {lj.name} ({lj.type})", lj.M[:3, 3], axis
    if source.is_paper:
        return f"joint {robot.joint_names[j]} ({robot.jtype[j]})", robot.M0[j, :3, 3], _axis(robot, j)
    return f"body {robot.names[j]}", robot.M0[j, :3, 3], None


def provenance_groups(result) -> tuple[object, list[dict]]:
    """DRNG's columns grouped by provenance: (principle or rule, joint).

    DRNG is run again on the analysed robot (``result.extended``, ``result.rows``): an
    :class:`~baseparams.analysis.Analysis` keeps its counts, not its columns.

    Parameters
    ----------
    result : Analysis
        The analysis.

    Returns
    -------
    drng : DRNGResult
        The columns (:func:`baseparams.nullspace.drng.drng`).
    groups : list of dict
        In source order, then joint order: ``{"source": Source, "joint": int (column's joint
        index), "place": str, "point": ndarray (3,), "axis": ndarray (3,) or None, "columns": int,
        "labels": [str] (distinct, e.g. "O z"), "bodies": [str] (child, parent and extra bodies)}``.
    """
    from ..enums import Source
    from ..nullspace.drng import drng

    res = drng(result.robot, extended=result.extended, rows=result.rows)
    c, robot = res.columns, result.robot
    groups: dict[tuple[int, int], dict] = {}
    for k in range(len(c)):
        g = groups.setdefault((int(c.principle[k]), int(c.joint[k])), {"columns": 0, "labels": [], "bodies": set()})
        g["columns"] += 1
        if str(c.label[k]) not in g["labels"]:
            g["labels"].append(str(c.label[k]))
        g["bodies"] |= {int(b) for b in (c.child[k], c.parent[k], c.extra[k]) if b >= 0}
        if c.more[k] is not None:
            g["bodies"] |= {int(b) for b in c.more[k][0]}
    out = []
    for (s, j), g in sorted(groups.items()):
        place, point, axis = _joint_place(robot, Source(s), j)
        out.append({"source": Source(s), "joint": j, "place": place, "point": point, "axis": axis,
                    "columns": g["columns"], "labels": g["labels"],
                    "bodies": [robot.names[b] for b in sorted(g["bodies"])]})
    return res, out


def _prov_parts(groups: list[dict], span: float) -> list[str]:
    """One hidden ``g.prov`` per provenance group: the joint's point O, its axis and a label."""
    parts = []
    for k, g in enumerate(groups):
        o = np.asarray(g["point"], dtype=float)
        axis = ""
        if g["axis"] is not None:
            z = np.asarray(g["axis"], dtype=float)
            axis = f"<line data-a='{_pt(o - 0.25 * span * z)}' data-b='{_pt(o + 0.25 * span * z)}'/>"
        parts.append(f"<g class='prov' data-group='{k}' data-source='{html.escape(g['source'].label)}' "
                     f"data-joint='{html.escape(g['place'])}' data-columns='{g['columns']}' "
                     f"data-bodies='{_attr(g['bodies'])}'>{axis}<circle data-p='{_pt(o)}' r='6'/>"
                     f"<text data-p='{_pt(o)}'>{html.escape(g['place'])}</text></g>")
    return parts


def _robot_svg(robot, groups: list[dict], width: int = 500, height: int = 440) -> tuple[str, dict]:
    """The 3D view's SVG (``g.body`` per body, ``g.loop``, ``g.prov`` per provenance group) and its data."""
    pts = np.vstack([robot.M0[:, :3, 3], np.zeros((1, 3))] + [lj.M[None, :3, 3] for lj in robot.loops])
    center = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    radius = float(np.linalg.norm(pts - center, axis=1).max()) or 1.0
    parts = _robot_parts(robot, 2 * radius) + _prov_parts(groups, 2 * radius)
    return (f"<svg id='view3d' width='{width}' height='{height}'>{''.join(parts)}</svg>",
            {"scale": 0.45 * min(width, height) / radius, "center": center.round(6).tolist()})


def _grid(result) -> str:
    cls = parameter_classes(result)
    into = regrouped_into(result)
    from ..model import inertia

    head = "".join(f"<th>{html.escape(str(p))}</th>" for p in inertia.NAMES.get(result.convention, range(10)))
    rows = []
    for i, body in enumerate(result.robot.names):
        cells = []
        for n in result.names[10 * i:10 * i + 10]:
            why = {"regrouped": f" into {', '.join(into[n])}", "identifiable": " alone"}.get(cls[n], "")
            cells.append(f"<td class='{cls[n]}' data-param='{html.escape(n)}' "
                         f"data-into='{html.escape(' '.join(into[n]))}' "
                         f"title='{html.escape(n)}: {cls[n]}{html.escape(why)}'>{html.escape(n.split('.')[-1])}</td>")
        rows.append(f"<tr data-body='{html.escape(body)}'><th>{html.escape(body)}</th>{''.join(cells)}</tr>")
    legend = ("<p class='legend'><span style='background:#cfe8cf'>identifiable alone</span>"
              "<span style='background:#ffe9b3'>regrouped (hover: into which)</span>"
              "<span style='background:#f4c7c7'>unidentifiable</span></p>")
    return f"{legend}<table id='grid'><tr><th>body</th>{head}</tr>{''.join(rows)}</table>"


def _source_kind(source) -> str:
    return ("paper principle" if source.is_paper else "extended rule" if source.is_extended
            else "measured rows: joint torques only" if source.label == "unmeasured root"
            else "measured rows: unmeasured joints")


def _provenance_list(result, groups: list[dict]) -> str:
    """The nullspace directions by source, each source's groups as hoverable entries."""
    from ..enums import Source

    items = []
    for src in Source:
        if src.label not in result.by_principle:
            continue
        mine = [(k, g) for k, g in enumerate(groups) if g["source"] is src]
        sub = "".join(
            f"<li class='prov-item' data-group='{k}' data-source='{html.escape(src.label)}' "
            f"data-columns='{g['columns']}'><b>{html.escape(g['place'])}</b>: {g['columns']} "
            f"column{'s' * (g['columns'] != 1)} ({html.escape(', '.join(g['labels'][:4]))}"
            f"{', ...' if len(g['labels']) > 4 else ''}); bodies {html.escape(', '.join(g['bodies']))}</li>"
            for k, g in mine)
        ncols = sum(g["columns"] for _, g in mine)
        items.append(f"<li class='source' data-source='{html.escape(src.label)}' "
                     f"data-rank='{result.by_principle[src.label]}'><b>{html.escape(src.label)}</b> "
                     f"<span class='muted'>({_source_kind(src)})</span>: rank {result.by_principle[src.label]} "
                     f"from {ncols} column{'s' * (ncols != 1)}<ul>{sub}</ul></li>")
    cert = result.certificate
    if cert is None:
        num = ("<p id='numerical' data-count='0'>Not certified (<code>--no-verify</code>): the directions above "
               "are DRNG's, unverified.</p>")
    else:
        num = (f"<p id='numerical' data-count='{cert.completed}'><b>{cert.completed}</b> "
               f"direction{'s' * (cert.completed != 1)} found numerically (no geometric rule).</p>")
    return (f"<p>Each direction of the nullspace is a combination of parameters that no measurement sees; "
            f"it comes from a geometric principle or rule at a joint (O: the joint's point, z: its axis, "
            f"x, y: directions across it). Hover or click an entry to show it on the 3D view "
            f"(<code>#prov=K</code> in the address shows entry K on opening).</p>"
            f"<ul id='provenance'>{''.join(items)}</ul>{num}")


def _decade_ticks(lo: float, hi: float) -> list[int]:
    """Integer powers of ten in ``[lo, hi]`` (log10 values), at most about eight."""
    ks = list(range(int(np.ceil(lo)), int(np.floor(hi)) + 1))
    step = max(1, len(ks) // 8)
    return ks[::step]


def _log_plot(values: np.ndarray, tol: float | None, plot_id: str, rank: int | None = None, width: int = 640,
              height: int = 240) -> str:
    """An SVG of positive values on a log scale (``circle.sv`` each), the tolerance, the rank gap."""
    v = np.asarray(values, dtype=float)
    v = np.where(v > 0, v, np.nan)
    finite = v[np.isfinite(v)]
    lo, hi = (np.log10(finite.min()) - 0.5, np.log10(finite.max()) + 0.5) if finite.size else (-1, 1)
    if tol:
        lo = min(lo, np.log10(tol) - 0.5)
    left, right = 58, 10

    def x(k):
        return left + k * (width - left - right) / max(len(v) - 1, 1)

    def y(val):
        return height - 22 - (np.log10(val) - lo) / (hi - lo) * (height - 32)

    ticks = "".join(f"<line x1='{left - 4}' x2='{width}' y1='{y(10.0**e):.1f}' y2='{y(10.0**e):.1f}' "
                    f"stroke='#eee'/><text class='tick' x='16' y='{y(10.0**e) + 3:.1f}'>1e{e}</text>"
                    for e in _decade_ticks(lo, hi))
    pts = "".join(f"<circle class='sv' cx='{x(k):.1f}' cy='{(y(val) if np.isfinite(val) else height - 5):.1f}' "
                  f"r='2.5'/>" for k, val in enumerate(v))
    line = (f"<line class='tol' x1='{left}' x2='{width}' y1='{y(tol):.1f}' y2='{y(tol):.1f}' stroke='#c33' "
            f"stroke-dasharray='4'/>") if tol else ""
    gap = ""
    if rank is not None and 0 < rank < len(v):
        gx = 0.5 * (x(rank - 1) + x(rank))
        gap = (f"<line class='gap' x1='{gx:.1f}' x2='{gx:.1f}' y1='0' y2='{height}' stroke='#1f5fbf' "
               f"stroke-dasharray='2 3'/><text x='{gx + 4:.1f}' y='12'>rank {rank} | nullity {len(v) - rank}</text>")
    labels = (f"<text class='axis-label' x='{(left + width) / 2:.0f}' y='{height - 1}' text-anchor='middle'>index "
              f"(largest first)</text><text class='axis-label' transform='translate(10,{height / 2:.0f}) rotate(-90)' "
              f"text-anchor='middle'>singular value</text>")
    return f"<svg id='{plot_id}' width='{width}' height='{height}'>{ticks}{pts}{line}{gap}{labels}</svg>"


def _certification(result) -> str:
    cert = result.certificate
    if cert is None:
        return "<h2>Certification: skipped</h2><p>The nullity is DRNG's rank, unverified (--no-verify).</p>"
    num = cert.numerical
    s = cert.sampling or {}
    sampling = f"{s.get('kept', num.samples)} of {s.get('requested', num.samples)} random samples kept"
    if "not_converged" in s and not result.robot.only_couplings:
        sampling += (f" ({s['not_converged']} outside the workspace, {s['branch_jumps']} off the reference branch "
                     f"or past a singular configuration, "
                     f"{s['ill_conditioned']} ill-conditioned; max loop residual {s['max_loop_residual']:.1e})")
        sampling += "".join(f"; {line}" for line in s.get("motion", ()))
    from ..numerics import decision_lines

    decision = "".join(f"<p id='rank-decision'>{html.escape(line)}</p>"
                       for line in decision_lines(result.rank_decision()))
    note = "" if result.practical is None else result.practical.note(result.n_base)
    snapped = f"<p id='snapped'>{html.escape(note)}</p>" if note else ""
    return (f"<h2>Certification: {html.escape(str(cert.status))}</h2><p>{html.escape(cert.message)}</p>{decision}"
            f"{snapped}"
            f"<p>Singular values of the sampled regressor (log scale); dashed red: the tolerance "
            f"({num.tol:.3g}); dotted blue: the rank decision, singular-value gap {num.gap:.3g}.</p>"
            f"{_log_plot(num.singular_values, num.tol, 'svplot', num.rank)}"
            f"<p id='sampling'>Sampling: {html.escape(sampling)}.</p>")


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
    _, groups = provenance_groups(result)
    view, data = _robot_svg(result.robot, groups)
    exprs = "".join(f"<tr><td>{html.escape(b['name'])}</td><td class='expr'>{html.escape(b['expression'])}</td></tr>"
                    for b in j["base_parameters"])
    loops = (f", {len(result.robot.loops)} loop joints (blue circles)" if result.robot.loops else "")
    body = (f"<h1>{html.escape(result.robot.name)}: {result.n_base} base parameters, nullity {result.nullity} "
            f"({html.escape(str(result.status))})</h1>"
            f"<p>{result.robot.n} bodies{loops}, {10 * result.robot.n} standard parameters "
            f"({html.escape(result.convention)} convention), rows: {html.escape(str(result.rows))}. The robot at "
            f"q = 0 (red: joint axes); drag the view to rotate; click a body or a row.</p>"
            f"<div style='display:flex;gap:1em;flex-wrap:wrap'><div>{view}</div><div>{_grid(result)}</div></div>"
            f"<h2>Why: the nullspace directions by provenance</h2>{_provenance_list(result, groups)}"
            f"<h2>Base parameters</h2>{_form_note(j)}<table id='base'><tr><th>name</th><th>expression</th></tr>{exprs}"
            f"</table>{_regrouped_table(j)}"
            f"{_certification(result)}"
            f"<script type='application/json' id='robot-data'>{json.dumps(data)}</script>")
    return _page(f"{result.robot.name}: base parameters", body, _VIEWER)


def _num(v, spec: str = ".6g", missing: str = "-") -> str:
    """A number for a table or a label: ``missing`` when absent or not finite (never ``nan``)."""
    if v is None or isinstance(v, str):
        return missing
    v = float(v)
    if not np.isfinite(v):
        return missing
    text = format(v, spec)
    return "0" if float(text) == 0 else text


def _ticks(lo: float, hi: float, n: int = 4) -> list[float]:
    """About ``n`` round tick values (1, 2, 5 times a power of ten) in ``[lo, hi]``."""
    span = hi - lo
    if not np.isfinite(span) or span <= 0:
        return [lo]
    raw = span / n
    mag = 10.0 ** np.floor(np.log10(raw))
    step = next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw)
    first = np.ceil(lo / step) * step
    return [float(v) for v in np.arange(first, hi + 1e-9 * span, step)]


def _frame(width: int, height: int, box: tuple[int, int, int, int], xr, yr, xlabel: str, ylabel: str,
           xticks=None, yticks=None) -> tuple[str, callable, callable]:
    """Axes of a plot: the axis lines, ticks with labels (``text.tick``) and axis titles (``text.axis-label``).

    ``box`` is ``(left, right, top, bottom)`` margins; ``xr``, ``yr`` the data ranges. Returns the
    SVG parts and the maps from data to pixel coordinates.
    """
    left, right, top, bottom = box
    (x0, x1), (y0, y1) = xr, yr
    x1 = x1 if x1 > x0 else x0 + 1.0
    y1 = y1 if y1 > y0 else y0 + 1.0

    def px(v):
        return left + (np.asarray(v, dtype=float) - x0) / (x1 - x0) * (width - left - right)

    def py(v):
        return height - bottom - (np.asarray(v, dtype=float) - y0) / (y1 - y0) * (height - top - bottom)

    yb = height - bottom
    parts = [f"<line class='axis' x1='{left}' x2='{width - right}' y1='{yb}' y2='{yb}' stroke='#888'/>",
             f"<line class='axis' x1='{left}' x2='{left}' y1='{top}' y2='{yb}' stroke='#888'/>"]
    for v in (_ticks(x0, x1) if xticks is None else xticks):
        x = float(px(v))
        parts.append(f"<line x1='{x:.1f}' x2='{x:.1f}' y1='{yb}' y2='{yb + 3}' stroke='#888'/>"
                     f"<text class='tick' x='{x:.1f}' y='{yb + 12}' text-anchor='middle'>{_num(v, '.3g')}</text>")
    for v in (_ticks(y0, y1) if yticks is None else yticks):
        y = float(py(v))
        parts.append(f"<line x1='{left - 3}' x2='{width - right}' y1='{y:.1f}' y2='{y:.1f}' stroke='#eee'/>"
                     f"<text class='tick' x='{left - 4}' y='{y + 3:.1f}' text-anchor='end'>{_num(v, '.3g')}</text>")
    parts.append(f"<text class='axis-label' x='{(left + width - right) / 2:.0f}' y='{height - 3}' "
                 f"text-anchor='middle'>{html.escape(xlabel)}</text>"
                 f"<text class='axis-label' transform='translate(10,{(top + yb) / 2:.0f}) rotate(-90)' "
                 f"text-anchor='middle'>{html.escape(ylabel)}</text>")
    return "".join(parts), px, py


def _series_svg(t: np.ndarray, ys: list[np.ndarray], plot_id: str, ylabel: str, width: int = 380,
                height: int = 150, colors=("#555", "#1f5fbf")) -> str:
    """Polylines (one ``polyline.series`` per array in ``ys``) over ``t`` [s] on labelled axes, <= 1500 points."""
    step = max(1, len(t) // 1500)
    t = t[::step]
    lo = min(float(np.min(y[::step])) for y in ys)
    hi = max(float(np.max(y[::step])) for y in ys)
    axes, px, py = _frame(width, height, (52, 8, 6, 30), (float(t[0]), float(t[-1])), (lo, hi), "time [s]", ylabel)
    lines = []
    for k, y in enumerate(ys):
        pts = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(px(t), py(y[::step])))
        lines.append(f"<polyline class='series' points='{pts}' fill='none' stroke='{colors[k % 2]}' stroke-width='1'/>")
    return f"<svg class='plot' id='{plot_id}' width='{width}' height='{height}'>{axes}{''.join(lines)}</svg>"


def _histogram(e: np.ndarray, unit: str, width: int = 170, height: int = 150) -> str:
    """The residuals' histogram (30 bins) with a labelled residual axis [unit] and a count axis."""
    counts, edges = np.histogram(e, bins=30)
    top = max(int(counts.max()), 1)
    axes, px, py = _frame(width, height, (34, 6, 6, 30), (float(edges[0]), float(edges[-1])), (0.0, float(top)),
                          f"residual [{unit}]", "count", xticks=_ticks(float(edges[0]), float(edges[-1]), 3),
                          yticks=[0, top])
    x, y = px(edges), py(counts)
    bars = "".join(f"<rect x='{x[k]:.1f}' y='{y[k]:.1f}' width='{max(x[k + 1] - x[k] - 1, 0.5):.1f}' "
                   f"height='{float(py(0)) - y[k]:.1f}' fill='#888'/>" for k in range(len(counts)))
    return f"<svg class='hist' width='{width}' height='{height}'>{axes}{bars}</svg>"


def _spectrum_svg(spec: dict, joints: list[str], unit: str, width: int = 640, height: int = 270) -> str:
    """Amplitude spectra on log-log axes: one ``polyline.spectrum`` per joint, ``line.cutoff``."""
    f, a = np.asarray(spec["f"], dtype=float), np.asarray(spec["amplitude"], dtype=float)
    keep = f > 0
    f, a = f[keep], a[keep]
    top = float(np.max(a)) if a.size and np.max(a) > 0 else 1.0
    a = np.clip(a, top * 1e-7, None)
    (x0, x1), (y0, y1) = np.log10([f.min(), f.max()]), (np.log10(top) - 7.2, np.log10(top) + 0.2)
    left, bottom = 52, 30

    def x(v):
        return left + (np.log10(v) - x0) / ((x1 - x0) or 1.0) * (width - left - 10)

    def y(v):
        return height - bottom - (np.log10(v) - y0) / (y1 - y0) * (height - bottom - 5)

    grid = "".join(f"<line x1='{x(10.0**e):.1f}' x2='{x(10.0**e):.1f}' y1='0' y2='{height - bottom}' stroke='#eee'/>"
                   f"<text class='tick' x='{x(10.0**e) - 10:.1f}' y='{height - bottom + 12}'>{10.0**e:g}</text>"
                   for e in _decade_ticks(x0, x1))
    grid += "".join(f"<text class='tick' x='{left - 4}' y='{y(10.0**e) + 3:.1f}' text-anchor='end'>1e{e}</text>"
                    for e in _decade_ticks(y0, y1))
    grid += (f"<text class='axis-label' x='{(left + width) / 2:.0f}' y='{height - 3}' text-anchor='middle'>"
             f"frequency [Hz]</text><text class='axis-label' transform='translate(10,{(height - bottom) / 2:.0f}) "
             f"rotate(-90)' text-anchor='middle'>amplitude [{html.escape(unit)}]</text>")
    lines = "".join(f"<polyline class='spectrum' data-joint='{html.escape(name)}' fill='none' stroke-width='1' "
                    f"stroke='{PALETTE[k % len(PALETTE)]}' points='"
                    + " ".join(f"{x(fv):.1f},{y(av):.1f}" for fv, av in zip(f, a[:, k])) + "'/>"
                    for k, name in enumerate(joints))
    cut = spec.get("cutoff")
    if cut and f.min() <= cut <= f.max():
        lines += (f"<line class='cutoff' x1='{x(cut):.1f}' x2='{x(cut):.1f}' y1='0' y2='{height - bottom}' "
                  f"stroke='#c33' stroke-dasharray='4'/>")
    return f"<svg id='spectrum' width='{width}' height='{height}'>{grid}{lines}</svg>"


def joint_units(ident) -> dict[str, dict[str, str]]:
    """Units of each measured joint's quantities in an identification.

    Parameters
    ----------
    ident : Identification
        The identification.

    Returns
    -------
    dict
        ``joint -> {"force", "position", "Ia", "Fv", "Fc", "Fo"}``: ``N m``, ``rad``, ``kg m^2``,
        ``N m s/rad``, ``N m``, ``N m`` for a revolute joint; ``N``, ``m``, ``kg``, ``N s/m``, ``N``,
        ``N`` for a prismatic one.
    """
    r = ident.model.robot
    out = {}
    for i, name in enumerate(r.joint_names):
        if r.jtype[i] == "P":
            out[name] = {"force": "N", "position": "m", "Ia": "kg", "Fv": "N s/m", "Fc": "N", "Fo": "N"}
        else:
            out[name] = {"force": "N m", "position": "rad", "Ia": "kg m^2", "Fv": "N m s/rad", "Fc": "N m",
                         "Fo": "N m"}
    return out


def _one(units: list[str]) -> str:
    """One unit, or the distinct ones joined (``N m or N``)."""
    return " or ".join(dict.fromkeys(units)) or "-"


def _spectrum_section(ident) -> str:
    s = (ident.series or {}).get("train") or {}
    spec = s.get("spectrum")
    if not spec:
        return ""
    units = joint_units(ident)
    legend = "".join(f"<span style='color:{PALETTE[k % len(PALETTE)]}'>&#9644; {html.escape(name)}</span>"
                     for k, name in enumerate(s["joints"]))
    cut = _num(spec.get("cutoff"), ".3g", "none")
    return (f"<h2>Excitation spectrum</h2><p>Amplitude spectrum of the training positions per joint "
            f"({html.escape(spec.get('of', 'q'))}, log scales, largest amplitude per band); dashed red: the "
            f"low-pass cutoff {cut} Hz. Content above the cutoff is removed before the fit.</p>"
            f"{_spectrum_svg(spec, list(s['joints']), _one([units[j]['position'] for j in s['joints']]))}"
            f"<p class='legend'>{legend}</p>")


def _torque_blocks(ident) -> str:
    units = joint_units(ident)
    blocks = []
    for part in ("train", "validation"):
        s = (ident.series or {}).get(part)
        if not s:
            continue
        for k, joint in enumerate(s["joints"]):
            e = s["tau"][:, k] - s["tau_hat"][:, k]
            unit = s.get("unit") or units[joint]["force"]  # a fit from motor currents: the currents [A]
            quantity = {"N": "force", "A": "current"}.get(unit, "torque")
            blocks.append(f"<div class='joint' data-part='{part}' data-joint='{html.escape(joint)}'><b>{part}: "
                          f"{html.escape(joint)}</b> (as plotted, both low-passed and decimated: RMS "
                          f"{_num(np.sqrt(np.mean(e**2)), '.4g')} {unit}; against the raw {quantity}s: the table)<br>"
                          + _series_svg(s["t"], [s["tau"][:, k], s["tau_hat"][:, k]], f"{part}-{k}",
                                        f"{quantity} [{unit}]") +
                          f"{_histogram(e, unit)}</div>")
    return "".join(blocks)


def _parameter_unit(name: str, convention: str) -> str:
    """SI unit of a (regrouped) base parameter from its name's suffix (``link2.XXR`` -> ``kg m^2``)."""
    from ..model import inertia

    names = list(inertia.NAMES.get(convention, ()))
    suffix = name.rsplit(".", 1)[-1]
    for stem in (suffix, suffix[:-1] if suffix.endswith("R") else None):
        if stem in names:
            return {0: "kg", 1: "kg m", 2: "kg m^2"}[int(inertia.LENGTH_POWER[convention][names.index(stem)])]
    return "SI"


def _pct_cell(b: dict) -> str:
    """``%sigma``, or ``n/a`` with the reason when it is not a number."""
    p = b["pct_sigma"]
    if np.isfinite(p):
        return f"<td>{_num(p, '.3g')}</td>"
    why = "the value is 0" if b["value"] == 0 else "the standard deviation is not finite (a direction not excited)"
    return f"<td class='na' title='{html.escape(why)}'>n/a</td>"


def _values_table(j: dict) -> str:
    """Base parameters: name, value, unit, std, %sigma (and a bar), expression."""
    pct = [b["pct_sigma"] for b in j["base_parameters"]]
    top = max([p for p in pct if np.isfinite(p)] + [1.0])
    rows = []
    for b in j["base_parameters"]:
        width = min(200.0, 200 * b["pct_sigma"] / top) if np.isfinite(b["pct_sigma"]) else 0.0
        rows.append(f"<tr><td>{html.escape(b['name'])}</td><td>{_num(b['value'])}</td>"
                    f"<td class='unit'>{_parameter_unit(b['name'], j['convention'])}</td>"
                    f"<td>{_num(b['std'], '.3g', 'n/a')}</td>"
                    f"{_pct_cell(b)}<td><svg width='200' height='10'><rect class='pct' width='{width:.1f}' "
                    f"height='10' fill='#1f5fbf'/></svg></td><td class='expr'>{html.escape(b['expression'])}</td></tr>")
    return (f"<h2>Base parameters ({html.escape(j['convention'])} convention, SI units)</h2><table id='values'>"
            f"<tr><th>name</th><th>value</th><th>unit</th><th>std</th><th>%sigma</th><th>%sigma (bar)</th>"
            f"<th>expression</th></tr>{''.join(rows)}</table>")


#: the drive terms of the reports: kind -> description
DRIVE_TERMS = {"Ia": "rotor inertia", "Fv": "viscous friction", "Fc": "Coulomb friction", "Fo": "torque offset",
               "Iam": "coupled rotor inertia", "Fvm": "coupled viscous friction", "Fcm": "coupled Coulomb friction"}


def _drive_row(ident, owner: str, kind: str, value, unit: str, extra: str = "") -> str:
    """One drive parameter's row: value, std, %sigma, unit, or where it was regrouped."""
    est = ident.fit.estimate
    pos = {name: k for k, name in enumerate(ident.model.names)}
    k = pos.get(f"{kind}_{owner}")
    attrs = f"class='drive' data-owner='{html.escape(owner)}' data-kind='{kind}'"
    head = f"<td>{html.escape(owner)}</td>{extra}<td>{kind} ({DRIVE_TERMS[kind]})</td>"
    if isinstance(value, str):  # regrouped into a base parameter
        return (f"<tr {attrs}>{head}<td>-</td><td>-</td><td>-</td><td class='unit'>{unit}</td>"
                f"<td>{html.escape(value)} (its value includes this term)</td></tr>")
    std = est.std[k] if k is not None else None
    pct = 100 * std / abs(value) if std is not None and value else None
    return (f"<tr {attrs}>{head}<td>{_num(value)}</td><td>{_num(std, '.3g', 'n/a')}</td>"
            f"<td>{_num(pct, '.3g', 'n/a')}</td><td class='unit'>{unit}</td><td></td></tr>")


def _drives_table(ident) -> str:
    """Drive terms per joint and coupled motor (those modelled): value, std, %sigma, unit."""
    units = joint_units(ident)
    couplings = ident.couplings()
    pad = "<td>-</td>" if couplings else ""
    rows = [_drive_row(ident, d["joint"], kind, d[kind], units[d["joint"]][kind], pad)
            for d in ident.drives() for kind in ("Ia", "Fv", "Fc", "Fo") if d[kind] is not None]
    coupled = {"Iam": "kg m^2", "Fvm": "N m s/rad", "Fcm": "N m"}
    for c in couplings:
        joints = ", ".join(f"{w:g} {jn}" for jn, w in c["joints"].items())
        rows += [_drive_row(ident, c["name"], kind, c[kind], coupled[kind], f"<td>{html.escape(joints)}</td>")
                 for kind in ("Iam", "Fvm", "Fcm") if c[kind] is not None]
    if not rows:
        return ("<h2>Drive terms</h2><p id='drives'>None modelled (<code>--friction none</code>, no "
                "<code>--rotor</code>).</p>")
    return ("<h2>Drive terms</h2><table id='drives'><tr><th>joint or motor</th>"
            + ("<th>joints</th>" if couplings else "")
            + "<th>term</th><th>value</th><th>std</th><th>%sigma</th><th>unit</th><th>note</th></tr>"
            + "".join(rows) + "</table>")


def _rms_table(ident, j: dict) -> str:
    """Residual RMS per joint, training and validation, with units (a fit from motor currents: of its currents)."""
    units = {n: u["force"] for n, u in joint_units(ident).items()}
    if ident.currents is not None:
        units = dict.fromkeys(ident.currents.motors, "A")
    val = j["validation"]
    rows = "".join(f"<tr><td>{html.escape(name)}</td><td>{_num(v, '.4g')}</td>"
                   f"<td>{_num(val['rms'].get(name), '.4g') if val else '-'}</td><td>{units[name]}</td></tr>"
                   for name, v in j["train"]["rms"].items())
    note = "" if val else " (no validation: <code>--holdout SECONDS</code> or <code>--validate FILE</code>)"
    what = "currents" if ident.currents is not None else "torques"
    how = (f"predicted minus raw measured {what} at every sample" if "samples" in j["train"] else
           "train: the fit's own rows (filtered, decimated); validation: against the raw torques at every sample")
    return (f"<h2>Residual RMS per joint{note}</h2><p>{how}</p><table id='rms'><tr><th>joint</th><th>train RMS</th>"
            f"<th>validation RMS</th><th>unit</th></tr>{rows}</table>")


def _physical_table(ident, j: dict) -> str:
    if j["physical"] is None:
        return ""
    phys = j["physical"]
    rows = "".join(f"<tr><td>{html.escape(b)}</td><td>{_num(m, '.4g')}</td><td>{_num(e, '.3g')}</td></tr>"
                   for b, m, e in zip(phys["masses"], phys["masses"].values(), ident.fit.physical.min_eigenvalues))
    return (f"<h2>Physical consistency: feasible {j['physical']['feasible']}</h2><table id='physical'>"
            f"<tr><th>body</th><th>mass [kg]</th><th>smallest eigenvalue of N_i [kg m^2]</th></tr>{rows}</table>")


def identification_html(ident) -> str:
    """The identification report (module doc) as one self-contained HTML page.

    Parameters
    ----------
    ident : Identification
        The result of :func:`baseparams.ident.identify`.

    Returns
    -------
    str
        The page: torques and residuals on labelled axes (time [s], torque [N m] or force [N]),
        the excitation spectrum (frequency [Hz]), tables with column headers of the base
        parameters (value, unit, std, %sigma, expression), the drive terms (rotor inertia,
        friction, offsets, coupled motors: value, std, %sigma, unit), the residual RMS per joint
        and the physical check, then how it was computed (the standard deviations' covariance,
        the default estimate's choice and every note of the run); a missing number reads ``-`` or
        ``n/a`` (with the reason), never ``nan``.
    """
    j = ident.to_json()
    val = j["validation"]
    unit = "A" if ident.currents is not None else _one([u["force"] for u in joint_units(ident).values()])
    what = "currents" if ident.currents is not None else "torques"
    body = (f"<h1>{html.escape(j['model'])}: identification ({html.escape(j.get('estimator', j['method']))})</h1>"
            f"<p>{j['n_samples']['used']} samples used of {j['n_samples']['read']}; condition number "
            f"{_num(j['condition_number'], '.4g')}; train RMS {_num(j['train']['rms_total'], '.4g')} {unit}"
            + (f"; validation RMS {_num(val['rms_total'], '.4g')} {unit}" if val else "") + "</p>"
            f"<h2>Measured (grey) and predicted (blue) {what}, residual histograms</h2>"
            f"<div id='torques'>{_torque_blocks(ident)}</div>{_spectrum_section(ident)}{_gains_section(j)}"
            f"{_values_table(j)}{_drives_table(ident)}{_rms_table(ident, j)}{_physical_table(ident, j)}"
            f"{_notes_section(j)}")
    return _page(f"{j['model']}: identification", body, _DONE)


def _gains_section(j: dict) -> str:
    """A fit from motor currents: each motor's gain, its std or why it has none, the anchor, the joint-side RMS."""
    c = j.get("currents")
    if c is None:
        return ""
    anchored = [] if c["anchor"] == "model file" else [a.split("=")[0].strip() for a in c["anchor"].split(",")]

    def how(m):
        return ("anchor" if m in anchored else "not determined by the currents" if m in c["undetermined"] else
                _num(c["std"][m], ".3g"))

    rows = "".join(f"<tr><td>{html.escape(m)}</td><td>{_num(c['gains'][m], '.6g')}</td><td>{how(m)}</td></tr>"
                   for m in c["motors"])
    torque = [f"{label} {_num(part['joint_torque']['rms_total'], '.4g')} {part['joint_torque'].get('unit', '')}"
              for label, part in (("train", j["train"]), ("validation", j["validation"]))
              if part and part.get("joint_torque")]
    extra = (f"<p>Joint-side torque RMS against the log's joint torques (rigid body; no motor-side friction or "
             f"rotor inertia): {html.escape('; '.join(torque))}</p>" if torque else "")
    return (f"<h2>Motor gains [N m/A at the joint side]</h2><p>{html.escape(c.get('scale_note') or c['anchor'])}</p>"
            f"<table id='gains'><tr><th>motor</th><th>gain</th><th>std</th></tr>{rows}</table>{extra}")


def _notes_section(j: dict) -> str:
    """How the estimate and its standard deviations were obtained, and every note of the run."""
    items = [f"standard deviations: {j['covariance']}", *j.get("notes", ())]
    return "<h2>How it was computed</h2><ul>" + "".join(f"<li>{html.escape(str(n))}</li>" for n in items) + "</ul>"
