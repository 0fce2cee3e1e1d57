"""The package works from a wheel (issue 16): every data file the code reads is package
data, a missing one is an error naming it, and an installed wheel used outside the checkout
gives the checkout's actions (slow: builds the wheel and installs it into a fresh venv)."""

from __future__ import annotations

import glob
import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from agents import make_controller
from agents.controllers import learned, pid
from agents.controllers.registry import SHIPPED_FILES, learned_spec
from agents.evaluation import benchmark
from agents.training import presets

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("agents", "hyperloop_env")
SHIPPED_AGENTS = ("ppo", "ppo-guidance")


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def _package_data_files(spec: dict[str, list[str]] | None = None) -> set[Path]:
    """The files ``[tool.setuptools.package-data]`` puts into the wheel (setuptools globs
    each pattern relative to its package's directory, ``**`` recursive)."""
    if spec is None:
        spec = _pyproject()["tool"]["setuptools"]["package-data"]
    out: set[Path] = set()
    for pkg, patterns in spec.items():
        base = ROOT / pkg.replace(".", "/")
        for pat in patterns:
            for hit in glob.glob(pat, root_dir=base, recursive=True):
                if (base / hit).is_file():
                    out.add((base / hit).resolve())
    return out


def _files_read_by_the_code() -> list[Path]:
    """The data files the code opens at run time, named by the code's own constants."""
    from agents.evaluation.published import COMFORT_FILE, PUBLISHED_FILE

    files = [pid.GAINS_FILE, benchmark.SUITE_FILE, presets.PRESET_DIR / "defaults.json"]
    files += [PUBLISHED_FILE, COMFORT_FILE]
    files += sorted(presets.PRESET_DIR.glob("*.json"))
    for name in SHIPPED_AGENTS:
        folder = learned.shipped_path(learned_spec(name)[1])
        files += [folder / f for f in SHIPPED_FILES]
    return [Path(f).resolve() for f in files]


def _non_python_files() -> list[Path]:
    out = []
    for pkg in PACKAGES:
        for p in (ROOT / pkg).rglob("*"):
            if (
                p.is_file()
                and p.suffix not in (".py", ".pyc", ".nbi", ".nbc")
                and ("__pycache__" not in p.parts)
            ):
                out.append(p.resolve())
    return out


def test_every_data_file_read_by_the_code_is_package_data() -> None:
    covered = _package_data_files()
    read = _files_read_by_the_code()
    assert all(f.is_file() for f in read), [str(f) for f in read if not f.is_file()]
    missing = [str(f.relative_to(ROOT)) for f in read if f not in covered]
    assert not missing, f"read at run time but not package data: {missing}"
    # and no other file in the packages is left out of the wheel either
    left_out = [str(f.relative_to(ROOT)) for f in _non_python_files() if f not in covered]
    assert not left_out, f"files in the packages that the wheel would not contain: {left_out}"


def test_package_data_check_has_teeth() -> None:
    """Without the ``controllers/*.json`` glob the PID design would be left out."""
    spec = _pyproject()["tool"]["setuptools"]["package-data"]
    assert pid.GAINS_FILE.resolve() in _package_data_files(spec)
    fewer = {k: [p for p in v if not p.startswith("controllers/")] for k, v in spec.items()}
    assert pid.GAINS_FILE.resolve() not in _package_data_files(fewer)
    assert (ROOT / "agents" / "controllers" / "base.py").resolve() not in _package_data_files()


def test_missing_pid_design_is_an_error_naming_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    gone = tmp_path / "pid_gains.json"
    monkeypatch.setattr(pid, "GAINS_FILE", gone)
    with pytest.raises(FileNotFoundError, match="pid_gains.json"):
        make_controller("pid")
    # an explicit design needs no file
    assert make_controller("pid", design=pid.PIDDesign()).design == pid.PIDDesign()


