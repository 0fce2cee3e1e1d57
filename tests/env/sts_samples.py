"""Samples of the candidate laws the headline's level analyses select, shared by the STS
tests (``test_sts_compiled.py``, ``test_sts_newton.py``); not a test module."""

from __future__ import annotations

import numpy as np
from scipy import stats

# (law, parameters) as the headline's level analyses select them (standardised samples)
FIXTURES = [
    ("t", (15.5, -0.003, 0.93)),
    ("t", (4.0, 0.1, 0.8)),
    ("genextreme", (0.194, -0.396, 0.98)),
    ("genextreme", (-0.15, 0.2, 1.1)),
    ("skewnorm", (0.87, -0.61, 1.17)),
    ("skewnorm", (-4.0, 0.9, 1.4)),
]


def sample(name: str, params: tuple[float, ...], n: int = 20_000, seed: int = 7) -> np.ndarray:
    """``n`` draws of the law (seeded), standardised to mean 0 and standard deviation 1."""
    x = getattr(stats, name).rvs(*params, size=n, random_state=np.random.default_rng(seed))
    return (x - x.mean()) / x.std()
