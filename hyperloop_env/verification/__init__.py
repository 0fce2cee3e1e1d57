"""Verification of the simulator against analytical and independent numerical references.

Run ``hyperloop verify`` (alias ``python -m hyperloop_env.verification``; a table) or
``... --json`` (one JSON object keyed by case name). The exit code is 1 if any case fails,
except the cases listed in :data:`KNOWN_FAILURES` (documented physics bugs, reported as
XFAIL; one that starts to pass is an XPASS and fails the run until its entry is removed).
Every case is also a function returning a :class:`CaseResult`; :func:`run_all` runs them
all.

One job per module:

* :mod:`~hyperloop_env.verification.registry`: the cases by name (:data:`CASES`, with the
  description of every case in its docstring), :data:`KNOWN_FAILURES`, :func:`run_all`;
* the cases by topic: :mod:`~hyperloop_env.verification.beam` (span frequencies, static
  modal series, moving-force amplification), :mod:`~hyperloop_env.verification.guideway`
  (guideway through the production path), :mod:`~hyperloop_env.verification.equilibrium`
  (equilibrium, passive stability), :mod:`~hyperloop_env.verification.integrator` (RK4 vs
  Radau), :mod:`~hyperloop_env.verification.vehicle` (vehicle modes, curves, magnets) and
  :mod:`~hyperloop_env.verification.irregularity` (profile variance);
* :mod:`~hyperloop_env.verification.reference`: the independent references;
* :mod:`~hyperloop_env.verification.common`: :class:`CaseResult` and shared helpers;
* :mod:`~hyperloop_env.verification.report`: the table and the JSON object (:func:`render`);
* :mod:`~hyperloop_env.verification.cli`: the flags of ``hyperloop verify`` and its alias
  ``python -m hyperloop_env.verification`` (:func:`main`).

A new case: a function returning a :class:`CaseResult` in the topic module, an entry in
``registry.CASES`` and its description in the registry's docstring.
"""

from __future__ import annotations

from hyperloop_env.verification.beam import (
    BEAM_FREQ_TOL,
    BEAM_MODES,
    DAF_ALPHAS,
    DAF_LITERATURE,
    DAF_LITERATURE_TOL,
    beam_frequency,
    moving_force_daf,
    moving_force_daf_numerical,
    static_midspan_deflection,
    static_midspan_series,
)
from hyperloop_env.verification.cli import main
from hyperloop_env.verification.common import CaseResult
from hyperloop_env.verification.equilibrium import equilibrium_rigid, passive_stability
from hyperloop_env.verification.integrator import integrator_vs_radau, span_switch_times
from hyperloop_env.verification.irregularity import irregularity_variance, psd_band_integral
from hyperloop_env.verification.reference import fryba_daf
from hyperloop_env.verification.registry import (
    CASE_NAMES,
    CASES,
    KNOWN_FAILURES,
    all_verified,
    outcome,
    run_all,
)
from hyperloop_env.verification.report import format_table, render, results_json

__all__ = [
    "BEAM_FREQ_TOL",
    "BEAM_MODES",
    "CASES",
    "CASE_NAMES",
    "DAF_ALPHAS",
    "DAF_LITERATURE",
    "DAF_LITERATURE_TOL",
    "KNOWN_FAILURES",
    "CaseResult",
    "all_verified",
    "beam_frequency",
    "equilibrium_rigid",
    "format_table",
    "fryba_daf",
    "integrator_vs_radau",
    "irregularity_variance",
    "main",
    "moving_force_daf",
    "moving_force_daf_numerical",
    "outcome",
    "passive_stability",
    "psd_band_integral",
    "render",
    "results_json",
    "run_all",
    "span_switch_times",
    "static_midspan_deflection",
    "static_midspan_series",
]
