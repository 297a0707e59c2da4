"""Why a design fails, said to a user: the constraint that binds and what would loosen it.

Also the check of a sampled trajectory at the controller's rate (loops closed, keep-out, torques).
"""

from __future__ import annotations

import numpy as np

from .constraints import Evaluator, linear_rows, nonlinear_labels
from .limits import design_coordinates
from .problem import FEAS_TOL, Problem, keepout_height


def _constraint_text(prob: Problem, kind: int, joint: int) -> tuple[str, str]:
    """A constraint named for a user, and what would loosen it."""
    lim, robot = prob.limits, prob.model.robot
    name = robot.joint_names[robot.dof_body[design_coordinates(robot)[joint]]] if joint >= 0 and kind < 5 else ""
    if kind == 0:
        return (f"joint {name!r}: position range [{lim[joint, 0]:.4g}, {lim[joint, 1]:.4g}]",
                "widen its position limits (or a smaller --margin)")
    if kind == 1:
        return (f"joint {name!r}: velocity limit {lim[joint, 2]:.4g}",
                "a lower base frequency or fewer harmonics (slower motion), or a higher velocity limit")
    if kind == 2:
        return (f"joint {name!r}: acceleration limit {lim[joint, 3]:.4g}",
                "a higher --acceleration, a lower base frequency or fewer harmonics")
    if kind == 3:
        return (f"joint {name!r}: effort limit {lim[joint, 4]:.4g} N m (model torques, --torque)",
                "a lower base frequency (smaller inertial torques), or no --torque")
    if kind == 4:
        return (f"the loops' conditioning cond(J_p) <= {prob.cond_max:.3g}",
                "narrower actuated ranges around the reference assembly")
    body, z_min = prob.keepout[joint]
    return f"the keep-out of link {robot.names[body]!r} (z >= {z_min:.4g} m)", "a lower keep-out height"


def binding(prob: Problem, x: np.ndarray, at_rest: bool = False) -> str:
    """Why ``x`` is not a usable design, with what would help.

    The most violated constraint; else the ones that bind and the parameters the motion leaves
    unexcited.

    Parameters
    ----------
    prob : Problem
        The design problem.
    x : ndarray, shape ``(m k,)``
        The variables (:meth:`Problem.states`).
    at_rest : bool
        Only the constraints that bind at rest (torques, loops, keep-out): a start that fails before
        any motion.

    Returns
    -------
    str
        One sentence for an error message: the binding constraint and what would loosen it.
    """
    c, rhs, labels = linear_rows(prob)
    ev = Evaluator(prob, (c, rhs))
    out = ev(x)
    if not out["valid"]:
        kind, joint = 4, -1
        text, helps = _constraint_text(prob, kind, joint)
        return f"the loops do not close there: the binding constraint is {text}; {helps}"
    slack = np.concatenate([c @ x + rhs, out["cons"]])
    labels = labels + nonlinear_labels(prob)
    if at_rest:  # motion rows do not bind at rest
        keep = [i for i, (kind, _) in enumerate(labels) if kind >= 3]
        slack, labels = slack[keep], [labels[i] for i in keep]
    if slack.size and slack.min() < -FEAS_TOL:
        text, helps = _constraint_text(prob, *labels[int(np.argmin(slack))])
        return f"the binding constraint is {text}; {helps}"
    tight = [lab for lab in dict.fromkeys(labels[i] for i in np.flatnonzero(slack < 0.02)) if lab[0] >= 3]
    tight += _limiting(prob, x.reshape(prob.m, prob.k))
    tight = list(dict.fromkeys(tight))[:4]
    a = ev.val["a"].reshape(-1, ev.val["a"].shape[2])
    norm = np.linalg.norm(a, axis=0)
    weak = [prob.model.names[i] for i in np.flatnonzero(norm <= 1e-9 * max(norm.max(), 1e-300))]
    if not weak:
        from ..ident.estimate import excitation
        from ..numerics import StreamingQR

        weak = list(excitation(StreamingQR(prob.model.n_params).add(a).r, prob.model.names)[1])
    texts = [_constraint_text(prob, *lab) for lab in tight]
    what = f"the motion leaves {', '.join(weak[:5])}{' ...' if len(weak) > 5 else ''} unexcited"
    if not texts:
        return f"{what}; more harmonics or looser limits (a wider, faster motion) would help"
    return (f"{what}; binding: {'; '.join(t for t, _ in texts)}; what would help: "
            f"{'; '.join(dict.fromkeys(h for _, h in texts))}")


def _limiting(prob: Problem, xm: np.ndarray) -> list[tuple[int, int]]:
    """Per joint ``(kind, joint)``, tightest first: which limit bounds its oscillation most.

    Kind 0, 1, 2: position, velocity, acceleration; the room is the factor by which the
    oscillation could grow.
    """
    q, dq, ddq = (b @ xm.T for b in prob.bases)
    lim = prob.limits
    dev = q - xm[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(dev > 0, (lim[:, 1] - xm[:, 0]) / dev, np.where(dev < 0, (lim[:, 0] - xm[:, 0]) / dev, np.inf))
        ratios = np.vstack([room.min(axis=0), lim[:, 2] / np.abs(dq).max(axis=0), lim[:, 3] / np.abs(ddq).max(axis=0)])
    ratios = np.where(np.isfinite(ratios), ratios, np.inf)
    kinds = np.argmin(ratios, axis=0)
    best = ratios[kinds, np.arange(prob.m)]
    return [(int(kinds[j]), int(j)) for j in np.argsort(best) if np.isfinite(best[j])]


def violation(prob: Problem, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> str:
    """What a trajectory sampled at the controller's rate violates among the loop, keep-out and torque limits.

    Parameters
    ----------
    prob : Problem
        The design problem.
    q, dq, ddq : ndarray, shape ``(S, m)``
        The sampled states of the designed coordinates.

    Returns
    -------
    str
        The violation and what would help; ``''`` when nothing is violated.
    """
    robot = prob.model.robot
    if prob.cond_max is not None:
        from ..kinematics.loops import close_loops

        cs = close_loops(robot, q, dq, ddq, cond_max=prob.cond_max)
        if cs.kept < len(q):
            return (f"{len(q) - cs.kept} samples outside the workspace, off the assembly mode or with "
                    f"cond(J_p) > {prob.cond_max:.3g}: narrower actuated ranges would help")
    if prob.keepout is not None:
        low = keepout_height(prob, q) < prob.keepout_min - 1e-9  # (S, K)
        if low.any():
            k = int(np.argmax(low.sum(axis=0)))
            body, z_min = prob.keepout[k]
            return (f"{int(low.any(axis=1).sum())} samples with {robot.names[body]!r} (or another kept-out link) "
                    f"below its keep-out height {z_min:.4g} m: a lower keep-out height would help")
    if prob.theta is not None:
        tau = np.concatenate([prob.model.regressor(q[k:k + 4000], dq[k:k + 4000], ddq[k:k + 4000]) @ prob.theta
                              for k in range(0, len(q), 4000)])
        with np.errstate(invalid="ignore"):
            over = np.abs(tau) > prob.limits[:, 4]
        if over.any():
            names = robot.coordinate_names(design_coordinates(robot))
            return (f"{int(over.any(axis=1).sum())} samples with torques above the effort limits of "
                    f"{[n for n, o in zip(names, over.any(axis=0)) if o]}: a lower base frequency or no --torque "
                    f"would help")
    return ""
