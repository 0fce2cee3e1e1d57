"""The library tier: ``run(spec, settings)`` is the study itself — the same result as the
study's own function with the same values — and refuses what is not a study's spec."""

from __future__ import annotations

import pytest

from agents.evaluation import studies
from agents.evaluation.settings import Settings

SEEDS = (1_000_000, 1_000_001, 1_000_002)


def test_a_capacity_spec_runs_the_capacity_study() -> None:
    from agents.evaluation.capacity_benchmark import run

    spec = studies.CapacitySpec(
        ("passive", "pid"), ("paper-2000-straight",), ("roughness",), ratio=1.1
    )
    st = Settings(seed_list=SEEDS, distance_km=0.2, n_boot_fit=50, workers=1, progress=False)
    got = studies.run(spec, st)
    want = run(
        ["passive", "pid"], ["paper-2000-straight"], ["roughness"], seeds=list(SEEDS),
        distance_km=0.2, n_boot=50, progress=False, ratio=1.1,
    )  # fmt: skip
    assert got["capacities"] == want["capacities"]
    assert got["headline"]["verdicts"] == want["headline"]["verdicts"]


def test_a_study_default_stands_for_a_setting_left_at_none() -> None:
    st = Settings()
    assert studies._distance(st, "capacity") == 3.0 and studies._distance(st, "evaluate") == 10.0
    assert len(studies._seeds(st, "capacity", min_n=2)) == 32
    assert studies._seeds(Settings(seeds=2, seed0=7), "capacity", min_n=2) == [7, 8]


def test_what_is_not_a_spec_is_refused() -> None:
    with pytest.raises(TypeError, match="no study takes a dict"):
        studies.run({"entrants": ["pid"]}, Settings())


def test_settings_name_the_flag_of_a_bad_value() -> None:
    with pytest.raises(ValueError, match=r"--distance-km must be a finite number > 0"):
        Settings(distance_km=-1.0)
    with pytest.raises(ValueError, match="--workers must be an integer >= 1"):
        Settings(workers=0)
    with pytest.raises(ValueError, match="--address needs --backend ray"):
        Settings(address="auto")
    import numpy as np

    assert Settings(distance_km=np.float64(2.0)).distance_km == 2.0  # numbers are numbers
