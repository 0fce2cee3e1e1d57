#!/usr/bin/env python
"""One realisation of every disturbance family, as figures in ``docs/disturbances/``.

    python scripts/plot_disturbances.py [--out docs/disturbances] [--seed 0]

For each registered disturbance (``hyperloop_env.disturbances.DISTURBANCES``) at its
default severity: the guideway profile it adds (left rail, lateral) over 300 m, and the
passive vehicle's gap excursion (FL) at 1000 km/h with and without it (no irregularity
otherwise), so the figure shows both what the disturbance is and what it does.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def realise(name: str, seed: int, length_m: float = 300.0):
    import gymnasium as gym

    from hyperloop_env import ENV_ID
    from hyperloop_env.disturbances import DISTURBANCES

    d = DISTURBANCES[name]()
    kw = {"track_length_m": length_m, "irregularity": "none", "coil_time_constant_s": 0.0}
    if name == "roughness":
        kw.pop("irregularity")
    out = {}
    for label, dist in (("with", {name: d}), ("without", {})):
        env = gym.make(ENV_ID, disturbances=dist, **kw)
        env.reset(seed=seed)
        sim = env.unwrapped.sim
        act = np.zeros(env.action_space.shape, np.float32)
        x, gap = [], []
        while True:
            _, _, te, tr, info = env.step(act)
            x.append(info["position_m"])
            gap.append(info["gap_excursion_m"][0])
            if te or tr:
                break
        n, dx = sim.profile_grid
        grid = np.arange(n) * dx
        m = grid <= length_m + 20
        out[label] = (np.array(x), np.array(gap), grid[m], sim.irr[:, m].copy())
        env.close()
    return d, out


def main(argv: list[str] | None = None) -> int:
    from hyperloop_env.disturbances import DISTURBANCES

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "disturbances")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", nargs="*", default=None, help="disturbance names")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for name in args.only or list(DISTURBANCES):
        d, out = realise(name, args.seed)
        fig, (a0, a1) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
        _, _, grid, irr = out["with"]
        _, _, _, irr0 = out["without"]
        a0.plot(grid, (irr[0] - irr0[0]) * 1e3, lw=1, label="left rail, vertical")
        a0.plot(grid, (irr[2] - irr0[2]) * 1e3, lw=1, label="lateral")
        a0.set_ylabel("profile added [mm]")
        a0.legend(fontsize=8)
        a0.set_title(f"{name}: {d.description} (severity {d.severity:g} {d.severity_unit})",
                     fontsize=10)  # fmt: skip
        for label, style in (("without", "k--"), ("with", "C3-")):
            x, gap, _, _ = out[label]
            a1.plot(x, gap * 1e3, style, lw=0.8, label=f"{label} {name}")
        a1.set_xlabel("position x [m]")
        a1.set_ylabel("FL gap excursion [mm]\n(passive, 1000 km/h)")
        a1.legend(fontsize=8)
        fig.tight_layout()
        path = args.out / f"{name}.png"
        fig.savefig(path, dpi=80)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
