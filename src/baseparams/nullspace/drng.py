"""DRNG: the regressor nullspace from the three principles and the extended rules, ranked.

:mod:`.principles` gives the paper's columns (with its slips fixed), :mod:`~baseparams.nullspace.rules` the rules
that close its gaps, :func:`unmeasured_columns` what the measured rows add; :mod:`.rank`
decides their exact rank. :func:`drng` runs them all and returns a :class:`~.result.DRNGResult`.
"""

from __future__ import annotations

import time

import numpy as np

from ..enums import Source
from ..model.inertia import PAPER_NAMES
from ..model.inertia import hat as hat10
from ..model.robot import Robot
from ..numerics import measured_joints, row_mask, rows_spec
from .columns import EXTENDED, PAPER, PRINCIPLES, UNMEASURED, Columns, sym_params
from .principles import drng_columns
from .result import DRNGResult, scaled_rank
from .rules import rule_columns

__all__ = ["DRNGResult", "drng", "unmeasured_columns", "PAPER", "EXTENDED", "UNMEASURED", "PRINCIPLES"]


def unseen_bodies(robot: Robot, rows) -> np.ndarray:
    """Bodies that no measured row sees: every joint on the path to the root unmeasured.

    Joint ``j``'s generalized forces are its line against the summed wrenches of the bodies it
    carries (its subtree), and a floating root's base wrench is the sum of every body's; so
    body ``i`` enters only the rows of the joints on its path to the root, its own included.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    rows : str or sequence of str
        The measured rows (:func:`baseparams.numerics.row_mask`).

    Returns
    -------
    ndarray of bool, shape ``(n,)``
        True for a body none of whose path joints (nor, floating, the base wrench) is measured.
    """
    _, measured = measured_joints(robot, rows)
    seen = np.zeros(robot.n, dtype=bool)
    for i in range(robot.n):  # parents come first
        p = int(robot.parent[i])
        seen[i] = measured[i] or (p >= 0 and seen[p])
    return ~seen


def unmeasured_columns(robot: Robot, rows, tol: float = 1e-9) -> Columns:
    """Columns that the measured rows add.

    Rule U (:func:`unseen_bodies`): a body none of whose path joints is measured enters no
    measured row, so each of its ten parameters is a nullspace direction on its own (with joint
    torques alone, ``rows="joints"``, that is a floating root: ``unmeasured root``; with passive
    joints, any body above the first measured joint of its path: ``unmeasured body``). Rules
    P1-P7 (:func:`passive_columns`): what an unmeasured joint loses besides. With the base wrench measured
    nothing is added: it sees every direction the full dynamics see (Ayusawa et al. 2014, the
    paper's remark; certification checks it).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    rows : str or sequence of str
        The measured generalized forces (:func:`baseparams.numerics.row_mask`).
    tol : float, default 1e-9
        Geometric tolerance of the passive-joint rules (:func:`passive_columns`).

    Returns
    -------
    Columns
        Ten single-body unit columns per unseen body, labelled with the parameter names and
        marked ``unmeasured root`` (a floating root) or ``unmeasured body``, then the passive
        joints' columns; none when every row is measured.

    Raises
    ------
    BaseparamsError
        Unknown ``rows`` (checked unless it is ``"all"``).
    """
    if isinstance(rows, str) and rows == "all":
        return Columns.empty()
    if row_mask(robot, rows).all():
        return Columns.empty()
    unseen = np.flatnonzero(unseen_bodies(robot, rows))
    parts = []
    if len(unseen):
        k = 10 * len(unseen)
        child = np.repeat(unseen, 10)
        z = np.zeros(k, dtype=int)
        labels = np.array(list(PAPER_NAMES) * len(unseen), dtype=object)
        src = np.array([Source.UNMEASURED if robot.jtype[i] == "F" else Source.UNSEEN for i in child])
        parts.append(Columns(np.tile(np.eye(10), (len(unseen), 1)), child, z - 1, src, child.copy(), labels,
                             hp=np.zeros((k, 10))))
    extra = passive_columns(robot, rows, tol)
    if len(extra):
        parts.append(extra)
    return Columns.concat(parts) if parts else Columns.empty()


def _slides(robot: Robot) -> np.ndarray:
    """Per body, whether its joint only translates: prismatic, or compound of slides alone."""
    sc = robot.screws
    out = np.zeros(robot.n, dtype=bool)
    for i in range(robot.n):
        qi, nd = robot.q_index[i], robot.ndofs[i]
        out[i] = robot.jtype[i] in ("P", "C") and nd > 0 and not np.any(sc[qi:qi + nd, :3])
    return out


