"""R-M: the nullspace directions that linear joint couplings (``<mimic>``) add.

A coupling ``q_f = m q_l + o`` makes the bodies it drives move as functions of one coordinate.
Group the 1-dof joints driven by the same independent coordinate ``q_l`` (chains of mimics
composed); a **coupled group** is a set of bodies ``G`` whose joints all belong to that group,
hanging from one **anchor** body ``A`` (the first body up the tree whose joint does not), so that
body ``k`` of ``G`` moves by

    g_k(t) = g_A(t) h_k(q_l(t)),        h_k(q) = prod_j exp(S_j (m_j q + o_j))

(the product over the joints from ``A`` to ``k``, world screws ``S_j`` at the reference). The
extended rules' one criterion (``docs/extended-rules.md``) then reads, for changes ``dN_A`` and
``dN_k`` of their pseudo-inertias: the kinetic term

    2 T = K(V, V; dN_A) + sum_k K(xi_k, xi_k; dN_k),   xi_k = Ad(h_k^-1) V + (h_k^-1 h_k') qdot_l,

(``K(a, b; N) = tr(a^ N b^T)`` over the top three rows, ``V`` the anchor's body twist) vanishes for
every ``V`` in the anchor's twist span and every ``qdot_l``, and the potential's vector
``c(q) = dN_A e4 + sum_k h_k(q) dN_k e4`` does not change with ``q`` and keeps its height as the
anchor moves (under the world: its height does not change). Treating ``V`` and ``qdot_l`` as
independent only makes the conditions stronger, so every solution is a nullspace direction.

Each condition is ``sum_a q^a P_a(q)`` with ``P_a`` trigonometric polynomials whose frequencies
are integer multiples of the group's common frequency (rational rotation rates), degree ``a`` up
to twice the P joints on a path; it holds identically iff it holds at ``2 K + 1`` equally spaced
values in each of ``D + 1`` consecutive periods (:func:`sample_values`). The conditions are
then one finite linear system per group, solved exactly (SVD); the solutions new to the columns
found before are emitted on as few bodies as possible (one, two, three, then the rest), with
provenance ``Source.R_M``. Cost: one small system per group (a hand), independent of the rest of
the robot but for the anchor's twist and motion spans.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from ..enums import Source
from ..model.inertia import HAT_INDEX
from ..model.robot import Coupling, Robot
from ..model.scale import decision_scale
from ..pga.core import hat
from ..pga.linalg import cross3
from .columns import Columns, on_bodies
from .principles import world_axes
from .rules import parallelograms

RM = Source.R_M

#: largest denominator of a rotation rate (``|omega| m``) taken as rational; a group with another
#: rate is skipped (fewer directions found, never a wrong one)
MAX_DENOMINATOR = 64
#: largest harmonic ``K`` of a group's conditions (samples per period ``2 K + 1``); beyond it the
#: group is skipped
MAX_HARMONIC = 256
#: singular values of a group's conditions: below ``tol`` or at least ``GAP`` times the largest below (relative)
GAP = 1e4
#: largest degree of a composed polynomial coupling (chains of MJCF ``polycoef``); beyond it, not grouped
MAX_DEGREE = 16
#: smallest component (of a unit solution) outside the directions already found that counts as new
NEW = 1e-6
#: largest group (anchor included) whose solutions on three bodies are searched; larger groups
#: search fewer and give the rest as wider columns
MAX_TRIPLES_BLOCKS = 10
#: largest group (anchor included) whose solutions on two bodies are searched
MAX_PAIRS_BLOCKS = 24


def coupled_polynomials(robot: Robot, extra: tuple[Coupling, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Each coordinate as a polynomial of its leader: ``q[j] = sum_a coef[j, a] q[lead[j]] ** a``.

    Chains of couplings are composed (a polynomial of a polynomial). Coordinates driven by several
    coordinates (a coupling with :attr:`~baseparams.model.robot.Coupling.more` terms) get
    ``lead = -1``, as do the ones they drive, coordinates of multi-dof joints, and chains whose
    composed degree exceeds :data:`MAX_DEGREE`.

    Parameters
    ----------
    robot : Robot
        The robot (``dof`` coordinates, :attr:`~baseparams.model.robot.Robot.couplings`).
    extra : tuple of Coupling, optional
        Couplings implied by the geometry (:func:`parallelogram_couplings`) besides the robot's.

    Returns
    -------
    lead : ndarray of int, shape ``(dof,)``
        The driving coordinate (``j`` itself for an independent coordinate; ``-1``: not grouped).
    coef : ndarray, shape ``(dof, d + 1)``
        Coefficients, lowest power first (``[offset, ratio, ...]``; ``[0, 1, 0...]`` for a leader).
    """
    from numpy.polynomial import Polynomial

    dof = robot.dof
    drive = {c.succ: c for c in (*robot.couplings, *extra)}
    lead = np.arange(dof)
    polys = [Polynomial([0.0, 1.0]) for _ in range(dof)]
    one = np.ones(dof, dtype=bool)
    one[robot.q_index[robot.ndofs != 1]] = False  # coordinates of multi-dof joints
    for j in range(dof):
        k, p, seen = j, Polynomial([0.0, 1.0]), {j}
        while k in drive and lead[j] >= 0:
            c = drive[k]
            if c.more or c.pred in seen or not one[c.pred]:
                lead[j] = -1
                break
            p, k = p(Polynomial(c.coefficients())), c.pred
            if p.degree() > MAX_DEGREE:
                lead[j] = -1
                break
            seen.add(k)
        if lead[j] >= 0:
            lead[j], polys[j] = k, p
        if not one[j]:
            lead[j] = -1
    width = max(2, max(len(p.coef) for p in polys))
    coef = np.zeros((dof, width))
    for j, p in enumerate(polys):
        coef[j, :len(p.coef)] = p.coef
        if len(p.coef) < 2 and lead[j] >= 0:  # a constant (a zero ratio): no leading power
            coef[j, 1] = 0.0
    return lead, coef


