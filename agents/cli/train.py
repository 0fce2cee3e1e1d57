"""``hyperloop train``: arguments, presets, validation, and the main job
(:mod:`agents.training.experiment`).

``python train.py`` (in a checkout) and the console script ``hyperloop-train`` are aliases
of it; outputs go under the current directory (``runs/``).


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
2. trains with an ``EvalCallback`` (best model -> ``<out>/best/``), resumable checkpoints
   (``<out>/checkpoints/``: model, VecNormalize statistics, step count, random state and the
   run's configuration; :mod:`agents.training.checkpoints`), a progress bar and TensorBoard
   logs (``<out>/tb/``);
3. saves ``<out>/model.zip``, ``<out>/vecnormalize.pkl`` and ``<out>/training_log.json``
   (command, preset, hyper-parameters, timesteps, seed, wall time, final eval reward);
4. unless ``--no-eval``: evaluates the trained agent and the baselines (passive, PID, LQR)
   on the four paper conditions with the STS suite (:mod:`agents.evaluate`) and writes the
   report (Markdown, JSON, CSV, figures) into ``<out>/report/``.

Options given on the command line override the preset's values; the preset overrides the
built-in defaults. ``--preset`` takes a name (``--list-presets``) or a JSON file (e.g.
``configs/*.json``) with the same keys; without it the preset is ``default``, which
overlaps PPO's updates with its rollouts on a second process (``--no-overlap-updates``:
plain Stable-Baselines3 PPO; :mod:`agents.training.overlap`).

Seeds: every seed a run uses (its envs from ``--seed``, its evaluation envs from
``--seed`` + 10 000, the re-seed of a resumed run) lies in the training range
[0, 99 999], apart from the evaluation seeds (from 1 000 000); a ``--seed`` that would leave
it is refused (:mod:`agents.training.seeding`), and the training log records them
(``training_seeds``).

No lost or mixed work:

* **Checkpoints** are written every ``--checkpoint-freq`` env steps (default 250 000) or
  every ``--checkpoint-interval-s`` seconds of wall time (default 300: a hard kill loses at
  most about five minutes), at the end, and on Ctrl-C / SIGTERM: the run stops at the next
  step, saves a checkpoint and exits with status 130 (143 for SIGTERM); ``--resume``
  continues from it. Each file is written atomically and listed with its SHA-256 in the
  checkpoint's manifest; a damaged newest checkpoint is skipped with a warning and the
  next older one is used.
* **One run per directory**: a run holds ``<out>/.lock`` (an exclusive ``flock`` with its
  pid) until it has trained, evaluated and shipped; a second ``train.py`` on the same
  ``--out`` (new, ``--resume`` or ``--eval-only``) is refused naming the directory and
  that pid. A new run refuses an ``--out`` that already holds files
  (pass ``--overwrite`` to delete that run's files first, or ``--resume`` to continue it);
  ``--resume`` refuses a checkpoint from another configuration (algorithm, scenario,
  environment options, hyper-parameters, number and kind of envs, seed); ``--timesteps``
  and the evaluation/checkpoint settings may change.
* Every option is checked before anything is created (``--timesteps 1.9`` or
  ``--seed -1`` are errors, not 1 and a crash), and so is every key of the preset (an
  unknown key, or a value of the wrong type or out of bounds, is an error naming the key
  and the preset file): a refused run leaves its ``--out`` as it was.
"""

from __future__ import annotations

import argparse
import json
import math
import numbers
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.evaluation.seeds import TRAIN_SEED_LIMIT
from agents.installation import install_command, missing_extra_message, missing_modules
from agents.invocation import command_line, invoked_args, invoked_prog
from agents.training.experiment import (
    RunDirError,
    TrainingInterrupted,
    env_config,
    env_kwargs,
    eval_env_kwargs,
    evaluate_run,
    is_integer_value,
    read_json,
    run_lock,
    train,
    training_wrapper_problem,
)
from agents.training.presets import (
    ALGOS,
    DEFAULT_PRESET,
    DEFAULTS,
    OPTION_CHECKS,
    PRESETS,
    VEC_MODES,
    PresetError,
    check_option,
    defaults,
    load_preset,
)
from agents.training.seeding import EVAL_ENVS_MAX, EVAL_SEED_OFFSET, eval_env_count, seed_problem
from agents.training.shipping import ShipError, check_ship_destination, ship
from agents.training.tune import SEARCH_SPACES as SEARCH_SPACE_NAMES
from hyperloop_env.json_values import python_numbers
from hyperloop_env.scenarios import PAPER_SCENARIOS, SCENARIOS


