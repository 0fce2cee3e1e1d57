"""Training presets as data files (``agents/training/presets/*.json``; see its README).

``DEFAULTS`` is ``defaults.json``; every other file is a preset applied on top of it, and a
run that names none takes ``default.json`` (:data:`DEFAULT_PRESET`: the main job's options).
Every preset (a named one or a ``--preset file.json``) is checked when it is loaded
(:func:`check_options`): an unknown key, or a value of the wrong type or out of bounds, is
a :class:`PresetError` naming the key and the file, before anything is created.
"""

from __future__ import annotations

import json
import math
import numbers
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from agents.controllers.registry import default_controllers
from agents.evaluation.seeds import TRAIN_SEED_LIMIT

PRESET_DIR = Path(__file__).resolve().parent / "presets"
DEFAULTS_FILE = PRESET_DIR / "defaults.json"
ALGOS: tuple[str, ...] = ("ppo", "sac")
VEC_MODES: tuple[str, ...] = ("native", "dummy", "subproc")
ACTIVATIONS: tuple[str, ...] = ("tanh", "relu")
"""The hidden layers' activation functions a preset may name (``activation``)."""
BASELINES: tuple[str, ...] = tuple(default_controllers())
"""The baselines a trained agent is compared with: the registry's default controllers."""


class PresetError(ValueError):
    """A preset (or a configuration) holds an unknown key or an invalid value."""


class _Bad(ValueError):
    """One value is invalid: the message says what it must be."""


Check = Callable[[Any], Any]
"""Returns the value normalised (Python int / float / list), raises :class:`_Bad`."""


def _integer(lo: int, hi: int | None = None, *, also: tuple[int, ...] = ()) -> Check:
    what = f"an integer >= {lo}" if hi is None else f"an integer in [{lo}, {hi}]"
    if also:
        what += " or " + " or ".join(map(str, also))

    def check(v: Any) -> int:
        integral = isinstance(v, numbers.Real) and not isinstance(v, bool)
        if not integral or not math.isfinite(v) or not float(v).is_integer():
            raise _Bad(f"must be {what}")
        n = int(v)
        if n not in also and (n < lo or (hi is not None and n > hi)):
            raise _Bad(f"must be {what}")
        return n

    return check


