"""The studies as a library: ``run(spec, settings) -> result`` for every study.

A study's **spec** says what it computes (which controllers, conditions, family, levels,
search settings — a typed, frozen dataclass checked by the study); the shared
:class:`~agents.evaluation.settings.Settings` say how and where (seeds, distance, workers,
backend, output folder, bootstrap sizes, …; declared once). :func:`run` dispatches on the
spec's type:

============================  ==============================================================
spec                          study
============================  ==============================================================
:class:`EvaluateSpec`         :func:`agents.evaluation.evaluate.evaluate`
:class:`FragilitySpec`        :func:`agents.evaluation.fragility.fragility`
:class:`BenchmarkSpec`        :func:`agents.evaluation.benchmark.run_benchmark`
:class:`CapacitySpec`         :func:`agents.evaluation.capacity_benchmark.run`
:class:`~agents.evaluation.reproduce_paper.PaperSpec`  :func:`agents.evaluation.reproduce_paper.run`
============================  ==============================================================

A field of :class:`Settings` left at None (``seeds``, ``distance_km``) takes the study's
own default (:data:`STUDY_DEFAULTS`). The ``hyperloop`` subcommands are these calls with a
parser in front (:mod:`agents.cli`).

>>> from agents.evaluation.settings import Settings
>>> from agents.evaluation.studies import EvaluateSpec, run
>>> res = run(EvaluateSpec(("passive",), ("paper-1000-straight",)),
...           Settings(distance_km=0.5, settle_s=0.1, out=None, progress=False))  # doctest: +SKIP
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from agents.evaluation import seeds as seeding
from agents.evaluation.settings import Settings

STUDY_DEFAULTS: dict[str, dict[str, Any]] = {
    "evaluate": {"seeds": 1, "distance_km": 10.0, "out": Path("reports")},
    "fragility": {"seeds": 10, "distance_km": 10.0, "out": Path("reports/fragility")},
    "benchmark": {"seeds": 8, "distance_km": 3.0, "out": Path("reports/benchmark")},
    "capacity": {"seeds": 32, "distance_km": 3.0, "out": Path("reports/capacity")},
    "paper": {"seeds": 1, "distance_km": 10.0, "out": Path("reports/paper")},
}
"""Each study's own number of seeds, distance per run [km] and output folder."""


@dataclass(frozen=True)
class EvaluateSpec:
    """Controllers on conditions: the paper's STS, RMS gaps, contacts, comfort."""

    controllers: tuple[str, ...]
    conditions: tuple[str, ...] = ("paper",)


@dataclass(frozen=True)
class FragilitySpec:
    """Contact probability against one family's severity levels (with ``fixed``
    disturbances held at their severity)."""

    controllers: tuple[str, ...]
    family: str
    levels: tuple[float, ...]
    conditions: tuple[str, ...] = ("paper-1000-straight",)
    fixed: dict[str, float] = field(default_factory=dict)
    interval: str = "exact"
    block_size: int | None = None
    max_samples: int | None = None
    max_block_mb: float | None = None
    batched: bool | None = None


@dataclass(frozen=True)
class BenchmarkSpec:
    """The suite's fragility grid for every entrant (``name+g``: with the guidance
    currents); ``families`` None: the whole suite."""

    entrants: tuple[str, ...]
    conditions: tuple[str, ...] = ("paper",)
    families: tuple[str, ...] | None = None
    suite: str | Path | dict[str, Any] | None = None


@dataclass(frozen=True)
class CapacitySpec:
    """Per-seed capacities of every entrant and the paired verdicts (the headline)."""

    entrants: tuple[str, ...]
    conditions: tuple[str, ...] = ("paper",)
    families: tuple[str, ...] = ("roughness", "pier_settlement", "thermal_camber")
    ratio: float | None = None
    step: float | None = None
    check_above: int | None = None
    rows: int | None = None
    entrant_seeds: dict[str, int] | None = None


def _seeds(st: Settings, study: str, min_n: int = 1) -> list[int]:
    n = st.seeds if st.seeds is not None else STUDY_DEFAULTS[study]["seeds"]
    return seeding.seed_list(n, st.seed0, st.seed_list, min_n=min_n)


def _distance(st: Settings, study: str) -> float:
    return st.distance_km if st.distance_km is not None else STUDY_DEFAULTS[study]["distance_km"]


def _given(**kw: Any) -> dict[str, Any]:
    """The keywords given (not None): the study's defaults stand for the others."""
    return {k: v for k, v in kw.items() if v is not None}


