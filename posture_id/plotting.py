"""Plots (matplotlib, imported lazily, file output with the Agg backend)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_trial"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_trial(result, path: str | Path | None = None, title: str | None = None):
    """Tilt (top) and segment sway with the body COM sway α_BS (bottom), in degrees.

    Args:
        result: a :class:`~posture_id.simulation.SimulationResult` (or anything with
            ``time``, ``tilt``, ``theta``, ``alpha``, ``segments``, ``abort_time``).
        path: PNG/PDF file to write (atomically); the figure is returned either way.
    """
    plt = _pyplot()
    fig, (ax_tilt, ax_sway) = plt.subplots(2, 1, sharex=True, figsize=(10, 6),
                                           gridspec_kw={"height_ratios": [1, 2]})
    ax_tilt.plot(result.time, np.degrees(result.tilt), color="0.3", lw=1)
    ax_tilt.set_ylabel("platform tilt (°)")
    for j, name in enumerate(result.segments):
        ax_sway.plot(result.time, np.degrees(result.theta[:, j]), lw=0.9, label=name)
    ax_sway.plot(result.time, np.degrees(result.alpha[:, 0]), "k--", lw=0.8,
                 label="body COM (α_BS)")
    if result.abort_time is not None:
        for ax in (ax_tilt, ax_sway):
            ax.axvline(result.abort_time, color="r", lw=1)
        ax_sway.text(result.abort_time, 0, " aborted", color="r")
    ax_sway.set_xlabel("time (s)")
    ax_sway.set_ylabel("segment angle in space (°)")
    ax_sway.legend(loc="upper right", ncol=len(result.segments) + 1, fontsize=8)
    for ax in (ax_tilt, ax_sway):
        ax.grid(alpha=0.3)
    fig.suptitle(title or getattr(result, "description", ""))
    fig.tight_layout()
    if path is not None:
        from posture_id.io_utils import atomic_write

        path = Path(path)
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=120, format=path.suffix[1:] or "png"))
    return fig
