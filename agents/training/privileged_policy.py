"""PPO's actor-critic policy with a privileged critic (asymmetric actor-critic).

The observation the policy is given is ``[o, s]``: the agent's observation ``o`` (its
first ``actor_inputs`` entries) and the privileged entries ``s`` of
:mod:`agents.training.privileged`. The actor sees only ``o``: its features are ``o``, its
first layer has ``actor_inputs`` inputs, and its action distribution does not depend on
``s`` at all (a test perturbs ``s``). The critic (value network, ``net_arch["vf"]``) sees
``[o, s]``. Everything else is SB3's :class:`~stable_baselines3.common.policies.
ActorCriticPolicy` (MLP extractor, Gaussian action distribution, optimiser, saving); the
saved model loads with ``PPO.load`` where this module is importable.

A controller (:class:`agents.controllers.learned.SB3Controller`) runs the actor on the
plain observation: the policy's ``actor_inputs`` tells it how many of the observation
statistics to use.
"""

from __future__ import annotations

from typing import Any

import torch as th
from gymnasium import spaces
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor, MlpExtractor


class ActorInputs(BaseFeaturesExtractor):
    """The first ``n`` entries of a flat observation: the actor's features."""

    def __init__(self, observation_space: spaces.Box, n: int) -> None:
        super().__init__(observation_space, int(n))
        self.n = int(n)

    def forward(self, observations: th.Tensor) -> th.Tensor:
        return th.flatten(observations, start_dim=1)[:, : self.n]


class PrivilegedCriticPolicy(ActorCriticPolicy):
    """:class:`ActorCriticPolicy` whose actor sees the first ``actor_inputs`` entries of the
    observation and whose critic sees all of them (module docstring)."""

    def __init__(self, *args: Any, actor_inputs: int, **kwargs: Any) -> None:
        n = int(actor_inputs)
        obs_space = args[0] if args else kwargs["observation_space"]
        total = int(obs_space.shape[0])
        if not 1 <= n < total:
            raise ValueError(
                f"actor_inputs must be in [1, {total - 1}] (the observation has {total} "
                f"entries, the privileged ones last), got {actor_inputs!r}"
            )
        if kwargs.get("share_features_extractor") is True:
            raise ValueError("a privileged critic cannot share the actor's features")
        kwargs["share_features_extractor"] = False
        self.actor_inputs = n  # read by _build_mlp_extractor during the base's __init__
        super().__init__(*args, **kwargs)

    def _build_mlp_extractor(self) -> None:
        self.pi_features_extractor = ActorInputs(self.observation_space, self.actor_inputs)
        arch = self.net_arch
        pi, vf = (arch.get("pi", []), arch.get("vf", [])) if isinstance(arch, dict) else (arch,) * 2
        act, dev = self.activation_fn, self.device
        ext = MlpExtractor(self.actor_inputs, {"pi": pi, "vf": []}, act, dev)
        critic = MlpExtractor(self.features_dim, {"pi": [], "vf": vf}, act, dev)
        ext.value_net = critic.value_net
        ext.latent_dim_vf = critic.latent_dim_vf
        self.mlp_extractor = ext

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        data["actor_inputs"] = self.actor_inputs
        return data
