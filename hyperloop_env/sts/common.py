"""Constants and input validation shared by the STS modules."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from hyperloop_env.physics.params import MagnetParams
from hyperloop_env.physics.units import UNIT_NAMES  # noqa: F401  (re-exported)

DEFAULT_CLEARANCE_M: float = MagnetParams.clearance_m
DEFAULT_CANDIDATES: tuple[str, ...] = ("norm", "t", "logistic", "laplace", "genextreme", "skewnorm")
CONFIDENCE: float = 0.95
"""Confidence level of every interval reported by this module."""

_BLOCK_TAU_FACTOR = 3.0  # moving-block length in units of the integrated autocorrelation time
_REFIT_FALLBACK_MAX = 50  # replicates refitted by full MLE when the one-step bootstrap fails
_CLOSED_FORM_REFIT = frozenset({"laplace"})  # laws whose MLE is cheap enough to refit exactly
_POSITIVE_SHAPES: dict[str, tuple[bool, ...]] = {"t": (True,), "genextreme": (False,)}
_DEGENERATE_RTOL = 1e-12
_MAX_GATHER = 2_000_000  # max block draws materialised at once in the bootstrap

FloatArray = NDArray[np.float64]


def _check_positive(name: str, value: float) -> None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def _validate_common(
    dt_s: float,
    clearance_m: float,
    settle_s: float,
    alpha: float,
    n_boot: int,
    min_samples: int,
    max_fit_samples: int,
    selection_test: str,
    candidates: Sequence[str],
) -> None:
    _check_positive("dt_s", dt_s)
    _check_positive("clearance_m", clearance_m)
    if not (isinstance(settle_s, (int, float)) and math.isfinite(settle_s) and settle_s >= 0):
        raise ValueError(f"settle_s must be a finite number >= 0, got {settle_s!r}")
    if not (isinstance(alpha, (int, float)) and 0.0 < alpha < 1.0):
        raise ValueError(f"alpha must be in (0, 1), got {alpha!r}")
    if not isinstance(n_boot, (int, np.integer)) or n_boot < 0:
        raise ValueError(f"n_boot must be an int >= 0, got {n_boot!r}")
    if not isinstance(min_samples, (int, np.integer)) or min_samples < 3:
        raise ValueError(f"min_samples must be an int >= 3, got {min_samples!r}")
    if not isinstance(max_fit_samples, (int, np.integer)) or max_fit_samples < 100:
        raise ValueError(f"max_fit_samples must be an int >= 100, got {max_fit_samples!r}")
    if selection_test not in ("thinned", "raw"):
        raise ValueError(f"selection_test must be 'thinned' or 'raw', got {selection_test!r}")
    if isinstance(candidates, str) or len(candidates) == 0:
        raise ValueError(f"candidates must be a non-empty sequence of names, got {candidates!r}")
    for name in candidates:
        if not isinstance(getattr(stats, str(name), None), stats.rv_continuous):
            raise ValueError(
                f"candidates: {name!r} is not a continuous distribution of scipy.stats"
            )


def _as_finite_1d(signal: ArrayLike, what: str) -> FloatArray:
    try:
        x = np.asarray(signal, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{what} must be numeric: {exc}") from None
    if x.ndim != 1:
        raise ValueError(f"{what} must be one-dimensional, got shape {x.shape}")
    _check_finite(x, what)
    return x


def _check_finite(x: FloatArray, what: str) -> None:
    bad = ~np.isfinite(x)
    if bad.any():
        first = np.argwhere(bad)[0]
        kind = "NaN" if np.isnan(x[tuple(first)]) else "inf"
        raise ValueError(
            f"{what} contains {int(bad.sum())} non-finite value(s) ({kind} at index "
            f"{tuple(int(i) for i in first) if first.size > 1 else int(first[0])})"
        )


def _as_segments(signal: ArrayLike | Sequence[ArrayLike]) -> list[FloatArray]:
    if isinstance(signal, np.ndarray) and signal.ndim == 1:
        return [_as_finite_1d(signal, "signal")]
    if isinstance(signal, (list, tuple)) and signal and all(np.ndim(s) == 1 for s in signal):
        return [_as_finite_1d(s, f"signal[{i}]") for i, s in enumerate(signal)]
    return [_as_finite_1d(signal, "signal")]


def _to_generator(rng: int | np.random.Generator | None) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, (int, np.integer)):
        return np.random.default_rng(rng)
    raise ValueError(f"rng must be None, an int seed or a numpy Generator, got {rng!r}")
