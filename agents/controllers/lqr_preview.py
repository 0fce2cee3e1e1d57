"""LQG with guideway preview: the rear magnet units are told by the front ones what
guideway is coming (``lqr-preview``).

The vehicle carries its own preview sensor: the rear units (RL, RR) run over the guideway
the front units (FL, FR) of the same side ran over one set spacing d1 earlier (docs/model.md,
"Disturbances": the irregularity is a function of x, "front and rear units see the same
profile d1/v apart"). The controller is :class:`~agents.controllers.lqr.LQRController`
(same Riccati and Kalman gains, same filter, integrator and saturation; see
:mod:`agents.controllers.lqr`) plus a finite-preview feed-forward for the rear units'
track, per plane (the levitation gaps and, with ``actuators="levitation+guidance"``, the
guidance gaps).

**Preview signal.** Each step, from the measurement-updated estimate x̂ (step k, after the
Kalman update) and the measured gap excursion s_a of front unit a (the plane's gap row
``s_a = C_v,a·x + c_r·r_a`` of the design model, ``c_r = −σ``, σ the magnet orientation
sign of ``s = σ·(y_a − w − r_y)``; lateral plane: z_a = z_unit − r_a, σ = 1)::

    h_a = (s_a − C_v,a·x̂) / c_r          [m]   the guideway position under unit a
    ρ̃_a = (h_a, ṙ̂_a)                   [m, m/s] with ṙ̂_a the filter's track rate

(vertical: ``h_a = ŷ_a − σ·s_a``, the measured gap subtracted from the estimated magnet
height). ρ̃ of FL and FR goes into a delay line (a ring buffer per row and side of
H + 1 samples). The rear unit of the same side is at that guideway position
``N = round(d1 / (v·dt))`` control steps later (v from the observation's speed entry, dt
the control interval).

**Finite-preview LQR (Tomizuka 1975; Tomizuka & Whitney, J. Dyn. Sys. Meas. Control 97
(1975) 319; the discrete form of e.g. Hać, J. Sound Vib. 157 (1992) for vehicle
suspensions).** Take the LQR's augmented design model ``z_{k+1} = A z + B u`` (z = [x, q],
the discretised plant with all four units' Gauss–Markov track states ρ_a = (r_a, ṙ_a)
and the gap integrators; per-step cost ``zᵀQz + uᵀRu``, :mod:`agents.controllers.lqr`)
and split z into the rear units' track states ρ (4 states) and the rest z̄. ρ is not
driven by z̄ or u, so the rear track enters the rest as a known input,
``z̄⁺ = Ā z̄ + B̄ u + G ρ_k``, with the cross cost ``2 z̄ᵀN₀ρ_k`` (the rear gaps contain
r), and the z̄ block S̄ of the LQR's Riccati solution S is the Riccati solution of
(Ā, B̄). With the exosystem "ρ_k … ρ_{k+N} known, beyond the horizon the track model's
prediction ρ_{k+N+i} = Φ_ρ^i ρ_{k+N}" the optimal law is (W = (R + B̄ᵀS̄B̄)⁻¹,
A_c = Ā − B̄K̄ the closed loop)::

    u_k = −K̄ z̄_k − Σ_{j<N} K_j ρ_{k+j} − K_N^tail ρ_{k+N}
    K_0 = W B̄ᵀ S̄ G,  K_j = W B̄ᵀ P_{j−1},  P_0 = A_cᵀ S̄ G + N₀,  P_j = A_cᵀ P_{j−1}
    K_N^tail = W B̄ᵀ (P_{N−1} + X_N Φ_ρ),  X_N − A_cᵀ X_N Φ_ρ = A_cᵀ P_{N−1}  (Stein)

(derivation: the value function ``z̄ᵀS̄z̄ + 2 z̄ᵀP D + …`` of the state [z̄, D], D the
stacked preview, gives ``P = A_cᵀ(S̄ G_D + P F) + N`` with F the shift). The K_j do not
depend on N; only the tail gain does, and for N = 0 it is the LQR's own gain on ρ
(checked at construction, as is K̄ = the LQR's gain on z̄: the same Riccati solution).
If the known future is the track model's own prediction, ``ρ_{k+j} = Φ_ρ^j ρ̂_k``, the
law is the LQR's exactly: ``Σ_{j<N} K_j Φ_ρ^j + K_N^tail Φ_ρ^N = K_ρ`` (the certainty
equivalence of the LQR's rear-track feed-forward; a test checks it to 1e-9).

**The preview used.** The rear track ahead is taken as the model's prediction from the
filter's estimate plus the change the front unit measured between the same two places,
weighted by α::

    ρ_rear(k + j) = Φ_ρ^j ρ̂_rear(k) + α·(ρ̃_front(k − N + j) − ρ̃_front(k − N)),  j = 0 … N

so that, by the identity above, the command is the LQR's plus the preview of the change::

    u_k = u_k^LQR − α·Σ_{j=1..N} G_j·(ρ̃_front(k − N + j) − ρ̃_front(k − N)),
    G_j = K_j (j < N),  G_N = K_N^tail

Only changes enter, never the absolute guideway height, which is barely observable (the
gaps are relative; the only inertial signal is the heave acceleration, so the filter's frame
drifts by ~2 mm, held by its "capsule ≈ 0" pseudo-measurements; a preview in absolute terms
put the vehicle in contact within 1 s). α = 1 would count the model's trend and the
measured change both; the front's measured change is also not the rear's: the flexible
beam's deflection under the vehicle's own load differs between the front and the rear
passage (standard deviation ≈ 0.98 mm at 1000 km/h, ≈ 0.45 mm at 2000 km/h under ``lqr``:
``test_beam_deflection_differs_between_front_and_rear_passage``; driven by the magnet
forces themselves), and the rear's preview forces load the span the front units
are on. α = :data:`PREVIEW_WEIGHT` = 0.5 was chosen on validation seeds by the capacity score
(``hyperloop tune preview``; the scan of α = 0.25, 0.5, 0.75, 1 is in
``agents/controllers/lqr_preview_weight.json``). α = 0 is the plain LQR law bit for bit.

No preview (the plain LQR law, bit for bit) while N = 0 (a set spacing shorter than half
a control step's travel: the front units are then no earlier than the rear ones), while
N > H (speed below d1/(H·dt): ``max_preview_s`` = H·dt = 0.25 s by default, i.e. below
≈ 230 km/h at d1 = 16 m), before N + 1 samples of an episode are in the delay line, and
with ``max_preview_s=0`` or ``preview_weight=0``. The delay is rounded to whole steps
(≤ 0.5 ms; a 14 cm shift at 1000 km/h); the speed is taken as constant over the delay.
A zero set spacing is not a valid vehicle (``VehicleParams``). The lateral plane gets the
same preview (guidance gaps, lateral track position).

**What it achieves here (measured; tests/agents/controllers/test_lqr_preview.py and the
headline).** On ``paper-1000-straight`` at the default roughness the rear units' RMS gap
excursion falls to ≈ 0.56 of plain LQR's while the front units' rises ≈ 1.12×; at the
roughness where gaps reach the clearance the rear units are the ones that touch first, and
there the preview raises the capacity (validation seeds: +4 % levitation only, +15 % with the
guidance pairs actuated). In the linear design model with an exactly known guideway the
preview lowers the rear gap RMS by only ≈ 3 % (the LQR's weights trade gap against heave
acceleration).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba as nb
import numpy as np
from scipy.linalg import lu_factor, lu_solve

from agents.controllers.lqr import (
    LateralLQRDesign,
    LQGMatrices,
    LQRController,
    LQRDesign,
    _dare,
    _PlaneLQG,
    accumulate_rows,
    lqg_command,
    lqg_update,
)
from hyperloop_env.observation import SPEED_SCALE_M_S
from hyperloop_env.physics.arrays import aligned_copy, aligned_zeros
from hyperloop_env.physics.entry import compiled_entry, strided
from hyperloop_env.physics.units import N_UNITS

NU = N_UNITS
FRONT_UNITS = (0, 1)  # FL, FR (hyperloop_env.physics.units.UNIT_NAMES)
REAR_UNITS = (2, 3)  # RL, RR: the rear unit of the same side, in the same order
N_SIGNALS = 2 * len(FRONT_UNITS)  # the delay line's signals: (h, ṙ̂) of FL, then FR
MAX_PREVIEW_S = 0.25
"""Default longest preview [s] (the delay line's length): below d1/0.25 s the rear units
get no preview (plain LQR)."""
PREVIEW_WEIGHT = 0.5
"""α: the default weight of the front units' measured change (module docstring, chosen on
validation seeds by ``hyperloop tune preview``)."""


@dataclass(frozen=True)
class PreviewGains:
    """The finite-preview gains of one plane (module docstring), in physical units.

    ``pure[j]`` (H, NU, 4): K_j on the rear track states ρ_{k+j} = (r, ṙ) of RL then RR
    [A/m, A/(m/s)]; ``tail[N]`` (H + 1, NU, 4): the tail gain for a preview of N steps
    (``tail[0]``: the LQR's gain on the rear track states); ``k_rear`` (NU, 4): the LQR's
    gain on them; ``rear_cols`` / ``front_cols``: the rows of (r, ṙ) of RL, RR / FL, FR in
    the design state x."""

    pure: np.ndarray
    tail: np.ndarray
    k_rear: np.ndarray
    rear_cols: np.ndarray
    front_cols: np.ndarray

    @property
    def horizon(self) -> int:
        return self.pure.shape[0]


def _track_cols(n: int, units: tuple[int, ...]) -> np.ndarray:
    """Rows of the track states (r_a, ṙ_a) of ``units`` in a design state of ``n`` states
    (the vehicle states, then (r, ṙ) per unit: :func:`agents.controllers.lqr._design_plane`)."""
    nv = n - 2 * NU
    return np.array([nv + 2 * a + k for a in units for k in (0, 1)], dtype=np.int64)


def preview_gains(m: LQGMatrices, horizon: int) -> PreviewGains:
    """Tomizuka preview gains for the rear track of the plane designed as ``m`` (module
    docstring), from the LQR problem ``m`` carries (its scaled [x, q] model, weights and
    Riccati solution, :func:`agents.controllers.lqr._design_plane`); the gain of that
    solution must be the LQR's ``m.K`` (else ``RuntimeError``)."""
    if m.St is None or m.Pt is None or m.Gt is None or m.Qt is None or m.R is None:
        raise ValueError("the LQG design carries no LQR problem (LQGMatrices.Pt … St)")
    n = m.Phi.shape[0]
    At, Bt, Qt, S, R, sa = m.Pt, m.Gt, m.Qt, m.St, m.R, m.sa
    K = np.linalg.solve(R + Bt.T @ S @ Bt, Bt.T @ S @ At) / sa[None, :]
    if not np.allclose(K, m.K, rtol=1e-6, atol=1e-9 * np.abs(m.K).max()):
        raise RuntimeError("the LQR problem does not give the LQR's gain")
    na = At.shape[0]
    rho = _track_cols(n, REAR_UNITS)
    rest = np.setdiff1d(np.arange(na), rho)
    Ab, Bb, G = At[np.ix_(rest, rest)], Bt[rest], At[np.ix_(rest, rho)]
    F, N0, Sb = At[np.ix_(rho, rho)], Qt[np.ix_(rest, rho)], S[np.ix_(rest, rest)]
    W = np.linalg.inv(R + Bb.T @ Sb @ Bb)
    Kb = W @ Bb.T @ Sb @ Ab
    Ac = Ab - Bb @ Kb
    nr = len(rest)
    # Stein equation X − A_cᵀ X F = C, column-major: (I − Fᵀ ⊗ A_cᵀ) vec X = vec C
    lu = lu_factor(np.eye(nr * len(rho)) - np.kron(F.T, Ac.T))

    def stein(c: np.ndarray) -> np.ndarray:
        return lu_solve(lu, c.ravel(order="F")).reshape(c.shape, order="F")

    SG = Sb @ G
    pure = np.zeros((horizon, NU, len(rho)))
    tail = np.zeros((horizon + 1, NU, len(rho)))
    tail[0] = W @ Bb.T @ (SG + stein(Ac.T @ SG + N0) @ F)  # N = 0: the LQR's own gain
    if horizon:
        pure[0] = W @ Bb.T @ SG
    P = Ac.T @ SG + N0  # P_0
    for N in range(1, horizon + 1):  # P = P_{N−1}
        tail[N] = W @ Bb.T @ (P + stein(Ac.T @ P) @ F)
        if N < horizon:
            pure[N] = W @ Bb.T @ P
        P = Ac.T @ P
    inv = 1.0 / sa[rho]  # ρ_t = ρ / s_ρ: gains on physical ρ
    pure, tail = pure * inv, tail * inv
    if not np.allclose(tail[0], K[:, rho], rtol=1e-6, atol=1e-9 * np.abs(K[:, rho]).max()):
        raise RuntimeError("the zero-preview gain is not the LQR's gain on the rear track")
    return PreviewGains(
        pure, tail, np.ascontiguousarray(m.K[:, rho]), rho, _track_cols(n, FRONT_UNITS)
    )


def front_signal_map(C: np.ndarray, gains: PreviewGains, X: np.ndarray) -> np.ndarray:
    """The front units' preview signals ρ̃ = (h, ṙ̂) of FL then FR, (4, m): a linear map of an
    operand v of m entries given ``X`` (n, m), the map from v to the filter's
    measurement-updated estimate x̂ = X·v, whose entry n + a is the measured gap y_a of unit
    a (the gaps lead the measurements)::

        h_a = (y_a − Σ_{c ≠ r_a} C_ac·x̂_c) / C_a,r_a        ṙ̂_a = x̂ at the unit's track rate

    (the gap row a of the design model's C, ``C_a,r_a = −σ``: the guideway position under
    unit a that the measured gap implies, given the estimated magnet)."""
    n = X.shape[0]
    E = np.zeros((N_SIGNALS, X.shape[1]))
    for s, a in enumerate(FRONT_UNITS):
        col = gains.front_cols[2 * s]
        c = C[a].copy()
        c[col] = 0.0
        row = -(c @ X)
        row[n + a] += 1.0  # the measured gap of unit a
        E[2 * s] = row / C[a, col]
        E[2 * s + 1] = X[gains.front_cols[2 * s + 1]]
    return E


def preview_map(plane: _PlaneLQG, gains: PreviewGains) -> np.ndarray:
    """``E`` (4, n + nl): :func:`front_signal_map` of the LQG's ``[z; y]``
    (:class:`agents.controllers.lqr._PlaneLQG`'s estimator coordinates z and live
    measurements y), through x̂ = (I − MC)·V·z + M·y."""
    n = plane.n
    live = np.flatnonzero(plane.src >= 0)
    xu = np.hstack([(np.eye(n) - plane.M @ plane.C) @ plane.V, plane.M[:, live]])
    return front_signal_map(plane.C, gains, xu)


SIDE_BY_SIDE = 4
"""Commands whose preview sums :func:`_preview_rows` runs side by side (four accumulators)."""


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def preview_add(obs, pg, E, W, S, speed_src, geo, line, Pv, P, Nrow):  # pragma: no cover
    """The preview's share of one step of one plane, added to the LQG's command sum
    ``S = K·[z; y; q]`` (:func:`agents.controllers.lqr.lqg_command`) for every row i:
    ``S_a += α·Σ_{j=1..N} G_j,a·(ρ̃(k − N + j) − ρ̃(k − N))`` (module docstring).

    ``pg = (pure, tail)`` (:class:`PreviewGains`); ``E``: :func:`preview_map`;
    ``geo = (d1 [m], dt [s], α)``; ``line = (buf, count, step)``: ``buf`` (L, 4, rows) the
    delay line of the front units' ρ̃ = (h, ṙ̂) of FL, FR, one ring for every row, written at
    slot ``step[0] mod L`` (the batch's step count); ``count`` (rows,) the steps since each
    row's reset (a row reads only what it wrote since); ``Pv`` (4, rows), ``P`` (4, rows),
    ``Nrow`` (rows,): scratch.

    The rows' sums run side by side (rows innermost: vector instructions across rows), each
    row's four commands' sums in the order of a row alone (j, then the signal): bit for bit
    the sums of one row at a time. A batch whose rows have several delays N (from their own
    speeds) runs the side-by-side sums once per delay, each added to the rows of that delay."""
    buf, count, step = line
    pure, tail = pg
    d1, dt, alpha = geo[0], geo[1], geo[2]
    n_rows = obs.shape[0]
    H = pure.shape[0]
    L = buf.shape[0]
    ns = buf.shape[1]
    accumulate_rows(E, W[: E.shape[1]], Pv)
    g_step = step[0]
    step[0] = g_step + 1
    slot = g_step % L
    for c in range(ns):
        for i in range(n_rows):
            buf[slot, c, i] = Pv[c, i]
    for i in range(n_rows):
        k = count[i]
        count[i] = k + 1
        Nrow[i] = 0
        v = np.float64(obs[i, speed_src]) * SPEED_SCALE_M_S
        steps = d1 / (v * dt) if v > 0.0 else math.inf
        if not (steps >= 0.5 and steps < H + 0.5):
            continue
        N = int(steps + 0.5)
        if k < N:  # the delay line does not reach back to the rear units' position yet
            continue
        Nrow[i] = N
    for i in range(n_rows):  # every delay once (at its first row)
        N = Nrow[i]
        if N == 0:
            continue
        first = True
        for j in range(i):
            if Nrow[j] == N:
                first = False
                break
        if first:
            _preview_rows(pure, tail, buf, (g_step - N) % L, N, alpha, Nrow, P, S)


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def _preview_rows(pure, tail, buf, base, N, alpha, Nrow, P, S):  # pragma: no cover
    """:func:`preview_add`'s sums for every row at delay ``N`` (``base``: the ring's slot of
    ρ̃(k − N)), added to the rows whose delay is ``N``."""
    nu = S.shape[0]
    L, ns, n_rows = buf.shape
    a = 0
    while a < nu:
        w = min(SIDE_BY_SIDE, nu - a)  # commands' sums side by side, each in its own order
        for r in range(w):
            for i in range(n_rows):
                P[r, i] = 0.0
        sl = base
        for j in range(1, N + 1):
            sl = sl + 1 if sl + 1 < L else 0  # (k − N + j) mod L
            g = pure[j] if j < N else tail[N]
            for c in range(ns):
                b0 = buf[base, c]
                bj = buf[sl, c]
                if w == SIDE_BY_SIDE:
                    g0, g1, g2, g3 = g[a, c], g[a + 1, c], g[a + 2, c], g[a + 3, c]
                    for i in range(n_rows):
                        d = bj[i] - b0[i]
                        P[0, i] += g0 * d
                        P[1, i] += g1 * d
                        P[2, i] += g2 * d
                        P[3, i] += g3 * d
                else:
                    for r in range(w):
                        gr = g[a + r, c]
                        for i in range(n_rows):
                            P[r, i] += gr * (bj[i] - b0[i])
        for r in range(w):
            for i in range(n_rows):
                if Nrow[i] == N:
                    S[a + r, i] += alpha * P[r, i]
        a += w


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def preview_lqg_step(
    obs, lq, pg, E, W, Z, S, speed_src, geo, line, Pv, P, Nrow, out, col0
):  # pragma: no cover - compiled
    """One step of one plane's preview LQG for every row of ``obs``: the LQR's law
    (:func:`agents.controllers.lqr.lqg_step`, its halves :func:`~agents.controllers.lqr.
    lqg_command` and :func:`~agents.controllers.lqr.lqg_update`, the same operations in the
    same order: bit-identical where no preview is active) with :func:`preview_add` in
    between. ``lq = (src, scale, K, F, scal)``."""
    src, scale, K, F, scal = lq
    lqg_command(obs, src, scale, K, W, S)
    preview_add(obs, pg, E, W, S, speed_src, geo, line, Pv, P, Nrow)
    lqg_update(F, scal, W, Z, S, out, col0)


class _PreviewPlane:
    """The running preview LQG of one plane for N rows: the constants of the LQR's plane
    (``plane``), the preview ``gains`` and map, the rows' filter, integrator and delay-line
    states."""

    def __init__(
        self, plane: _PlaneLQG, gains: PreviewGains, speed_src: int, geo: tuple[float, ...]
    ) -> None:
        self.plane, self.gains = plane, gains
        self.E = aligned_copy(preview_map(plane, gains))
        self.speed_src = int(speed_src)
        self.geo = np.array(geo, dtype=np.float64)
        self.pg = (aligned_copy(gains.pure), aligned_copy(gains.tail))
        self._entries: dict[type, Any] = {}  # preview_lqg_step by the observation's dtype
        self._new(0)

    def _new(self, n: int) -> None:
        self.lqg = self.plane._new_state(n)  # (W, Z, S)
        # on cache lines (hyperloop_env.physics.arrays); a slot's rows contiguous
        self.buf = aligned_zeros((self.gains.horizon + 1, N_SIGNALS, n))
        self.count = np.zeros(n, dtype=np.int64)
        self.step = np.zeros(1, dtype=np.int64)
        self.Pv = aligned_zeros((N_SIGNALS, n))
        self.P = aligned_zeros((SIDE_BY_SIDE, n))
        self.Nrow = np.zeros(n, dtype=np.int64)

    def reset_batch(self, mask: np.ndarray) -> None:
        """Zero the rows where ``mask`` is True (a new size starts a fresh batch)."""
        m = np.asarray(mask, dtype=bool)
        if self.count.shape[0] != m.shape[0]:
            self._new(m.shape[0])
            return
        self.lqg[0][:, m] = 0.0
        self.count[m] = 0

    def step_batch(self, obs: np.ndarray, out: np.ndarray, col0: int) -> None:
        """One control step of every row; the commands go to ``out[:, col0 : col0 + NU]``."""
        if self.count.shape[0] != obs.shape[0]:
            self.reset_batch(np.ones(obs.shape[0], dtype=bool))
        W, Z, S = self.lqg
        f = self._entries.get(obs.dtype.type) or self._bind(obs.dtype)
        f(  # = preview_lqg_step(obs, …)
            obs,
            self.plane._const,
            self.pg,
            self.E,
            W,
            Z,
            S,
            self.speed_src,
            self.geo,
            (self.buf, self.count, self.step),
            self.Pv,
            self.P,
            self.Nrow,
            out,
            col0,
        )

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "_entries": {}}  # compiled entries: bound anew

    def _bind(self, dt: np.dtype) -> Any:
        """:func:`preview_lqg_step` for observations of dtype ``dt`` (float32 or float64, two
        dimensions, any layout) and this plane's own arrays (their types fixed here), called
        without numba's type dispatch (:mod:`hyperloop_env.physics.entry`)."""
        W, Z, S = self.lqg
        f = compiled_entry(
            preview_lqg_step,
            strided(dt, 2),
            self.plane._const,
            self.pg,
            self.E,
            W,
            Z,
            S,
            self.speed_src,
            self.geo,
            (self.buf, self.count, self.step),
            self.Pv,
            self.P,
            self.Nrow,
            nb.float32[:, ::1],
            nb.int64,
        )
        self._entries[dt.type] = f
        return f


