"""The training experiment: environments, model, checkpoints and resume, the training loop
and the final STS evaluation (its command line: ``hyperloop train``,
:mod:`agents.cli.train`).

A run directory holds one run: a new run refuses a directory that already has files
(``overwrite=True`` / ``--overwrite`` removes a previous run's files first, :data:`RUN_FILES`),
and ``resume=True`` continues from the newest intact checkpoint of the *same*
configuration (:mod:`.checkpoints`). Final outputs are written atomically.
"""

from __future__ import annotations

import contextlib
import json
import numbers
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from agents.evaluation.outputs import (
    atomic_path,
    atomic_write_text,
    output_lock,
    prepare_output_dir,
)
from agents.training.presets import BASELINES
from agents.training.seeding import (
    eval_env_count,
    eval_env_seed,
    resume_seed,
    seed_problem,
    seed_record,
)
from hyperloop_env.config import EnvConfig
from hyperloop_env.json_values import python_numbers
from hyperloop_env.scenarios import PAPER_SCENARIOS

RUN_FILES: tuple[str, ...] = (
    "model.zip",
    "vecnormalize.pkl",
    "training_log.json",
    "run_config.json",
    "checkpoints",
    "best",
    "eval",
    "tb",
    "report",
)
"""What a training run writes into its directory (removed first by ``--overwrite``)."""


class RunDirError(ValueError):
    """The run directory cannot be used as asked (not empty, no checkpoint, ...)."""


class TrainingInterrupted(Exception):  # noqa: N818 - it is the outcome, not a bug
    """Training stopped on SIGINT / SIGTERM after saving a checkpoint."""

    def __init__(self, signum: int, checkpoint: Path, steps: int) -> None:
        super().__init__(f"interrupted at {steps} steps; checkpoint {checkpoint}")
        self.signum = signum
        self.checkpoint = checkpoint
        self.steps = steps


def is_integer_value(v: Any) -> bool:
    """An int, a NumPy integer, or a float with an integral value (not bool)."""
    if isinstance(v, bool):
        return False
    if isinstance(v, numbers.Integral):
        return True
    return isinstance(v, numbers.Real) and float(v).is_integer()


def env_kwargs(cfg: dict[str, Any]) -> dict[str, Any]:
    """The environment keywords of a training config (``track_length_m`` + ``env_kwargs``)."""
    kw: dict[str, Any] = {"track_length_m": float(cfg["track_length_m"])}
    kw.update(cfg.get("env_kwargs") or {})
    return kw


def env_config(cfg: dict[str, Any]) -> EnvConfig:
    """The training environment's :class:`~hyperloop_env.config.EnvConfig`."""
    return EnvConfig.from_kwargs(scenario=cfg["scenario"], **env_kwargs(cfg))


def run_fingerprint(cfg: dict[str, Any]) -> dict[str, Any]:
    """The resolved configuration a checkpoint belongs to: algorithm, scenario, the full
    environment configuration (``EnvConfig.to_kwargs()``), the algorithm's
    hyper-parameters, the number of environments, the vector env kind and the seed.
    ``timesteps``, output, device, evaluation and checkpoint settings are not part of it
    (a resumed run may change them)."""
    from agents.training.run_state import (
        ALGO_HYPERPARAMETERS,
        COMMON_HYPERPARAMETERS,
        jsonable,
    )

    algo = cfg["algo"]
    keys = COMMON_HYPERPARAMETERS + ALGO_HYPERPARAMETERS.get(algo, ())
    fp = {
        "algo": algo,
        "scenario": cfg["scenario"],
        "env": env_config(cfg).to_kwargs(),
        "hyperparameters": {k: cfg[k] for k in keys},
        "n_envs": cfg["n_envs"],
        "vec": cfg["vec"],
        "seed": cfg["seed"],
    }
    if cfg.get("residual") is not None:  # absent otherwise: earlier runs' fingerprints stand
        fp["residual"] = cfg["residual"]
    if cfg.get("privileged_critic"):  # likewise
        fp["privileged_critic"] = True
    if cfg.get("curriculum") is not None:  # likewise
        fp["curriculum"] = cfg["curriculum"]
    if cfg.get("overlap_updates"):  # likewise
        fp["overlap_updates"] = True
    return jsonable(fp)


