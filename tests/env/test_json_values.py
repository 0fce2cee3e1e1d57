"""The one JSON conversion rule (hyperloop_env.json_values) gives the documented values."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from hyperloop_env.json_values import json_value, python_number, python_numbers


class _Fit:
    def to_dict(self) -> dict:
        return {"theta": np.float32(0.5), "ci": (math.inf, 1.0)}


def test_json_value_gives_values_json_can_hold() -> None:
    """NaN/inf -> None, numpy -> Python, to_dict() objects -> dict, arrays -> lists."""
    got = json_value(
        {"a": [np.int64(3), np.nan, np.bool_(True)], "f": _Fit(), "arr": np.array([1.5, -math.inf])}
    )
    assert got == {"a": [3, None, True], "f": {"theta": 0.5, "ci": [None, 1.0]}, "arr": [1.5, None]}
    assert type(got["a"][0]) is int and type(got["f"]["theta"]) is float
    assert type(got["a"][2]) is bool
    json.dumps(got, allow_nan=False)


def test_json_value_keeps_non_finite_floats_on_request() -> None:
    got = json_value({"x": (np.float64(math.inf), math.nan), "f": _Fit()}, non_finite="keep")
    assert got["x"][0] == math.inf and math.isnan(got["x"][1])
    assert type(got["x"][0]) is float
    assert got["f"] == {"theta": 0.5, "ci": [math.inf, 1.0]}
    assert json.loads(json.dumps(got))["x"][0] == math.inf


def test_json_value_keys_paths_scalars_and_other_values() -> None:
    got = json_value(
        {1: Path("runs") / "a", "arr0": np.array(2.5), "s": "text", "n": None, "b": False}
    )
    assert got == {"1": "runs/a", "arr0": 2.5, "s": "text", "n": None, "b": False}
    assert type(got["arr0"]) is float


def test_json_value_refuses_an_unknown_non_finite_option() -> None:
    with pytest.raises(ValueError, match="non_finite"):
        json_value(1.0, non_finite="drop")  # type: ignore[arg-type]


def test_python_numbers_keeps_structure_and_other_values() -> None:
    path = Path("out")
    cfg = {"n": np.int64(4), "lr": np.float32(0.25), "arch": (np.int32(64), 64), "out": path}
    got = python_numbers(cfg)
    assert got == {"n": 4, "lr": 0.25, "arch": (64, 64), "out": path}
    assert type(got["n"]) is int and type(got["lr"]) is float
    assert type(got["arch"]) is tuple and type(got["arch"][0]) is int
    assert got["out"] is path
    assert python_number(np.bool_(True)) is True
    assert python_number(math.nan) is not None
