"""``analyse_episodes(..., intervals="worst")``: only the worst unit's bootstrap interval is
drawn, and that unit's record is the one ``intervals="all"`` gives (each unit draws from its
own child stream); the capacity benchmark's per-level STS relies on it."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from hyperloop_env.sts import analyse_episodes, worst_index

DT = 1e-3
OM = 0.008


def _episodes(scales: tuple[float, ...], n: int = 4000, n_ep: int = 3) -> list[np.ndarray]:
    """AR(1) gap signals [m], one column per unit (unit 2 driven by Student t innovations),
    each scaled to its standard deviation ``scales[u]``."""
    rng = np.random.default_rng(11)
    out = []
    for _ in range(n_ep):
        cols = []
        for u, sc in enumerate(scales):
            e = rng.standard_t(4, n) if u == 2 else rng.standard_normal(n)
            x = np.empty(n)
            x[0] = e[0]
            for i in range(1, n):
                x[i] = 0.9 * x[i - 1] + e[i]
            cols.append(sc * x / np.std(x))
        out.append(np.column_stack(cols))
    return out


def _same(a: object, b: object) -> bool:
    """Field by field equality, NaN equal to NaN."""
    da, db = dataclasses.asdict(a), dataclasses.asdict(b)
    return da.keys() == db.keys() and all(_eq(da[k], db[k]) for k in da)


def _eq(x: object, y: object) -> bool:
    if isinstance(x, float) and isinstance(y, float):
        return x == y or (math.isnan(x) and math.isnan(y))
    if isinstance(x, tuple | list) and isinstance(y, tuple | list):
        return len(x) == len(y) and all(_eq(a, b) for a, b in zip(x, y, strict=True))
    return x == y


def test_the_worst_units_record_is_the_one_all_intervals_give() -> None:
    eps = _episodes((0.0015, 0.002, 0.0025, 0.0018))
    full = analyse_episodes(eps, DT, clearance_m=OM, n_boot=60, rng=3)
    worst = analyse_episodes(eps, DT, clearance_m=OM, n_boot=60, rng=3, intervals="worst")
    w = worst_index([u.p_unsteady for u in full.units])
    assert full.worst_unit == full.units[w].name == worst.worst_unit
    assert all(math.isfinite(c) for c in full.units[w].p_unsteady_ci)
    assert _same(full.units[w], worst.units[w])
    for u, (a, b) in enumerate(zip(full.units, worst.units, strict=True)):
        assert a.p_unsteady == b.p_unsteady and a.distribution == b.distribution
        if u != w:
            assert all(math.isnan(c) for c in b.p_unsteady_fit_ci)
            assert b.n_boot == 0 and "only the worst unit" in b.ci_method
            assert all(math.isfinite(c) for c in a.p_unsteady_fit_ci)


def test_worst_index_takes_the_largest_finite_value_first_on_ties() -> None:
    assert worst_index([0.1, 0.3, 0.3, 0.2]) == 1
    assert worst_index([math.nan, 0.05, math.nan, 0.01]) == 1
    assert worst_index([math.nan, math.nan]) == 0


def test_intervals_must_be_all_or_worst() -> None:
    eps = _episodes((0.0015, 0.002, 0.0025, 0.0018), n=200, n_ep=1)
    with pytest.raises(ValueError, match="intervals"):
        analyse_episodes(eps, DT, intervals="best")  # type: ignore[arg-type]
