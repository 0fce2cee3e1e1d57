"""A new actuator kind through the public extension point (README, "Extending" → "An
actuator kind"): ``register_actuator_kind(ActuatorKind(...))`` and nothing else.

The toy kind ``booster`` is an auxiliary levitation magnet on each unit (the levitation
magnet's geometry, force law ``"levitation"``) whose coil is off at rest: reference current
I0/4, neutral command 0 (so action 0 is 0 A), clamp [0, I0/4]. Registering it changes the
physics for the whole process, so the episode runs in a fresh interpreter (which also
checks that the cached compiled kernels read the kinds as data, not as stale constants); an
environment made before the registration keeps the two built-in kinds.

Checked: the action space grows by four channels and the observation by the kind's block;
the currents are recorded (``info["booster_current_A"]``); action 0 is the neutral current
(0 A) and then the vehicle flies as without the kind; a commanded current is
applied, observed as I/reference and costed by the reward's current term; the kind's force
on a unit is the levitation magnet law at its current (upward, F0·(I/I0)² at the nominal
gap); both environments agree.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = textwrap.dedent(
    """
    import numpy as np

    from hyperloop_env.env import HyperloopSuspensionEnv
    from hyperloop_env.physics import ActuatorKind, KindObservation, register_actuator_kind
    from hyperloop_env.physics.layout import NQ, P_F0, P_I0, P_IG0, P_MU, Q_UY
    from hyperloop_env.physics.magnets import magnet_forces
    from hyperloop_env.physics.simulator import Simulator
    from hyperloop_env.physics.params import ModelParams
    from hyperloop_env.physics.vehicle import rhs
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    plain = HyperloopSuspensionEnv()  # made before the registration: keeps the two kinds
    register_actuator_kind(
        ActuatorKind(
            name="booster",
            description="auxiliary levitation magnet of each unit, off at rest",
            command="booster coil current [A]",
            neutral=0.0,
            reference_A=lambda P: 0.25 * float(P[P_I0]),
            limits_A=lambda P: (0.0, 0.25 * float(P[P_I0])),
            record_field="booster_current_A",
            observation=KindObservation("current_booster", "booster current [A]", "I/(I0/4)"),
            force_law="levitation",
            channel_prefix="b",
        )
    )

    env = HyperloopSuspensionEnv(actuators="levitation+booster")
    assert plain.action_space.shape == (4,), plain.action_space
    assert env.action_space.shape == (8,), env.action_space
    spec = env.observation_spec
    assert env.observation_space.shape == (plain.observation_space.shape[0] + 4,)
    ob = spec.slice("current_booster")
    assert ob.stop - ob.start == 4 and spec.start("current_booster") > spec.start("current")
    assert env.sim.command_names[4:] == ("bFL", "bFR", "bRL", "bRR"), env.sim.command_names

    # action 0: the booster stays at its neutral current (0 A), the flight is the plain one
    o1, i1 = plain.reset(seed=3)
    o2, i2 = env.reset(seed=3)
    assert np.array_equal(i2["booster_current_A"], np.zeros(4))
    for _ in range(20):
        o1, r1, *_, i1 = plain.step(np.zeros(4))
        o2, r2, *_, i2 = env.step(np.zeros(8))
        assert np.array_equal(i2["booster_current_A"], np.zeros(4))
        assert np.all(o2[ob] == 0.0)
        np.testing.assert_allclose(i2["gap_excursion_m"], i1["gap_excursion_m"], atol=1e-15)
        np.testing.assert_allclose(r2, r1, rtol=1e-12)
    assert "booster_current_A" not in i1

    # a commanded booster current: applied after the coil lag, observed, costed
    ref = 0.25 * env.unwrapped.nominal_current_A
    act = np.array([0, 0, 0, 0, 0.5, 0.5, -1.0, 2.0], dtype=np.float32)
    o2, r2, *_, i2 = env.step(act)
    command = np.array([0.5 * ref, 0.5 * ref, 0.0, ref])  # clamp [0, ref]; action clipped
    tau = env.params.magnet.coil_time_constant_s
    lag = 1.0 - np.exp(-env.params.simulation.control_dt_s / tau) if tau > 0 else 1.0
    expected = command * lag  # from 0 A (the neutral current) towards the command
    np.testing.assert_allclose(i2["booster_current_A"], expected, rtol=1e-12)
    np.testing.assert_allclose(o2[ob], expected / ref, rtol=1e-6)
    w = env.config.reward.current
    lev = np.mean((i2["current_A"] / env.unwrapped.nominal_current_A - 1.0) ** 2)
    gui = np.mean((i2["guidance_current_A"] / env.sim.P[P_IG0]) ** 2)  # 0: not actuated
    assert gui == 0.0
    np.testing.assert_allclose(
        i2["reward_terms"]["current"], -w * (lev + np.mean((expected / ref) ** 2)), rtol=1e-9
    )

    # the vector environment loops over the same kinds
    venv = HyperloopSuspensionVectorEnv(num_envs=2, actuators="levitation+booster")
    assert venv.single_action_space.shape == (8,)
    vo, vi = venv.reset(seed=3)
    vo, vr, *_, vi = venv.step(np.stack([act, np.zeros(8, dtype=np.float32)]))
    np.testing.assert_allclose(vi["booster_current_A"][0], expected, rtol=1e-12)
    assert np.array_equal(vi["booster_current_A"][1], np.zeros(4))

    # the force law: a levitation magnet at the booster current, upward, on a simple case
    sim = Simulator(ModelParams(actuators="levitation+booster"))
    sim.reset(seed=0)
    i0 = sim.nominal_current_A
    cmd = sim.neutral_command.copy()
    assert np.array_equal(cmd[8:], np.zeros(4))
    y = sim.y.copy()
    base = np.zeros_like(y)
    rhs(0.0, y, sim.P, sim.irr, 0.0, cmd, cmd, sim.spans, base, sim.wts, sim.uo)
    s, z = sim.uo[0, 0], sim.uo[1, 0]  # gap excursion, lateral offset of FL
    ib = 0.2 * i0
    cmd[8] = ib  # booster of FL
    dydt = np.zeros_like(y)
    rhs(0.0, y, sim.P, sim.irr, 0.0, cmd, cmd, sim.spans, dydt, sim.wts, sim.uo)
    force = (dydt[NQ + Q_UY] - base[NQ + Q_UY]) * sim.P[P_MU]  # vertical force on FL [N]
    p = sim.params.magnet
    kmag = 4e-7 * np.pi * p.turns**2 / 4.0
    fy, _ = magnet_forces(
        ib, s, z, kmag, p.pole_length_m, p.pole_width_m, p.nominal_gap_m, p.orientation_sign
    )
    assert force > 0.0, force
    np.testing.assert_allclose(force, fy, rtol=1e-9)
    np.testing.assert_allclose(force, sim.P[P_F0] * 0.2**2, rtol=1e-2)  # F0·(I/I0)² at δ0
    # the other units feel nothing
    others = slice(NQ + Q_UY + 1, NQ + Q_UY + 4)
    np.testing.assert_array_equal(dydt[others], base[others])
    print("toy actuator ok")
    """
)


def test_toy_actuator_kind_through_the_extension_point() -> None:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    res = subprocess.run(
        [sys.executable, "-c", SCRIPT],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=1800,
    )
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-6000:]
    assert "toy actuator ok" in res.stdout
