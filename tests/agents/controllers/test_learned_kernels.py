"""The compiled float32 forward pass of the learned controllers
(:mod:`agents.controllers.learned`): tanh within a few float32 ulps, the layer product
against float64 NumPy, a batch equal to its rows one at a time, NaN propagating."""

from __future__ import annotations

import numpy as np
import pytest

from agents.controllers.learned import _NumpyPolicy, dense_t32, mlp_forward, tanh32_array


def test_tanh32_is_within_six_float32_ulps_of_tanh() -> None:
    x = np.linspace(-12.0, 12.0, 400_001).astype(np.float32)
    out = np.empty_like(x)
    tanh32_array(x, out)
    ref = np.tanh(x.astype(np.float64))
    ulp = np.spacing(np.abs(ref).astype(np.float32)).astype(np.float64)
    assert np.max(np.abs(out - ref) / ulp) <= 6.0
    assert np.max(np.abs(out - ref)) < 4e-7
    special = np.array([np.nan, np.inf, -np.inf, 0.0, -0.0], dtype=np.float32)
    res = np.empty_like(special)
    tanh32_array(special, res)
    assert np.isnan(res[0]) and res[1] == 1.0 and res[2] == -1.0 and res[3] == 0.0
    assert np.signbit(res[4])


@pytest.mark.parametrize(("n_in", "n_out"), [(23, 32), (31, 8), (1, 1), (6, 7), (32, 4)])
def test_dense_t32_is_the_product_and_row_independent(n_in: int, n_out: int) -> None:
    rng = np.random.default_rng(n_in * 100 + n_out)
    w = rng.normal(size=(n_in, n_out)).astype(np.float32)
    x = rng.normal(size=(n_in, 37)).astype(np.float32)
    y = np.empty((n_out, 37), dtype=np.float32)
    dense_t32(x, w, y)
    ref = (x.astype(np.float64).T @ w.astype(np.float64)).T
    bound = 1e-6 * n_in * (np.abs(x).T @ np.abs(w)).T.max()
    assert np.max(np.abs(y - ref)) <= bound
    one = np.empty((n_out, 1), dtype=np.float32)
    for i in (0, 5, 36):
        dense_t32(np.ascontiguousarray(x[:, i : i + 1]), w, one)
        np.testing.assert_array_equal(one[:, 0], y[:, i])


def _policy(rng: np.random.Generator, sizes: list[int], act: str) -> _NumpyPolicy:
    layers = []
    for k, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
        last = k == len(sizes) - 2
        layers.append(
            (
                rng.normal(size=(a, b)) / np.sqrt(a),
                rng.normal(size=b) * 0.1,
                "linear" if last else act,
            )
        )
    return _NumpyPolicy(layers, squash=False)


@pytest.mark.parametrize("act", ["tanh", "relu"])
def test_forward_pass_matches_the_float64_reference_to_float32_rounding(act: str) -> None:
    rng = np.random.default_rng(7)
    pol = _policy(rng, [23, 32, 32, 4], act)
    std = rng.random(23) + 0.5
    norm = {"mean": rng.normal(size=23), "std": std, "inv_std": 1.0 / std, "clip": 5.0}
    raw = rng.normal(0.0, 3.0, (65, 23)).astype(np.float32)
    raw[0, 0] = 100.0  # beyond the normalisation clip
    out = pol.actions(raw, norm)
    x = np.clip((raw.astype(np.float64) - norm["mean"]) / norm["std"], -5.0, 5.0)
    ref = np.clip(pol(x), -1.0, 1.0)
    assert out.dtype == np.float32 and out.shape == (65, 4)
    assert np.max(np.abs(out - ref)) < 2e-6
    assert np.any(np.abs(ref) < 0.99)  # not everything saturated
    for i in (0, 1, 64):  # a batch equals its rows one at a time, bit for bit
        np.testing.assert_array_equal(pol.actions(raw[i : i + 1], norm)[0], out[i])
    np.testing.assert_array_equal(pol.actions(raw.astype(np.float64), norm), out)
    raw[3, 5] = np.nan
    out = pol.actions(raw, norm)
    assert np.isnan(out[3]).all() and np.isfinite(np.delete(out, 3, axis=0)).all()
    plain = pol.actions(raw[:2], None)  # no normalisation statistics: the raw values
    np.testing.assert_allclose(plain, np.clip(pol(raw[:2].astype(np.float64)), -1, 1), atol=2e-6)


