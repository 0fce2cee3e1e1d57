"""Controller entry points for residual runs in their presets' run directories, so that the
command-line tools (which take controller names, not options) can fly them.

``hyperloop train --preset ppo-residual --no-eval`` writes ``runs/ppo-residual``; then
``hyperloop capacity --entrants lqr-preview agents.training.residual_runs:ppo_residual …``
flies it against its base law (the measurements of ``docs/benchmark/residual/``; its
README has the commands). Each factory is :func:`agents.controllers.residual.make_residual`
of ``RUNS[name]`` (relative to the working directory) with the run's name; ``path=``
replaces the directory. The variants' presets are in ``docs/benchmark/residual/presets/``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from agents.controllers.residual import ResidualController, make_residual

RUNS: dict[str, str] = {
    "ppo-residual": "runs/ppo-residual",
    "ppo-residual-guidance": "runs/ppo-residual-guidance",
    "ppo-residual-scale03": "runs/ppo-residual-scale03",
    "ppo-residual-scale03-gap60": "runs/ppo-residual-scale03-gap60",
    "ppo-residual-guidance-scale03": "runs/ppo-residual-guidance-scale03",
    "ppo-residual-scale05-memory": "runs/ppo-residual-scale05-memory",
    "ppo-residual-guidance-scale06": "runs/ppo-residual-guidance-scale06",
    "ppo-residual-guidance-scale06-rough2000": "runs/ppo-residual-guidance-scale06-rough2000",
    "ppo-residual-guidance-scale10": "runs/ppo-residual-guidance-scale10",
    "ppo-residual-guidance-priv": "runs/ppo-residual-guidance-priv",
}
"""Run name -> the run directory its preset writes (``out``)."""


def _factory(name: str) -> Any:
    def make(
        env_or_params: Any = None, path: str | Path | None = None, **kw: Any
    ) -> ResidualController:
        kw.setdefault("name", name)
        return make_residual(env_or_params, Path(path or RUNS[name]), **kw)

    make.__doc__ = f"The residual agent of ``{RUNS[name]}`` (or ``path=``), named {name!r}."
    return make


ppo_residual = _factory("ppo-residual")
ppo_residual_guidance = _factory("ppo-residual-guidance")
ppo_residual_scale03 = _factory("ppo-residual-scale03")
ppo_residual_scale03_gap60 = _factory("ppo-residual-scale03-gap60")
ppo_residual_guidance_scale03 = _factory("ppo-residual-guidance-scale03")
ppo_residual_scale05_memory = _factory("ppo-residual-scale05-memory")
ppo_residual_guidance_scale06 = _factory("ppo-residual-guidance-scale06")
ppo_residual_guidance_scale06_rough2000 = _factory("ppo-residual-guidance-scale06-rough2000")
ppo_residual_guidance_scale10 = _factory("ppo-residual-guidance-scale10")
ppo_residual_guidance_priv = _factory("ppo-residual-guidance-priv")
