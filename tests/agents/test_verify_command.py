"""``hyperloop verify`` (agents.cli.verify) and its alias ``python -m
hyperloop_env.verification``: the same flags (declared once in the verification package),
the same output and the same exit status."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from agents.cli import main as hyperloop
from agents.cli import verify
from hyperloop_env import verification as v
from hyperloop_env.verification import cli as alias

ROOT = Path(__file__).resolve().parents[2]
CASE = "static_midspan_deflection"


def _flags(parser: object) -> list[tuple[tuple[str, ...], object, object]]:
    return [(a.option_strings, a.choices, a.help) for a in parser._actions]  # type: ignore[attr-defined]


def test_the_command_and_its_alias_have_the_same_flags() -> None:
    import argparse

    ap = argparse.ArgumentParser(allow_abbrev=False)
    alias.add_arguments(ap)
    assert _flags(verify.build_parser()) == _flags(ap)
    assert verify.build_parser().description == alias.DESCRIPTION
    assert not verify.build_parser().allow_abbrev


@pytest.mark.parametrize("fmt", [[], ["--json"], ["--markdown"]])
def test_the_command_prints_what_the_alias_prints(
    fmt: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert hyperloop(["verify", "--case", CASE, *fmt]) == 0
    ours = capsys.readouterr().out
    assert alias.main(["--case", CASE, *fmt]) == 0
    assert ours == capsys.readouterr().out
    if fmt == ["--json"]:
        assert json.loads(ours)[CASE]["passed"] is True
    assert CASE in ours


def test_a_failing_case_is_exit_status_1(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    failing = v.CaseResult(name=CASE, description="forced failure", passed=False, tolerance=0.0)
    monkeypatch.setitem(v.CASES, CASE, lambda: failing)
    assert verify.main(["--case", CASE]) == 1
    assert "FAIL" in capsys.readouterr().out
    monkeypatch.setitem(v.KNOWN_FAILURES, CASE, "a documented bug")
    assert verify.main(["--case", CASE, "--json"]) == 0  # a known failure that still fails
    assert json.loads(capsys.readouterr().out)[CASE]["outcome"] == "XFAIL"


def test_an_unknown_case_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        verify.main(["--case", "no_such_case"])
    assert exc.value.code == 2
    assert "hyperloop verify: error: argument --case" in capsys.readouterr().err


def test_the_alias_runs_as_a_module() -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    r = subprocess.run(
        [sys.executable, "-m", "hyperloop_env.verification", "--case", CASE, "--help"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("usage: python -m hyperloop_env.verification ")
