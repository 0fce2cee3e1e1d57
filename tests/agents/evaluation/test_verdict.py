"""The main job's verdict and comparison figure (issue 16, point 8)."""

from __future__ import annotations

from agents.evaluation.report import plot_comparison, verdict


def _m(ctrl: str, sc: str, rms: float, contacts: int = 0) -> dict:
    return {
        "metrics": {
            "controller": ctrl,
            "condition": sc,
            "rms_gap_mm": rms,
            "n_contact_episodes": contacts,
            "n_episodes": 1,
        }
    }


def test_verdict_names_the_best_controller_with_the_numbers(tmp_path) -> None:  # noqa: ANN001
    res = [
        _m("pid", "a", 0.70),
        _m("pid", "b", 0.74),
        _m("lqr", "a", 0.46),
        _m("lqr", "b", 0.55),
        _m("runs/x", "a", 0.30, contacts=1),
        _m("runs/x", "b", 0.3),
    ]
    text = verdict(res, 2.0, 1)
    first = text.splitlines()[0]
    assert first.startswith("Verdict: lqr held the gap best")  # contacts rank first
    assert "lqr 0.505 mm; pid 0.720 mm; runs/x 0.300 mm (1/2 runs touched)" in first
    assert "Contacts: 1 of 6 runs touched" in text
    assert "1 seed(s) × 2 km" in text and "(one seed)" in text
    assert "hyperloop capacity" in text
    p = plot_comparison(res, tmp_path / "c.png")
    assert p.stat().st_size > 5000
