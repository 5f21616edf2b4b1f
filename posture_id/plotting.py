"""Plots: the only module that imports matplotlib (a layer contract enforces it).

Figures are built as :class:`matplotlib.figure.Figure` objects, never through pyplot's
global state, so a plot neither switches the user's backend (Jupyter, Qt) nor keeps
figures alive after it returns. Every function returns the figure, writes it atomically
when given ``path``, and draws into the caller's axes when given ``ax`` (an array of axes
shaped like the figure's own layout).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write

__all__ = ["plot_trial", "plot_dataset_overview", "plot_images", "plot_fit", "plot_locked_sway",
           "plot_coverage", "plot_reliability", "plot_identifiability", "plot_intervals",
           "plot_score_grid", "plot_marker_angles", "plot_condition_frfs", "plot_robot_check"]


def _axes(ax, nrows: int, ncols: int, figsize, **kwargs):
    """(figure, axes as an (nrows, ncols) array): the caller's axes, or a new figure."""
    if ax is not None:
        axes = np.asarray(ax, dtype=object).reshape(nrows, ncols)
        return axes[0, 0].figure, axes
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    axes = fig.subplots(nrows, ncols, squeeze=False, **kwargs)
    return fig, axes


def _over_frequency(column, ylabels) -> None:
    """Label a column of axes over a log frequency axis (Hz, named on the last): each its
    y label and a grid; the first (a gain) on a log scale."""
    column[0].set_yscale("log")
    for a, label in zip(column, ylabels, strict=True):
        a.set_ylabel(label)
        a.grid(alpha=0.3, which="both")
        a.set_xscale("log")
    column[-1].set_xlabel("frequency (Hz)")


def plot_trial(result, path: str | Path | None = None, ax=None, title: str | None = None):
    """Tilt (top) and segment sway with the body COM sway α_BS (bottom), in degrees.

    Args:
        result: a :class:`~posture_id.simulation.batch.SimulationResult` (or anything with
            ``time``, ``tilt``, ``theta``, ``alpha``, ``segments``, ``abort_time``).
        path: PNG/PDF file to write (atomically); the figure is returned either way.
    """
    fig, axes = _axes(ax, 2, 1, (10, 6), sharex=True, gridspec_kw={"height_ratios": [1, 2]})
    ax_tilt, ax_sway = axes[:, 0]
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
    return _finished(fig, path)


def plot_dataset_overview(kp_normalised: np.ndarray, joints, max_sway_deg: np.ndarray,
                          kept: np.ndarray, limit_deg: float, path=None, ax=None):
    """The paper's Fig. 2 analogue.

    Args:
        kp_normalised: (K, N) K̃p of the kept trials.
        joints: (N,) module names.
        max_sway_deg: (S,) largest |segment angle| of every simulated trial, degrees.
        kept: (S,) bool. limit_deg: sway limit; rejected trials fill the last bin.
    """
    fig, axes = _axes(ax, 1, 2, (11, 4))
    ax_kp, ax_sway = axes[0]
    bins = np.linspace(-1.0, max(2.5, float(np.nanmax(kp_normalised))), 50)
    for i, joint in enumerate(joints):
        ax_kp.hist(kp_normalised[:, i], bins=bins, histtype="step", lw=1.2, label=joint)
    ax_kp.set_xlabel("normalised Kp, (Kp − Kp₀)/Kp₀")
    ax_kp.set_ylabel("kept trials")
    ax_kp.legend()
    ax_kp.set_title("Kp of the stable simulations")
    width = limit_deg / 24
    edges = np.arange(0, limit_deg + 1e-9, width)
    counts, _ = np.histogram(np.clip(max_sway_deg[kept], 0, limit_deg), bins=edges)
    ax_sway.bar(edges[:-1], counts, width=width, align="edge", color="C0", label="kept")
    ax_sway.bar([limit_deg], [int((~kept).sum())], width=width, align="edge", color="C3",
                label=f"aborted at {limit_deg:g}°")
    ax_sway.set_xlabel("maximum segment sway (°)")
    ax_sway.set_ylabel("simulations")
    ax_sway.legend()
    ax_sway.set_title(f"{int((~kept).sum())} of {len(kept)} aborted")
    return _finished(fig, path)


def plot_images(modular: np.ndarray, monolithic: np.ndarray, joints, path=None, ax=None):
    """One trial's modular images (N rows × 3 channels) and monolithic channels."""
    n = modular.shape[0]
    cols = max(3, monolithic.shape[0])
    fig, axes = _axes(ax, n + 1, cols, (2.2 * cols, 2.2 * (n + 1)))
    names = ["log|S| above", "log|S| below", "phase difference"]

    def shown(image: np.ndarray, phase: bool) -> np.ndarray:
        return image if phase else np.log10(image + 1e-12)

    for i in range(n):
        for c in range(cols):
            ax = axes[i, c]
            ax.axis("off")
            if c < 3:
                ax.imshow(shown(modular[i, c], c == 2), origin="lower", aspect="auto",
                          cmap="twilight" if c == 2 else "viridis")
                ax.set_title(f"{joints[i]}: {names[c]}", fontsize=8)
    for c in range(cols):
        ax = axes[n, c]
        ax.axis("off")
        if c < monolithic.shape[0]:
            ax.imshow(shown(monolithic[c], c >= n), origin="lower", aspect="auto",
                      cmap="twilight" if c >= n else "viridis")
            ax.set_title(f"monolithic channel {c}", fontsize=8)
    fig.suptitle("spectrogram images (frequency 0–10 Hz up, time right; magnitudes log10)")
    return _finished(fig, path)


def _finished(fig, path):
    """``fig`` laid out tight and saved to ``path`` (when given): what every plot returns."""
    fig.tight_layout()
    _save(fig, path)
    return fig


def _save(fig, path) -> None:
    if path is not None:
        path = Path(path)
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=110, format=path.suffix[1:] or "png"))


