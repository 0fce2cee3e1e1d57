"""Every figure of the evaluation, drawn with Matplotlib's Agg backend (no display needed):

* :func:`plot_hist`, :func:`plot_timeseries` — excursion histograms with the fitted density
  and ±Ω (the paper's Fig. 5) and excursion time series (its Figs. 8–11), per evaluate case;
* :func:`plot_comparison` — the controllers of an evaluation compared (RMS gap, contacts);
* :func:`plot_fragility` — P(contact) against severity with the lognormal fits, per
  condition of a fragility sweep;
* :func:`plot_capacities` — the entrants' empirical capacity distributions, per condition
  of a capacity run.

Each is saved by :func:`save_figure`: written atomically, an interrupted save never leaves
a truncated PNG. The tables are rendered by :mod:`agents.evaluation.render`."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.evaluation.outputs import atomic_path
from agents.evaluation.render import probability
from agents.evaluation.rollout import Episode
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES
from hyperloop_env.sts import STSReport


def _pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend (imported on first use: a run without
    figures never loads Matplotlib)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: str | Path, dpi: int = 90) -> Path:
    """Write ``fig`` as a PNG to ``path`` atomically and close it: the image is saved into
    a temporary file beside ``path`` and renamed over it
    (:func:`~agents.evaluation.outputs.atomic_path`), so an interrupted or failed save
    leaves the old file (or none), never a truncated one. Every figure is saved here."""
    target = Path(path)
    try:
        with atomic_path(target) as tmp:
            fig.savefig(tmp, dpi=dpi, format="png")
    finally:
        _pyplot().close(fig)
    return target


def plot_hist(
    report: STSReport,
    episodes: list[Episode],
    settle_s: float,
    path: Path,
    signal: str = "levitation",
) -> None:
    """Histograms of one signal per unit with the fitted density and ±clearance:
    ``signal="levitation"`` the gap excursion s, ``"guidance"`` the guidance gap z."""
    from scipy import stats

    plt = _pyplot()

    om = report.clearance_m * 1e3
    dt = episodes[0].dt_s
    n0 = int(math.ceil(settle_s / dt - 1e-9)) if settle_s > 0 else 0
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for a, (ax, u) in enumerate(zip(axes.flat, report.units, strict=True)):
        sig = [e.gap_m if signal == "levitation" else e.lateral_m for e in episodes]
        x = np.concatenate([g[1 + n0 :, a] for g in sig]) * 1e3
        lim = max(om * 1.3, float(np.max(np.abs(x))) * 1.05 if len(x) else 0.0)
        if len(x):
            ax.hist(
                x,
                bins=80,
                range=(-lim, lim),
                density=True,
                histtype="stepfilled",  # one polygon, not 80 bars: the same picture
                alpha=0.6,
                label="simulated",
            )
        if u.distribution not in ("none", "degenerate") and len(u.distribution_params):
            law = getattr(stats, u.distribution)
            *shape, loc, scale = u.distribution_params
            xs = np.linspace(-lim, lim, 400)
            pdf = law.pdf(xs * 1e-3, *shape, loc=loc, scale=scale) * 1e-3
            ax.plot(xs, pdf, "k-", lw=1.5, label=f"fitted {u.distribution}")
        for s in (-om, om):
            ax.axvline(s, color="r", ls="--", lw=1.2)
        ax.set_title(f"{u.name}: P(unsteady) = {probability(u.p_unsteady)}")
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
    save_figure(fig, path)


def plot_timeseries(ep: Episode, path: Path) -> None:
    """The gap excursion and lateral offset of every unit over one episode, ±Ω dashed."""
    plt = _pyplot()

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
    save_figure(fig, path)


def plot_comparison(results: list[dict[str, Any]], path: Path) -> Path:
    """One figure comparing the controllers: RMS gap excursion per condition (bars), runs
    that touched marked with a cross above their bar."""
    plt = _pyplot()

    by: dict[str, list[dict[str, Any]]] = {}
    for r in results:
        by.setdefault(r["metrics"]["controller"], []).append(r["metrics"])
    scen = list(dict.fromkeys(m["condition"] for ms in by.values() for m in ms))
    names = list(by)
    width = 0.8 / max(len(names), 1)
    fig, ax = plt.subplots(figsize=(2.0 + 1.6 * len(scen), 4.0))
    for k, name in enumerate(names):
        ms = {m["condition"]: m for m in by[name]}
        xs = [i + (k - (len(names) - 1) / 2) * width for i in range(len(scen))]
        ys = [ms[s]["rms_gap_mm"] if s in ms else math.nan for s in scen]
        ax.bar(xs, ys, width=width, label=name)
        for x, s, y in zip(xs, scen, ys, strict=True):
            if s in ms and ms[s]["n_contact_episodes"]:
                ax.plot([x], [y if math.isfinite(y) else 0.0], "kx", ms=8)
    ax.set_xticks(range(len(scen)))
    ax.set_xticklabels(scen, rotation=15, fontsize=8)
    ax.set_ylabel("RMS gap excursion [mm] (x: runs touched)")
    ax.set_title("Controllers compared")
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)


LEGEND_NOTE = re.compile(r" \((?:no finite MLE|\d+ bootstrap)[^)]*\)")
"""The parenthetical notes of a fragility fit's summary that the figure legend leaves out."""