def force_only_bodies(robot: Robot, rows) -> np.ndarray:
    """Bodies seen only by pure-force rows: every measured joint on the path to the root prismatic.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    rows : str or sequence of str
        The measured rows (:func:`baseparams.numerics.row_mask`).

    Returns
    -------
    ndarray of bool, shape ``(n,)``
        True for a body that some measured row sees and every such row is a prismatic joint's (or
        a compound joint's made of slides alone).
    """
    _, measured = measured_joints(robot, rows)
    slides = _slides(robot)
    seen = np.zeros(robot.n, dtype=bool)
    moment = np.zeros(robot.n, dtype=bool)  # some measured row on the path carries a moment
    for i in range(robot.n):
        p = int(robot.parent[i])
        seen[i] = measured[i] or (p >= 0 and seen[p])
        moment[i] = (measured[i] and not slides[i]) or (p >= 0 and moment[p])
    return seen & ~moment


def passive_columns(robot: Robot, rows, tol: float = 1e-9) -> Columns:
    """Rules P1-P7: what the unmeasured joints lose besides the unseen bodies (rule U).

    Joint ``k``'s row is its line against the summed wrench of its subtree; a body's wrench is
    ``(d/dt L - c x m g, d/dt(m v_c) - m g)``. Each rule names a parameter change whose wrench no
    measured row sees, at any state (``docs/extended-rules.md``, "Measured rows"):

    * P1: a body seen only by slides' rows (every measured joint on its path prismatic, or
      compound of slides) is seen through its force alone, which holds no second moment: its six
      second moments.
    * P2: an unmeasured slide (hinge) whose parent is seen only by slides' rows: the force of a
      first moment ``h`` (no mass) is ``d^2/dt^2 (R h)``, the same on the body and its parent for
      every ``h`` (``h`` along the hinge): moved to the parent.
    * P3: a body seen only by slides' rows, whose rotation axes and measured slides all have one
      direction ``a``: a first moment normal to ``a`` stays normal to it and to the rows.
    * P4: a body turning about a fixed point ``O`` (fixed base; R, U, S joints whose axes meet at
      ``O``) seen only by vertical revolute rows through ``O`` (or without gravity): a first
      moment at ``O`` has no angular momentum about ``O``, and its gravity moment is horizontal.
    * P5: an unmeasured hinge ``a``: the inertia about ``a`` (second moments ``1 - 2 a a^T``)
      makes the couple ``d/dt(c a)``, normal to the measured hinges above when ``a`` is normal to
      them and everything above turns about them.
    * P6: an unmeasured slide ``d`` under hinges along ``d`` only: measured slides normal to
      ``d`` and measured hinges along ``d`` (moments about a line along ``d`` do not change when a
      body slides along it) do not see the slide: the whole body moved to the parent.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).
    rows : str or sequence of str
        The measured rows (:func:`baseparams.numerics.row_mask`).
    tol : float, default 1e-9
        Geometric tolerance (parallel and normal directions, meeting axes).

    Returns
    -------
    Columns
        The columns, marked ``passive joint``, each labelled with its rule; ``joint`` is the
        body's own (P1, P3, P4) or the unmeasured joint's (P2, P5, P6, P7).
    """
    force = force_only_bodies(robot, rows)
    _, measured = measured_joints(robot, rows)
    slides, pivots = _slides(robot), _pivot_points(robot, tol)
    out: list[tuple[int, int, np.ndarray, str]] = []  # (body, parent or -1, block, label)
    for j in range(robot.n):
        out += _body_rules(robot, j, force, measured, pivots[j], tol)
        if not measured[j] and robot.parent[j] >= 0:
            out += _joint_rules(robot, j, force, measured, slides, tol)
    if not out:
        return Columns.empty()
    child, par = np.array([c[0] for c in out]), np.array([c[1] for c in out])
    h = np.array([c[2] for c in out])
    hp = np.where((par >= 0)[:, None], -h, 0.0)
    return Columns(h, child, par, np.full(len(out), Source.PASSIVE), child.copy(),
                   np.array([c[3] for c in out], dtype=object), hp=hp)