def plot_fit(result, path=None, ax=None):
    """Recorded (grey) versus fitted (colour) sway per segment, degrees."""
    n = len(result.segments)
    fig, axes = _axes(ax, n, 1, (10, 2.2 * n + 0.8), sharex=True)
    for j, name in enumerate(result.segments):
        ax = axes[j, 0]
        ax.plot(result.time, np.degrees(result.recorded[:, j]), color="0.6", lw=1.4,
                label="recorded")
        ax.plot(result.time, np.degrees(result.fitted[:, j]), color=f"C{j}", lw=0.8,
                label="fitted")
        ax.set_ylabel(f"{name} (°)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    fig.suptitle(f"DEC fit: RMS {result.rms_deg:.4f}°, classes {'/'.join(result.classes)}")
    return _finished(fig, path)


def plot_loss_curves(history, path=None, ax=None):
    """Training and validation loss per epoch (log scale), the best epoch marked.

    Args:
        history: rows with ``epoch``, ``train_loss``, ``validation_loss``.
    """
    fig, axes = _axes(ax, 1, 1, (7, 4))
    a = axes[0, 0]
    epochs = [r["epoch"] for r in history]
    a.plot(epochs, [r["train_loss"] for r in history], "o-", ms=3, label="training")
    a.plot(epochs, [r["validation_loss"] for r in history], "o-", ms=3, label="validation")
    if history:
        best = min(history, key=lambda r: r["validation_loss"])
        a.axvline(best["epoch"], color="0.5", lw=0.8, ls="--",
                  label=f"best: epoch {best['epoch']}")
    a.set_yscale("log")
    a.set_xlabel("epoch")
    a.set_ylabel("loss")
    a.grid(alpha=0.3, which="both")
    a.legend()
    return _finished(fig, path)


def plot_shares(labels, shares_pct, expected_pct: float, xlabel: str, expected_label: str,
                path=None, ax=None):
    """Horizontal bars, one share (%) per label, and the share expected as a line."""
    fig, axes = _axes(ax, 1, 1, (7, 0.35 * len(labels) + 1.5))
    a = axes[0, 0]
    a.barh(range(len(labels)), shares_pct, color="C0")
    a.axvline(expected_pct, color="C3", lw=1, ls="--", label=expected_label)
    a.set_yticks(range(len(labels)), labels, fontsize=7)
    a.invert_yaxis()
    a.set_xlabel(xlabel)
    a.grid(alpha=0.3, axis="x")
    a.legend(fontsize=8)
    return _finished(fig, path)


def plot_parameter_errors(names, mean, spread, path=None, ax=None, title=""):
    """The paper's Fig. 5: mean absolute error of each normalised parameter with its spread.

    Args:
        names: (P,) labels. mean, spread: (P,) mean and standard deviation of |error|.
    """
    fig, axes = _axes(ax, 1, 1, (max(6, 0.6 * len(names)), 4))
    a = axes[0, 0]
    x = np.arange(len(names))
    a.bar(x, mean, yerr=spread, capsize=3, color="C0", alpha=0.8)
    a.set_xticks(x, names, rotation=45, ha="right")
    a.set_ylabel("|error| (normalised units)")
    a.set_title(title or "absolute error per parameter: mean ± standard deviation")
    a.grid(alpha=0.3, axis="y")
    return _finished(fig, path)


def plot_identification_error(parameter_mse, error, path=None, ax=None, ylabel="", title=""):
    """The paper's Fig. 6: identification error against the parameter MSE, per trial."""
    fig, axes = _axes(ax, 1, 1, (6, 4.5))
    a = axes[0, 0]
    a.loglog(parameter_mse, error, "o", ms=3, alpha=0.6)
    a.set_xlabel("parameter MSE (normalised)")
    a.set_ylabel(ylabel)
    a.set_title(title)
    a.grid(alpha=0.3, which="both")
    return _finished(fig, path)


def plot_identification(result, path=None, ax=None):
    """Recorded (grey) versus re-simulated (colour) sway of every segment and of the body
    COM, degrees (the paper's Fig. 7)."""
    names = [*(s.segment for s in result.segments), "body COM (α_BS)"]
    n = len(names)
    fig, axes = _axes(ax, n, 1, (10, 1.9 * n + 0.9), sharex=True)
    recorded = np.column_stack([result.recorded, result.sway_recorded])
    simulated = np.column_stack([result.resimulated, result.sway_resimulated])
    for j, name in enumerate(names):
        a = axes[j, 0]
        a.plot(result.time, np.degrees(recorded[:, j]), color="0.6", lw=1.4, label="recorded")
        a.plot(result.time, np.degrees(simulated[:, j]), color=f"C{j}", lw=0.8,
               label="re-simulated")
        a.set_ylabel(f"{name} (°)")
        a.grid(alpha=0.3)
        a.legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    fig.suptitle(f"{result.method.value}: classes {'/'.join(result.classes)}, E_rel "
                 f"{100 * result.e_rel:.2f} %")
    return _finished(fig, path)


def plot_benchmark(groups: dict, path=None, ax=None):
    """Box plots of E_rel (left, log scale) and seconds per recording (right) per group.

    Args:
        groups: label → (E_rel values, seconds values).
    """
    fig, axes = _axes(ax, 1, 2, (max(8, 1.1 * len(groups) + 3), 4.5))
    labels = list(groups)
    for a, k, title in ((axes[0, 0], 0, "E_rel of the re-simulated body sway"),
                        (axes[0, 1], 1, "seconds identifying a recording")):
        a.boxplot([np.maximum(groups[g][k], 1e-6) for g in labels], tick_labels=labels)
        a.set_yscale("log")
        a.set_title(title)
        a.grid(alpha=0.3, which="both", axis="y")
        a.tick_params(axis="x", labelsize=7)
    return _finished(fig, path)


def plot_frf(result, path=None, ax=None):
    """Gain (deg/deg), phase (degrees) and coherence against frequency (log axis), one
    line per channel: the FRF plots of the posture literature."""
    fig, axes = _axes(ax, 3, 1, (8, 8), sharex=True)
    f = result.frequencies_hz
    for m, name in enumerate(result.channels):
        style = {"color": f"C{m}", "marker": "o", "ms": 3, "lw": 1, "label": name}
        axes[0, 0].plot(f, result.gain[:, m], **style)
        axes[1, 0].plot(f, result.phase_deg[:, m], **style)
        if result.coherence is not None:
            axes[2, 0].plot(f, result.coherence[:, m], **style)
    _over_frequency(axes[:, 0], ("gain (deg/deg)", "phase (°)", "coherence γ²"))
    axes[2, 0].set_ylim(0, 1.05)
    if result.coherence is None:
        axes[2, 0].text(0.5, 0.5, "one cycle, no bands: nothing averaged", ha="center",
                        transform=axes[2, 0].transAxes)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"FRF of {result.name} relative to the tilt ({result.cycles} cycle(s) "
                 f"of {result.period_s:g} s)")
    return _finished(fig, path)


