"""Streaming accumulators against numpy / the batch comfort on the full signal."""

from __future__ import annotations

import numpy as np
import pytest

from agents.evaluation.streaming import (
    Exceedances,
    Moments,
    Thinned,
    WeightedRMS,
    merge_moments,
    moments_summary,
)
from hyperloop_env.comfort import weighted_rms


def _chunks(t: int, rng: np.random.Generator) -> list[tuple[int, int]]:
    edges = np.unique(np.concatenate([[0, t], rng.integers(1, t, 12)]))
    return list(zip(edges[:-1], edges[1:], strict=True))


def _signal(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t, n, c = 5000, 3, 4
    x = rng.standard_t(5, (t, n, c)) * 1e-3 + rng.normal(0, 5e-4, (1, n, c))
    ends = np.array([5000, 3170, 41])  # runs stop at different steps
    mask = np.arange(t)[:, None] < ends[None, :]
    return x, mask, ends


def test_moments_and_merge_equal_numpy_on_the_full_signal() -> None:
    x, mask, ends = _signal()
    m = Moments(3, 4)
    for a, b in _chunks(x.shape[0], np.random.default_rng(1)):
        m.update(x[a:b], mask[a:b])
    for i, e in enumerate(ends):
        full = x[:e, i]
        s = moments_summary({k: v[None] for k, v in m.row(i).items()})
        np.testing.assert_allclose(s["mean"][0], full.mean(axis=0), rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(s["var"][0], full.var(axis=0), rtol=1e-10)
        np.testing.assert_allclose(s["rms"][0], np.sqrt((full**2).mean(axis=0)), rtol=1e-12)
        np.testing.assert_array_equal(m.maxabs[i], np.abs(full).max(axis=0))
        assert m.n[i, 0] == e
    pooled = np.concatenate([x[:e, i] for i, e in enumerate(ends)])
    s = moments_summary(merge_moments([m.row(i) for i in range(3)]))
    np.testing.assert_allclose(s["mean"], pooled.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(s["std"], pooled.std(axis=0), rtol=1e-10)
    np.testing.assert_allclose(s["rms"], np.sqrt((pooled**2).mean(axis=0)), rtol=1e-12)


def test_moments_ignore_non_finite_and_masked_samples() -> None:
    x = np.ones((10, 1, 2))
    x[3, 0, 0] = np.nan
    mask = np.ones((10, 1), bool)
    mask[7:] = False
    x[8:] = 1e9
    m = Moments(1, 2)
    m.update(x, mask)
    assert m.n.tolist() == [[6, 7]] and m.maxabs.tolist() == [[1.0, 1.0]]


def test_exceedance_counts_equal_numpy() -> None:
    x, mask, ends = _signal(3)
    levels = np.array([1e-3, 2e-3, 4e-3])
    e = Exceedances(3, 4, levels)
    for a, b in _chunks(x.shape[0], np.random.default_rng(2)):
        e.update(x[a:b], mask[a:b])
    for i, end in enumerate(ends):
        full = np.abs(x[:end, i])
        for j, lev in enumerate(levels):
            np.testing.assert_array_equal(e.count[i, j], (full >= lev).sum(axis=0))
            assert e.count_any[i, j] == (full >= lev).any(axis=1).sum()
        assert e.n[i] == end


@pytest.mark.parametrize("kind", ["k", "d"])
def test_streaming_iso_filter_equals_the_batch_comfort(kind: str) -> None:
    rng = np.random.default_rng(4)
    dt = 1e-3
    t = np.arange(20000) * dt
    ends = np.array([20000, 9000])
    x = np.stack(
        [
            0.3 + np.sin(2 * np.pi * 6 * t) + 0.2 * rng.normal(size=t.size),
            -1.2 + 0.5 * np.sin(2 * np.pi * 1.3 * t) + 0.1 * rng.normal(size=t.size),
        ],
        axis=1,
    )  # non-zero means: the batch removes them first
    mask = np.arange(t.size)[:, None] < ends[None, :]
    w = WeightedRMS(2, dt, kind, settle_s=0.5)
    for a, b in _chunks(t.size, rng):
        w.update(x[a:b], mask[a:b])
    got = w.result()
    for i, e in enumerate(ends):
        ref = weighted_rms(x[:e, i], dt, kind, settle_s=0.5)  # type: ignore[arg-type]
        assert got[i] == pytest.approx(ref, rel=1e-9)


def test_thinned_keeps_every_kth_step() -> None:
    x, mask, ends = _signal(5)
    th = Thinned(3, 4, max_steps=5000, stride=7)
    first = 1
    for a, b in _chunks(x.shape[0], np.random.default_rng(6)):
        th.update(x[a:b], mask[a:b], first)
        first += b - a
    for i, e in enumerate(ends):
        np.testing.assert_array_equal(th.row(i), x[:e:7, i])  # steps 1, 8, 15, …
    assert th.data.shape[1] == -(-5000 // 7)


def test_thinned_grows_when_a_run_is_longer_than_planned() -> None:
    x = np.arange(300.0).reshape(300, 1, 1)
    th = Thinned(1, 1, max_steps=100, stride=3)
    th.update(x, np.ones((300, 1), bool), 1)
    np.testing.assert_array_equal(th.row(0)[:, 0], x[::3, 0, 0])
