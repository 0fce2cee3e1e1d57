"""Every observation block recomputed from ``info`` with a levitation clearance Ω = 6 mm that
differs from the guidance clearance Ω_g = 8 mm (with the defaults both are 8 mm, so a block
scaled by the wrong clearance would go unnoticed), and with the guidance pairs actuated so
that the guidance blocks (rates, differential currents / I_g0) are exercised too.
Scalings (hyperloop_env/observation.py): gap / Ω, rates = backward difference / (1 m/s),
lateral / Ω_g, accelerations / g, currents I/I0 − 1 and ΔI/I_g0, speed / (2000 km/h),
curvature × 1e5 m at 0, 250, 500, 1000 m ahead."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import hyperloop_env  # noqa: F401  (registration)
from hyperloop_env.physics.model import guidance_bias_A

OMEGA = 0.006
KW = {
    "scenario": "paper-1000-curved",
    "clearance_m": OMEGA,
    "actuators": "levitation+guidance",
    "track_length_m": 80.0,
}


def _expected(info: dict, prev: dict | None, p, i0: float, ig0: float) -> dict[str, np.ndarray]:
    dt = p.simulation.control_dt_s
    gap, lat = info["gap_excursion_m"], info["lateral_offset_m"]
    x = info["position_m"]
    c = p.condition
    kappa = [
        min(max((x + d - c.curve_start_m) / c.transition_length_m, 0.0), 1.0) / c.curve_radius_m
        for d in (0.0, 250.0, 500.0, 1000.0)
    ]
    return {
        "gap": gap / OMEGA,
        "gap_rate": np.zeros(4) if prev is None else (gap - prev["gap_excursion_m"]) / dt,
        "lateral": lat / 0.008,
        "lateral_rate": np.zeros(4) if prev is None else (lat - prev["lateral_offset_m"]) / dt,
        "acc": np.asarray(info["acceleration_m_s2"]) / 9.81,
        "current": info["current_A"] / i0 - 1.0,
        "current_guidance": info["guidance_current_A"] / ig0,
        "speed": np.array([1000.0 / 2000.0]),
        "curvature": np.array(kappa) * 1e5,
    }


def test_single_env_observation_blocks_with_distinct_clearances() -> None:
    env = gym.make("HyperloopSuspension-v0", **KW)
    u = env.unwrapped
    spec = u.observation_spec
    assert set(spec.slices) == {
        "gap",
        "gap_rate",
        "lateral",
        "lateral_rate",
        "acc",
        "current",
        "current_guidance",
        "speed",
        "curvature",
    }
    obs, info = env.reset(seed=3)
    p = u.params
    assert p.magnet.clearance_m == OMEGA and p.guidance.clearance_m == 0.008
    i0, ig0 = u.nominal_current_A, guidance_bias_A(p)
    prev = None
    rng = np.random.default_rng(1)
    for k in range(120):
        want = _expected(info, prev, p, i0, ig0)
        for name, value in want.items():
            np.testing.assert_allclose(
                obs[spec.slice(name)],
                value,
                rtol=2e-6,
                atol=2e-6,
                err_msg=f"step {k}, block {name}",
            )
        prev = info
        a = rng.uniform(-0.3, 0.3, env.action_space.shape).astype(np.float32)
        obs, _, term, trunc, info = env.step(a)
        if term or trunc:
            break
    assert np.any(np.abs(obs[spec.slice("current_guidance")]) > 1e-3)  # the pairs were driven
    env.close()


def test_vector_env_observation_gap_and_lateral_scaling() -> None:
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    envs = HyperloopSuspensionVectorEnv(num_envs=2, **KW)
    obs, _ = envs.reset(seed=5)
    spec = envs.observation_spec
    rng = np.random.default_rng(2)
    for _ in range(20):
        obs, _, _, _, info = envs.step(rng.uniform(-0.3, 0.3, (2, 8)).astype(np.float32))
        np.testing.assert_allclose(
            obs[:, spec.slice("gap")], info["gap_excursion_m"] / OMEGA, rtol=2e-6, atol=2e-6
        )
        np.testing.assert_allclose(
            obs[:, spec.slice("lateral")], info["lateral_offset_m"] / 0.008, rtol=2e-6, atol=2e-6
        )
    envs.close()
