"""Constrained linear MPC of the levitation currents, solved with DAQP (a dual active-set QP
solver for embedded MPC: Arnström, Bemporad, Axehill, IEEE TAC 2022).

Model, estimator and weights are the LQG's (:mod:`agents.controllers.lqr`): the vertical
plane's design model with the coil lag and the track-disturbance states, the gap integral
``q`` (``q_{k+1} = q_k + dt·s_k``), the steady-state Kalman filter on the measured gaps,
currents and heave acceleration, the Bryson weights. Every control step (dt = 1 ms) it
solves, for the filtered state ξ₀ = [x̂, q] (design coordinates scaled by the LQR's state
scales, ``LQGMatrices.sa``), over a horizon of N steps (``MPCDesign.horizon_ms``)::

    minimise   Σ_{k<N} (ξ_kᵀ Q ξ_k + u_kᵀ R u_k) + ξ_Nᵀ S ξ_N + Σ_a (ρ₁ ε_a + ρ₂ ε_a²)
    subject to ξ_{k+1} = Φ ξ_k + Γ u_k                     (the design model, ZOH)
               u_min ≤ u_k ≤ u_max                        coil current in [0, I_max] [A]
               |u_k − u_{k−1}| ≤ Δu_max                    current rate (u_{−1}: the last command)
               |s_{a,k}| ≤ s_max + ε_a,  ε_a ≥ 0               the gap inside the soft limit,
                                                     k every ``gap_check_ms`` (5, 10, 15, 20 ms)

with u the coil-current deviation from I0 [A], s the gap excursion [m], ε [mm] the
violation of the soft gap limit per unit, and S the LQR's Riccati solution as the terminal
cost. The gap limit is imposed every ``gap_check_ms`` rather than at every step: in the first
milliseconds the currents cannot move the gap (a limit at every step made the QP degenerate).
Consequence (Bellman): when no constraint is active, the first move equals the LQR's command
``−K·ξ₀`` — the MPC is the LQR plus the constraints (a test checks it).

Solution: the QP is condensed (the inputs and slacks are the variables, 4·N + 4: dense and
small, the case an active-set method is made for); the unconstrained optimum ``U* = −L·ξ₀``
and its predicted gaps are computed for every row of the batch in one compiled product; a
row whose U* satisfies every constraint takes it (it is then the QP's exact solution,
ε = 0), the others are solved by DAQP (its workspace and the factorisation of the Hessian
set up once; every solve warm-started from the row's own previous active set, none after a
reset — so that a QP's solution is a function of the QP and the row's history alone:
``act_batch`` row i equals a single controller fed row i, bit for bit). A solve that ends
with another exit flag than 1 (optimal) uses DAQP's last iterate, clipped to the current
limits, and is counted in :attr:`MPCController.stats`. The filter's time update uses the
command actually sent. Rows the rollout engine has left idle (``idle_batch``: their commands
are ignored until their next reset) take the unconstrained optimum without a QP. (OSQP
was tried first; this dense, small QP is the case an active-set method is made for:
``speed/bench_mpc.py`` prints DAQP's time and iterations.)

With ``actuators="levitation+guidance"`` the guidance pairs are driven by the LQG of the
lateral plane (:class:`~agents.controllers.lqr.LateralLQRDesign`), as ``lqr`` does.

**Preview** (``preview_weight`` = α > 0; registered as ``mpc-preview`` with α =
:data:`~agents.controllers.lqr_preview.PREVIEW_WEIGHT`): the rear units' guideway ahead as
``lqr-preview`` takes it (:mod:`agents.controllers.lqr_preview`: the model's prediction plus
α × the change the front units measured one set spacing earlier) enters the prediction as
a known input: ξ̃ is augmented by the injections ``w_j = Δ_{j+1} − Φ_ρ Δ_j`` into the rear
track states over the N_p = round(d1 / (v₀·dt)) steps of the nominal speed v₀ (58 at
1000 km/h, 29 at 2000 km/h), and S is the augmented problem's Riccati solution
(:func:`~agents.controllers.lqr_preview.preview_problem`), so the terminal cost values the
preview beyond the 20 ms horizon too. Consequence: with no constraint active the first move
is ``lqr-preview``'s command (a test checks it, and the closed loops to 1e-5), the gap
limits are checked against the previewed track, and α = 0 is the plain MPC bit for bit. The
delay at the measured speed N is used per row: shorter than N_p, the model takes over from
N on; longer, the first N_p changes are used. The QP keeps its size (the inputs and
slacks); only the products with ξ̃ grow (30 → 262 states at 1000 km/h).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numba as nb
import numpy as np

from agents.controllers.lqr import (
    NU,
    LateralLQRDesign,
    LQRController,
    LQRDesign,
    accumulate_rows,
    lqg_step,
)
from agents.controllers.lqr_preview import (
    MAX_PREVIEW_S,
    N_SIGNALS,
    check_preview_weight,
    front_signal_map,
    preview_gains,
    preview_problem,
)
from hyperloop_env.observation import SPEED_SCALE_M_S
from hyperloop_env.physics.arrays import aligned_copy, aligned_zeros


@dataclass(frozen=True)
class MPCDesign:
    """The MPC's horizon, limits and solver settings (module docstring); ``lqr``: the
    model, filter and weights it shares with the LQG."""

    horizon_ms: float = 20.0
    gap_limit_fraction: float = 0.75  # soft limit s_max = 0.75 · clearance (6 mm of 8 mm)
    gap_check_ms: float = 5.0  # the soft limit is imposed every 5 ms of the horizon
    max_rate_A_per_ms: float = 20.0  # Δu_max per 1 ms step [A]
    slack_linear: float = 1e3  # ρ₁ per mm of violation (an exact penalty)
    slack_quadratic: float = 1e2  # ρ₂ per mm²
    max_iter: int = 1000  # DAQP's iteration limit (active-set changes)
    lqr: LQRDesign = field(default_factory=LQRDesign)

    def __post_init__(self) -> None:
        for name in (
            "horizon_ms",
            "gap_check_ms",
            "max_rate_A_per_ms",
            "slack_linear",
            "slack_quadratic",
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"MPCDesign.{name} must be a finite number, got {v!r}")
            if v <= 0:
                raise ValueError(f"MPCDesign.{name} must be > 0, got {v!r}")
        f = self.gap_limit_fraction
        if isinstance(f, bool) or not isinstance(f, int | float) or not 0.0 < f <= 1.0:
            raise ValueError(f"MPCDesign.gap_limit_fraction must be in (0, 1], got {f!r}")
        if isinstance(self.max_iter, bool) or not isinstance(self.max_iter, int):
            raise ValueError(f"MPCDesign.max_iter must be an int, got {self.max_iter!r}")
        if self.max_iter < 1:
            raise ValueError(f"MPCDesign.max_iter must be >= 1, got {self.max_iter!r}")
        if not isinstance(self.lqr, LQRDesign):
            raise ValueError(f"MPCDesign.lqr must be an LQRDesign, got {self.lqr!r}")


# -- the compiled parts of a step (the same operations in the same order as NumPy's) ---------
@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def measurement_update(o, src, scale, C, M, X, Y, inn, Xu):  # pragma: no cover - compiled
    """``Y = o[:, src]·scale`` (non-finite → 0, a missing source 0) (ny, B), the innovation
    ``inn = Y − C·X̂⁻`` and the updated estimate ``Xu = M·inn + X̂⁻`` (n, B)."""
    B = o.shape[0]
    for k in range(src.shape[0]):
        c = src[k]
        for i in range(B):
            v = np.float64(o[i, c]) * scale[k] if c >= 0 else 0.0
            Y[k, i] = v if math.isfinite(v) else 0.0
    accumulate_rows(C, X, inn)
    for k in range(inn.shape[0]):
        for i in range(B):
            inn[k, i] = Y[k, i] - inn[k, i]
    accumulate_rows(M, inn, Xu)
    for k in range(Xu.shape[0]):
        for i in range(B):
            Xu[k, i] = Xu[k, i] + X[k, i]


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def scaled_state(Xu, Q, inv_sa, xi):  # pragma: no cover - compiled
    """``xi = [Xu; Q]·inv_sa`` (row-wise): the scaled ξ̃0 without preview."""
    n = Xu.shape[0]
    for k in range(n):
        for i in range(Xu.shape[1]):
            xi[k, i] = Xu[k, i] * inv_sa[k]
    for k in range(Q.shape[0]):
        for i in range(Q.shape[1]):
            xi[n + k, i] = Q[k, i] * inv_sa[n + k]


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def estimate(o, src, scale, C, M, X, Y, inn, Xu, Q, inv_sa, xi):  # pragma: no cover
    """The first part of a step without preview in one call: :func:`measurement_update`,
    then :func:`scaled_state`."""
    measurement_update(o, src, scale, C, M, X, Y, inn, Xu)
    scaled_state(Xu, Q, inv_sa, xi)


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def unconstrained(LW, xi, nu, lims, U, idle, Z, ok, U0, bad):  # pragma: no cover - compiled
    """``Z = LW·xi`` (the unconstrained optimum U* over the horizon, then its checked gaps),
    ``U0 = Z[:NU]`` (every row's first move), ``ok[i]``: row i's U* keeps every limit
    (``lims = (s_max, u_lo − tol, u_hi + tol, Δu + tol)``: |gap| ≤ s_max, u_lo − tol ≤ U ≤
    u_hi + tol, |u_0 − u_−1| and every |u_k+1 − u_k| ≤ Δu + tol; NaN fails), and in
    ``bad[:n]`` the n rows, returned, whose U* breaks a limit and that are not ``idle``
    (they need a QP). The checks run limit by limit over the rows (vectorised); each is
    a comparison, so the order does not change ``ok``."""
    accumulate_rows(LW, xi, Z)
    s_max, lo, hi, du = lims[0], lims[1], lims[2], lims[3]
    n_u = U.shape[0]
    B = xi.shape[1]
    for i in range(B):
        ok[i] = True
    for r in range(nu, Z.shape[0]):
        z = Z[r]
        for i in range(B):
            ok[i] = ok[i] & (abs(z[i]) <= s_max)
    for r in range(nu):
        z = Z[r]
        for i in range(B):
            ok[i] = ok[i] & (z[i] >= lo) & (z[i] <= hi)
    for u in range(n_u):
        z = Z[u]
        p = U[u]
        for i in range(B):
            ok[i] = ok[i] & (abs(z[i] - p[i]) <= du)
    for r in range(n_u, nu):
        z = Z[r]
        p = Z[r - n_u]
        for i in range(B):
            ok[i] = ok[i] & (abs(z[i] - p[i]) <= du)
    for u in range(n_u):
        for i in range(B):
            U0[u, i] = Z[u, i]
    n_bad = 0
    for i in range(B):
        if not (ok[i] or idle[i]):
            bad[n_bad] = i
            n_bad += 1
    return n_bad


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def time_update(U0, u_lo, u_hi, Q, Y, dt, qmax, Phi, Xu, X, Gam, T, U):  # pragma: no cover
    """The command clipped to the current limits, the clamped gap integral
    ``Q = clip(Q + dt·Y[:NU], ±qmax)``, the predicted estimate ``X̂⁻ = Φ·Xu + Γ·U0`` and
    ``U = U0``."""
    for u in range(U0.shape[0]):
        for i in range(U0.shape[1]):
            v = U0[u, i]
            v = u_lo if v < u_lo else v
            U0[u, i] = u_hi if v > u_hi else v
            q = Q[u, i] + dt * Y[u, i]
            q = -qmax if q < -qmax else q
            Q[u, i] = qmax if q > qmax else q
    accumulate_rows(Phi, Xu, X)
    accumulate_rows(Gam, U0, T)
    for k in range(X.shape[0]):
        for i in range(X.shape[1]):
            X[k, i] = X[k, i] + T[k, i]
    for u in range(U.shape[0]):
        for i in range(U.shape[1]):
            U[u, i] = U0[u, i]


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def finish(
    U0, u_lo, u_hi, Q, Y, dt, qmax, Phi, Xu, X, Gam, T, U, act, out, col0
):  # pragma: no cover
    """The last part of a step in one call: :func:`time_update`, then the actions
    ``out[i, col0 + u] = float32(clip(a·U0[u, i], lo, hi))`` (``act = (a, lo, hi)``; the
    clip as NumPy's ``np.clip`` does it: x unless a bound lies strictly beyond it, so NaN
    stays NaN and −0 at a zero bound stays −0)."""
    time_update(U0, u_lo, u_hi, Q, Y, dt, qmax, Phi, Xu, X, Gam, T, U)
    a, lo, hi = act[0], act[1], act[2]
    for u in range(U0.shape[0]):
        for i in range(U0.shape[1]):
            v = a * U0[u, i]
            v = lo if v < lo else v
            out[i, col0 + u] = hi if v > hi else v


class _State:
    """One batch's running state (columns are the rows of the batch): the predicted
    estimate x̂⁻ (n, B), the gap integral q (NU, B) [m·s], the last command (NU, B) [A],
    and each row's last QP solution (B, nz) and its active set (B, nc) for the warm start.
    The arrays the compiled steps stream through start on a cache line
    (:func:`~hyperloop_env.physics.arrays.aligned_zeros`)."""

    def __init__(self, n: int, nz: int, nc: int, rows: int, delay: int = 0) -> None:
        self.X = aligned_zeros((n, rows))
        self.Q = aligned_zeros((NU, rows))
        self.U = aligned_zeros((NU, rows))
        self.ws_x = np.zeros((rows, nz))  # the last solution
        self.sense = np.zeros((rows, nc), dtype=np.int32)  # its active set (DAQP's flags)
        # the preview's delay line of the front units' (h, ṙ̂) and the steps since reset
        self.buf = np.zeros((delay, N_SIGNALS, rows))
        self.count = np.zeros(rows, dtype=np.int64)
        self.idle = np.zeros(rows, dtype=bool)  # rows whose commands the caller ignores
        self.n_idle = 0

    @property
    def rows(self) -> int:
        return self.X.shape[1]

    def zero(self, mask: np.ndarray) -> None:
        for a in (self.X, self.Q, self.U):
            a[:, mask] = 0.0
        self.ws_x[mask] = 0.0
        self.sense[mask] = 0
        self.count[mask] = 0
        self.idle[mask] = False
        self.n_idle = int(np.count_nonzero(self.idle))


class _Scratch:
    """The buffers of one step for B rows (aligned like :class:`_State`'s): measurements,
    innovation, updated estimate, scaled state, the unconstrained optimum and its checks,
    the first moves, the rows that need a QP and the time update's product."""

    def __init__(self, n_meas: int, n: int, na: int, nz_rows: int, rows: int) -> None:
        self.Y = aligned_zeros((n_meas, rows))
        self.inn = aligned_zeros((n_meas, rows))
        self.Xu = aligned_zeros((n, rows))
        self.xi = aligned_zeros((na, rows))
        self.Z = aligned_zeros((nz_rows, rows))
        self.ok = aligned_zeros(rows, np.bool_)
        self.U0 = aligned_zeros((NU, rows))
        self.bad = aligned_zeros(rows, np.int64)
        self.T = aligned_zeros((n, rows))


def _condensed(
    Pt: np.ndarray, Gt: np.ndarray, Qt: np.ndarray, R: np.ndarray, St: np.ndarray, N: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The prediction over N steps condensed onto the inputs: ``Sx``, ``Su`` with
    ξ̃_k = Pt^k ξ̃0 + Σ_j Pt^{k−1−j} Gt u_j (k = 1..N, stacked), and the cost's
    ``H = Suᵀ Q̄ Su + I⊗R`` (symmetrised) and ``F = Suᵀ Q̄ Sx`` (Q̄: Qt per step, St at the
    end)."""
    na = Pt.shape[0]
    nu = N * NU
    # condensed prediction ξ̃_k = Pt^k ξ̃0 + Σ_j Pt^{k−1−j} Gt u_j, k = 1..N
    Sx = np.zeros((N * na, na))
    Su = np.zeros((N * na, nu))
    pk = np.eye(na)
    for k in range(N):
        pk = Pt @ pk
        Sx[k * na : (k + 1) * na] = pk
    blocks = [Gt]
    for _ in range(1, N):
        blocks.append(Pt @ blocks[-1])
    for k in range(N):
        for j in range(k + 1):
            Su[k * na : (k + 1) * na, j * NU : (j + 1) * NU] = blocks[k - j]
    Qbar = np.zeros((N * na, N * na))
    for k in range(N - 1):
        Qbar[k * na : (k + 1) * na, k * na : (k + 1) * na] = Qt
    Qbar[(N - 1) * na :, (N - 1) * na :] = St
    H = Su.T @ Qbar @ Su + np.kron(np.eye(N), R)
    H = 0.5 * (H + H.T)
    F = Su.T @ Qbar @ Sx  # q = 2·F·ξ̃0 (the QP's ½zᵀPz + qᵀz has P = 2H)
    return Sx, Su, H, F


class MPCController(LQRController):
    """Constrained linear MPC of the levitation currents on the LQG's model and filter
    (module docstring); ``design``: :class:`MPCDesign`."""

    name = "mpc"

    def __init__(
        self,
        env_or_params: Any = None,
        design: MPCDesign | None = None,
        action_scale: float | None = None,
        lateral_design: LateralLQRDesign | None = None,
        preview_weight: float = 0.0,
    ) -> None:
        d = design if design is not None else MPCDesign()
        if not isinstance(d, MPCDesign):
            raise TypeError(f"design must be an MPCDesign, got {type(d).__name__}")
        check_preview_weight(preview_weight)
        super().__init__(env_or_params, d.lqr, action_scale, lateral_design)
        import daqp  # a dependency of the package; imported when an MPC is built

        self.mpc_design = d
        m = self.matrices
        ctx = self.ctx
        N = max(1, round(d.horizon_ms * 1e-3 / ctx.dt_s))
        self.horizon_steps = N
        vp = self.vertical
        self._a = vp.a_per_A
        self._u_lo, self._u_hi = vp.lo / vp.a_per_A, vp.hi / vp.a_per_A  # [A]
        self._du = d.max_rate_A_per_ms * ctx.dt_s * 1e3  # per step [A]
        self._s_max = d.gap_limit_fraction * ctx.clearance_m
        tol = 1e-12  # the unconstrained optimum's limits (:func:`unconstrained`)
        self._lims = np.array(
            [self._s_max, self._u_lo - tol, self._u_hi + tol, self._du + tol], dtype=np.float64
        )
        Pt, Gt, Qt, R, St, sa = m.Pt, m.Gt, m.Qt, m.R, m.St, m.sa
        self._setup_preview(float(preview_weight))
        if self.preview_steps:  # the problem augmented by the rear track's known future
            Pt, Gt, Qt, St, sa = preview_problem(m, self.preview_steps)
        H, F, Gsu, n_checked = self._setup_prediction(N, Pt, Gt, Qt, R, St, sa)
        self._setup_qp(daqp, H, F, Gsu, n_checked)
        self.stats = {
            "steps": 0,
            "rows": 0,
            "qp_solves": 0,
            "qp_iterations": 0,
            "qp_unsolved": 0,
            "idle_rows": 0,
        }
        """Counts: control steps, vehicle-steps, QPs solved by DAQP, their iterations in
        all, the QPs that did not end optimal (exit flag 1), and the vehicle-steps of idle
        rows (``idle_batch``; no QP)."""
        self._batch_state = _State(self._n, self._nz, self._nc, 0, self._delay)
        self._single_state = _State(self._n, self._nz, self._nc, 1, self._delay)
        self._scratch: dict[int, _Scratch] = {}  # per batch size
        # the compiled steps' constants, on cache lines (:mod:`hyperloop_env.physics.arrays`)
        self._est = tuple(aligned_copy(a) for a in (vp.src, vp.scale, vp.C, vp.M))
        self._upd = tuple(aligned_copy(a) for a in (vp.Phi, vp.Gam))
        self._act_lims = np.array([vp.a_per_A, vp.lo, vp.hi], dtype=np.float64)

    def _setup_prediction(
        self,
        N: int,
        Pt: np.ndarray,
        Gt: np.ndarray,
        Qt: np.ndarray,
        R: np.ndarray,
        St: np.ndarray,
        sa: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """The condensed prediction over the horizon of N steps: the unconstrained optimum
        U* = −L·ξ̃0 and its predicted gaps at the checked steps in one product (``_LW``).
        Returns the QP's H and F (module docstring), the checked gaps' response to U and the
        number of checked steps."""
        m = self.matrices
        d = self.mpc_design
        na = Pt.shape[0]
        n = m.Phi.shape[0]
        nu = N * NU
        Sx, Su, H, F = _condensed(Pt, Gt, Qt, R, St, N)
        L = np.linalg.solve(H, F)  # U* = −L·ξ̃0
        # predicted gaps s_{a,k} (k = 1..N): C̃s ξ̃_k, C̃s the gap rows in scaled coordinates
        Cs = np.zeros((NU, na))
        Cs[:, :n] = m.C_s * sa[None, :n]
        every = min(N, max(1, round(d.gap_check_ms * 1e-3 / self.ctx.dt_s)))
        checked = np.arange(N - 1, -1, -every)[::-1]  # horizon steps k+1 with a gap limit
        self.gap_check_steps = tuple(int(k) + 1 for k in checked)
        pick = np.zeros((len(checked), N))
        pick[np.arange(len(checked)), checked] = 1.0
        Gsx = np.kron(pick, Cs) @ Sx
        Gsu = np.kron(pick, Cs) @ Su
        ng = Gsx.shape[0]
        self._first_move = -L[:NU]  # (NU, na): the LQR gain in scaled coordinates (a test)
        # unconstrained optimum and its gaps in one product: [U*; s] = LW·ξ̃0
        self._LW = aligned_copy(np.vstack([-L, Gsx - Gsu @ L]))
        self._inv_sa = aligned_copy(1.0 / sa)
        self._n, self._na, self._nu, self._ng = n, na, nu, ng
        self._Gsx = Gsx
        return H, F, Gsu, len(checked)

    def _setup_qp(
        self, daqp: Any, H: np.ndarray, F: np.ndarray, Gsu: np.ndarray, n_checked: int
    ) -> None:
        """The QP (module docstring) set up once in DAQP, with the constant parts of its
        bounds and the buffers :meth:`_solve` writes its vectors to."""
        d = self.mpc_design
        nu, ng = self._nu, self._ng
        # the QP: z = [U (nu); ε (NU) in mm]; simple bounds on z (current limits, ε ≥ 0),
        # general rows: the current rate, then the gap limit from above and from below
        nz = nu + NU
        Hq = np.zeros((nz, nz))
        Hq[:nu, :nu] = 2.0 * H
        Hq[nu:, nu:] = 2.0 * d.slack_quadratic * np.eye(NU)
        self._qF = 2.0 * F  # (nu, na): f = [2F·ξ̃0; ρ₁] (½zᵀHq z + fᵀz)
        self._q_slack = np.full(NU, d.slack_linear)
        e_mm = np.kron(np.ones((n_checked, 1)), np.eye(NU))  # ε [mm], per unit
        D = np.eye(nu) - np.eye(nu, k=-NU)  # u_k − u_{k−1} (k = 0: u_0, u_{−1} in the bounds)
        self._Gsu_mm = 1e3 * Gsu  # the gaps' response to U [mm/A]
        A = np.vstack(
            [
                np.hstack([D, np.zeros((nu, NU))]),  # current rate
                np.hstack([self._Gsu_mm, -e_mm]),  # s − ε ≤ s_max  (rows in mm)
                np.hstack([self._Gsu_mm, e_mm]),  # s + ε ≥ −s_max
            ]
        )
        big = 1e30  # DAQP's infinity
        self._hi_b = np.concatenate(
            [
                np.full(nu, self._u_hi),
                np.full(NU, big),
                np.full(nu, self._du),
                np.full(ng, 1e3 * self._s_max),
                np.full(ng, big),
            ]
        )
        self._lo_b = np.concatenate(
            [
                np.full(nu, self._u_lo),
                np.zeros(NU),
                np.full(nu, -self._du),
                np.full(ng, -big),
                np.full(ng, -1e3 * self._s_max),
            ]
        )
        nc = self._hi_b.size
        self._nz, self._nc = nz, nc
        self._r_rate = nz  # first rate row in the bounds (after the nz simple bounds)
        self._r_gap = nz + nu
        self._f = np.zeros(nz)  # _solve's buffers: the linear term, the bounds, the free gaps
        self._f[nu:] = self._q_slack
        self._lo, self._hi = self._lo_b.copy(), self._hi_b.copy()
        self._g0 = np.zeros(ng)
        self._qp = daqp.Model()
        self._qp.setup(Hq, np.zeros(nz), A, self._hi_b.copy(), self._lo_b.copy())
        self._qp.settings = {"iter_limit": d.max_iter}

    # -- state ------------------------------------------------------------------------------
    def reset(self, seed: int | None = None) -> None:
        super().reset(seed)
        if hasattr(self, "_single_state"):
            self._single_state.zero(np.ones(1, dtype=bool))

    def reset_batch(self, mask: np.ndarray) -> None:
        super().reset_batch(mask)
        m = np.asarray(mask, dtype=bool)
        st = self._batch_state
        if m.shape[0] != st.rows:
            self._batch_state = _State(self._n, self._nz, self._nc, m.shape[0], self._delay)
            return
        st.zero(m)

    def idle_batch(self, mask: np.ndarray) -> None:
        """Mark the batch rows whose commands the caller ignores until their next
        ``reset_batch`` (the rollout engine's idle rows, :mod:`agents.evaluation.engine`):
        they take the unconstrained optimum without a QP (finite, not the MPC's law). The
        other rows are unaffected, bit for bit (a test)."""
        m = np.asarray(mask)
        st = self._batch_state
        if m.dtype != np.bool_ or m.shape != (st.rows,):
            raise ValueError(
                f"idle_batch: mask must be a bool array of shape ({st.rows},), got "
                f"{m.dtype} {m.shape}"
            )
        st.idle[:] = m
        st.n_idle = int(np.count_nonzero(m))

    # -- the law ------------------------------------------------------------------------------
    def _buffers(self, rows: int) -> _Scratch:
        b = self._scratch.get(rows)
        if b is None:
            b = _Scratch(
                self.vertical.src.size, self._n, self._inv_sa.size, self._LW.shape[0], rows
            )
            self._scratch[rows] = b
        return b

    def _step(self, o: np.ndarray, st: _State, out: np.ndarray, col0: int) -> None:
        """One MPC step for the rows of ``o`` (B, obs_size): the commands, in action units,
        to ``out[:, col0:col0 + NU]``. The unconstrained parts run compiled
        (:func:`estimate`, :func:`unconstrained`, :func:`finish`); the QPs of the rows whose
        unconstrained optimum breaks a limit are solved here."""
        vp = self.vertical
        B = o.shape[0]
        b = self._buffers(B)
        src, scale, C, M = self._est
        if self.preview_steps:
            measurement_update(o, src, scale, C, M, st.X, b.Y, b.inn, b.Xu)
            parts = [b.Xu, st.Q, self._injections(o, b.Y, b.Xu, st)]
            xi = np.vstack(parts) * self._inv_sa[:, None]  # scaled ξ̃0 (na, B)
        else:
            xi = b.xi
            estimate(o, src, scale, C, M, st.X, b.Y, b.inn, b.Xu, st.Q, self._inv_sa, xi)
        U0 = b.U0
        n_bad = unconstrained(
            self._LW, xi, self._nu, self._lims, st.U, st.idle, b.Z, b.ok, U0, b.bad
        )
        # idle rows (``idle_batch``: their commands are ignored) take the unconstrained optimum
        for i in b.bad[:n_bad].tolist():  # a contiguous copy: one BLAS path for all
            U0[:, i] = self._solve(np.ascontiguousarray(xi[:, i]), st, i)
        Phi, Gam = self._upd
        finish(
            U0, self._u_lo, self._u_hi, st.Q, b.Y, vp.dt, vp.qmax, Phi, b.Xu, st.X, Gam, b.T,
            st.U, self._act_lims, out, col0,
        )  # fmt: skip
        stats = self.stats
        stats["steps"] += 1
        stats["rows"] += B
        stats["idle_rows"] += st.n_idle

    def _solve(self, xi: np.ndarray, st: _State, i: int) -> np.ndarray:
        """The QP of row ``i`` (ξ̃0 = ``xi``), warm-started from the row's previous active set
        (none after a reset); returns its first move (NU,) [A]."""
        nu, ng = self._nu, self._ng
        f, lo, hi = self._f, self._lo, self._hi  # buffers the QP's vectors are written to
        np.dot(self._qF, xi, out=f[:nu])  # f = [2F·ξ̃0; ρ₁]
        np.copyto(lo, self._lo_b)
        np.copyto(hi, self._hi_b)
        r = self._r_rate
        lo[r : r + NU] += st.U[:, i]  # u_0 − u_{−1} within ±Δu
        hi[r : r + NU] += st.U[:, i]
        g0 = self._g0
        np.dot(self._Gsx, xi, out=g0)
        g0 *= 1e3  # the gaps' free response [mm]
        r = self._r_gap
        hi[r : r + ng] -= g0
        lo[r + ng : r + 2 * ng] -= g0
        qp = self._qp
        qp.update(f=f, bupper=hi, blower=lo, sense=st.sense[i].copy())
        x, _, flag, info = qp.solve()
        self.stats["qp_solves"] += 1
        self.stats["qp_iterations"] += int(info["iterations"])
        self.last_status = int(flag)
        if flag != 1:
            self.stats["qp_unsolved"] += 1
        lam = info["lam"]
        sense = st.sense[i]  # DAQP's flags: 1 active, 3 active at the lower bound
        np.not_equal(lam, 0.0, out=sense, casting="unsafe")
        sense[lam < 0.0] = 3
        st.ws_x[i] = x
        return x[:NU]

    # -- the preview ------------------------------------------------------------------------
    def _setup_preview(self, weight: float) -> None:
        """The preview's constants (module docstring): ``preview_steps`` = the set spacing's
        delay at the nominal speed (0: no preview, the plain MPC), the delay line's length,
        the map from (x̂, y) to the front units' (h, ṙ̂) and the rear track's Φ_ρ."""
        ctx = self.ctx
        m = self.matrices
        self.preview_weight = weight
        self._d1 = ctx.params.vehicle.set_spacing_m
        horizon = int(round(MAX_PREVIEW_S / ctx.dt_s))
        v0 = ctx.params.condition.speed_kmh / 3.6
        steps = int(round(self._d1 / (v0 * ctx.dt_s)))
        self.preview_steps = steps if weight > 0.0 and 1 <= steps <= horizon else 0
        self._delay = horizon + 1 if self.preview_steps else 0
        if not self.preview_steps:
            return
        n = m.Phi.shape[0]
        g = preview_gains(m, 0)
        E = front_signal_map(m.C, g, np.hstack([np.eye(n), np.zeros((n, m.C.shape[0]))]))
        self._Ex, self._Ey = E[:, :n].copy(), E[:, n:].copy()  # ρ̃ = Ex·x̂ + Ey·y
        self._phi_rho = m.Phi[np.ix_(g.rear_cols, g.rear_cols)]
        self._speed_col = ctx.observation.start("speed")

    def _injections(self, o: np.ndarray, Y: np.ndarray, Xu: np.ndarray, st: _State) -> np.ndarray:
        """The rows' preview state (4·preview_steps, B) [m, m/s]: the front units' (h, ṙ̂) into
        the delay line, then w_j = Δ_{j+1} − Φ_ρ Δ_j with Δ_j = α·(ρ̃(k − N + j) − ρ̃(k − N)),
        N the delay at the row's measured speed (:func:`agents.controllers.lqr_preview.
        preview_problem`); zero where the row has no preview yet (or its delay is outside
        1 … H steps). A delay N shorter than ``preview_steps`` gives w_j = 0 from j = N on (the
        model beyond N), a longer one uses the first ``preview_steps`` changes."""
        B = o.shape[0]
        L = st.buf.shape[0]
        rows = np.arange(B)
        k = st.count.copy()
        st.buf[k % L, :, rows] = (self._Ex @ Xu + self._Ey @ Y).T
        st.count += 1
        v = o[:, self._speed_col].astype(np.float64) * SPEED_SCALE_M_S
        with np.errstate(divide="ignore", invalid="ignore"):
            steps = np.where(v > 0.0, self._d1 / (v * self.ctx.dt_s), np.inf)
        ok = (steps >= 0.5) & (steps < L - 0.5)
        N = np.where(ok, np.floor(steps + 0.5), 0).astype(np.int64)
        ok &= k >= N
        P = self.preview_steps
        W = np.zeros((P, B, N_SIGNALS))
        if ok.any():
            j = np.arange(1, P + 1)[:, None]  # Δ_1 … Δ_P
            live = ok[None, :] & (j <= N[None, :])  # (P, B)
            base = st.buf[(k - N) % L, :, rows]  # (B, 4): ρ̃(k − N)
            D = st.buf[(k - N + j) % L, :, rows[None, :]] - base[None]  # (P, B, 4)
            D *= self.preview_weight
            D[~live] = 0.0
            W[:] = D
            W[1:] -= D[:-1] @ self._phi_rho.T  # w_j = Δ_{j+1} − Φ_ρ Δ_j (Δ_0 = 0)
            W[~live] = 0.0
        return W.transpose(0, 2, 1).reshape(P * N_SIGNALS, B)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        """Actions for N independent vehicles, ``(N, obs_size) -> (N, n_act)`` float32."""
        o = self._obs2d(obs, 2)
        n = o.shape[0]
        if self._batch_state.rows != n:
            self.reset_batch(np.ones(n, dtype=bool))
        out = np.zeros((n, self._n_act), dtype=np.float32)
        self._step(o, self._batch_state, out, self._lev.start)
        lp = self.lateral
        if lp is not None:
            lqg_step(o, *lp._const, *lp._batch, out, self._guid.start)
        return out

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The action for one vehicle: row 0 of the batched law on a batch of one."""
        o = self._obs2d(obs, 1)[None, :]
        out = np.zeros((1, self._n_act), dtype=np.float32)
        self._step(o, self._single_state, out, self._lev.start)
        lp = self.lateral
        if lp is not None:
            lp.step(o, out, self._guid.start, single=True)
        return out[0]