def test_registry_pid_uses_the_stored_design() -> None:
    stored = json.loads(pid.GAINS_FILE.read_text())["design"]
    assert make_controller("pid").design == pid.PIDDesign(**stored)
    assert make_controller("pid").design != pid.PIDDesign()  # the defaults differ


@pytest.mark.parametrize("gone", ["vecnormalize.pkl", "training_log.json"])
def test_missing_shipped_agent_file_is_an_error_naming_it(
    gone: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    src = learned.shipped_path("ppo")
    (tmp_path / "ppo").mkdir()
    for f in SHIPPED_FILES:
        if f != gone:
            shutil.copy2(src / f, tmp_path / "ppo" / f)
    monkeypatch.setattr(learned, "SHIPPED_DIR", tmp_path)
    with pytest.raises(FileNotFoundError, match=gone):
        make_controller("ppo")
    if gone == "training_log.json":  # the benchmark reads the agent's actuator set there
        with pytest.raises(FileNotFoundError, match=gone):
            benchmark.learned_actuators("ppo")


# ---- the wheel, installed into a fresh venv, used outside the checkout (slow) ----------

PROBE = r"""
import json, sys
import numpy as np
import agents
from agents import make_controller
from agents.controllers import pid

data = json.loads(sys.stdin.read())
out = {"agents_file": agents.__file__, "gains_file": str(pid.GAINS_FILE), "actions": {}}
for name, key in (("pid", "lev"), ("lqr", "lev"), ("ppo", "lev"), ("ppo-guidance", "guided")):
    c = make_controller(name)
    c.reset()
    out["actions"][name] = [np.asarray(c.act(np.asarray(o)), float).tolist() for o in data[key]]
print(json.dumps(out))
"""


def _observations(actuators: str, n: int = 6) -> list[list[float]]:
    """Observations of a short run (passive actions), for feeding the controllers."""
    import gymnasium as gym

    from hyperloop_env import ENV_ID

    env = gym.make(ENV_ID, scenario="paper-1000-curved", actuators=actuators)
    obs, _ = env.reset(seed=3)
    out = []
    for _ in range(n):
        out.append(obs.astype(float).tolist())
        obs, *_ = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    env.close()
    return out


def _actions(data: dict) -> dict[str, list]:
    """The probe's computation in this (checkout) process."""
    res = {}
    for name, key in (("pid", "lev"), ("lqr", "lev"), ("ppo", "lev"), ("ppo-guidance", "guided")):
        c = make_controller(name)
        c.reset()
        res[name] = [np.asarray(c.act(np.asarray(o)), float).tolist() for o in data[key]]
    return res


def build_wheel_venv(tmp_path: Path) -> tuple[Path, Path]:
    """Build the wheel from a copy of the checkout (no build/ in the repo), install it with
    ``--no-deps`` into a fresh ``--system-site-packages`` venv; returns (venv python, wheel)."""
    src = tmp_path / "src"
    src.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "*.nbi", "*.nbc")
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, src / name)
    for pkg in PACKAGES:
        shutil.copytree(ROOT / pkg, src / pkg, ignore=ignore)
    dist = tmp_path / "dist"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(dist),
            str(src),
        ],
        check=True,
        cwd=src,
        timeout=300,
    )
    (wheel,) = dist.glob("*.whl")
    venv = tmp_path / "venv"
    subprocess.run(
        [sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(venv)],
        check=True,
        timeout=120,
    )
    py = venv / "bin" / "python"
    # the system pip (seen through --system-site-packages) installs into the venv
    subprocess.run(
        [str(py), "-m", "pip", "install", "--no-deps", "--force-reinstall", "-q", str(wheel)],
        check=True,
        timeout=300,
    )
    return py, wheel


