"""Compiled kernels shared by the single and the native vector environment.

Row i of every 2-D array is environment i; the single environment passes one row, so both
environments produce bit-identical observations, rewards and noise.

* :func:`commanded_currents` — action → full command vector of the simulator;
* :func:`observe` — the observation (:mod:`hyperloop_env.observation`) from the records;
* :func:`reward` — the reward terms (:mod:`hyperloop_env.reward`) and their sum;
* :func:`add_noise` — counter-based Gaussian sensor noise (:mod:`hyperloop_env.sensors`);
* :func:`step_outcome` — the vector environment's step after the physics in one call:
  modes, observation, reward, step counters, terminated/truncated.

``mode[i]``: 0 skip the row, 1 a reset (gap rate and reward zero), 2 a step.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from hyperloop_env.observation import (
    CURVATURE_SCALE_M,
    GAP_RATE_SCALE_M_S,
    SPEED_SCALE_M_S,
    command_current,
)
from hyperloop_env.physics.layout import (
    KIND_STRIDE,
    M_ACC_HEAVE,
    M_ACC_LAT,
    M_GAP,
    M_LAT,
    M_SPEED,
    M_X,
    P_CLEAR,
    P_CURVE0,
    P_DT,
    P_G,
    P_GCLEAR,
    P_KAPPA,
    P_KINDS,
    P_TRANS,
)
from hyperloop_env.physics.units import N_UNITS
from hyperloop_env.reward import (
    capped_square,
    comfort_term,
    contact_term,
    current_penalty,
    current_term,
    gap_penalty,
    gap_term,
    guidance_term,
    kind_block,
    survival_term,
)

MODE_SKIP = 0
MODE_RESET = 1
MODE_STEP = 2

# positions in the offsets array (observation.KERNEL_BLOCKS, then one per actuator kind)
_B_GAP, _B_RATE, _B_LAT, _B_LRATE, _B_ACC, _B_SPEED, _B_CURV, _B_KINDS = range(8)

_command_current = nb.njit(inline="always")(command_current)


@nb.njit(cache=True, error_model="numpy", _nrt=False)  # no zero-division checks, no refcounts
def commanded_currents(action, base, neutral, scale, index, out) -> bool:  # pragma: no cover
    """``out[i, index[j]] = base[i, j]·(neutral[j] + scale·clip(a[i, j], −1, 1))`` [A]
    (:func:`observation.command_current`); False if any action is not finite. Channels not
    in ``index`` keep their value in ``out``."""
    n = action.shape[0]
    m = action.shape[1]
    for i in range(n):
        for j in range(m):
            x = action[i, j]
            if not math.isfinite(x):
                return False
            x = -1.0 if x < -1.0 else (1.0 if x > 1.0 else x)
            out[i, index[j]] = _command_current(base[i, j], neutral[j], scale, x)
    return True


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _observe_row(i, rec, P, prev, mode, obs, offsets, preview):  # pragma: no cover - compiled
    """Row ``i`` of :func:`observe` (a row not skipped). Returns the sums of the gap, guidance
    and current terms of the row's reward (:func:`hyperloop_env.reward.gap_term`'s sum of
    :func:`~hyperloop_env.reward.capped_square`, the guidance term's, the current term's sum of
    squares over every kind), from the quotients the observation holds: the reward's values,
    operation for operation, without dividing twice (:func:`step_outcome`)."""
    npv = preview.shape[0]
    og, orr, ol = offsets[_B_GAP], offsets[_B_RATE], offsets[_B_LAT]
    olr = offsets[_B_LRATE]
    oa, osp, ocv = offsets[_B_ACC], offsets[_B_SPEED], offsets[_B_CURV]
    nk = (P.shape[1] - P_KINDS) // KIND_STRIDE
    first = mode[i] == MODE_RESET
    r = rec[i]
    p = P[i]
    clear = p[P_CLEAR]
    latc = p[P_GCLEAR]
    g = p[P_G]
    inv_dt = 1.0 / p[P_DT]
    o = obs[i]
    sgap = 0.0
    slat = 0.0
    for a in range(N_UNITS):
        s = r[M_GAP + a]
        q = s / clear
        o[og + a] = q
        sgap += capped_square(q)
        if first:
            o[orr + a] = 0.0
        else:
            o[orr + a] = (s - prev[i, a]) * inv_dt / GAP_RATE_SCALE_M_S
        prev[i, a] = s
        z = r[M_LAT + a]
        q = z / latc
        o[ol + a] = q
        slat += capped_square(q)
        if olr >= 0:
            if first:
                o[olr + a] = 0.0
            else:
                o[olr + a] = (z - prev[i, N_UNITS + a]) * inv_dt / GAP_RATE_SCALE_M_S
        prev[i, N_UNITS + a] = z
    scur = 0.0
    for k in range(nk):
        ok = offsets[_B_KINDS + k]
        ref, neutral, rs = kind_block(p, k)
        sk = 0.0
        for a in range(N_UNITS):
            e = r[rs + a] / ref - neutral
            if ok >= 0:
                o[ok + a] = e
            sk += e * e
        scur = scur + sk
    o[oa] = r[M_ACC_HEAVE] / g
    o[oa + 1] = r[M_ACC_LAT] / g
    o[osp] = r[M_SPEED] / SPEED_SCALE_M_S
    x = r[M_X]
    for k in range(npv):
        u = (x + preview[k] - p[P_CURVE0]) / p[P_TRANS]
        u = 0.0 if u <= 0.0 else (1.0 if u >= 1.0 else u)
        o[ocv + k] = p[P_KAPPA] * u * CURVATURE_SCALE_M
    for j in range(obs.shape[1]):  # a select, not a branch: the loop vectorises
        v = o[j]
        o[j] = v if v - v == 0.0 else np.float32(0.0)  # NaN and ±inf give NaN
    return sgap, slat, scur


@nb.njit(cache=True, error_model="numpy", _nrt=False)  # no zero-division checks, no refcounts
def observe(rec, P, prev, mode, obs, offsets, preview):  # pragma: no cover - compiled
    """Observation rows from the records, by block offsets (−1: block absent; the gap,
    lateral, acceleration, levitation current, speed and curvature blocks are always
    present). Each actuator kind k's block holds its applied currents (record slot
    ``K_RECORD``) as I/reference − neutral. ``prev`` (n, 2·N_UNITS) holds the previous gaps
    and guidance gaps and is updated; non-finite entries are replaced by 0."""
    for i in range(rec.shape[0]):
        if mode[i] != MODE_SKIP:
            _observe_row(i, rec, P, prev, mode, obs, offsets, preview)


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _store_reward(i, r, p, mode, weights, terms, out, t0, t1, t2):  # pragma: no cover
    """Row ``i``'s reward terms and their sum from its gap, guidance and current terms
    ``t0``-``t2`` (a reset row: zeros)."""
    if mode[i] == MODE_RESET:
        for j in range(terms.shape[1]):
            terms[i, j] = 0.0
        out[i] = 0.0
        return
    t3 = comfort_term(r, p, weights[3])
    t4 = survival_term(r, p, weights[4])
    t5 = contact_term(r, p, weights[5])
    terms[i, 0] = t0
    terms[i, 1] = t1
    terms[i, 2] = t2
    terms[i, 3] = t3
    terms[i, 4] = t4
    terms[i, 5] = t5
    out[i] = t0 + t1 + t2 + t3 + t4 + t5


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _reward_row(i, rec, P, mode, weights, terms, out):  # pragma: no cover - compiled
    """Row ``i`` of :func:`reward` (a row not skipped)."""
    r = rec[i]
    p = P[i]
    if mode[i] == MODE_RESET:
        _store_reward(i, r, p, mode, weights, terms, out, 0.0, 0.0, 0.0)
        return
    t0 = gap_term(r, p, weights[0])
    t1 = guidance_term(r, p, weights[1])
    t2 = current_term(r, p, weights[2])
    _store_reward(i, r, p, mode, weights, terms, out, t0, t1, t2)


@nb.njit(cache=True, error_model="numpy", _nrt=False)  # no zero-division checks, no refcounts
def reward(rec, P, mode, weights, terms, out):  # pragma: no cover - compiled
    """Reward terms (order of ``reward.REWARD_TERMS``) and their sum per row; a reset row
    gets zeros."""
    for i in range(rec.shape[0]):
        if mode[i] != MODE_SKIP:
            _reward_row(i, rec, P, mode, weights, terms, out)


@nb.njit(cache=True, error_model="numpy", _nrt=False)  # no zero-division checks, no refcounts
def step_outcome(
    rec,
    P,
    prev,
    mode,
    obs,
    offsets,
    preview,
    weights,
    terms,
    rew,
    prev_done,
    steps,
    max_steps,
    sensor_steps,
    contact_col,
    terminated,
    truncated,
    done,
):  # pragma: no cover - compiled
    """One step of the vector environment after the physics, for every row: ``mode`` from
    ``prev_done`` (reset rows: their new episode's first observation), :func:`observe` and
    :func:`reward` row by row in one pass (the reward's gap, guidance and current sums from
    the observation's quotients, :func:`_observe_row`: the same values bit for bit), then
    for the rows that stepped (``not prev_done``) the step counters (``steps`` and, if it
    has rows, ``sensor_steps``) and ``terminated = contact``, ``truncated = steps >=
    max_steps and not terminated``, ``done`` their union (all False for reset rows).
    Returns whether any row is done."""
    n = rec.shape[0]
    for i in range(n):  # a row's observation and reward in one pass (shared quotients)
        mode[i] = MODE_RESET if prev_done[i] else MODE_STEP
        sgap, slat, scur = _observe_row(i, rec, P, prev, mode, obs, offsets, preview)
        t0 = gap_penalty(sgap, weights[0])
        t1 = gap_penalty(slat, weights[1])
        t2 = current_penalty(scur, weights[2])
        _store_reward(i, rec[i], P[i], mode, weights, terms, rew, t0, t1, t2)
    count_sensor = sensor_steps.shape[0] == n
    any_done = False
    for i in range(n):
        te = False
        tr = False
        if not prev_done[i]:
            steps[i] += 1
            if count_sensor:
                sensor_steps[i] += 1
            te = rec[i, contact_col] > 0.5
            tr = (steps[i] >= max_steps[i]) and not te
        terminated[i] = te
        truncated[i] = tr
        done[i] = te or tr
        any_done = any_done or te or tr
    return any_done


@nb.njit(cache=True)
def _splitmix64(x):  # pragma: no cover - compiled
    z = x + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@nb.njit(cache=True)
def add_noise(obs, keys, counters, std, n_noisy):  # pragma: no cover - compiled
    """obs[i, :n_noisy] += std·N(0, 1), the normal draws a pure function of (keys[i],
    counters[i], channel) (counter-based, so a batch matches single environments)."""
    two53 = 1.0 / 9007199254740992.0
    for i in range(obs.shape[0]):
        base = _splitmix64(keys[i] ^ (counters[i] * np.uint64(0x100000001B3)))
        for j in range(n_noisy):
            z1 = _splitmix64(base + np.uint64(2 * j))
            z2 = _splitmix64(base + np.uint64(2 * j + 1))
            u1 = ((z1 >> np.uint64(11)) + np.uint64(1)) * two53  # (0, 1]
            u2 = (z2 >> np.uint64(11)) * two53
            obs[i, j] += std * math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)
