"""The one controller registry: entries by entry point with metadata, every tool's default
list derived from it (equal to the lists the tools had before), and registrations made in
the driver reaching spawned (and Ray) workers."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from agents.controllers import factories, registry
from agents.controllers.registry import (
    GUIDED,
    LEVITATION,
    controller_spec,
    make_controller,
    register_controller,
    resolve,
)
from agents.evaluation.backends import run_blocks

ROOT = Path(__file__).resolve().parents[3]


def test_every_default_list_equals_the_one_it_replaced() -> None:
    """The lists the tools hard-coded before the registry carried the metadata."""
    from agents.evaluation import benchmark, capacity_benchmark
    from agents.evaluation import reproduce_paper as rp
    from agents.training import presets

    levitation = ("passive", "pid", "lqr", "lqr-preview", "mpc", "ppo", "ppo-memory", "sac")
    guided = ("pid", "lqr", "lqr-preview", "ppo-guidance", "ppo-residual-guidance")
    # headline labels: "+g" marks a baseline that also drives the guidance pairs
    entrants = levitation + (
        "pid+g",
        "lqr+g",
        "lqr-preview+g",
        "ppo-guidance",
        "ppo-residual-guidance",
    )
    assert benchmark.DEFAULT_ENTRANTS == entrants
    assert capacity_benchmark.DEFAULT_ENTRANTS == entrants
    from agents.cli import benchmark as benchmark_cli

    assert benchmark_cli.build_parser().parse_args([]).entrants == list(entrants)
    from agents.cli import capacity as capacity_cli

    assert capacity_cli.build_parser().parse_args([]).entrants == list(entrants)
    from agents.cli import evaluate as evaluate_cli

    assert evaluate_cli.build_parser().parse_args([]).controllers == ["passive", "pid", "lqr"]
    from agents.cli import fragility as fragility_cli

    frag = fragility_cli.build_parser().parse_args(["--levels", "1"])
    assert frag.controllers == ["passive", "pid", "lqr"]
    assert presets.BASELINES == ("passive", "pid", "lqr")
    assert rp.CRITICAL_RADIUS_CASES == (
        ("passive", "levitation"),
        ("pid", "levitation"),
        ("lqr", "levitation"),
        ("pid", "levitation+guidance"),
        ("lqr", "levitation+guidance"),
    )
    assert rp.CONTROLLERS == ("passive", "pid", "lqr")
    # the golden fixtures' and the speed benchmarks' lists
    assert registry.entrants(LEVITATION) == list(levitation)
    assert registry.entrants(GUIDED) == list(guided)
    speed = next(d for d in (ROOT / "speed", ROOT / "benchmarks") if d.is_dir())
    sys.path.insert(0, str(speed))
    try:
        import bench_fragility as bench
    finally:
        sys.path.remove(str(speed))
    assert bench.CONTROLLERS == levitation
    assert bench.LOOP_CONTROLLERS == (*bench.CONTROLLERS, "ppo-guidance", "ppo-residual-guidance")
    guided_only = {"actuators": "levitation+guidance"}
    assert bench.GUIDED == {"ppo-guidance": guided_only, "ppo-residual-guidance": guided_only}


def test_metadata_of_the_builtins() -> None:
    both = ("levitation", "levitation+guidance")
    rows = {
        n: (s.kind, s.actuators, s.algo, s.shipped, s.default, s.entrant, s.entry_point)
        for n in (
            "passive",
            "pid",
            "lqr",
            "ppo",
            "ppo-memory",
            "ppo-guidance",
            "sac",
            "ppo-residual-guidance",
        )
        if (s := controller_spec(n))
    }
    ep = "agents.controllers.factories:"
    assert rows == {
        "passive": ("baseline", both, None, None, True, ("levitation",), ep + "passive"),
        "pid": ("baseline", both, None, None, True, both, ep + "pid"),
        "lqr": ("baseline", both, None, None, True, both, ep + "lqr"),
        "ppo": ("learned", ("levitation",), "ppo", "ppo", False, ("levitation",), ep + "ppo"),
        "ppo-memory": (
            "learned",
            ("levitation",),
            "ppo",
            "ppo-memory",
            False,
            ("levitation",),
            ep + "ppo_memory",
        ),
        "ppo-guidance": (
            "learned",
            ("levitation+guidance",),
            "ppo",
            "ppo-guidance",
            False,
            ("levitation+guidance",),
            ep + "ppo_guidance",
        ),
        "sac": ("learned", ("levitation",), "sac", "sac", False, ("levitation",), ep + "sac"),
        "ppo-residual-guidance": (
            "learned",
            ("levitation+guidance",),
            "ppo",
            "ppo-residual-guidance",
            False,
            ("levitation+guidance",),
            ep + "ppo_residual_guidance",
        ),
    }
    assert registry.shipped_folder("ppo-guidance") == ROOT / "agents" / "shipped" / "ppo-guidance"
    assert registry.shipped_folder("pid") is None
    assert registry.default_controllers() == ["passive", "pid", "lqr"]


@pytest.mark.parametrize(
    "name", ["ppo", "ppo-memory", "sac", "ppo-guidance", "ppo-residual-guidance"]
)
def test_a_shipped_agents_actuators_are_those_it_was_trained_with(name: str) -> None:
    log = json.loads((registry.shipped_folder(name) / "training_log.json").read_text())
    trained = (log.get("env_kwargs") or {}).get("actuators", "levitation")
    assert controller_spec(name).actuators == (trained,)


def test_one_resolver_for_names_entry_points_and_model_paths() -> None:
    assert resolve("pid") is factories.pid
    assert resolve("agents.controllers.factories:lqr") is factories.lqr
    assert resolve("ppo-guidance") is factories.ppo_guidance
    assert callable(resolve(str(registry.shipped_folder("ppo") / "model.zip")))
    with pytest.raises(ValueError, match="unknown controller 'nope'"):
        resolve("nope")


@pytest.fixture
def fresh_registry(monkeypatch: pytest.MonkeyPatch) -> None:
    """Registrations made by the test vanish after it."""
    monkeypatch.setattr(registry, "_REGISTRY", dict(registry._REGISTRY))


def test_registration_metadata_is_checked(fresh_registry: None) -> None:
    spec = register_controller(
        "mine", "agents.controllers.factories:passive", actuators=GUIDED, default=True
    )
    assert spec.actuators == (GUIDED,) and spec.kind == "baseline"
    assert registry.default_controllers() == ["passive", "pid", "lqr", "mine"]
    assert registry.registrations() == (spec,)
    with pytest.raises(ValueError, match="kind must be one of"):
        register_controller("bad", "agents.controllers.factories:pid", kind="neural")
    with pytest.raises(ValueError, match="entrant"):
        register_controller("bad", "agents.controllers.factories:pid", entrant=(GUIDED,))
    with pytest.raises(TypeError, match="unknown metadata"):
        register_controller("bad", "agents.controllers.factories:pid", colour="red")
    with pytest.raises(ValueError, match="entry point must be"):
        register_controller("bad", "not an entry point")
    register_controller("bad", "agents.controllers.factories:nothing")
    assert "has no 'nothing'" in registry.controller_problem("bad")


# the same user module as test_entry_points (a zero-action controller outside the package)
from test_entry_points import MODULE  # noqa: E402


@pytest.fixture
def user_entry_point(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fresh_registry: None) -> str:
    """A module outside the package, importable here and (PYTHONPATH) in the workers."""
    (tmp_path / "registry_user_mod.py").write_text(MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", f"{tmp_path}:{ROOT}")
    return "registry_user_mod:make"


def test_a_name_registered_in_the_parent_is_built_in_spawned_workers(
    user_entry_point: str,
) -> None:
    """The local backend's spawned workers (fragility, capacity) build a name registered
    only in this process by entry point; a name registered as a callable is not sent."""
    register_controller("zero-registered", user_entry_point)
    out = dict(run_blocks(["zero-registered"] * 2, workers=2, fn=make_controller))
    assert [type(out[i]).__name__ for i in (0, 1)] == ["Zero", "Zero"]
    assert type(make_controller("zero-registered")).__name__ == "Zero"

    register_controller("zero-callable", make_controller(user_entry_point).__class__)
    with pytest.raises(ValueError, match="unknown controller 'zero-callable'"):
        list(run_blocks(["zero-callable"] * 2, workers=2, fn=make_controller))


@pytest.mark.slow
def test_a_registered_name_in_the_capacity_search_on_spawned_workers(
    user_entry_point: str,
) -> None:
    """End to end (slow: the default suite has the backend test above and the entry-point
    one of test_entry_points): the capacity search of the registered zero-action controller
    on 2 spawned workers equals the passive controller's."""
    from agents.evaluation.capacity_benchmark import run

    register_controller("zero-registered", user_entry_point)
    res = run(
        ["zero-registered", "passive"],
        ["paper-2000-straight"],
        ["roughness"],
        seeds=[1_000_000, 1_000_001],
        distance_km=0.2,
        workers=2,
        n_boot=20,
        progress=False,
        ratio=1.1,
    )
    cell = res["capacities"]["paper-2000-straight"]["roughness"]
    caps = {lab: [d["capacity"] for d in v] for lab, v in cell.items()}
    assert caps["zero-registered"] == caps["passive"]


@pytest.mark.slow
def test_a_name_registered_in_the_parent_is_built_on_ray_workers(user_entry_point: str) -> None:
    """Ray tasks carry the registrations the same way."""
    pytest.importorskip("ray", reason="needs Ray (optional extra: pip install -e '.[ray]')")
    register_controller("zero-registered", user_entry_point)
    out = dict(run_blocks(["zero-registered"] * 2, backend="ray", fn=make_controller))
    assert [type(out[i]).__name__ for i in (0, 1)] == ["Zero", "Zero"]
