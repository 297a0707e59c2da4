"""Base parameters: an orthonormal basis of ``Null^perp`` and the regrouped form users know.

Regrouping (in a chosen parameter convention, e.g. ``khalil`` link-frame or ``paper``
spatial): the standard parameters split into identifiable ``pi_I`` and dependent ``pi_D``
with the nullspace basis ``B`` restricted to ``D`` invertible; then

    beta = pi_I + K pi_D,   K = -B_I B_D^{-1}

gives ``Y pi = Y_I beta`` for every ``pi``. ``D`` is chosen greedily from the last body's
parameters backwards (mass, first moments, then second moments), which regroups each body's
dependent parameters onto its predecessors as in Khalil's rules (``ZZ1R = ZZ1 + YY2 + ...``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import BaseparamsError
from ..model import inertia as _inertia
from ..model.robot import Robot

_NAMES = _inertia.NAMES


def parameter_names(robot: Robot, convention: str = "khalil") -> list[str]:
    """``body.PARAM`` for every parameter, e.g. ``link2.ZZ``; ``paper`` names are the spatial
    pseudo-inertia entries ``MXX...M`` written ``XX...M`` (at q = 0, world frame)."""
    return [f"{b}.{p}" for b in robot.names for p in _NAMES[convention]]


def paper_from(robot: Robot, convention: str) -> np.ndarray:
    """Block-diagonal ``T (10 n, 10 n)``: paper parameters = ``T @`` convention parameters.

    Conventions other than ``paper`` are link-frame (the body frame), mapped by ``M0``."""
    n = robot.n
    t = np.zeros((10 * n, 10 * n))
    if convention == "paper":
        return np.eye(10 * n)
    eye = np.eye(10)
    per = _inertia.from_convention(eye, convention)  # (10, 4, 4) body-frame N of unit params
    for i in range(n):
        t[10 * i:10 * i + 10, 10 * i:10 * i + 10] = _inertia.hat(_inertia.transform(per, robot.M0[i])).T
    return t


def clean(x: np.ndarray, atol: float = 1e-9) -> np.ndarray:
    """Remove rounding noise: zero below ``atol``; snap to 10 significant digits."""
    x = np.where(np.abs(x) < atol, 0.0, x)
    with np.errstate(divide="ignore", invalid="ignore"):
        mag = np.where(x == 0, 0, np.floor(np.log10(np.abs(np.where(x == 0, 1, x)))))
    scale = 10.0 ** (9 - mag)
    return np.round(x * scale) / scale


def _fmt(c: float) -> str:
    return f"{c:.10g}"


@dataclass(frozen=True)
class BaseParameters:
    """The base-parameter structure of a robot in one convention.

    ``independent (nb,)`` indices of ``pi_I``; ``dependent (k,)`` of ``pi_D``; ``K (nb, k)``;
    ``E (nb, 10 n)`` with ``beta = E @ pi`` (convention coordinates); ``names`` of all
    standard parameters; ``unidentifiable`` indices of parameters that no base parameter sees;
    ``base_basis (10 n, nb)`` orthonormal basis of ``Null^perp`` in the paper convention.
    """

    convention: str
    names: list[str]
    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    E: np.ndarray
    unidentifiable: np.ndarray
    base_basis: np.ndarray
    T: np.ndarray

    @property
    def n_base(self) -> int:
        return len(self.independent)

    def base_names(self) -> list[str]:
        """``NAMER`` when the parameter absorbs others (Khalil's suffix), else ``NAME``."""
        return [self.names[i] + ("R" if np.any(self.K[r] != 0) else "") for r, i in enumerate(self.independent)]

    def expressions(self) -> list[dict[str, str]]:
        """``[{name, expression}]``: each base parameter as a combination of standard ones."""
        out = []
        for r, (i, bname) in enumerate(zip(self.independent, self.base_names())):
            terms = [self.names[i]]
            for c, d in sorted(zip(self.K[r], self.dependent), key=lambda t: t[1]):
                if c == 0:
                    continue
                sign = "-" if c < 0 else "+"
                mag = abs(c)
                terms.append(f"{sign} {self.names[d]}" if mag == 1 else f"{sign} {_fmt(mag)}*{self.names[d]}")
            out.append({"name": bname, "expression": " ".join(terms)})
        return out

    def _check(self, convention: str) -> None:
        _inertia.check_convention(convention)
        if convention != self.convention:
            raise BaseparamsError(
                f"parameter vector in the {convention!r} convention given to base parameters regrouped in the "
                f"{self.convention!r} convention; regroup in {convention!r} (base_parameters(..., {convention!r}), "
                f"--convention {convention}) or convert the vector first")

    def to_base(self, pi: np.ndarray, convention: str) -> np.ndarray:
        """Base parameters ``beta (nb,)`` from a full vector ``pi (10 n,)``.

        ``convention`` (required) names ``pi``'s convention; it must be this object's
        :attr:`convention` (a mismatch is an error, never a number)."""
        self._check(convention)
        pi = np.asarray(pi, dtype=float)
        if pi.shape != (self.E.shape[1],):
            raise BaseparamsError(f"expected a parameter vector of shape ({self.E.shape[1]},), got {pi.shape}")
        return self.E @ pi

    def from_base(self, beta: np.ndarray) -> np.ndarray:
        """The minimum-norm full vector ``(10 n,)`` with these base parameters, in this object's
        :attr:`convention`."""
        beta = np.asarray(beta, dtype=float)
        if beta.shape != (self.E.shape[0],):
            raise BaseparamsError(f"expected {self.E.shape[0]} base parameters, got shape {beta.shape}")
        return np.linalg.pinv(self.E) @ beta


def _choose_dependent(b: np.ndarray, order: np.ndarray, rtol: float = 1e-8) -> np.ndarray:
    """Greedy rows of ``b (m, k)`` (in ``order``) spanning R^k: ``b[D]`` invertible."""
    k = b.shape[1]
    basis = np.zeros((0, k))
    chosen = []
    scale = max(np.abs(b).max(), 1e-300)
    for r in order:
        v = b[r] - basis.T @ (basis @ b[r]) if len(basis) else b[r].copy()
        nv = np.linalg.norm(v)
        if nv > rtol * scale:
            basis = np.vstack([basis, v / nv])
            chosen.append(r)
            if len(chosen) == k:
                break
    return np.array(chosen, dtype=int)


def base_parameters(robot: Robot, null_basis: np.ndarray, convention: str = "khalil") -> BaseParameters:
    """Regroup given an orthonormal nullspace basis ``(10 n, k)`` in the paper convention."""
    n10 = 10 * robot.n
    t = paper_from(robot, convention)
    tinv = np.linalg.inv(t)
    b = tinv @ null_basis  # nullspace in convention coordinates
    k = b.shape[1]
    # candidate order: last body first; within a body M, MZ, MY, MX, then second moments backwards
    within = {"paper": [9, 8, 7, 6, 5, 4, 3, 2, 1, 0], "khalil": [9, 8, 7, 6, 5, 4, 3, 2, 1, 0],
              "pinocchio": [0, 3, 2, 1, 9, 8, 6, 7, 5, 4], "idyntree": [0, 3, 2, 1, 9, 8, 7, 6, 5, 4],
              "rpna": [0, 3, 2, 1, 6, 7, 5, 4, 8, 9]}[convention]
    order = np.array([10 * i + w for i in reversed(range(robot.n)) for w in within])
    dep = _choose_dependent(b, order) if k else np.zeros(0, dtype=int)
    if len(dep) < k:
        raise RuntimeError("nullspace basis is rank-deficient; orthonormalise it first")
    ind = np.setdiff1d(np.arange(n10), dep)
    kmat = -b[ind] @ np.linalg.inv(b[dep]) if k else np.zeros((len(ind), 0))
    kmat = clean(kmat)
    e = np.zeros((len(ind), n10))
    e[np.arange(len(ind)), ind] = 1.0
    e[:, dep] = kmat
    # base space basis (paper convention): orthonormal complement of the nullspace
    if k:
        u, _, _ = np.linalg.svd(null_basis, full_matrices=True)
        base_basis = u[:, k:]
    else:
        base_basis = np.eye(n10)
    # a standard parameter is unidentifiable iff its unit vector lies in the nullspace
    q, _ = np.linalg.qr(b) if k else (np.zeros((n10, 0)), None)
    unid = np.flatnonzero(np.abs(np.einsum("ij,ij->i", q, q) - 1) < 1e-9) if k else np.zeros(0, dtype=int)
    return BaseParameters(convention, parameter_names(robot, convention), ind, dep, kmat, e, unid,
                          base_basis, t)
