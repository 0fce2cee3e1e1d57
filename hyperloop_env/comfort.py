"""Ride comfort: ISO 2631-1 frequency-weighted RMS acceleration of the capsule.

Frequency weightings (ISO 2631-1:1997, Annex A, Table A.2; parameters as restated in
ISO 8041, Table 3.1 of the Larson Davis HVM200 manual). Each weighting is the product of
four analog stages in the Laplace variable ``p = j·2πf``::

    band-limiting high-pass  H_h = p² / (p² + p·ω1/Q1 + ω1²)
    band-limiting low-pass   H_l = ω2² / (p² + p·ω2/Q2 + ω2²)
    a-v transition           H_t = (1 + p/ω3) / (1 + p/(Q4·ω4) + p²/ω4²)
    upward step              H_s = (1 + p/(Q5·ω5) + p²/ω5²) / (1 + p/(Q6·ω6) + p²/ω6²) · (ω5/ω6)²
    W(p) = K · H_h · H_l · H_t · H_s,        ω_i = 2π f_i

==========  =====  ======  =====  ======  =====  =====  ====  =====  ====  =====  =====
weighting   f1 Hz  Q1      f2 Hz  Q2      f3 Hz  f4 Hz  Q4    f5 Hz  Q5    f6 Hz  Q6
==========  =====  ======  =====  ======  =====  =====  ====  =====  ====  =====  =====
W_k (vert.) 0.4    1/√2    100    1/√2    12.5   12.5   0.63  2.37   0.91  3.35   0.91
W_d (lat.)  0.4    1/√2    100    1/√2    2.0    2.0    0.63  ∞      –     ∞      –
==========  =====  ======  =====  ======  =====  =====  ====  =====  ====  =====  =====

W_k applies to vertical (z-axis) whole-body vibration, W_d to horizontal; the gain K is 1.
Time-domain weighting uses the bilinear transform of each analog stage (as measuring
instruments do; the frequency warping at 100 Hz with fs = 1 kHz is ~3 %, at 5 Hz < 0.1 %).

Comfort scale (ISO 2631-1 Annex C.2.3, public transport; overlapping bands as in the
standard): < 0.315 m/s² not uncomfortable; 0.315–0.63 a little; 0.5–1 fairly; 0.8–1.6
uncomfortable; 1.25–2.5 very; > 2 extremely uncomfortable.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
from scipy import signal as sps

Weighting = Literal["k", "d"]

_PARAMS: dict[str, dict[str, float]] = {
    "k": dict(
        f1=0.4,
        q1=1 / math.sqrt(2),
        f2=100.0,
        q2=1 / math.sqrt(2),
        f3=12.5,
        f4=12.5,
        q4=0.63,
        f5=2.37,
        q5=0.91,
        f6=3.35,
        q6=0.91,
        k=1.0,
    ),
    "d": dict(
        f1=0.4,
        q1=1 / math.sqrt(2),
        f2=100.0,
        q2=1 / math.sqrt(2),
        f3=2.0,
        f4=2.0,
        q4=0.63,
        f5=math.inf,
        q5=1.0,
        f6=math.inf,
        q6=1.0,
        k=1.0,
    ),
}

HORIZONTAL_FACTOR = 1.4
"""ISO 2631-1 §8.2.3 multiplying factor k for horizontal axes (comfort, seated)."""


def _check_kind(kind: str) -> dict[str, float]:
    if kind not in _PARAMS:
        raise ValueError(f"weighting must be one of {sorted(_PARAMS)}, got {kind!r}")
    return _PARAMS[kind]


def analog_stages(kind: Weighting) -> list[tuple[np.ndarray, np.ndarray]]:
    """The analog stages (b, a) (polynomials in p, highest power first) of weighting
    ``kind`` ("k": W_k vertical, "d": W_d horizontal)."""
    c = _check_kind(kind)
    w1, w2, w3, w4 = (2 * math.pi * c[f] for f in ("f1", "f2", "f3", "f4"))
    stages = [
        (np.array([1.0, 0.0, 0.0]), np.array([1.0, w1 / c["q1"], w1 * w1])),
        (np.array([w2 * w2]), np.array([1.0, w2 / c["q2"], w2 * w2])),
        (np.array([1.0 / w3, 1.0]), np.array([1.0 / (w4 * w4), 1.0 / (c["q4"] * w4), 1.0])),
    ]
    if math.isfinite(c["f5"]):
        w5, w6 = 2 * math.pi * c["f5"], 2 * math.pi * c["f6"]
        gain = (w5 / w6) ** 2
        stages.append(
            (
                gain * np.array([1.0 / (w5 * w5), 1.0 / (c["q5"] * w5), 1.0]),
                np.array([1.0 / (w6 * w6), 1.0 / (c["q6"] * w6), 1.0]),
            )
        )
    stages[0] = (stages[0][0] * c["k"], stages[0][1])
    return stages


def weighting_gain(kind: Weighting, f_hz: float | np.ndarray) -> np.ndarray:
    """|W(j·2πf)| of the analog weighting (exact, no discretisation)."""
    p = 1j * 2 * math.pi * np.asarray(f_hz, dtype=np.float64)
    h = np.ones_like(p)
    for b, a in analog_stages(kind):
        h = h * np.polyval(b, p) / np.polyval(a, p)
    return np.abs(h)


def digital_sos(kind: Weighting, fs_hz: float) -> np.ndarray:
    """Second-order sections of the weighting discretised by the bilinear transform."""
    if not (math.isfinite(fs_hz) and fs_hz > 0):
        raise ValueError(f"fs_hz must be a finite number > 0, got {fs_hz!r}")
    _check_kind(kind)
    sos = []
    for b, a in analog_stages(kind):
        bd, ad = sps.bilinear(b, a, fs=fs_hz)  # both of length 3 (second order)
        sos.append(np.concatenate([bd / ad[0], ad / ad[0]]))
    return np.array(sos)


def weighted_signal(acc: np.ndarray, dt_s: float, kind: Weighting) -> np.ndarray:
    """Frequency-weighted acceleration time series [m/s²] (causal, mean removed first so
    the 0.4 Hz high-pass starts without a step transient)."""
    x = np.asarray(acc, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"acc must be 1-D, got shape {x.shape}")
    if not (math.isfinite(dt_s) and dt_s > 0):
        raise ValueError(f"dt_s must be a finite number > 0, got {dt_s!r}")
    if x.size == 0:
        return x.copy()
    if not np.isfinite(x).all():
        raise ValueError("acc must be finite")
    return sps.sosfilt(digital_sos(kind, 1.0 / dt_s), x - x.mean())


def weighted_rms(acc: np.ndarray, dt_s: float, kind: Weighting, settle_s: float = 0.0) -> float:
    """ISO 2631-1 frequency-weighted RMS acceleration a_w [m/s²] (eq. 1 of the standard),
    ignoring the first ``settle_s`` seconds of the weighted signal. NaN if empty."""
    y = weighted_signal(acc, dt_s, kind)
    n0 = int(round(settle_s / dt_s)) if settle_s > 0 else 0
    y = y[n0:]
    return float(np.sqrt(np.mean(y * y))) if y.size else math.nan


def comfort_label(a_w: float) -> str:
    """ISO 2631-1 Annex C.2.3 verbal comfort reaction for a weighted RMS [m/s²]."""
    if not math.isfinite(a_w):
        return "n/a"
    for limit, label in (
        (0.315, "not uncomfortable"),
        (0.63, "a little uncomfortable"),
        (1.0, "fairly uncomfortable"),
        (1.6, "uncomfortable"),
        (2.5, "very uncomfortable"),
    ):
        if a_w < limit:
            return label
    return "extremely uncomfortable"


@dataclass(frozen=True)
class ComfortReport:
    """Weighted RMS accelerations of the capsule [m/s²]."""

    a_wz_m_s2: float  # vertical, W_k
    a_wy_m_s2: float  # lateral, W_d
    a_v_m_s2: float  # vibration total value sqrt((1.4 a_wy)² + a_wz²) (no longitudinal)
    label: str

    def to_dict(self) -> dict[str, float | str | None]:
        return {
            k: (v if not isinstance(v, float) or math.isfinite(v) else None)
            for k, v in asdict(self).items()
        }


def ride_comfort(
    acc_vertical: np.ndarray, acc_lateral: np.ndarray, dt_s: float, settle_s: float = 0.0
) -> ComfortReport:
    """ISO 2631-1 comfort of the capsule from its vertical and lateral accelerations."""
    az = weighted_rms(acc_vertical, dt_s, "k", settle_s)
    ay = weighted_rms(acc_lateral, dt_s, "d", settle_s)
    av = math.sqrt((HORIZONTAL_FACTOR * ay) ** 2 + az**2) if math.isfinite(az + ay) else math.nan
    return ComfortReport(az, ay, av, comfort_label(av))