def plot_locked_sway(time, recorded, locked, fits: dict, frequencies_hz, recorded_spectrum,
                     excited, noise, path=None, ax=None, title=""):
    """Why raw sway fails: the recorded body COM sway against its stimulus-locked part and
    fits (top), the sway's spectrum at the excited and the empty harmonics with the noise
    level estimated there (bottom).

    Args:
        time: (S,) s. recorded, locked: (S,) body COM sway, degrees (with and without the
            noise). fits: label → (S,) the sway each fit's parameters give without noise.
        frequencies_hz: (H,) harmonics of the stimulus cycle. recorded_spectrum: (H,) |X|
            of the recording's drift-free cycle average, degrees. excited: (H,) bool.
        noise: (K,) the noise level estimated at the excited harmonics, degrees.
    """
    fig, axes = _axes(ax, 2, 1, (10, 7))
    top, bottom = axes[:, 0]
    top.plot(time, recorded, color="0.6", lw=0.7, label="recorded (motor + sensor noise)")
    top.plot(time, locked, "k", lw=1.2, label="stimulus-locked response (truth)")
    for (label, sway), style in zip(fits.items(), ("C3--", "C0-", "C2-."), strict=False):
        top.plot(time, sway, style, lw=1.0, label=label)
    top.set_xlabel("time (s)")
    top.set_ylabel("body COM sway (°)")
    top.legend(loc="upper right", fontsize=8)
    top.grid(alpha=0.3)
    f = np.asarray(frequencies_hz)
    spectrum = np.asarray(recorded_spectrum)
    bottom.loglog(f[~excited], spectrum[~excited], ".", color="0.6", ms=3,
                  label="empty harmonics (noise only)")
    bottom.loglog(f[excited], spectrum[excited], "C3.", ms=4, label="excited harmonics")
    bottom.loglog(f[excited][: len(noise)], np.asarray(noise) * np.sqrt(2), "C0-", lw=1,
                  label="noise level estimated (σ√2)")
    bottom.set_xlabel("frequency (Hz)")
    bottom.set_ylabel("|cycle average DFT| (°)")
    bottom.legend(loc="lower left", fontsize=8)
    bottom.grid(alpha=0.3, which="both")
    fig.suptitle(title)
    return _finished(fig, path)


def plot_coverage(levels, curves: dict, labels, band, path=None, ax=None):
    """Empirical against nominal coverage (left) and the 90 % coverage of every parameter
    (right).

    Args:
        levels: (K,) nominal levels. curves: name → (K, P) coverage of P parameters.
        labels: (P,) parameter names. band: (low, high) target band of the 90 % level.
    """
    fig, axes = _axes(ax, 1, 2, (13, 5), gridspec_kw={"width_ratios": [1, 2]})
    left, right = axes[0, 0], axes[0, 1]
    levels = np.asarray(levels)
    left.plot([0.45, 1], [0.45, 1], color="0.5", lw=0.8, ls="--", label="ideal")
    k90 = int(np.argmin(np.abs(levels - 0.9)))
    width = 0.8 / max(len(curves), 1)
    for i, (name, cov) in enumerate(curves.items()):
        cov = np.asarray(cov)
        mean = cov.mean(axis=1)
        left.errorbar(levels, mean, yerr=np.clip([mean - cov.min(axis=1),
                                                  cov.max(axis=1) - mean], 0, None),
                      marker="o", capsize=3, label=name, color=f"C{i}")
        right.plot(np.arange(cov.shape[1]) + (i - (len(curves) - 1) / 2) * width, cov[k90],
                   "o", color=f"C{i}", label=name, zorder=3)
    left.set_xlabel("nominal coverage")
    left.set_ylabel("empirical coverage (mean, min–max over parameters)")
    left.legend(fontsize=7)
    left.grid(alpha=0.3)
    right.axhspan(*band, color="0.88", label=f"target {band[0]:.0%}–{band[1]:.0%}", zorder=0)
    right.axhline(levels[k90], color="0.5", lw=0.8, ls="--", zorder=1)
    lowest = min((float(np.min(np.asarray(c)[k90])) for c in curves.values()), default=0.8)
    right.set_ylim(max(0.0, min(0.8, lowest - 0.02)), 1.0)
    right.set_xticks(np.arange(len(labels)), labels, rotation=60, ha="right", fontsize=7)
    right.set_ylabel("coverage of the 90 % intervals")
    right.legend(fontsize=7, loc="lower right")
    right.grid(alpha=0.3, axis="y")
    return _finished(fig, path)