def test_forward_pass_takes_any_layout_and_names_a_wrong_shape() -> None:
    """Strided and transposed observations give the contiguous ones' actions bit for bit (the
    compiled pass reads strides); a row of the wrong length is a ValueError naming the shape."""
    rng = np.random.default_rng(11)
    pol = _policy(rng, [23, 32, 32, 4], "tanh")
    std = rng.random(23) + 0.5
    norm = {"mean": rng.normal(size=23), "std": std, "inv_std": 1.0 / std, "clip": 5.0}
    raw = rng.normal(0.0, 3.0, (40, 23)).astype(np.float32)
    out = pol.actions(raw, norm)
    wide = np.zeros((80, 46), dtype=np.float32)
    wide[::2, ::2] = raw
    np.testing.assert_array_equal(pol.actions(wide[::2, ::2], norm), out)
    np.testing.assert_array_equal(pol.actions(np.asfortranarray(raw), norm), out)
    with pytest.raises(ValueError, match=r"shape \(N, 23\), got \(40, 22\)"):
        pol.actions(raw[:, :22], norm)
    with pytest.raises(ValueError, match=r"shape \(N, 23\), got \(23,\)"):
        pol.actions(raw[0], norm)


def test_forward_pass_follows_new_statistics_and_names_bad_ones() -> None:
    """The compiled pass is bound to the types of the normalisation arrays it was called with:
    statistics replaced in the dict by arrays of another layout or dtype (or another dict),
    and float64 after float32 observations, give the actions of a policy that never saw the
    first ones; statistics of the wrong length or kind are a ValueError naming them."""
    rng = np.random.default_rng(12)
    pol = _policy(rng, [9, 16, 4], "tanh")
    raw = rng.normal(0.0, 3.0, (10, 9)).astype(np.float32)
    std = rng.random(9) + 0.5
    a = {"mean": rng.normal(size=9), "inv_std": 1.0 / std, "clip": 5.0}
    b = {"mean": rng.normal(size=9), "inv_std": rng.random(9) + 0.5, "clip": 5.0}
    fresh_b = _policy(np.random.default_rng(12), [9, 16, 4], "tanh").actions(raw, dict(b))
    first = pol.actions(raw, a)
    assert not np.array_equal(first, fresh_b)
    np.testing.assert_array_equal(pol.actions(raw, b), fresh_b)  # another dict
    a["mean"], a["inv_std"] = b["mean"], b["inv_std"]  # replaced in the same dict
    np.testing.assert_array_equal(pol.actions(raw, a), fresh_b)
    a["mean"] = np.repeat(b["mean"], 2)[::2]  # the same values, strided
    np.testing.assert_array_equal(pol.actions(raw, a), fresh_b)
    a["inv_std"] = np.repeat(b["inv_std"], 3)[::3]
    np.testing.assert_array_equal(pol.actions(raw, a), fresh_b)
    a["mean"] = b["mean"].astype(np.float32).astype(np.float64)  # contiguous again
    want = _policy(np.random.default_rng(12), [9, 16, 4], "tanh").actions(raw, dict(a))
    a["mean"] = a["mean"].astype(np.float32)  # the same values in float32
    np.testing.assert_array_equal(pol.actions(raw, a), want)
    np.testing.assert_array_equal(pol.actions(raw.astype(np.float64), a), want)
    with pytest.raises(ValueError, match=r"mean must be a float array of shape \(9,\)"):
        pol.actions(raw, {**a, "mean": np.zeros(8)})
    with pytest.raises(ValueError, match="inv_std must be a float array"):
        pol.actions(raw, {**a, "inv_std": np.ones(9, dtype=np.int64)})


def test_mlp_forward_squashes_with_tanh() -> None:
    pol = _NumpyPolicy([(np.eye(2) * 3.0, np.zeros(2), "linear")], squash=True)
    out = pol.actions(np.array([[0.5, -2.0]], dtype=np.float32), None)
    np.testing.assert_allclose(out[0], np.tanh([1.5, -6.0]), atol=1e-6)
    params = np.array([3.0, 0.0, 0.0, 3.0, 0.0, 0.0], dtype=np.float32)
    layout = np.array([[0, 2, 2, 0]])
    raw = np.empty((1, 2), dtype=np.float32)
    mlp_forward(
        np.array([[0.5, -2.0]], dtype=np.float32),
        np.zeros(2),
        np.ones(2),
        np.inf,
        params,
        layout,
        False,
        np.empty((2, 2, 1), dtype=np.float32),
        raw,
    )
    np.testing.assert_array_equal(raw[0], [1.0, -1.0])  # clipped, not squashed