def check_preview_weight(weight: Any) -> None:
    """``ValueError`` naming ``preview_weight`` unless it is a number in [0, 2] (α)."""
    if not (isinstance(weight, int | float) and not isinstance(weight, bool) and 0 <= weight <= 2):
        raise ValueError(f"preview_weight must be a number in [0, 2], got {weight!r}")


class LQRPreviewController(LQRController):
    """LQG (:class:`~agents.controllers.lqr.LQRController`) with a finite-preview LQR
    feed-forward of the guideway the front units measured to the rear units, per plane
    (levitation; with guidance actuated also the guidance pairs). See the module
    docstring for the equations, units and sources.

    ``max_preview_s`` [s]: the longest preview (the delay line's length H·dt; the rear
    units get none while the set spacing takes longer than that to travel); 0 gives the
    plain LQR law. ``preview_weight``: α, the weight of the front units' measured change
    (0 gives the plain LQR law). ``act`` and ``act_batch`` run the same compiled law
    (:func:`preview_lqg_step`) on separate states (one row for ``act``)."""

    name = "lqr-preview"

    def __init__(
        self,
        env_or_params: Any = None,
        design: LQRDesign | None = None,
        action_scale: float | None = None,
        lateral_design: LateralLQRDesign | None = None,
        max_preview_s: float = MAX_PREVIEW_S,
        preview_weight: float = PREVIEW_WEIGHT,
    ) -> None:
        if not (isinstance(max_preview_s, int | float) and 0.0 <= max_preview_s <= 10.0):
            raise ValueError(f"max_preview_s must be a number in [0, 10] s, got {max_preview_s!r}")
        check_preview_weight(preview_weight)
        super().__init__(env_or_params, design, action_scale, lateral_design)
        ctx = self.ctx
        horizon = int(round(max_preview_s / ctx.dt_s))
        self.max_preview_s = float(max_preview_s)
        mats = [self.matrices] + ([self.lateral_matrices] if self.lateral is not None else [])
        self.gains = tuple(preview_gains(m, horizon) for m in mats)
        speed = ctx.observation.start("speed")
        p = ctx.params
        geo = (p.vehicle.set_spacing_m, ctx.dt_s, float(preview_weight))
        self._cols = tuple(c for _, c in self._planes)
        pairs = list(zip((pl for pl, _ in self._planes), self.gains, strict=True))
        self._batch = tuple(_PreviewPlane(pl, g, speed, geo) for pl, g in pairs)
        self._single = tuple(_PreviewPlane(pl, g, speed, geo) for pl, g in pairs)
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Start an episode (the state of :meth:`act`)."""
        super().reset(seed)
        for p in getattr(self, "_single", ()):
            p.reset_batch(np.ones(1, dtype=bool))

    def reset_batch(self, mask: np.ndarray) -> None:
        """Reset the filter, integrator and delay line of the rows where ``mask`` is True
        (the state of :meth:`act_batch`; a new mask size starts a fresh batch)."""
        for p in self._batch:
            p.reset_batch(mask)

    def _run(self, planes: tuple[_PreviewPlane, ...], o: np.ndarray) -> np.ndarray:
        out = np.zeros((o.shape[0], self._n_act), dtype=np.float32)
        for p, col in zip(planes, self._cols, strict=True):
            p.step_batch(o, out, col)
        return out

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        """Actions for N independent vehicles, ``(N, obs_size) -> (N, n_act)`` float32."""
        return self._run(self._batch, self._obs2d(obs, 2))

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The action for one vehicle, ``(obs_size,) -> (n_act,)`` float32 (its own state,
        apart from :meth:`act_batch`'s)."""
        return self._run(self._single, self._obs2d(obs, 1)[None, :])[0]