def _first_moment(v: np.ndarray) -> np.ndarray:
    """A parameter block holding the first moment ``v`` alone (``MX MY MZ``)."""
    blk = np.zeros(10)
    blk[6:9] = v
    return blk


def _body_rules(robot: Robot, j: int, force: np.ndarray, measured: np.ndarray, pivot, tol: float) -> list:
    """P1, P3, P4 on body ``j`` alone: ``[(j, -1, block, label)]``."""
    out = []
    if force[j]:  # P1
        out += [(j, -1, e, f"P1 {nm} (seen by slides' rows only)") for e, nm in zip(np.eye(10)[:6], PAPER_NAMES[:6])]
        a = _level_axis(robot, j, measured, tol)
        if a is not None:  # P3: the plane normal to a
            out += [(j, -1, _first_moment(v), "P3 first moment normal to the rotation axes and measured slides")
                    for v in np.linalg.svd(a[None])[2][1:]]
    if _vertical_pivot(robot, j, measured, pivot, tol):  # P4
        out += [(j, -1, sym_params(np.r_[v, 0.0], np.r_[pivot, 1.0]),
                 f"P4 first moment {'xyz'[k]} at the fixed point {np.round(pivot, 6).tolist()}")
                for k, v in enumerate(np.eye(3))]
    return out


def _joint_rules(robot: Robot, j: int, force: np.ndarray, measured: np.ndarray, slides: np.ndarray,
                 tol: float) -> list:
    """P2, P5, P6, P7 of the unmeasured joint ``j`` (a parent ``p``): ``[(j, p or -1, block, label)]``."""
    p, jt, out = int(robot.parent[j]), robot.jtype[j], []
    sc = robot.screws[robot.q_index[j]]
    v = sc[:3] if jt == "R" else sc[3:]
    v = v / max(np.linalg.norm(v), 1e-300)
    if force[p] and slides[j]:  # P2
        out += [(j, p, _first_moment(e), f"P2 {nm} moved to the parent (unmeasured slide)")
                for e, nm in zip(np.eye(3), PAPER_NAMES[6:9])]
    elif force[p] and jt == "R":
        out.append((j, p, _first_moment(v), "P2 first moment along the unmeasured hinge moved to the parent"))
    if jt == "R" and _normal_moment_rows(robot, j, measured, tol):  # P5
        blk = np.zeros(10)
        blk[:6] = _second_moments(np.eye(3) - 2.0 * np.outer(v, v))
        out.append((j, -1, blk, "P5 inertia about the unmeasured hinge"))
    if jt == "P" and _sliding_unseen(robot, j, measured, tol):  # P6
        out += [(j, p, e, f"P6 {nm} moved to the parent (unmeasured slide)") for e, nm in zip(np.eye(10), PAPER_NAMES)]
    elif force[j] and jt in ("R", "P"):  # P7
        a = _level_axis(robot, j, measured, tol)
        if a is not None and (abs(a @ v) <= tol if jt == "P" else np.linalg.norm(np.cross(a, v)) <= tol):
            out += [(j, p, e, f"P7 {nm} moved to the parent (unmeasured joint moving normal to the force rows)")
                    for e, nm in zip(np.eye(10), PAPER_NAMES)]
    return out


def _pivot_points(robot: Robot, tol: float) -> list:
    """Per body, the fixed point ``O`` it turns about, or None (geometry only, parents first).

    Fixed base, every joint from the root to the body revolute, universal or spherical, all
    their axes through one point ``O`` (at least two of them not parallel). A body whose path
    axes have no common point passes that on to its subtree, so each body's own axes are
    checked once.
    """
    out: list = [None] * robot.n
    lines: list = [None] * robot.n  # parallel axes so far (no point decided yet), or None when dead
    for i in range(robot.n):
        p = int(robot.parent[i])
        if robot.jtype[i] not in ("R", "U", "S") or (p >= 0 and out[p] is None and lines[p] is None):
            continue
        qi = robot.q_index[i]
        sc = robot.screws[qi:qi + robot.ndofs[i]]
        nw = np.linalg.norm(sc[:, :3], axis=1)[:, None]
        w, pt = sc[:, :3] / nw, np.cross(sc[:, :3] / nw, sc[:, 3:] / nw)  # direction, a point of each axis
        if p >= 0 and out[p] is not None:
            o = out[p]
            scale = max(1.0, float(np.abs(pt).max()), float(np.abs(o).max()))
            out[i] = o if np.abs(np.cross(w, o - pt)).max() <= tol * scale else None
            continue
        if p >= 0:
            w, pt = np.vstack([lines[p][0], w]), np.vstack([lines[p][1], pt])
        if np.linalg.matrix_rank(w, tol=1e-6) < 2:
            lines[i] = (w, pt)
            continue
        proj = np.eye(3)[None] - w[:, :, None] * w[:, None, :]
        o = np.linalg.lstsq(proj.sum(0), np.einsum("kab,kb->a", proj, pt), rcond=None)[0]
        scale = max(1.0, float(np.abs(pt).max()))
        out[i] = o if np.abs(np.cross(w, o - pt)).max() <= tol * scale else None
    return out


