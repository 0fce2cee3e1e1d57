"""Residual controllers (agents/controllers/residual.py): at zero correction the residual
controller flies as its base law bit for bit (``lqr-preview`` with the levitation currents
and with the guidance pairs, single and batched, a few hundred steps with the preview
active and a row restarted midway); the correction's arithmetic; the run record."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from agents.controllers.base import ControllerError
from agents.controllers.registry import GUIDED, LEVITATION, make_controller
from agents.controllers.residual import (
    ResidualController,
    ZeroPolicy,
    apply_correction,
    check_record,
    make_residual,
    run_record,
)
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

STEPS = 300  # the rear units' preview is active from step 58 at 1000 km/h


class _Constant:
    """A policy answering ``value`` everywhere (a correction that is not zero)."""

    def __init__(self, n: int, value: float) -> None:
        self.n, self.value = n, value

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.full(self.n, self.value, dtype=np.float32)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        return np.full((np.shape(obs)[0], self.n), self.value, dtype=np.float32)


def _venv(actuators: str, n: int = 3) -> HyperloopSuspensionVectorEnv:
    return HyperloopSuspensionVectorEnv(
        n, scenario="paper-1000-straight", track_length_m=400.0, actuators=actuators
    )


def _fly_batch(ctrl: object, actuators: str) -> list[bytes]:
    """Every action (as bytes) of ``ctrl`` flying 3 rows in closed loop; row 1 restarts at
    step 150 (a masked reset, as the evaluation engine does)."""
    venv = _venv(actuators)
    obs, _ = venv.reset(seed=11)
    ctrl.reset_batch(np.ones(3, dtype=bool))
    out = []
    for k in range(STEPS):
        a = ctrl.act_batch(obs)
        out.append(np.asarray(a).tobytes())
        obs, *_ = venv.step(a)
        if k == 150:
            mask = np.array([False, True, False])
            obs, _ = venv.reset(options={"reset_mask": mask})
            ctrl.reset_batch(mask)
    return out


def _fly_single(ctrl: object, actuators: str) -> list[bytes]:
    venv = _venv(actuators, 1)
    obs, _ = venv.reset(seed=12)
    ctrl.reset()
    out = []
    for _ in range(STEPS):
        a = ctrl.act(obs[0])
        out.append(np.asarray(a).tobytes())
        obs, *_ = venv.step(a[None, :])
    return out


@pytest.mark.parametrize("actuators", [LEVITATION, GUIDED])
def test_zero_correction_flies_as_the_base_bit_for_bit(actuators: str) -> None:
    """The issue's test: ``lqr-preview`` and ``lqr-preview+g`` with a zero policy (and with
    scale 0 under a policy that is not zero) against the bare base law, batched and single."""
    venv = _venv(actuators)
    n = venv.single_action_space.shape[0]
    ref_b = _fly_batch(make_controller("lqr-preview", venv), actuators)
    ref_s = _fly_single(make_controller("lqr-preview", venv), actuators)
    for policy, scale in ((ZeroPolicy(n), 0.2), (_Constant(n, 0.7), 0.0)):
        res = ResidualController(make_controller("lqr-preview", venv), policy, scale)
        assert _fly_batch(res, actuators) == ref_b
        assert _fly_single(res, actuators) == ref_s
    # the factory without a run: the base law and a zero policy
    res = make_controller("agents.controllers.residual:make_residual", venv)
    assert isinstance(res.policy, ZeroPolicy) and res.base.name == "lqr-preview"
    assert _fly_batch(res, actuators) == ref_b


def test_a_correction_moves_the_base_action() -> None:
    venv = _venv(LEVITATION)
    base = make_controller("lqr-preview", venv)
    res = ResidualController(make_controller("lqr-preview", venv), _Constant(4, 0.5), 0.1)
    obs, _ = venv.reset(seed=3)
    base.reset_batch(np.ones(3, dtype=bool))
    res.reset_batch(np.ones(3, dtype=bool))
    for _ in range(20):
        a0, a1 = base.act_batch(obs), res.act_batch(obs)
        np.testing.assert_allclose(a1, np.clip(a0 + np.float32(0.05), -1, 1), rtol=0, atol=1e-7)
        obs, *_ = venv.step(a0)


def test_apply_correction() -> None:
    base = np.array([-0.0, 0.0, 0.95, -0.9, 0.3], dtype=np.float32)
    c = np.array([0.0, -0.0, 1.0, -1.0, 0.5], dtype=np.float32)
    out = apply_correction(base, c, 0.1)
    assert out.dtype == np.float32
    assert out[:2].tobytes() == base[:2].tobytes()  # zero correction: the base, sign and all
    np.testing.assert_array_equal(out[2:4], [1.0, -1.0])  # clipped to the action range
    assert out[4] == np.float32(0.3) + np.float32(0.1) * np.float32(0.5)
    assert np.isnan(apply_correction(base, np.full(5, np.nan), 0.1)).all()  # NaN is seen


def _correction_by_numpy(base, correction, scale):  # noqa: ANN001, ANN202
    """The correction as whole-array NumPy steps (the reference of the compiled pass)."""
    b = np.asarray(base, dtype=np.float32)
    d = np.float32(scale) * np.asarray(correction, dtype=np.float32)
    out = np.clip(b + d, np.float32(-1.0), np.float32(1.0))
    return np.where(d == 0, b, out).astype(np.float32)


def test_apply_correction_is_the_numpy_steps_bit_for_bit() -> None:
    """Random actions and corrections with signed zeros, NaN, ±inf, float64 corrections and
    a broadcast row: the compiled pass equals the NumPy steps bit for bit."""
    rng = np.random.default_rng(0)
    for t in range(200):
        shape = (int(rng.integers(1, 70)), int(rng.integers(1, 9)))
        b = (rng.standard_normal(shape) * 0.7).astype(np.float32)
        c = rng.uniform(-1.2, 1.2, shape).astype(np.float32)
        c[rng.random(shape) < 0.2] = 0.0
        c[rng.random(shape) < 0.05] = -0.0
        b[rng.random(shape) < 0.1] = -0.0
        c[rng.random(shape) < 0.02] = np.nan
        b[rng.random(shape) < 0.02] = np.inf
        scale = float(rng.choice([0.0, 0.1, 1.0, 2.0]))
        cc = c.astype(np.float64) if t % 3 == 0 else c
        for args in ((b, cc), (b[0], c[0]), (b, c[0])):
            want = _correction_by_numpy(*args, scale)
            got = apply_correction(*args, scale)
            assert got.shape == want.shape and got.tobytes() == want.tobytes(), t


def test_record_checks() -> None:
    assert check_record({"base": "lqr", "scale": 0.2}) == {
        "base": "lqr",
        "scale": 0.2,
        "base_kwargs": {},
    }
    for bad in ({"base": "lqr", "scale": -1}, {"base": "", "scale": 0.1}, {"base": 3},
                {"base": "lqr", "scale": 0.1, "other": 1}, "lqr"):  # fmt: skip
        with pytest.raises((ValueError, TypeError)):
            check_record(bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="scale"):
        ResidualController(ZeroPolicy(4), ZeroPolicy(4), float("inf"))


def test_run_record_needs_the_residual_entry(tmp_path: Path) -> None:
    with pytest.raises(ControllerError, match="cannot read"):
        run_record(tmp_path)
    (tmp_path / "training_log.json").write_text(json.dumps({"algo": "ppo"}))
    with pytest.raises(ControllerError, match="no 'residual' record"):
        run_record(tmp_path)
    rec = {"base": "lqr-preview", "scale": 0.1}
    (tmp_path / "training_log.json").write_text(json.dumps({"residual": rec}))
    assert run_record(tmp_path / "model.zip")["scale"] == 0.1
    with pytest.raises(ControllerError):
        make_residual(None, tmp_path)  # the record reads, the model is missing
