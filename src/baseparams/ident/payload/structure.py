"""Which of a payload's parameters a motion identifies, decided as the project decides base parameters.

Structurally first: the payload's ten columns and the fitted drive terms' on the fitted rows, at
random states of the joints that move (the joints that do not move held at their logged median,
at rest: welded), column-scaled, their rank decided at a gap of the spectrum
(:func:`baseparams.numerics.rank_decision`, :func:`baseparams.numerics.spectrum`). The nullspace's
payload part is what no recording of these joints can identify (e.g. only the last joint moving:
its torque sees the inertia about its axis and the first moments across it, nothing of the mass).

Then on the log's own rows (weighted as fitted, column-scaled): a gap inside the structurally
identified directions leaves the ones below it not identified by this log. What is not identified
is named in words (:func:`describe`) and held at a stated prior or not reported as a number.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...display import summary_repr
from ...errors import BaseparamsError
from .model import DRIVE_MEANING, MEANING, NAMES

#: a parameter (or a quantity's gradient) is identified when its part along the unidentified directions is below
#: this fraction of it (scaled coordinates)
IDENTIFIED_RTOL = 1e-6
#: the parameters in the order they lead the combinations of :func:`describe`: mass, first moments, inertia
PIVOT_ORDER = (9, 6, 7, 8, 0, 1, 2, 3, 4, 5)
#: a column whose norm is at most this fraction of the largest is rounding of zero (not scaled up)
ZERO_COLUMN = 1e-10
#: the smallest gap at which the structural rank is decided (random states: the spectrum drops to rounding)
STRUCTURAL_GAP = 1e6


@dataclass(frozen=True, eq=False)
class Structure:
    """What the moving joints can identify.

    Parameters
    ----------
    scale : ndarray, shape ``(k,)``
        Column scales of the structural regressor (payload, then drive terms).
    null : ndarray, shape ``(k, u)``
        Orthonormal basis of the unidentified directions in scaled coordinates (``x = v / scale``).
    rank : int
        Structural rank of the ``k`` columns.
    gap : float
        The gap the rank was decided at (inf at full rank).
    weak : int
        Directions added by a gap in the log's own spectrum (not identified by this log).
    log_gap : float or None
        That gap, or None.
    """

    scale: np.ndarray
    null: np.ndarray
    rank: int
    gap: float
    weak: int = 0
    log_gap: float | None = None

    __repr__ = summary_repr

    @property
    def payload_null(self) -> np.ndarray:
        """``(10, u')``: an orthonormal basis of the unidentified payload directions (scaled coordinates)."""
        v = self.null[:10]
        if not v.size:
            return np.zeros((10, 0))
        u, s, _ = np.linalg.svd(v, full_matrices=False)
        return u[:, s > IDENTIFIED_RTOL * max(s.max(initial=0.0), 1.0)]

    @property
    def free(self) -> np.ndarray:
        """``(k, k - u)``: an orthonormal basis of the identified directions (scaled coordinates)."""
        k = len(self.scale)
        if not self.null.shape[1]:
            return np.eye(k)
        u, _, _ = np.linalg.svd(self.null, full_matrices=True)
        return u[:, self.null.shape[1]:]

    def identified(self, gradient: np.ndarray) -> bool:
        """Whether a quantity of the payload with this gradient is identified.

        Parameters
        ----------
        gradient : ndarray, shape ``(10,)``
            ``d quantity / d phi`` (:data:`~baseparams.ident.payload.model.NAMES`).

        Returns
        -------
        bool
            True when the gradient vanishes on the unidentified directions.
        """
        g = np.asarray(gradient, dtype=float) / self.scale[:10]
        u = self.payload_null
        norm = np.linalg.norm(g)
        return norm == 0 or not u.shape[1] or float(np.linalg.norm(g @ u)) <= IDENTIFIED_RTOL * norm

    def parameters(self) -> list[bool]:
        """Per payload parameter (:data:`NAMES`), whether it is identified on its own.

        Returns
        -------
        list of bool
            Ten flags.
        """
        return [self.identified(np.eye(10)[k]) for k in range(10)]


def structural(model, q_log: np.ndarray, moving: np.ndarray, samples: int, seed: int) -> Structure:
    """The structural rank of the payload's and drive terms' columns at random states of the moving joints.

    Parameters
    ----------
    model : PayloadModel
        The model (its fitted rows).
    q_log : ndarray, shape ``(S, dof)``
        The logged positions (the still joints' medians; the moving joints' spread).
    moving : ndarray of bool, shape ``(dof,)``
        The joints that move.
    samples : int
        Random states.
    seed : int
        Their seed.

    Returns
    -------
    Structure
        The unidentified directions.

    Raises
    ------
    BaseparamsError
        A rank without a clear gap (the message lists the spectrum's clusters).
    """
    from ...numerics import rank_decision

    rng = np.random.default_rng(seed)
    dof = q_log.shape[1]
    q = np.tile(np.median(q_log, axis=0), (samples, 1))
    mv = np.flatnonzero(moving)
    q[:, mv] += rng.uniform(-np.pi, np.pi, (samples, len(mv)))
    dq, ddq = np.zeros((samples, dof)), np.zeros((samples, dof))
    dq[:, mv], ddq[:, mv] = rng.uniform(-1, 1, (2, samples, len(mv)))
    a = model.columns(q, dq, ddq)[0].reshape(-1, model.n_params)
    scale = np.linalg.norm(a, axis=0)
    scale = np.where(scale > ZERO_COLUMN * scale.max(initial=0.0), scale, 1.0)  # rounding of zero stays zero
    d = rank_decision(a / scale, rtol=1e-9, min_gap=STRUCTURAL_GAP, samples=samples)
    if not d.decided:
        lines = "; ".join(d.spectrum.lines()) if d.spectrum is not None else ""
        raise BaseparamsError(f"link {model.link!r}: which payload parameters the moving joints identify is not "
                              f"decided (no gap in the spectrum of the columns: {lines}); try another seed or more "
                              f"samples")
    return Structure(scale, d.null_basis, d.rank, float(d.gap))


def with_log_gap(st: Structure, c: np.ndarray) -> Structure:
    """The structure with the directions below a gap of the log's own spectrum counted out.

    Parameters
    ----------
    st : Structure
        The structural decision.
    c : ndarray, shape ``(N, k - u)``
        The log's weighted rows in the identified coordinates (``free`` of ``st``).

    Returns
    -------
    Structure
        ``st``, or with the weak directions added to its nullspace (``weak``, ``log_gap``).
    """
    from ...numerics import spectrum

    if not c.shape[1]:
        return st
    norms = np.linalg.norm(c, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    _, s, vt = np.linalg.svd(c / norms, full_matrices=False)
    spec = spectrum(s)
    top = spec.clusters[0] if spec.clusters else None
    if top is None or top.stop >= len(s):
        return st
    keep = top.stop
    weak = st.free @ ((vt[keep:] / norms).T)  # scaled coordinates
    null, _ = np.linalg.qr(np.concatenate([st.null, weak], axis=1))
    return Structure(st.scale, null, st.rank - (len(s) - keep), st.gap, len(s) - keep, spec.gap(keep))


def describe(st: Structure, drives=()) -> list[str]:
    """The payload directions not identified, in words: one line each, the parameters named.

    Parameters
    ----------
    st : Structure
        The decision.
    drives : sequence of str
        The drive terms' names (the columns after the payload's ten), e.g. ``Ia_joint6``.

    Returns
    -------
    list of str
        E.g. ``M (mass)``, ``MZ - 0.088 M (first moment m cz, mass)`` or ``ZZ (inertia zz about
        LINK's origin), with - Ia_joint6 (rotor inertia: they regroup)``: each a direction (or a combination) of
        the payload's parameters (LINK's frame, about its origin) the motion leaves free, and the
        drive terms it regroups with; empty when every payload parameter is identified.
    """
    if not st.payload_null.shape[1]:
        return []
    k = len(st.scale)
    names = list(NAMES) + [str(n) for n in drives] + [f"drive{i}" for i in range(len(drives), k - 10)]
    order = np.r_[PIVOT_ORDER, np.arange(10, k)].astype(int)
    x = (st.null / st.scale[:, None])[order]  # parameter coordinates, the mass and first moments first
    out = []
    for red in _reduced(x.T):
        row = np.zeros(k)
        row[order] = red
        tol = 1e-9 * np.abs(row).max()
        idx = [i for i in order if abs(row[i]) > tol]
        if not idx or idx[0] >= 10:
            continue  # drive terms among themselves (e.g. Coulomb and offset of a joint that never reverses)
        lead = row[idx[0]]
        own = [i for i in idx if i < 10]
        text = _terms(row, own, lead, names) + f" ({', '.join(MEANING[names[i]] for i in own)})"
        other = [i for i in idx if i >= 10]
        if other:
            what = ", ".join(DRIVE_MEANING.get(names[i].split("_")[0].lstrip("d"), "drive term") for i in other)
            text += ", with " + _terms(row, other, lead, names, first=False) + f" ({what}: they regroup)"
        out.append(text)
    return out


def _terms(row: np.ndarray, idx, lead: float, names, first: bool = True) -> str:
    """``a - 0.5 b + c``: the entries ``idx`` of ``row`` relative to ``lead``, named."""
    parts = []
    for n, i in enumerate(idx):
        r = row[i] / lead
        sign = ("-" if r < 0 else "") if first and n == 0 else (" - " if r < 0 else " + ") if n else \
            ("- " if r < 0 else "+ ")
        size = "" if abs(abs(r) - 1) < 1e-9 else f"{abs(r):.4g} "
        parts.append(f"{sign}{size}{names[i]}")
    return "".join(parts)


def _reduced(m: np.ndarray) -> np.ndarray:
    """The reduced row echelon form of ``m`` (rows: a basis of the same row space, as sparse as pivots make it)."""
    a = np.array(m, dtype=float)
    r, lead = 0, 0
    rows, cols = a.shape
    for lead in range(cols):
        if r >= rows:
            break
        p = r + int(np.argmax(np.abs(a[r:, lead])))
        if abs(a[p, lead]) <= 1e-9 * max(np.abs(a).max(), 1e-300):
            continue
        a[[r, p]] = a[[p, r]]
        a[r] /= a[r, lead]
        for i in range(rows):
            if i != r:
                a[i] -= a[i, lead] * a[r]
        r += 1
    return a[:r]