def _vertical_pivot(robot: Robot, j: int, measured: np.ndarray, o, tol: float) -> bool:
    """Whether only vertical lines through body ``j``'s fixed point ``o`` see it (P4).

    ``o`` from :func:`_pivot_points` (None: no fixed point). Some joint on the path is measured,
    and every measured one is revolute and vertical (parallel to gravity) with vertical axes
    only above it (so it stays vertical), or gravity is zero.
    """
    if o is None:
        return False
    path = []
    i = j
    while i >= 0:
        path.append(i)
        i = int(robot.parent[i])
    if not any(measured[i] for i in path):
        return False  # unseen: rule U
    g = robot.gravity
    gn = float(np.linalg.norm(g))
    if gn == 0:
        return True
    if any(measured[i] and robot.jtype[i] != "R" for i in path):
        return False  # a measured U or S joint sees the gravity moment in every direction
    coords = [robot.q_index[i] + c for i in path for c in range(robot.ndofs[i])]
    w = robot.screws[coords][:, :3]
    vertical = np.linalg.norm(np.cross(w / np.linalg.norm(w, axis=1)[:, None], g / gn), axis=1) <= tol
    start = np.cumsum([0] + [robot.ndofs[i] for i in path])
    return not any(measured[i] and not vertical[start[m]:].all() for m, i in enumerate(path))


def _second_moments(s: np.ndarray) -> np.ndarray:
    """The ``XX XY XZ YY YZ ZZ`` entries of a symmetric ``(3, 3)`` second-moment block."""
    m = np.zeros((4, 4))
    m[:3, :3] = s
    return hat10(m)[:6]


def _normal_moment_rows(robot: Robot, j: int, measured: np.ndarray, tol: float) -> bool:
    """Whether no measured row above revolute joint ``j`` sees a couple along ``j``'s axis, at any q.

    The couple is ``d/dt(c a)``, ``a`` the axis (fixed in ``j``'s parent). A measured prismatic
    joint sees forces only. A measured revolute joint ``k`` sees ``u_k . d/dt(c a) = c' u_k . a
    + c omega . (a x u_k)`` (``omega`` the parent of ``j``'s angular velocity): both vanish when
    ``a`` is normal to ``u_k`` and every joint above ``j`` is prismatic or revolute about ``u_k``
    (then ``omega`` is along ``u_k``). Any other measured joint (U, S, C, a floating base's
    wrench) sees every couple; without a measured revolute joint above, nothing is asked.
    """
    a = robot.screws[robot.q_index[j], :3]
    a = a / np.linalg.norm(a)
    path = []
    k = int(robot.parent[j])
    while k >= 0:
        path.append(k)
        k = int(robot.parent[k])
    seen = [k for k in path if measured[k]]
    if any(robot.jtype[k] not in ("R", "P") for k in seen):
        return False
    turns = [k for k in seen if robot.jtype[k] == "R"]
    if not turns:
        return True
    u = robot.screws[robot.q_index[turns[0]], :3]
    u = u / np.linalg.norm(u)
    if abs(u @ a) > tol:
        return False
    for k in path:
        if robot.jtype[k] == "P":
            continue
        if robot.jtype[k] != "R":
            return False
        w = robot.screws[robot.q_index[k], :3]
        if np.linalg.norm(np.cross(u, w / np.linalg.norm(w))) > tol:
            return False
    return True