def integer(s: str) -> int:
    """An integer option: ``100000``, ``1e5`` or ``2.0``; ``1.9`` or ``inf`` are errors."""
    try:
        return int(s)
    except ValueError:
        pass
    try:
        f = float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {s!r}") from None
    if not math.isfinite(f) or not f.is_integer():
        raise argparse.ArgumentTypeError(f"expected an integer, got {s!r}")
    return int(f)


PROG = "hyperloop-train"
"""The tool's name when it was not started as a command (``main()`` called from code)."""


def tool_name(prog: str | None = None) -> str:
    """``prog`` if given (``hyperloop train``: the dispatcher names it), else the name this
    command was invoked by (``hyperloop-train``, ``python train.py``'s ``train.py``)."""
    return prog if prog is not None else invoked_prog(PROG)


def build_parser(prog: str | None = None) -> argparse.ArgumentParser:
    name = tool_name(prog)
    p = argparse.ArgumentParser(
        prog=name,
        description="Train a PPO/SAC suspension controller on HyperloopSuspension-v0 and "
        "evaluate it against passive, PID and LQR with the STS suite.",
        epilog="Presets: "
        + ", ".join(PRESETS)
        + f". Example: {name} --preset shipped-ppo. Command-line options override "
        "the preset. Outputs go under the current directory.",
    )
    a = p.add_argument
    a("--preset", help="named preset (see --list-presets) or a JSON file of options")
    a("--list-presets", action="store_true", help="print the presets and exit")
    a("--algo", help=f"{' | '.join(ALGOS)} (default {DEFAULTS['algo']})")
    a("--scenario", help=f"training scenario (default {DEFAULTS['scenario']!r})")
    a("--timesteps", type=integer, help="total env steps to train")
    a("--n-envs", type=integer, help=f"parallel envs (default {DEFAULTS['n_envs']})")
    a(
        "--seed",
        type=integer,
        help=f"training seed (default 0): the run's envs use seeds from it up to seed + "
        f"{EVAL_SEED_OFFSET + EVAL_ENVS_MAX - 1}, all in the training range [0, "
        f"{TRAIN_SEED_LIMIT - 1}]",
    )
    a(
        "--out",
        help="output directory (default runs/<algo>-<scenario>-<seed>); must be new "
        "or empty unless --resume or --overwrite",
    )
    a(
        "--resume",
        action="store_true",
        help="continue from the newest intact checkpoint in --out (same configuration)",
    )
    a(
        "--overwrite",
        action="store_true",
        help="delete the previous run's files in --out first (with --eval-only: replace its "
        "report)",
    )
    _output_arguments(a)
    _tune_arguments(p)
    a("--no-progress", action="store_true", help="no progress bar")
    a("--verbose", type=integer, default=0, choices=(0, 1, 2), help="SB3 verbosity (0, 1, 2)")
    return p


def _output_arguments(a: Any) -> None:
    """The device, the final evaluation, the vector env, the checkpoints and shipping."""
    a("--device", help="torch device: cpu (default), cuda, cuda:N, mps, auto")
    a("--eval-distance-km", type=float, help="track per scenario and seed in the final report")
    a("--eval-seeds", type=integer, help="seeds per scenario in the final report (default 1)")
    a("--no-eval", action="store_true", help="skip the final STS evaluation")
    a(
        "--eval-only",
        action="store_true",
        help="no training: evaluate the agent already saved in --out (model.zip)",
    )
    a("--vec", choices=VEC_MODES, help="vector env: native (default), dummy, subproc")
    a(
        "--overlap-updates",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="PPO: each update on a second process while the next rollout is collected "
        "(both cores; a policy lag of one update: agents.training.overlap)",
    )
    a("--track-length-m", type=float, help="track section per training episode [m]")
    a("--eval-freq", type=integer, help="env steps between EvalCallback runs")
    a("--checkpoint-freq", type=integer, help="env steps between checkpoints")
    a(
        "--checkpoint-interval-s",
        type=float,
        help="wall-clock seconds between checkpoints (default "
        f"{DEFAULTS['checkpoint_interval_s']:g}); one is also saved on Ctrl-C and at the end",
    )
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
        help="copy the result (model, VecNormalize stats, log, report) to agents/shipped/<algo>/ "
        "of the source checkout (refused for an installed, non-editable package)",
    )


