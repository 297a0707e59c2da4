"""R-C compound joints: a body on several joints is a chain of elementary joints without mass between them.

A compound joint C (an MJCF body with several ``joint`` elements, a URDF ``planar`` joint) moves
its body by ``g = g_parent exp(S_1 q_1) ... exp(S_k q_k)``: the same motion as a chain of ``k``
elementary joints (R for a rotation screw, P for a translation) whose ``k - 1`` intermediate
links carry no mass. The regressor of the robot is the chain's regressor restricted to the real
bodies' columns (massless links contribute nothing), so

    null(W) = { x : (x, 0) in null(W_chain) },

the chain's nullspace intersected with "nothing on the intermediate links"
(``docs/extended-rules.md``, "R-C"). The chain has one joint per body, where the principles and
the other rules apply as they are written (axes through their frames' origins, transfers across
each elementary joint); so its DRNG columns, combined to vanish on the intermediate links, give
the compound robot's directions that no rule sees across the compound joint as a whole (a planar
root ``slide x, slide z, hinge y``: the out-of-plane and mass transfers through the slides).

The combination is exact linear algebra on the chain's columns (no sampling): per connected set
of intermediate links, the nullspace of the columns' blocks on them (singular values decided by
a gap, as R-M's; an ambiguous one skips the set: fewer directions, never a wrong one), then only
the directions new to the columns found before, on as few bodies as possible (one, two, three,
then all the set touches).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..enums import Source
from ..model import inertia as I
from ..model.robot import Robot
from ..model.scale import decision_scale
from ..pga import inverse_transform
from .columns import Columns, on_bodies, to_dense
from .coupled import NEW, gap_split, null_rows, prior_rows, sparse_solutions


def _elementary(s: np.ndarray, tol: float) -> tuple[str, np.ndarray, np.ndarray]:
    """``(type, unit axis, a point of it)`` of a joint-frame screw ``s (6,)``.

    A rotation or a translation: the robot checks that a compound twist is one of them.
    """
    w, v = s[:3], s[3:]
    nw = np.linalg.norm(w)
    if nw <= tol:
        return "P", v / np.linalg.norm(v), np.zeros(3)
    return "R", w / nw, np.cross(w, v) / (nw * nw)


def expand_compound(robot: Robot, tol: float = 1e-9) -> tuple[Robot, np.ndarray, np.ndarray] | None:
    """The robot with each compound joint replaced by a chain of elementary joints and massless links.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    tol : float, default 1e-9
        Zero-norm threshold of a screw's parts.

    Returns
    -------
    chain : Robot
        ``n + v`` bodies: before each expanded body, one massless link per screw but the last,
        joined by that screw (R or P, frame on the axis, the body's orientation); the body itself
        on the last screw, its frame moved onto that screw's axis (its inertia re-expressed
        there). The same coordinates in the same order, loops and couplings re-indexed.
    index : ndarray of int, shape ``(n,)``
        Each body's index in ``chain``.
    virtual : ndarray of int, shape ``(v,)``
        The massless links' indices in ``chain``.

    None when the robot has no compound joint.
    """
    todo = {i: [_elementary(s, tol) for s in robot.axes[i]] for i, t in enumerate(robot.jtype) if t == "C"}
    if not todo:
        return None
    names, jnames, jtype, parent, m0, axes, nb = [], [], [], [], [], [], []
    index, virtual = np.zeros(robot.n, dtype=int), []

    def add(name, jname, t, p, frame, axis, n_body):
        names.append(name), jnames.append(jname), jtype.append(t), parent.append(p)
        m0.append(frame), axes.append(axis), nb.append(n_body)
        return len(names) - 1

    for i in range(robot.n):
        p = -1 if robot.parent[i] < 0 else int(index[robot.parent[i]])
        if i not in todo:
            index[i] = add(robot.names[i], robot.joint_names[i], robot.jtype[i], p, robot.M0[i], robot.axes[i],
                           robot.N_body[i])
            continue
        for k, (t, axis, point) in enumerate(todo[i]):
            shift = np.eye(4)
            shift[:3, 3] = point
            frame = robot.M0[i] @ shift
            if k < len(todo[i]) - 1:
                p = add(f"{robot.names[i]}#{k}", f"{robot.joint_names[i]}#{k}", t, p, frame, axis[None],
                        np.zeros((4, 4)))
                virtual.append(p)
            else:
                index[i] = add(robot.names[i], robot.joint_names[i], t, p, frame, axis[None],
                               I.transform(robot.N_body[i], inverse_transform(shift)))
    loops = tuple(replace(lj, parent=-1 if lj.parent < 0 else int(index[lj.parent]), child=int(index[lj.child]))
                  for lj in robot.loops)
    chain = replace(robot, names=tuple(names), joint_names=tuple(jnames), jtype=tuple(jtype),
                    parent=np.array(parent, dtype=int), M0=np.array(m0), axes=tuple(axes), N_body=np.array(nb),
                    loops=loops, armature=None)
    return chain, index, np.array(virtual, dtype=int)


def _touched(cols: Columns) -> list[np.ndarray]:
    """The bodies each column has a block on."""
    out = []
    for k in range(len(cols)):
        b = [cols.child[k], cols.parent[k], cols.extra[k]]
        if cols.more[k] is not None:
            b += list(cols.more[k][0])
        out.append(np.array([x for x in b if x >= 0], dtype=int))
    return out


def _components(touch: list[np.ndarray], marked: np.ndarray) -> list[np.ndarray]:
    """Columns grouped by connected sets of ``marked`` bodies (union-find); columns touching none are left out."""
    root = {int(b): int(b) for b in marked}

    def find(b):
        while root[b] != b:
            root[b] = root[root[b]]
            b = root[b]
        return b

    for bodies in touch:
        hit = [int(b) for b in bodies if int(b) in root]
        for b in hit[1:]:
            root[find(b)] = find(hit[0])
    groups: dict[int, list[int]] = {}
    for k, bodies in enumerate(touch):
        hit = [int(b) for b in bodies if int(b) in root]
        if hit:
            groups.setdefault(find(hit[0]), []).append(k)
    return [np.array(g) for g in groups.values()]


def _new_directions(cols: Columns, prior: Columns | None, unit: np.ndarray) -> list[Columns]:
    """Of ``cols``, the directions new to ``prior`` and to each other, every block kept.

    Grouped by the bodies they touch (:func:`_touched`: ``child``, ``parent``, ``extra`` and the
    ``more`` blocks of R-M's widest columns), fewest first; each group's columns (for
    ``pi / unit``) are reduced against the span of what is known on those bodies, and what is new
    (singular values above :data:`~.coupled.NEW`) emitted on the same bodies.
    """
    known = prior if prior is not None else Columns.empty()
    out = []
    sets = [tuple(sorted(int(b) for b in set(t.tolist()))) for t in _touched(cols)]
    for who in sorted(set(sets), key=lambda w: (len(w), w)):
        sel = cols.subset(np.array([w == who for w in sets]))
        x = to_dense(sel, max(who) + 1).reshape(max(who) + 1, 10, -1)[list(who)] / unit[None, :, None]
        x = (x / np.maximum(np.linalg.norm(x, axis=(0, 1)), 1e-300)).reshape(10 * len(who), -1).T
        seed = prior_rows(known, list(who), unit)
        u_, s, _ = np.linalg.svd(x - (x @ seed.T) @ seed, full_matrices=False)
        k = int(np.sum(s > NEW))
        if k:
            y = (u_[:, :k].T @ x).reshape(k, len(who), 10) * unit
            new = on_bodies(list(who), y.reshape(k, -1), Source.R_C, f"compound joints as chains: {sel.label[0]}")
            out.append(new)
            known = Columns.concat([known, new])
    return out


def compound_columns(robot: Robot, expanded: tuple[Robot, np.ndarray, np.ndarray] | None, chain_columns: Columns,
                     tol: float = 1e-9, prior: Columns | None = None) -> Columns:
    """R-C: the directions the compound joints' elementary chains give.

    The chain's columns without a block on a massless link are columns of the robot as they are
    (emitted when they touch a body at or below a compound joint: elsewhere the chain is the
    robot); the others are combined to vanish on the massless links, and only the directions
    new to ``prior`` and to those are emitted, on as few bodies as found.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    expanded : tuple or None
        :func:`expand_compound` of ``robot`` (None: no compound joint, nothing to add).
    chain_columns : Columns
        DRNG's columns on the chain (every row measured: valid for any measured subset).
    tol : float, default 1e-9
        Relative singular-value threshold of the combinations.
    prior : Columns, optional
        Columns found before: only new directions are emitted.

    Returns
    -------
    Columns
        Columns in the ``paper`` convention (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ
        MX MY MZ M`` of each body, world frame at q = 0), provenance ``R-C compound joints``.
    """
    if expanded is None:
        return Columns.empty()
    chain, index, virtual = expanded
    real = np.full(chain.n, -1)
    real[index] = np.arange(robot.n)
    below = np.zeros(chain.n, dtype=bool)  # at or below a compound joint
    for b in range(chain.n):
        p = int(chain.parent[b])
        below[b] = b in set(virtual) or (p >= 0 and below[p])
    cols = chain_columns
    touch = _touched(cols)
    direct = np.array([not np.any(real[t] < 0) and bool(np.any(below[t])) for t in touch], dtype=bool)
    unit = decision_scale(robot, "paper")[:10]
    lifted = cols.subset(direct).reindexed(real, np.arange(len(robot.loops)), robot.n)
    parts = _new_directions(replace(lifted, principle=np.full(len(lifted), Source.R_C)), prior, unit)
    known = Columns.concat([prior or Columns.empty(), *parts])
    for comp in _components(touch, virtual):
        sel = cols.subset(comp)
        dense = to_dense(sel, chain.n).reshape(chain.n, 10, -1) / unit[None, :, None]
        dense /= np.maximum(np.linalg.norm(dense, axis=(0, 1)), 1e-300)
        bodies = np.unique(np.concatenate([touch[k] for k in comp]))
        gone, kept = bodies[real[bodies] < 0], bodies[real[bodies] >= 0]
        combos = null_rows(dense[gone].reshape(-1, len(comp)), tol, 1.0)
        if combos is None or not len(combos) or not len(kept):
            continue
        y = dense[kept].reshape(-1, len(comp)) @ combos.T  # (10 u, d): the combinations on the real bodies
        u_, s, _ = np.linalg.svd(y, full_matrices=True)
        s = np.r_[s, np.zeros(len(y) - len(s))]
        zero, clear = gap_split(s[None], tol, 1.0)  # unit columns, orthonormal combinations: the scale is 1
        rank = int(np.sum(~zero))
        if not (zero | clear).all() or not rank:
            continue  # nothing, or a rank not decided by a gap: skipped (fewer directions, never a wrong one)
        who = [int(real[b]) for b in kept]
        seed = prior_rows(known, who, unit)
        # rows whose solutions are span(y) + span(seed): the search then adds to seed what y brings
        both, sb, _ = np.linalg.svd(np.hstack([u_[:, :rank], seed.T]), full_matrices=True)
        span = int(np.sum(sb > NEW))
        r = both[:, span:].T if span < len(y) else np.zeros((1, len(y)))
        label = f"compound joints of {', '.join(robot.names[w] for w in who)} as chains"
        for sub, x in sparse_solutions(r, len(who), tol, seed):
            parts.append(on_bodies([who[b] for b in sub], x * np.tile(unit, len(sub)), Source.R_C, label))
    return Columns.concat(parts)
