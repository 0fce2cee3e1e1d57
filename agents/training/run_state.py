"""What a checkpoint records about a training run besides its files: the configuration
fingerprint's parts (which hyper-parameters count, the values as JSON reads them back, the
differences between two fingerprints), the global random states and the policy's digest.
:mod:`agents.training.checkpoints` writes them into a checkpoint's manifest and checks them
on ``--resume``.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

from hyperloop_env.json_values import json_value

COMMON_HYPERPARAMETERS: tuple[str, ...] = (
    "gamma",
    "learning_rate",
    "batch_size",
    "log_std_init",
    "net_arch",
    "critic_arch",
    "activation",
    "norm_reward",
)
ALGO_HYPERPARAMETERS: dict[str, tuple[str, ...]] = {
    "ppo": ("n_steps", "n_epochs", "gae_lambda", "clip_range", "ent_coef"),
    "sac": ("sac_buffer_size", "sac_learning_starts", "sac_train_freq", "sac_gradient_steps"),
}


def jsonable(x: Any) -> Any:
    """``x`` as it reads back from JSON (lists for tuples, Python numbers, inf kept)."""
    return json.loads(json.dumps(json_value(x, non_finite="keep")))


def config_differences(
    saved: dict[str, Any], current: dict[str, Any], prefix: str = ""
) -> list[str]:
    """Human-readable differences ``key: saved -> current`` between two fingerprints."""
    out = []
    for key in sorted(set(saved) | set(current)):
        name = f"{prefix}{key}"
        a, b = saved.get(key, "<missing>"), current.get(key, "<missing>")
        if isinstance(a, dict) and isinstance(b, dict):
            out += config_differences(a, b, name + ".")
        elif a != b:
            out.append(f"{name}: {a!r} in the checkpoint, {b!r} now")
    return out


def rng_state() -> dict[str, Any]:
    """The global Python, NumPy and torch (CPU) random states, JSON-friendly."""
    import random

    import numpy as np
    import torch

    py = random.getstate()
    # SB3 draws minibatch permutations from NumPy's global (legacy) generator
    name, keys, pos, has_gauss, cached = np.random.get_state()  # noqa: NPY002
    return {
        "python": [py[0], list(py[1]), py[2]],
        "numpy": [name, keys.tolist(), int(pos), int(has_gauss), float(cached)],
        "torch": torch.get_rng_state().tolist(),
    }


def set_rng_state(state: dict[str, Any]) -> None:
    """Restore what :func:`rng_state` returned."""
    import random

    import numpy as np
    import torch

    v, keys, gauss = state["python"]
    random.setstate((v, tuple(keys), gauss))
    name, nkeys, pos, has_gauss, cached = state["numpy"]
    np.random.set_state(  # noqa: NPY002
        (name, np.array(nkeys, dtype=np.uint32), pos, has_gauss, cached)
    )
    torch.set_rng_state(torch.tensor(state["torch"], dtype=torch.uint8))


def policy_digest(model: Any) -> str:
    """SHA-256 of the policy's parameters (all tensors of ``model.policy.state_dict()``)."""
    h = hashlib.sha256()
    for name, tensor in sorted(model.policy.state_dict().items()):
        h.update(name.encode())
        h.update(tensor.detach().cpu().contiguous().numpy().tobytes())
    return h.hexdigest()
