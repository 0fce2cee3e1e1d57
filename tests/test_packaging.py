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
from agents.controllers.registry import SHIPPED_FILES
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
    files = [pid.GAINS_FILE, benchmark.SUITE_FILE, presets.PRESET_DIR / "defaults.json"]
    files += sorted(presets.PRESET_DIR.glob("*.json"))
    for name in SHIPPED_AGENTS:
        folder = learned.shipped_path(learned.learned_spec(name)[1])
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
    for name, key in (("pid", "lev"), ("lqr", "lev"), ("ppo", "lev"),
                      ("ppo-guidance", "guided")):  # fmt: skip
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
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                    "-q", "-w", str(dist), str(src)], check=True, cwd=src, timeout=300)  # fmt: skip
    (wheel,) = dist.glob("*.whl")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip",
                    str(venv)], check=True, timeout=120)  # fmt: skip
    py = venv / "bin" / "python"
    # the system pip (seen through --system-site-packages) installs into the venv
    subprocess.run([str(py), "-m", "pip", "install", "--no-deps", "--force-reinstall", "-q",
                    str(wheel)], check=True, timeout=300)  # fmt: skip
    return py, wheel


def outside_env() -> dict[str, str]:
    """The environment for a process that must not see the checkout."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PYTHONNOUSERSITE"] = "1"
    return env


@pytest.mark.slow
def test_installed_wheel_outside_the_checkout_gives_the_checkout_actions(
    tmp_path: Path,
) -> None:
    pytest.importorskip("stable_baselines3")
    py, wheel = build_wheel_venv(tmp_path)
    import zipfile

    names = set(zipfile.ZipFile(wheel).namelist())
    for f in _files_read_by_the_code():
        assert f.relative_to(ROOT).as_posix() in names, f"{f} not in the wheel"

    data = {"lev": _observations("levitation"), "guided": _observations("levitation+guidance")}
    want = _actions(data)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    r = subprocess.run([str(py), "-c", PROBE], input=json.dumps(data), capture_output=True,
                       text=True, cwd=elsewhere, env=outside_env(), timeout=600)  # fmt: skip
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout.strip().splitlines()[-1])
    site = Path(got["agents_file"]).resolve()
    assert (tmp_path / "venv").resolve() in site.parents, site  # the wheel, not the checkout
    assert (tmp_path / "venv").resolve() in Path(got["gains_file"]).resolve().parents
    for name, acts in want.items():
        np.testing.assert_allclose(got["actions"][name], acts, rtol=1e-6, atol=1e-7,
                                   err_msg=name)  # fmt: skip
