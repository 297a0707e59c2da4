"""Plots: an identification's measured vs predicted torques, an excitation trajectory (matplotlib)."""

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
        raise BaseparamsError("--plot needs matplotlib: pip install 'baseparams[plot]'") from None
    return plt


def trajectory_plot(excitation, path) -> Path:
    """An excitation trajectory: position, velocity and acceleration per joint, with the limits.

    Parameters
    ----------
    excitation : baseparams.excite.Excitation
        The design.
    path : str or Path
        Output file; the format from its suffix (``.png``, ``.svg``, ``.pdf``).

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
    fig, axes = plt.subplots(len(e.joints), 3, figsize=(12, 1.6 * len(e.joints) + 0.8), sharex=True, squeeze=False)
    for j, name in enumerate(e.joints):
        lo, hi, v, a, _ = e.limits[j]
        for col, (y, bounds, label) in enumerate(((e.q[:, j], (lo, hi), "q"), (e.dq[:, j], (-v, v), "dq"),
                                                 (e.ddq[:, j], (-a, a), "ddq"))):
            ax = axes[j, col]
            ax.plot(e.t, y, lw=0.8, color="C0")
            for b in bounds:
                if b == b:  # not NaN: a limit
                    ax.axhline(b, lw=0.6, ls="--", color="C3")
            ax.set_ylabel(f"{label} {name}", fontsize=7)
    for col in range(3):
        axes[-1, col].set_xlabel("t [s]")
    fig.suptitle(f"{e.robot}: {e.harmonics} harmonics, period {e.period:.4g} s, {e.criterion} {e.value:.4g} "
                 f"(condition number {e.condition_number:.4g}); dashed: limits", fontsize=9)
    fig.tight_layout()
    return _save(plt, fig, Path(path))


def _save(plt, fig, path: Path) -> Path:
    """Save and close the figure; an unwritable path is one line."""
    try:
        fig.savefig(path)
    except OSError as exc:
        raise BaseparamsError(f"--plot {path}: cannot write ({exc.strerror or exc})") from None
    finally:
        plt.close(fig)
    return path


def torque_plot(result, path) -> Path:
    """Measured and predicted torques per joint, training and validation, in one figure.

    Parameters
    ----------
    result : baseparams.identify.Identification
        An identification with its series (:attr:`Identification.series`).
    path : str or Path
        Output file; the format from its suffix (``.png``, ``.svg``, ``.pdf``).

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
    fig, axes = plt.subplots(len(joints), 1, figsize=(10, 1.8 * len(joints) + 0.6), sharex=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        for label, s in parts:
            ax.plot(s["t"], s["tau"][:, j], lw=0.8, color="0.3" if label == "train" else "0.55",
                    label=f"measured ({label})")
            ax.plot(s["t"], s["tau_hat"][:, j], lw=0.8, color="C0" if label == "train" else "C1",
                    label=f"predicted ({label})")
        ax.set_ylabel(joints[j], fontsize=8)
    axes[0, 0].legend(fontsize=7, ncol=4, loc="upper right")
    axes[-1, 0].set_xlabel("t [s]")
    j = result.to_json()
    fig.suptitle(f"{j['model']}: {j['method']}, train RMS {j['train']['rms_total']:.3g}"
                 + (f", validation RMS {j['validation']['rms_total']:.3g}" if j["validation"] else ""), fontsize=9)
    fig.tight_layout()
    return _save(plt, fig, Path(path))