def plot_reliability(diagrams: dict, path=None, ax=None):
    """Reliability diagrams (top: observed frequency against mean predicted probability per
    bin) and how many samples each bin holds (bottom, log scale: a bin of a handful of
    samples scatters widely).

    Args:
        diagrams: name → {"mean_probability", "frequency", "count"} (bins, NaN when empty).
    """
    fig, axes = _axes(ax, 2, 1, (6.5, 7.5), gridspec_kw={"height_ratios": [3, 1.3]})
    top, bottom = axes[0, 0], axes[1, 0]
    top.plot([0, 1], [0, 1], color="0.5", lw=0.8, ls="--", label="perfectly calibrated")
    width = 0.8 / max(len(diagrams), 1) / 10
    for i, (name, d) in enumerate(diagrams.items()):
        p = np.asarray(d["mean_probability"], dtype=float)
        f = np.asarray(d["frequency"], dtype=float)
        n = np.asarray(d["count"], dtype=float)
        used = n > 0
        top.plot(p[used], f[used], marker="o", color=f"C{i}", label=name)
        centres = (np.arange(len(n)) + 0.5) / len(n)
        bottom.bar(centres + (i - (len(diagrams) - 1) / 2) * width, np.where(n > 0, n, np.nan),
                   width, color=f"C{i}")
    top.set_ylabel("observed frequency of C = +1")
    top.set_title("class probabilities")
    top.legend(fontsize=7)
    top.grid(alpha=0.3)
    bottom.set_yscale("log")
    bottom.set_xlim(0, 1)
    bottom.set_xlabel("predicted P(C = +1, controls the COM)")
    bottom.set_ylabel("samples per bin")
    bottom.grid(alpha=0.3, axis="y")
    return _finished(fig, path)


def plot_identifiability(ratios: dict, labels, path=None, ax=None):
    """Width of the 90 % intervals against the prior's, per parameter.

    Args:
        ratios: name → (P,) ratios. labels: (P,) parameter names.
    """
    fig, axes = _axes(ax, 1, 1, (12, 4.5))
    a = axes[0, 0]
    width = 0.8 / max(len(ratios), 1)
    for i, (name, r) in enumerate(ratios.items()):
        a.bar(np.arange(len(labels)) + (i - (len(ratios) - 1) / 2) * width, r, width,
              color=f"C{i}", label=name)
    for y, text in ((0.25, "well determined below"), (0.75, "not determined above")):
        a.axhline(y, color="0.4", lw=0.8, ls="--")
        a.text(len(labels) - 0.5, y, text, ha="right", va="bottom", fontsize=7)
    a.set_xticks(np.arange(len(labels)), labels, rotation=60, ha="right", fontsize=7)
    a.set_ylabel("90 % interval width / prior's")
    a.legend(fontsize=7)
    a.grid(alpha=0.3, axis="y")
    return _finished(fig, path)


def plot_intervals(joints, estimate, lower, upper, words, prior, level: float, method: str,
                   path=None, ax=None):
    """Each module's Kp, Ki, Kd, Δ with its interval, relative to the defaults (p̃), the
    prior's interval shaded; colour by how well the recording determines it.

    Args:
        joints: (N,) module names. estimate, lower, upper: (N, 4) normalised p̃.
        words: (N, 4) "well determined", "partly determined" or "not determined".
        prior: (low, high) the prior's interval at ``level``. method: one line.
    """
    n = len(joints)
    fig, axes = _axes(ax, 1, 1, (8, 1.8 * n + 1.5))
    a = axes[0, 0]
    a.axvspan(*prior, color="0.92", label=f"prior's {level:.0%} interval")
    colours = {"well determined": "C0", "partly determined": "C1", "not determined": "C3"}
    ticks = []
    y = 0.0
    for i, joint in enumerate(joints):
        for k, name in enumerate(("Kp", "Ki", "Kd", "delay")):
            a.plot([lower[i][k], upper[i][k]], [y, y], color=colours.get(words[i][k], "0.5"),
                   lw=3)
            a.plot(estimate[i][k], y, "o", color="k", ms=4)
            ticks.append((y, f"{joint} {name}"))
            y -= 1
        y -= 0.5
    a.set_yticks([t for t, _ in ticks], [s for _, s in ticks], fontsize=8)
    a.axvline(0, color="0.5", lw=0.8)
    a.set_xlabel("p / p_default − 1")
    a.set_title(f"{level:.0%} intervals ({method})\nblue: well determined, orange: partly, "
                "red: not determined by this recording", fontsize=9)
    a.legend(fontsize=7, loc="lower right")
    a.grid(alpha=0.3, axis="x")
    return _finished(fig, path)


def plot_batch(time, tilt, alpha_bs, stable, description: str = "", path=None, ax=None):
    """Tilt (top) and every trial's body COM sway α_BS (bottom), in degrees; trials that
    left the sway limit in red.

    Args:
        time: (S,) s. tilt: (S,) rad. alpha_bs: (B, S) rad, NaN after an abort.
        stable: (B,) bool.
    """
    fig, axes = _axes(ax, 2, 1, (10, 6), sharex=True, gridspec_kw={"height_ratios": [1, 2]})
    ax_tilt, ax_sway = axes[:, 0]
    ax_tilt.plot(time, np.degrees(tilt), color="0.3", lw=1)
    ax_tilt.set_ylabel("platform tilt (°)")
    for sway, kept in zip(alpha_bs, stable, strict=True):
        ax_sway.plot(time, np.degrees(sway), lw=0.6, alpha=0.5, color="C0" if kept else "C3")
    ax_sway.set_xlabel("time (s)")
    ax_sway.set_ylabel("body COM sway α_BS (°)")
    for a in (ax_tilt, ax_sway):
        a.grid(alpha=0.3)
    fig.suptitle(f"{description}: {len(stable)} trials, {int(np.sum(stable))} stable "
                 "(blue), the others red")
    return _finished(fig, path)


