"""The ``hyperloop`` command: its subcommands, the shared flags (one name, one default, one
help text wherever they appear), the one-way imports (no library module imports a command
module) and a user's ``module:factory`` found beside them as ``python -m`` finds it."""

from __future__ import annotations

import ast
import importlib
import os
import subprocess
import sys
from dataclasses import fields
from pathlib import Path

import pytest

from agents.cli import SUBCOMMANDS, main
from agents.evaluation.settings import PER_STUDY, Settings

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ("evaluate", "fragility", "benchmark", "capacity", "paper")


def test_help_lists_every_subcommand(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for name in ("evaluate", "fragility", "benchmark", "capacity", "paper", "headline"):
        assert f"\n  {name} " in out, name
    assert main(["no-such-thing"]) == 2
    assert "unknown subcommand 'no-such-thing'" in capsys.readouterr().err


def _actions(name: str) -> dict[str, object]:
    parser = importlib.import_module(f"agents.cli.{name}").build_parser()
    return {a.dest: a for a in parser._actions if a.dest != "help"}


def test_shared_flags_have_one_name_default_and_help() -> None:
    """Every setting that two subcommands share: the same flags, help and default (the
    per-study fields — seeds, distance, folder — the same flags and help)."""
    parsers = {name: _actions(name) for name in STUDIES}
    declared = {f.name for f in fields(Settings)}
    shared = 0
    for dest in declared:
        having = {n: p[dest] for n, p in parsers.items() if dest in p}
        if len(having) < 2:
            continue
        shared += 1
        first_name, first = next(iter(having.items()))
        for n, act in having.items():
            assert act.option_strings == first.option_strings, (dest, n, first_name)
            assert act.help == first.help, (dest, n, first_name)
            if dest not in PER_STUDY:
                assert act.default == first.default, (dest, n, first_name)
    assert shared >= 12
    for name in ("evaluate", "fragility", "capacity"):  # the three, all of them
        for dest in ("seed0", "seed_list", "allow_training_seeds", "distance_km", "out"):
            assert dest in parsers[name], (name, dest)


def test_a_shared_flag_is_declared_in_one_place() -> None:
    """No command module adds a settings flag by hand: each comes from add_settings."""
    import re

    flags = {f.metadata["flag"] for f in fields(Settings)}
    for path in (ROOT / "agents" / "cli").glob("*.py"):
        text = path.read_text()
        for flag in flags:
            assert not re.search(rf'add_argument\(\s*"{flag}"', text), (path.name, flag)


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
    return out


ALIASES = {"benchmark.py", "capacity.py", "evaluate.py", "fragility.py", "reproduce_paper.py"}
"""The ``python -m agents.<name>`` shims: thin aliases, allowed to import a command."""


def test_no_library_module_imports_a_command_module() -> None:
    for pkg in ("agents", "hyperloop_env"):
        for path in (ROOT / pkg).rglob("*.py"):
            rel = path.relative_to(ROOT)
            if rel.parts[:2] == ("agents", "cli") or (len(rel.parts) == 2 and rel.name in ALIASES):
                continue
            bad = {m for m in _imports(path) if m == "agents.cli" or m.startswith("agents.cli.")}
            assert not bad, f"{rel} imports the command module(s) {sorted(bad)}"


def test_every_subcommand_has_a_thin_module_with_help() -> None:
    for name, (module, desc) in SUBCOMMANDS.items():
        mod = importlib.import_module(module)
        assert callable(mod.main) and desc, name
        assert mod.build_parser(f"hyperloop {name}").prog == f"hyperloop {name}"


FACTORY = """
import numpy as np


class Zero:
    name = "zero"

    def __init__(self, ctx):
        self.n = ctx.actuators.size

    def reset(self, seed=None):
        pass

    def act(self, obs):
        return np.zeros(self.n, dtype=np.float32)


def make(ctx, **kw):
    return Zero(ctx)
"""

CONSOLE_SCRIPT = "import sys\nfrom agents.cli import main\nsys.exit(main())\n"
"""What pip writes as the ``hyperloop`` console script: started from its own folder, so
the user's folder is not on the import path unless the command puts it there."""


def test_a_console_command_imports_a_users_module_from_the_current_folder(
    tmp_path: Path,
) -> None:
    work = tmp_path / "work"
    (work / "mypkg").mkdir(parents=True)
    (work / "mypkg" / "__init__.py").write_text("")
    (work / "mypkg" / "mine.py").write_text(FACTORY)
    bindir = tmp_path / "bin"
    bindir.mkdir()
    (bindir / "hyperloop").write_text(CONSOLE_SCRIPT)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, str(bindir / "hyperloop"), "evaluate"]
    cmd += ["--controllers", "mypkg.mine:make", "--conditions", "paper-1000-straight"]
    cmd += ["--distance-km", "1.5", "--out", "r", "--no-progress", "--no-figures"]
    done = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert (work / "r" / "results.json").is_file()


def test_headline_forwards_its_shared_settings_to_capacity(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``hyperloop headline`` declares the capacity run's settings as every subcommand does
    (add_settings) and passes them on as given."""
    from agents.cli import capacity, headline

    seen: list[list[str]] = []
    monkeypatch.setattr(capacity, "main", lambda flags, prog: seen.append(flags) or 3)
    (tmp_path / "README.md").write_text("a checkout\n")
    argv = ["--seeds", "4", "--distance-km", "0.5", "--workers", "1", "--out", "o", "--resume"]
    assert headline.main([*argv, "--root", str(tmp_path)]) == 3  # capacity's code returned
    assert seen == [
        ["--out", "o", "--seeds", "4", "--distance-km", "0.5", "--workers", "1", "--resume"]
    ]
