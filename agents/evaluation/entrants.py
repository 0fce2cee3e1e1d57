"""The entrants of the benchmark and the capacity study: a controller name of
:func:`agents.make_controller`, ``name+g`` for the controller with the guidance currents too
(``actuators="levitation+guidance"``); a learned agent flies the actuator set it was trained
with. ``shielded:<entrant>`` is the entrant wearing the safety filter
(:mod:`agents.controllers.shield`): ``shielded:lqr+g``, ``shielded:ppo-guidance``."""

from __future__ import annotations

import json

from agents.controllers import registry
from agents.controllers.registry import GUIDED, LEVITATION


def entrant_actuators(name: str) -> tuple[str, str]:
    """(controller name, actuator set) of an entrant (module docstring)."""
    from agents.controllers.registry import (
        available_controllers,
        controller_problem,
        is_entry_point,
        offered_controllers,
        unshielded,
    )

    base, act = (name[:-2], GUIDED) if name.endswith("+g") else (name, None)
    if unshielded(base) not in available_controllers() and not is_entry_point(base):
        raise ValueError(
            f"unknown entrant {name!r}: {base!r} is not a controller "
            f"(available: {offered_controllers()}, 'package.module:factory' "
            "or the path of a saved model.zip; append +g for "
            "levitation+guidance; prefix shielded: for the safety filter)"
        )
    problem = controller_problem(base)  # not shipped, or the [train] extra missing
    if problem:
        raise ValueError(f"entrant {name!r}: {problem}")
    trained = learned_actuators(base)
    if trained is not None:
        if act is not None and act != trained:
            raise ValueError(f"entrant {name!r}: {base!r} was trained with actuators={trained!r}")
        return base, trained
    return base, act or LEVITATION


def learned_actuators(name: str) -> str | None:
    """The actuator set a shipped learned agent was trained with (None for a classical
    controller or an agent that is not shipped)."""
    from agents.controllers.learned import MODEL_FILE
    from agents.controllers.registry import controller_spec, shipped_folder
    from agents.installation import require_data_file

    spec = controller_spec(name)
    folder = shipped_folder(name) if spec is not None and spec.kind == "learned" else None
    if folder is None or not (folder / MODEL_FILE).is_file():
        return None
    # a shipped agent's log is package data: missing or unreadable is an error naming it
    log = require_data_file(folder / "training_log.json", f"the shipped {name!r} agent")
    try:
        kw = json.loads(log.read_text()).get("env_kwargs") or {}
    except ValueError as exc:
        raise ValueError(f"{log}: not a JSON training log ({exc})") from None
    return str(kw.get("actuators", LEVITATION))


def entrant_label(base: str, actuators: str) -> str:
    from agents.controllers.registry import controller_spec

    spec = controller_spec(base)
    if actuators == GUIDED and (spec is None or spec.kind != "learned"):
        return f"{base}+g"
    return base


def default_entrants() -> tuple[str, ...]:
    """The headline entrants: the registry's entrants with the levitation currents, then
    those with the guidance currents too (:func:`agents.controllers.registry.entrants`),
    labelled as :func:`entrant_label` does."""
    return tuple(entrant_label(n, a) for a in (LEVITATION, GUIDED) for n in registry.entrants(a))


DEFAULT_ENTRANTS = default_entrants()
"""The entrants of ``benchmark`` and ``capacity`` by default (the registry's at import)."""
