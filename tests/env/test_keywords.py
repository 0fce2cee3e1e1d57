"""One declaration per environment keyword (hyperloop_env.keywords): the keyword list, the
validation, ``to_kwargs`` and the docstring tables come from the field metadata; one name
per reward term; the former reward keyword names still work, with a DeprecationWarning."""

from __future__ import annotations

import json
import math
import pydoc
import warnings
from dataclasses import fields
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env.config as config_module
from hyperloop_env.config import (
    ALIASES,
    KEYWORDS,
    PHYSICAL_OVERRIDES,
    EnvConfig,
    RewardWeights,
    canonical_keywords,
)
from hyperloop_env.env import CONSTRUCTOR_KEYWORDS, HyperloopSuspensionEnv
from hyperloop_env.keywords import TABLE_MARKER, field_table, keyword_table
from hyperloop_env.reward import REWARD_TERMS, reward_info
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

ENV_ID = "HyperloopSuspension-v0"
ROOT = Path(__file__).resolve().parents[2]
SHIPPED_LOGS = sorted((ROOT / "agents" / "shipped").glob("*/training_log.json"))
SAVED_OLD = sorted((Path(__file__).parent / "data").glob("saved_env_config_*.json"))
"""Environment configurations saved by the agents shipped before the reward keywords were
renamed (their training logs' ``config.env``)."""


def test_keyword_list_comes_from_the_declarations() -> None:
    assert EnvConfig.keyword_names() == tuple(KEYWORDS)
    assert EnvConfig.keyword_names() == (
        "scenario",
        "speed_kmh",
        "curve_radius_m",
        "cant_deg",
        "track_length_m",
        "irregularity",
        "control_dt_s",
        "clearance_m",
        "magnet",
        "coil_time_constant_s",
        "actuators",
        "disturbances",
        "action_scale",
        "safety_margin_mm",
        "safety_cost",
        "sensor_noise_std",
        "sensor_delay",
        "observation_history",
        "observation_front_preview",
        "gap_weight",
        "guidance_weight",
        "current_weight",
        "comfort_weight",
        "survival_weight",
        "contact_weight",
    )
    assert PHYSICAL_OVERRIDES == EnvConfig.keyword_names()[1:10]
    assert all(d.keyword.doc for d in KEYWORDS.values())


def test_one_name_per_reward_term() -> None:
    """The term (REWARD_TERMS, reward_info), the RewardWeights field and the keyword
    (``<term>_weight``) share one name."""
    assert tuple(f.name for f in fields(RewardWeights)) == REWARD_TERMS
    assert tuple(reward_info(np.zeros(len(REWARD_TERMS)))) == REWARD_TERMS
    reward_keywords = [n for n, d in KEYWORDS.items() if d.path[0] == "reward"]
    assert reward_keywords == [f"{t}_weight" for t in REWARD_TERMS]
    assert [KEYWORDS[n].path for n in reward_keywords] == [("reward", t) for t in REWARD_TERMS]
    weights = {f"{t}_weight": float(k + 1) for k, t in enumerate(REWARD_TERMS)}
    assert EnvConfig.from_kwargs(**weights).reward.as_tuple() == tuple(weights.values())


def test_the_docstring_tables_are_generated_from_the_declarations() -> None:
    env_doc = HyperloopSuspensionEnv.__doc__
    table = keyword_table(EnvConfig, CONSTRUCTOR_KEYWORDS)
    assert TABLE_MARKER not in env_doc
    assert "\n".join("    " + t if t else t for t in table.split("\n")) in env_doc
    text = pydoc.render_doc(HyperloopSuspensionEnv, renderer=pydoc.plaintext)  # help(env)
    for name, d in KEYWORDS.items():
        row = next(r for r in table.split("\n") if r.startswith(f"| `{name}` "))
        assert row.split("|")[5].strip() == d.keyword.doc
        assert f"`{name}`" in text
    for alias, name in ALIASES.items():
        assert f"``{alias}`` (now ``{name}``)" in " ".join(env_doc.split())
    cfg_doc = config_module.__doc__
    assert TABLE_MARKER not in cfg_doc and field_table(EnvConfig) in cfg_doc
    for name, d in KEYWORDS.items():
        assert f"\n{name} " in cfg_doc and f"``{d.field_path}``" in cfg_doc


def _below(bounds: tuple[float, float], lo_open: bool) -> float:
    lo = bounds[0]
    return lo if lo_open else (lo - 1.0 if lo == 0 else lo * 0.5)


@pytest.mark.parametrize(
    "name", [n for n, d in KEYWORDS.items() if d.keyword.bounds and d.keyword.bounds[0] > -1e300]
)
def test_every_declared_bound_is_enforced_naming_the_keyword(name: str) -> None:
    k = KEYWORDS[name].keyword
    assert k.bounds is not None
    with pytest.raises(ValueError, match=f"^{name} must be"):
        EnvConfig.from_kwargs(**{name: _below(k.bounds, k.lo_open)})
    if k.bounds[1] < math.inf:
        with pytest.raises(ValueError, match=f"^{name} must be <="):
            EnvConfig.from_kwargs(**{name: k.bounds[1] * 2})
    with pytest.raises(ValueError, match=f"^{name} must be a number"):
        EnvConfig.from_kwargs(**{name: "x"})


