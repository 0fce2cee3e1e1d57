"""ISO 2631-1 frequency weightings (hyperloop_env.comfort)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hyperloop_env.comfort import (
    comfort_label,
    ride_comfort,
    weighted_rms,
    weighted_signal,
    weighting_gain,
)

# ISO 2631-1:1997 Table 3 (W_k) and Table 4 (W_d) factors (x1000) at one-third-octave
# centre frequencies.
WK_TABLE = {1.0: 482, 2.0: 531, 4.0: 967, 5.0: 1039, 6.3: 1054, 8.0: 1036, 16.0: 768}
WD_TABLE = {1.0: 1011, 2.0: 890, 4.0: 512}


@pytest.mark.parametrize(("f", "w"), sorted(WK_TABLE.items()))
def test_wk_gain_matches_standard_table(f: float, w: int) -> None:
    assert float(weighting_gain("k", f)) == pytest.approx(w / 1000, rel=0.02)


@pytest.mark.parametrize(("f", "w"), sorted(WD_TABLE.items()))
def test_wd_gain_matches_standard_table(f: float, w: int) -> None:
    assert float(weighting_gain("d", f)) == pytest.approx(w / 1000, rel=0.02)


@pytest.mark.parametrize(("kind", "f"), [("k", 5.0), ("k", 1.0), ("k", 12.5), ("d", 1.5)])
def test_sine_weighted_rms_equals_gain(kind: str, f: float) -> None:
    dt = 1e-3
    t = np.arange(0.0, 20.0, dt)
    x = 0.7 * np.sin(2 * math.pi * f * t)
    rms = weighted_rms(x, dt, kind, settle_s=5.0)
    expected = 0.7 / math.sqrt(2) * float(weighting_gain(kind, f))
    assert rms == pytest.approx(expected, rel=0.03)


def test_vertical_5hz_sine_gets_wk_gain_within_few_percent() -> None:
    dt = 1e-3
    t = np.arange(0.0, 20.0, dt)
    x = np.sin(2 * math.pi * 5.0 * t)
    ratio = weighted_rms(x, dt, "k", settle_s=5.0) / (1 / math.sqrt(2))
    assert ratio == pytest.approx(1.039, rel=0.03)


def test_weighting_removes_dc_and_is_linear() -> None:
    dt = 1e-3
    t = np.arange(0.0, 30.0, dt)
    x = np.sin(2 * math.pi * 4 * t)
    a = weighted_rms(x + 5.0, dt, "k", settle_s=10)
    b = weighted_rms(x, dt, "k", settle_s=10)
    assert a == pytest.approx(b, rel=1e-3)
    assert weighted_rms(3 * x, dt, "k", 10) == pytest.approx(3 * b, rel=1e-9)


def test_ride_comfort_and_labels() -> None:
    dt = 1e-3
    t = np.arange(0.0, 10.0, dt)
    rep = ride_comfort(0.2 * np.sin(2 * math.pi * 6 * t), np.zeros_like(t), dt, settle_s=3)
    assert rep.a_wy_m_s2 == pytest.approx(0.0, abs=1e-12)
    assert rep.a_v_m_s2 == pytest.approx(rep.a_wz_m_s2)
    assert rep.label == "not uncomfortable"
    assert comfort_label(0.5) == "a little uncomfortable"
    assert comfort_label(3.0) == "extremely uncomfortable"
    assert comfort_label(math.nan) == "n/a"
    assert set(rep.to_dict()) == {"a_wz_m_s2", "a_wy_m_s2", "a_v_m_s2", "label"}


def test_invalid_inputs() -> None:
    with pytest.raises(ValueError, match="weighting"):
        weighting_gain("x", 1.0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="dt_s"):
        weighted_signal(np.zeros(10), 0.0, "k")
    with pytest.raises(ValueError, match="finite"):
        weighted_signal(np.array([0.0, np.nan]), 1e-3, "k")
    assert math.isnan(weighted_rms(np.zeros(0), 1e-3, "k"))