def _tune_arguments(p: argparse.ArgumentParser) -> None:
    """The hyper-parameter search's options (``--tune``)."""
    t = p.add_argument_group(
        f"hyper-parameter search (Ray Tune: {install_command('tune')})",
        "--tune searches the reward weights, hyper-parameters and (memory spaces) "
        "observation options of the preset (agents.training.tune) instead of training "
        "once; each trial trains --tune-timesteps steps and is scored by its paired "
        "roughness capacity ratio against LQR on the validation seeds.",
    ).add_argument
    t("--tune", action="store_true", help="run the search (no final training)")
    t("--tune-trials", type=integer, default=8, help="configurations tried (default 8)")
    t(
        "--tune-timesteps",
        type=integer,
        default=400_000,
        help="env steps per trial (default 400 000)",
    )
    t(
        "--tune-workers",
        type=integer,
        default=2,
        help="trials in parallel (default 2 = this machine's cores)",
    )
    t("--tune-seed", type=integer, default=0, help="seed of the configuration draws")
    t(
        "--tune-space",
        default=None,
        choices=tuple(SEARCH_SPACE_NAMES),
        help="search space (default: the preset's algorithm, i.e. ppo; ppo-memory and "
        "sac-memory add the observation memory options)",
    )
    t("--tune-out", help="search directory (default runs/tune-<preset or algo>)")
    t(
        "--address",
        default=None,
        help="Ray cluster address (e.g. auto or ray://host:10001); default: a local Ray",
    )


def _load_preset(name: str | None, parser: argparse.ArgumentParser) -> dict[str, Any]:
    """The preset ``name``; without one, ``default`` (the main job's options on top of the
    built-in defaults)."""
    if name is None:
        name = DEFAULT_PRESET
    try:
        return load_preset(name)
    except ValueError as exc:
        parser.error(str(exc))
        raise AssertionError from None  # unreachable