def coupled_coordinates(robot: Robot, extra: tuple[Coupling, ...] = ()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each coordinate as a linear function of its leader: ``q[j] = ratio[j] q[lead[j]] + offset[j]``.

    :func:`coupled_polynomials` restricted to the linear ones: a coordinate driven by a polynomial
    of degree two or more gets ``lead = -1`` here.

    Parameters
    ----------
    robot : Robot
        The robot (``dof`` coordinates, :attr:`~baseparams.model.robot.Robot.couplings`).
    extra : tuple of Coupling, optional
        Couplings implied by the geometry (:func:`parallelogram_couplings`) besides the robot's.

    Returns
    -------
    lead : ndarray of int, shape ``(dof,)``
        The driving coordinate (``j`` itself for an independent coordinate; ``-1``: not grouped).
    ratio : ndarray, shape ``(dof,)``
        Multiplier (dimensionless for R-R or P-P, rad/m or m/rad otherwise).
    offset : ndarray, shape ``(dof,)``
        Constant term (rad or m).
    """
    lead, coef = coupled_polynomials(robot, extra)
    nonlinear = np.any(np.abs(coef[:, 2:]) > 0, axis=1)
    return np.where(nonlinear, -1, lead), coef[:, 1].copy(), coef[:, 0].copy()


def coupled_groups(robot: Robot) -> list[tuple[int, list[int]]]:
    """The coupled groups: ``(anchor, bodies)`` with the bodies base-first.

    A body belongs to the group of its 1-dof joint's leading coordinate when that coordinate
    drives at least one other joint; the anchor is the first body up the tree outside the group
    (``-1``: the world). A group of one body under its anchor is a tree joint (the other rules'
    business) and is left out.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` bodies).

    Returns
    -------
    list of (int, list of int)
        Anchor body and the group's bodies (increasing indices, so parents first).
    """
    if not robot.couplings:
        return []
    lead, _ = coupled_polynomials(robot)
    qi = robot.q_index
    driven = np.bincount(lead[lead >= 0], minlength=robot.dof)
    key = {}
    for i in range(robot.n):
        if robot.ndofs[i] == 1 and lead[qi[i]] >= 0 and driven[lead[qi[i]]] > 1:
            key[i] = int(lead[qi[i]])
    groups: dict[tuple[int, int], list[int]] = {}
    anchor = {}
    for i in sorted(key):
        p = int(robot.parent[i])
        anchor[i] = anchor[p] if p in key and key[p] == key[i] else p
        groups.setdefault((key[i], anchor[i]), []).append(i)
    return [(a, bodies) for (_, a), bodies in groups.items() if len(bodies) > 1]


def twist_span(robot: Robot, body: int, tol: float = 1e-9) -> np.ndarray:
    """Orthonormal basis ``(r, 6)`` of the body twists ``g^-1 dg`` a body takes, over all motions.

    The body Jacobian's column of joint ``j`` is ``Ad((e^{S_{j+1} q} ... e^{S_p q})^-1) S_j``;
    over all ``q`` it spans the closure of ``S_j`` under ``ad`` of the later screws on the path.
    Coupled coordinates are treated as independent (a larger span: stronger conditions).

    Parameters
    ----------
    robot : Robot
        The robot.
    body : int
        The body (``-1``: the world, no motion).
    tol : float, default 1e-9
        Rank threshold.

    Returns
    -------
    ndarray, shape ``(r, 6)``
        Twists ``(omega, v)`` in world coordinates at the reference, orthonormal rows.
    """
    path = []
    while body >= 0:
        path.append(body)
        body = int(robot.parent[body])
    dofs = np.flatnonzero(np.isin(robot.dof_body, path))  # base-first along the path
    s, span = robot.screws, np.zeros((0, 6))
    for k, j in enumerate(dofs):  # root first: a floating root saturates the span at once
        span = _orth(np.vstack([span, _closure(s[j][None], s[dofs[k + 1:]], tol)]), tol)
        if len(span) == 6:
            break
    return span


def _ad(s: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``ad_s x`` of twists ``(omega, v)``: ``(6,), (m, 6) -> (m, 6)``."""
    w, v = s[:3], s[3:]
    return np.hstack([cross3(w, x[:, :3]), cross3(w, x[:, 3:]) + cross3(v, x[:, :3])])


def _closure(span: np.ndarray, gens: np.ndarray, tol: float) -> np.ndarray:
    """Orthonormal basis of the smallest ``ad_{gens}``-invariant subspace containing ``span``."""
    basis = _orth(span, tol)
    while len(basis) < 6:
        grown = _orth(np.vstack([basis] + [_ad(s, basis) for s in gens]), tol)
        if len(grown) == len(basis):
            return grown
        basis = grown
    return basis


def _orth(a: np.ndarray, tol: float) -> np.ndarray:
    if len(a) == 0:
        return np.zeros((0, a.shape[1]))
    _, s, vt = np.linalg.svd(a, full_matrices=False)
    return vt[: int(np.sum(s > tol * max(1.0, s[0])))]


def _rates(robot: Robot, bodies: list[int], ratio: np.ndarray, tol: float) -> tuple[list[float], list[int]]:
    """Per body: the sum of its path's rotation rates ``|omega_j m_j|`` and its number of slides.

    A slide is a P joint or a helical one (its translation grows with the coordinate).
    """
    qi, pos = robot.q_index, {k: i for i, k in enumerate(bodies)}
    rates, slides = [], []
    for k in bodies:
        s = robot.screws[qi[k]]
        w = float(np.linalg.norm(s[:3]))
        p = pos.get(int(robot.parent[k]))
        rate, sl = (0.0, 0) if p is None else (rates[p], slides[p])
        rates.append(rate + w * abs(float(ratio[qi[k]])))
        slides.append(sl + int(w <= tol or abs(float(s[:3] @ s[3:])) > tol * max(1.0, float(np.linalg.norm(s[3:])))))
    return rates, slides


def sample_values(robot: Robot, bodies: list[int], ratio: np.ndarray, tol: float = 1e-9) -> np.ndarray | None:
    """Values of the leading coordinate on which a group's conditions hold iff they hold for all.

    Every condition is ``sum_a q^a P_a(q)`` with ``a <= D`` (``D`` twice the most slides on a
    path) and ``P_a`` trigonometric polynomials whose frequencies are sums of ``s_j f_j``,
    ``|s_j| <= 2``, over the rates ``f_j = |omega_j m_j|`` of a path's rotations. With rational
    rates (denominator at most :data:`MAX_DENOMINATOR`) these are integer multiples ``k f0``,
    ``|k| <= K``, of their greatest common divisor ``f0``. The values are ``N = 2 K + 1``
    equally spaced points in each of ``D + 1`` consecutive periods ``T = 2 pi / f0``: at each
    point the ``D + 1`` values ``q + m T`` make every ``P_a`` vanish there, and a trigonometric
    polynomial of degree ``K`` vanishing at ``N`` equally spaced points of a period is zero.

    Parameters
    ----------
    robot : Robot
        The robot.
    bodies : list of int
        The group's bodies, parents first.
    ratio : ndarray, shape ``(dof,)``
        Multipliers from :func:`coupled_coordinates`.
    tol : float, default 1e-9
        Tolerance of a rate's rational approximation (relative) and of a slide.

    Returns
    -------
    ndarray, shape ``(N (D + 1),)`` or None
        The values (rad or m); None when a rate is not rational enough or ``K`` exceeds
        :data:`MAX_HARMONIC` (the group is then skipped).
    """
    from fractions import Fraction
    from math import gcd, lcm

    rates, slides = _rates(robot, bodies, ratio, tol)
    qi = robot.q_index
    fr = []
    for k in bodies:
        w = float(np.linalg.norm(robot.screws[qi[k]][:3])) * abs(float(ratio[qi[k]]))
        if w > tol:
            f = Fraction(w).limit_denominator(MAX_DENOMINATOR)
            if abs(float(f) - w) > tol * max(1.0, w):
                return None
            fr.append(f)
    f0, harmonic = Fraction(1), 0
    if fr:
        f0 = Fraction(gcd(*(f.numerator for f in fr)), lcm(*(f.denominator for f in fr)))
        harmonic = int(round(2 * max(rates) / float(f0)))
    if harmonic > MAX_HARMONIC:
        return None
    n, period, deg = 2 * harmonic + 1, 2 * np.pi / float(f0), 2 * max(slides)
    base = (np.arange(n) + 0.5) * period / n
    return (base[None, :] + period * (np.arange(deg + 1)[:, None] - 0.5 * (deg + 1))).ravel()


def _motions(robot: Robot, bodies: list[int], coef: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``h_k(q)`` and ``dh_k/dq`` of the group's bodies relative to the anchor: ``(M, G, 4, 4)`` each.

    Joint ``j`` is at ``p_j(q)`` (``coef[j]``, :func:`coupled_polynomials`): ``exp(S_j p_j(q))``,
    derivative ``exp(S_j p_j) S_j^ p_j'(q)``.
    """
    from numpy.polynomial import polynomial as P

    from ..pga.core import se3_exp

    qi, pos = robot.q_index, {k: i for i, k in enumerate(bodies)}
    h = np.zeros((len(q), len(bodies), 4, 4))
    dh = np.zeros_like(h)
    for i, k in enumerate(bodies):
        s, c = robot.screws[qi[k]], coef[qi[k]]
        e = se3_exp(P.polyval(q, c)[:, None] * s)  # (M, 4, 4)
        es = e @ hat(s) * P.polyval(q, P.polyder(c))[:, None, None]
        p = pos.get(int(robot.parent[k]))
        if p is None:
            h[:, i], dh[:, i] = e, es
        else:
            h[:, i], dh[:, i] = h[:, p] @ e, dh[:, p] @ e + h[:, p] @ es
    return h, dh


def nonlinear_values(n_unknowns: int, times: int = 1) -> np.ndarray:
    """Values of the leading coordinate at which a polynomially coupled group's conditions are sampled.

    A coupling of degree two or more puts the coordinate inside the trigonometric functions
    (``exp(S p(q))``): the conditions are analytic in ``q``, not trigonometric polynomials, and
    no finite set of values proves them; they are imposed at ``times (12 u + 16)`` values
    spread over ``[-1.5, 1.5]`` (``u`` the unknowns' blocks), generic points (golden-ratio
    spacing), and a solution must survive twice as many (:func:`group_nullspace`).

    Parameters
    ----------
    n_unknowns : int
        Unknown blocks of ten (the group's bodies and anchor).
    times : int, default 1
        Multiplier of the number of values.

    Returns
    -------
    ndarray, shape ``(M,)``
        The values (rad or m).
    """
    m = times * (12 * n_unknowns + 16)
    return 6.0 * (((np.arange(m) + 0.5) * 0.6180339887498949) % 1.0) - 3.0


def _functional(c: np.ndarray) -> np.ndarray:
    """Coefficients ``(*, 10)`` of ``dN -> tr(dN c)`` on the ``hat`` entries of a symmetric ``dN``: ``(*, 4, 4)``."""
    s = c + np.swapaxes(c, -1, -2)
    out = np.stack([s[..., i, j] for i, j in HAT_INDEX], axis=-1)
    out[..., [0, 3, 5, 9]] *= 0.5
    return out


def group_system(robot: Robot, anchor: int, bodies: list[int], coef: np.ndarray, q: np.ndarray,
                 level: np.ndarray | None = None, tol: float = 1e-9, motions=None) -> np.ndarray:
    """The criterion's conditions on a coupled group: ``(rows, 10 (G + 1))`` (anchor block first).

    Rows: the kinetic form's entries ``K(a, b)`` for ``a <= b`` among ``qdot_l`` and a basis of
    the anchor's twist span (:func:`twist_span`), at every value of ``q``; then, with gravity,
    the potential (:func:`_potential_rows`). Each row is normalised (zero rows dropped).

    Parameters
    ----------
    robot : Robot
        The robot.
    anchor : int
        The group's anchor (``-1``: the world, whose block the caller drops).
    bodies : list of int
        The group's bodies, parents first.
    coef : ndarray, shape ``(dof, d + 1)``
        Each coordinate as a polynomial of its leader (:func:`coupled_polynomials`).
    q : ndarray, shape ``(M,)``
        Values of the leading coordinate (:func:`sample_values`, :func:`nonlinear_values`).
    level : ndarray, shape ``(L, 4)``, optional
        Rows ``gbar^T X`` over a basis ``X`` of the anchor's motion span
        (:mod:`.subspaces`): a vector ``c`` of the anchor keeps its height iff ``level c = 0``;
        default none known (only ``c = 0``).
    tol : float, default 1e-9
        Geometric tolerance.
    motions : tuple of ndarray, optional
        ``(h (M, G, 4, 4), dh (M, G, L, 4, 4))``: the bodies' motions and their derivatives in ``L``
        leading coordinates (a group driven by several: :func:`multi_groups`); default those of
        ``coef`` at ``q``.

    Returns
    -------
    ndarray, shape ``(rows, 10 (G + 1))``
        Linear conditions on the ``paper``-convention parameter changes (``hat`` order, world
        frame at q = 0) of the anchor then of each body.
    """
    if motions is None:
        h, dh = _motions(robot, bodies, coef, q)
        dh = dh[:, :, None]
    else:
        h, dh = motions
    nl = dh.shape[2]
    w = twist_span(robot, anchor, tol) if anchor >= 0 else np.zeros((0, 6))
    gens = hat(w)  # (r, 4, 4)
    hinv = np.linalg.inv(h)
    xk = np.concatenate([hinv[:, :, None] @ dh, hinv[:, :, None] @ gens[None, None] @ h[:, :, None]], axis=2)
    xa = np.concatenate([np.zeros((nl, 4, 4)), gens])  # the anchor does not see qdot_l
    a, b = np.triu_indices(len(w) + nl)
    fk = _functional(np.swapaxes(xk[:, :, b, :3], -1, -2) @ xk[:, :, a, :3])  # (M, G, P, 10)
    fa = _functional(np.swapaxes(xa[b, :3], -1, -2) @ xa[a, :3])  # (P, 10)
    m, g, npair = fk.shape[0], len(bodies), len(a)
    kin = np.concatenate([np.broadcast_to(fa, (m, npair, 10)), np.moveaxis(fk, 1, 2).reshape(m, npair, 10 * g)], axis=2)
    rows = [kin.reshape(m * npair, 10 * (g + 1))]
    if np.linalg.norm(robot.gravity) > tol:
        rows.append(_potential_rows(robot, anchor, h, level))
    out = np.concatenate(rows)
    norm = np.linalg.norm(out, axis=1)
    keep = norm > tol * max(1.0, float(norm.max()))
    return out[keep] / norm[keep, None]


def _potential_rows(robot: Robot, anchor: int, h: np.ndarray, level: np.ndarray | None) -> np.ndarray:
    """The potential's conditions ``(rows, 10 (G + 1))``: ``c(q) = dN_A e4 + sum_k h_k(q) dN_k e4``.

    Under the world (fixed) the height ``gbar^T c(q)`` must not change with ``q``; under a
    moving anchor, with ``g_A = I + sum_i a_i X_i`` over its motion span, neither may
    ``gbar^T c(q)`` nor ``level c(q)`` (``level = gbar^T X``), and ``level c(q0) = 0``; without
    level rows, ``c(q)`` must not change.
    """
    m, g = h.shape[0], h.shape[1]
    pot = np.zeros((m, 4, g + 1, 10))
    pot[:, :, 0, 6:] = np.eye(4)
    pot[:, :, 1:, 6:] = np.moveaxis(h, 1, 2)  # h_k(q) dN_k e4
    diff = (pot[1:] - pot[:1]).reshape(m - 1, 4, -1)
    if anchor < 0:
        return np.einsum("a,mab->mb", np.r_[robot.gravity, 0.0], diff)
    if level is None:
        return diff.reshape(4 * (m - 1), -1)
    # the potential is -gbar^T g_A c(q) with g_A = I + sum_i a_i X_i (X_i spanning g_A - I): it
    # stays constant when gbar^T c(q) and every level row's l_i c(q) = gbar^T X_i c(q) do not
    # change with q and l_i c(q0) = 0 (a part of c(q) none of them sees may move freely: an
    # in-plane first moment of a horizontal mechanism)
    see = np.vstack([np.r_[robot.gravity, 0.0], level])
    return np.concatenate([np.einsum("la,mab->mlb", see, diff).reshape(len(see) * (m - 1), -1),
                           np.einsum("la,ab->lb", level, pot[0].reshape(4, -1))])


def group_nullspace(robot: Robot, anchor: int, bodies: list[int], tol: float = 1e-9, level: np.ndarray | None = None,
                    unit: np.ndarray | None = None, extra: tuple[Coupling, ...] = ()):
    """The conditions of a coupled group reduced to a square triangular factor, or None.

    Parameters
    ----------
    robot : Robot
        The robot.
    anchor : int
        The anchor body (``-1``: the world).
    bodies : list of int
        The group's bodies, parents first (:func:`coupled_groups`).
    tol : float, default 1e-9
        Geometric tolerance.
    level : ndarray, shape ``(L, 4)``, optional
        The anchor's level rows (:func:`group_system`).
    unit : ndarray, shape ``(10,)``, optional
        Per-entry factors ``d`` of a body block (:func:`baseparams.model.scale.decision_scale`;
        default ones): the system is solved for ``y = x / d``, an ordinary-sized equivalent, so
        that its rank decisions do not depend on the unit of length.
    extra : tuple of Coupling, optional
        Couplings implied by the geometry (:func:`coupled_coordinates`).

    Returns
    -------
    (ndarray, list of int) or None
        ``R (10 u, 10 u)``, upper triangular with ``R y = 0`` exactly for the solutions
        ``x = d y`` of :func:`group_system`, and the ``u`` bodies its blocks belong to (the anchor first unless it
        is the world); None when :func:`sample_values` finds no exact set of values, or when a
        polynomially coupled group's solutions change with twice as many sampled values
        (:func:`nonlinear_values`): the group is then skipped.
    """
    _, coef = coupled_polynomials(robot, extra)
    qi = robot.q_index[bodies]
    nonlinear = bool(np.any(np.abs(coef[qi, 2:]) > 0))
    q = nonlinear_values(len(bodies) + 1) if nonlinear else sample_values(robot, bodies, coef[:, 1], tol)
    if q is None:
        return None
    a, who = _group_rows(robot, anchor, bodies, coef, q, level, tol, unit)
    if nonlinear:  # sampled, not proven: a solution must survive twice as many values
        more, _ = _group_rows(robot, anchor, bodies, coef, nonlinear_values(len(bodies) + 1, 2) + 0.01, level, tol,
                              unit)
        scale = max(float(np.abs(a).max()), 1e-300)
        n1, n2 = null_rows(a, tol, scale), null_rows(np.vstack([a, more]), tol, scale)
        if n1 is None or n2 is None or len(n1) != len(n2):
            return None
        a = np.vstack([a, more])
    if len(a) < a.shape[1]:  # pad to square: the same solutions
        a = np.vstack([a, np.zeros((a.shape[1] - len(a), a.shape[1]))])
    r = np.linalg.qr(a, mode="r")
    return r, who


def _group_rows(robot: Robot, anchor: int, bodies: list[int], coef: np.ndarray, q: np.ndarray,
                level: np.ndarray | None, tol: float, unit: np.ndarray | None,
                motions=None) -> tuple[np.ndarray, list[int]]:
    """:func:`group_system` for ``y = x / unit``, the world's block dropped: ``(rows, who)``."""
    a = group_system(robot, anchor, bodies, coef, q, level, tol, motions)
    if unit is not None:
        a = a * np.tile(unit, len(bodies) + 1)
        a /= np.linalg.norm(a, axis=1, keepdims=True)
    who = [anchor, *bodies]
    if anchor < 0:
        a, who = a[:, 10:], who[1:]
    return a, who


def null_rows(a: np.ndarray, tol: float, scale: float) -> np.ndarray | None:
    """Orthonormal rows spanning the nullspace of ``a``; None when a singular value is ambiguous.

    Ambiguous: neither clearly zero nor clearly not (:func:`gap_split`): the subset or group is then
    skipped (fewer directions, never a wrong one).

    Parameters
    ----------
    a : ndarray, shape ``(r, m)``
        The system.
    tol : float
        Relative threshold of a zero singular value.
    scale : float
        What ``tol`` is relative to.

    Returns
    -------
    ndarray, shape ``(m - rank, m)``, or None
        The nullspace's orthonormal basis as rows; None when the rank is not decided by a gap.
    """
    _, s, vt = np.linalg.svd(a, full_matrices=a.shape[0] < a.shape[1])
    s = np.r_[s, np.zeros(a.shape[1] - len(s))]
    zero, clear = gap_split(s[None], tol, scale)
    if not (zero | clear).all():
        return None
    return vt[int(np.sum(~zero)):]


def gap_split(sv: np.ndarray, tol: float, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Singular values ``(k, m)`` that are clearly zero and clearly not, per row.

    Zero: at most ``tol * scale``. Not zero: at least ``GAP`` times the largest zero (floored at
    ``1e-15 * scale``, rounding) and above ``tol * scale``: the rank sits in a gap of ``GAP`` or
    more. A value in between leaves the rank undecided (the caller skips the system: fewer
    directions, never a wrong one).

    Parameters
    ----------
    sv : ndarray, shape ``(k, m)``
        Singular values, one system per row.
    tol : float
        Relative threshold of a zero.
    scale : float
        What ``tol`` is relative to.

    Returns
    -------
    zero, clear : ndarray of bool, shape ``(k, m)``
        Clearly zero; clearly not zero.
    """
    zero = sv <= tol * scale
    top = np.max(np.where(zero, sv, 0.0), axis=1, keepdims=True)
    clear = ~zero & (sv >= GAP * np.maximum(top, 1e-15 * scale))
    return zero, clear


def _subset_nulls(r: np.ndarray, u: int, size: int, tol: float, scale: float):
    """Nullspaces of ``r`` restricted to every ``size``-subset of the ``u`` blocks, batched.

    Yields ``(subset, column indices, X (d, 10 size))`` for the subsets with a nullspace and no
    ambiguous singular value (:func:`null_rows`), one batched SVD for all subsets of the size.
    """
    subs = list(combinations(range(u), size))
    idx = (10 * np.array(subs)[:, :, None] + np.arange(10)).reshape(len(subs), -1)
    a = r[:, idx].transpose(1, 0, 2)  # (subsets, 10 u, 10 size)
    _, sv, vt = np.linalg.svd(a, full_matrices=a.shape[1] < a.shape[2])
    sv = np.concatenate([sv, np.zeros((len(subs), a.shape[2] - sv.shape[1]))], axis=1)
    zero, clear = gap_split(sv, tol, scale)
    for k in np.flatnonzero(zero.any(axis=1) & (zero | clear).all(axis=1)):
        yield subs[k], idx[k], vt[k, int(np.sum(~zero[k])):]


def sparse_solutions(r: np.ndarray, u: int, tol: float, prior: np.ndarray) -> list[tuple[tuple[int, ...], np.ndarray]]:
    """A basis of the solutions of ``r x = 0`` beyond ``prior``, each on as few of the ``u`` blocks as found.

    Subsets of blocks by size (1; 2 when ``u <= MAX_PAIRS_BLOCKS``; 3 when
    ``u <= MAX_TRIPLES_BLOCKS``: the cost stays bounded per group), each kept for the
    directions it adds to ``prior`` and the ones before; what they leave is returned on all the
    blocks it touches.

    Parameters
    ----------
    r : ndarray, shape ``(m, 10 u)``
        The system (ten unknowns per block).
    u : int
        Number of blocks.
    tol : float
        Relative threshold of a zero singular value (:func:`gap_split`).
    prior : ndarray, shape ``(p, 10 u)``
        Orthonormal rows spanning known solutions (inside the solution set).

    Returns
    -------
    list of (tuple of int, ndarray)
        ``(blocks, X (d, 10 len(blocks)))``: new solutions on those blocks.
    """
    scale = max(float(np.abs(r).max()), 1e-300)
    null = null_rows(r, tol, scale)
    if null is None:
        return []
    found, out = prior, []
    for size in [k for k, most in ((1, u), (2, MAX_PAIRS_BLOCKS), (3, MAX_TRIPLES_BLOCKS)) if u <= most]:
        if len(found) >= len(null):
            return out
        for sub, idx, x in _subset_nulls(r, u, size, tol, scale):
            emb = np.zeros((len(x), 10 * u))
            emb[:, idx] = x
            ru, rs, rvt = np.linalg.svd(emb - (emb @ found.T) @ found, full_matrices=False)
            k = int(np.sum(rs > NEW))
            if k:
                out.append((sub, ru[:, :k].T @ x))
                found = np.vstack([found, rvt[:k]])
    ru, rs, _ = np.linalg.svd(null - (null @ found.T) @ found, full_matrices=False)
    rest = (ru[:, : int(np.sum(rs > NEW))].T @ null).reshape(-1, u, 10)
    if len(rest):
        sub = tuple(int(b) for b in np.flatnonzero(np.abs(rest).max(axis=(0, 2)) > 0))
        out.append((sub, rest[:, sub].reshape(len(rest), -1)))
    return out


def prior_rows(prior: Columns, who: list[int], unit: np.ndarray) -> np.ndarray:
    """Orthonormal rows spanning the ``prior`` columns that lie on the blocks ``who`` (for ``pi / unit``).

    Parameters
    ----------
    prior : Columns
        Known columns (``paper`` convention).
    who : list of int
        ``u`` bodies.
    unit : ndarray, shape ``(10,)``
        Per-parameter scale of the decisions.

    Returns
    -------
    ndarray, shape ``(p, 10 u)``
        Orthonormal rows: the span of the columns all of whose blocks are on ``who``.
    """
    pos = {b: i for i, b in enumerate(who)}
    inside = np.isin(prior.child, who) & ((prior.parent < 0) | np.isin(prior.parent, who))
    inside &= ((prior.extra < 0) | np.isin(prior.extra, who)) & ~prior.has_more()
    sel = prior.subset(inside)
    if not len(sel):
        return np.zeros((0, 10 * len(who)))
    v = np.zeros((len(sel), len(who), 10))
    k = np.arange(len(sel))
    v[k, [pos[int(b)] for b in sel.child]] += sel.h
    for body, h in ((sel.parent, sel.hp), (sel.extra, sel.he)):
        m = body >= 0
        v[k[m], [pos[int(b)] for b in body[m]]] += h[m]
    v = (v / unit).reshape(len(sel), -1)
    norm = np.linalg.norm(v, axis=1)
    v = v[norm > 0] / norm[norm > 0, None]  # a zero column (a rule's degenerate case) spans nothing
    if not len(v):
        return v
    _, s, vt = np.linalg.svd(v, full_matrices=False)
    return vt[: int(np.sum(s > 1e-9 * s[0]))]


def _levels(robot: Robot, anchors: list[int], tol: float) -> dict[int, np.ndarray]:
    """Per moving anchor, the rows ``gbar^T X ((L, 4))`` over its motion span's basis (:mod:`.subspaces`)."""
    moving = sorted({a for a in anchors if a >= 0})
    if not moving or np.linalg.norm(robot.gravity) <= tol:
        return {}
    from .subspaces import motion_spans

    ms = motion_spans(robot, tol)
    g = robot.gravity / np.linalg.norm(robot.gravity)
    return {a: np.einsum("a,kab->kb", g, ms.padded[a]) for a in moving}


def _group_label(names: list[str], anchor: int, bodies: list[int]) -> str:
    top = names[anchor] if anchor >= 0 else "the world"
    return f"coupled group on {top}: {', '.join(names[b] for b in bodies)}"


def coupled_columns(robot: Robot, tol: float = 1e-9, prior: Columns | None = None) -> Columns:
    """R-M: the columns the coupled groups add, each on at most three bodies.

    For every coupled group (:func:`coupled_groups`) the criterion's conditions
    (:func:`group_system`) are solved exactly (:func:`group_nullspace`), and the solutions
    supported on one, two or three of its bodies (the anchor included) are emitted, each only
    for the directions it adds to ``prior`` and to the ones before, until they span all
    solutions; what no such subset gives is emitted on all the group's bodies it touches.

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Geometric tolerance (relative singular-value threshold of the group systems).
    prior : Columns, optional
        Columns found before (the principles and the other rules): only new directions are
        emitted, so that no column repeats a known one up to rounding.

    Returns
    -------
    Columns
        Columns in the ``paper`` convention (spatial pseudo-inertia entries ``XX XY XZ YY YZ ZZ
        MX MY MZ M`` of each body, world frame at q = 0), provenance ``R-M coupled joints``; the
        highest body carries ``h``, the others ``hp`` and ``he``.
    """
    cols = _group_columns(robot, coupled_groups(robot), tol, prior, RM)
    more = multi_group_columns(robot, tol, Columns.concat([prior or Columns.empty(), cols]))
    return Columns.concat([cols, more])


def multi_groups(robot: Robot, tol: float = 1e-9) -> list[tuple[int, list[int], np.ndarray, np.ndarray, np.ndarray]]:
    """Groups whose joints are driven by several coordinates (a tendon tying three joints), couplings alone.

    With linear couplings and no loop joint, every coordinate is an affine function of the
    independent ones: ``q = G q_a + o`` (``G`` constant). A body with a coordinate driven by two or
    three independent coordinates ``L`` (its joint's, 1-dof or universal, together) starts a
    group; the bodies next to it in the tree (parent or children, R, P or U joints) whose
    coordinates are driven by coordinates of ``L`` only join it; the anchor is the parent of the
    group's top body (a leader may also move the anchor: the conditions then only get stronger).

    Parameters
    ----------
    robot : Robot
        The robot.
    tol : float, default 1e-9
        Threshold of a zero entry of ``G``.

    Returns
    -------
    list of (int, list of int, ndarray, ndarray, ndarray)
        ``(anchor, bodies (parents first), leaders L (indices into robot.actuated), G (dof, len(L)),
        o (dof,))``.
    """
    if robot.loops or not any(c.more for c in robot.couplings) or any(c.poly for c in robot.couplings):
        return []
    from ..kinematics.loops import close_loops

    cs = close_loops(robot, np.zeros((1, len(robot.actuated))), cond_max=np.inf)
    if not cs.kept:
        return []
    g, o, qi, nd = cs.G[0], cs.q[0], robot.q_index, robot.ndofs
    rows = [[frozenset(np.flatnonzero(np.abs(g[qi[i] + c]) > tol).tolist()) for c in range(nd[i])]
            if robot.jtype[i] in ("R", "P", "U") else None for i in range(robot.n)]
    lead = [None if r is None else frozenset().union(*r) for r in rows]
    children: dict[int, list[int]] = {}
    for i in range(robot.n):
        children.setdefault(int(robot.parent[i]), []).append(i)
    out, seen = [], set()
    for i in range(robot.n):
        if lead[i] is None or i in seen or not any(len(r) >= 2 for r in rows[i]) or len(lead[i]) > 3:
            continue
        group, stack = {i}, [i]
        while stack:  # grow along the tree through bodies driven by the same leaders only
            k = stack.pop()
            for j in [int(robot.parent[k]), *children.get(k, [])]:
                if j >= 0 and j not in group and lead[j] is not None and lead[j] and lead[j] <= lead[i]:
                    group.add(j)
                    stack.append(j)
        bodies = sorted(group)
        tops = [b for b in bodies if int(robot.parent[b]) not in group]
        seen |= group
        if len(tops) == 1:  # one anchor
            ls = np.array(sorted(lead[i]))
            out.append((int(robot.parent[tops[0]]), bodies, ls, g[:, ls], o))
    return out


def _multi_motions(robot: Robot, bodies: list[int], g: np.ndarray, o: np.ndarray,
                   qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``h (M, G, 4, 4)`` and ``dh (M, G, L, 4, 4)`` of a group driven by ``L`` coordinates ``qs (M, L)``.

    A body's joint is the product of its coordinates' exponentials (world screws at the reference).
    """
    from ..pga.core import se3_exp

    qi, pos = robot.q_index, {k: i for i, k in enumerate(bodies)}
    m, nl = qs.shape
    h = np.zeros((m, len(bodies), 4, 4))
    dh = np.zeros((m, len(bodies), nl, 4, 4))
    for i, k in enumerate(bodies):
        e = np.broadcast_to(np.eye(4), (m, 4, 4)).copy()
        de = np.zeros((m, nl, 4, 4))
        for c in range(qi[k], qi[k] + robot.ndofs[k]):
            s, row = robot.screws[c], g[c]
            ec = se3_exp((o[c] + qs @ row)[:, None] * s)
            de = de @ ec[:, None] + e[:, None] @ ((ec @ hat(s))[:, None] * row[None, :, None, None])
            e = e @ ec
        p = pos.get(int(robot.parent[k]))
        if p is None:
            h[:, i], dh[:, i] = e, de
        else:
            h[:, i], dh[:, i] = h[:, p] @ e, dh[:, p] @ e[:, None] + h[:, p][:, None] @ de
    return h, dh


def _multi_values(n_unknowns: int, nl: int, times: int = 1) -> np.ndarray:
    """Generic points ``(M, L)`` in ``[-3, 3]^L`` (additive recurrences of irrational steps)."""
    m = times * (12 * n_unknowns + 16) * nl
    steps = np.array([0.6180339887498949, 0.41421356237309515, 0.7320508075688772])[:nl]
    return 6.0 * (((np.arange(m)[:, None] + 0.5) * steps) % 1.0) - 3.0


def multi_group_columns(robot: Robot, tol: float = 1e-9, prior: Columns | None = None) -> Columns:
    """R-M on groups driven by several coordinates (:func:`multi_groups`): sampled, kept when twice as many agree.

    Parameters
    ----------
    robot : Robot
        The robot.
    tol : float, default 1e-9
        Relative singular-value threshold.
    prior : Columns, optional
        Columns found before: only new directions are emitted.

    Returns
    -------
    Columns
        Provenance ``R-M coupled joints``.
    """
    parts = []
    unit = decision_scale(robot, "paper")[:10]
    for anchor, bodies, leaders, g, o in multi_groups(robot, tol):
        level = _levels(robot, [anchor], tol).get(anchor)
        systems = []
        for times, shift in ((1, 0.0), (2, 0.01)):
            qs = _multi_values(len(bodies) + 1, len(leaders), times) + shift
            systems.append(_group_rows(robot, anchor, bodies, None, qs[:, 0], level, tol, unit,
                                       _multi_motions(robot, bodies, g, o, qs)))
        (a, who), (more, _) = systems
        scale = max(float(np.abs(a).max()), 1e-300)
        n1, n2 = null_rows(a, tol, scale), null_rows(np.vstack([a, more]), tol, scale)
        if n1 is None or n2 is None or len(n1) != len(n2) or not len(n2):
            continue
        r = np.linalg.qr(np.vstack([a, more]), mode="r")
        label = _group_label(robot.names, anchor, bodies) + f" (driven by {len(leaders)} coordinates)"
        seed = prior_rows(prior, who, unit) if prior is not None else np.zeros((0, 10 * len(who)))
        for sub, y in sparse_solutions(r, len(who), tol, seed):
            parts.append(on_bodies([who[b] for b in sub], y * np.tile(unit, len(sub)), RM, label))
    return Columns.concat(parts)


def _group_columns(robot: Robot, groups: list, tol: float, prior: Columns | None, source: int,
                   labels: list[str] | None = None, extra: tuple[Coupling, ...] = ()) -> Columns:
    """The columns of ``groups [(anchor, bodies)]``, new to ``prior``, with provenance ``source``."""
    if not groups:
        return Columns.empty()
    parts = []
    levels = _levels(robot, [a for a, _ in groups], tol)
    unit = decision_scale(robot, "paper")[:10]
    for i, (anchor, bodies) in enumerate(groups):
        red = group_nullspace(robot, anchor, bodies, tol, levels.get(anchor), unit, extra)
        if red is None:
            continue
        r, who = red
        label = labels[i] if labels else _group_label(robot.names, anchor, bodies)
        seed = prior_rows(prior, who, unit) if prior is not None else np.zeros((0, 10 * len(who)))
        for sub, y in sparse_solutions(r, len(who), tol, seed):
            parts.append(on_bodies([who[b] for b in sub], y * np.tile(unit, len(sub)), source, label))
    return Columns.concat(parts)


def parallelogram_couplings(robot: Robot) -> list[tuple[int, list[int], tuple[Coupling, ...], str]]:
    """The couplings a parallelogram's assembly mode implies: ``(anchor, bodies, couplings, loop)`` each.

    On the parallelogram mode (:func:`.rules.parallelograms`) the crank ``L1`` and the rocker
    ``L3`` turn by the same angle relative to the root ``L0`` and the coupler ``L2`` keeps the
    root's orientation, so every tree joint of the cycle is ``+-`` the crank joint's coordinate:
    the cycle's three moving links are a coupled group on ``L0``, whose criterion
    (:func:`group_system`) is exact where R-L1's closed forms are not complete (a horizontal
    linkage, a moving root). Cycles whose joints are already coupled are left to R-M.

    Parameters
    ----------
    robot : Robot
        The robot (its ``loops`` and ``couplings``).

    Returns
    -------
    list of (int, list of int, tuple of Coupling, str)
        The root ``L0`` (``-1``: the world), the links ``L1, L2, L3`` (increasing indices), the
        implied couplings (driving coordinate: the first link's tree joint) and the loop
        joint's name.
    """
    pars = parallelograms(robot)
    if not pars:
        return []
    coupled = {c.succ for c in robot.couplings} | {k for c in robot.couplings for k, _ in c.terms()}
    axw, qi = world_axes(robot), robot.q_index
    out = []
    for par in pars:
        l0, l1, l2, l3 = par["links"]
        links = sorted((l1, l2, l3))
        if any(robot.ndofs[b] != 1 or int(qi[b]) in coupled for b in links):
            continue
        turn = {l0: 0, l1: 1, l2: 0, l3: 1}  # each link's rotation relative to the root, in crank angles
        lead = links[0]  # a child of the root: its parent is outside the cycle
        if int(robot.parent[lead]) != l0:
            continue
        axis = par["axis"]
        sign = {b: float(np.sign(axw[b] @ axis)) for b in links}
        cps = tuple(Coupling(f"parallelogram {par['loop']}", int(qi[lead]), int(qi[b]),
                             sign[b] * sign[lead] * (turn[b] - turn[int(robot.parent[b])]))
                    for b in links[1:])
        out.append((l0, links, cps, par["loop"]))
    return out


def parallelogram_group_columns(robot: Robot, tol: float = 1e-9, prior: Columns | None = None) -> Columns:
    """R-L1 completed: each parallelogram's links as the coupled group they are (:func:`parallelogram_couplings`).

    Parameters
    ----------
    robot : Robot
        The robot (``n`` moving bodies).
    tol : float, default 1e-9
        Geometric tolerance.
    prior : Columns, optional
        Columns found before: only new directions are emitted.

    Returns
    -------
    Columns
        Columns in the ``paper`` convention, provenance ``R-L1 parallelograms``.
    """
    parts = []
    for anchor, links, cps, loop in parallelogram_couplings(robot):
        label = (f"parallelogram (loop {loop!r}): its links as joints coupled to "
                 f"{robot.names[links[0]]!r} (exact criterion of R-M)")
        parts.append(_group_columns(robot, [(anchor, links)], tol, prior, Source.R_L1, [label], cps))
    return Columns.concat(parts)
