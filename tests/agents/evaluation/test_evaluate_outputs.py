"""The evaluation CLI's output folder: one run per folder, figures written atomically,
distinct figure files for controllers whose names give the same file name."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from agents.controllers import registry
from agents.evaluation.evaluate import evaluate, file_stem
from agents.evaluation.figures import (
    plot_capacities,
    plot_comparison,
    plot_fragility,
    plot_hist,
    plot_timeseries,
)
from agents.evaluation.metrics import summarise
from agents.evaluation.outputs import output_lock
from agents.evaluation.rollout import Episode, run_episodes

ROOT = Path(__file__).resolve().parents[3]

SHORT = [
    "--scenarios",
    "paper-2000-straight",
    "--distance-km",
    "0.2",
    "--seeds",
    "1",
    "--settle-s",
    "0.1",
    "--no-progress",
    "--n-boot",
    "10",
]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}


def _sigint_default() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _run_main(*args: str) -> subprocess.CompletedProcess[str]:
    code = "import sys; from agents.cli.evaluate import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run(
        [sys.executable, "-c", code, *args],
        cwd=ROOT,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_evaluate_refuses_a_folder_another_run_holds(tmp_path: Path) -> None:
    out = tmp_path / "out"
    with output_lock(out, "test"):
        proc = _run_main("--controllers", "passive", "--no-figures", *SHORT, "--out", str(out))
        assert proc.returncode == 2, proc.stderr
        assert str(out) in proc.stderr and "in use" in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr
        assert not (out / "results.json").exists()
        assert not (out / "report.md").exists()
    # once released, the same folder is used (and the lock file is gone afterwards)
    proc = _run_main("--controllers", "passive", "--no-figures", *SHORT, "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    assert (out / "results.json").is_file()
    assert not (out / ".lock").exists()


# --------------------------------------------------------------------------------------
# figures: written atomically (a failure mid-write leaves the old file or none)
# --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def episodes() -> list[Episode]:
    eps = run_episodes("passive", "paper-2000-straight", [1], 0.2)
    for e in eps:
        e.controller = "passive"
    return eps


class _FakeFit:
    status = "no data"

    def summary(self) -> str:
        return "no fit"

    def probability(self, s: object) -> np.ndarray:  # pragma: no cover - not drawn
        return np.zeros(np.shape(s))


def _fragility_result() -> dict[str, Any]:
    rows = [
        {
            "controller": "passive",
            "condition": "c",
            "level": lv,
            "p_contact": 0.5,
            "p_contact_ci": [0.1, 0.9],
        }
        for lv in (0.1, 0.2)
    ]
    settings = {
        "levels": [0.1, 0.2],
        "controllers": ["passive"],
        "family": "roughness",
        "severity_unit": "x",
        "seeds": [1, 2],
        "distance_km": 0.2,
        "interval": "exact",
    }
    fits = [{"controller": "passive", "condition": "c", "fit": _FakeFit()}]
    return {"settings": settings, "levels": rows, "fits": fits}


def _capacity_analysis() -> dict[str, Any]:
    cell = {"entrants": {"a": {"ecdf": {"x": [0.1, 0.2, 0.4], "F": [0.3, 0.6, 1.0]}}}}
    return {"c": {"roughness": cell}}


def _plotters(episodes: list[Episode]) -> dict[str, Callable[[Path], None]]:
    report, metrics, guidance = summarise(episodes, 0.1, 10)
    return {
        "hist": lambda p: plot_hist(report, episodes, 0.1, p),
        "hist_guidance": lambda p: plot_hist(guidance, episodes, 0.1, p, signal="guidance"),
        "timeseries": lambda p: plot_timeseries(episodes[0], p),
        "comparison": lambda p: plot_comparison([{"metrics": metrics}], p),
        "fragility": lambda p: plot_fragility(_fragility_result(), "c", p),
        "capacities": lambda p: plot_capacities(_capacity_analysis(), ["a"], p.parent),
    }


PLOTS = ("hist", "hist_guidance", "timeseries", "comparison", "fragility", "capacities")


def _target(tmp_path: Path, which: str) -> Path:
    return tmp_path / ("capacities_c.png" if which == "capacities" else f"{which}.png")


def _interrupt_savefig(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every ``Figure.savefig`` writes the file, truncates it to a few bytes (a write cut
    short) and is then interrupted."""
    from matplotlib.figure import Figure

    real = Figure.savefig

    def cut(self: Figure, fname: Any, *args: Any, **kwargs: Any) -> None:
        real(self, fname, *args, **kwargs)
        with open(fname, "r+b") as fh:
            fh.truncate(10)
        raise KeyboardInterrupt

    monkeypatch.setattr(Figure, "savefig", cut)