def resolve_config(argv: list[str] | None = None, prog: str | None = None) -> dict[str, Any]:
    """Parse and validate the command line; returns the merged configuration."""
    parser = build_parser(prog)
    args = parser.parse_args(argv)
    if args.list_presets:
        for name, values in PRESETS.items():
            print(f"{name}: {json.dumps(values)}")
        parser.exit(0)
    missing = missing_modules("train")  # one line naming the extra, not an ImportError
    if missing:
        parser.error(missing_extra_message("train", "training", missing))
    try:
        cfg = defaults()
    except PresetError as exc:
        parser.error(str(exc))
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
        "overlap_updates",
        "track_length_m",
        "eval_freq",
        "checkpoint_freq",
        "checkpoint_interval_s",
    ):
        value = getattr(args, key)
        if value is not None:
            cfg[key] = value
    if args.env_kwarg:
        cfg["env_kwargs"] = {
            **cfg.get("env_kwargs", {}),
            **_parse_env_kwargs(args.env_kwarg, parser),
        }
    if args.preset is None and args.overlap_updates is None and cfg["algo"] != "ppo":
        cfg["overlap_updates"] = False  # the default preset overlaps PPO's updates only
    cfg["preset"] = args.preset
    cfg["resume"] = args.resume
    cfg["overwrite"] = args.overwrite
    cfg["no_eval"] = args.no_eval
    cfg["eval_only"] = args.eval_only
    cfg["ship"] = args.ship
    if args.eval_only and args.no_eval:
        parser.error("--eval-only and --no-eval exclude each other")
    if args.resume and args.overwrite:
        parser.error(
            "--resume and --overwrite exclude each other (continue the run, or replace it)"
        )
    if args.eval_only and args.resume:
        parser.error("--eval-only and --resume exclude each other")
    cfg["progress_bar"] = not args.no_progress
    cfg["verbose"] = args.verbose
    cfg["tune"] = None
    if args.tune:
        if args.resume or args.eval_only or args.ship:
            parser.error("--tune excludes --resume, --eval-only and --ship")
        space = args.tune_space or cfg["algo"]
        if space not in SEARCH_SPACE_NAMES or space.split("-")[0] != cfg["algo"]:
            parser.error(
                f"--tune-space {space!r} does not train --algo {cfg['algo']} "
                f"(spaces: {list(SEARCH_SPACE_NAMES)})"
            )
        for key in ("tune_trials", "tune_timesteps", "tune_workers"):
            if getattr(args, key) < 1:
                parser.error(f"--{key.replace('_', '-')} must be >= 1, got {getattr(args, key)}")
        cfg["no_eval"] = True
        cfg["tune"] = {
            "trials": args.tune_trials,
            "timesteps": args.tune_timesteps,
            "workers": args.tune_workers,
            "seed": args.tune_seed,
            "space": space,
            "address": args.address,
            "out": args.tune_out or f"runs/tune-{Path(args.preset or cfg['algo']).stem}",
        }
    elif args.address is not None:
        parser.error("--address is a --tune option")
    _validate(cfg, parser)
    if cfg["ship"]:  # before training: never train for an hour, then fail to ship
        try:
            check_ship_destination(cfg.get("ship_name") or cfg["algo"])
        except ShipError as exc:
            parser.error(str(exc))
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
    cfg.update(python_numbers(cfg))  # NumPy scalars from a programmatic config
    cfg["algo"] = str(cfg["algo"]).lower()
    if cfg["algo"] not in ALGOS:
        parser.error(f"--algo must be one of {list(ALGOS)}, got {cfg['algo']!r}")
    if cfg["scenario"] not in SCENARIOS:
        parser.error(f"unknown --scenario {cfg['scenario']!r}; valid: {sorted(SCENARIOS)}")
    for key, lo, hi in (
        ("timesteps", 1, None),
        ("n_envs", 1, None),
        ("eval_seeds", 1, None),
        ("eval_freq", 1, None),
        ("checkpoint_freq", 1, None),
    ):
        v = cfg[key]
        ok = is_integer_value(v) and int(v) >= lo and (hi is None or int(v) <= hi)
        if not ok:
            rng = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
            parser.error(f"--{key.replace('_', '-')} must be an integer {rng}, got {v!r}")
        cfg[key] = int(v)
    for key in ("eval_distance_km", "track_length_m", "checkpoint_interval_s"):
        v = cfg[key]
        if not isinstance(v, numbers.Real) or isinstance(v, bool) or not math.isfinite(v) or v <= 0:
            parser.error(f"--{key.replace('_', '-')} must be a positive number, got {v!r}")
        cfg[key] = float(v)
    for key in ("net_arch", "critic_arch"):
        v = cfg[key]
        if v is None and key == "critic_arch":
            continue
        if (
            not isinstance(v, list | tuple)
            or not v
            or not all(is_integer_value(w) and int(w) >= 1 for w in v)
        ):
            parser.error(f"{key} must be a non-empty list of layer widths >= 1, got {v!r}")
        cfg[key] = [int(w) for w in v]
    if cfg["vec"] not in VEC_MODES:
        parser.error(f"--vec must be one of {list(VEC_MODES)}, got {cfg['vec']!r}")
    cfg["device"] = _check_device(str(cfg["device"]), parser)
    _check_preset_options(cfg, parser)
    wrapper = training_wrapper_problem(cfg)
    if wrapper is not None:
        parser.error(wrapper)
    _check_seed(cfg, parser)
    try:  # fail fast on a bad --env-kwarg / preset env option
        env_config(cfg)
    except (TypeError, ValueError) as exc:
        parser.error(f"invalid environment options {env_kwargs(cfg)}: {exc}")
    if not cfg["no_eval"]:  # the final report must have samples after its settling time
        from agents.evaluation.evaluate import check_settling, episode_configs

        magnet = env_kwargs(cfg).get("magnet", "repelling")
        try:
            configs = episode_configs(
                PAPER_SCENARIOS,
                cfg["eval_distance_km"],
                magnet,
                eval_env_kwargs(cfg),
                "--eval-distance-km",
            )
            check_settling(configs, 1.0, cfg["eval_distance_km"], ("--eval-distance-km", ""))
        except ValueError as exc:
            parser.error(f"final evaluation: {exc}")