def _sliding_unseen(robot: Robot, j: int, measured: np.ndarray, tol: float) -> bool:
    """Whether no measured row above prismatic joint ``j`` sees its slide ``d``, at any q.

    Every revolute joint above ``j`` turns about ``d`` and no other joint turns (so ``d`` keeps
    its direction and the parent turns about it); every measured prismatic joint above slides
    normal to ``d`` (its force line does not see the slide), every measured revolute one is
    parallel to ``d`` (moments about a line along ``d`` do not change when a body slides along
    it). Any other measured joint (U, S, C, a floating base's wrench) sees the slide.
    """
    d = robot.screws[robot.q_index[j], 3:]
    d = d / np.linalg.norm(d)
    k = int(robot.parent[j])
    while k >= 0:
        jt = robot.jtype[k]
        sc = robot.screws[robot.q_index[k]]
        if jt == "R":
            if np.linalg.norm(np.cross(d, sc[:3] / np.linalg.norm(sc[:3]))) > tol:
                return False
        elif jt == "P":
            if measured[k] and abs(d @ sc[3:]) > tol * np.linalg.norm(sc[3:]):
                return False
        else:
            return False
        k = int(robot.parent[k])
    return True


def _level_axis(robot: Robot, j: int, measured: np.ndarray, tol: float) -> np.ndarray | None:
    """The one direction ``a`` of every rotation axis and every measured slide on body ``j``'s path, or None.

    Only R and P joints on the path; the axes and slides taken at q = 0 (world frame) stay
    parallel to ``a`` in every configuration, since every rotation above them is about ``a``.
    """
    screws, a = robot.screws, None
    i = j
    while i >= 0:
        jt = robot.jtype[i]
        if jt not in ("R", "P"):
            return None
        sc = screws[robot.q_index[i]]
        if jt == "R" or measured[i]:
            v = sc[:3] if jt == "R" else sc[3:]
            v = v / np.linalg.norm(v)
            if a is None:
                a = v
            elif np.linalg.norm(np.cross(a, v)) > tol:
                return None
        i = int(robot.parent[i])
    return a


def _unlocked(robot: Robot) -> tuple[Robot, np.ndarray, np.ndarray] | None:
    """The robot without the bodies its loops hold still (:func:`.rules.locked_bodies`), or None.

    Those bodies never move: the others move exactly as they would hanging from the world there
    (a body whose parent is held still hangs from the world, a loop to one closes on the world),
    so the moving bodies' directions are the smaller robot's. Returns ``(robot, body index (m,)
    in the original, loop index (l,) in the original)``; None when no body or every body is held
    still, or a coupling ties a held coordinate to a moving one.
    """
    from dataclasses import replace

    from .rules import locked_bodies

    locked = locked_bodies(robot)
    if not locked.any() or locked.all():
        return None
    keep = np.flatnonzero(~locked)
    new = -np.ones(robot.n, dtype=int)
    new[keep] = np.arange(len(keep))
    coords = np.flatnonzero(np.isin(robot.dof_body, keep))
    qnew = -np.ones(robot.dof, dtype=int)
    qnew[coords] = np.arange(len(coords))
    couplings = []
    for c in robot.couplings:
        idx = [c.succ, *(k for k, _ in c.terms())]
        if all(qnew[k] < 0 for k in idx):
            continue
        if any(qnew[k] < 0 for k in idx):
            return None
        couplings.append(replace(c, succ=int(qnew[c.succ]), pred=int(qnew[c.pred]),
                                 more=tuple((int(qnew[k]), r) for k, r in c.more)))
    loops, kept_loops = [], []
    for k, lj in enumerate(robot.loops):
        a = -1 if lj.parent < 0 else int(new[lj.parent])
        b = int(new[lj.child])
        if max(a, b) < 0:
            continue
        if a > b:  # the world (a held body) now on the successor's side: swap the two copies
            a, b, m, mc = b, a, (lj.M if lj.M_child is None else lj.M_child), lj.M
            lj = replace(lj, M=m, M_child=None if np.abs(mc - m).max() <= 1e-12 else mc,
                         axes=lj.axes[::-1].copy() if lj.type == "U" else lj.axes)
        loops.append(replace(lj, parent=a, child=b))
        kept_loops.append(k)
    independent = tuple(int(qnew[k]) for k in robot.actuated)
    sub = Robot(robot.name, tuple(robot.names[i] for i in keep), tuple(robot.joint_names[i] for i in keep),
                tuple(robot.jtype[i] for i in keep), np.array([-1 if robot.parent[i] < 0 else new[robot.parent[i]]
                                                               for i in keep]),
                robot.M0[keep], tuple(robot.axes[i] for i in keep), robot.N_body[keep], robot.gravity, tuple(loops),
                independent if (loops or couplings) else None, robot.q_box if (loops or couplings) else None,
                tuple(couplings))
    return sub, keep, np.array(kept_loops, dtype=int)


