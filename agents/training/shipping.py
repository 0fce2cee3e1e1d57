"""Copy a finished run into ``agents/shipped/<algo>/`` (``train.py --ship``)."""

from __future__ import annotations

from pathlib import Path

SHIP_FILES = ("model.zip", "vecnormalize.pkl", "training_log.json")
SHIP_REPORT_FILES = ("report.md", "summary.csv", "results.json")


def ship(out: Path, algo: str) -> Path:
    """Copy a finished run into ``agents/shipped/<algo>/`` (model, VecNormalize statistics,
    training log, the EvalCallback curve as CSV and the STS report tables, no figures)."""
    import shutil

    import numpy as np

    from agents.controllers.learned import shipped_path

    dest = shipped_path(algo)
    dest.mkdir(parents=True, exist_ok=True)
    for name in SHIP_FILES:
        shutil.copy2(out / name, dest / name)
    curve = out / "eval" / "evaluations.npz"
    if curve.exists():
        d = np.load(curve)
        rows = ["timesteps,mean_reward,std_reward,mean_ep_length"]
        for t, r, n in zip(d["timesteps"], d["results"], d["ep_lengths"], strict=True):
            rows.append(f"{int(t)},{float(np.mean(r)):.2f},{float(np.std(r)):.2f},{np.mean(n):.1f}")
        (dest / "eval_curve.csv").write_text("\n".join(rows) + "\n")
    for name in SHIP_REPORT_FILES:
        src = out / "report" / name
        if src.exists():
            text = src.read_text()
            if name.endswith(".md"):  # the figures stay in the run directory
                text = "\n".join(ln for ln in text.splitlines() if not ln.startswith("![")) + "\n"
            (dest / f"eval_{name}").write_text(text)
    return dest