@functools.singledispatch
def run(spec: Any, settings: Settings, *, command: str | None = None) -> dict[str, Any]:
    """Run the study of ``spec`` with the shared ``settings`` (module docstring)."""
    raise TypeError(f"no study takes a {type(spec).__name__}; specs: {sorted(SPECS)}")


@run.register
def _(spec: EvaluateSpec, settings: Settings, *, command: str | None = None) -> dict[str, Any]:
    from agents.evaluation.evaluate import evaluate

    st = settings
    return evaluate(
        list(spec.controllers), list(spec.conditions), _distance(st, "evaluate"),
        _seeds(st, "evaluate"), st.magnet, st.out, st.settle_s, st.progress,
        env_kwargs={"actuators": st.actuators}, figures=st.figures, n_boot=st.n_boot,
        command=command, overwrite=st.overwrite, allow_training_seeds=st.allow_training_seeds,
        workers=st.workers,
    )  # fmt: skip


@run.register
def _(spec: FragilitySpec, settings: Settings, *, command: str | None = None) -> dict[str, Any]:
    from agents.evaluation.fragility import fragility

    st = settings
    return fragility(
        list(spec.controllers), list(spec.conditions), spec.family, list(spec.levels),
        _seeds(st, "fragility"), _distance(st, "fragility"),
        allow_training_seeds=st.allow_training_seeds, magnet=st.magnet,
        fixed=dict(spec.fixed), settle_s=st.settle_s, env_kwargs={"actuators": st.actuators},
        interval=spec.interval, n_boot=st.n_boot, n_boot_fragility=st.n_boot_fit,
        backend=st.backend, workers=st.workers, address=st.address, out_dir=st.out,
        overwrite=st.overwrite, figures=st.figures, progress=st.progress, command=command,
        batched=spec.batched,
        **_given(block_size=spec.block_size, max_samples=spec.max_samples,
                 max_block_mb=spec.max_block_mb),
    )  # fmt: skip


@run.register
def _(spec: BenchmarkSpec, settings: Settings, *, command: str | None = None) -> dict[str, Any]:
    from agents.evaluation.benchmark import entrant_actuators, run_benchmark

    st = settings
    seeds = _seeds(st, "benchmark", min_n=2)
    seeding.check_evaluation_seeds(
        [entrant_actuators(e)[0] for e in spec.entrants], seeds, st.allow_training_seeds
    )
    return run_benchmark(
        list(spec.entrants), list(spec.conditions),
        None if spec.families is None else list(spec.families), seeds,
        _distance(st, "benchmark"), allow_training_seeds=st.allow_training_seeds,
        suite=spec.suite, workers=st.workers, backend=st.backend, address=st.address,
        out_dir=st.out, overwrite=st.overwrite, resume=st.resume, figures=st.figures,
        progress=st.progress, n_boot=st.n_boot, n_boot_fragility=st.n_boot_fit,
        command=command,
    )  # fmt: skip


@run.register
def _(spec: CapacitySpec, settings: Settings, *, command: str | None = None) -> dict[str, Any]:
    from agents.evaluation import capacity_benchmark as cb

    st = settings
    return cb.run(
        list(spec.entrants), list(spec.conditions), list(spec.families),
        _seeds(st, "capacity", min_n=2), _distance(st, "capacity"), workers=st.workers,
        backend=st.backend, address=st.address, n_boot=st.n_boot_fit, out_dir=st.out,
        overwrite=st.overwrite, resume=st.resume,
        allow_training_seeds=st.allow_training_seeds, progress=st.progress,
        figures=st.figures, command=command, entrant_seeds=spec.entrant_seeds,
        **_given(ratio=spec.ratio, step=spec.step, check_above=spec.check_above,
                 rows=spec.rows),
    )  # fmt: skip


def _paper(spec: Any, settings: Settings, *, command: str | None = None) -> dict[str, Any]:
    from agents.evaluation import reproduce_paper as rp

    if settings.out is None:
        raise ValueError("the paper reproduction writes a report: give Settings.out")
    return rp.run(
        spec, settings.out, overwrite=settings.overwrite, progress=settings.progress,
        command=command, workers=settings.workers,
    )  # fmt: skip


def _register_paper() -> None:
    from agents.evaluation.reproduce_paper import PaperSpec

    run.register(PaperSpec)(_paper)


_register_paper()

SPECS = {
    "EvaluateSpec": EvaluateSpec,
    "FragilitySpec": FragilitySpec,
    "BenchmarkSpec": BenchmarkSpec,
    "CapacitySpec": CapacitySpec,
}