def training_wrapper_problem(cfg: dict[str, Any]) -> str | None:
    """Why the options ``privileged_critic`` (PPO with ``vec="native"`` only),
    ``curriculum`` (``vec="native"`` only) and ``overlap_updates`` (PPO only) cannot train
    as given, or None."""
    if cfg.get("curriculum") is not None and cfg["vec"] != "native":
        return (
            "curriculum sets each episode's severity through the native vector env's resets; "
            f"use vec 'native', not {cfg['vec']!r}"
        )
    if cfg.get("overlap_updates") and cfg["algo"] != "ppo":
        return (
            "overlap_updates overlaps PPO's updates with its rollouts; "
            f"--algo {cfg['algo']} is not PPO"
        )
    if cfg.get("privileged_critic"):
        if cfg["algo"] != "ppo":
            return f"privileged_critic trains PPO's critic; --algo {cfg['algo']} has none"
        if cfg["vec"] != "native":
            return (
                "privileged_critic reads the simulator's state from the native vector env; "
                f"use vec 'native', not {cfg['vec']!r}"
            )
    return None


def make_native_vec_env(num_envs: int, config: EnvConfig) -> Any:
    """The native batched ``HyperloopSuspension-v0`` (as ``gymnasium.make_vec(...,
    vectorization_mode="vector_entry_point")``) with ``reset_mask`` support, ready for
    :class:`~agents.training.sb3_adapter.GymnasiumVectorToSB3`."""
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    return HyperloopSuspensionVectorEnv(num_envs=num_envs, config=config)


def make_vec_env(
    config: EnvConfig,
    n_envs: int,
    seed: int,
    vec: str = "native",
    residual: dict[str, Any] | None = None,
    privileged: bool = False,
    curriculum: dict[str, Any] | None = None,
) -> Any:
    """SB3 VecEnv (VecMonitor on top) of ``n_envs`` HyperloopSuspension-v0 environments;
    with a ``residual`` record (the preset option) each acts by the correction to the
    record's base law (:mod:`agents.training.residual`); with ``privileged`` (the option
    ``privileged_critic``; native only) the simulator's state is appended to every
    observation (:mod:`agents.training.privileged`); with a ``curriculum`` record (native
    only) each episode's severity of its family follows the curriculum
    (:mod:`agents.training.curriculum`; the training env's, never the evaluation's)."""
    import gymnasium as gym
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecMonitor

    from agents.training.sb3_adapter import GymnasiumVectorToSB3
    from hyperloop_env import ENV_ID

    if vec == "native":
        # = gym.make_vec(..., vectorization_mode="vector_entry_point") + reset_mask support
        venv = make_native_vec_env(n_envs, config)
        if curriculum is not None:
            from agents.training.curriculum import SeverityCurriculum

            venv = SeverityCurriculum(venv, curriculum, seed)
        if residual is not None:
            from agents.training.residual import residual_vec_env

            venv = residual_vec_env(venv, residual)
        if privileged:
            from agents.training.privileged import PrivilegedObservationVecEnv

            venv = PrivilegedObservationVecEnv(venv)
        sb3_env = GymnasiumVectorToSB3(venv)
    else:
        if privileged or curriculum is not None:
            raise ValueError("privileged_critic and curriculum need vec='native'")

        def make_one() -> Any:
            env = gym.make(ENV_ID, config=config)
            if residual is not None:
                from agents.training.residual import residual_env

                env = residual_env(env, residual)
            return env

        if vec == "dummy":
            sb3_env = DummyVecEnv([make_one] * n_envs)
        else:
            from agents.training.interrupts import sigint_ignored

            with sigint_ignored():  # Ctrl-C stops the trainer cleanly, not its workers
                sb3_env = SubprocVecEnv([make_one] * n_envs)
    sb3_env.seed(seed)
    return VecMonitor(sb3_env)