def _check_seed(cfg: dict[str, Any], parser: argparse.ArgumentParser) -> None:
    """Every seed the run derives from ``--seed`` stays in the training range
    (:mod:`agents.training.seeding`), apart from every evaluation seed."""
    seed = cfg["seed"]
    if not is_integer_value(seed):
        parser.error(f"--seed must be an integer in the training range, got {seed!r}")
    cfg["seed"] = int(seed)
    problem = seed_problem(cfg["seed"], cfg["n_envs"], eval_env_count(cfg["eval_episodes"]))
    if problem is not None:
        parser.error(problem)


FLAG_OPTIONS = frozenset(
    {
        "algo",
        "scenario",
        "timesteps",
        "n_envs",
        "eval_seeds",
        "eval_freq",
        "checkpoint_freq",
        "seed",
        "eval_distance_km",
        "track_length_m",
        "checkpoint_interval_s",
        "net_arch",
        "critic_arch",
        "vec",
        "device",
        "env_kwargs",
    }
)
"""The options :func:`_validate` checks under their command-line names."""


def _preset_source(cfg: dict[str, Any]) -> str:
    return f" (--preset {cfg['preset']})" if cfg.get("preset") else ""


def _check_preset_options(cfg: dict[str, Any], parser: argparse.ArgumentParser) -> None:
    """The options without a command-line flag (hyper-parameters …), checked as a preset's
    are (a configuration built in code may hold anything), then the sizes PPO needs."""
    for key in sorted(OPTION_CHECKS.keys() - FLAG_OPTIONS):
        try:
            cfg[key] = check_option(key, cfg[key], "the configuration")
        except PresetError as exc:
            parser.error(str(exc))
    if cfg["algo"] != "ppo":
        return
    if cfg["batch_size"] < 2:  # PPO normalises the advantages of each mini-batch
        parser.error(
            f"batch_size must be >= 2 for PPO (it normalises the advantages of each "
            f"mini-batch), got {cfg['batch_size']}{_preset_source(cfg)}"
        )
    if cfg["n_steps"] * cfg["n_envs"] < 2:
        parser.error(
            f"n_steps × n_envs (the rollout) must be >= 2 for PPO, got {cfg['n_steps']} × "
            f"{cfg['n_envs']}{_preset_source(cfg)}"
        )


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


def _resume_command(argv: list[str] | None = None, prog: str | None = None) -> str:
    args = [a for a in (invoked_args() if argv is None else argv) if a != "--resume"]
    return command_line(tool_name(prog), [*args, "--resume"])


def _run_tune(cfg: dict[str, Any], prog: str | None = None) -> int:
    from agents.evaluation.outputs import OutputDirError, prepare_output_dir

    tc = cfg["tune"]
    try:
        import ray  # noqa: F401
        from ray import tune  # noqa: F401
    except ImportError:
        print(
            f"{tool_name(prog)}: error: --tune needs Ray Tune, not installed (the [tune] extra): "
            f"{install_command('tune')}",
            file=sys.stderr,
        )
        return 2
    try:
        old = Path(tc["out"])
        trials = [q.name for q in old.glob("trial_*")] if old.is_dir() else []
        prepare_output_dir(
            old,
            overwrite=cfg["overwrite"],
            owned=("tune_results.json", "tune_trials.csv", "ray", *trials),
            flag="--overwrite to replace it",
        )
    except OutputDirError as exc:
        print(f"{tool_name(prog)}: error: --tune-out: {exc}", file=sys.stderr)
        return 2
    from agents.training.tune import run_search

    base = {k: v for k, v in cfg.items() if k not in ("tune", "out", "ship", "eval_only")}
    base["resume"] = base["overwrite"] = False
    t0 = time.perf_counter()
    res = run_search(
        base,
        tc["trials"],
        tc["timesteps"],
        tc["out"],
        seed=tc["seed"],
        workers=tc["workers"],
        address=tc["address"],
        space=tc["space"],
    )
    best = res["best"]
    print(
        f"search: {len(res['trials'])} trials in {time.perf_counter() - t0:.0f} s; best "
        f"trial {best['index']} (score {best['score']:.4g}); results in "
        f"{Path(tc['out']) / 'tune_results.json'}"
    )
    return 0


