"""Plots of an identification: measured vs predicted torques per joint (matplotlib)."""

from __future__ import annotations

from pathlib import Path

from ..errors import BaseparamsError


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
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise BaseparamsError("--plot needs matplotlib: pip install 'baseparams[plot]'") from None
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
    path = Path(path)
    try:
        fig.savefig(path)
    except OSError as exc:
        raise BaseparamsError(f"--plot {path}: cannot write ({exc.strerror or exc})") from None
    finally:
        plt.close(fig)
    return path