# --------------------------------------------------------------------------------------
# model
# --------------------------------------------------------------------------------------


def build_model(cfg: dict[str, Any], env: Any, tb_log: str | None) -> Any:
    import torch.nn as nn
    from stable_baselines3 import PPO, SAC

    act = {"tanh": nn.Tanh, "relu": nn.ReLU}[cfg["activation"]]  # presets.ACTIVATIONS
    common = {
        "env": env,
        "seed": cfg["seed"],
        "device": cfg["device"],
        "tensorboard_log": tb_log,
        "verbose": cfg["verbose"],
        "gamma": cfg["gamma"],
        "learning_rate": cfg["learning_rate"],
    }
    # net_arch: the actor's hidden layers (the network a controller runs at every step);
    # critic_arch: the value (PPO) / Q (SAC) networks' (training only; None = net_arch)
    critic_arch = list(cfg.get("critic_arch") or cfg["net_arch"])
    if cfg["algo"] == "ppo":
        policy: Any = "MlpPolicy"
        extra: dict[str, Any] = {}  # policy options beyond the layers
        if cfg.get("privileged_critic"):  # the critic also sees the simulator's state
            from agents.training.privileged import PRIVILEGED_SIZE
            from agents.training.privileged_policy import PrivilegedCriticPolicy

            policy = PrivilegedCriticPolicy
            extra["actor_inputs"] = int(env.observation_space.shape[0]) - PRIVILEGED_SIZE
        ppo: Any = PPO
        if cfg.get("overlap_updates"):  # each update on a second process (overlap.py)
            from agents.training.overlap import OPTIMIZER_KWARGS, OverlappedPPO

            ppo = OverlappedPPO
            extra["optimizer_kwargs"] = dict(OPTIMIZER_KWARGS)
        return ppo(
            policy,
            n_steps=cfg["n_steps"],
            batch_size=cfg["batch_size"],
            n_epochs=cfg["n_epochs"],
            gae_lambda=cfg["gae_lambda"],
            clip_range=cfg["clip_range"],
            ent_coef=cfg["ent_coef"],
            policy_kwargs={
                "net_arch": {"pi": list(cfg["net_arch"]), "vf": critic_arch},
                "activation_fn": act,
                "log_std_init": cfg["log_std_init"],
                **extra,
            },
            **common,
        )
    return SAC(
        "MlpPolicy",
        buffer_size=cfg["sac_buffer_size"],
        learning_starts=cfg["sac_learning_starts"],
        batch_size=cfg["batch_size"],
        train_freq=cfg["sac_train_freq"],
        gradient_steps=cfg["sac_gradient_steps"],
        policy_kwargs={
            "net_arch": {"pi": list(cfg["net_arch"]), "qf": critic_arch},
            "activation_fn": act,
            "log_std_init": cfg["log_std_init"],
        },
        **common,
    )


# --------------------------------------------------------------------------------------
# training
# --------------------------------------------------------------------------------------


def _command() -> str:
    from agents.invocation import command_line, invoked_args, invoked_prog

    return command_line(invoked_prog("hyperloop-train"), invoked_args())


def _check_resume_dir(cfg: dict[str, Any]) -> None:
    out = Path(cfg["out"])
    if cfg.get("resume") and not out.is_dir():
        raise RunDirError(
            f"--resume: no checkpoint in {out} (the directory does not exist); train "
            "without --resume first"
        )


