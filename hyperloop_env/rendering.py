"""Frame drawing for the environments (pygame; ``rgb_array`` needs no display).

A frame (640 × 360) shows

* top: a side view 50 m long around the capsule — the guideway under the left magnets as
  a polyline through the piers (every span, zero deflection) and the deflection w under
  the front and rear units, with the capsule riding on its magnet units; vertical
  displacements are exaggerated (1 mm = 4 px);
* bottom left: one bar per unit (FL, FR, RL, RR) for the gap excursion s_a against the
  clearance ±Ω (red lines), green below Ω/2, orange below 0.8 Ω, red beyond, and a thin
  horizontal bar for the lateral offset against the lateral clearance;
* bottom right: speed, position, time, curve radius and curvature, and the coil currents
  relative to I0.

``human`` mode shows the same frame in a pygame window. Without a display it warns once
(the message says to use ``rgb_array``) and draws off-screen, so Gymnasium's
``check_env`` passes on a headless machine as it does for CartPole.
"""

from __future__ import annotations

import math
import os
import sys
from typing import Any

import numpy as np

from hyperloop_env.physics.layout import (
    M_GAP,
    M_I,
    M_KAPPA,
    M_LAT,
    M_T,
    M_W,
    M_X,
    P_CLEAR,
    P_D1H,
    P_GCLEAR,
    P_I0,
    P_SPAN,
    P_SPEED,
)
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES

WIDTH, HEIGHT = 640, 360
VIEW_M = 50.0  # length of the side view [m]
PX_PER_M = WIDTH / VIEW_M
PX_PER_MM = 4.0  # vertical exaggeration of displacements

BG = (245, 246, 248)
INK = (30, 30, 40)
GRID = (200, 204, 210)
GUIDE = (90, 90, 100)
CAPSULE = (70, 110, 170)
UNIT = (40, 60, 90)
GREEN = (60, 160, 80)
ORANGE = (230, 150, 40)
RED = (210, 50, 50)


def _pygame() -> Any:
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    try:
        import pygame
    except ImportError as exc:  # pragma: no cover - pygame is a dependency of rendering
        raise ImportError(
            "rendering needs pygame: pip install pygame (or gymnasium[classic-control])"
        ) from exc
    return pygame


def _level_colour(frac: float) -> tuple[int, int, int]:
    a = abs(frac)
    if a < 0.5:
        return GREEN
    if a < 0.8:
        return ORANGE
    return RED


