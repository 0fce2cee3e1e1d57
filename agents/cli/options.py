"""Every subcommand's shared flags, generated from the declarations of
:class:`agents.evaluation.settings.Settings` (one name, one default, one help text each).

``add_settings(parser, names, seeds=…, distance_km=…, out=…)`` adds the flags of the
settings ``names`` (the per-study fields take the study's default);
``settings_from_args(args, names)`` turns the parsed flags back into a checked
:class:`Settings` (``ValueError`` naming the flag).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import MISSING
from typing import Any

from agents.evaluation.settings import PER_STUDY, Settings, settings_field

EVALUATION = (
    "seeds",
    "seed0",
    "seed_list",
    "allow_training_seeds",
    "distance_km",
    "magnet",
    "actuators",
    "settle_s",
    "n_boot",
    "out",
    "overwrite",
    "progress",
    "figures",
)
"""The settings of a study that flies runs and writes a report."""
PARALLEL = ("workers", "backend", "address")
"""The settings of a study whose runs are spread over worker processes or a Ray cluster."""


def add_settings(
    parser: argparse.ArgumentParser, names: Sequence[str], **study_defaults: Any
) -> None:
    """Add the flags of the settings ``names`` to ``parser``; ``study_defaults`` gives the
    study's own default of a per-study field (:data:`PER_STUDY`), required for each."""
    unknown = set(study_defaults) - set(PER_STUDY)
    if unknown:
        raise TypeError(f"only {PER_STUDY} take a study's default, not {sorted(unknown)}")
    groups: dict[str, Any] = {}
    for name in names:
        f = settings_field(name)
        meta = dict(f.metadata["argparse"])
        group = meta.pop("group", None)
        aliases = meta.pop("aliases", ())
        negated = meta.pop("negated", False)
        flags = (f.metadata["flag"], *aliases)
        target: Any = parser
        if group is not None:
            if group not in groups:
                groups[group] = parser.add_mutually_exclusive_group()
            target = groups[group]
        kw: dict[str, Any] = {"dest": name, "help": f.metadata["help"]}
        if name in PER_STUDY:
            if name not in study_defaults:
                raise TypeError(f"the setting {name!r} needs the study's default")
            kw["default"] = study_defaults[name]
        elif f.default is not MISSING:
            kw["default"] = f.default
        else:
            kw["default"] = f.default_factory()
        if negated:
            kw.update(action="store_false", default=True)
        elif f.type in ("bool", bool) or isinstance(kw["default"], bool):
            kw["action"] = "store_true"
        kw.update(meta)
        target.add_argument(*flags, **kw)


def settings_from_args(args: argparse.Namespace, names: Sequence[str]) -> Settings:
    """The :class:`Settings` of the parsed ``args`` (the fields ``names``; the others keep
    their defaults); ``ValueError`` naming the flag of a bad value — also for the ``ray``
    backend without Ray installed (the message names the extra to install)."""
    st = Settings(**{n: getattr(args, n) for n in names})
    if "backend" in names:
        from agents.evaluation.backends import check_backend

        try:
            check_backend(st.backend, st.workers, st.address)
        except ImportError as exc:
            raise ValueError(str(exc)) from None
    return st
