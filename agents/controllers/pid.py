"""Decentralised gap PID: one loop per magnet unit on its measured gap excursion.

Design method (pole placement on the linearised per-unit model)
---------------------------------------------------------------
Per unit, the primary suspension (K_h/4 ≈ 3e7 N/m) is stiffer than the magnet spring
(k_m = 2F0/δ0 ≈ 1.8e7 N/m), so below the frame mode (~15 Hz) the unit and its quarter of
the capsule move together: a mass ``m = m_u + m_c/4`` on the magnet. Linearising the
force law at the equilibrium (F0 = (m_c + m_m)·g/4, I0, δ0; paper eq. 3–5)::

    F = F0 + k_i·i − k_m·s,    k_i = 2F0/I0 [N/A],   k_m = 2F0/δ0 [N/m]
    s = σ·y  (σ = +1 repelling, −1 attracting)  ⇒  s̈ = σ·(k_i·i − k_m·s)/m

(repelling: a stable 7 Hz spring; attracting: a real pole at +√(k_m/m) ≈ 44 rad/s).
With ``i = −σ·(Kp·s + Kd·ṡ + Ki·∫s)`` the closed loop is
``λ³ + b·Kd·λ² + (b·Kp + σ·ω_m²)·λ + b·Ki`` (b = k_i/m, ω_m² = k_m/m), placed at
``(λ + ρω)(λ² + 2ζωλ + ω²)``::

    Kd = (2ζ + ρ)·ω / b,   Kp = (ω²(1 + 2ζρ) − σ·ω_m²) / b,   Ki = ρ·ω³ / b

The design parameters (ω, ζ, ρ, derivative filter) are chosen by ``hyperloop tune pid``
(a search over pole-placement designs, each verified on the full 14-state vertical model
with the coil lag, the derivative filter and the discrete 1 ms loop — closed-loop spectral
radius < 1 for both magnet orientations — and scored by the RMS gap excursion of short
nonlinear runs on the paper scenarios); the choice and the command that produced it live
in ``agents/pid_gains.json``. The gains themselves are recomputed from the model for every
parameter set (so the attracting magnet gets its larger Kp automatically).

Implementation: derivative from the measured gap rate (the observation's backward
difference) through a first-order low-pass (cut-off ``deriv_filter_ratio``·ω); integral
with conditional integration (anti-windup: the integrator is frozen while the output is
saturated in the direction the error would push it) and clamped so that Ki·∫s alone stays
inside the output range; output limited to the action range that keeps the current inside
[0, I_max]. Per-step work is plain Python floats (no numpy scalar ops, no allocations but
the returned action).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numba as nb
import numpy as np

from agents.controllers.base import BaseController, ControlContext, control_context
from agents.controllers.linear import c2d, vertical_model
from hyperloop_env.physics.arrays import is_float
from hyperloop_env.physics.params import MU0
from hyperloop_env.physics.units import N_UNITS

NU = N_UNITS

GAINS_FILE = Path(__file__).with_name("pid_gains.json")


@dataclass(frozen=True)
class PIDDesign:
    """Pole-placement design parameters (see the module docstring)."""

    omega_rad_s: float = 100.0  # closed-loop bandwidth ω
    zeta: float = 0.8  # damping of the dominant pair
    integral_ratio: float = 0.2  # ρ: integral pole at −ρ·ω
    deriv_filter_ratio: float = 5.0  # derivative low-pass cut-off = ratio·ω [rad/s]

    def __post_init__(self) -> None:
        for k, v in asdict(self).items():
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"PIDDesign.{k} must be a finite number > 0, got {v!r}")


@dataclass(frozen=True)
class PIDGains:
    """Gains in physical units: current deviation [A] per gap excursion [m] etc.; the
    control law is ``ΔI = −σ·(kp·s + kd·ṡ_f + ki·∫s)``."""

    kp_A_per_m: float
    ki_A_per_m_s: float
    kd_A_s_per_m: float
    sigma: float
    deriv_filter_rad_s: float
    mass_kg: float
    k_current_N_per_A: float
    k_magnet_N_per_m: float


def load_design(path: Path | str = GAINS_FILE) -> PIDDesign:
    """The tuned design stored by ``hyperloop tune pid`` in
    ``agents/controllers/pid_gains.json`` (package data). A missing file is an error naming
    it — never a silent fallback to other gains, which would change the PID baseline."""
    from agents.installation import require_data_file

    p = require_data_file(path, "the tuned PID design")
    data = json.loads(p.read_text())
    return PIDDesign(**data["design"])


def unit_model(ctx: ControlContext) -> dict[str, float]:
    """Per-unit linear model constants (combined unit + quarter-capsule mass)."""
    p = ctx.params
    g = p.simulation.gravity_m_s2
    f0 = p.vehicle.total_mass_kg * g / NU
    m = (p.vehicle.frame_mass_kg + p.vehicle.capsule_mass_kg) / NU
    return {
        "mass_kg": m,
        "k_current_N_per_A": 2.0 * f0 / ctx.nominal_current_A,
        "k_magnet_N_per_m": 2.0 * f0 / p.magnet.nominal_gap_m,
        "sigma": p.magnet.orientation_sign,
    }


def design_pid(ctx: ControlContext | Any, design: PIDDesign | None = None) -> PIDGains:
    """Pole-placement PID gains for the plant described by ``ctx``."""
    ctx = control_context(ctx)
    d = design if design is not None else load_design()
    um = unit_model(ctx)
    m, ki_, km, sigma = um["mass_kg"], um["k_current_N_per_A"], um["k_magnet_N_per_m"], um["sigma"]
    b = ki_ / m
    wm2 = km / m
    w, z, r = d.omega_rad_s, d.zeta, d.integral_ratio
    kd = (2 * z + r) * w / b
    kp = (w * w * (1 + 2 * z * r) - sigma * wm2) / b
    kint = r * w**3 / b
    if kp <= 0:
        raise ValueError(
            f"PID design with omega={w} rad/s gives a non-positive Kp for this plant; "
            "raise omega_rad_s"
        )
    return PIDGains(kp, kint, kd, sigma, d.deriv_filter_ratio * w, m, ki_, km)


@dataclass(frozen=True)
class GuidanceDesign:
    """Pole placement of the guidance loops (one per unit, on its guidance gap excursion
    z_a, acting on the pair's differential current ΔI_a; used when the actuator set
    includes ``guidance``). The unit alone moves against the guidance magnets (the
    secondary suspension to the capsule is ~15× softer), so the design model is
    ``m_u·z̈ = b_g·ΔI − k_l·z`` with m_u = m_m/4, b_g = σ·4·F_g0/I_g0 [N/A] and
    k_l = σ·4·F_g0/δg0 − σ·(2/π)·F0/b2 + K_z/4 [N/m] (guidance pair, levitation edge
    force, secondary spring to a capsule at rest; σ = +1 repelling, −1 attracting).
    ω = 60 rad/s is about three times the open-loop lateral frequency (≈ 20 rad/s, stable
    when repelling, a real pole when attracting) and leaves the 2 ms coil lag a factor 8;
    the integral removes the quasi-static offset in curves."""

    omega_rad_s: float = 60.0
    zeta: float = 0.7
    integral_ratio: float = 0.2
    deriv_filter_ratio: float = 5.0

    def __post_init__(self) -> None:
        for k, v in asdict(self).items():
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"GuidanceDesign.{k} must be a finite number > 0, got {v!r}")


def guidance_unit_model(ctx: ControlContext) -> dict[str, float]:
    """Per-unit lateral design model (see :class:`GuidanceDesign`), from the parameters."""
    p = ctx.params
    g = p.simulation.gravity_m_s2
    sigma = p.magnet.orientation_sign
    f0 = p.vehicle.total_mass_kg * g / NU
    gd = p.guidance
    ig0 = ctx.guidance_bias_A
    f_g0 = (
        MU0
        * gd.turns**2
        / 4.0
        * ig0**2
        * p.magnet.pole_length_m
        * gd.pole_height_m
        / (gd.nominal_gap_m**2)
    )
    k_edge = 2.0 / math.pi * f0 / p.magnet.pole_width_m
    return {
        "mass_kg": p.vehicle.frame_mass_kg / NU,
        "b_N_per_A": sigma * 4.0 * f_g0 / ig0,
        "k_N_per_m": sigma * 4.0 * f_g0 / gd.nominal_gap_m
        - sigma * k_edge
        + p.vehicle.secondary_stiffness_N_per_m / NU,
        "bias_current_A": ig0,
        "max_current_dev_A": min(ig0, gd.max_current_A - ig0),
    }


def design_guidance_pid(
    ctx: ControlContext | Any, design: GuidanceDesign | None = None
) -> PIDGains:
    """Pole-placement gains of the guidance loops: ``ΔI = −sgn(b)·(kp·z + kd·ż_f +
    ki·∫z)`` places the closed loop at (λ + ρω)(λ² + 2ζωλ + ω²)."""
    ctx = control_context(ctx)
    d = design if design is not None else GuidanceDesign()
    um = guidance_unit_model(ctx)
    m, bg, kl = um["mass_kg"], um["b_N_per_A"], um["k_N_per_m"]
    b = abs(bg) / m
    w, z, r = d.omega_rad_s, d.zeta, d.integral_ratio
    kd = (2 * z + r) * w / b
    kp = (w * w * (1 + 2 * z * r) - kl / m) / b
    kint = r * w**3 / b
    if kp <= 0:
        raise ValueError(f"guidance PID with omega={w} rad/s gives Kp <= 0; raise omega_rad_s")
    return PIDGains(kp, kint, kd, math.copysign(1.0, bg), d.deriv_filter_ratio * w, m, bg, kl)


def closed_loop_spectral_radius(ctx: ControlContext | Any, gains: PIDGains) -> float:
    """Spectral radius of the discrete closed loop: full 14-state vertical model + coil
    lag (ZOH at the control interval) with this PID exactly as implemented (backward-
    difference gap rate, derivative filter, integral). < 1 means stable (linear, no
    saturation)."""
    ctx = control_context(ctx)
    vm = vertical_model(ctx.params)
    dt = ctx.dt_s
    Phi, Gam = c2d(vm.A, vm.B, dt)
    n = vm.n
    C = vm.C_gap
    alpha = dt / (1.0 / gains.deriv_filter_rad_s + dt)
    sg = gains.sigma
    # z = [x (n), s_prev (NU), f (NU), I (NU)];  u = Ku @ z
    sp, fi, ii = slice(n, n + NU), slice(n + NU, n + 2 * NU), slice(n + 2 * NU, n + 3 * NU)
    N = n + 3 * NU
    eye = np.eye(NU)
    Ku = np.zeros((NU, N))
    Ku[:, :n] = -sg * (
        gains.kp_A_per_m * C + gains.kd_A_s_per_m * alpha / dt * C + gains.ki_A_per_m_s * dt * C
    )
    Ku[:, sp] = sg * gains.kd_A_s_per_m * alpha / dt * eye
    Ku[:, fi] = -sg * gains.kd_A_s_per_m * (1 - alpha) * eye
    Ku[:, ii] = -sg * gains.ki_A_per_m_s * eye
    M = np.zeros((N, N))
    M[:n] = np.hstack([Phi, np.zeros((n, 3 * NU))]) + Gam @ Ku
    M[sp, :n] = C
    M[fi, :n] = alpha / dt * C
    M[fi, sp] = -alpha / dt * eye
    M[fi, fi] = (1 - alpha) * eye
    M[ii, :n] = dt * C
    M[ii, ii] = eye
    return float(np.max(np.abs(np.linalg.eigvals(M))))


@nb.njit(cache=True, nogil=True)
def pid_step_batch(
    obs, g0, r0, clear, kp, kd, ki, dt, al, lo, hi, imax, integ, dfilt, out, o0
):  # pragma: no cover - compiled
    """The loop law of :meth:`PIDController._step` for every row i and unit a of a batch:
    error ``obs[i, g0 + a]·clear``, rate ``obs[i, r0 + a]``, loop states ``integ``/``dfilt``
    (N, NU) updated in place, action to ``out[i, o0 + a]``; the same operations in the same
    order, so the same floats as the single controller."""
    for i in range(obs.shape[0]):
        for a in range(integ.shape[1]):
            x = np.float64(obs[i, g0 + a]) * clear
            if x != x:  # NaN guard: a diverged measurement gives no action
                x = 0.0
            d = dfilt[i, a]
            df = d + al * (np.float64(obs[i, r0 + a]) - d)
            if df != df:
                df = 0.0
            dfilt[i, a] = df
            old = integ[i, a]
            i_new = old + x * dt
            if i_new > imax:
                i_new = imax
            elif i_new < -imax:
                i_new = -imax
            u = kp * x + kd * df + ki * i_new
            if u > hi:
                if ki * x > 0.0:  # integrating would push further into saturation
                    i_new = old
                u = hi
            elif u < lo:
                if ki * x < 0.0:
                    i_new = old
                u = lo
            integ[i, a] = i_new
            out[i, o0 + a] = u


class PIDController(BaseController):
    """Per-unit gap PID (see the module docstring). ``design`` overrides the tuned
    design; ``gains`` overrides the designed gains altogether."""

    name = "pid"

    def __init__(
        self,
        env_or_params: Any = None,
        design: PIDDesign | None = None,
        gains: PIDGains | None = None,
        action_scale: float | None = None,
        guidance_design: GuidanceDesign | None = None,
    ) -> None:
        self.ctx = control_context(env_or_params, action_scale)
        self.design = design if design is not None else load_design()
        self.gains = gains if gains is not None else design_pid(self.ctx, self.design)
        g = self.gains
        ctx = self.ctx
        self._dt = ctx.dt_s
        self._clear = ctx.clearance_m
        # action per ampere: a = ΔI / (I0·scale); fold σ and the units into the gains
        a_per_A = 1.0 / (ctx.nominal_current_A * ctx.action_scale)
        self._kp = -g.sigma * g.kp_A_per_m * a_per_A
        self._kd = -g.sigma * g.kd_A_s_per_m * a_per_A
        self._ki = -g.sigma * g.ki_A_per_m_s * a_per_A
        self._alpha = self._dt / (1.0 / g.deriv_filter_rad_s + self._dt)
        self._lo, self._hi = ctx.action_limits()
        # integrator clamp: |ki·∫s| within the output range
        self._imax = max(abs(self._lo), abs(self._hi)) / abs(self._ki)
        spec = ctx.observation
        self._obs_size = spec.size
        self._g0, self._r0 = spec.start("gap"), spec.start("gap_rate")
        self._lev0 = ctx.actuators.slice("levitation").start
        self._n_act = ctx.n_actions
        self.guidance_gains: PIDGains | None = None
        if "guidance" in ctx.actuators.kinds:
            gg = design_guidance_pid(ctx, guidance_design)
            self.guidance_gains = gg
            # action per ampere of ΔI: a = ΔI / (I_g0·scale)
            ga = 1.0 / (ctx.guidance_bias_A * ctx.action_scale)
            self._gkp = -gg.sigma * gg.kp_A_per_m * ga
            self._gkd = -gg.sigma * gg.kd_A_s_per_m * ga
            self._gki = -gg.sigma * gg.ki_A_per_m_s * ga
            self._galpha = self._dt / (1.0 / gg.deriv_filter_rad_s + self._dt)
            glim = min(1.0, guidance_unit_model(ctx)["max_current_dev_A"] * ga)
            self._glo, self._ghi = -glim, glim
            self._gimax = glim / abs(self._gki)
            self._l0, self._lr0 = spec.start("lateral"), spec.start("lateral_rate")
            self._gclear = ctx.params.guidance.clearance_m
            self._g0a = ctx.actuators.slice("guidance").start
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        self._integ = [0.0] * NU
        self._dfilt = [0.0] * NU
        self._ginteg = [0.0] * NU
        self._gdfilt = [0.0] * NU
        self._b_integ = None

    def act(self, obs: np.ndarray) -> np.ndarray:
        o = obs.tolist() if isinstance(obs, np.ndarray) else list(obs)
        if len(o) != self._obs_size:
            raise ValueError(f"obs must have shape ({self._obs_size},), got {np.shape(obs)}")
        out = self._step(o)
        if self.guidance_gains is not None:
            self._guidance_step(o, out)
        return np.array(out, dtype=np.float32)

    # ---- batched: N independent copies of the loops (same arithmetic, row by row) ------
    def reset_batch(self, mask: np.ndarray) -> None:
        """Reset the loop states of the rows where ``mask`` is True (``act_batch``'s state;
        a new mask size starts a fresh batch)."""
        m = np.asarray(mask, dtype=bool)
        if getattr(self, "_b_integ", None) is None or self._b_integ.shape[0] != m.shape[0]:
            n = m.shape[0]
            self._b_integ = np.zeros((n, NU))
            self._b_dfilt = np.zeros((n, NU))
            self._b_ginteg = np.zeros((n, NU))
            self._b_gdfilt = np.zeros((n, NU))
            return
        for arr in (self._b_integ, self._b_dfilt, self._b_ginteg, self._b_gdfilt):
            arr[m] = 0.0

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        """Actions for N independent vehicles, ``(N, obs_size) -> (N, n_act)`` (each row
        follows its own loop state; :meth:`reset_batch` starts rows anew); compiled
        (:func:`pid_step_batch`), the single controller's floats."""
        o = np.asarray(obs)
        dt = o.dtype
        if not is_float(dt):
            o = o.astype(np.float64)
        if o.ndim != 2 or o.shape[1] != self._obs_size:
            raise ValueError(f"obs must have shape (N, {self._obs_size}), got {o.shape}")
        n = o.shape[0]
        if getattr(self, "_b_integ", None) is None or self._b_integ.shape[0] != n:
            self.reset_batch(np.ones(n, dtype=bool))
        out = np.zeros((n, self._n_act), dtype=np.float32)
        pid_step_batch(
            o,
            self._g0,
            self._r0,
            self._clear,
            self._kp,
            self._kd,
            self._ki,
            self._dt,
            self._alpha,
            self._lo,
            self._hi,
            self._imax,
            self._b_integ,
            self._b_dfilt,
            out,
            self._lev0,
        )
        if self.guidance_gains is not None:
            pid_step_batch(
                o,
                self._l0,
                self._lr0,
                self._gclear,
                self._gkp,
                self._gkd,
                self._gki,
                self._dt,
                self._galpha,
                self._glo,
                self._ghi,
                self._gimax,
                self._b_ginteg,
                self._b_gdfilt,
                out,
                self._g0a,
            )
        return out

    def _guidance_step(self, o: list[float], out: list[float]) -> None:
        """The guidance loops (same structure as the gap loops) into ``out``."""
        kp, kd, ki, dt, al = self._gkp, self._gkd, self._gki, self._dt, self._galpha
        lo, hi, imax, clear = self._glo, self._ghi, self._gimax, self._gclear
        integ, dfilt = self._ginteg, self._gdfilt
        l0, r0, g0 = self._l0, self._lr0, self._g0a
        for a in range(NU):
            z = o[l0 + a] * clear
            if z != z:
                z = 0.0
            df = dfilt[a] + al * (o[r0 + a] - dfilt[a])
            if df != df:
                df = 0.0
            dfilt[a] = df
            i_new = integ[a] + z * dt
            if i_new > imax:
                i_new = imax
            elif i_new < -imax:
                i_new = -imax
            u = kp * z + kd * df + ki * i_new
            if u > hi:
                if ki * z > 0.0:
                    i_new = integ[a]
                u = hi
            elif u < lo:
                if ki * z < 0.0:
                    i_new = integ[a]
                u = lo
            integ[a] = i_new
            out[g0 + a] = u

    def _step(self, o: list[float]) -> list[float]:
        kp, kd, ki, dt, al = self._kp, self._kd, self._ki, self._dt, self._alpha
        lo, hi, imax, clear = self._lo, self._hi, self._imax, self._clear
        integ, dfilt = self._integ, self._dfilt
        g0, r0, l0 = self._g0, self._r0, self._lev0
        out = [0.0] * self._n_act  # channels of other actuator kinds stay at their bias
        for a in range(NU):
            s = o[g0 + a] * clear
            if s != s:  # NaN guard: a diverged measurement gives no action
                s = 0.0
            df = dfilt[a] + al * (o[r0 + a] - dfilt[a])
            if df != df:
                df = 0.0
            dfilt[a] = df
            i_new = integ[a] + s * dt
            if i_new > imax:
                i_new = imax
            elif i_new < -imax:
                i_new = -imax
            u = kp * s + kd * df + ki * i_new
            if u > hi:
                if ki * s > 0.0:  # integrating would push further into saturation
                    i_new = integ[a]
                u = hi
            elif u < lo:
                if ki * s < 0.0:
                    i_new = integ[a]
                u = lo
            integ[a] = i_new
            out[l0 + a] = u
        return out
