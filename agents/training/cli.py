"""Command line of ``train.py``: arguments, presets, validation, and the main job.


Quick start (trains and evaluates in a few minutes on a 2-core CPU)::

    python train.py                               # PPO on the default scenario
    python train.py --preset shipped-ppo          # reproduces agents/shipped/ppo
    python train.py --algo sac --timesteps 200000 --out runs/my-sac
    python train.py --out runs/my-sac --resume    # continue from the last checkpoint
    tensorboard --logdir runs/

What it does:

1. builds ``--n-envs`` copies of ``HyperloopSuspension-v0`` (by default the native batched
   vector env through :class:`agents.training.sb3_adapter.GymnasiumVectorToSB3`;
   ``--vec dummy`` uses SB3's ``DummyVecEnv`` of single envs), wrapped in ``VecMonitor``
   and ``VecNormalize`` (observations and rewards normalised; statistics saved as
   ``vecnormalize.pkl``);
2. trains with an ``EvalCallback`` (best model -> ``<out>/best/``), a ``CheckpointCallback``
   (``<out>/checkpoints/``: model, VecNormalize statistics and the timestep count), a
   progress bar and TensorBoard logs (``<out>/tb/``);
3. saves ``<out>/model.zip``, ``<out>/vecnormalize.pkl`` and ``<out>/training_log.json``
   (command, preset, hyper-parameters, timesteps, seed, wall time, final eval reward);
4. unless ``--no-eval``: evaluates the trained agent and the baselines (passive, PID, LQR)
   on the four paper conditions with the STS suite (:mod:`agents.evaluate`) and writes the
   report (Markdown, JSON, CSV, figures) into ``<out>/report/``.

Options given on the command line override the preset's values; the preset overrides the
built-in defaults. ``--preset`` takes a name (``--list-presets``) or a JSON file (e.g.
``configs/*.json``) with the same keys.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import time
from pathlib import Path
from typing import Any

from agents.training.experiment import env_config, env_kwargs, evaluate_run, read_json, train
from agents.training.presets import ALGOS, DEFAULTS, PRESETS, VEC_MODES, load_preset
from agents.training.shipping import ship
from hyperloop_env.scenarios import SCENARIOS


def integer(s: str) -> int:
    return int(float(s)) if re.fullmatch(r"[+-]?\d+(\.\d*)?([eE][+-]?\d+)?", s) else int(s)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="train.py",
        description="Train a PPO/SAC suspension controller on HyperloopSuspension-v0 and "
        "evaluate it against passive, PID and LQR with the STS suite.",
        epilog="Presets: "
        + ", ".join(PRESETS)
        + ". Example: python train.py --preset shipped-ppo. Command-line options override "
        "the preset.",
    )
    a = p.add_argument
    a("--preset", help="named preset (see --list-presets) or a JSON file of options")
    a("--list-presets", action="store_true", help="print the presets and exit")
    a("--algo", help=f"{' | '.join(ALGOS)} (default {DEFAULTS['algo']})")
    a("--scenario", help=f"training scenario (default {DEFAULTS['scenario']!r})")
    a("--timesteps", type=integer, help="total env steps to train")
    a("--n-envs", type=int, help=f"parallel envs (default {DEFAULTS['n_envs']})")
    a("--seed", type=int, help="random seed (default 0)")
    a("--out", help="output directory (default runs/<algo>-<scenario>-<seed>)")
    a("--resume", action="store_true", help="continue from the last checkpoint in --out")
    a("--device", help="torch device: cpu (default), cuda, cuda:N, mps, auto")
    a("--eval-distance-km", type=float, help="track per scenario and seed in the final report")
    a("--eval-seeds", type=int, help="seeds per scenario in the final report (default 1)")
    a("--no-eval", action="store_true", help="skip the final STS evaluation")
    a(
        "--eval-only",
        action="store_true",
        help="no training: evaluate the agent already saved in --out (model.zip)",
    )
    a("--vec", choices=VEC_MODES, help="vector env: native (default), dummy, subproc")
    a("--track-length-m", type=float, help="track section per training episode [m]")
    a("--eval-freq", type=integer, help="env steps between EvalCallback runs")
    a("--checkpoint-freq", type=integer, help="env steps between checkpoints")
    a(
        "--env-kwarg",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="extra HyperloopSuspension-v0 keyword for training (repeatable), e.g. "
        "gap_weight=10, irregularity=maglev-rough",
    )
    a(
        "--ship",
        action="store_true",
        help="copy the result (model, VecNormalize stats, log, report) to agents/shipped/<algo>/",
    )
    a("--no-progress", action="store_true", help="no progress bar")
    a("--verbose", type=int, default=0, help="SB3 verbosity (0, 1, 2)")
    return p


def _load_preset(name: str | None, parser: argparse.ArgumentParser) -> dict[str, Any]:
    if name is None:
        return {}
    try:
        return load_preset(name)
    except ValueError as exc:
        parser.error(str(exc))
        raise AssertionError from None  # unreachable


def resolve_config(argv: list[str] | None = None) -> dict[str, Any]:
    """Parse and validate the command line; returns the merged configuration."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.list_presets:
        for name, values in PRESETS.items():
            print(f"{name}: {json.dumps(values)}")
        parser.exit(0)
    cfg = dict(DEFAULTS)
    cfg.update(_load_preset(args.preset, parser))
    for key in (
        "algo",
        "scenario",
        "timesteps",
        "n_envs",
        "seed",
        "out",
        "device",
        "eval_distance_km",
        "eval_seeds",
        "vec",
        "track_length_m",
        "eval_freq",
        "checkpoint_freq",
    ):
        value = getattr(args, key)
        if value is not None:
            cfg[key] = value
    if args.env_kwarg:
        cfg["env_kwargs"] = {
            **cfg.get("env_kwargs", {}),
            **_parse_env_kwargs(args.env_kwarg, parser),
        }
    cfg["preset"] = args.preset
    cfg["resume"] = args.resume
    cfg["no_eval"] = args.no_eval
    cfg["eval_only"] = args.eval_only
    cfg["ship"] = args.ship
    if args.eval_only and args.no_eval:
        parser.error("--eval-only and --no-eval exclude each other")
    cfg["progress_bar"] = not args.no_progress
    cfg["verbose"] = args.verbose
    _validate(cfg, parser)
    if cfg["out"] is None:
        cfg["out"] = f"runs/{cfg['algo']}-{cfg['scenario']}-{cfg['seed']}"
    return cfg