class Renderer:
    """Draws frames from a measurement record and the packed parameters."""

    def __init__(self, mode: str = "rgb_array", fps: float = 50.0) -> None:
        pg = _pygame()
        self.pg = pg
        self.mode = mode
        self.fps = fps
        pg.font.init()
        self.font = pg.font.Font(None, 18)
        self.font_big = pg.font.Font(None, 22)
        self.window = None
        self.clock = None
        self.headless_reason: str | None = None
        if mode == "human":
            try:
                self.window = self._open_window()
            except RuntimeError as exc:
                # no display: draw off-screen and say so once (Gymnasium's check_env and
                # CartPole behave the same way on a headless machine)
                self.headless_reason = str(exc)
                from gymnasium import logger

                logger.warn(f"{exc}. Frames are drawn off-screen and not shown.")
            else:
                pg.display.set_caption("HyperloopSuspension-v0")
                self.clock = pg.time.Clock()
        self.surf = pg.Surface((WIDTH, HEIGHT))
        self._text_cache: dict[tuple[str, bool], Any] = {}

    def _open_window(self) -> Any:
        """A pygame window; RuntimeError if there is no display. SDL silently falls back to
        an invisible "offscreen" driver on headless Linux: that counts as no display unless
        it was asked for with ``SDL_VIDEODRIVER`` (e.g. ``dummy`` in tests)."""
        pg = self.pg
        hint = "use render_mode='rgb_array' on a headless machine"
        asked = os.environ.get("SDL_VIDEODRIVER", "")
        if (
            sys.platform.startswith("linux")
            and not asked
            and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
        ):
            raise RuntimeError(
                f"render_mode='human' needs a display (neither DISPLAY nor WAYLAND_DISPLAY is "
                f"set); {hint}"
            )
        try:
            pg.display.init()
            driver = pg.display.get_driver()
            if driver in ("offscreen", "dummy") and asked not in ("offscreen", "dummy"):
                pg.display.quit()
                raise RuntimeError(
                    f"render_mode='human' needs a display (SDL video driver: {driver}); {hint}"
                )
            return pg.display.set_mode((WIDTH, HEIGHT))
        except pg.error as exc:
            msg = f"render_mode='human' needs a display (pygame: {exc}); {hint}"
            raise RuntimeError(msg) from exc

    def _text(self, s: str, pos: tuple[int, int], big: bool = False) -> None:
        key = (s, big)
        img = self._text_cache.get(key)
        if img is None:
            img = (self.font_big if big else self.font).render(s, True, INK)
            if len(self._text_cache) > 512:
                self._text_cache.clear()
            self._text_cache[key] = img
        self.surf.blit(img, pos)

    def draw(self, rec: np.ndarray, P: np.ndarray, params: ModelParams) -> np.ndarray | None:
        pg = self.pg
        s = self.surf
        s.fill(BG)
        self._side_view(rec, P)
        self._gap_bars(rec, P)
        self._text_panel(rec, P, params)
        if self.mode == "human":
            if self.window is None or self.clock is None:
                return None  # headless: nothing to show (see headless_reason)
            pg.event.pump()
            self.window.blit(s, (0, 0))
            pg.display.flip()
            self.clock.tick(self.fps)
            return None
        return np.ascontiguousarray(np.transpose(pg.surfarray.pixels3d(s), (1, 0, 2)))

    def _side_view(self, rec: np.ndarray, P: np.ndarray) -> None:
        pg = self.pg
        s = self.surf
        x_c = float(rec[M_X])
        y0 = 120  # screen row of zero deflection
        x_left = x_c - VIEW_M / 2

        def sx(x: float) -> int:
            return int(round((x - x_left) * PX_PER_M))

        def sy(dy_m: float) -> int:  # up positive, exaggerated, clamped to the view
            v = -dy_m * 1e3 * PX_PER_MM
            v = max(-100.0, min(100.0, v)) if math.isfinite(v) else 0.0
            return int(round(y0 + v))

        self._text("side view (displacements x4 px/mm)", (8, 6))
        span = float(P[P_SPAN])
        d1h = float(P[P_D1H])
        pts = [(x_c + d1h, float(rec[M_W + 0])), (x_c - d1h, float(rec[M_W + 2]))]
        j0 = math.floor(x_left / span)
        piers = [k * span for k in range(j0, j0 + int(VIEW_M / span) + 2)]
        pts += [(xp, 0.0) for xp in piers]
        pts.sort()
        pg.draw.lines(s, GUIDE, False, [(sx(x), sy(w)) for x, w in pts], 3)
        for xp in piers:
            px = sx(xp)
            pg.draw.polygon(s, GRID, [(px, y0 + 4), (px - 8, y0 + 60), (px + 8, y0 + 60)])
        # magnet units above the guide (repelling) at w + s; capsule on top of them
        h = {}
        for a, xo in ((0, d1h), (2, -d1h)):
            w = float(rec[M_W + a])
            gap = float(rec[M_GAP + a])
            h[a] = w + gap
            px = sx(x_c + xo)
            py = sy(h[a]) - 14
            pg.draw.rect(s, UNIT, (px - 7, py, 14, 10))
        xf, xr = x_c + 12.5, x_c - 12.5
        slope = (h[0] - h[2]) / (2 * d1h)
        hf = 0.5 * (h[0] + h[2]) + slope * 12.5
        hr = 0.5 * (h[0] + h[2]) - slope * 12.5
        base_f, base_r = sy(hf) - 18, sy(hr) - 18
        poly = [(sx(xr), base_r), (sx(xf), base_f), (sx(xf), base_f - 40), (sx(xr), base_r - 40)]
        pg.draw.polygon(s, CAPSULE, poly)
        pg.draw.line(s, GRID, (0, 205), (WIDTH, 205), 1)

    def _gap_bars(self, rec: np.ndarray, P: np.ndarray) -> None:
        pg = self.pg
        s = self.surf
        clear = float(P[P_CLEAR])
        latc = float(P[P_GCLEAR])
        top, bottom = 225, 335
        mid = (top + bottom) // 2
        half = (bottom - top) // 2 - 8  # pixels for Ω
        self._text("gap s/Ω   (lateral below)", (8, 210))
        self._text("+Ω", (292, mid - half - 6))
        self._text("-Ω", (292, mid + half - 6))
        for a in range(N_UNITS):
            cx = 40 + a * 70
            frac = float(rec[M_GAP + a]) / clear
            frac = frac if math.isfinite(frac) else 0.0
            fv = max(-1.2, min(1.2, frac))
            pg.draw.line(s, RED, (cx - 22, mid - half), (cx + 22, mid - half), 2)
            pg.draw.line(s, RED, (cx - 22, mid + half), (cx + 22, mid + half), 2)
            pg.draw.line(s, GRID, (cx - 22, mid), (cx + 22, mid), 1)
            length = int(round(fv * half))
            y1, y2 = sorted((mid, mid - length))
            pg.draw.rect(s, _level_colour(frac), (cx - 12, y1, 24, max(1, y2 - y1)))
            lat = float(rec[M_LAT + a]) / latc
            lat = lat if math.isfinite(lat) else 0.0
            lv = max(-1.2, min(1.2, lat))
            pg.draw.line(s, GRID, (cx - 25, bottom + 8), (cx + 25, bottom + 8), 1)
            x1, x2 = sorted((cx, cx + int(round(lv * 25))))
            pg.draw.rect(s, _level_colour(lat), (x1, bottom + 6, max(1, x2 - x1), 5))
            self._text(UNIT_NAMES[a], (cx - 8, bottom + 13))

    def _text_panel(self, rec: np.ndarray, P: np.ndarray, params: ModelParams) -> None:
        x0 = 320
        c = params.condition
        radius = "straight" if math.isinf(c.curve_radius_m) else f"R = {c.curve_radius_m:,.0f} m"
        i0 = float(P[P_I0])
        lines = [
            f"v = {float(P[P_SPEED]) * 3.6:.0f} km/h   {params.magnet.orientation}",
            f"x = {float(rec[M_X]):.1f} m   t = {float(rec[M_T]):.3f} s",
            f"{radius}   kappa here = {float(rec[M_KAPPA]) * 1e5:.2f}e-5 /m",
            f"clearance = {float(P[P_CLEAR]) * 1e3:.1f} mm   I0 = {i0:.1f} A",
            "I/I0: " + "  ".join(f"{float(rec[M_I + a]) / i0:.2f}" for a in range(N_UNITS)),
            "s [mm]: " + "  ".join(f"{float(rec[M_GAP + a]) * 1e3:+.2f}" for a in range(N_UNITS)),
        ]
        self._text("HyperloopSuspension-v0", (x0, 212), big=True)
        for k, line in enumerate(lines):
            self._text(line, (x0, 236 + 19 * k))

    def close(self) -> None:
        if self.window is not None:
            self.pg.display.quit()
            self.window = None


def save_png(frame: np.ndarray, path: str) -> None:
    """Write an RGB frame (H, W, 3) uint8 as PNG (pygame)."""
    pg = _pygame()
    surf = pg.surfarray.make_surface(np.transpose(frame, (1, 0, 2)))
    pg.image.save(surf, path)
