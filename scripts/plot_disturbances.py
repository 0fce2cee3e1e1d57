#!/usr/bin/env python
"""One realisation of every disturbance family, as figures in ``docs/disturbances/``.

    python scripts/plot_disturbances.py [--out docs/disturbances] [--seed 0]

For each registered disturbance (``hyperloop_env.disturbances.DISTURBANCES``) at its
default severity: the guideway profile it adds (left rail, lateral) over 300 m, and the
passive vehicle's gap excursion (FL) at 1000 km/h with and without it (no irregularity
otherwise), so the figure shows both what the disturbance is and what it does. A
disturbance of the sensors (``sensor_dropout``) adds no profile: its figure shows the
failed unit's gap as measured (held during the dropouts, shaded) against the true gap.
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
if str(ROOT) not in sys.path:  # this checkout's package, not an installed one
    sys.path.insert(0, str(ROOT))


def realise(name: str, seed: int, length_m: float = 300.0):
    import gymnasium as gym

    from hyperloop_env import ENV_ID
    from hyperloop_env.disturbances import DISTURBANCES

    d = DISTURBANCES[name]()
    kw = {"track_length_m": length_m, "irregularity": "none", "coil_time_constant_s": 0.0}
    out = {}
    for label, dist in (("with", {name: d}), ("without", {})):
        env_kw = dict(kw)
        if name == "roughness" and label == "with":  # the disturbance sets the irregularity
            env_kw.pop("irregularity")
        env = gym.make(ENV_ID, disturbances=dist, **env_kw)
        env.reset(seed=seed)
        sim = env.unwrapped.sim
        act = np.zeros(env.action_space.shape, np.float32)
        x, gap, obs_gap, true_gap = [], [], [], []
        hooks = env.unwrapped.sensors._hooks
        unit = getattr(hooks[0], "unit", 0) if hooks and hooks[0] is not None else 0
        g0 = env.unwrapped.observation_spec.start("gap") + unit
        om = env.unwrapped.params.magnet.clearance_m
        while True:
            obs, _, te, tr, info = env.step(act)
            x.append(info["position_m"])
            gap.append(info["gap_excursion_m"][0])
            obs_gap.append(obs[g0] * om)
            true_gap.append(info["gap_excursion_m"][unit])
            if te or tr:
                break
        n, dx = sim.profile_grid
        grid = np.arange(n) * dx
        m = grid <= length_m + 20
        out[label] = (np.array(x), np.array(gap), grid[m], sim.irr[:, m].copy())
        if label == "with":
            out["sensor"] = (unit, np.array(obs_gap), np.array(true_gap))
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
        if _is_sensor_disturbance(out):
            _plot_sensor(name, d, out, a0, a1)
            _save(fig, args.out / f"{name}.png")
            continue
        _, _, grid, irr = out["with"]
        _, _, _, irr0 = out["without"]
        a0.plot(grid, (irr[0] - irr0[0]) * 1e3, lw=1, label="left rail, vertical")
        a0.plot(grid, (irr[2] - irr0[2]) * 1e3, lw=1, label="lateral")
        a0.set_ylabel("profile added [mm]")
        a0.legend(fontsize=8)
        a0.set_title(
            _title(f"{name}: {d.description} (severity {d.severity:g} {d.severity_unit})"),
            fontsize=10,
        )
        for label, style in (("without", "k--"), ("with", "C3-")):
            x, gap, _, _ = out[label]
            a1.plot(x, gap * 1e3, style, lw=0.8, label=f"{label} {name}")
        a1.set_xlabel("position x [m]")
        a1.set_ylabel("FL gap excursion [mm]\n(passive, 1000 km/h)")
        a1.legend(fontsize=8)
        _save(fig, args.out / f"{name}.png")
    return 0


def _title(text: str, width: int = 100) -> str:
    """The title, wrapped onto two lines when it would not fit the figure."""
    if len(text) <= width:
        return text
    cut = text.rfind(" (", 0, width)
    return text[:cut] + "\n" + text[cut + 1 :] if cut > 0 else text


def _save(fig, path: Path) -> None:
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    print(f"wrote {path}")


def _is_sensor_disturbance(out) -> bool:
    """No profile change but the measured gap differs from the true one."""
    same_profile = np.array_equal(out["with"][3], out["without"][3])
    _, obs_gap, true_gap = out["sensor"]
    return same_profile and not np.allclose(obs_gap, true_gap, atol=1e-6)


def _plot_sensor(name: str, d, out, a0, a1) -> None:
    from hyperloop_env.physics.units import UNIT_NAMES

    x = out["with"][0]
    unit, obs_gap, true_gap = out["sensor"]
    held = np.abs(obs_gap - true_gap) > 1e-6
    a0.plot(x, true_gap * 1e3, "k-", lw=0.8, label=f"{UNIT_NAMES[unit]} gap, true")
    a0.plot(x, obs_gap * 1e3, "C3-", lw=0.8, label=f"{UNIT_NAMES[unit]} gap, measured")
    a0.set_ylabel("gap excursion [mm]")
    a0.legend(fontsize=8)
    a0.set_title(
        _title(f"{name}: {d.description} (severity {d.severity:g}: {d.severity_unit})"), fontsize=10
    )
    a1.fill_between(
        x,
        0,
        held.astype(float),
        step="post",
        color="C3",
        alpha=0.4,
        label=f"sensor frozen ({held.mean():.0%} of the steps here)",
    )
    a1.set_ylim(0, 1.2)
    a1.set_xlabel("position x [m]")
    a1.set_ylabel("dropout")
    a1.legend(fontsize=8, loc="upper right")


if __name__ == "__main__":
    sys.exit(main())