def main(argv: Sequence[str] | None = None, prog: str | None = None) -> int:
    """``hyperloop train`` (``prog``: the name in the usage line and the messages; by
    default the name it was invoked by, :func:`agents.invocation.invoked_prog`)."""
    argv = None if argv is None else list(argv)
    cfg = resolve_config(argv, prog)
    if cfg["tune"] is not None:
        return _run_tune(cfg, prog)
    from agents.evaluation.outputs import OutputDirError

    try:  # one run per directory: held while training, evaluating and shipping
        with run_lock(cfg):
            return _main(cfg, argv, prog)
    except (RunDirError, OutputDirError) as exc:
        print(f"{tool_name(prog)}: error: {exc}", file=sys.stderr)
        return 2


def check_saved_model(out: Path) -> None:
    """``--eval-only``: ``<out>/model.zip`` must be a saved model; :class:`RunDirError`
    naming the file otherwise (missing, empty, not a zip, a zip without a model)."""
    from agents.controllers.learned import MODEL_FILE, model_file_problem

    path = out / MODEL_FILE
    if not path.is_file():
        raise RunDirError(f"--eval-only: no {MODEL_FILE} in {out} (train into it first)")
    problem = model_file_problem(path)
    if problem is not None:
        raise RunDirError(
            f"--eval-only: the model file {path} {problem}; train again (--overwrite) or restore it"
        )


def _main(cfg: dict[str, Any], argv: list[str] | None = None, prog: str | None = None) -> int:
    name = tool_name(prog)
    t0 = time.perf_counter()
    try:
        if cfg["eval_only"]:
            check_saved_model(Path(cfg["out"]))
            log = read_json(Path(cfg["out"]) / "training_log.json") or {}
            cfg["algo"] = log.get("algo", cfg["algo"])  # evaluate what was trained
        else:
            train(cfg)
        if not cfg["no_eval"]:
            from agents.evaluation.report import summary_table, verdict

            # after training the old report describes an older model: replace it
            res = evaluate_run(cfg, overwrite=cfg["overwrite"] or not cfg["eval_only"])
            print(summary_table(res["results"]))
            st = res["settings"]
            print(verdict(res["results"], st["distance_km"], len(st["seeds"])))
            paths = res["paths"]
            report = paths.get("md") or str(Path(cfg["out"]) / "report")
            rep_dir = Path(cfg["out"]) / "report"
            print(
                f"STS report: {report}  (JSON, CSV and figures in {rep_dir}; the controllers "
                f"compared: {rep_dir / 'figures' / 'comparison.png'})"
            )
    except TrainingInterrupted as exc:
        print(
            f"{name}: interrupted at {exc.steps} timesteps; checkpoint saved "
            f"({exc.checkpoint}). Continue with:\n  {_resume_command(argv, prog)}",
            file=sys.stderr,
            flush=True,
        )
        return 128 + exc.signum
    except KeyboardInterrupt:
        print(
            f"{name}: aborted; --resume continues from the newest checkpoint in "
            f"{cfg['out']}, if one was saved",
            file=sys.stderr,
        )
        return 130
    except ValueError as exc:  # run directory / checkpoint / report directory / model
        from agents.controllers.base import ControllerError
        from agents.evaluation.outputs import OutputDirError
        from agents.training.checkpoints import CheckpointError

        if not isinstance(exc, RunDirError | CheckpointError | OutputDirError | ControllerError):
            raise
        print(f"{name}: error: {exc}", file=sys.stderr)
        return 2
    if cfg["ship"]:
        try:
            dest = ship(Path(cfg["out"]), cfg.get("ship_name") or cfg["algo"])
        except ShipError as exc:
            print(f"{name}: error: {exc}", file=sys.stderr)
            return 2
        print(f"shipped to {dest}")
    print(f"total wall time {time.perf_counter() - t0:.0f} s; outputs in {cfg['out']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