@contextlib.contextmanager
def run_lock(cfg: dict[str, Any]) -> Iterator[Path]:
    """Hold the run directory ``cfg["out"]`` for this process while it trains, evaluates
    and ships (:func:`agents.evaluation.outputs.output_lock`: ``<out>/.lock`` with this
    pid): a second ``train.py`` on the same directory — a new run, ``--resume`` or
    ``--eval-only`` — is refused (``OutputLockError`` naming the directory and the pid)
    instead of mixing its checkpoints and model with this run's. Re-entrant in one
    process; a ``--resume`` of a missing directory is refused before anything is
    created."""
    _check_resume_dir(cfg)
    with output_lock(cfg["out"], "run directory") as out:
        yield out


def prepare_run_dir(cfg: dict[str, Any]) -> Path:
    """Check the run directory before anything is built: a new run needs an empty (or
    new) directory unless ``overwrite``; ``resume`` needs an existing one."""
    out = Path(cfg["out"])
    if cfg.get("resume"):
        _check_resume_dir(cfg)
        return out
    return prepare_output_dir(
        out,
        overwrite=bool(cfg.get("overwrite")),
        owned=RUN_FILES,
        flag="--resume to continue that run, or --overwrite to replace it",
    )


def train(cfg: dict[str, Any]) -> dict[str, Any]:
    """Train according to ``cfg`` (see :func:`agents.cli.train.resolve_config`);
    returns the training log. Raises :class:`RunDirError` (or
    :class:`~agents.training.checkpoints.CheckpointError`, or
    :class:`~agents.evaluation.outputs.OutputLockError` while another run holds the
    directory: :func:`run_lock`) before building anything if the run directory cannot be
    used, and :class:`TrainingInterrupted` after saving a checkpoint if SIGINT / SIGTERM
    stopped it."""
    with run_lock(cfg):
        return _train(cfg)


def residual_eval_problem(out: Path) -> str:
    """Why a residual run has no final STS evaluation (its agent is the base law plus the
    policy, which the evaluation's controller names cannot carry), and what to run."""
    return (
        f"a residual run ({out}) has no final evaluation here; train with --no-eval and "
        "measure it with hyperloop capacity / evaluate, the controller "
        "agents.controllers.residual:make_residual with path=" + str(out) + " (docs/training.md, "
        '"Residual controllers")'
    )


def _start_learner(cfg: dict[str, Any]) -> Any:
    """The learner process of a run that overlaps PPO's updates (:mod:`.overlap`), or None."""
    if not cfg.get("overlap_updates"):
        return None
    from agents.training.overlap import start_learner

    return start_learner()