def _parse_env_kwargs(items: list[str], parser: argparse.ArgumentParser) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key.isidentifier():
            parser.error(f"--env-kwarg expects KEY=VALUE, got {item!r}")
        try:
            out[key] = json.loads(raw)
        except ValueError:
            out[key] = raw
    return out


def _validate(cfg: dict[str, Any], parser: argparse.ArgumentParser) -> None:
    cfg["algo"] = str(cfg["algo"]).lower()
    if cfg["algo"] not in ALGOS:
        parser.error(f"--algo must be one of {list(ALGOS)}, got {cfg['algo']!r}")
    if cfg["scenario"] not in SCENARIOS:
        parser.error(f"unknown --scenario {cfg['scenario']!r}; valid: {sorted(SCENARIOS)}")
    for key, lo in (("timesteps", 1), ("n_envs", 1), ("eval_seeds", 1)):
        v = cfg[key]
        if not isinstance(v, int) or isinstance(v, bool) or v < lo:
            parser.error(f"--{key.replace('_', '-')} must be an integer >= {lo}, got {v!r}")
    for key in ("eval_freq", "checkpoint_freq"):
        if not isinstance(cfg[key], int) or cfg[key] < 1:
            parser.error(f"--{key.replace('_', '-')} must be a positive integer, got {cfg[key]!r}")
    for key in ("eval_distance_km", "track_length_m"):
        v = cfg[key]
        if not isinstance(v, int | float) or not math.isfinite(v) or v <= 0:
            parser.error(f"--{key.replace('_', '-')} must be a positive number, got {v!r}")
    if cfg["vec"] not in VEC_MODES:
        parser.error(f"--vec must be one of {list(VEC_MODES)}, got {cfg['vec']!r}")
    cfg["device"] = _check_device(str(cfg["device"]), parser)
    try:  # fail fast on a bad --env-kwarg / preset env option
        env_config(cfg)
    except (TypeError, ValueError) as exc:
        parser.error(f"invalid environment options {env_kwargs(cfg)}: {exc}")


def _check_device(device: str, parser: argparse.ArgumentParser) -> str:
    import torch

    if device == "auto":
        return device
    try:
        dev = torch.device(device)
    except (RuntimeError, ValueError):
        parser.error(f"--device {device!r} is not a torch device (use cpu, cuda, cuda:0, mps)")
    if dev.type == "cuda" and not torch.cuda.is_available():
        parser.error(f"--device {device!r}: CUDA is not available on this machine (use cpu)")
    if dev.type == "mps" and not torch.backends.mps.is_available():
        parser.error(f"--device {device!r}: MPS is not available on this machine (use cpu)")
    if dev.type not in ("cpu", "cuda", "mps"):
        parser.error(f"--device {device!r}: unsupported device type (use cpu, cuda, mps)")
    return device



def main(argv: list[str] | None = None) -> int:
    cfg = resolve_config(argv)
    t0 = time.perf_counter()
    if cfg["eval_only"]:
        if not (Path(cfg["out"]) / "model.zip").exists():
            raise SystemExit(f"train.py: error: --eval-only: no model.zip in {cfg['out']}")
        log = read_json(Path(cfg["out"]) / "training_log.json") or {}
        cfg["algo"] = log.get("algo", cfg["algo"])  # evaluate what was trained
    else:
        train(cfg)
    if not cfg["no_eval"]:
        from agents.evaluation.report import summary_table

        res = evaluate_run(cfg)
        print(summary_table(res["results"]))
        paths = res["paths"]
        report = paths.get("md") or str(Path(cfg["out"]) / "report")
        print(f"STS report: {report}  (JSON, CSV and figures in {Path(cfg['out']) / 'report'})")
    if cfg["ship"]:
        dest = ship(Path(cfg["out"]), cfg["algo"])
        print(f"shipped to {dest}")
    print(f"total wall time {time.perf_counter() - t0:.0f} s; outputs in {cfg['out']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
