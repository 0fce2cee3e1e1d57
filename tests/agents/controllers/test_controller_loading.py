"""Controllers that cannot be built, or that act wrongly: one clear error naming the
controller (and its file), never a traceback — in ``make_controller`` and in every
evaluation command-line tool (evaluate, fragility, benchmark, capacity)."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from agents.controllers import make_controller

ROOT = Path(__file__).resolve().parents[3]
MODULE = "loading_fixture_controllers"

FACTORIES = """
import numpy as np
from agents.controllers.factories import passive


def returns_none(env_or_params=None, **kw):
    return None


def raises(env_or_params=None, **kw):
    raise RuntimeError("the gains file is unreadable")


class _Wrap:
    def __init__(self, inner, fn):
        self.inner, self.fn, self.name = inner, fn, "wrapped"

    def reset(self, seed=None):
        self.inner.reset(seed)

    def act(self, obs):
        return self.fn(self.inner.act(obs))


class _Batched(_Wrap):
    def act_batch(self, obs):
        return np.stack([self.act(o) for o in obs])


def nan(env_or_params=None, **kw):
    return _Wrap(passive(env_or_params), lambda a: np.full_like(a, np.nan))


def nan_later(env_or_params=None, **kw):
    calls = []

    def f(a):
        calls.append(1)
        return a if len(calls) < 5 else np.full_like(a, np.nan)

    return _Wrap(passive(env_or_params), f)


def wide(env_or_params=None, **kw):
    return _Wrap(passive(env_or_params), lambda a: np.zeros(7, dtype=np.float32))


def nan_batch(env_or_params=None, **kw):
    return _Batched(passive(env_or_params), lambda a: np.full_like(a, np.nan))


def wide_batch(env_or_params=None, **kw):
    return _Batched(passive(env_or_params), lambda a: np.zeros(7, dtype=np.float32))
"""

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
    "--no-figures",
    "--n-boot",
    "10",
]


@pytest.fixture(scope="module")
def fixtures(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with the factories' module, a model.zip that is not a zip and an empty zip."""
    d = tmp_path_factory.mktemp("controllers")
    (d / f"{MODULE}.py").write_text(FACTORIES)
    (d / "text").mkdir()
    (d / "text" / "model.zip").write_text("not a zip\n")
    (d / "empty").mkdir()
    zipfile.ZipFile(d / "empty" / "model.zip", "w").close()
    return d


