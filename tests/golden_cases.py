#!/usr/bin/env python
"""Golden regression fixtures: fixed-seed trajectories and evaluation metrics.

    python tests/golden_cases.py          # regenerate tests/golden/*.npz (deliberate change)
    python tests/golden_cases.py --check  # compare the code with the stored fixtures

The fixtures pin what the benchmark computes, through public APIs only (so they survive
refactoring): simulator records, single and vector environment trajectories (observations,
rewards, reward terms, terminations; autoresets, sensor noise and delay included),
closed-loop episodes of every built-in controller and the metrics of a small evaluation.
``tests/test_golden.py`` imports this module and compares the code with them (bit for bit
on the machine that wrote them; to 1e-9 relative elsewhere, where libm may round
transcendental functions differently). It lives beside the tests, not named ``test_*``, so
pytest does not collect it.

Rule (README, "Development"): a regenerated golden file is committed together with the
reason for the change in the commit message.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = Path(__file__).resolve().parent / "golden"
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

PAPER = ("paper-1000-straight", "paper-1000-curved", "paper-2000-straight", "paper-2000-curved")


def simulator_cases() -> dict[str, np.ndarray]:
    """Simulator.step with scripted currents; named measurement fields per step."""
    from hyperloop_env.physics import ModelParams, OperatingCondition, Simulator
    from hyperloop_env.physics.params import MagnetParams

    out: dict[str, np.ndarray] = {}
    cases = {
        "sim_default": ModelParams(),
        "sim_2000_curve": ModelParams(
            condition=OperatingCondition(speed_kmh=2000.0, curve_radius_m=3e5, cant_deg=1.0)
        ),
        "sim_attracting_lag": ModelParams(
            magnet=MagnetParams(orientation="attracting", coil_time_constant_s=2e-3)
        ),
    }
    for name, p in cases.items():
        sim = Simulator(p)
        sim.reset(seed=3)
        i0 = sim.nominal_current_A
        rng = np.random.default_rng(11)
        rows = []
        for k in range(600):
            if name == "sim_attracting_lag":  # a crude stabilising loop for the EMS magnet
                m = sim.step(i0 * (1.0 + 60.0 * _last_gap(rows) + 0.0 * rng.random(4)))
            else:
                m = sim.step(i0 * (1.0 + 0.2 * np.sin(0.01 * k) + 0.05 * rng.standard_normal(4)))
            rows.append(
                np.concatenate(
                    [
                        m.gap_excursion_m,
                        m.lateral_offset_m,
                        m.guideway_deflection_m,
                        m.lateral_deflection_m,
                        m.current_A,
                        m.magnet_force_N,
                        m.acceleration,
                        [
                            m.position_m,
                            m.time_s,
                            m.curvature_per_m,
                            m.lateral_load_m_s2,
                            float(m.contact),
                        ],
                    ]
                )
            )
            if m.contact:
                break
        out[name] = np.array(rows)
    return out


def _last_gap(rows: list[np.ndarray]) -> np.ndarray:
    return rows[-1][:4] if rows else np.zeros(4)


def env_cases() -> dict[str, np.ndarray]:
    """gym.make trajectories: obs | reward | 5 reward terms | terminated | truncated | gaps."""
    import gymnasium as gym

    import hyperloop_env  # noqa: F401

    configs: dict[str, dict] = {
        **{f"env_{s}": {"scenario": s} for s in PAPER},
        "env_random": {"scenario": "random", "track_length_m": 300.0},
        "env_noise_delay": {
            "scenario": "paper-1000-curved",
            "sensor_noise_std": 0.02,
            "sensor_delay": 1,
            "gap_weight": 3.0,
            "current_weight": 0.2,
            "comfort_weight": 0.5,
            "coil_time_constant_s": 0.0,
        },
        "env_attracting": {"scenario": "paper-2000-straight", "magnet": "attracting"},
        "env_rough": {
            "scenario": "paper-2000-curved",
            "irregularity": "maglev-rough",
            "action_scale": 0.5,
            "cant_deg": 2.0,
        },
        "env_guided": {
            "scenario": "paper-1000-curved",
            "actuators": "levitation+guidance",
            "disturbances": {"thermal_camber": 0.003},
        },
    }
    out: dict[str, np.ndarray] = {}
    for name, kw in configs.items():
        env = gym.make("HyperloopSuspension-v0", **kw)
        rng = np.random.default_rng(5)
        rows = []
        for ep in range(2):
            obs, info = env.reset(seed=100 + ep)
            rows.append(_env_row(obs, 0.0, info, False, False))
            for _ in range(400):
                a = np.clip(0.3 * rng.standard_normal(env.action_space.shape), -1, 1)
                a = a.astype(np.float32)
                obs, r, term, trunc, info = env.step(a)
                rows.append(_env_row(obs, r, info, term, trunc))
                if term or trunc:
                    break
        env.close()
        out[name] = np.array(rows)
    return out


def _env_row(obs: np.ndarray, r: float, info: dict, term: bool, trunc: bool) -> np.ndarray:
    from hyperloop_env.reward import REWARD_TERMS

    terms = info.get("reward_terms", {})
    t = [terms.get(k, 0.0) for k in REWARD_TERMS]
    return np.concatenate(
        [
            np.asarray(obs, dtype=np.float64),
            [r],
            t,
            [float(term), float(trunc)],
            info["gap_excursion_m"],
            info["current_A"],
            info["guidance_current_A"],
            [info["position_m"]],
        ]
    )


def vector_cases() -> dict[str, np.ndarray]:
    """Native vector env: autoresets (short track), noise, delay, random scenario."""
    import gymnasium as gym

    import hyperloop_env  # noqa: F401

    out = {}
    for name, kw in {
        "vec_random": {"scenario": "random", "track_length_m": 60.0},
        "vec_noise_delay": {
            "scenario": "paper-2000-straight",
            "track_length_m": 80.0,
            "sensor_noise_std": 0.05,
            "sensor_delay": 1,
        },
    }.items():
        envs = gym.make_vec(
            "HyperloopSuspension-v0", num_envs=3, vectorization_mode="vector_entry_point", **kw
        )
        obs, _ = envs.reset(seed=21)
        rng = np.random.default_rng(9)
        rows = [np.concatenate([obs.ravel(), np.zeros(9)])]
        for _ in range(300):
            a = np.clip(0.5 * rng.standard_normal((3, 4)), -1, 1).astype(np.float32)
            obs, r, term, trunc, _ = envs.step(a)
            rows.append(np.concatenate([obs.ravel(), r, term, trunc]))
        envs.close()
        out[name] = np.array(rows, dtype=np.float64)
    return out


def controller_cases() -> dict[str, np.ndarray]:
    """Closed-loop episodes (0.3 km) of each built-in controller on each paper scenario."""
    from agents import make_controller
    from agents.controllers.registry import GUIDED, LEVITATION, entrants
    from agents.evaluation.rollout import run_episode

    out = {}
    guided = {"actuators": GUIDED}
    for ctrl in entrants(LEVITATION):  # passive, pid, lqr, ppo
        for sc in PAPER:
            cases = [("repelling", None)]
            if ctrl in entrants(GUIDED):  # pid, lqr (ppo-guidance is another entry)
                cases += [("repelling", guided), ("attracting", guided)]
            for magnet, kw in cases:
                ep = run_episode(
                    lambda env, c=ctrl: make_controller(c, env), sc, 4, 0.3, magnet, kw
                )
                arr = np.column_stack(
                    [
                        ep.time_s,
                        ep.position_m,
                        ep.gap_m,
                        ep.lateral_m,
                        ep.current_A,
                        ep.guidance_current_A,
                        ep.acc_m_s2,
                    ]
                )
                tag = "_guided" if kw else ""
                out[f"ctrl_{ctrl}_{sc}_{magnet}{tag}"] = arr
    return out


def evaluation_cases() -> dict[str, np.ndarray]:
    """Metrics of ``agents.evaluate.evaluate`` (4 controllers x 4 paper scenarios, 0.6 km)."""
    from agents.controllers.registry import LEVITATION, entrants
    from agents.evaluation.evaluate import evaluate

    # seeds 0 and 1 (explicit: the fixture predates the evaluation-range default; ppo's
    # training range, hence allow_training_seeds)
    res = evaluate(
        entrants(LEVITATION),  # passive, pid, lqr, ppo
        ["paper"],
        distance_km=0.6,
        seeds=[0, 1],
        out_dir=None,
        settle_s=0.2,
        progress=False,
        figures=False,
        n_boot=20,
        allow_training_seeds=True,
    )
    keys = (
        "rms_gap_mm",
        "max_abs_gap_mm",
        "mean_lateral_mm",
        "max_abs_lateral_mm",
        "rms_current_dev_A",
        "n_contact_episodes",
        "a_wz_m_s2",
        "a_wy_m_s2",
        "a_v_m_s2",
        "p_unsteady",
        "steps_total",
        "p_unsteady_guidance",
        "rms_lateral_mm",
    )
    rows = []
    for r in res["results"]:
        m = r["metrics"]
        row = [_num(m[k]) for k in keys]
        row += [_num(x) for x in m["p_unsteady_units"]]
        row += [_num(x) for x in m["rms_gap_units_mm"]]
        for u in (*r["report"].units, *r["report_guidance"].units):
            row += [
                _num(u.mean_m),
                _num(u.std_m),
                _num(u.p_unsteady_fit),
                _num(u.p_unsteady_ci[0]),
                _num(u.p_unsteady_ci[1]),
                _num(u.ks_pvalue),
            ]
        rows.append(row)
    return {"eval_metrics": np.array(rows, dtype=np.float64)}


def paper_cases() -> dict[str, np.ndarray]:
    """The paper reproduction's curve results (``agents.reproduce_paper``), shortened: the
    passive radius sweep at 1000 and 2000 km/h (contact, its time and kind, P(unsteady),
    lateral offsets, RMS gap over 1 km) and the critical-radius bisection of the passive
    and PID vehicles (every radius tried and its outcome, 5 % bracket), and the passive
    evaluation of the attracting (EMS) magnet on the paper conditions (contact times)."""
    from agents.evaluation.evaluate import evaluate
    from agents.evaluation.reproduce_paper import critical_radius, radius_sweep

    kinds = {None: 0.0, "gap": 1.0, "lateral": 2.0, "gap+lateral": 3.0}
    sweep = radius_sweep((60e3, 150e3, 400e3), (1000.0, 2000.0), 1.0, 0, "repelling", 0.2)
    rows = [
        [
            r["speed_kmh"],
            r["radius_m"],
            r["a_lat_m_s2"],
            float(r["contact"]),
            kinds[r["contact_kind"]],
            _num(r["time_to_contact_s"]),
            _num(r["position_of_contact_m"]),
            _num(r["p_unsteady"]),
            r["mean_lateral_mm"],
            r["max_abs_lateral_mm"],
            _num(r["rms_gap_mm"]),
        ]
        for r in sweep
    ]
    out = {"paper_radius_sweep": np.array(rows, dtype=np.float64)}
    for ctrl in ("passive", "pid"):
        for v in (1000.0, 2000.0):
            c = critical_radius(ctrl, v, 1.0, 0, "repelling", rel_bracket=0.05)
            ev = [[r, float(hit)] for r, hit in c["evaluations"]]
            out[f"paper_critical_radius_{ctrl}_{v:.0f}"] = np.array(
                [[_num(c["critical_radius_m"]), _num(c["bracket_rel"])], *ev], dtype=np.float64
            )
    res = evaluate(
        ["passive"],
        ["paper"],
        distance_km=0.3,
        seeds=[0],
        magnet="attracting",
        out_dir=None,
        settle_s=0.0,
        progress=False,
        figures=False,
        n_boot=0,
    )
    out["paper_attracting_passive"] = np.array(
        [
            [
                float(r["metrics"]["n_contact_episodes"]),
                _num(r["metrics"]["time_to_first_contact_s"]),
                _num(r["metrics"]["position_of_first_contact_m"]),
                kinds[r["metrics"]["contact_kind"]],
                _num(r["metrics"]["p_unsteady"]),
            ]
            for r in res["results"]
        ],
        dtype=np.float64,
    )
    return out


def _num(x: object) -> float:
    if x is None:
        return math.nan
    return float(x)  # type: ignore[arg-type]


GROUPS: dict[str, Callable[[], dict[str, np.ndarray]]] = {
    "simulator": simulator_cases,
    "env": env_cases,
    "vector": vector_cases,
    "controllers": controller_cases,
    "evaluation": evaluation_cases,
    "paper": paper_cases,
}


def generate(groups: list[str]) -> dict[str, dict[str, np.ndarray]]:
    return {g: GROUPS[g]() for g in groups}


def compare(stored: dict[str, np.ndarray], new: dict[str, np.ndarray], rtol: float) -> list[str]:
    """Differences between two fixture dicts (empty list: identical within rtol)."""
    problems = []
    for k in sorted(set(stored) | set(new)):
        if k not in stored or k not in new:
            problems.append(f"{k}: missing in {'stored' if k not in stored else 'new'}")
            continue
        a, b = stored[k], new[k]
        if a.shape != b.shape:
            problems.append(f"{k}: shape {a.shape} != {b.shape}")
            continue
        same_nan = np.isnan(a) == np.isnan(b)
        fa, fb = np.nan_to_num(a), np.nan_to_num(b)
        scale = np.maximum(np.abs(fa), np.abs(fb))
        # relative to each column's scale (a gap of 1e-6 m next to 0 is not "relative 1")
        col = np.max(np.abs(fa), axis=0, keepdims=True) if fa.ndim == 2 else np.max(np.abs(fa))
        tol = rtol * np.maximum(scale, col) + 1e-300
        bad = (np.abs(fa - fb) > tol) | ~same_nan
        if bad.any():
            idx = np.argwhere(bad)[0]
            problems.append(
                f"{k}: {int(bad.sum())} value(s) differ, first at {tuple(int(i) for i in idx)}: "
                f"{a[tuple(idx)]!r} vs {b[tuple(idx)]!r}"
            )
    return problems


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="compare instead of writing")
    ap.add_argument("--exact", action="store_true", help="with --check: bit for bit")
    ap.add_argument("--groups", nargs="+", default=list(GROUPS), choices=list(GROUPS))
    args = ap.parse_args(argv)
    GOLDEN.mkdir(parents=True, exist_ok=True)
    failed = False
    for g in args.groups:
        new = GROUPS[g]()
        path = GOLDEN / f"{g}.npz"
        if args.check:
            if not path.exists():
                print(f"{g}: no stored fixture {path}")
                failed = True
                continue
            with np.load(path) as f:
                stored = {k: f[k] for k in f.files}
            problems = compare(stored, new, 0.0 if args.exact else 1e-9)
            print(f"{g}: {'OK' if not problems else 'DIFFERS'} ({len(new)} arrays)")
            for p in problems:
                print("  " + p)
            failed |= bool(problems)
        else:
            tmp = path.with_suffix(".tmp.npz")
            np.savez_compressed(tmp, **new)
            tmp.replace(path)
            print(f"wrote {path} ({len(new)} arrays)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
