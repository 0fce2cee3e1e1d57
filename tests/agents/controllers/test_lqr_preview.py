"""``lqr-preview`` (agents/controllers/lqr_preview.py): the LQG with a finite-preview
feed-forward of the guideway the front units measured to the rear units. Values, not
shapes: the preview gains against the LQR's own Riccati solution, their certainty
equivalence and their effect in the linear design model, the closed loop in the simulator
against plain ``lqr`` (pinned), the batched law against the one-row law, the no-preview
limits against ``lqr`` bit for bit, the tuned weight against its scan, bad input."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from agents.controllers.lqr import LQRController
from agents.controllers.lqr_preview import PREVIEW_WEIGHT, LQRPreviewController, _track_cols
from agents.controllers.registry import GUIDED, LEVITATION, controller_spec, make_controller
from agents.evaluation.rollout import make_env, run_episodes
from hyperloop_env.config import EnvConfig

SEEDS = [1, 2, 3, 4]


def _rms(eps: list, units: slice) -> float:
    g = np.concatenate([e.gap_m[500:, units] for e in eps])
    return float(np.sqrt((g**2).mean()))


def test_zero_preview_gain_is_the_lqr_gain_and_gains_decay() -> None:
    p = EnvConfig(scenario="paper-1000-straight").resolve().base
    c = LQRPreviewController(p)
    g = c.gains[0]
    k_rho = c.matrices.K[:, g.rear_cols]
    np.testing.assert_allclose(g.tail[0], k_rho, rtol=1e-6, atol=1e-9 * np.abs(k_rho).max())
    assert g.horizon == 250  # 0.25 s at 1 ms
    # the preview gains fade with the look-ahead (the closed loop is stable)
    assert np.abs(g.pure[200]).max() < 2e-3 * np.abs(g.pure[:10]).max()


def test_the_model_prediction_as_preview_is_the_lqr_law() -> None:
    """Σ_{j<N} K_j Φ_ρ^j + K_N^tail Φ_ρ^N = K_ρ for every N (module docstring): a preview
    that only repeats the track model's prediction leaves the LQR's command unchanged, so
    the law needs only the measured changes. Both planes."""
    p = EnvConfig(scenario="paper-1000-straight", actuators=GUIDED).resolve().base
    c = LQRPreviewController(p)
    for m, g in zip((c.matrices, c.lateral_matrices), c.gains, strict=True):
        F = m.Phi[np.ix_(g.rear_cols, g.rear_cols)]
        scale = np.abs(g.k_rear).max()
        for N in (1, 29, 58, 250):
            total = g.tail[N] @ np.linalg.matrix_power(F, N)
            for j in range(N):
                total = total + g.pure[j] @ np.linalg.matrix_power(F, j)
            np.testing.assert_allclose(total, g.k_rear, rtol=0, atol=1e-9 * scale)
        # the constant-future sum is not the LQR's gain: the trend matters
        assert np.abs(g.pure[:58].sum(axis=0) + g.tail[58] - g.k_rear).max() > 1e-3 * scale


def _linear_rear_rms(preview: bool, n_steps: int = 4000) -> np.ndarray:
    """Gap RMS [m] of the four units in the LQR's linear design model (full state known)
    on a band-limited guideway profile (2–60 Hz at the control rate, 0.5 mm RMS) that the
    rear units meet N = 58 steps (16 m at 1000 km/h) after the front units; with
    ``preview`` the exact future profile enters through the preview gains."""
    from scipy.signal import butter, sosfilt

    p = EnvConfig(scenario="paper-1000-straight").resolve().base
    c = LQRPreviewController(p)
    m, g = c.matrices, c.gains[0]
    n, nu, dt, lag = m.Phi.shape[0], 4, 1e-3, 58
    A = np.zeros((n + nu, n + nu))
    A[:n, :n], A[n:, :n], A[n:, n:] = m.Phi, dt * m.C_s, np.eye(nu)
    B = np.vstack([m.Gam, np.zeros((nu, nu))])
    w = np.random.default_rng(0).normal(size=n_steps + lag + 1)
    prof = sosfilt(butter(2, [2.0, 60.0], "bandpass", fs=1000.0, output="sos"), w)
    prof *= 0.5e-3 / prof.std()
    rate = np.gradient(prof) / dt
    z = np.zeros(n + nu)
    gaps = []
    for k in range(n_steps):
        for a in range(4):
            r, rd = _track_cols(n, (a,))
            k_a = k + (lag if a < 2 else 0)
            z[r], z[rd] = prof[k_a], rate[k_a]
        u = -m.K @ z
        if preview:
            u += g.k_rear @ z[g.rear_cols]
            for j in range(lag + 1):
                rho = np.array([prof[k + j], rate[k + j]] * 2)
                u -= (g.pure[j] if j < lag else g.tail[lag]) @ rho
        gaps.append(m.C_s @ z[:n])
        z = A @ z + B @ u
    return np.sqrt((np.array(gaps)[500:] ** 2).mean(axis=0))


def test_exact_preview_lowers_the_rear_gaps_in_the_design_model() -> None:
    """Measured: rear 0.466 -> 0.453 mm (ratio 0.972), front 0.470 -> 0.464 mm (0.987): the exact
    future guideway helps, but little (the LQR already feeds the current track forward and
    trades gap against heave acceleration). A wrong sign of the preview raises both."""
    plain, prev = _linear_rear_rms(False), _linear_rear_rms(True)
    rear = prev[2:].mean() / plain[2:].mean()
    front = prev[:2].mean() / plain[:2].mean()
    assert rear == pytest.approx(0.972, abs=0.005)
    assert front == pytest.approx(0.987, abs=0.005)


def test_closed_loop_against_lqr_on_paper_1000_straight() -> None:
    """Pinned (4 seeds × 1 km, default weight α = 0.5): the preview brings the rear units'
    RMS gap excursion to ≈ 0.556 of plain LQR's and raises the front units' ≈ 1.12× (module
    docstring: the beam's deflection under the vehicle). No contact. With α = 1 the rear
    units gain more and the front units lose more (≈ 0.38 / 1.27): the pin moves with α."""
    lqr = run_episodes("lqr", "paper-1000-straight", SEEDS, 1.0)
    prev = run_episodes("lqr-preview", "paper-1000-straight", SEEDS, 1.0)
    full = run_episodes(
        "lqr-preview", "paper-1000-straight", SEEDS, 1.0, controller_kwargs={"preview_weight": 1.0}
    )
    assert not any(e.terminated for e in lqr + prev + full)
    rear = _rms(prev, slice(2, 4)) / _rms(lqr, slice(2, 4))
    front = _rms(prev, slice(0, 2)) / _rms(lqr, slice(0, 2))
    assert rear == pytest.approx(0.556, abs=0.01)
    assert front == pytest.approx(1.119, abs=0.01)
    assert _rms(full, slice(2, 4)) / _rms(lqr, slice(2, 4)) == pytest.approx(0.377, abs=0.01)
    assert _rms(full, slice(0, 2)) / _rms(lqr, slice(0, 2)) == pytest.approx(1.273, abs=0.01)


def test_guidance_preview_lowers_the_rear_lateral_gaps() -> None:
    """With the guidance pairs actuated the lateral plane gets the same preview: on
    paper-1000-straight (4 seeds × 1 km) the rear units' lateral offset, about its mean,
    falls to ≈ 0.873 of `lqr`'s RMS while the front units' stays (≈ 0.999); the levitation
    gaps move as without guidance (rear ≈ 0.550). Pinned."""
    kw = {"actuators": GUIDED}
    lqr = run_episodes("lqr", "paper-1000-straight", SEEDS, 1.0, env_kwargs=kw)
    prev = run_episodes("lqr-preview", "paper-1000-straight", SEEDS, 1.0, env_kwargs=kw)
    assert not any(e.terminated for e in lqr + prev)

    def lat(eps: list, units: slice) -> float:
        g = np.concatenate([e.lateral_m[500:, units] for e in eps])
        return float(np.sqrt(((g - g.mean(axis=0)) ** 2).mean()))

    assert lat(prev, slice(2, 4)) / lat(lqr, slice(2, 4)) == pytest.approx(0.873, abs=0.01)
    assert lat(prev, slice(0, 2)) / lat(lqr, slice(0, 2)) == pytest.approx(0.999, abs=0.01)
    assert _rms(prev, slice(2, 4)) / _rms(lqr, slice(2, 4)) == pytest.approx(0.550, abs=0.01)


@pytest.mark.parametrize(
    ("scenario", "mm"), [("paper-1000-straight", 0.98), ("paper-2000-straight", 0.45)]
)
def test_beam_deflection_differs_between_front_and_rear_passage(scenario: str, mm: float) -> None:
    """The number the module docstring and the README give for why the front units' change
    is not the rear units': under `lqr` (seed 1, 1 km) the guideway deflection under a rear
    unit minus the deflection the front unit of its side had at the same place (units at
    ±d1/2 from the capsule centre) varies with ≈ 0.98 mm standard deviation at 1000 km/h,
    ≈ 0.45 mm at 2000 km/h. Pinned."""
    from hyperloop_env.physics.model import Measurement

    env = make_env(scenario, track_length_m=1000.0)
    obs, _ = env.reset(seed=1)
    ctrl = make_controller("lqr", env)
    w, x, done = [], [], False
    while not done:
        obs, _, te, tr, _ = env.step(ctrl.act(obs))
        done = te or tr
        m = Measurement.from_record(env.unwrapped.sim.meas)
        w.append(m.guideway_deflection_m.copy())
        x.append(m.position_m)
    env.close()
    w, x = np.array(w), np.array(x)
    half = env.unwrapped.sim.params.vehicle.set_spacing_m / 2.0
    front, rear = x + half, x - half
    seen = rear > front[0] + 5.0  # the rear units where the front units have been
    diff = np.concatenate([(w[:, 2 + s] - np.interp(rear, front, w[:, s]))[seen] for s in (0, 1)])
    assert diff.std() * 1e3 == pytest.approx(mm, abs=0.02)


def _recorded_obs(actuators: str, seeds: list[int], n_steps: int) -> np.ndarray:
    """Observations (seeds, steps, obs_size) of closed-loop runs of ``lqr-preview``."""
    out = []
    for seed in seeds:
        env = make_env("paper-1000-straight", track_length_m=500.0, actuators=actuators)
        obs, _ = env.reset(seed=seed)
        ctrl = make_controller("lqr-preview", env)
        ctrl.reset(seed=seed)
        rows = []
        for _ in range(n_steps):
            rows.append(obs)
            obs, *_ = env.step(ctrl.act(obs))
        env.close()
        out.append(rows)
    return np.array(out, dtype=np.float32)


def _batch_and_rows(
    actuators: str, obs: np.ndarray, reset_step: int, reset_rows: list[int]
) -> tuple[np.ndarray, np.ndarray, object]:
    """The batched law on the rows of ``obs`` (rows, steps, obs) and the one-row law on
    each, the rows ``reset_rows`` reset at ``reset_step``: (batched actions, one-row
    actions), each (steps, rows, n_act), and the batched controller."""
    env = make_env("paper-1000-straight", track_length_m=500.0, actuators=actuators)
    n = obs.shape[0]
    batch = make_controller("lqr-preview", env)
    singles = [make_controller("lqr-preview", env) for _ in range(n)]
    for s in singles:
        s.reset()
    batch.reset_batch(np.ones(n, dtype=bool))
    got, want = [], []
    for k in range(obs.shape[1]):
        if k == reset_step:
            batch.reset_batch(np.isin(np.arange(n), reset_rows))
            for i in reset_rows:
                singles[i].reset()
        got.append(batch.act_batch(obs[:, k]))
        want.append([s.act(obs[i, k]) for i, s in enumerate(singles)])
    env.close()
    return np.array(got), np.array(want), batch


@pytest.mark.parametrize("actuators", [LEVITATION, GUIDED])
def test_act_batch_is_act_row_by_row(actuators: str) -> None:
    """300 steps (the preview is active from step 58 on) of three seeds: the batched law on
    the rows equals the one-row law on each, also after one row is reset mid-way."""
    obs = _recorded_obs(actuators, [0, 1, 2], 300)
    got, want, _ = _batch_and_rows(actuators, obs, 150, [1])
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-7)
    assert float(np.abs(got).max()) > 1e-3


@pytest.mark.parametrize("actuators", [LEVITATION, GUIDED])
def test_no_preview_is_plain_lqr_bit_for_bit(actuators: str) -> None:
    """``max_preview_s=0``, ``preview_weight=0`` and a set spacing shorter than half a
    step's travel (N = 0) give exactly the LQR's commands (act_batch and act); with the
    preview they differ."""
    obs = _recorded_obs(actuators, [3, 4], 200)
    cfg = EnvConfig(scenario="paper-1000-straight", actuators=actuators)
    p = cfg.resolve().base
    short = replace(p, vehicle=replace(p.vehicle, set_spacing_m=0.1))
    for params, kw in ((p, {"max_preview_s": 0.0}), (p, {"preview_weight": 0.0}), (short, {})):
        lqr, prev, prev1 = (
            LQRController(params),
            LQRPreviewController(params, **kw),
            LQRPreviewController(params, **kw),
        )
        lqr1 = LQRController(params)
        for k in range(obs.shape[1]):
            want = lqr.act_batch(obs[:, k])
            np.testing.assert_array_equal(prev.act_batch(obs[:, k]), want)
            np.testing.assert_array_equal(prev1.act(obs[0, k]), lqr1.act_batch(obs[:1, k])[0])
    lqr, prev = LQRController(p), LQRPreviewController(p)
    diff = max(
        float(np.abs(prev.act_batch(obs[:, k]) - lqr.act_batch(obs[:, k])).max())
        for k in range(obs.shape[1])
    )
    assert diff > 1e-3


def test_bad_input_raises_value_error() -> None:
    ctrl = make_controller("lqr-preview")
    size = ctrl.ctx.observation.size
    with pytest.raises(ValueError, match=rf"obs must have shape \({size},\)"):
        ctrl.act(np.zeros(size + 1))
    with pytest.raises(ValueError, match=rf"obs must have shape \(N, {size}\)"):
        ctrl.act_batch(np.zeros(size))
    with pytest.raises(ValueError, match=rf"obs must have shape \(N, {size}\)"):
        ctrl.act_batch(np.zeros((2, size - 1)))
    with pytest.raises(ValueError, match="max_preview_s"):
        make_controller("lqr-preview", max_preview_s=-1.0)
    for bad in (-0.1, 2.5, float("nan"), True, "0.5"):
        with pytest.raises(ValueError, match="preview_weight"):
            make_controller("lqr-preview", preview_weight=bad)
    with pytest.raises(TypeError):
        make_controller("lqr-preview", preview_wieght=0.5)


def test_default_weight_is_the_best_of_its_scan() -> None:
    """PREVIEW_WEIGHT is the scan's best α (agents/controllers/lqr_preview_weight.json,
    written by hyperloop tune preview on validation seeds, never evaluation seeds)."""
    from agents.evaluation.seeds import CALIBRATION_SEED0, VALIDATION_SEED0

    doc = json.loads(
        (
            Path(__file__).resolve().parents[3] / "agents/controllers/lqr_preview_weight.json"
        ).read_text()
    )
    best = max(doc["scan"], key=lambda r: r["score"])
    assert doc["weight"] == best["weight"] == PREVIEW_WEIGHT
    for row in doc["scan"]:
        logs = [np.log(c["ratio"]) for c in row["conditions"].values()]
        assert row["score"] == pytest.approx(float(np.mean(logs)), abs=1e-12)
    lo, hi = doc["seeds"]
    assert VALIDATION_SEED0 <= lo <= hi < CALIBRATION_SEED0  # validation seeds only


def test_registered_as_an_entrant_not_a_default() -> None:
    spec = controller_spec("lqr-preview")
    assert spec is not None
    assert spec.entry_point == "agents.controllers.factories:lqr_preview"
    assert (spec.kind, spec.actuators, spec.default, spec.entrant) == (
        "baseline",
        (LEVITATION, GUIDED),
        False,
        (LEVITATION, GUIDED),
    )
    for acts in (LEVITATION, GUIDED):
        env = make_env("paper-1000-straight", track_length_m=100.0, actuators=acts)
        obs, _ = env.reset(seed=0)
        ctrl = make_controller("lqr-preview", env)
        assert ctrl.name == "lqr-preview"
        a = ctrl.act(obs)
        assert a.shape == env.action_space.shape and a.dtype == np.float32
        env.close()


@pytest.mark.parametrize("actuators", [LEVITATION, GUIDED])
def test_rows_at_other_speeds_are_each_rows_own_law_bit_for_bit(actuators: str) -> None:
    """Rows whose measured speeds give two preview delays N in one batch (the side-by-side
    sums run once per delay) command exactly what the one-row law commands on each, also
    after two rows are reset mid-way."""
    obs = _recorded_obs(actuators, [0, 1, 2, 3], 260)
    env = make_env("paper-1000-straight", track_length_m=500.0, actuators=actuators)
    col = make_controller("lqr-preview", env).ctx.observation.start("speed")
    env.close()
    obs[0, :, col] *= 1.05  # N 58 -> 55 in rows 0 and 2
    obs[2, :, col] *= 1.05
    got, want, batch = _batch_and_rows(actuators, obs, 120, [0, 3])
    np.testing.assert_array_equal(got, want)
    delays = batch._batch[0].Nrow  # the last step's delay of each row (0: no preview)
    assert delays[0] == delays[2] != delays[1] == delays[3] and delays.min() > 0