def outside_env() -> dict[str, str]:
    """The environment for a process that must not see the checkout."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PYTHONNOUSERSITE"] = "1"
    return env


@pytest.fixture(scope="module")
def installed_wheel(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """(venv python, wheel, a working directory outside the checkout)."""
    tmp = tmp_path_factory.mktemp("wheel")
    py, wheel = build_wheel_venv(tmp)
    elsewhere = tmp / "elsewhere"
    elsewhere.mkdir()
    return py, wheel, elsewhere


@pytest.mark.slow
def test_installed_wheel_outside_the_checkout_gives_the_checkout_actions(
    installed_wheel: tuple[Path, Path, Path],
) -> None:
    pytest.importorskip("stable_baselines3")
    py, wheel, elsewhere = installed_wheel
    venv = py.parents[1]
    import zipfile

    names = set(zipfile.ZipFile(wheel).namelist())
    for f in _files_read_by_the_code():
        assert f.relative_to(ROOT).as_posix() in names, f"{f} not in the wheel"

    data = {"lev": _observations("levitation"), "guided": _observations("levitation+guidance")}
    want = _actions(data)
    r = subprocess.run(
        [str(py), "-c", PROBE],
        input=json.dumps(data),
        capture_output=True,
        text=True,
        cwd=elsewhere,
        env=outside_env(),
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout.strip().splitlines()[-1])
    site = Path(got["agents_file"]).resolve()
    assert venv.resolve() in site.parents, site  # the wheel, not the checkout
    assert venv.resolve() in Path(got["gains_file"]).resolve().parents
    for name, acts in want.items():
        np.testing.assert_allclose(got["actions"][name], acts, rtol=1e-6, atol=1e-7, err_msg=name)


# ---- console scripts, the name a tool was invoked by, outputs outside the package -----


def test_console_scripts_are_the_documented_ones_and_resolve() -> None:
    import importlib

    from agents.invocation import CONSOLE_SCRIPTS

    scripts = _pyproject()["project"]["scripts"]
    assert tuple(scripts) == CONSOLE_SCRIPTS
    assert scripts["hyperloop-train"] == "agents.cli.train:main"
    assert scripts["hyperloop-capacity"] == "agents.cli.capacity:main"
    for target in scripts.values():
        mod, func = target.split(":")
        assert callable(getattr(importlib.import_module(mod), func)), target


def test_invoked_prog(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import types

    from agents.invocation import command_line, invoked_args, invoked_prog

    def started(argv0: str, spec_name: str | None, file: str | None = None) -> str:
        main = types.ModuleType("__main__")
        main.__spec__ = types.SimpleNamespace(name=spec_name) if spec_name else None
        if file:
            main.__file__ = file
        monkeypatch.setitem(sys.modules, "__main__", main)
        monkeypatch.setattr(sys, "argv", [argv0, "--help"])
        return invoked_prog("dflt")

    assert started("/venv/bin/hyperloop-train", None) == "hyperloop-train"
    assert started("/x/agents/cli/train.py", "agents.cli.train") == "python -m agents.cli.train"
    # the hyperloop command names its subcommand; the arguments are the subcommand's
    assert started("/venv/bin/hyperloop", None) == "hyperloop"
    monkeypatch.setattr(sys, "argv", ["/venv/bin/hyperloop", "train", "--out", "r"])
    assert (invoked_prog("dflt"), invoked_args()) == ("hyperloop train", ["--out", "r"])
    monkeypatch.setattr(sys, "argv", ["/x/agents/cli/__main__.py", "train", "--resume"])
    main = types.ModuleType("__main__")
    main.__spec__ = types.SimpleNamespace(name="agents.cli.__main__")
    monkeypatch.setitem(sys.modules, "__main__", main)
    assert (invoked_prog("dflt"), invoked_args()) == ("python -m agents.cli train", ["--resume"])
    assert started("/x/agents/evaluate.py", "agents.evaluate") == "python -m agents.evaluate"
    script = tmp_path / "train.py"
    script.write_text("")
    assert started(str(script), None, str(script)) == "train.py"
    # started by something else (pytest, a notebook): the default
    assert started("/x/pytest/__main__.py", "pytest", "/x/pytest/__main__.py") == "dflt"
    assert started("/venv/bin/pytest", None, "/venv/bin/pytest") == "dflt"
    assert command_line("train.py", ["--out", "a b"]) == "python train.py --out 'a b'"
    assert command_line("hyperloop-train", ["--resume"]) == "hyperloop-train --resume"


@pytest.mark.parametrize(
    ("argv", "usage"),
    [
        (["-m", "agents.cli", "train"], "usage: hyperloop train "),
        (["train.py"], "usage: train.py "),
        (["-m", "agents.evaluate"], "usage: python -m agents.evaluate "),
    ],
)
def test_usage_names_the_command_it_was_invoked_by(argv: list[str], usage: str) -> None:
    r = subprocess.run(
        [sys.executable, *argv, "--help"], capture_output=True, text=True, cwd=ROOT, timeout=120
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(usage), r.stdout[:200]


def test_output_defaults_are_relative_to_the_working_directory() -> None:
    from agents.cli import benchmark, capacity, evaluate, fragility

    for cli in (evaluate, fragility, benchmark, capacity):
        parser = cli.build_parser()
        out = parser.get_default("out")
        assert not Path(out).is_absolute() and Path(out).parts[0] == "reports", out


def test_ship_into_an_installed_package_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("torch")
    from agents.cli import train as cli
    from agents.training import shipping

    assert shipping.source_checkout() == ROOT  # a checkout may ship
    assert shipping.check_ship_destination("ppo") == learned.shipped_path("ppo")
    installed = tmp_path / "site-packages" / "agents" / "shipped"
    installed.mkdir(parents=True)
    monkeypatch.setattr(learned, "SHIPPED_DIR", installed)
    assert shipping.source_checkout() is None
    with pytest.raises(SystemExit) as exc:
        cli.resolve_config(["--ship", "--no-eval", "--out", str(tmp_path / "run")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--ship" in err and "installed copy" in err and "pip install -e" in err
    assert not (tmp_path / "run").exists()
    with pytest.raises(shipping.ShipError, match="installed copy"):
        shipping.ship(tmp_path / "run", "ppo")
    assert not any(installed.iterdir())


@pytest.mark.slow
def test_installed_console_scripts(installed_wheel: tuple[Path, Path, Path]) -> None:
    """Each console script runs from outside the checkout and names itself in its usage
    (hyperloop-capacity's prog is fixed in agents/evaluation/capacity_benchmark.py);
    ``hyperloop-train --ship`` refuses to write into the installed package."""
    pytest.importorskip("torch")
    from agents.invocation import CONSOLE_SCRIPTS

    py, _, elsewhere = installed_wheel
    for name in CONSOLE_SCRIPTS:
        r = subprocess.run(
            [str(py.parent / name), "--help"],
            capture_output=True,
            text=True,
            cwd=elsewhere,
            env=outside_env(),
            timeout=300,
        )
        assert r.returncode == 0, (name, r.stderr)
        if name != "hyperloop-capacity":
            assert r.stdout.startswith(f"usage: {name} "), (name, r.stdout[:200])
    r = subprocess.run(
        [str(py.parent / "hyperloop-train"), "--ship", "--no-eval", "--out", "run"],
        capture_output=True,
        text=True,
        cwd=elsewhere,
        env=outside_env(),
        timeout=300,
    )
    assert r.returncode == 2, r.stderr
    assert "hyperloop-train: error: --ship" in r.stderr and "installed copy" in r.stderr
    assert not (elsewhere / "run").exists()


def test_resume_command_is_the_invoked_command() -> None:
    pytest.importorskip("torch")
    from agents.cli import train as cli

    # called from code (here: pytest) the tool's console-script name stands in
    assert cli._resume_command(["--out", "runs/a b", "--resume", "--seed", "3"]) == (
        "hyperloop-train --out 'runs/a b' --seed 3 --resume"
    )


# ---- metadata, extras, names that cannot be built -------------------------------------

TRAIN_HINT = 'pip install "hyperloop-suspension-gym[train]"'


def _req_name(req: str) -> str:
    import re

    return re.split(r"[\[<>=!~; ]", req, maxsplit=1)[0].lower().replace("_", "-")


def test_metadata() -> None:
    meta = _pyproject()
    project = meta["project"]
    assert project["license"] == "MIT" and project["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License") and (
        "Copyright (c) 2026 hyperloop-suspension-gym contributors" in text
    )
    assert not any(c.startswith("License ::") for c in project["classifiers"])  # SPDX only
    assert project["keywords"]
    assert "setuptools>=77" in meta["build-system"]["requires"]  # SPDX license-files
    # the gymnasium floor is what the code needs: AutoresetMode appeared in 1.1
    assert "gymnasium>=1.1" in project["dependencies"]
    assert "AutoresetMode" in (ROOT / "hyperloop_env" / "vector_env.py").read_text()
    # no requirement listed twice (the core dependencies are not repeated in an extra)
    core = {_req_name(r) for r in project["dependencies"]}
    for extra, reqs in project["optional-dependencies"].items():
        names = [_req_name(r) for r in reqs]
        assert len(names) == len(set(names)), extra
        assert not core & set(names), (extra, core & set(names))


def test_learned_controller_without_the_train_extra_names_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from agents.installation import MissingExtraError

    monkeypatch.setitem(sys.modules, "stable_baselines3", None)  # not installed
    with pytest.raises(MissingExtraError) as exc:
        make_controller("ppo")
    msg = str(exc.value)
    assert TRAIN_HINT in msg and "\n" not in msg
    assert isinstance(exc.value, ImportError)


def test_cli_without_the_train_extra_fails_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from agents.cli import evaluate as ev
    from agents.cli import train as cli

    monkeypatch.setitem(sys.modules, "stable_baselines3", None)
    with pytest.raises(SystemExit) as exc:
        ev.main(["--controllers", "pid", "ppo", "--out", str(tmp_path / "r"), "--no-progress"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert TRAIN_HINT in err[-1] and "controller 'ppo'" in err[-1]
    with pytest.raises(SystemExit) as exc:
        cli.main(["--no-eval", "--out", str(tmp_path / "run")])
    assert exc.value.code == 2
    assert TRAIN_HINT in capsys.readouterr().err
    assert not (tmp_path / "r").exists() and not (tmp_path / "run").exists()


def test_ray_backend_without_ray_names_the_extra(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from agents.cli import benchmark as benchmark_cli
    from agents.cli import fragility as fragility_cli

    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(SystemExit) as exc:
        fragility_cli.main(
            [
                "--controllers",
                "passive",
                "--levels",
                "0.1",
                "--backend",
                "ray",
                "--out",
                str(tmp_path / "f"),
                "--no-progress",
            ]
        )
    assert exc.value.code == 2
    assert 'pip install "hyperloop-suspension-gym[ray]"' in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        benchmark_cli.main(["--backend", "ray", "--out", str(tmp_path / "b"), "--no-progress"])
    assert exc.value.code == 2
    assert 'pip install "hyperloop-suspension-gym[ray]"' in capsys.readouterr().err


def test_a_controller_that_cannot_be_built_is_not_offered(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A learned entry without a shipped agent (here ``sac``, its folder hidden: a
    shipped-agents folder with the others only) stays in the registry (``path=`` a run)
    but the tools neither list it nor crash on it mid-run: one error line before any work."""
    from agents.cli import evaluate as ev
    from agents.cli import fragility as fragility_cli
    from agents.controllers.registry import (
        available_controllers,
        controller_problem,
        offered_controllers,
    )

    shipped = tmp_path / "shipped"
    shipped.mkdir()
    for d in learned.SHIPPED_DIR.iterdir():
        if d.is_dir() and d.name != "sac":
            (shipped / d.name).symlink_to(d)
    monkeypatch.setattr(learned, "SHIPPED_DIR", shipped)
    out = tmp_path / "out"
    out.mkdir()
    assert not (learned.shipped_path("sac") / "model.zip").exists()
    assert "sac" in available_controllers() and "sac" not in offered_controllers()
    assert {"passive", "pid", "lqr", "ppo", "ppo-guidance"} <= set(offered_controllers())
    assert controller_problem("sac", {"path": "runs/my-sac"}) is None
    assert "sac" not in ev.build_parser().format_help().split("--controllers")[1].split("--")[0]
    with pytest.raises(SystemExit) as exc:
        ev.main(["--controllers", "sac", "--out", str(out / "r"), "--no-progress"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "controller 'sac': no agent of it is shipped" in err[-1]
    with pytest.raises(SystemExit) as exc:
        fragility_cli.main(
            [
                "--controllers",
                "sac",
                "--levels",
                "0.1",
                "--out",
                str(out / "f"),
                "--no-progress",
            ]
        )
    assert exc.value.code == 2
    assert "no agent of it is shipped" in capsys.readouterr().err
    with pytest.raises(ValueError, match="entrant 'sac': controller 'sac': no agent"):
        benchmark.entrant_actuators("sac")
    assert not any(out.iterdir())


# ---- the environment id in a process that never imported the package -----------------

REMOTE = r"""
import sys
import gymnasium as gym

assert "hyperloop_env" not in sys.modules
env = gym.make("hyperloop_env:HyperloopSuspension-v0", scenario="paper-1000-straight")
obs, _ = env.reset(seed=0)
assert obs.shape == env.observation_space.shape
print("make", type(env.unwrapped).__module__)

if __name__ == "__main__":
    # spawned workers start from a fresh interpreter: they find the env through the spec's
    # entry point (a module path), not through this process's registry
    envs = gym.make_vec("hyperloop_env:HyperloopSuspension-v0", num_envs=2,
                        vectorization_mode="async", vector_kwargs={"context": "spawn"},
                        scenario="paper-1000-straight")
    obs, _ = envs.reset(seed=0)
    obs, *_ = envs.step(envs.action_space.sample() * 0)
    assert obs.shape == (2, *env.observation_space.shape)
    envs.close()
    print("make_vec async spawn", obs.shape)
"""


def test_entry_point_and_module_qualified_id_without_a_prior_import(tmp_path: Path) -> None:
    """Gymnasium 1.x loads no ``gymnasium.envs`` plugins, so the module-qualified id is the
    way for a process that never imported hyperloop_env; spawned async workers too."""
    import gymnasium.envs.registration as reg

    assert not hasattr(reg, "load_plugin_envs")  # removed in Gymnasium 1.0: no env plugins
    eps = _pyproject()["project"]["entry-points"]["gymnasium.envs"]
    assert eps == {"__root__": "hyperloop_env:register_envs"}
    script = tmp_path / "remote.py"
    script.write_text(REMOTE)
    env = outside_env()
    env["PYTHONPATH"] = str(ROOT)  # this checkout, not another copy on the path
    r = subprocess.run(
        [sys.executable, str(script)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert "make hyperloop_env.env" in r.stdout and "make_vec async spawn (2, " in r.stdout


@pytest.mark.slow
def test_installed_wheel_env_by_module_qualified_id(
    installed_wheel: tuple[Path, Path, Path],
) -> None:
    import zipfile

    py, wheel, elsewhere = installed_wheel
    eps = (
        zipfile.ZipFile(wheel)
        .read(next(n for n in zipfile.ZipFile(wheel).namelist() if n.endswith("entry_points.txt")))
        .decode()
    )
    assert "[gymnasium.envs]" in eps and "hyperloop-train = agents.cli.train:main" in eps
    script = elsewhere / "remote.py"
    script.write_text(REMOTE + "\nimport hyperloop_env; print('from', hyperloop_env.__file__)\n")
    r = subprocess.run(
        [str(py), str(script)],
        capture_output=True,
        text=True,
        cwd=elsewhere,
        env=outside_env(),
        timeout=600,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert "make_vec async spawn (2, " in r.stdout
    assert str(py.parents[1].resolve()) in r.stdout.split("from ")[-1]