def _number(
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> Check:
    parts = []
    if lo is not None:
        parts.append(f"{'>' if lo_open else '>='} {lo:g}")
    if hi is not None:
        parts.append(f"{'<' if hi_open else '<='} {hi:g}")
    what = "a finite number" + (" " + " and ".join(parts) if parts else "")

    def check(v: Any) -> float:
        if not isinstance(v, numbers.Real) or isinstance(v, bool) or not math.isfinite(v):
            raise _Bad(f"must be {what}")
        x = float(v)
        below = lo is not None and (x <= lo if lo_open else x < lo)
        above = hi is not None and (x >= hi if hi_open else x > hi)
        if below or above:
            raise _Bad(f"must be {what}")
        return x

    return check


def _choice(options: tuple[str, ...], *, lower: bool = False) -> Check:
    def check(v: Any) -> str:
        s = v.lower() if lower and isinstance(v, str) else v
        if not isinstance(s, str) or s not in options:
            raise _Bad(f"must be one of {list(options)}")
        return s

    return check


def _scenario(v: Any) -> str:
    from hyperloop_env.scenarios import SCENARIOS

    if not isinstance(v, str) or v not in SCENARIOS:
        raise _Bad(f"must be a scenario name, one of {sorted(SCENARIOS)}")
    return v


def _text(v: Any) -> str:
    if not isinstance(v, str) or not v.strip():
        raise _Bad("must be a non-empty string")
    return v


def _optional(check: Check) -> Check:
    def optional(v: Any) -> Any:
        return None if v is None else check(v)

    return optional


def _boolean(v: Any) -> bool:
    if not isinstance(v, bool):
        raise _Bad("must be true or false")
    return v


def _layers(v: Any) -> list[int]:
    width = _integer(1)
    if not isinstance(v, list | tuple) or not v:
        raise _Bad("must be a non-empty list of layer widths >= 1")
    try:
        return [width(w) for w in v]
    except _Bad:
        raise _Bad("must be a non-empty list of layer widths >= 1") from None


def _env_kwargs(v: Any) -> dict[str, Any]:
    if not isinstance(v, Mapping) or not all(isinstance(k, str) and k.isidentifier() for k in v):
        raise _Bad("must be an object of environment keywords (checked when the env is built)")
    return dict(v)


def _residual(v: Any) -> dict[str, Any]:
    from agents.controllers.residual import check_record

    try:
        return check_record(v)
    except ValueError as exc:
        raise _Bad(
            f"must be a residual record {{'base': <controller>, 'scale': <0..2>}}: {exc}"
        ) from None


def _curriculum(v: Any) -> dict[str, Any]:
    from agents.training.curriculum import check_curriculum

    try:
        return check_curriculum(v)
    except ValueError as exc:
        raise _Bad(f"must be a curriculum record: {exc}") from None


_SHIP_NAME = re.compile(r"^[a-z0-9][a-z0-9_+-]*$")


def _ship_name(v: Any) -> str:
    if not isinstance(v, str) or not _SHIP_NAME.match(v):
        raise _Bad("must be the name of an agents/shipped/ folder (lower-case letters, digits, -)")
    return v


OPTION_CHECKS: dict[str, Check] = {
    "algo": _choice(ALGOS, lower=True),
    "scenario": _scenario,
    "timesteps": _integer(1),
    "n_envs": _integer(1),
    "seed": _integer(0, TRAIN_SEED_LIMIT - 1),
    "out": _optional(_text),
    "device": _text,
    "eval_distance_km": _number(0, lo_open=True),
    "eval_seeds": _integer(1),
    "vec": _choice(VEC_MODES),
    "track_length_m": _number(0, lo_open=True),
    "eval_freq": _integer(1),
    "eval_episodes": _integer(1),
    "checkpoint_freq": _integer(1),
    "checkpoint_interval_s": _number(0, lo_open=True),
    "gamma": _number(0, 1, lo_open=True),
    "learning_rate": _number(0, lo_open=True),
    "n_steps": _integer(1),
    "batch_size": _integer(1),
    "n_epochs": _integer(1),
    "gae_lambda": _number(0, 1),
    "clip_range": _number(0, lo_open=True),
    "ent_coef": _number(0),
    "log_std_init": _number(),
    "net_arch": _layers,
    "critic_arch": _optional(_layers),
    "activation": _choice(ACTIVATIONS),
    "sac_buffer_size": _integer(1),
    "sac_learning_starts": _integer(0),
    "sac_train_freq": _integer(1),
    "sac_gradient_steps": _integer(1, also=(-1,)),
    "norm_reward": _boolean,
    "env_kwargs": _env_kwargs,
    "ship_name": _optional(_ship_name),
    "residual": _optional(_residual),
    "privileged_critic": _boolean,
    "overlap_updates": _boolean,
    "curriculum": _optional(_curriculum),
}
"""What every option may hold (type and bounds); the keys are those of ``defaults.json``."""


def check_option(key: str, value: Any, source: str) -> Any:
    """``value`` of option ``key`` normalised; :class:`PresetError` naming ``key`` and
    ``source`` (the preset file) if it is unknown or invalid."""
    check = OPTION_CHECKS.get(key)
    if check is None:
        raise PresetError(
            f"{source}: unknown option {key!r}; valid options: {sorted(OPTION_CHECKS)}"
        )
    try:
        return check(value)
    except _Bad as exc:
        raise PresetError(f"{source}: option {key!r} {exc}, got {value!r}") from None


def check_options(data: Mapping[str, Any], source: str) -> dict[str, Any]:
    """The options of ``data`` (a preset) normalised, each checked with
    :data:`OPTION_CHECKS`: :class:`PresetError` naming the first unknown key or invalid
    value and ``source``."""
    unknown = sorted(set(data) - set(OPTION_CHECKS))
    if unknown:
        raise PresetError(
            f"{source}: unknown option(s) {unknown}; valid options: {sorted(OPTION_CHECKS)}"
        )
    return {key: check_option(key, value, source) for key, value in data.items()}


def _load(path: Path) -> dict[str, Any]:
    data = json.loads(path.read_text())
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a JSON object of options")
    return data


DEFAULT_PRESET = "default"
"""The preset of a run that names none: ``python train.py``'s (``default.json``)."""
DEFAULTS: dict[str, Any] = _load(DEFAULTS_FILE)
PRESETS: dict[str, dict[str, Any]] = {
    p.stem: _load(p) for p in sorted(PRESET_DIR.glob("*.json")) if p.stem != "defaults"
}


def defaults() -> dict[str, Any]:
    """``defaults.json``, checked (:class:`PresetError` naming the file and the key)."""
    return check_options(DEFAULTS, str(DEFAULTS_FILE))


def load_preset(name: str) -> dict[str, Any]:
    """A named preset or a JSON file of options, checked (:func:`check_options`);
    ``ValueError`` (:class:`PresetError` for its options) naming the problem and the file."""
    if name in PRESETS:
        return check_options(PRESETS[name], str(PRESET_DIR / f"{name}.json"))
    path = Path(name)
    if path.suffix == ".json" and path.exists():
        try:
            data = _load(path)
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise ValueError(f"--preset {name}: not a JSON object of options ({exc})") from None
        return check_options(data, f"--preset {name}")
    raise ValueError(f"unknown preset {name!r}; valid presets: {list(PRESETS)} or a .json file")
