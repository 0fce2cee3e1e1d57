"""The reward: a sum of named terms, each a small compiled function of one step's record.

=========  =========================================================  ======================
term       value                                                      keyword weight w
=========  =========================================================  ======================
gap        −w · mean_a min((s_a/Ω)², 4)   (in [−4w, 0]; −w at Ω)        ``gap_weight`` (1)
guidance   −w · mean_a min((z_a/Ω_g)², 4) (guidance gaps)               ``guidance_weight`` (1)
current    −w · Σ_kinds mean_a (I_k,a/ref_k − neutral_k)²              ``current_weight`` (0.05)
comfort    −w · min((a_heave² + a_lat²)/g², 100)                      ``comfort_weight`` (1)
survival   +w while there is no contact (0 at the contact step)        ``survival_weight`` (1)
contact    −w at the contact step, else 0                              ``contact_weight`` (100)
=========  =========================================================  ======================

s_a: gap excursion, Ω: clearance, z_a: guidance gap excursion (the unit's lateral offset
from the guideway), Ω_g: guidance clearance, I_k,a: applied current of every actuator kind
k the simulator knows (commanded or not), with its reference current ref_k and neutral
command neutral_k (``ActuatorKind``): the levitation coils give ((I_a − I0)/I0)² (I0:
equilibrium current), the guidance pairs (ΔI_a/I_g0)² (ΔI_a: applied differential guidance
current, 0 unless the guidance pairs are actuated; I_g0: guidance bias current), so the term
is −w · [mean_a ((I_a − I0)/I0)² + mean_a (ΔI_a/I_g0)²]; a_heave/a_lat: capsule accelerations
(track frame), g: gravity. Non-finite inputs (a diverged state, which the simulator flags as
contact) give the caps (gap and guidance: 4 per unit; current: the sum of squares over the
units is capped at 1e12, so the term is at least −w·2.5e11; comfort: 100).

:data:`REWARD_TERMS` is the one list of names: the order of the weights
(:class:`hyperloop_env.config.RewardWeights`), of the terms the kernel writes and of
``info["reward_terms"]``. The survival bonus is needed for PPO: without it every step costs
(the gap term alone averages ≈ −0.04 for the passive vehicle), so over a 7200-step episode
crashing early (−100 once) would beat flying; with it a step without contact is worth ≈ +1.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from hyperloop_env.physics.layout import (
    K_NEUTRAL,
    K_RECORD,
    K_REF,
    KIND_STRIDE,
    M_ACC_HEAVE,
    M_ACC_LAT,
    M_CONTACT,
    M_GAP,
    M_LAT,
    P_CLEAR,
    P_G,
    P_GCLEAR,
    P_KINDS,
)
from hyperloop_env.physics.units import N_UNITS

REWARD_TERMS: tuple[str, ...] = ("gap", "guidance", "current", "comfort", "survival", "contact")
"""Names of the reward terms, in the order of the weights, the kernel and the info dict."""

GAP_TERM_CAP = 4.0  # (s/Ω)² is capped at 4 (|s| = 2Ω): only matters at the contact step
CURRENT_TERM_CAP = 1e12  # cap of the sum of squares (before the mean over units)
COMFORT_TERM_CAP = 100.0  # (a_heave² + a_lat²)/g² capped at 100 (10 g)
_MEAN = 1.0 / N_UNITS


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def capped_square(q: float) -> float:  # pragma: no cover - compiled
    """One unit's share of the gap and guidance terms: min(q², 4) for q = s_a/Ω (NaN: NaN)."""
    q = q**2
    return q if q < GAP_TERM_CAP else GAP_TERM_CAP


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def gap_penalty(total: float, w: float) -> float:  # pragma: no cover - compiled
    """−w · total/N_UNITS for the sum ``total`` of the units' :func:`capped_square` (a NaN
    sum gives the cap); the gap and the guidance term."""
    if not total <= N_UNITS * GAP_TERM_CAP:  # NaN
        total = N_UNITS * GAP_TERM_CAP
    return -w * _MEAN * total


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def current_penalty(total: float, w: float) -> float:  # pragma: no cover - compiled
    """−w · total/N_UNITS for the sum ``total`` over kinds of each kind's sum of squares
    (capped at 1e12; NaN gives the cap)."""
    if not total < CURRENT_TERM_CAP:
        total = CURRENT_TERM_CAP
    return -w * _MEAN * total


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def kind_block(p: np.ndarray, k: int) -> tuple[float, float, int]:  # pragma: no cover
    """Actuator kind ``k``'s reference current [A], neutral command and the record slot of
    its first unit's applied current, from the parameter row ``p``: the current term's and
    the observation's I_k,a/ref_k − neutral_k."""
    kb = P_KINDS + k * KIND_STRIDE
    return p[kb + K_REF], p[kb + K_NEUTRAL], int(p[kb + K_RECORD])


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def gap_term(r: np.ndarray, p: np.ndarray, w: float) -> float:
    """−w · mean_a min((s_a/Ω)², 4)."""
    clear = p[P_CLEAR]
    sgap = 0.0
    for a in range(N_UNITS):
        sgap += capped_square(r[M_GAP + a] / clear)
    return gap_penalty(sgap, w)


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def guidance_term(r: np.ndarray, p: np.ndarray, w: float) -> float:
    """−w · mean_a min((z_a/Ω_g)², 4)."""
    clear = p[P_GCLEAR]
    sz = 0.0
    for a in range(N_UNITS):
        sz += capped_square(r[M_LAT + a] / clear)
    return gap_penalty(sz, w)


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def current_term(r: np.ndarray, p: np.ndarray, w: float) -> float:
    """−w · Σ_kinds mean_a (I_k,a/ref_k − neutral_k)² of the applied currents of every
    actuator kind in ``p`` (levitation and guidance: −w · [mean_a ((I_a − I0)/I0)² +
    mean_a (ΔI_a/I_g0)²])."""
    scur = 0.0
    for k in range((p.shape[0] - P_KINDS) // KIND_STRIDE):
        ref, neutral, rs = kind_block(p, k)
        sk = 0.0
        for a in range(N_UNITS):
            e = r[rs + a] / ref - neutral
            sk += e * e
        scur = scur + sk
    return current_penalty(scur, w)


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def comfort_term(r: np.ndarray, p: np.ndarray, w: float) -> float:
    """−w · min((a_heave² + a_lat²)/g², 100)."""
    g = p[P_G]
    ah = r[M_ACC_HEAVE]
    al = r[M_ACC_LAT]
    cq = (ah * ah + al * al) / (g * g)
    if not cq < COMFORT_TERM_CAP:
        cq = COMFORT_TERM_CAP
    return -w * cq


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def survival_term(r: np.ndarray, p: np.ndarray, w: float) -> float:
    """+w without contact, 0 at the contact step."""
    return 0.0 if r[M_CONTACT] > 0.5 else w


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def contact_term(r: np.ndarray, p: np.ndarray, w: float) -> float:
    """−w at the contact step, else 0."""
    return -w if r[M_CONTACT] > 0.5 else 0.0


def reward_info(terms: np.ndarray) -> dict[str, float]:
    """``info["reward_terms"]`` of one environment from its row of term values."""
    return {name: float(terms[k]) for k, name in enumerate(REWARD_TERMS)}