def _train(cfg: dict[str, Any]) -> dict[str, Any]:
    """Train (or resume) a run and write its model and log: the run folder prepared, the
    model built or loaded (:func:`_start` / :func:`_continue`), learning with evaluation and
    checkpoint callbacks (:func:`_learn`), the final model and its log saved."""
    import torch
    from stable_baselines3.common.vec_env import VecNormalize

    cfg = python_numbers(cfg)
    if cfg.get("residual") is not None and not cfg.get("no_eval", True):
        raise RunDirError(residual_eval_problem(Path(cfg["out"])))  # before hours of training
    wrapper = training_wrapper_problem(cfg)
    if wrapper is not None:
        raise ValueError(wrapper)
    eval_n = eval_env_count(cfg["eval_episodes"])
    problem = seed_problem(cfg["seed"], cfg["n_envs"], eval_n)
    if problem is not None:  # the command line refuses it; a configuration built in code
        raise ValueError(problem)
    torch.set_num_threads(1)
    out = prepare_run_dir(cfg)
    fingerprint = run_fingerprint(cfg)
    command = _command()
    learner = _start_learner(cfg)  # it starts up while the envs and the model are built
    try:
        resumed = _load_checkpoint(cfg, out, fingerprint) if cfg["resume"] else None
        eval_env = make_vec_env(
            env_config(cfg),
            eval_n,
            eval_env_seed(cfg["seed"]),
            cfg["vec"],
            cfg.get("residual"),
            bool(cfg.get("privileged_critic")),
        )
        eval_env = VecNormalize(eval_env, training=False, norm_reward=False)
        tb_log = str(out / "tb")
        if resumed is not None:
            model, train_env, remaining, wall_before, resumed_info = _continue(cfg, resumed, tb_log)
        else:
            model, train_env = _start(cfg, out, tb_log, eval_env, command, fingerprint)
            remaining, wall_before, resumed_info = cfg["timesteps"], 0.0, None
    except BaseException:
        if learner is not None:
            learner.close()
        raise
    if learner is not None:
        model.adopt_learner(learner)
    start = int(model.num_timesteps)
    eval_cb = _eval_callback(cfg, eval_env, out, resumed)
    wall, ckpt_cb = _learn(
        cfg, model, (train_env, eval_env), eval_cb, out, fingerprint, command, wall_before,
        remaining, resumed,
    )  # fmt: skip
    with atomic_path(out / "model.zip") as tmp:
        model.save(str(tmp))
    with atomic_path(out / "vecnormalize.pkl") as tmp:
        train_env.save(str(tmp))
    # a short evaluation of the final policy, for the log
    from stable_baselines3.common.evaluation import evaluate_policy

    eval_env.obs_rms = train_env.obs_rms
    mean_r, std_r = evaluate_policy(model, eval_env, n_eval_episodes=cfg["eval_episodes"])
    log = _training_log(
        cfg, model, command, fingerprint, eval_cb, ckpt_cb, resumed, resumed_info,
        wall, wall_before, start, (mean_r, std_r), eval_n,
    )  # fmt: skip
    atomic_write_text(out / "training_log.json", json.dumps(log, indent=2) + "\n")
    train_env.close()
    eval_env.close()
    print(
        f"trained {cfg['algo']} for {model.num_timesteps} timesteps in {wall:.0f} s; "
        f"final eval reward {mean_r:.1f} +- {std_r:.1f}; model saved to {out / 'model.zip'}"
    )
    return log


def _load_checkpoint(cfg: dict[str, Any], out: Path, fingerprint: dict[str, Any]) -> Any:
    """The run's latest usable checkpoint (:func:`agents.training.checkpoints.load_latest`)."""
    from agents.training import checkpoints as ck

    base_env = make_vec_env(
        env_config(cfg),
        cfg["n_envs"],
        cfg["seed"],
        cfg["vec"],
        cfg.get("residual"),
        bool(cfg.get("privileged_critic")),
        cfg.get("curriculum"),
    )
    try:
        return ck.load_latest(out, fingerprint, cfg["algo"], base_env, cfg["device"])
    except BaseException:
        base_env.close()
        raise


def _continue(
    cfg: dict[str, Any], resumed: Any, tb_log: str
) -> tuple[Any, Any, int, float, dict[str, Any]]:
    """(model, train env, timesteps remaining, earlier wall time, resume record) of a
    resumed run."""
    from agents.training.curriculum import find_curriculum
    from agents.training.run_state import policy_digest, set_rng_state

    model, train_env = resumed.model, resumed.env
    steps = resumed.steps
    digest = policy_digest(model)  # right after loading: the checkpoint's weights
    # loading re-seeds the global generators and the envs with the run's seed: continue
    # from the checkpoint's random state instead, with fresh episodes for this segment
    # (their seeds derived from the run's seed and the step count, in the training range)
    set_rng_state(resumed.manifest["rng"])
    train_env.seed(resume_seed(cfg["seed"], steps, cfg["n_envs"]))
    cur = find_curriculum(train_env)
    if cur is not None:  # the level reached, its draws from the segment's seed
        cur.load_state(
            resumed.manifest.get("curriculum") or {"level": cur.level},
            resume_seed(cfg["seed"], steps, cfg["n_envs"]),
        )
    model.tensorboard_log = tb_log
    wall_before = float(resumed.manifest.get("wall_time_s") or 0.0)
    info = {
        "checkpoint": str(resumed.checkpoint.path("model")),
        "num_timesteps": steps,
        "policy_sha256": digest,
        "skipped": resumed.skipped,
    }
    print(f"resuming from {resumed.checkpoint.path('model')} ({steps} timesteps)", flush=True)
    remaining = max(0, cfg["timesteps"] - model.num_timesteps)
    if remaining == 0:
        print(
            f"already trained {model.num_timesteps} >= --timesteps {cfg['timesteps']}; "
            "raise --timesteps to train further"
        )
    return model, train_env, remaining, wall_before, info