def plot_cohort(names, joints, kp, e_rel, path=None, ax=None):
    """Each identified recording's Kp per module (left) and E_rel (right).

    Args:
        names: (R,) recordings. joints: (N,) modules. kp: (R, N) N·m/rad.
        e_rel: (R,) fraction (∞ drawn at the top: the re-simulation fell).
    """
    fig, axes = _axes(ax, 1, 2, (11, 0.3 * len(names) + 2.5))
    a_kp, a_rel = axes[0]
    y = np.arange(len(names))
    for j, joint in enumerate(joints):
        a_kp.plot(np.asarray(kp)[:, j], y, "o", label=joint)
    a_kp.set_yticks(y, names, fontsize=7)
    a_kp.set_xlabel("Kp (N·m/rad)")
    a_kp.legend(fontsize=8)
    shown = np.minimum(np.asarray(e_rel, dtype=float), 1.0) * 100
    a_rel.barh(y, shown, color=["C3" if not np.isfinite(e) else "C0" for e in e_rel])
    a_rel.set_yticks(y, [""] * len(names))
    a_rel.set_xlabel("E_rel (%; fallen re-simulations red, at 100)")
    for a in (a_kp, a_rel):
        a.grid(alpha=0.3, axis="x")
        a.invert_yaxis()
    return _finished(fig, path)


def plot_score_grid(rows: list[str], columns: list[str], panels: dict, path=None, ax=None):
    """Heat maps, one per panel: ``panels`` maps a title to ((rows, columns) values,
    (low, high) colour range, format) — e.g. the universal network's classes and Kp error
    per body family and stimulus."""
    fig, axes = _axes(ax, 1, len(panels), (4.2 * len(panels) + 1, 0.45 * len(rows) + 1.8))
    for a, (title, (values, (low, high), fmt)) in zip(axes[0], panels.items(), strict=True):
        values = np.asarray(values, dtype=float)
        image = a.imshow(values, vmin=low, vmax=high, cmap="viridis", aspect="auto")
        a.set_xticks(range(len(columns)), columns, rotation=45, ha="right", fontsize=7)
        a.set_yticks(range(len(rows)), rows if a is axes[0, 0] else [""] * len(rows),
                     fontsize=7)
        for (i, j), v in np.ndenumerate(values):
            if np.isfinite(v):
                a.text(j, i, format(v, fmt), ha="center", va="center", fontsize=6,
                       color="white" if v < (low + high) / 2 else "black")
        a.set_title(title, fontsize=9)
        fig.colorbar(image, ax=a, shrink=0.8)
    return _finished(fig, path)


def plot_model_frfs(frequencies_hz, recorded, models: dict, coherence, title: str = "",
                    path=None, ax=None):
    """The recording's locked FRF (gain, phase; points) with models' FRFs over it (lines),
    and its coherence: the figure of an FRF fit (IC) or a model comparison.

    Args:
        frequencies_hz: (K,) Hz. recorded: (K,) complex tilt → COM sway. models: label →
            (K,) complex. coherence: (K,) 0–1.
    """
    fig, axes = _axes(ax, 3, 1, (8, 8), sharex=True)
    f = np.asarray(frequencies_hz)
    axes[0, 0].plot(f, np.abs(recorded), "o", ms=3, color="k", label="recording")
    axes[1, 0].plot(f, np.degrees(np.unwrap(np.angle(recorded))), "o", ms=3, color="k")
    for k, (label, h) in enumerate(models.items()):
        axes[0, 0].plot(f, np.abs(h), color=f"C{k}", lw=1.5, label=label)
        axes[1, 0].plot(f, np.degrees(np.unwrap(np.angle(h))), color=f"C{k}", lw=1.5)
    axes[2, 0].plot(f, coherence, "o-", ms=3, lw=1, color="k")
    _over_frequency(axes[:, 0], ("gain (deg/deg)", "phase (°)", "locked share γ²"))
    axes[2, 0].set_ylim(0, 1.05)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(title)
    return _finished(fig, path)


def plot_condition_frfs(conditions, trials, curves: dict, title: str = "", path=None,
                        ax=None):
    """Several trials of one subject fitted jointly: every trial's recorded locked FRF of
    the COM sway (gain, phase; points, coloured by its condition, one marker per trial of
    a condition) with the model's FRF in each condition over them (lines, the same
    colour): the figure of a joint fit.

    Args:
        conditions: (C,) the condition labels (colours C0, C1, ... in this order).
        trials: per trial (condition, frequencies_hz (K,), recorded (K,) complex, model
            (K,) complex at those frequencies).
        curves: condition → ((F,) Hz, (F,) complex): the model's FRF in that condition.
    """
    fig, axes = _axes(ax, 2, 1, (8, 6.5), sharex=True)
    gain, phase = axes[0, 0], axes[1, 0]
    colour = {c: f"C{k}" for k, c in enumerate(conditions)}
    unwrapped = {}
    for condition in conditions:
        f, h = curves[condition]
        unwrapped[condition] = (np.asarray(f), np.degrees(np.unwrap(np.angle(h))))
        gain.plot(f, np.abs(h), color=colour[condition], lw=1.5, label=f"model, {condition}")
        phase.plot(*unwrapped[condition], color=colour[condition], lw=1.5)
    seen: dict = {}
    markers = "osD^v<>ph*"
    for condition, f, recorded, _ in trials:
        k = seen[condition] = seen.get(condition, -1) + 1
        f = np.asarray(f)
        degrees = np.degrees(np.angle(recorded))
        near = np.interp(f, *unwrapped[condition])  # the curve's branch of the phase
        degrees = degrees + 360.0 * np.round((near - degrees) / 360.0)
        style = {"ls": "none", "marker": markers[k % len(markers)], "ms": 5,
                 "mfc": colour[condition], "mec": "k", "mew": 0.5}
        gain.plot(f, np.abs(recorded), **style,
                  label=f"recorded, {condition}" if k == 0 else None)
        phase.plot(f, degrees, **style)
    _over_frequency((gain, phase), ("gain (deg/deg)", "phase (°)"))
    gain.legend(fontsize=8)
    fig.suptitle(title)
    return _finished(fig, path)