def plot_fragility(res: dict[str, Any], condition: str, path: Path) -> None:
    """Probability of contact against severity for one condition of a fragility sweep
    (:func:`agents.evaluation.fragility.fragility`): data with intervals, fitted lognormal
    curves, one colour per controller."""
    plt = _pyplot()

    s = res["settings"]
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    levels = np.array(s["levels"], dtype=float)
    logx = bool(np.all(levels > 0))
    ctrls = s["controllers"]
    span = np.log(levels.max() / levels.min()) if logx and levels.size > 1 else 1.0
    for ci, ctrl in enumerate(ctrls):
        rs = sorted(
            (r for r in res["levels"] if r["controller"] == ctrl and r["condition"] == condition),
            key=lambda r: r["level"],
        )
        x = np.array([r["level"] for r in rs])
        p = np.array([r["p_contact"] for r in rs])
        lo = np.array([r["p_contact_ci"][0] for r in rs])
        hi = np.array([r["p_contact_ci"][1] for r in rs])
        shift = (ci - (len(ctrls) - 1) / 2) * 0.012 * span  # separate the points a little
        xs = x * np.exp(shift) if logx else x + shift * (x.max() - x.min() + 1e-12)
        colour = f"C{ci}"
        fit = next(
            f for f in res["fits"] if f["controller"] == ctrl and f["condition"] == condition
        )["fit"]
        label = f"{ctrl}: {LEGEND_NOTE.sub('', fit.summary())}"
        ax.errorbar(
            xs, p, yerr=[p - lo, hi - p], fmt="o", color=colour, ms=4, capsize=3, label=label
        )
        if fit.status == "fit":
            grid = (
                np.geomspace(levels.min() / 1.5, levels.max() * 1.5, 200)
                if logx
                else np.linspace(levels.min(), levels.max(), 200)
            )
            ax.plot(grid, fit.probability(grid), "-", color=colour, lw=1.4)
    if logx:
        from matplotlib.ticker import FuncFormatter

        ax.set_xscale("log")
        fmt = FuncFormatter(lambda v, _: f"{v:g}")
        ax.xaxis.set_major_formatter(fmt)
        ax.xaxis.set_minor_formatter(fmt)
        ax.tick_params(axis="x", which="minor", labelsize=7)
    ax.set_ylim(-0.03, 1.03)
    ax.set_xlabel(f"{s['family']} severity ({s['severity_unit']})")
    ax.set_ylabel("P(contact) per run")
    ax.set_title(
        f"{condition}: {len(s['seeds'])} runs × {s['distance_km']:g} km per level "
        f"({'Clopper–Pearson' if s['interval'] == 'exact' else 'Wilson'} 95 %)",
        fontsize=10,
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    save_figure(fig, path)


def plot_capacities(analysis: dict[str, Any], labels: Sequence[str], folder: Path) -> list[Path]:
    """One figure per condition of a capacity run
    (:func:`agents.evaluation.capacity_benchmark.analyse`): each family's empirical
    capacity distributions, one step curve per entrant."""
    plt = _pyplot()

    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for cond, fams in analysis.items():
        fig, axes = plt.subplots(1, len(fams), figsize=(5 * len(fams), 4), squeeze=False)
        for ax, (fam, cell) in zip(axes[0], fams.items(), strict=True):
            for lab in labels:
                e = cell["entrants"][lab]["ecdf"]
                ax.step(e["x"], e["F"], where="post", label=lab)
            ax.set_xscale("log")
            ax.set_xlabel(f"{fam} capacity")
            ax.set_ylabel("fraction of seeds touched (P(contact | s))")
            ax.set_title(f"{cond}: {fam}")
            ax.grid(True, which="both", alpha=0.3)
        axes[0][0].legend(fontsize=8)
        fig.tight_layout()
        paths.append(save_figure(fig, folder / f"capacities_{cond}.png"))
    return paths