@pytest.mark.parametrize(("alias", "name"), sorted(ALIASES.items()))
def test_former_reward_keywords_are_deprecated_aliases(alias: str, name: str) -> None:
    with pytest.warns(DeprecationWarning, match=f"'{alias}' is deprecated: use '{name}'") as rec:
        env = gym.make(ENV_ID, track_length_m=20.0, **{alias: 0.5})
    assert rec[0].filename == __file__  # points at the caller's gym.make
    assert env.unwrapped.env_config == EnvConfig.from_kwargs(track_length_m=20.0, **{name: 0.5})
    assert env.unwrapped.env_config.to_kwargs()[name] == 0.5
    env.close()
    with pytest.warns(DeprecationWarning):
        venv = HyperloopSuspensionVectorEnv(2, track_length_m=20.0, **{alias: 0.5})
    assert venv.env_config.reward == env.unwrapped.env_config.reward
    venv.close()
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match=f"^{alias} must be"):
        EnvConfig.from_kwargs(**{alias: -1.0})  # the error names the keyword as given
    with pytest.raises(TypeError, match="got both"):
        EnvConfig.from_kwargs(**{alias: 1.0, name: 1.0})
    assert alias not in EnvConfig.keyword_names()


def test_current_names_do_not_warn_and_unknown_keywords_still_raise_type_error() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        EnvConfig.from_kwargs(**EnvConfig().to_kwargs())
    with pytest.raises(TypeError, match="unexpected keyword argument 'survival'"):
        EnvConfig.from_kwargs(survival=1.0)


@pytest.mark.parametrize("saved_file", SAVED_OLD, ids=lambda p: p.stem)
def test_configs_saved_under_former_keyword_names_still_load(saved_file: Path) -> None:
    """A training log written with the former keyword names loads unchanged; under the
    current names it is the configuration the run would fingerprint today (a checkpoint of
    it resumes)."""
    saved = json.loads(saved_file.read_text())["env"]
    assert "survival_bonus" in saved and "contact_penalty" in saved
    with pytest.warns(DeprecationWarning):
        cfg = EnvConfig.from_kwargs(**saved)
    assert canonical_keywords(saved) == cfg.to_kwargs()
    assert cfg.reward.survival == saved["survival_bonus"]
    assert cfg.reward.contact == saved["contact_penalty"]


@pytest.mark.parametrize("log", SHIPPED_LOGS, ids=lambda p: p.parent.name)
def test_shipped_agents_saved_configs_load(log: Path) -> None:
    """The shipped agents' training logs load as they are, without a deprecation."""
    saved = json.loads(log.read_text())["config"]["env"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cfg = EnvConfig.from_kwargs(**saved)
    assert canonical_keywords(saved) == cfg.to_kwargs()


def test_a_new_keyword_is_one_declared_field() -> None:
    """The README recipe: a field with ``kw`` metadata is a keyword with its validation,
    its table row and its alias; a ``kw_group`` field nests keywords."""
    from dataclasses import dataclass, field

    from hyperloop_env.keywords import declared, kw, kw_group, validate_fields

    @dataclass(frozen=True)
    class Inner:
        gain: float = field(
            default=2.0,
            metadata=kw("toy gain", unit="N/A", bounds=(0.0, 5.0), name="toy_gain"),
        )

        def __post_init__(self) -> None:
            validate_fields(self)

    @dataclass(frozen=True)
    class Toy:
        mode: str = field(default="a", metadata=kw("toy mode", choices=("a", "b")))
        inner: Inner = field(default_factory=Inner, metadata=kw_group("toy group"))

        def __post_init__(self) -> None:
            validate_fields(self)

    assert [(d.name, d.field_path) for d in declared(Toy)] == [
        ("mode", "mode"),
        ("toy_gain", "inner.gain"),
    ]
    assert Toy(inner=Inner(np.float32(1.5))).inner.gain == 1.5
    assert type(Toy(inner=Inner(np.float32(1.5))).inner.gain) is float
    with pytest.raises(ValueError, match=r"^toy_gain must be <= 5.0 N/A, got 6"):
        Inner(6)
    with pytest.raises(ValueError, match=r"^mode must be 'a' or 'b', got 'c'"):
        Toy(mode="c")
    with pytest.raises(ValueError, match=r"^inner must be a Inner"):
        Toy(inner=None)  # type: ignore[arg-type]
    table = keyword_table(Toy)
    assert "| `toy_gain` | `2.0`   | N/A  | >= 0.0, <= 5.0 | toy gain    |" in table