@pytest.mark.parametrize("which", PLOTS)
def test_a_figure_cut_short_leaves_the_old_file_intact(
    which: str, episodes: list[Episode], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = _target(tmp_path, which)
    plot = _plotters(episodes)[which]
    plot(target)
    old = target.read_bytes()
    assert old.startswith(b"\x89PNG")
    _interrupt_savefig(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        plot(target)
    assert target.read_bytes() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name]  # no temporary left


@pytest.mark.parametrize("which", PLOTS)
def test_a_figure_cut_short_leaves_no_file(
    which: str, episodes: list[Episode], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _interrupt_savefig(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        _plotters(episodes)[which](_target(tmp_path, which))
    assert list(tmp_path.iterdir()) == []


def test_every_figure_is_saved_by_the_one_atomic_helper() -> None:
    import inspect

    from agents.evaluation import figures

    src = inspect.getsource(figures)
    assert src.count(".savefig(") == 1
    assert 'format="png"' in inspect.getsource(figures.save_figure)


_SLOW_SAVE = """
import sys, time
from matplotlib.figure import Figure
from agents.cli.evaluate import main

real = Figure.savefig

def slow(self, fname, *args, **kwargs):
    with open(fname, "wb"):  # the file exists, empty, while the image is drawn
        pass
    print("saving", flush=True)
    time.sleep(120)
    real(self, fname, *args, **kwargs)

Figure.savefig = slow
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_while_a_figure_is_saved_leaves_no_partial_file(
    sig: signal.Signals, tmp_path: Path
) -> None:
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-c", _SLOW_SAVE, "--controllers", "passive", *SHORT, "--out", str(out)],
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_sigint_default,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.strip() == "saving", proc.stderr.read() if proc.stderr else ""
        proc.send_signal(sig)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode in (130, 143, -sig), proc.returncode
    left = [p.relative_to(out) for p in out.rglob("*") if not p.is_dir()] if out.exists() else []
    assert left == []  # no empty or partial PNG, no temporary file, the lock released


# --------------------------------------------------------------------------------------
# controllers whose names give the same file name
# --------------------------------------------------------------------------------------


def _register(monkeypatch: pytest.MonkeyPatch, *names: str) -> None:
    for n in names:
        spec = registry.ControllerSpec(n, "agents.controllers.factories:passive")
        monkeypatch.setitem(registry._REGISTRY, n, spec)


def _figures_by_controller(out: Path) -> dict[str, list[str]]:
    data = json.loads((out / "results.json").read_text())
    return {r["metrics"]["controller"]: r["figures"] for r in data["results"]}


def test_controllers_with_the_same_file_name_get_distinct_figures(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    names = ("/x/a/b", "/x/a_b")
    assert file_stem(names[0]) == file_stem(names[1])  # the clash this is about
    _register(monkeypatch, *names)
    kw = dict(settle_s=0.1, progress=False, n_boot=10)
    evaluate(list(names), ["paper-2000-straight"], 0.2, 1, "repelling", tmp_path / "a", **kw)
    figs = _figures_by_controller(tmp_path / "a")
    assert set(figs) == set(names)
    paths = [p for n in names for p in figs[n]]
    assert len(paths) == 6 and len(set(paths)) == 6  # three per controller, none shared
    assert all((tmp_path / "a" / p).is_file() for p in paths)
    assert len(list((tmp_path / "a" / "figures").glob("*.png"))) == 7  # and the comparison
    # deterministic: the same names give the same files, whatever their order
    evaluate(list(names[::-1]), ["paper-2000-straight"], 0.2, 1, "repelling", tmp_path / "b", **kw)
    again = _figures_by_controller(tmp_path / "b")
    for n in names:
        assert [Path(p).name for p in again[n]] == [Path(p).name for p in figs[n]]


def test_controller_file_stems_are_unique_and_stable() -> None:
    from agents.evaluation.evaluate import controller_file_stems

    names = ["/x/a/b", "/x/a_b", "pid", "PID", "lqr", "x_a_b"]
    stems = controller_file_stems(names)
    assert len({s.casefold() for s in stems.values()}) == len(names)
    assert stems["pid"] != stems["PID"]  # one file on a case-insensitive file system
    assert stems["lqr"] == "lqr"  # no clash: the plain name
    assert controller_file_stems(names[::-1]) == stems
    assert all(file_stem(s) == s for s in stems.values())  # still a file name
