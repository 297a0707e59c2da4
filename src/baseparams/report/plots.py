"""Static figures (matplotlib, the ``plot`` extra), for papers.

An analysis (:func:`analysis_plot`: the robot at q = 0 in 3D, the parameter grid coloured by
class, the singular values with the tolerance), an identification's measured vs predicted torques
(:func:`torque_plot`), an excitation trajectory (:func:`trajectory_plot`).
"""

from __future__ import annotations

from pathlib import Path

from ..errors import BaseparamsError


def _pyplot():
    """The pyplot module on the Agg backend, or a one-line error naming the extra."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise BaseparamsError("plotting needs matplotlib: pip install 'baseparams[plot]'") from None
    return plt


def trajectory_plot(excitation, path, robot=None, inputs=(), what: str = "plot=") -> Path:
    """An excitation trajectory: position, velocity and acceleration per joint, with the limits.

    Parameters
    ----------
    excitation : baseparams.excitation.Excitation
        The design.
    path : str or Path
        Output file; the format from its suffix (``.png``, ``.svg``, ``.pdf``).
    robot : Robot, optional
        The robot designed for: its joint types give the units (``rad``, ``rad/s``, ``rad/s^2``
        for a revolute joint, ``m``, ``m/s``, ``m/s^2`` for a prismatic one); without it the
        axes read ``rad or m``.
    inputs : iterable of str or path
        The run's input files, which the figure must not overwrite.
    what : str
        The output's role, for messages (its keyword).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    BaseparamsError
        matplotlib missing (names the extra), or an unwritable path.
    """
    plt = _pyplot()
    e = excitation
    kinds = dict(zip(robot.joint_names, robot.jtype)) if robot is not None else {}
    fig, axes = plt.subplots(len(e.joints), 3, figsize=(12, 1.6 * len(e.joints) + 0.8), sharex=True, squeeze=False)
    for j, name in enumerate(e.joints):
        lo, hi, v, a, _ = e.limits[j]
        u = {"P": "m", "R": "rad"}.get(kinds.get(name), "rad or m")
        series = ((e.q[:, j], (lo, hi), f"q [{u}]"), (e.dq[:, j], (-v, v), f"dq [{u}/s]"),
                  (e.ddq[:, j], (-a, a), f"ddq [{u}/s^2]"))
        for col, (y, bounds, label) in enumerate(series):
            ax = axes[j, col]
            ax.plot(e.t, y, lw=0.8, color="C0")
            for b in bounds:
                if b == b:  # not NaN: a limit
                    ax.axhline(b, lw=0.6, ls="--", color="C3")
            ax.set_ylabel(f"{name}\n{label}", fontsize=7)
    for col in range(3):
        axes[-1, col].set_xlabel("time [s]")
    fig.suptitle(f"{e.robot}: {e.harmonics} harmonics, period {e.period:.4g} s, {e.criterion} {e.value:.4g} "
                 f"(condition number {e.condition_number:.4g}); dashed: limits", fontsize=9)
    fig.tight_layout()
    return _save(plt, fig, Path(path), inputs, what)


def _save(plt, fig, path: Path, inputs=(), what: str = "plot=") -> Path:
    """Save and close the figure atomically, never onto an input (:func:`baseparams.files.atomic_path`)."""
    from ..files import atomic_path

    try:
        with atomic_path(path, inputs, what) as tmp:
            fig.savefig(tmp, format=path.suffix.lstrip(".").lower() or None)
    except OSError as exc:
        raise BaseparamsError(f"{what} {path}: cannot write ({exc.strerror or exc})") from None
    finally:
        plt.close(fig)
    return path


def torque_plot(result, path, inputs=(), what: str = "plot=") -> Path:
    """Measured and predicted torques per joint, training and validation, in one figure.

    A result identified from motor currents (its series' ``unit`` ``A``): the currents per motor.

    Parameters
    ----------
    result : baseparams.ident.Identification
        An identification with its series (:attr:`Identification.series`).
    path : str or Path
        Output file; the format from its suffix (``.png``, ``.svg``, ``.pdf``).
    inputs : iterable of str or path
        The run's input files, which the figure must not overwrite.
    what : str
        The output's role, for messages (its keyword).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    BaseparamsError
        matplotlib missing (names the extra), a result without series, or an unwritable path.
    """
    plt = _pyplot()
    if not result.series:
        raise BaseparamsError("this identification kept no torque series to plot")
    parts = [(k, v) for k, v in (("train", result.series["train"]), ("validation", result.series["validation"])) if v]
    joints = parts[0][1]["joints"]
    robot = result.model.robot
    kinds = dict(zip(robot.joint_names, robot.jtype))
    fig, axes = plt.subplots(len(joints), 1, figsize=(10, 1.8 * len(joints) + 0.6), sharex=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        for label, s in parts:
            ax.plot(s["t"], s["tau"][:, j], lw=0.8, color="0.3" if label == "train" else "0.55",
                    label=f"measured ({label})")
            ax.plot(s["t"], s["tau_hat"][:, j], lw=0.8, color="C0" if label == "train" else "C1",
                    label=f"predicted ({label})")
        quantity = ("current [A]" if parts[0][1].get("unit") == "A" else "force [N]" if kinds.get(joints[j]) == "P"
                    else "torque [N m]")  # a fit from motor currents: its series are the currents
        ax.set_ylabel(f"{joints[j]}\n{quantity}", fontsize=8)
    axes[0, 0].legend(fontsize=7, ncol=4, loc="upper right")
    axes[-1, 0].set_xlabel("time [s]")
    j = result.to_json()
    unit = parts[0][1].get("unit") or " or ".join(dict.fromkeys("N" if kinds.get(n) == "P" else "N m" for n in joints))
    fig.suptitle(f"{j['model']}: {j['method']}, train RMS {j['train']['rms_total']:.3g} {unit}"
                 + (f", validation RMS {j['validation']['rms_total']:.3g} {unit}" if j["validation"] else ""),
                 fontsize=9)
    fig.tight_layout()
    return _save(plt, fig, Path(path), inputs, what)


#: the grid's colour of each parameter class (the HTML report's)
CLASS_COLORS = {"identifiable": "#cfe8cf", "regrouped": "#ffe9b3", "unidentifiable": "#f4c7c7"}


def _robot_axes(ax, robot) -> None:
    """The robot at q = 0 on 3D axes: links between joint frames, joint axes (red), loop joints (blue)."""
    import numpy as np

    pos = robot.M0[:, :3, 3]
    pts = np.vstack([pos, np.zeros((1, 3))] + [lj.M[None, :3, 3] for lj in robot.loops])
    span = float(np.ptp(pts, axis=0).max()) or 1.0
    for i in range(robot.n):
        a = np.zeros(3) if robot.parent[i] < 0 else pos[robot.parent[i]]
        ax.plot(*np.c_[a, pos[i]], color="0.2", lw=2)
        if robot.jtype[i] in "RPUC":
            z = robot.M0[i, :3, :3] @ np.asarray(robot.axes[i], dtype=float).reshape(-1, 3)[0][:3]
            if np.linalg.norm(z) > 0:
                z = 0.05 * span * z / np.linalg.norm(z)
                ax.plot(*np.c_[pos[i] - z, pos[i] + z], color="C3", lw=1.5)
    for lj in robot.loops:
        m = lj.M[:3, 3]
        for b in (lj.parent, lj.child):
            ax.plot(*np.c_[np.zeros(3) if b < 0 else pos[b], m], color="C0", lw=1, ls="--")
        ax.scatter(*m, color="C0", s=25)
    center = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    for k, setter in enumerate((ax.set_xlim, ax.set_ylim, ax.set_zlim)):
        setter(center[k] - 0.55 * span, center[k] + 0.55 * span)
    ax.set_box_aspect((1, 1, 1))
    for setter, label in ((ax.set_xlabel, "x [m]"), (ax.set_ylabel, "y [m]"), (ax.set_zlabel, "z [m]")):
        setter(label, fontsize=7)
    ax.set_title(f"{robot.name} at q = 0", fontsize=9)
    ax.tick_params(labelsize=6)


def _grid_axes(ax, result, classes: dict[str, str]) -> None:
    """The parameter grid: one rectangle per standard parameter, coloured by class (``gid`` ``cell-i-k``)."""
    from matplotlib.patches import Patch, Rectangle

    from ..model import inertia

    n = result.robot.n
    for i in range(n):
        for k, name in enumerate(result.names[10 * i:10 * i + 10]):
            ax.add_patch(Rectangle((k, i), 1, 1, facecolor=CLASS_COLORS[classes[name]], edgecolor="white", lw=0.8,
                                   gid=f"cell-{i}-{k}"))
            if n <= 24:
                ax.text(k + 0.5, i + 0.5, name.rsplit(".", 1)[-1], ha="center", va="center", fontsize=5, color="0.3")
    ax.set_xlim(0, 10)
    ax.set_ylim(n, 0)
    ax.set_xticks([k + 0.5 for k in range(10)], list(inertia.NAMES.get(result.convention, range(10))), fontsize=6,
                  rotation=90)
    ax.set_yticks([i + 0.5 for i in range(n)], list(result.robot.names), fontsize=max(4, min(8, 300 // max(n, 1))))
    ax.tick_params(length=0)
    ax.set_xlabel(f"parameter ({result.convention} convention)", fontsize=7)
    ax.set_ylabel("body", fontsize=7)
    ax.set_title(f"{result.n_base} base parameters, nullity {result.nullity} ({result.status})", fontsize=9)
    ax.legend(handles=[Patch(facecolor=c, label=k) for k, c in CLASS_COLORS.items()], fontsize=6,
              loc="upper center", bbox_to_anchor=(0.5, -0.06 if n < 20 else -0.02), ncol=3, frameon=False)


def _singular_axes(ax, result) -> None:
    """The certification's singular values (log scale), the tolerance (dashed) and the rank decision."""
    cert = result.certificate
    if cert is None:
        ax.text(0.5, 0.5, "not certified (--no-verify)", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        return
    num = cert.numerical
    sv = [v if v > 0 else float("nan") for v in num.singular_values]
    ax.semilogy(range(1, len(sv) + 1), sv, ".", ms=3, color="0.2", gid="singular-values")
    ax.axhline(num.tol, ls="--", lw=0.8, color="C3", label=f"tolerance {num.tol:.2g}")
    if 0 < num.rank < len(sv):
        ax.axvline(num.rank + 0.5, ls=":", lw=0.8, color="C0", label=f"rank {num.rank}, gap {num.gap:.2g}")
    ax.legend(fontsize=6)
    ax.set_xlabel("index (largest first)", fontsize=7)
    ax.set_ylabel("singular value (sampled regressor)", fontsize=7)
    ax.set_title(f"singular values ({num.samples} samples)", fontsize=9)
    ax.tick_params(labelsize=6)


def analysis_figure(result):
    """The analysis as one figure: the robot at q = 0, the parameter grid, the singular values.

    Parameters
    ----------
    result : Analysis
        The analysis (:func:`baseparams.analyze`).

    Returns
    -------
    matplotlib.figure.Figure
        Three axes: the robot in 3D (links, joint axes in red, loop joints in blue), the grid of
        each body's ten standard parameters coloured by class (:data:`CLASS_COLORS`,
        :func:`baseparams.report.html.parameter_classes`; each cell's ``gid`` is ``cell-i-k``,
        body ``i``, parameter ``k``) and the certification's singular values with the tolerance.

    Raises
    ------
    BaseparamsError
        matplotlib missing (names the extra).
    """
    from .html import parameter_classes

    plt = _pyplot()
    n = result.robot.n
    fig = plt.figure(figsize=(13, max(4.2, 0.16 * n + 1.6)))
    gs = fig.add_gridspec(1, 3, width_ratios=(1.2, 0.9, 1.1))
    _robot_axes(fig.add_subplot(gs[0], projection="3d"), result.robot)
    _grid_axes(fig.add_subplot(gs[1]), result, parameter_classes(result))
    _singular_axes(fig.add_subplot(gs[2]), result)
    fig.suptitle(f"{result.robot.name}: {n} bodies, {10 * n} standard parameters ({result.convention})", fontsize=10)
    fig.tight_layout()
    return fig


def analysis_plot(result, path, inputs=(), what: str = "plot=") -> Path:
    """The analysis figure (:func:`analysis_figure`) written to a file.

    Parameters
    ----------
    result : Analysis
        The analysis.
    path : str or Path
        Output file; the format from its suffix (``.png``, ``.svg``, ``.pdf``).
    inputs : iterable of str or path
        The run's input files, which the figure must not overwrite.
    what : str
        The output's role, for messages (its keyword).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    BaseparamsError
        matplotlib missing (names the extra), or an unwritable path.
    """
    fig = analysis_figure(result)
    return _save(_pyplot(), fig, Path(path), inputs, what)