def _start(
    cfg: dict[str, Any],
    out: Path,
    tb_log: str,
    eval_env: Any,
    command: str,
    fingerprint: dict[str, Any],
) -> tuple[Any, Any]:
    """(model, train env) of a new run; ``run_config.json`` written once the model is
    built (a run that fails before leaves nothing behind)."""
    from stable_baselines3.common.vec_env import VecNormalize

    train_env = make_vec_env(
        env_config(cfg),
        cfg["n_envs"],
        cfg["seed"],
        cfg["vec"],
        cfg.get("residual"),
        bool(cfg.get("privileged_critic")),
        cfg.get("curriculum"),
    )
    train_env = VecNormalize(
        train_env, norm_obs=True, norm_reward=cfg["norm_reward"], gamma=cfg["gamma"]
    )
    try:
        model = build_model(cfg, train_env, tb_log)
    except BaseException:
        train_env.close()
        eval_env.close()
        raise
    atomic_write_text(
        out / "run_config.json",
        json.dumps({"command": command, "config": fingerprint}, indent=2) + "\n",
    )
    return model, train_env


def _eval_callback(cfg: dict[str, Any], eval_env: Any, out: Path, resumed: Any) -> Any:
    """SB3's evaluation callback (its history restored on a resume)."""
    from stable_baselines3.common.callbacks import EvalCallback

    from agents.training import checkpoints as ck

    eval_cb = EvalCallback(
        eval_env,
        n_eval_episodes=cfg["eval_episodes"],
        eval_freq=max(1, cfg["eval_freq"] // cfg["n_envs"]),
        best_model_save_path=str(out / "best"),
        log_path=str(out / "eval"),
        deterministic=True,
        verbose=cfg["verbose"],
    )
    if resumed is not None:
        ck.restore_eval_history(
            eval_cb, out / "eval", resumed.steps, resumed.manifest.get("best_mean_reward")
        )
    return eval_cb


def _learn(
    cfg: dict[str, Any],
    model: Any,
    envs: tuple[Any, Any],
    eval_cb: Any,
    out: Path,
    fingerprint: dict[str, Any],
    command: str,
    wall_before: float,
    remaining: int,
    resumed: Any,
) -> tuple[float, Any]:
    """Learn ``remaining`` timesteps with the evaluation and checkpoint callbacks (Ctrl-C or
    SIGTERM: a checkpoint, then :class:`TrainingInterrupted`); (wall time [s], the
    checkpoint callback). The envs are closed on any failure."""
    from agents.training import checkpoints as ck
    from agents.training.checkpoint_callback import make_checkpoint_callback
    from agents.training.interrupts import GracefulInterrupt

    interrupt = GracefulInterrupt()
    start = int(model.num_timesteps)
    ckpt_cb = make_checkpoint_callback(
        out=out,
        fingerprint=fingerprint,
        checkpoint_freq=cfg["checkpoint_freq"],
        checkpoint_interval_s=cfg["checkpoint_interval_s"],
        interrupt=interrupt,
        eval_callback=eval_cb,
        wall_time_before_s=wall_before,
        command=command,
        announce=(
            f"training started: {cfg['algo']} on {cfg['scenario']}, {cfg['n_envs']} envs, "
            f"{start} -> {cfg['timesteps']} timesteps; checkpoints every "
            f"{cfg['checkpoint_freq']} steps or {cfg['checkpoint_interval_s']:g} s in "
            f"{out / ck.CHECKPOINT_DIR} (Ctrl-C saves one and stops)"
        ),
    )
    t0 = time.perf_counter()
    try:
        if remaining > 0:
            with interrupt:
                model.learn(
                    total_timesteps=remaining,
                    callback=[eval_cb, ckpt_cb],
                    progress_bar=cfg["progress_bar"],
                    reset_num_timesteps=resumed is None,
                    tb_log_name=cfg["algo"],
                )
        else:  # nothing to train: the checkpoint resumed from is the final one
            ckpt_cb.init_callback(model)
            if resumed is not None:
                ckpt_cb.last_saved_steps = resumed.steps
                ckpt_cb.last_saved = resumed.checkpoint.path("manifest")
        if interrupt.signum is not None:
            path, steps = ckpt_cb.save_interrupted()
            raise TrainingInterrupted(interrupt.signum, path, steps)
        ckpt_cb.save_final()
    except BaseException:
        for env in envs:
            env.close()
        raise
    return time.perf_counter() - t0, ckpt_cb


def _training_log(
    cfg: dict[str, Any],
    model: Any,
    command: str,
    fingerprint: dict[str, Any],
    eval_cb: Any,
    ckpt_cb: Any,
    resumed: Any,
    resumed_info: dict[str, Any] | None,
    wall: float,
    wall_before: float,
    start: int,
    final: tuple[float, float],
    eval_n: int,
) -> dict[str, Any]:
    """The run's ``training_log.json`` content."""
    import numpy as np

    from agents.training.run_state import ALGO_HYPERPARAMETERS, COMMON_HYPERPARAMETERS, jsonable

    mean_r, std_r = final
    trained = int(model.num_timesteps) - start
    n_envs = cfg["n_envs"]
    log = {
        "command": command,
        "preset": cfg["preset"],
        "algo": cfg["algo"],
        "scenario": cfg["scenario"],
        "seed": cfg["seed"],
        "training_seeds": seed_record(
            cfg["seed"], n_envs, eval_n, resumed.steps if resumed is not None else None
        ),
        "num_timesteps": int(model.num_timesteps),
        "timesteps_requested": cfg["timesteps"],
        "n_envs": n_envs,
        "vec": cfg["vec"],
        "wall_time_s": round(wall + wall_before, 1),
        "env_steps_per_s": round(trained / wall, 1) if wall > 0 and trained else None,
        "final_eval_mean_reward": float(mean_r),
        "final_eval_std_reward": float(std_r),
        "best_eval_mean_reward": float(eval_cb.best_mean_reward)
        if np.isfinite(eval_cb.best_mean_reward)
        else None,
        "env_kwargs": env_kwargs(cfg),
        **({"residual": cfg["residual"]} if cfg.get("residual") is not None else {}),
        **({"privileged_critic": True} if cfg.get("privileged_critic") else {}),
        **_curriculum_log(model),
        "hyperparameters": {
            k: cfg[k] for k in COMMON_HYPERPARAMETERS + ALGO_HYPERPARAMETERS.get(cfg["algo"], ())
        },
        "config": fingerprint,
        "checkpoint": str(ckpt_cb.last_saved) if ckpt_cb.last_saved else None,
        "resumed_from": resumed_info,
        "versions": _versions(),
    }
    return jsonable(log)


def _curriculum_log(model: Any) -> dict[str, Any]:
    """The training log's ``curriculum``: its record, the levels reached (env steps of
    this segment, level) and the last level; nothing for a run without one."""
    from agents.training.curriculum import find_curriculum

    cur = find_curriculum(model.get_env())
    if cur is None:
        return {}
    return {"curriculum": {**cur.record, "history": cur.history, "level": cur.level}}


def _versions() -> dict[str, str]:
    import gymnasium
    import numpy
    import stable_baselines3
    import torch

    from agents.training.numerics import numerics_state

    return {
        "python": sys.version.split()[0],
        "numpy": numpy.__version__,
        "stable_baselines3": stable_baselines3.__version__,
        "torch": torch.__version__,
        "gymnasium": gymnasium.__version__,
        "torch_cpu_capability": torch.backends.cpu.get_cpu_capability(),
        **numerics_state(),
    }


def read_json(path: Path) -> dict[str, Any] | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


# --------------------------------------------------------------------------------------
# evaluation
# --------------------------------------------------------------------------------------


EVAL_ENV_KEYS = (
    "actuators",
    "action_scale",
    "sensor_noise_std",
    "sensor_delay",
    "coil_time_constant_s",
    "control_dt_s",
    "clearance_m",
    "magnet",
)


def eval_env_kwargs(cfg: dict[str, Any]) -> dict[str, Any]:
    """The training env options that the final evaluation keeps (:data:`EVAL_ENV_KEYS`)."""
    kw = env_kwargs(cfg)
    return {k: kw[k] for k in EVAL_ENV_KEYS if k in kw and k != "magnet"}


REPORT_SEED_NAMES = (
    "--eval-seeds",
    "python -m agents.evaluate --seed0",
    "--seed-list",
    "python -m agents.evaluate --allow-training-seeds",
)
"""How the final evaluation's seed errors name the options (train.py has only the count)."""


def _check_report_seeds(out: Path, n_seeds: int) -> None:
    from agents.evaluation import seeds as seeding

    try:
        seeding.check_evaluation_seeds(
            [str(out)], seeding.resolve(n_seeds), names=REPORT_SEED_NAMES
        )
    except ValueError as exc:
        raise RunDirError(f"final evaluation: {exc}") from None


def evaluate_run(cfg: dict[str, Any], overwrite: bool = True) -> dict[str, Any]:
    """STS evaluation of the trained agent and the baselines on the four paper conditions
    (:func:`agents.evaluation.evaluate.evaluate`); the report goes to ``<out>/report/``
    (a previous report there is replaced only with ``overwrite``). An agent whose
    training log records training seeds among the evaluation seeds (trained elsewhere)
    is refused: :class:`RunDirError`. The cases run on one worker process per CPU
    (:func:`~agents.evaluation.settings.default_workers`; the results do not depend on it)."""
    from agents.evaluation import evaluate as ev
    from agents.evaluation.settings import default_workers

    out = Path(cfg["out"])
    if cfg.get("residual") is not None:
        raise RunDirError(residual_eval_problem(out))
    _check_report_seeds(out, cfg["eval_seeds"])
    algo = cfg["algo"]
    kw = env_kwargs(cfg)
    eval_kw = eval_env_kwargs(cfg)
    from agents.invocation import command_line, invoked_prog

    cmd = command_line(
        invoked_prog("hyperloop-train"),
        [
            "--eval-only",
            "--algo",
            algo,
            "--out",
            str(out),
            "--eval-distance-km",
            str(cfg["eval_distance_km"]),
            "--eval-seeds",
            str(cfg["eval_seeds"]),
        ],
    )
    # the trained agent is named by its run directory (a controller entry point), so the
    # report never mixes it up with the shipped agent of the same algorithm
    return ev.evaluate(
        [*BASELINES, str(out)],
        scenarios=list(PAPER_SCENARIOS),
        distance_km=float(cfg["eval_distance_km"]),
        seeds=cfg["eval_seeds"],
        magnet=kw.get("magnet", "repelling"),
        out_dir=out / "report",
        progress=cfg["progress_bar"],
        env_kwargs=eval_kw or None,
        command=f"{cmd}  (agents.evaluate.evaluate: passive pid lqr and this run's {algo} "
        "agent, paper scenarios)",
        overwrite=overwrite,
        workers=default_workers(),  # the cases on every core (the same results)
    )
