"""The paper reproduction on several processes: the curve part's rows (radius sweep and
critical-radius bisections) are those of the serial functions, in their order, whatever the
number of workers; the output folder is held while a reproduction runs."""

from __future__ import annotations

from pathlib import Path

import pytest

from agents.evaluation import reproduce_paper as rp
from agents.evaluation.outputs import OutputLockError

ROOT = Path(__file__).resolve().parents[3]
SEED = 1_000_000  # the evaluation range


def test_curve_study_on_two_workers_gives_the_serial_rows_in_order() -> None:
    """Two spawned workers return the bisections and sweep runs in completion order;
    :func:`rp.curve_study` must put each back in its place: the rows equal the serial
    :func:`rp.radius_sweep` and :func:`rp.critical_radius` calls (the golden paper cases
    pin those), value for value."""
    spec = rp.PaperSpec(seeds=(SEED,), sweep_km=0.8, settle_s=0.2, bracket_rel=0.25)
    speeds = (1000.0, 2000.0)
    sweep_ref = rp.radius_sweep(rp.DEFAULT_RADII_M, speeds, 0.8, SEED, "repelling", 0.2)
    crit_ref = [
        rp.critical_radius(c, v, 0.8, SEED, "repelling", acts, rel_bracket=0.25)
        for c, acts in rp.CRITICAL_RADIUS_CASES
        for v in speeds
    ]
    sweep, crit = rp.curve_study(spec, SEED, workers=2)
    assert sweep == sweep_ref
    assert crit == crit_ref
    # the rows differ from one another, so a mixed-up order could not pass
    assert len({(r["speed_kmh"], r["radius_m"]) for r in sweep}) == len(sweep) == 14
    assert len({(c["controller"], c["actuators"], c["speed_kmh"]) for c in crit}) == len(crit)


def test_a_second_reproduction_into_a_held_folder_is_refused(tmp_path: Path, folder_holder) -> None:  # noqa: ANN001
    """Another process holding ``--out`` (a reproduction running there): refused before
    anything flies, naming the folder and the holder's pid; nothing written."""
    out = tmp_path / "paper"
    proc = folder_holder(out)
    with pytest.raises(OutputLockError, match=rf"{out}.*in use.*pid {proc.pid}"):
        rp.run(rp.PaperSpec(), out, progress=False)
    assert [p.name for p in out.iterdir()] == [".lock"]


@pytest.mark.parametrize("workers", [0, 1.5, True])
def test_a_bad_worker_count_is_refused_before_the_folder(tmp_path: Path, workers: object) -> None:
    with pytest.raises(ValueError, match="workers must be an int >= 1"):
        rp.run(rp.PaperSpec(), tmp_path / "paper", progress=False, workers=workers)  # type: ignore[arg-type]
    assert not (tmp_path / "paper").exists()
