"""A safety filter any controller can wear: ``shielded:<name>`` in every tool, or
``Shield(controller, ctx, …)`` from Python.

Every control step the wrapped controller proposes an action ``a_p``; the filter predicts,
on the linearised model, where the proposed action held for ``horizon_steps`` control steps
would take every gap excursion it commands, and returns ``a_p`` itself if every predicted
excursion stays inside the bound, else the closest action that keeps them inside.

**Model and estimate.** The LQG's design model of each commanded plane
(:mod:`agents.controllers.lqr`: the vertical plane with the coil lag and the
track-disturbance states; with ``actuators="levitation+guidance"`` also the lateral plane)
and its steady-state Kalman filter, run by the filter itself on the measured gaps, currents
and accelerations and fed with the action the filter *sends* (not the proposal): the
estimate x̂ after the measurement update of step t. With the held command u [action units,
``a_per_A`` per A] the predicted excursions (levitation gaps s_a, guidance gaps z_a) are::

    e_k = C_s·(Φ^k x̂ + Σ_{j<k} Φ^j Γ u / a_per_A),   k = 1 … H      [m]

(``H = horizon_steps``; the condensed prediction of :func:`agents.controllers.mpc.
_condensed`, the held input summing its columns).

**Bound.** ``b = limit − margin`` per plane [mm]: ``limit_mm`` defaults to the plane's
clearance (Ω = 8 mm for the levitation gaps, Ω_g = 8 mm for the guidance gaps), ``margin_mm``
to 2 mm (:data:`hyperloop_env.safety.DEFAULT_SAFETY_MARGIN_MM`, the safety cost's margin):
a step the filter accepts is predicted to cost 0. ``limit_mm=math.inf`` makes the bound
infinite: the filter then returns the proposed action array itself, bit for bit, and runs no
estimator (a test).

**The QP.** For a row whose prediction leaves the bound (|e_k| > b for some unit and k),
per plane, with ε ≥ 0 the worst predicted excursion beyond the bound [mm]::

    minimise   ‖u − a_p‖² + ρ₁·ε + ρ₂·ε²
    subject to lo ≤ u ≤ hi                       (the actuator limits, action units)
               −b − ε ≤ e_k(u) ≤ b + ε,  k = 1 … H, every unit

solved by DAQP (as the MPC: a dense, small QP; 5 variables, 8·H rows). ρ₁ = 10⁴ per mm is
an exact penalty (the action term is at most 16): ε > 0 only where no action inside the
limits keeps the prediction within the bound, and then the result is the least-violating
action (its ε within 16/ρ₁ mm of the smallest possible). Such a step is counted as
infeasible (ε > 1 nm), never silently.

**Counters** (:attr:`Shield.stats`, :meth:`Shield.counters`): ``steps`` vehicle-steps
filtered (idle rows of a batch excluded), ``changed`` those whose action was changed,
``infeasible`` those where no action kept the prediction inside the bound (the
least-violating one was sent), ``qp_solves`` QPs solved, ``qp_unsolved`` QPs DAQP did not end
optimal (their last iterate, clipped to the limits, was sent). With the levitation
currents alone the guidance gaps are not commanded, so not filtered.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from agents.controllers.base import ControlContext, control_context
from agents.controllers.lqr import (
    NU,
    LQRController,
    _PlaneLQG,
    accumulate_rows,
    lqg_command,
    lqg_update,
)
from agents.controllers.mpc import _condensed
from hyperloop_env.safety import DEFAULT_SAFETY_MARGIN_MM

INFEASIBLE_TOL_MM = 1e-6
"""A QP whose slack ε exceeds this [mm] (1 nm) is counted as infeasible."""
COUNTERS = ("steps", "changed", "infeasible", "qp_solves", "qp_unsolved")
"""The names of the counters (:attr:`Shield.stats`)."""


@dataclass(frozen=True)
class ShieldDesign:
    """The filter's bound, horizon and penalty (module docstring).

    ``margin_mm``: m ≥ 0 [mm]; ``limit_mm``: the limit the margin is taken from [mm] (None:
    each plane's clearance; ``math.inf``: no bound, the filter passes every action through);
    ``horizon_steps``: H ≥ 1 control steps (1 ms each at the default control rate);
    ``slack_linear`` ρ₁ [1/mm] and ``slack_quadratic`` ρ₂ [1/mm²] > 0."""

    margin_mm: float = DEFAULT_SAFETY_MARGIN_MM
    limit_mm: float | None = None
    horizon_steps: int = 10
    slack_linear: float = 1e4
    slack_quadratic: float = 1.0
    max_iter: int = 1000

    def __post_init__(self) -> None:
        m = self.margin_mm
        if isinstance(m, bool) or not isinstance(m, int | float) or not math.isfinite(m) or m < 0:
            raise ValueError(f"margin_mm must be a finite number >= 0, got {m!r}")
        lim = self.limit_mm
        if lim is not None:
            if isinstance(lim, bool) or not isinstance(lim, int | float) or math.isnan(lim):
                raise ValueError(f"limit_mm must be None, a number or math.inf, got {lim!r}")
            if lim <= m:
                raise ValueError(f"limit_mm must exceed margin_mm ({m!r} mm), got {lim!r}")
        h = self.horizon_steps
        if isinstance(h, bool) or not isinstance(h, int | np.integer) or h < 1:
            raise ValueError(f"horizon_steps must be an int >= 1, got {h!r}")
        for name in ("slack_linear", "slack_quadratic"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number > 0, got {v!r}")
            if v <= 0:
                raise ValueError(f"{name} must be > 0, got {v!r}")
        it = self.max_iter
        if isinstance(it, bool) or not isinstance(it, int) or it < 1:
            raise ValueError(f"max_iter must be an int >= 1, got {it!r}")

    @property
    def passes_through(self) -> bool:
        """The bound is infinite: every action passes unchanged."""
        return self.limit_mm is not None and math.isinf(self.limit_mm)


SHIELD_KEYWORDS = (
    "design",
    "margin_mm",
    "limit_mm",
    "horizon_steps",
    "slack_linear",
    "slack_quadratic",
    "max_iter",
)
"""The keywords of :class:`Shield` (``make_controller("shielded:<name>", …)`` takes them
out of the keywords it passes to ``<name>``'s factory)."""


class _PlaneFilter:
    """The filter of one plane: its estimator (an LQG plane, :class:`_PlaneLQG`, fed with
    the command sent), the prediction matrices and its QP (DAQP)."""

    def __init__(self, plane: _PlaneLQG, col0: int, bound_mm: float, d: ShieldDesign) -> None:
        import daqp  # a dependency of the package (as the MPC's)

        self.plane = plane
        self.col0 = col0
        self.bound_mm = bound_mm
        self.lo, self.hi, self.a = plane.lo, plane.hi, plane.a_per_A
        n, nl, H = plane.n, plane._nl, d.horizon_steps
        live = np.flatnonzero(plane.src >= 0)
        # x̂ (after the measurement update) = E·[z; y]: the filter's state z (x̂⁻ = V z)
        E = np.hstack([(np.eye(n) - plane.M @ plane.C) @ plane.V, plane.M[:, live]])
        zeros = np.zeros((n, n))
        Sx, Su, _, _ = _condensed(plane.Phi, plane.Gam, zeros, np.eye(NU), zeros, H)
        held = Su @ np.kron(np.ones((H, 1)), np.eye(NU))  # u_k = u for every k
        Cs = np.kron(np.eye(H), self._gap_rows(plane))
        self.Px = np.ascontiguousarray(1e3 * Cs @ Sx @ E)  # (4H, n + nl): free response [mm]
        self.Pu = np.ascontiguousarray(1e3 * Cs @ held / self.a)  # (4H, 4) [mm per action]
        self.n_w = n + nl
        ng = NU * H
        nz = NU + 1  # u (action units), ε [mm]
        Hq = np.zeros((nz, nz))
        Hq[:NU, :NU] = 2.0 * np.eye(NU)
        Hq[NU, NU] = 2.0 * d.slack_quadratic
        ones = np.ones((ng, 1))
        A = np.vstack([np.hstack([self.Pu, -ones]), np.hstack([self.Pu, ones])])
        big = 1e30  # DAQP's infinity
        self._hi0 = np.concatenate([np.full(NU, self.hi), [big], np.full(ng, bound_mm), [big] * ng])
        self._lo0 = np.concatenate(
            [np.full(NU, self.lo), [0.0], [-big] * ng, np.full(ng, -bound_mm)]
        )
        self._f = np.zeros(nz)
        self._f[NU] = d.slack_linear
        self._ng = ng
        self.qp = daqp.Model()
        self.qp.setup(Hq, self._f.copy(), A, self._hi0.copy(), self._lo0.copy())
        self.qp.settings = {"iter_limit": d.max_iter}

    @staticmethod
    def _gap_rows(plane: _PlaneLQG) -> np.ndarray:
        """The plane's excursion rows C_s (4, n) [m]: the first four measurements."""
        return plane.C[:NU]

    def solve(self, free_mm: np.ndarray, proposal: np.ndarray) -> tuple[np.ndarray, float, int]:
        """The QP of one row (module docstring): (u (4,), ε [mm], DAQP's exit flag)."""
        ng = self._ng
        f = self._f
        f[:NU] = -2.0 * proposal
        hi, lo = self._hi0.copy(), self._lo0.copy()
        hi[NU + 1 : NU + 1 + ng] -= free_mm
        lo[NU + 1 + ng :] -= free_mm
        self.qp.update(f=f, bupper=hi, blower=lo)
        x, _, flag, _ = self.qp.solve()
        return np.clip(x[:NU], self.lo, self.hi), float(max(x[NU], 0.0)), int(flag)


class Shield:
    """``controller`` wearing the safety filter (module docstring) on the plant of ``ctx``
    (a ``ControlContext``, an env, ``ModelParams`` …: the one the controller was built for).

    Keywords: ``design`` (:class:`ShieldDesign`) or its fields ``margin_mm``, ``limit_mm``,
    ``horizon_steps``, ``slack_linear``, ``slack_quadratic``, ``max_iter``. A controller with
    ``act_batch`` gives a filter with ``act_batch`` / ``reset_batch`` / ``idle_batch``
    (:class:`BatchShield`; the proposals of all rows are checked in one product, a QP is
    solved only for a row whose prediction leaves the bound)."""

    def __new__(cls, controller: Any = None, *args: Any, **kwargs: Any) -> Shield:
        if cls is Shield and callable(getattr(controller, "act_batch", None)):
            cls = BatchShield
        return super().__new__(cls)

    def __init__(
        self,
        controller: Any,
        ctx: ControlContext | Any = None,
        design: ShieldDesign | None = None,
        **fields: Any,
    ) -> None:
        if design is not None and fields:
            raise TypeError(f"Shield: pass design= or its fields, not both ({sorted(fields)})")
        if design is None:
            unknown = set(fields) - set(ShieldDesign.__dataclass_fields__)
            if unknown:
                raise TypeError(f"Shield: unknown keyword(s) {sorted(unknown)}")
            design = ShieldDesign(**fields)
        if not isinstance(design, ShieldDesign):
            raise TypeError(f"design must be a ShieldDesign, got {type(design).__name__}")
        self.controller = controller
        self.design = design
        self.ctx = control_context(ctx)
        self.name = f"shielded:{getattr(controller, 'name', type(controller).__name__)}"
        self.stats = dict.fromkeys(COUNTERS, 0)
        """The counters (module docstring)."""
        self._filters: tuple[_PlaneFilter, ...] = ()
        if not design.passes_through:
            est = LQRController(self.ctx)  # the LQG's planes: the filter's estimators
            ctx_ = self.ctx
            lim_v = ctx_.clearance_m * 1e3 if design.limit_mm is None else design.limit_mm
            filters = [_PlaneFilter(est.vertical, est._lev.start, lim_v - design.margin_mm, design)]
            if est.lateral is not None:
                lim_g = ctx_.params.guidance.clearance_m * 1e3
                lim_g = lim_g if design.limit_mm is None else design.limit_mm
                filters.append(
                    _PlaneFilter(est.lateral, est._guid.start, lim_g - design.margin_mm, design)
                )
            self._filters = tuple(filters)
            self._obs2d = est._obs2d
        self._idle = np.zeros(0, dtype=bool)

    # -- counters ----------------------------------------------------------------------------
    def counters(self) -> dict[str, int | float]:
        """The counters and the fractions of filtered steps changed and infeasible."""
        s = dict(self.stats)
        n = max(1, s["steps"])
        return {
            **s,
            "changed_fraction": s["changed"] / n,
            "infeasible_fraction": s["infeasible"] / n,
        }

    def reset_counters(self) -> None:
        self.stats = dict.fromkeys(COUNTERS, 0)

    # -- single vehicle ------------------------------------------------------------------------
    def reset(self, seed: int | None = None) -> None:
        self.controller.reset(seed=seed)
        for f in self._filters:
            f.plane.reset()

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The filtered action for one vehicle (the proposal itself when it passes)."""
        proposal = self.controller.act(obs)
        if not self._filters:
            self.stats["steps"] += 1
            return proposal
        o = self._obs2d(obs, 1)[None, :]
        return self._filter(o, np.asarray(proposal)[None, :], single=True)[0]

    # -- the filter ------------------------------------------------------------------------------
    def _filter(self, o: np.ndarray, proposal: np.ndarray, single: bool) -> np.ndarray:
        """Filter the proposals (B, n_act) of the rows of ``o`` (B, obs_size): returns
        ``proposal`` itself if no row changes, else a float32 copy with the changed rows."""
        B = o.shape[0]
        idle = self._idle if (not single and self._idle.shape == (B,)) else np.zeros(B, bool)
        out = proposal
        changed = np.zeros(B, dtype=bool)
        infeasible = np.zeros(B, dtype=bool)
        for f in self._filters:
            p = f.plane
            src, scale, K, F, scal = p._const
            W, Z, S = p._single if single else p._batch
            lqg_command(o, src, scale, K, W, S)  # the live measurements into W
            cols = slice(f.col0, f.col0 + NU)
            a = np.clip(np.asarray(proposal[:, cols], dtype=np.float64), f.lo, f.hi)  # (B, 4)
            # compiled products, each row's sums in one order whatever the batch (as the MPC)
            free = np.empty((f.Px.shape[0], B))
            accumulate_rows(f.Px, W[: f.n_w], free)  # (4H, B): the free response [mm]
            pred = np.empty_like(free)
            accumulate_rows(f.Pu, np.ascontiguousarray(a.T), pred)
            pred += free
            bad = (np.abs(pred) > f.bound_mm).any(axis=0) & ~idle
            for i in np.flatnonzero(bad):
                u, eps, flag = f.solve(free[:, i].copy(), a[i])
                self.stats["qp_solves"] += 1
                if flag != 1:
                    self.stats["qp_unsolved"] += 1
                if eps > INFEASIBLE_TOL_MM or flag != 1:
                    infeasible[i] = True
                if not np.array_equal(u.astype(np.float32), np.asarray(proposal[i, cols])):
                    if out is proposal:
                        out = np.array(proposal, dtype=np.float32, copy=True)
                    out[i, cols] = u
                    a[i] = u
                    changed[i] = True
            S[:] = -a.T / p.a_per_A  # the command sent (lqg_update: u = clip(−a·S))
            lqg_update(F, scal, W, Z, S, np.zeros((B, f.col0 + NU)), f.col0)
        self.stats["steps"] += int(B - np.count_nonzero(idle))
        self.stats["changed"] += int(np.count_nonzero(changed))
        self.stats["infeasible"] += int(np.count_nonzero(infeasible))
        return out

    def __repr__(self) -> str:
        d = self.design
        return (
            f"Shield({self.controller!r}, margin_mm={d.margin_mm}, limit_mm={d.limit_mm}, "
            f"horizon_steps={d.horizon_steps})"
        )


class BatchShield(Shield):
    """:class:`Shield` of a controller with ``act_batch``."""

    def reset_batch(self, mask: np.ndarray) -> None:
        m = np.asarray(mask, dtype=bool)
        inner = getattr(self.controller, "reset_batch", None)
        if callable(inner):
            inner(mask)
        for f in self._filters:
            f.plane.reset_batch(m)
        if self._idle.shape != m.shape:
            self._idle = np.zeros(m.shape, dtype=bool)
        self._idle[m] = False

    def idle_batch(self, mask: np.ndarray) -> None:
        """Rows whose actions the caller ignores until their next reset: no QP, not
        counted; passed on to the controller if it takes it."""
        self._idle = np.array(mask, dtype=bool, copy=True)
        inner = getattr(self.controller, "idle_batch", None)
        if callable(inner):
            inner(mask)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        """Filtered actions for N vehicles, ``(N, obs_size) -> (N, n_act)``: the proposals
        themselves (the same array) when no row changes."""
        proposal = self.controller.act_batch(obs)
        if not self._filters:
            n = int(np.shape(obs)[0])
            self.stats["steps"] += n - int(np.count_nonzero(self._idle[:n]))
            return proposal
        o = self._obs2d(obs, 2)
        n = o.shape[0]
        if self._filters[0].plane._batch[0].shape[1] != n:
            for f in self._filters:
                f.plane.reset_batch(np.ones(n, dtype=bool))
            self._idle = np.zeros(n, dtype=bool)
        return self._filter(o, np.asarray(proposal), single=False)


def shield(controller: Any, ctx: Any = None, **kwargs: Any) -> Shield:
    """``Shield(controller, ctx, **kwargs)``."""
    return Shield(controller, ctx, **kwargs)