def plot_model_comparison(frequencies_hz, stimulated, recorded, models: dict, noise,
                          title: str = "", path=None, ax=None):
    """Two models against one recording's locked sway at every compared harmonic: the
    amplitudes (top; stimulated harmonics as dots, the others as crosses, the noise level
    shaded) and each model's residual in units of the noise there (bottom).

    Args:
        frequencies_hz: (K,) Hz. stimulated: (K,) bool. recorded: (K,) complex (deg).
        models: label → (K,) complex (deg). noise: (K,) the noise level σ (deg).
    """
    fig, axes = _axes(ax, 2, 1, (9, 7), sharex=True)
    f = np.asarray(frequencies_hz)
    on, off = np.asarray(stimulated), ~np.asarray(stimulated)
    top, bottom = axes[0, 0], axes[1, 0]
    top.fill_between(f, 1e-9, np.asarray(noise), color="0.85", label="noise level")
    top.plot(f[on], np.abs(recorded[on]), "o", ms=4, color="k", label="recording, stimulated")
    top.plot(f[off], np.abs(recorded[off]), "x", ms=4, color="k", label="recording, others")
    for k, (label, spectrum) in enumerate(models.items()):
        top.plot(f, np.abs(spectrum), "_", ms=7, mew=1.5, color=f"C{k}", label=label)
        bottom.plot(f, np.abs(spectrum - recorded) / noise, ".", ms=5, color=f"C{k}",
                    label=label)
    top.set_yscale("log")
    top.set_ylim(bottom=max(1e-6, 0.3 * float(np.min(noise))))
    top.set_ylabel("locked COM sway (deg)")
    bottom.axhline(1.0, color="0.4", lw=0.8, ls="--")
    bottom.set_yscale("log")
    bottom.set_ylabel("|model − recording| / noise")
    bottom.set_xscale("log")
    bottom.set_xlabel("frequency (Hz)")
    for a in (top, bottom):
        a.grid(alpha=0.3, which="both")
    top.legend(fontsize=8)
    bottom.legend(fontsize=8)
    fig.suptitle(title)
    return _finished(fig, path)


def plot_delta_bic(names, delta_bic, preferred, margin: float = 10.0, path=None, ax=None):
    """ΔBIC (IC − DEC) per recording, the ±``margin`` band of "undecided" shaded."""
    fig, axes = _axes(ax, 1, 1, (8, 0.35 * len(names) + 1.5))
    a = axes[0, 0]
    colours = {"dec": "C0", "ic": "C1", "undecided": "0.5"}
    y = np.arange(len(names))
    band = np.log10(1 + margin)
    a.axvspan(-band, band, color="0.9")
    a.barh(y, np.sign(delta_bic) * np.log10(1 + np.abs(delta_bic)),
           color=[colours.get(p, "0.5") for p in preferred])
    a.set_yticks(y, names)
    a.set_xlabel("sign(ΔBIC)·log10(1 + |ΔBIC|), ΔBIC = BIC(IC) − BIC(DEC): > 0 favours DEC")
    a.grid(alpha=0.3, axis="x")
    return _finished(fig, path)


def plot_reweighting(names, w_by_part, bic: dict, path=None, ax=None):
    """The proprioceptive weight W the IC model needed at each amplitude (left) and both
    models' BIC over every part (right, lower is better)."""
    fig, axes = _axes(ax, 1, 2, (9, 3.5))
    left, right = axes[0, 0], axes[0, 1]
    left.plot(range(1, len(w_by_part) + 1), w_by_part, "o-", color="C1")
    left.set_xticks(range(1, len(w_by_part) + 1), [f"part {k}" for k in
                                                    range(1, len(w_by_part) + 1)])
    left.set_ylim(0, 1)
    left.set_ylabel("IC proprioceptive weight W")
    right.bar(["DEC", "IC"], [bic["dec"], bic["ic"]], color=["C0", "C1"])
    right.set_ylabel("BIC (lower is better)")
    for a in (left, right):
        a.grid(alpha=0.3)
    fig.suptitle(" + ".join(str(n) for n in names))
    return _finished(fig, path)


def plot_norm_test(result, path=None, ax=None):
    """A tested FRF against a norm: gain and phase with the members' (top two), its PIR in
    the norm's prediction band (bottom), one column per channel."""
    norm = result.norm
    m = len(norm.channels)
    fig, axes = _axes(ax, 3, m, (5 * m, 8))
    f = norm.frequencies_hz
    tested = np.asarray(result.response).reshape(len(f), m)
    for c, name in enumerate(norm.channels):
        mean = (norm.mean_re_im[: len(f) * m] + 1j * norm.mean_re_im[len(f) * m:]).reshape(
            len(f), m)[:, c]
        axes[0, c].plot(f, np.abs(mean), "k-", label="norm mean")
        axes[0, c].plot(f, np.abs(tested[:, c]), "o-", color="C3", label=result.name)
        axes[1, c].plot(f, np.degrees(np.unwrap(np.angle(mean))), "k-")
        axes[1, c].plot(f, np.degrees(np.unwrap(np.angle(tested[:, c]))), "o-", color="C3")
        axes[0, c].set_xscale("log")
        axes[0, c].set_yscale("log")
        axes[1, c].set_xscale("log")
        axes[0, c].set_title(name)
        axes[0, c].set_ylabel("gain")
        axes[1, c].set_ylabel("phase (°)")
        axes[1, c].set_xlabel("frequency (Hz)")
        if result.pir is not None:
            s = len(norm.pir_t)
            mean_pir = norm.pir_mean[c * s : (c + 1) * s]
            band = norm.prediction_constant * norm.pir_sd[c * s : (c + 1) * s]
            axes[2, c].fill_between(norm.pir_t, mean_pir - band, mean_pir + band,
                                    color="0.85", label=f"{100 * norm.level:.0f} % prediction")
            axes[2, c].plot(norm.pir_t, mean_pir, "k-", lw=1)
            axes[2, c].plot(norm.pir_t, result.pir[c * s : (c + 1) * s], color="C3", lw=1)
            axes[2, c].set_xlabel("t (s)")
            axes[2, c].set_ylabel("PIR")
            axes[2, c].legend(fontsize=7)
        axes[0, c].legend(fontsize=7)
    fig.suptitle(f"{result.name}: human-likeness {result.human_likeness:.2f}")
    return _finished(fig, path)