def drng(robot: Robot, tol: float = 1e-9, extended: bool = True, rows: str = "all", check: bool = True) -> DRNGResult:
    """Run DRNG (corrected) on ``robot``: columns with provenance and their exact rank.

    The paper's Algorithm "DRNG" with slips E1-E5 fixed (:func:`.principles.drng_columns`), then
    the extended rules (:func:`~baseparams.nullspace.rules.rule_columns`, then
    :func:`.coupled.parallelogram_group_columns` for parallelograms and
    :func:`.coupled.coupled_columns` for joint couplings, and :func:`.compound.compound_columns` for
    compound joints, given the columns before), then :func:`unmeasured_columns`; each rule's
    columns checked against the regressor of a few random states before the next rule uses them
    (:class:`.checks.RuleCheck`: a column not in the nullspace is left out, the rule named in the
    result's ``notes``); the rank is decided by :func:`~.result.scaled_rank`.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies, ``10 n`` parameters).
    tol : float, default 1e-9
        Geometric tolerance of the principles and rules (parallel axes, zero gravity, ...).
    extended : bool, default True
        Add the rules that close the paper's gaps (:mod:`~baseparams.nullspace.rules`: R-A, R-B, R-L1, R-L2, R-L3;
        :mod:`.coupled`: R-M; :mod:`.compound`: R-C);
        ``False`` gives the paper's three principles alone.
    rows : str or sequence of str, default "all"
        The measured generalized forces (``all``, ``joints``, ``base``, or a set of joints:
        :func:`baseparams.numerics.row_mask`; see :func:`unmeasured_columns`).
    check : bool, default True
        Check each rule's columns (:class:`.checks.RuleCheck`); ``False`` for the robots DRNG
        builds on the way (a compound joint's chain), whose columns are checked on the robot.

    Returns
    -------
    DRNGResult
        The columns ``B_null (10 n, k)`` in the ``paper`` convention (spatial pseudo-inertia
        entries ``XX XY XZ YY YZ ZZ MX MY MZ M`` of each body, world frame at q = 0) with
        provenance, their exact rank and the time taken.

    Raises
    ------
    BaseparamsError
        Unknown ``rows`` (see :func:`unmeasured_columns`).
    """
    from .checks import RuleCheck

    t0 = time.perf_counter()
    rows = rows_spec(rows)
    checker = RuleCheck(robot, rows) if check else None
    take = checker.keep if checker is not None else _as_they_are
    cols = take(drng_columns(robot, tol))
    if extended:
        cols = _extended_columns(robot, tol, cols, take)
    extra = take(unmeasured_columns(robot, rows, tol))
    if len(extra):
        cols = Columns.concat([cols, extra])
    rank = scaled_rank(cols, robot)
    return DRNGResult(robot, cols, rank, time.perf_counter() - t0, extended, str(rows),
                      tuple(checker.notes) if checker is not None else ())


def _as_they_are(cols: Columns) -> Columns:
    return cols


def _extended_columns(robot: Robot, tol: float, cols: Columns, take) -> Columns:
    """``cols`` and the extended rules' columns after them, each rule's passed through ``take`` before the next runs."""
    cols = Columns.concat([cols, take(rule_columns(robot, tol))])
    if robot.couplings or robot.loops:  # R-M (imported for robots with couplings or loops only: start-up time)
        from .coupled import coupled_columns, parallelogram_group_columns

        if robot.loops:  # R-L1 completed: parallelograms as the coupled groups they are
            cols = Columns.concat([cols, take(parallelogram_group_columns(robot, tol, prior=cols))])
        if robot.couplings:
            cols = Columns.concat([cols, take(coupled_columns(robot, tol, prior=cols))])
    if robot.loops or robot.couplings:  # bodies held still by their loops: the others on a fixed base
        sub = _unlocked(robot)
        if sub is not None:
            cols = Columns.concat([cols, take(drng(sub[0], tol, check=False).columns.reindexed(*sub[1:], robot.n))])
    if "C" in robot.jtype:  # R-C: compound joints as chains of elementary joints without intermediate mass
        from .compound import compound_columns, expand_compound

        chain = expand_compound(robot, tol)
        found = drng(chain[0], tol, check=False).columns
        cols = Columns.concat([cols, take(compound_columns(robot, chain, found, tol, prior=cols))])
    return cols
