"""The safety filter (:mod:`agents.controllers.shield`) by value: with an infinite limit it is
its controller bit for bit; a proposal whose held prediction leaves the bound is replaced by
the closest action whose prediction stays inside (checked against an independent prediction
and an independent solver); where nothing is feasible the least-violating action is sent and
counted; ``shielded:<name>`` works wherever a controller name does."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.optimize import minimize

import hyperloop_env  # noqa: F401  (registration)
from agents import make_controller
from agents.controllers.base import BaseController, control_context
from agents.controllers.registry import controller_problem, controller_spec, resolve
from agents.controllers.shield import BatchShield, Shield, ShieldDesign
from agents.evaluation.entrants import entrant_actuators, entrant_label
from agents.evaluation.seeds import check_evaluation_seeds, is_learned

GUIDED = "levitation+guidance"


def _env(actuators: str = "levitation", **kw):  # noqa: ANN202
    kw.setdefault("scenario", "paper-2000-curved")
    kw.setdefault("track_length_m", 400.0)
    return gym.make("HyperloopSuspension-v0", disable_env_checker=True, actuators=actuators, **kw)


class Constant(BaseController):
    """Sends one action every step (no act_batch)."""

    name = "constant"

    def __init__(self, action: np.ndarray) -> None:
        self.action = np.asarray(action, dtype=np.float32)

    def act(self, obs: np.ndarray) -> np.ndarray:
        return self.action.copy()


def _prediction(ctx, u: np.ndarray, steps: int) -> np.ndarray:  # noqa: ANN001
    """Gap excursions [mm] (steps, 4) of the vertical design model from x = 0 with the
    action ``u`` held, by direct iteration (independent of the filter's condensed form)."""
    from agents.controllers.lqr import design_lqg

    m = design_lqg(ctx)
    a_per_A = 1.0 / (ctx.nominal_current_A * ctx.action_scale)
    x = np.zeros(m.Phi.shape[0])
    out = []
    for _ in range(steps):
        x = m.Phi @ x + m.Gam @ (np.asarray(u, dtype=np.float64) / a_per_A)
        out.append(1e3 * m.C_s @ x)
    return np.array(out)


# -- bit for bit with an infinite limit -------------------------------------------------------


@pytest.mark.parametrize(
    "name, actuators",
    [
        ("lqr", "levitation"),
        ("pid", "levitation"),
        ("ppo", "levitation"),
        ("lqr", GUIDED),
        ("pid", GUIDED),
        ("ppo-guidance", GUIDED),
    ],
)
def test_infinite_limit_is_the_controller_bit_for_bit(name: str, actuators: str) -> None:
    """Margin 0 and limit ∞: the same actions, bit for bit, over 300 closed-loop steps, on
    act (single vehicle) and act_batch (the proposal array itself is returned)."""
    pytest.importorskip("torch") if name.startswith("ppo") else None
    envs = [_env(actuators), _env(actuators)]
    obs = [e.reset(seed=1_000_003)[0] for e in envs]
    bare = make_controller(name, envs[0])
    sh = make_controller(f"shielded:{name}", envs[1], margin_mm=0.0, limit_mm=math.inf)
    assert isinstance(sh, Shield)
    bare.reset()
    sh.reset()
    for _ in range(300):
        a, b = bare.act(obs[0]), sh.act(obs[1])
        np.testing.assert_array_equal(a, b)
        assert a.dtype == b.dtype
        obs = [e.step(x)[0] for e, x in zip(envs, (a, b), strict=True)]
    assert sh.stats["steps"] == 300 and sh.stats["changed"] == 0
    if callable(getattr(bare, "act_batch", None)):
        assert isinstance(sh, BatchShield)
        batch = np.stack([obs[0]] * 3)
        bare.reset_batch(np.ones(3, bool))
        sh.reset_batch(np.ones(3, bool))
        for _ in range(5):
            np.testing.assert_array_equal(bare.act_batch(batch), sh.act_batch(batch))
        # a shipped agent without memory is one shared instance: leave it as found
        bare.reset()
        sh.reset()


def test_infinite_limit_returns_the_proposal_array_itself() -> None:
    """act and act_batch return the controller's own array (no copy, no cast)."""
    ctx = control_context(None)
    proposal = np.array([[0.25, -0.5, 0.125, 1.0]] * 2, dtype=np.float32)

    class Fixed(Constant):
        def act_batch(self, o: np.ndarray) -> np.ndarray:
            return proposal

        def act(self, o: np.ndarray) -> np.ndarray:
            return proposal[0]

    sh = Shield(Fixed(proposal[0]), ctx, margin_mm=0.0, limit_mm=math.inf)
    obs = np.zeros((2, ctx.observation.size), dtype=np.float32)
    assert sh.act_batch(obs) is proposal
    assert np.shares_memory(sh.act(obs[0]), proposal)  # the controller's own row view
    assert sh.stats["steps"] == 3 and sh.stats["changed"] == 0


def test_default_shield_leaves_a_calm_run_alone() -> None:
    """The default bound (8 − 2 mm) never binds for the LQR on a nominal run."""
    env = _env()
    obs, _ = env.reset(seed=1_000_000)
    sh = make_controller("shielded:lqr", env)
    bare = make_controller("lqr", env)
    for _ in range(300):
        a = sh.act(obs)
        np.testing.assert_array_equal(a, bare.act(obs))
        obs = env.step(a)[0]
    assert sh.counters()["steps"] == 300 and sh.counters()["changed_fraction"] == 0.0


# -- the QP by value -------------------------------------------------------------------------


def test_violating_proposal_is_replaced_by_the_closest_safe_action() -> None:
    """From x = 0 (a fresh filter, a zero observation), the full-current proposal held for
    10 ms predicts excursions above the bound (0.5 mm); the filtered action's independent
    prediction stays inside it, and it is the closest such action (SLSQP on the same
    problem, built from the direct iteration)."""
    ctx = control_context(None)
    lo, hi = ctx.action_limits()
    proposal = np.full(4, hi, dtype=np.float32)
    d = ShieldDesign(margin_mm=0.5, limit_mm=1.0, horizon_steps=10)
    sh = Shield(Constant(proposal), ctx, d)
    sh.reset()
    H = d.horizon_steps
    assert np.abs(_prediction(ctx, proposal, H)).max() > 0.5 + 0.1  # it would leave the bound
    a = sh.act(np.zeros(ctx.observation.size, dtype=np.float32))
    assert a.dtype == np.float32 and a.shape == (4,)
    assert np.abs(_prediction(ctx, a, H)).max() <= 0.5 + 1e-5
    assert sh.stats == {"steps": 1, "changed": 1, "infeasible": 0, "qp_solves": 1, "qp_unsolved": 0}

    # the closest action inside the bound and the limits, solved independently
    def worst(u: np.ndarray) -> np.ndarray:
        return 0.5 - np.abs(_prediction(ctx, u, H)).ravel()

    ref = minimize(
        lambda u: float(np.sum((u - proposal) ** 2)),
        np.zeros(4),
        constraints=[{"type": "ineq", "fun": worst}],
        bounds=[(lo, hi)] * 4,
        method="SLSQP",
        options={"ftol": 1e-12, "maxiter": 500},
    )
    assert ref.success
    np.testing.assert_allclose(a, ref.x, atol=2e-4)
    assert 0.0 < a.max() < hi


def test_nothing_feasible_sends_the_least_violating_action_and_says_so() -> None:
    """A measured excursion of 4 mm on every unit with a 0.5 mm bound: no action inside the
    limits brings the prediction back within 10 ms (authority < 1 mm per unit of action), so
    the filter sends the least-violating action — the full opposing current, at its limit —
    and counts the step infeasible."""
    ctx = control_context(None)
    lo, hi = ctx.action_limits()
    spec = ctx.observation
    obs = np.zeros(spec.size, dtype=np.float32)
    gap = spec.start("gap")
    obs[gap : gap + 4] = 4e-3 / ctx.clearance_m  # +4 mm
    d = ShieldDesign(margin_mm=0.5, limit_mm=1.0)
    sh = Shield(Constant(np.zeros(4)), ctx, d)
    sh.reset()
    a = sh.act(obs)
    assert sh.stats["infeasible"] == 1 and sh.stats["changed"] == 1
    assert sh.counters()["infeasible_fraction"] == 1.0
    # a positive action raises the excursion (Pu > 0), so the least-violating one is lo
    assert (sh._filters[0].Pu[-4:].diagonal() > 0).all()
    np.testing.assert_allclose(a, np.full(4, lo), atol=1e-6)


def test_batch_rows_are_independent_and_only_violating_rows_change() -> None:
    """act_batch row i equals the single filter fed row i; rows whose proposal passes are
    returned unchanged, bit for bit."""
    ctx = control_context(None)
    spec = ctx.observation
    rng = np.random.default_rng(0)
    obs = np.zeros((4, spec.size), dtype=np.float32)
    gap = spec.start("gap")
    obs[:, gap : gap + 4] = rng.uniform(-0.02, 0.02, (4, 4))
    obs[2, gap : gap + 4] = 0.06  # ~0.5 mm: near the bound

    class Batched(Constant):
        def act_batch(self, o: np.ndarray) -> np.ndarray:
            return np.tile(self.action, (o.shape[0], 1))

        def reset_batch(self, mask: np.ndarray) -> None:
            pass

    prop = np.array([0.9, 0.9, 0.9, 0.9], dtype=np.float32)
    d = ShieldDesign(margin_mm=0.5, limit_mm=1.0)
    sb = Shield(Batched(prop), ctx, d)
    assert isinstance(sb, BatchShield)
    sb.reset_batch(np.ones(4, bool))
    out = sb.act_batch(obs)
    changed = (out != prop).any(axis=1)
    assert sb.stats["changed"] == int(changed.sum()) >= 1 and sb.stats["steps"] == 4
    for i in range(4):
        s1 = Shield(Constant(prop), ctx, d)
        s1.reset()
        np.testing.assert_array_equal(s1.act(obs[i]), out[i])
    sb.idle_batch(np.array([True, True, True, True]))
    before = dict(sb.stats)
    sb.act_batch(obs)  # idle rows: no QP, not counted
    assert sb.stats["qp_solves"] == before["qp_solves"] and sb.stats["steps"] == before["steps"]


def test_shield_keeps_a_bad_controller_off_the_rail() -> None:
    """A controller that asks for full current on every unit touches within a few tens of
    milliseconds; wearing the filter (margin 2 mm) it changes actions and flies longer."""
    ctx_env = _env(scenario="paper-1000-straight")

    def fly(ctrl, env) -> int:  # noqa: ANN001
        obs, _ = env.reset(seed=1_000_001)
        ctrl.reset()
        for k in range(400):
            obs, _, term, trunc, _ = env.step(ctrl.act(obs))
            if term or trunc:
                return k
        return 400

    hi = control_context(ctx_env).action_limits()[1]
    bare = fly(Constant(np.full(4, hi)), ctx_env)
    sh = Shield(Constant(np.full(4, hi)), control_context(ctx_env))
    shielded = fly(sh, _env(scenario="paper-1000-straight"))
    assert bare < 100 and shielded > bare
    assert sh.stats["changed"] > 0


# -- options and names ------------------------------------------------------------------------


def test_bad_options_are_refused_naming_the_field() -> None:
    ctx = control_context(None)
    c = Constant(np.zeros(4))
    with pytest.raises(TypeError, match="margn_mm"):
        Shield(c, ctx, margn_mm=1.0)
    with pytest.raises(TypeError):
        make_controller("shielded:lqr", None, no_such_option=1)
    for kw, field in [
        ({"margin_mm": -1.0}, "margin_mm"),
        ({"margin_mm": math.nan}, "margin_mm"),
        ({"limit_mm": 1.0, "margin_mm": 2.0}, "limit_mm"),
        ({"horizon_steps": 0}, "horizon_steps"),
        ({"horizon_steps": 2.5}, "horizon_steps"),
        ({"slack_linear": 0.0}, "slack_linear"),
        ({"max_iter": 0}, "max_iter"),
    ]:
        with pytest.raises(ValueError, match=field):
            Shield(c, ctx, **kw)
        with pytest.raises(ValueError, match=field):
            make_controller("shielded:lqr", None, **kw)


def test_shielded_names_in_the_registry_and_the_tools() -> None:
    spec = controller_spec("shielded:ppo-guidance")
    assert spec is not None and spec.kind == "learned" and spec.actuators == (GUIDED,)
    assert spec.shipped == "ppo-guidance" and not spec.default and spec.entrant == ()
    assert is_learned("shielded:ppo") and is_learned("shielded:ppo+g") is True
    assert not is_learned("shielded:lqr")
    assert entrant_actuators("shielded:lqr+g") == ("shielded:lqr", GUIDED)
    assert entrant_label(*entrant_actuators("shielded:lqr+g")) == "shielded:lqr+g"
    assert entrant_actuators("shielded:pid") == ("shielded:pid", "levitation")
    assert controller_problem("shielded:lqr") is None
    with pytest.raises(ValueError, match="training range"):
        check_evaluation_seeds(["shielded:ppo"], [5])
    for bad in ("shielded:", "shielded:nope", "shielded:shielded:lqr"):
        assert controller_problem(bad) is not None
        with pytest.raises(ValueError):
            resolve(bad)
    with pytest.raises(ValueError, match="nope"):
        entrant_actuators("shielded:nope")
    ctrl = make_controller("shielded:pid", control_context(None), horizon_steps=5)
    assert ctrl.name == "shielded:pid" and ctrl.design.horizon_steps == 5


def test_the_command_line_tools_take_shielded_names(tmp_path, capsys) -> None:  # noqa: ANN001
    """``hyperloop evaluate`` and ``hyperloop capacity`` fly ``shielded:<name>``; an
    unknown shielded name is one error line (exit status 2) in ``capacity`` and ``score``."""
    from agents.cli import main

    common = ["--seeds", "2", "--no-progress", "--no-figures", "--overwrite"]
    out = tmp_path / "ev"
    argv = ["evaluate", "--controllers", "shielded:lqr", "--conditions", "paper-2000-straight"]
    assert main([*argv, "--distance-km", "1.2", "--out", str(out), *common]) == 0
    assert "shielded:lqr" in (out / "report.md").read_text()
    cap = tmp_path / "cap"
    argv = ["capacity", "--entrants", "shielded:pid+g", "--conditions", "paper-2000-straight"]
    argv += ["--families", "roughness", "--distance-km", "0.3", "--workers", "1"]
    assert main([*argv, "--out", str(cap), *common]) == 0
    assert "shielded:pid+g" in (cap / "headline.md").read_text()
    capsys.readouterr()
    for bad in (
        ["capacity", "--entrants", "shielded:nope", "--out", str(tmp_path / "x")],
        ["score", "shielded:nope", "--out", str(tmp_path / "y")],
    ):
        with pytest.raises(SystemExit) as exc:
            main(bad)
        assert exc.value.code == 2
        assert "'shielded:nope'" in capsys.readouterr().err