def preview_problem(
    m: LQGMatrices, steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The LQR problem ``m`` carries (scaled ξ̃ = [x, q] / sa, :func:`agents.controllers.lqr.
    _design_plane`) augmented by a known future of the rear track over ``steps`` steps, for
    a predictive controller (:class:`agents.controllers.mpc.MPCController`'s preview).

    The exosystem of the module docstring (ρ_rear(k + j) = Φ_ρ^j ρ̂_rear(k) + Δ_j, the model
    beyond ``steps``) written as injections into the rear track states::

        ρ_{j+1} = Φ_ρ ρ_j + w_j,   w_j = Δ_{j+1} − Φ_ρ Δ_j   (Δ_0 = 0),  j = 0 … steps − 1

    State ξ̃_a = [ξ̃; w̃_0; …; w̃_{steps−1}] (w̃ = w / s_ρ, the rear track states' scales);
    ``ξ̃_a⁺ = P ξ̃_a + G u`` with ρ̃⁺ += w̃_0 and the w̃ shifted forward (zero enters: beyond
    the preview the model's prediction); the stage cost is the LQR's on ξ̃ (none on w̃).
    Returns (P, G, Q, S, sa): S the Riccati solution of the augmented problem (its ξ̃ block
    is the LQR's, checked; the first move of its gain is the finite-preview law of this
    module), ``sa`` the scales of ξ_a."""
    if m.St is None or m.Pt is None or m.Gt is None or m.Qt is None or m.R is None:
        raise ValueError("the LQG design carries no LQR problem (LQGMatrices.Pt … St)")
    if not (isinstance(steps, int) and steps >= 1):
        raise ValueError(f"steps must be an int >= 1, got {steps!r}")
    n = m.Phi.shape[0]
    na = m.Pt.shape[0]
    rho = _track_cols(n, REAR_UNITS)
    nr = len(rho)
    nd = nr * steps
    P = np.zeros((na + nd, na + nd))
    P[:na, :na] = m.Pt
    P[rho, na : na + nr] = np.eye(nr)  # ρ̃⁺ += w̃_0 (same scales)
    P[na : na + nd - nr, na + nr :] = np.eye(nd - nr)  # the injections move forward
    G = np.vstack([m.Gt, np.zeros((nd, m.Gt.shape[1]))])
    Q = np.zeros_like(P)
    Q[:na, :na] = m.Qt
    S = _dare(P, G, Q, m.R)
    if not np.allclose(S[:na, :na], m.St, rtol=1e-6, atol=1e-9 * np.abs(m.St).max()):
        raise RuntimeError("the augmented Riccati solution's ξ block is not the LQR's")
    sa = np.concatenate([m.sa, np.tile(m.sa[rho], steps)])
    return P, G, Q, S, sa
