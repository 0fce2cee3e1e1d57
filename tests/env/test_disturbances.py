"""Disturbances as parts: registry, validation, seeded realisations, end to end in both envs."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from hyperloop_env import ENV_ID
from hyperloop_env.config import EnvConfig
from hyperloop_env.disturbances import (
    DISTURBANCES,
    ProfileGrid,
    Roughness,
    ThermalCamber,
    make_disturbance,
    merge,
    parse_disturbances,
    realise_all,
)
from hyperloop_env.physics import ModelParams
from hyperloop_env.physics.irregularity import band_variance
from hyperloop_env.physics.params import IrregularityParams
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv


def test_registry_and_parsing() -> None:
    assert set(DISTURBANCES) >= {"roughness", "thermal_camber"}
    d = make_disturbance("thermal_camber", 0.004)
    assert d == ThermalCamber(severity=0.004)
    assert parse_disturbances({"thermal_camber": 0.004}) == (d,)
    assert parse_disturbances({"thermal_camber": {"severity": 0.004, "spread": 0.2}}) == (
        ThermalCamber(0.004, 0.2),
    )
    assert parse_disturbances([d]) == (d,) and parse_disturbances(None) == ()
    with pytest.raises(ValueError, match="unknown disturbance 'earthquake'.*thermal_camber"):
        make_disturbance("earthquake", 1.0)
    with pytest.raises(ValueError, match=r"ThermalCamber.severity must be >= 0.0, got -0.001"):
        ThermalCamber(severity=-0.001)
    with pytest.raises(ValueError, match="ThermalCamber.severity must be a finite number"):
        ThermalCamber(severity=math.nan)
    with pytest.raises(ValueError, match="ThermalCamber.spread"):
        ThermalCamber(spread=2.0)
    with pytest.raises(TypeError, match="thermal_camber"):
        make_disturbance("thermal_camber", 0.003, colour="red")
    with pytest.raises(ValueError, match="more than once"):
        parse_disturbances([d, ThermalCamber(0.001)])
    # numpy scalars are numbers
    assert ThermalCamber(np.float32(0.002)).severity == pytest.approx(0.002)
    # merge: same name replaces, new names append
    r = Roughness.from_class("maglev")
    assert merge((r,), (d,)) == (r, d)
    assert merge((r, d), (Roughness(0.3),)) == (Roughness(0.3), d)


def test_roughness_severity_is_the_amplitude_factor() -> None:
    """Roughness(s) = s × the German "low" amplitude: PSD × s², so the band variance of
    severity 0.1 equals the named class "maglev" (German low at 10 % amplitude)."""
    ref = band_variance(IrregularityParams(spectrum="german-low"))
    for s in (0.1, 0.25, 0.7):
        p = Roughness(s).configure(ModelParams())
        assert band_variance(p.irregularity) == pytest.approx(s**2 * ref, rel=1e-12)
    maglev = Roughness.from_class("maglev").configure(ModelParams())
    assert band_variance(maglev.irregularity) == pytest.approx(0.01 * ref, rel=1e-12)
    assert Roughness.from_class("maglev").configure(ModelParams()) == ModelParams()


def test_thermal_camber_is_a_parabola_per_span() -> None:
    p = ModelParams()
    grid = ProfileGrid(n=3000, step_m=0.1)  # 300 m: 10 spans of 30 m
    d = ThermalCamber(severity=0.004, spread=0.5)
    r = d.realise(p, grid, np.random.default_rng(1))
    off = r.profile_offset
    assert off is not None and off.shape == (3, grid.n)
    np.testing.assert_array_equal(off[0], off[1])  # both rails
    assert np.all(off[2] == 0.0)  # no lateral part
    x = grid.x_m
    span = p.guideway.span_m
    for j in range(9):
        m = (x >= j * span) & (x < (j + 1) * span)
        xi = x[m] / span - j
        c = off[0, m].max()
        # parabola through the piers: c·4ξ(1 − ξ), c within severity·(1 ± spread)
        np.testing.assert_allclose(off[0, m], c * 4 * xi * (1 - xi), rtol=1e-12, atol=1e-7)
        assert 0.002 - 1e-6 <= c <= 0.006 + 1e-6
        assert off[0, m][0] == 0.0  # zero on the pier
    # seeded: same generator state, same bows; another seed, other bows
    r2 = d.realise(p, grid, np.random.default_rng(1))
    np.testing.assert_array_equal(off, r2.profile_offset)
    r3 = d.realise(p, grid, np.random.default_rng(2))
    assert not np.array_equal(off, r3.profile_offset)
    assert ThermalCamber(0.0).realise(p, grid, np.random.default_rng(0)).profile_offset is None


def test_realisations_are_independent_of_each_other() -> None:
    p = ModelParams()
    grid = ProfileGrid(n=600, step_m=0.1)
    a = (ThermalCamber(0.003),)
    b = (Roughness(0.2), ThermalCamber(0.003))  # roughness does not draw here
    _, off_a = realise_all(a, p, grid, seed=7)
    _, off_b = realise_all(b, p, grid, seed=7)
    # same family at another position in the tuple draws from another stream
    assert off_a is not None and off_b is not None
    assert not np.array_equal(off_a, off_b)
    _, again = realise_all(b, p, grid, seed=7)
    np.testing.assert_array_equal(off_b, again)


def test_thermal_camber_end_to_end_in_both_envs() -> None:
    kw = {"scenario": "paper-1000-straight", "track_length_m": 200.0, "irregularity": "none"}
    flat = gym.make(ENV_ID, **kw)
    bowed = gym.make(ENV_ID, disturbances={"thermal_camber": 0.004}, **kw)
    flat.reset(seed=3)
    bowed.reset(seed=3)
    # the simulator's profile is the camber (no irregularity): zero on the piers,
    # a parabola between them
    irr = bowed.unwrapped.sim.irr
    n, dx = bowed.unwrapped.sim.profile_grid
    x = np.arange(n) * dx
    piers = np.isclose(np.mod(x, 30.0), 0.0)
    assert np.all(irr[0, piers] == 0.0) and irr[0].max() > 0.002
    assert np.all(flat.unwrapped.sim.irr == 0.0)
    act = np.zeros(4, np.float32)
    g_flat, g_bowed = [], []
    for _ in range(600):
        g_flat.append(flat.step(act)[4]["gap_excursion_m"])
        g_bowed.append(bowed.step(act)[4]["gap_excursion_m"])
    # the vehicle follows the slow part of the bows; the kinks at the piers excite it
    assert np.std(g_bowed) > 1.3 * np.std(g_flat)
    # the native vector env sees the same realisation (environment 0 with seed 3)
    venv = HyperloopSuspensionVectorEnv(2, disturbances={"thermal_camber": 0.004}, **kw)
    venv.reset(seed=3)
    np.testing.assert_array_equal(venv.sim.IRR[0], irr)
    cfg = EnvConfig(disturbances={"thermal_camber": 0.004}, **kw)
    assert cfg.resolve().disturbances[-1] == ThermalCamber(0.004)


def test_irregularity_and_roughness_together_is_an_error() -> None:
    with pytest.raises(ValueError, match="irregularity= or a 'roughness'"):
        EnvConfig(irregularity="none", disturbances={"roughness": 0.2})