@pytest.fixture
def importable(fixtures: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    monkeypatch.syspath_prepend(str(fixtures))
    yield fixtures
    sys.modules.pop(MODULE, None)


def _evaluate(
    capsys: pytest.CaptureFixture[str], out: Path, controller: str, *extra: str
) -> tuple[int, str]:
    from agents.cli.evaluate import main

    try:
        code = main(["--controllers", controller, *SHORT, *extra, "--out", str(out)])
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


# --------------------------------------------------------------------------------------
# make_controller: one exception type naming the controller and the file
# --------------------------------------------------------------------------------------


def test_a_model_that_is_not_a_zip_is_a_controller_error(fixtures: Path) -> None:
    from agents.controllers.base import ControllerError

    model = fixtures / "text" / "model.zip"
    with pytest.raises(ControllerError, match="not a zip") as exc:
        make_controller(str(model))
    assert str(model) in str(exc.value)


def test_an_empty_zip_is_a_controller_error(fixtures: Path) -> None:
    from agents.controllers.base import ControllerError

    model = fixtures / "empty" / "model.zip"
    with pytest.raises(ControllerError) as exc:
        make_controller(str(model))
    assert str(model) in str(exc.value) and "no saved model" in str(exc.value)
    with pytest.raises(ControllerError, match="no saved model"):  # a run folder, or ppo path=
        make_controller("ppo", path=fixtures / "empty")


def test_a_factory_returning_no_controller_is_a_controller_error(importable: Path) -> None:
    from agents.controllers.base import ControllerError

    name = f"{MODULE}:returns_none"
    with pytest.raises(ControllerError, match=f"{name!r}.*returned None"):
        make_controller(name)


def test_a_factory_that_raises_is_a_controller_error_naming_it(importable: Path) -> None:
    from agents.controllers.base import ControllerError

    name = f"{MODULE}:raises"
    with pytest.raises(ControllerError, match=f"{name!r}.*the gains file is unreadable") as exc:
        make_controller(name)
    assert f"{MODULE}.py" in str(exc.value)  # the factory's file
    assert isinstance(exc.value.__cause__, RuntimeError)


def test_a_module_failing_on_import_is_a_controller_error_naming_its_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from agents.controllers.base import ControllerError
    from agents.controllers.registry import controller_problem

    mod = "loading_fixture_broken_on_import"
    (tmp_path / f"{mod}.py").write_text("raise RuntimeError('no config here')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, mod, raising=False)
    with pytest.raises(ControllerError, match=f"'{mod}:make'.*no config here") as exc:
        make_controller(f"{mod}:make")
    assert f"{mod}.py" in str(exc.value)
    assert "no config here" in (controller_problem(f"{mod}:make") or "")  # a CLI's check


def test_controller_errors_keep_their_kind_and_pickle() -> None:
    from agents.controllers.base import ControllerError

    with pytest.raises(TypeError) as bad_option:  # an option the factory does not take
        make_controller("mpc", None, horizon=10)
    assert isinstance(bad_option.value, ControllerError)
    assert "'mpc'" in str(bad_option.value)
    for exc in (ControllerError("controller 'x': broken"), bad_option.value):
        back = pickle.loads(pickle.dumps(exc))  # raised in a worker process, re-raised here
        assert type(back) is type(exc) and str(back) == str(exc)


def test_an_actuator_mismatch_is_a_controller_error() -> None:
    from agents.controllers.base import ControllerError, control_context
    from hyperloop_env.physics.params import ModelParams

    path = ROOT / "agents" / "shipped" / "ppo-guidance"
    with pytest.raises(ControllerError, match="acts on 8 currents.*has 4") as exc:
        make_controller(str(path), control_context(ModelParams()))
    assert "ppo-guidance" in str(exc.value)


# --------------------------------------------------------------------------------------
# actions: NaN or of the wrong shape, named with the controller and the step
# --------------------------------------------------------------------------------------


def test_checked_controller_names_the_step_and_the_shape(importable: Path) -> None:
    from agents.controllers.base import ControllerError, checked_controller, control_context

    ctrl = checked_controller(make_controller(f"{MODULE}:nan_later"), "mine", 4)
    ctrl.reset(seed=1)
    obs = np.zeros(control_context().observation.size, dtype=np.float32)
    for _ in range(4):
        assert ctrl.act(obs).shape == (4,)
    with pytest.raises(ControllerError, match=r"'mine'.*NaN.*control step 5"):
        ctrl.act(obs)
    wide = checked_controller(make_controller(f"{MODULE}:wide_batch"), "w", 4)
    wide.reset_batch(np.ones(2, dtype=bool))
    with pytest.raises(ControllerError, match=r"'w'.*shape \(2, 7\).*step 1.*\(2, 4\)"):
        wide.act_batch(np.zeros((2, obs.size), dtype=np.float32))


class _InfAtStep:
    """act_batch: zeros, then +inf in row 1 at its 3rd call (float32, C-contiguous: the
    checker's fast path)."""

    name = "inf-at-step"

    def __init__(self) -> None:
        self.calls = 0

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros(4, dtype=np.float32)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        self.calls += 1
        a = np.zeros((obs.shape[0], 4), dtype=np.float32)
        if self.calls == 3:
            a[1, 2] = np.inf
        return a


def test_checked_batch_names_an_infinite_action_its_row_and_its_step() -> None:
    from agents.controllers.base import ControllerError, checked_controller

    ctrl = checked_controller(_InfAtStep(), "inf", 4)
    obs = np.zeros((3, 23), dtype=np.float32)
    ctrl.reset_batch(np.ones(3, dtype=bool))
    a = ctrl.act_batch(obs)
    assert a.dtype == np.float32 and a.shape == (3, 4)
    ctrl.reset_batch(np.array([False, True, False]))  # row 1 starts anew after step 1
    ctrl.act_batch(obs)
    with pytest.raises(
        ControllerError, match=r"'inf'.*infinite.*control step 2 of its run \(row 1\)"
    ):
        ctrl.act_batch(obs)


def test_checked_batch_counts_steps_without_reset_batch() -> None:
    """A batch that no ``reset_batch`` sized: its rows count from the first ``act_batch``,
    and the count goes on across steps (the error at the third step names step 3)."""
    from agents.controllers.base import ControllerError, checked_controller

    ctrl = checked_controller(_InfAtStep(), "inf", 4)
    obs = np.zeros((2, 23), dtype=np.float32)
    ctrl.act_batch(obs)
    ctrl.act_batch(obs)
    with pytest.raises(
        ControllerError, match=r"'inf'.*infinite.*control step 3 of its run \(row 1\)"
    ):
        ctrl.act_batch(obs)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_all_finite_agrees_with_numpy_in_every_layout(dtype: type) -> None:
    """The compiled action check against ``np.isfinite(a).all()``: a bad value in the first,
    a middle and the last entry of C-contiguous, strided, transposed and 1-D arrays (the
    C-contiguous ones run the flat pass, the others the element-by-element one)."""
    from agents.controllers.base import all_finite

    base = np.arange(64 * 8, dtype=dtype).reshape(64, 8) / 7.0
    views = {
        "C": lambda a: a,
        "strided": lambda a: a[:, ::2],
        "rows": lambda a: a[::3],
        "F": lambda a: a.T,
        "1-D": lambda a: a[5],
        "one row": lambda a: a[5:6],
    }
    for layout, view in views.items():
        assert all_finite(view(base)) is True, layout
        for bad in (np.nan, np.inf, -np.inf):
            for pos in (0, view(base).size // 2, view(base).size - 1):
                a = view(base.copy())
                a[np.unravel_index(pos, a.shape)] = bad
                assert not np.isfinite(a).all()
                assert all_finite(a) is False, (layout, bad, pos)


# --------------------------------------------------------------------------------------
# evaluate: error: … and exit 2, never a traceback
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("case", "expect"),
    [
        ("text", ["not a zip"]),
        ("empty", ["no saved model"]),
        ("returns_none", ["returned None"]),
        ("raises", ["the gains file is unreadable", f"{MODULE}.py"]),
        ("nan", ["NaN", "control step 1"]),
        ("nan_batch", ["NaN", "control step 1"]),
        ("wide", ["shape (7,)", "control step 1", "(4,)"]),
        ("wide_batch", ["shape (1, 7)", "control step 1", "(1, 4)"]),
    ],
)
def test_evaluate_reports_a_broken_controller_in_one_line(
    case: str,
    expect: list[str],
    importable: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    if case in ("text", "empty"):
        controller = str(importable / case / "model.zip")
    else:
        controller = f"{MODULE}:{case}"
    code, err = _evaluate(capsys, tmp_path / "out", controller)
    assert code == 2, err
    assert "Traceback" not in err
    assert "error:" in err and repr(controller) in err, err
    for e in expect:
        assert e in err, err
    assert not (tmp_path / "out").exists()  # nothing written, no empty folder left


def test_evaluate_reports_an_actuator_mismatch_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, err = _evaluate(capsys, tmp_path / "out", "ppo-guidance")
    assert code == 2, err
    assert "'ppo-guidance'" in err and "acts on 8 currents" in err and "--actuators" in err


# --------------------------------------------------------------------------------------
# fragility, benchmark, capacity: the same errors, from their worker code
# --------------------------------------------------------------------------------------


def _cli(module: str, controller: str, out: Path, fixtures: Path) -> subprocess.CompletedProcess:
    args = {
        "agents.fragility": [
            "--controllers",
            controller,
            "--levels",
            "0.1",
            "0.2",
            "--seeds",
            "2",
            "--distance-km",
            "0.2",
            "--settle-s",
            "0.1",
            "--no-figures",
            "--no-progress",
            "--n-boot",
            "10",
            "--n-boot-fragility",
            "10",
        ],
        "agents.benchmark": [
            "--entrants",
            controller,
            "--seeds",
            "2",
            "--distance-km",
            "1",
            "--workers",
            "1",
            "--no-figures",
            "--no-progress",
        ],
        "agents.capacity": [
            "--entrants",
            controller,
            "--seeds",
            "2",
            "--distance-km",
            "0.2",
            "--workers",
            "1",
            "--no-figures",
            "--quiet",
        ],
    }[module]
    path = os.pathsep.join([str(fixtures), str(ROOT), os.environ.get("PYTHONPATH", "")])
    return subprocess.run(
        [sys.executable, "-m", module, *args, "--out", str(out)],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": path},
        capture_output=True,
        text=True,
        timeout=600,
    )


@pytest.mark.parametrize("module", ["agents.fragility", "agents.benchmark", "agents.capacity"])
@pytest.mark.parametrize("case", ["empty", "raises"])
def test_every_cli_reports_a_broken_controller_in_one_line(
    module: str, case: str, fixtures: Path, tmp_path: Path
) -> None:
    if case == "empty":
        controller = str(fixtures / "empty" / "model.zip")
        expect = "no saved model"
    else:
        controller = f"{MODULE}:raises"
        expect = "the gains file is unreadable"
    proc = _cli(module, controller, tmp_path / "out", fixtures)
    assert proc.returncode == 2, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert "error:" in proc.stderr and repr(controller) in proc.stderr, proc.stderr[-3000:]
    assert expect in proc.stderr, proc.stderr[-3000:]
