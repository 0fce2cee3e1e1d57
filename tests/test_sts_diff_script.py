"""``scripts/sts_diff.py``: two tasks' level STS compared field by field."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _run(tmp_path: Path, a: dict, b: dict) -> subprocess.CompletedProcess[str]:
    pa, pb = tmp_path / "a.json", tmp_path / "b.json"
    pa.write_text(json.dumps(a))
    pb.write_text(json.dumps(b))
    cmd = [sys.executable, str(ROOT / "scripts" / "sts_diff.py"), str(pa), str(pb)]
    return subprocess.run(cmd, capture_output=True, text=True, check=False)


def test_a_changed_law_fails_and_p_differences_are_measured(tmp_path: Path) -> None:
    cell = {"gap": {"distribution": "t", "p_unsteady": 1e-4, "p_unsteady_ci": [1e-5, 2e-4]}}
    other = {"gap": {"distribution": "t", "p_unsteady": 1.002e-4, "p_unsteady_ci": [1e-5, 2e-4]}}
    same = _run(tmp_path, {"roughness": cell}, {"roughness": other})
    assert same.returncode == 0
    assert "differing: 1, largest relative difference 2.00e-03" in same.stdout
    assert "/roughness/gap/p_unsteady: 0.0001 vs 0.0001002" in same.stdout
    law = dict(other, gap=dict(other["gap"], distribution="skewnorm"))
    changed = _run(tmp_path, {"roughness": cell}, {"roughness": law})
    assert changed.returncode == 1
    assert "DIFFERS /roughness/gap/distribution: 't' vs 'skewnorm'" in changed.stdout
