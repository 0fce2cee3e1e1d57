"""The numbers in results.json, summary.csv and sts_units.csv recomputed from the episodes.

``agents.evaluation.evaluate.evaluate`` runs a tiny case (passive and PID; a paper scenario
and the ``random`` one, whose seed 2 — 1262 km/h on the rough guideway — makes the passive
vehicle touch at 0.77 s while seed 1 flies: one failed episode of two); the same episodes
are run again through the public rollout API (deterministic by seed) and every reported
number is recomputed from their samples by the documented definitions, with numpy and
scipy only:

* RMS / max |gap|, per-unit RMS, mean / max |lateral|, RMS lateral, RMS ΔI (levitation and
  guidance) over all units and the post-settling samples (row 0 of an episode is the reset
  state, then ``ceil(settle_s/dt)`` samples are discarded);
* contacts: episodes ending in contact, the first contact time; per unit the entries into
  |s| ≥ Ω over the whole episode plus the terminal contact, attributed as documented
  (``hyperloop_env.sts.EpisodeSignal``);
* per unit: sample size, mean and std of the fitted normal (``scipy.stats.norm.fit``), the
  fitted law's P(|s| ≥ Ω) (scipy's sf + cdf of the reported law) and
  P(unsteady) = f + (1 − f)·P_fit with f the fraction of failed episodes; the empirical
  exceedance.
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from scipy import stats

from agents import make_controller
from agents.evaluation.evaluate import evaluate
from agents.evaluation.rollout import run_episode
from hyperloop_env.comfort import ride_comfort

CONTROLLERS = ("passive", "pid")
SCENARIOS = ("paper-1000-straight", "random")
DISTANCE_KM = 0.6
SEEDS = [1, 2]
SETTLE_S = 0.2
UNITS = ("FL", "FR", "RL", "RR")


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory: pytest.TempPathFactory) -> dict:
    out = tmp_path_factory.mktemp("eval")
    evaluate(
        list(CONTROLLERS),
        list(SCENARIOS),
        DISTANCE_KM,
        SEEDS,
        "repelling",
        out,
        settle_s=SETTLE_S,
        progress=False,
        figures=False,
        n_boot=20,
    )
    episodes = {
        (c, sc): [
            run_episode(lambda env, c=c: make_controller(c, env), sc, seed, DISTANCE_KM)
            for seed in SEEDS
        ]
        for c in CONTROLLERS
        for sc in SCENARIOS
    }
    with (out / "summary.csv").open() as fh:
        summary = {(r["controller"], r["condition"]): r for r in csv.DictReader(fh)}
    with (out / "sts_units.csv").open() as fh:
        units = {
            (r["controller"], r["condition"], r["signal"], r["unit"]): r for r in csv.DictReader(fh)
        }
    results = json.loads((out / "results.json").read_text())
    by_case = {
        (r["metrics"]["controller"], r["metrics"]["condition"]): r for r in results["results"]
    }
    return {
        "out": out,
        "episodes": episodes,
        "summary": summary,
        "units": units,
        "json": by_case,
        "settings": results["settings"],
    }


def _n0(dt: float) -> int:
    return int(math.ceil(SETTLE_S / dt - 1e-9))


def _f(x: str) -> float:
    return math.nan if x in ("", "None") else float(x)


def _close(got: float | None, want: float, rel: float = 1e-9, what: str = "") -> None:
    if want is None or (isinstance(want, float) and math.isnan(want)):
        assert got is None or (isinstance(got, float) and math.isnan(got)), what
        return
    assert got is not None, what
    assert got == pytest.approx(want, rel=rel, abs=1e-300), what


def test_the_case_covers_contact_and_no_contact(evaluated: dict) -> None:
    eps = evaluated["episodes"]
    assert not any(e.terminated for e in eps[("pid", "paper-1000-straight")])
    assert [e.terminated for e in eps[("passive", "random")]] == [False, True]
    assert evaluated["settings"]["seeds"] == SEEDS
    assert evaluated["settings"]["distance_km"] == DISTANCE_KM


@pytest.mark.parametrize("case", [(c, s) for c in CONTROLLERS for s in SCENARIOS])
def test_scalar_metrics_recomputed(evaluated: dict, case: tuple[str, str]) -> None:
    eps = evaluated["episodes"][case]
    dt = eps[0].dt_s
    n0 = _n0(dt)
    gap = np.concatenate([e.gap_m[1 + n0 :] for e in eps])
    lat = np.concatenate([e.lateral_m[1 + n0 :] for e in eps])
    cur = np.concatenate([e.current_A[1 + n0 :] - e.nominal_current_A for e in eps])
    gcur = np.concatenate([e.guidance_current_A[1 + n0 :] for e in eps])
    failed = [e for e in eps if e.terminated]
    want = {
        "rms_gap_mm": math.sqrt(float(np.mean(gap**2))) * 1e3,
        "max_abs_gap_mm": float(np.max(np.abs(gap))) * 1e3,
        "mean_lateral_mm": float(np.mean(lat)) * 1e3,
        "max_abs_lateral_mm": float(np.max(np.abs(lat))) * 1e3,
        "rms_lateral_mm": math.sqrt(float(np.mean(lat**2))) * 1e3,
        "rms_current_dev_A": math.sqrt(float(np.mean(cur**2))),
        "rms_guidance_current_A": math.sqrt(float(np.mean(gcur**2))),
        "n_contact_episodes": len(failed),
        "n_episodes": len(SEEDS),
        "steps_total": sum(len(e.time_s) - 1 for e in eps),
        "time_to_first_contact_s": min(e.time_s[-1] for e in failed) if failed else None,
    }
    comfort = [ride_comfort(e.acc_m_s2[1:, 0], e.acc_m_s2[1:, 1], dt, SETTLE_S) for e in eps]
    want["a_wz_m_s2"] = float(np.mean([c.a_wz_m_s2 for c in comfort]))
    want["a_wy_m_s2"] = float(np.mean([c.a_wy_m_s2 for c in comfort]))
    m = evaluated["json"][case]["metrics"]
    row = evaluated["summary"][case]
    units_rms = np.sqrt(np.mean(gap**2, axis=0)) * 1e3
    np.testing.assert_allclose(m["rms_gap_units_mm"], units_rms, rtol=1e-9)
    for k, v in want.items():
        if v is None:
            assert m[k] is None and row[k] == "", k
        elif isinstance(v, int):
            assert m[k] == v and int(row[k]) == v, k
        else:
            _close(m[k], v, what=f"results.json {k}")
            _close(_f(row[k]), v, what=f"summary.csv {k}")
    if failed:
        assert m["contact_kind"] == "gap" and row["contact_kind"] == "gap"
        np.testing.assert_allclose(
            sorted(m["contact_times_s"]), sorted(e.time_s[-1] for e in failed), rtol=1e-12
        )
    # the report's summary table shows the same RMS (3 decimals)
    md = (evaluated["out"] / "report.md").read_text()
    assert f"| {case[0]} | {case[1]} |" in md
    assert f"{want['rms_gap_mm']:.3f}" in md


def _contacts(sig: np.ndarray, omega: float, terminal: bool) -> int:
    """Entries into |s| ≥ Ω, plus the terminal contact unless the last sample is inside."""
    inside = np.abs(sig) >= omega
    entries = int(np.sum(inside & ~np.concatenate(([False], inside[:-1]))))
    return entries + int(terminal and not (len(sig) and inside[-1]))


@pytest.mark.parametrize("case", [(c, s) for c in CONTROLLERS for s in SCENARIOS])
@pytest.mark.parametrize("signal", ["levitation_gap", "guidance_gap"])
def test_per_unit_sts_recomputed(evaluated: dict, case: tuple[str, str], signal: str) -> None:
    eps = evaluated["episodes"][case]
    dt = eps[0].dt_s
    n0 = _n0(dt)
    omega = eps[0].clearance_m if signal == "levitation_gap" else eps[0].lateral_clearance_m
    assert omega == 0.008
    sigs = [(e.gap_m if signal == "levitation_gap" else e.lateral_m)[1:] for e in eps]
    f = sum(e.terminated for e in eps) / len(eps)
    key = "sts" if signal == "levitation_gap" else "sts_guidance"
    js_units = {u["name"]: u for u in evaluated["json"][case][key]["units"]}
    worst = 0.0
    for a, name in enumerate(UNITS):
        x = np.concatenate([s[n0:, a] for s in sigs])
        mu, sd = stats.norm.fit(x)  # MLE: mean and the ddof=0 std
        n_contacts = 0
        for e, s in zip(eps, sigs, strict=True):
            culprit = False
            if e.terminated:  # documented attribution of the terminal contact
                last = np.abs(s[-1])
                hit = np.flatnonzero(last >= omega)
                culprit = a in (hit if hit.size else np.flatnonzero(last == last.max()))
            n_contacts += _contacts(s[:, a], omega, culprit)
        row = evaluated["units"][(case[0], case[1], signal, name)]
        ju = js_units[name]
        assert int(row["n_samples"]) == ju["n_samples"] == x.size, name
        assert int(row["n_contacts"]) == ju["n_contacts"] == n_contacts, name
        assert int(row["n_failed_episodes"]) == sum(e.terminated for e in eps)
        _close(_f(row["mean_mm"]), mu * 1e3, what=f"{name} mean_mm")
        _close(_f(row["std_mm"]), sd * 1e3, what=f"{name} std_mm")
        _close(ju["mean_m"], mu, what=f"{name} mean_m")
        _close(ju["std_m"], sd, what=f"{name} std_m")
        exceed = float(np.mean(np.abs(x) >= omega))
        _close(_f(row["empirical_exceedance"]), exceed, what=f"{name} exceedance")
        # the fitted law's tail probability, from scipy and the reported law
        dist = ju["distribution"]
        assert row["distribution"] == dist
        if dist == "norm":
            p_fit = stats.norm.sf(omega, mu, sd) + stats.norm.cdf(-omega, mu, sd)
            np.testing.assert_allclose(ju["distribution_params"], [mu, sd], rtol=1e-9)
        else:
            law = getattr(stats, dist)
            pars = ju["distribution_params"]
            p_fit = law.sf(omega, *pars) + law.cdf(-omega, *pars)
        p_un = f + (1.0 - f) * p_fit
        _close(ju["p_unsteady_fit"], p_fit, rel=1e-6, what=f"{name} p_unsteady_fit")
        _close(_f(row["p_unsteady_fit"]), p_fit, rel=1e-6, what=f"{name} csv p_unsteady_fit")
        _close(ju["p_unsteady"], p_un, rel=1e-6, what=f"{name} p_unsteady")
        _close(_f(row["p_unsteady"]), p_un, rel=1e-6, what=f"{name} csv p_unsteady")
        _close(_f(row["p_steady"]), 1.0 - p_un, rel=1e-6, what=f"{name} p_steady")
        if f == 1.0:
            assert ju["p_unsteady"] == 1.0 and ju["p_unsteady_ci"] == [1.0, 1.0]
        lo, hi = _f(row["p_unsteady_ci_lo"]), _f(row["p_unsteady_ci_hi"])
        assert lo <= hi, name
        worst = max(worst, p_un)
    m = evaluated["json"][case]["metrics"]
    summ = evaluated["summary"][case]
    wkey = "p_unsteady" if signal == "levitation_gap" else "p_unsteady_guidance"
    _close(m[wkey], worst, rel=1e-6, what=wkey)
    _close(_f(summ[wkey]), worst, rel=1e-6, what=f"csv {wkey}")


def _csv_value(raw: str) -> object:
    if raw == "":
        return None
    if raw in ("True", "False"):
        return raw == "True"
    try:
        return float(raw)
    except ValueError:
        return raw


@pytest.mark.parametrize("signal", ["levitation_gap", "guidance_gap"])
def test_sts_units_csv_is_the_json_report(evaluated: dict, signal: str) -> None:
    """Every column of sts_units.csv equals the unit's entry of results.json (mm columns
    ×1e3 of the metre values, the CI columns the interval's ends), for every case."""
    key = "sts" if signal == "levitation_gap" else "sts_guidance"
    renamed = {"mean_mm": ("mean_m", 1e3), "std_mm": ("std_m", 1e3)}
    n = 0
    for case, res in evaluated["json"].items():
        for ju in res[key]["units"]:
            row = evaluated["units"][(case[0], case[1], signal, ju["name"])]
            for col, raw in row.items():
                if col in ("controller", "condition", "magnet", "signal"):
                    continue
                got = _csv_value(raw)
                if col == "unit":
                    want = ju["name"]
                elif col in renamed:
                    want = None if ju[renamed[col][0]] is None else ju[renamed[col][0]] * 1e3
                elif col in ("p_unsteady_ci_lo", "p_unsteady_ci_hi"):
                    want = ju["p_unsteady_ci"][0 if col.endswith("lo") else 1]
                else:
                    want = ju[col]
                if isinstance(want, float) and isinstance(got, float):
                    assert got == pytest.approx(want, rel=1e-12, abs=1e-300), (case, col)
                else:
                    assert got == want, (case, ju["name"], col, raw, want)
                n += 1
    assert n > 100
    # the intervals are real intervals somewhere (a lo/hi mix-up would not pass unnoticed)
    cis = [u["p_unsteady_ci"] for r in evaluated["json"].values() for u in r[key]["units"]]
    assert any(lo < hi for lo, hi in cis if lo is not None and hi is not None)