def plot_group_difference(result, path=None, ax=None):
    """The difference of two groups' mean PIRs with its confidence band, per channel."""
    m = len(result.channels)
    fig, axes = _axes(ax, m, 1, (8, 2.8 * m))
    for c, name in enumerate(result.channels):
        a = axes[c, 0]
        a.fill_between(result.t, result.low[c], result.high[c], color="0.85",
                       label=f"{100 * result.level:.0f} % band")
        a.plot(result.t, result.difference[c], color="C0", label="mean A − mean B")
        a.axhline(0, color="k", lw=0.6)
        a.set_ylabel(f"{name} PIR difference")
        a.legend(fontsize=7)
    axes[-1, 0].set_xlabel("t (s)")
    fig.suptitle(f"{result.names[0]} − {result.names[1]}: p = {result.p_value:.4f}")
    return _finished(fig, path)


def plot_parameter_differences(result, path=None, ax=None):
    """Each parameter's difference between two groups, relative to group B's mean, with
    its confidence interval; p < 0.05 in red."""
    rows = result.rows
    fig, axes = _axes(ax, 1, 1, (7, 0.3 * len(rows) + 1.5))
    a = axes[0, 0]
    for k, r in enumerate(rows):
        scale = abs(r["mean_b"]) or 1.0
        colour = "C3" if r["p_value"] < 0.05 else "C0"
        a.plot([100 * r["low"] / scale, 100 * r["high"] / scale], [k, k], color=colour)
        a.plot(100 * r["difference"] / scale, k, "o", color=colour)
    a.axvline(0, color="k", lw=0.6)
    a.set_yticks(range(len(rows)), [r["parameter"] for r in rows], fontsize=7)
    a.set_xlabel(f"{result.names[0]} − {result.names[1]} (% of {result.names[1]}'s mean)")
    return _finished(fig, path)


def plot_marker_angles(angles, path=None, ax=None):
    """A motion-capture trial's marker route checked by eye: the raw traces of every point
    used (forward and vertical coordinates about their means, mm; gaps filled shaded)
    beside the angles derived from them (degrees).

    Args:
        angles: a :class:`~posture_id.motion_capture.angles.MarkerAngles`.
    """
    fig, axes = _axes(ax, 3, 1, (10, 8), sharex=True)
    time = angles.time
    forward = angles.mapping.axes.forward_vector
    vertical = angles.mapping.axes.vertical_vector
    for name, track in angles.points.items():
        axes[0, 0].plot(time, 1e3 * (track @ forward - np.mean(track @ forward)), lw=0.7,
                        label=name)
        axes[1, 0].plot(time, 1e3 * (track @ vertical - np.mean(track @ vertical)), lw=0.7,
                        label=name)
    for gap in angles.gaps:
        for a in axes[:2, 0]:
            a.axvspan(time[gap.start], time[min(gap.stop, len(time) - 1)], color="C3",
                      alpha=0.2)
    axes[0, 0].set_ylabel(f"forward ({angles.mapping.axes.forward}) about mean (mm)")
    axes[1, 0].set_ylabel(f"vertical ({angles.mapping.axes.vertical}) about mean (mm)")
    axes[0, 0].legend(fontsize=7, ncol=4, loc="upper right")
    for k, name in enumerate(angles.mapping.segment_labels):
        axes[2, 0].plot(time, np.degrees(angles.theta[:, k]), lw=0.9, label=name)
    if angles.tilt is not None:
        axes[2, 0].plot(time, np.degrees(angles.tilt), color="0.3", lw=0.9, label="tilt")
    axes[2, 0].set_ylabel("derived angle (°)")
    axes[2, 0].set_xlabel("time (s)")
    axes[2, 0].legend(fontsize=7, ncol=4, loc="upper right")
    for a in axes[:, 0]:
        a.grid(alpha=0.3)
    fig.suptitle(f"{angles.trial.path.name}: markers (shaded: gaps filled) and the angles "
                 "derived from them")
    return _finished(fig, path)


def plot_paired_difference(result, path=None, ax=None):
    """Two conditions within the same subjects (:class:`~posture_id.norms.paired.
    PairedComparison`): per channel (columns), the mean gain ratio B/A (%, top) and the
    mean phase difference B − A (degrees, bottom) at each frequency (Hz, log axis) with
    their intervals; the frequencies whose p-value is below 5 % in red, filled."""
    m = len(result.channels)
    fig, axes = _axes(ax, 2, m, (6 * m, 6), sharex="col")
    f = np.asarray(result.frequencies_hz, dtype=float)
    a, b = result.names
    for c, name in enumerate(result.channels):
        differ = result.p_values[:, c] < 0.05
        rows = ((result.gain_ratio_percent, result.gain_ratio_low, result.gain_ratio_high,
                 100.0, f"gain {b}/{a} (%)"),
                (result.phase_difference_deg, result.phase_low, result.phase_high, 0.0,
                 f"phase {b} − {a} (°)"))
        for r, (mean, low, high, null, label) in enumerate(rows):
            cell = axes[r, c]
            cell.axhline(null, color="k", lw=0.6)
            for mask, colour, face, what in ((~differ, "C0", "white", "p ≥ 0.05"),
                                             (differ, "C3", "C3", "p < 0.05 (uncorrected)")):
                if not mask.any():
                    continue
                centre = mean[mask, c]
                cell.errorbar(f[mask], centre, yerr=[centre - low[mask, c],
                                                     high[mask, c] - centre],
                              fmt="o", color=colour, mfc=face, capsize=3, label=what)
            cell.set_xscale("log")
            cell.set_ylabel(label)
            cell.grid(alpha=0.3)
        axes[0, c].set_title(f"{name}: mean and {100 * result.level:.0f} % interval")
        axes[0, c].legend(fontsize=7)
        axes[1, c].set_xlabel("frequency (Hz)")
    fig.suptitle(f"{a} against {b}, {result.size} subjects (paired): whole FRF "
                 f"p = {result.p_value:.4f}")
    return _finished(fig, path)


