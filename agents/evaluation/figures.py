"""Figures of an evaluation: excursion histograms with the fitted density and ±Ω (the
paper's Fig. 5) and excursion time series (its Figs. 8–11). Matplotlib's Agg backend: no
display needed."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from agents.evaluation.rollout import Episode
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES
from hyperloop_env.sts import STSReport, format_probability


def plot_hist(
    report: STSReport,
    episodes: list[Episode],
    settle_s: float,
    path: Path,
    signal: str = "levitation",
) -> None:
    """Histograms of one signal per unit with the fitted density and ±clearance:
    ``signal="levitation"`` the gap excursion s, ``"guidance"`` the guidance gap z."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from scipy import stats

    om = report.clearance_m * 1e3
    dt = episodes[0].dt_s
    n0 = int(math.ceil(settle_s / dt - 1e-9)) if settle_s > 0 else 0
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for a, (ax, u) in enumerate(zip(axes.flat, report.units, strict=True)):
        sig = [e.gap_m if signal == "levitation" else e.lateral_m for e in episodes]
        x = np.concatenate([g[1 + n0 :, a] for g in sig]) * 1e3
        lim = max(om * 1.3, float(np.max(np.abs(x))) * 1.05 if len(x) else 0.0)
        if len(x):
            ax.hist(x, bins=80, range=(-lim, lim), density=True, alpha=0.6, label="simulated")
        if u.distribution not in ("none", "degenerate") and len(u.distribution_params):
            law = getattr(stats, u.distribution)
            *shape, loc, scale = u.distribution_params
            xs = np.linspace(-lim, lim, 400)
            pdf = law.pdf(xs * 1e-3, *shape, loc=loc, scale=scale) * 1e-3
            ax.plot(xs, pdf, "k-", lw=1.5, label=f"fitted {u.distribution}")
        for s in (-om, om):
            ax.axvline(s, color="r", ls="--", lw=1.2)
        ax.set_title(f"{u.name}: P(unsteady) = {format_probability(u.p_unsteady)}")
        ax.set_xlabel(
            "gap excursion s [mm]  (±Ω dashed)"
            if signal == "levitation"
            else "guidance gap excursion z [mm]  (±Ω_g dashed)"
        )
        ax.set_ylabel("density [1/mm]")
        if len(x):
            ax.legend(fontsize=7)
        else:
            ax.text(
                0.5,
                0.5,
                "no samples after settling\n(contact)",
                ha="center",
                transform=ax.transAxes,
            )
    e0 = episodes[0]
    fig.suptitle(f"{e0.controller} — {e0.scenario} ({e0.magnet})")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def plot_timeseries(ep: Episode, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    om = ep.clearance_m * 1e3
    fig, axes = plt.subplots(N_UNITS, 1, figsize=(11, 8), sharex=True)
    t = ep.time_s
    step = max(1, len(t) // 20000)
    for a, ax in enumerate(axes):
        ax.plot(t[::step], ep.gap_m[::step, a] * 1e3, lw=0.6, label="gap excursion")
        ax.plot(t[::step], ep.lateral_m[::step, a] * 1e3, lw=0.6, alpha=0.7, label="lateral offset")
        for s in (-om, om):
            ax.axhline(s, color="r", ls="--", lw=0.8)
        ax.set_ylabel(f"{UNIT_NAMES[a]} [mm]")
    axes[0].legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("time [s]")
    title = f"{ep.controller} — {ep.scenario} ({ep.magnet}), seed {ep.seed}"
    if ep.terminated:
        title += f": {ep.contact_kind} contact at t = {ep.contact_time_s:.3f} s"
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
