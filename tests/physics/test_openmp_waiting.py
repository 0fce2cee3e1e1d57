"""How numba's OpenMP threads wait between two parallel steps: the package sets passive
waiting after a short spin unless the user chose a policy (timing only; see
hyperloop_env/physics/__init__.py and speed/bench_threads.py)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

PROBE = (
    "import os, hyperloop_env.physics; "
    "print(os.environ.get('OMP_WAIT_POLICY'), os.environ.get('GOMP_SPINCOUNT'))"
)


def settings(**env: str) -> str:
    base = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    done = subprocess.run(
        [sys.executable, "-c", PROBE], env={**base, **env}, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


@pytest.mark.parametrize(
    ("given", "expected"),
    [
        ({}, "PASSIVE 100000"),
        ({"OMP_WAIT_POLICY": "ACTIVE"}, "ACTIVE None"),  # the user's policy, untouched
        ({"GOMP_SPINCOUNT": "1000"}, "PASSIVE 1000"),  # the user's spin count kept
    ],
)
def test_passive_after_a_short_spin_unless_the_user_chose(given, expected) -> None:
    assert settings(**given) == expected