def plot_study_conditions(result, path=None, ax=None):
    """A study's conditions (:class:`~posture_id.manifest.run.StudyResult`): each
    per-condition parameter of every subject across the conditions (one line per
    subject, left), and the body-COM gain against frequency in each condition (every
    subject thin, the median thick, right)."""
    rows = list(result.summary_rows)
    conditions = list(result.conditions)
    names = sorted({k.split(" [")[0] for r in rows for k in r
                    if k.endswith("]") and not k.startswith(("gain ", "phase "))
                    and " low [" not in k and " high [" not in k})
    fig, axes = _axes(ax, 1, len(names) + 1, (5 * (len(names) + 1), 4))
    axes = np.atleast_1d(axes).ravel()
    for cell, name in zip(axes, names, strict=False):
        for r in rows:
            values = [r.get(f"{name} [{c}]") for c in conditions]
            if all(v is not None for v in values):
                cell.plot(range(len(conditions)), values, "o-", alpha=0.7, label=r["subject"])
        cell.set_xticks(range(len(conditions)), conditions)
        cell.set_ylabel(name)
        cell.set_title(f"{name} per condition (a line per subject)")
        cell.grid(alpha=0.3)
        if cell.get_legend_handles_labels()[0]:
            cell.legend(fontsize=7, title="subject", ncol=max(1, len(rows) // 12))
    gains = axes[-1]
    for k, c in enumerate(conditions):
        curves = []
        for r in rows:
            points = sorted((float(key.split()[1]), v) for key, v in r.items()
                            if key.startswith("gain ") and key.endswith(f"[{c}]")
                            and v is not None)
            if points:
                f, g = zip(*points, strict=True)
                gains.plot(f, g, "o-" if len(f) == 1 else "-", color=f"C{k}", alpha=0.35,
                           lw=0.8, label=None if curves else f"{c} (each subject)")
                curves.append(dict(points))
        common = sorted(set.intersection(*(set(p) for p in curves))) if curves else []
        if common:  # every condition is drawn; its median where its subjects share points
            gains.plot(common, [np.median([p[f] for p in curves]) for f in common], "o-",
                       color=f"C{k}", lw=2, label=f"{c} (median)")
    gains.set_xscale("log")
    gains.set_xlabel("frequency (Hz)")
    gains.set_ylabel("body-COM gain (deg/deg)")
    gains.set_title("body-COM FRF gain per condition")
    gains.legend(fontsize=7)
    gains.grid(alpha=0.3)
    fig.suptitle(f"study: {len(result.subjects)} subjects, {len(conditions)} conditions")
    return _finished(fig, path)


def plot_robot_check(result, path=None, ax=None):
    """A robot check (:class:`~posture_id.robots.check.RobotCheck`): the body COM sway of
    the MuJoCo body and of the lumped model against time (top, degrees), and the Bode
    gain (deg/deg, log) and phase (°) of both per segment and of the body COM (solid:
    MuJoCo; dashed: lumped), 0.05-1 Hz."""
    fig, axes = _axes(ax, 3, 1, (9, 10), gridspec_kw={"height_ratios": [1, 1.2, 1]})
    ax_t, ax_g, ax_p = axes[:, 0]
    com = len(result.channels) - 1
    ax_t.plot(result.time, np.degrees(result.engine_sway[:, com]), lw=0.9,
              label=result.engine_label)
    ax_t.plot(result.time, np.degrees(result.lumped_sway[:, com]), "k--", lw=0.8,
              label=result.lumped_label)
    for fall, color in ((result.engine_fall_s, "r"), (result.lumped_fall_s, "m")):
        if fall is not None:
            ax_t.axvline(fall, color=color, lw=1)
            ax_t.text(fall, 0, " fell", color=color)
    ax_t.set_xlabel("time (s)")
    ax_t.set_ylabel("body COM sway (°)")
    ax_t.legend(fontsize=8, loc="upper right")
    f = result.frequencies_hz
    for m, name in enumerate(result.channels):
        for gain, phase, style, label in (
                (result.engine_gain, result.engine_phase_deg, "-", name),
                (result.lumped_gain, result.lumped_phase_deg, "--", None)):
            if gain is None:
                continue
            ax_g.plot(f, gain[:, m], style, color=f"C{m}", marker="o", ms=2.5, lw=1,
                      label=label)
            ax_p.plot(f, phase[:, m], style, color=f"C{m}", marker="o", ms=2.5, lw=1)
    if result.engine_gain is None or result.lumped_gain is None:
        ax_g.text(0.5, 0.5, "a body fell: no FRF of it", ha="center", transform=ax_g.transAxes)
    _over_frequency((ax_g, ax_p), ("gain (deg/deg)", "phase (°)"))
    ax_t.grid(alpha=0.3)
    if len(f):
        ax_g.legend(fontsize=8, title="solid: MuJoCo, dashed: lumped", title_fontsize=8)
    fig.suptitle(f"robot check of {result.name}: {result.engine_label} vs "
                 f"{result.lumped_label}", fontsize=10)
    return _finished(fig, path)
