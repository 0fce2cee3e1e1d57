"""The controller registry: one entry per name, ``make_controller(name, env_or_params)``.

Each entry (:class:`ControllerSpec`) names its factory by a string entry point
``"package.module:factory"`` (as Gymnasium's and safe-control-gym's ``register`` do) and
carries its metadata: the actuator sets it commands, its kind (``"baseline"`` or
``"learned"``), for a learned agent its algorithm and the folder of the shipped agent
(``agents/shipped/<shipped>/``), and what the command-line tools derive their defaults
from: ``default`` (the controllers ``evaluate`` and ``fragility`` run when none are given,
and the baselines a trained agent is compared with) and ``entrant`` (the actuator sets with
which it enters the headline benchmark, :func:`entrants`).

Built-ins: ``passive`` (constant bias currents), ``pid`` (per-unit gap PID, pole
placement), ``lqr`` (LQR + steady-state Kalman filter), ``lqr-preview`` (``lqr`` with a
feed-forward of the guideway the front units measured to the rear units,
:mod:`agents.controllers.lqr_preview`), ``mpc`` (constrained linear MPC on
the LQR's model and filter, DAQP), ``mpc-preview`` (``mpc`` with that preview), ``ppo`` /
``ppo-memory`` (PPO with the observation memory options) / ``ppo-guidance`` / ``sac``
/ ``ppo-residual-guidance`` (``lqr-preview+g`` plus a learned correction,
:mod:`agents.controllers.residual`)
(trained Stable-Baselines3 agents: the one shipped in ``agents/shipped/``, or ``path=`` a
``train.py`` run; :mod:`agents.controllers.learned`, torch imported only when asked for;
they need the ``train`` extra, and without it ``make_controller("ppo")`` raises one
:class:`~agents.installation.MissingExtraError` naming ``pip install
"hyperloop-suspension-gym[train]"``). The command-line tools offer only
:func:`offered_controllers` (the shipped agents).

Every tool takes, wherever it takes a controller name, also an entry point
``"package.module:factory"`` or the path of a saved ``model.zip`` (:func:`is_entry_point`);
:func:`resolve` turns any of the three into a factory. A user's controller is registered
the same way::

    from agents import register_controller
    register_controller("mine", "my_package.my_module:make", actuators="levitation")

A factory receives the plant (a Gymnasium env of this package, ``ModelParams``,
``Simulator``, ``ControlContext`` or None) and keyword options, and returns an object
satisfying :class:`agents.controllers.base.Controller`. A controller that cannot be built —
a name that does not resolve, a model file that does not load, a factory that raises or
returns something else than a controller — is one
:class:`~agents.controllers.base.ControllerError` (a ``ValueError``) naming the controller
and, for a user's factory, its file (:func:`make_controller`).

Worker processes: a registration lives in the process that made it. The runners
(:func:`agents.evaluation.backends.run_blocks`: spawned local workers and Ray tasks) send
:func:`registrations` — this process's registrations by entry point — with every task, and
the worker :func:`adopt` s them before building its controller, so a name registered in the
parent works in every worker (the worker imports the entry point's module: it must be
importable there, as any entry point). A factory registered as a Python callable
(``register_controller("mine", make)``) is not sent: it works in this process only.
"""

from __future__ import annotations

import importlib
import inspect
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from agents.controllers.base import (
    Controller,
    ControllerError,
    controller_error,
    controller_shape_problem,
)
from agents.installation import (
    MissingExtraError,
    missing_extra_message,
    missing_modules,
    require_data_file,
    require_extra,
)
from hyperloop_env.threads import one_blas_thread

Factory = Callable[..., Controller]

KINDS = ("baseline", "learned")
"""The kinds of controller: a classical design, or a trained agent."""

LEVITATION = "levitation"
GUIDED = "levitation+guidance"
_ENTRY_POINT = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_][\w.]*$")
"""``package.module:attr`` (attr may be dotted)."""


def _actuator_sets(value: str | Iterable[str], what: str) -> tuple[str, ...]:
    sets = (value,) if isinstance(value, str) else tuple(value)
    if not all(isinstance(s, str) and s for s in sets):
        raise ValueError(f"{what} must be actuator-set names (e.g. {GUIDED!r}), got {value!r}")
    return sets


@dataclass(frozen=True)
class ControllerSpec:
    """A registry entry: the factory's entry point and the controller's metadata.

    ``entry_point``: ``"package.module:factory"`` (resolved by import in the process that
    builds the controller, so it reaches worker processes) or a Python callable (this
    process only). ``actuators``: the actuator sets it commands (an env's ``actuators=``;
    a trained agent: the one it was trained with). ``kind``: one of :data:`KINDS`.
    ``algo`` / ``shipped``: a learned agent's algorithm (``"ppo"``, ``"sac"``) and the
    folder of its shipped agent under ``agents/shipped/`` (None: none is shipped by that
    name). ``default``: one of the tools' default controllers (:func:`default_controllers`).
    ``entrant``: the actuator sets (of ``actuators``) with which it enters the headline
    benchmark (:func:`entrants`). ``entrant_seeds``: the headline flies it on the first N
    of its evaluation seeds only (None: on all of them; its pairs are then paired on those
    N), for an entrant whose every seed costs several times another's (``mpc``: its QPs).
    """

    name: str
    entry_point: str | Factory
    kind: str = "baseline"
    actuators: tuple[str, ...] = (LEVITATION,)
    algo: str | None = None
    shipped: str | None = None
    default: bool = False
    entrant: tuple[str, ...] = field(default=())
    entrant_seeds: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"controller name must be a non-empty string, got {self.name!r}")
        ep = self.entry_point
        if isinstance(ep, str):
            if not _ENTRY_POINT.match(ep):
                raise ValueError(
                    f"controller {self.name!r}: entry point must be 'package.module:factory', "
                    f"got {ep!r}"
                )
        elif not callable(ep):
            raise ValueError(f"factory must be callable or 'package.module:factory', got {ep!r}")
        if self.kind not in KINDS:
            raise ValueError(f"controller {self.name!r}: kind must be one of {KINDS}")
        acts = _actuator_sets(self.actuators, "actuators")
        entrant = _actuator_sets(self.entrant, "entrant")
        if not set(entrant) <= set(acts):
            raise ValueError(
                f"controller {self.name!r}: entrant {entrant} not among its actuators {acts}"
            )
        object.__setattr__(self, "actuators", acts)
        object.__setattr__(self, "entrant", entrant)
        object.__setattr__(self, "default", bool(self.default))
        k = self.entrant_seeds
        if k is not None and (isinstance(k, bool) or not isinstance(k, int) or k < 2):
            raise ValueError(
                f"controller {self.name!r}: entrant_seeds must be None or an int >= 2, got {k!r}"
            )

    def factory(self) -> Factory:
        """The factory (an entry point imported here)."""
        ep = self.entry_point
        return import_entry_point(ep, self.name) if isinstance(ep, str) else ep


def _builtin(name: str, attr: str, **metadata: Any) -> ControllerSpec:
    return ControllerSpec(name, f"agents.controllers.factories:{attr}", **metadata)


def _shipped_agent(name: str, algo: str, actuators: str) -> ControllerSpec:
    """A learned entry whose agent is shipped in ``agents/shipped/<name>/`` and enters the
    headline with the one actuator set it was trained for (factory
    ``factories.<name with _ for ->``)."""
    return _builtin(
        name,
        name.replace("-", "_"),
        kind="learned",
        actuators=(actuators,),
        algo=algo,
        shipped=name,
        entrant=(actuators,),
    )


_BUILTINS: tuple[ControllerSpec, ...] = (
    _builtin(
        "passive", "passive", actuators=(LEVITATION, GUIDED), default=True, entrant=(LEVITATION,)
    ),
    _builtin(
        "pid", "pid", actuators=(LEVITATION, GUIDED), default=True, entrant=(LEVITATION, GUIDED)
    ),
    _builtin(
        "lqr", "lqr", actuators=(LEVITATION, GUIDED), default=True, entrant=(LEVITATION, GUIDED)
    ),
    _builtin(
        "lqr-preview", "lqr_preview", actuators=(LEVITATION, GUIDED), entrant=(LEVITATION, GUIDED)
    ),
    _builtin("mpc", "mpc", actuators=(LEVITATION, GUIDED), entrant=(LEVITATION,)),
    _builtin("mpc-preview", "mpc_preview", actuators=(LEVITATION, GUIDED)),
    _shipped_agent("ppo", "ppo", LEVITATION),
    _shipped_agent("ppo-memory", "ppo", LEVITATION),
    _shipped_agent("sac", "sac", LEVITATION),
    _shipped_agent("ppo-guidance", "ppo", GUIDED),
    _shipped_agent("ppo-residual-guidance", "ppo", GUIDED),
)
BUILTINS: dict[str, ControllerSpec] = {s.name: s for s in _BUILTINS}
"""The built-in entries (``ppo`` acts on the four levitation currents, ``ppo-guidance`` on the
levitation and guidance currents; both are shipped)."""

_REGISTRY: dict[str, ControllerSpec] = dict(BUILTINS)


def register_controller(
    name: str, factory: str | Factory, *, overwrite: bool = False, **metadata: Any
) -> ControllerSpec:
    """Register ``factory(env_or_params, **kwargs) -> Controller`` under ``name``:
    ``factory`` an entry point ``"package.module:factory"`` (reaches worker processes, see
    the module docstring) or a callable (this process only); ``metadata``: the fields of
    :class:`ControllerSpec` (``kind``, ``actuators``, ``algo``, ``shipped``, ``default``,
    ``entrant``, ``entrant_seeds``). Returns the entry."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"controller name must be a non-empty string, got {name!r}")
    if name in _REGISTRY and not overwrite:
        raise ValueError(f"controller {name!r} is already registered (pass overwrite=True)")
    if not isinstance(factory, str) and not callable(factory):
        raise ValueError(f"factory must be callable or 'package.module:factory', got {factory!r}")
    unknown = set(metadata) - {
        "kind",
        "actuators",
        "algo",
        "shipped",
        "default",
        "entrant",
        "entrant_seeds",
    }
    if unknown:
        raise TypeError(f"register_controller: unknown metadata {sorted(unknown)}")
    spec = ControllerSpec(name, factory, **metadata)
    _REGISTRY[name] = spec
    return spec


def registrations() -> tuple[ControllerSpec, ...]:
    """This process's registrations by entry point (not the built-ins, not callables): what
    a worker process needs to :func:`adopt` to build the same names (picklable)."""
    return tuple(
        s
        for s in _REGISTRY.values()
        if isinstance(s.entry_point, str) and BUILTINS.get(s.name) is not s
    )


def adopt(specs: Iterable[ControllerSpec]) -> None:
    """Register ``specs`` (a parent's :func:`registrations`) in this process, replacing
    entries of the same name; run by a worker before it builds a controller."""
    for s in specs:
        _REGISTRY[s.name] = s


SHIELD_PREFIX = "shielded:"
"""``shielded:<name>``: the controller ``<name>`` wearing the safety filter
(:class:`agents.controllers.shield.Shield`, its default design; from Python
``make_controller("shielded:lqr", env, margin_mm=…, limit_mm=…, horizon_steps=…)``, the
other keywords going to ``<name>``'s factory)."""


def shielded_target(name: str) -> str | None:
    """The controller a ``shielded:<name>`` wears the filter on (None: not a shielded name)."""
    if isinstance(name, str) and name.startswith(SHIELD_PREFIX):
        return name[len(SHIELD_PREFIX) :]
    return None


def unshielded(name: str) -> str:
    """``name`` without its ``shielded:`` prefix (if any)."""
    inner = shielded_target(name)
    return name if inner is None else inner


def _shield_factory(name: str, inner: str) -> Factory:
    """The factory of ``shielded:<inner>``: ``inner`` built by :func:`make_controller`, then
    wrapped in the filter (the filter's keywords taken out, the rest passed on)."""
    if not inner:
        raise ControllerError(f"controller {name!r}: name the controller to shield (shielded:lqr)")
    if shielded_target(inner) is not None:
        raise ControllerError(f"controller {name!r}: a controller wears one shield, not two")
    try:
        resolve(inner)  # an unknown controller is an error now, naming both
    except ControllerError as exc:
        raise ControllerError(f"controller {name!r}: {exc}") from None

    def make(env_or_params: Any = None, **kw: Any) -> Controller:
        from agents.controllers.base import control_context
        from agents.controllers.shield import SHIELD_KEYWORDS, Shield

        own = {k: kw.pop(k) for k in list(kw) if k in SHIELD_KEYWORDS}
        ctrl = make_controller(inner, env_or_params, **kw)
        return Shield(ctrl, control_context(env_or_params), **own)

    make.__qualname__ = make.__name__ = "shielded"
    return make


def controller_spec(name: str) -> ControllerSpec | None:
    """The registry entry of ``name`` (None: not a registry name); for ``shielded:<name>``
    the entry of ``<name>`` under the shielded name (its kind, actuators and shipped agent;
    neither a default nor an entrant)."""
    if not isinstance(name, str):
        return None
    inner = shielded_target(name)
    if inner is not None:
        spec = _REGISTRY.get(inner)
        if spec is None:
            return None

        def make(env_or_params: Any = None, **kw: Any) -> Controller:
            return _shield_factory(name, inner)(env_or_params, **kw)

        return ControllerSpec(
            name,
            make,
            kind=spec.kind,
            actuators=spec.actuators,
            algo=spec.algo,
            shipped=spec.shipped,
            entrant_seeds=spec.entrant_seeds,
        )
    return _REGISTRY.get(name)


def default_controllers() -> list[str]:
    """The controllers the tools run when none are given (``evaluate``, ``fragility``; the
    baselines a trained agent is compared with), in registry order."""
    return [s.name for s in _REGISTRY.values() if s.default]


def entrants(actuators: str) -> list[str]:
    """The controllers entering the headline benchmark with the actuator set
    ``actuators``, in registry order."""
    return [s.name for s in _REGISTRY.values() if actuators in s.entrant]


SHIPPED_FILES = ("model.zip", "vecnormalize.pkl", "training_log.json")
"""The files of a shipped agent (``agents/shipped/<name>/``) that loading it reads."""


def shipped_folder(name: str) -> Path | None:
    """The folder of the agent shipped for the registry name ``name`` (None: the entry has
    no ``shipped`` folder; the folder need not exist)."""
    from agents.controllers.learned import shipped_path

    spec = controller_spec(name)
    return shipped_path(spec.shipped) if spec is not None and spec.shipped else None


def learned_spec(name: str) -> tuple[str, str] | None:
    """(algorithm, shipped folder) of a learned entry with a shipped folder, else None."""
    spec = controller_spec(name)
    if spec is None or spec.kind != "learned" or not spec.algo or not spec.shipped:
        return None
    return spec.algo, spec.shipped


def check_shipped(name: str) -> None:
    """A shipped agent is package data: a missing file of it is an error naming the file
    (not an agent with unnormalised observations or another action set)."""
    from agents.controllers.learned import MODEL_FILE, shipped_path

    folder = shipped_folder(name) or shipped_path(name)
    if not (folder / MODEL_FILE).is_file():
        return  # not shipped at all: make_learned says so (and how to train one)
    for f in SHIPPED_FILES:
        require_data_file(folder / f, f"the shipped {name!r} agent")


def _is_shipped(name: str) -> bool:
    from agents.controllers.learned import MODEL_FILE

    folder = shipped_folder(name)
    return folder is not None and (folder / MODEL_FILE).is_file()


def is_entry_point(name: str) -> bool:
    """``name`` is a user's controller given as ``"package.module:factory"`` or as the path
    of a saved Stable-Baselines3 model (``.../model.zip``, or a run directory holding one)."""
    if not isinstance(name, str) or name in _REGISTRY:
        return False
    inner = shielded_target(name)
    if inner is not None:
        return is_entry_point(inner)
    if _ENTRY_POINT.match(name):
        return True
    p = Path(name)
    return p.suffix == ".zip" or (p.is_dir() and (p / "model.zip").is_file())


def import_entry_point(entry_point: str, name: str | None = None) -> Factory:
    """The callable ``"package.module:attr"`` names, imported; :class:`ControllerError` (a
    ``ValueError``) in one line (naming the controller ``name``, default the entry point)
    if it cannot be — the module missing or failing on import, the attribute missing."""
    label = entry_point if name is None else name
    mod_name, _, attr = entry_point.partition(":")
    try:
        obj: Any = importlib.import_module(mod_name)
    except ImportError as exc:
        raise ControllerError(f"controller {label!r}: cannot import {mod_name!r} ({exc})") from None
    except Exception as exc:  # the module raised on import (a syntax error, …)
        where = _source_of(exc) or mod_name
        raise ControllerError(
            f"controller {label!r}: importing {mod_name!r} failed ({where}): "
            f"{type(exc).__name__}: {exc}"
        ) from exc
    for part in attr.split("."):
        obj = getattr(obj, part, None)
        if obj is None:
            raise ControllerError(f"controller {label!r}: {mod_name!r} has no {attr!r}")
    if not callable(obj):
        raise ControllerError(f"controller {label!r}: {attr!r} is not callable")
    return obj


def _source_of(exc: BaseException) -> str:
    """The file an exception was raised in (its traceback's last frame), or ""."""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    filename = getattr(exc, "filename", None) if isinstance(exc, SyntaxError) else None
    return str(filename or (tb.tb_frame.f_code.co_filename if tb is not None else ""))


def resolve(name: str) -> Factory:
    """The factory of a registry name, of an entry point ``"package.module:factory"`` or of
    the path of a saved model (:func:`is_entry_point`); a name that cannot be built raises
    :class:`ControllerError` (a ``ValueError``) in one line. Entry points are imported in
    the process that builds the controller, so they reach spawned and Ray workers with no
    registration."""
    if not isinstance(name, str):
        raise ControllerError(f"controller must be a name, got {name!r}")
    if name in _REGISTRY:
        return _REGISTRY[name].factory()
    inner = shielded_target(name)
    if inner is not None:
        return _shield_factory(name, inner)
    if _ENTRY_POINT.match(name):
        return import_entry_point(name)
    p = Path(name)
    if p.suffix == ".zip" or p.is_dir():
        model = p if p.suffix == ".zip" else p / "model.zip"
        if not model.is_file():
            raise ControllerError(f"controller {name!r}: no Stable-Baselines3 model at {model}")

        def make(env_or_params: Any = None, **kw: Any) -> Controller:
            require_extra("train", f"controller {name!r} (a saved Stable-Baselines3 model)")
            from agents.controllers.learned import SB3Controller, _check_plant

            ctrl = SB3Controller(model, name=kw.pop("name", name), **kw)
            _check_plant(ctrl, env_or_params)
            return ctrl

        return make
    raise ControllerError(
        f"unknown controller {name!r}; available: {offered_controllers()}, or "
        "'package.module:factory', or the path of a saved model.zip (any of them as "
        "'shielded:<name>' with the safety filter)"
    )


def available_controllers() -> list[str]:
    """Names accepted by :func:`make_controller`."""
    return sorted(_REGISTRY)


def controller_problem(name: str, kwargs: dict[str, Any] | None = None) -> str | None:
    """Why ``make_controller(name, **kwargs)`` cannot build ``name`` here, in one line (an
    unknown name or an entry point that does not import, a learned agent that is neither
    shipped nor given a ``path``, the ``train`` extra missing for a learned agent), or None;
    for validating a command line before any work starts."""
    try:
        resolve(name)
    except ValueError as exc:
        return str(exc)
    inner = shielded_target(name)
    if inner is not None:
        return controller_problem(inner, kwargs)
    spec = controller_spec(name)
    if spec is None:
        if not _ENTRY_POINT.match(name):  # a saved model
            miss = missing_modules("train")
            if miss:
                return missing_extra_message("train", f"controller {name!r}", miss)
        return None
    if spec.kind != "learned":
        return None
    if spec.shipped is not None and (kwargs or {}).get("path") is None and not _is_shipped(name):
        from agents.controllers.learned import MODEL_FILE

        return (
            f"controller {name!r}: no agent of it is shipped ({shipped_folder(name) / MODEL_FILE} "
            f"does not exist); controllers available here: {offered_controllers()}"
        )
    miss = missing_modules("train")
    if miss:
        return missing_extra_message("train", f"controller {name!r}", miss)
    return None


def offered_controllers() -> list[str]:
    """The names the command-line tools offer: the registry's, less the learned ones whose
    agent is not shipped (then ``make_controller(name, path=run_dir)`` takes a run)."""
    return [
        n
        for n in available_controllers()
        if _REGISTRY[n].kind != "learned" or _REGISTRY[n].shipped is None or _is_shipped(n)
    ]


def make_controller(name: str, env_or_params: Any = None, **kwargs: Any) -> Controller:
    """Build the controller registered as ``name`` — or given as an entry point
    ``"package.module:factory"`` or the path of a saved SB3 ``model.zip``
    (:func:`is_entry_point`) — for the plant ``env_or_params`` (a Gymnasium env of this
    package, ``ModelParams``, ``Simulator``, ``ControlContext`` or None for the default
    parameters).

    Whatever goes wrong is one :class:`~agents.controllers.base.ControllerError` (a
    ``ValueError``; an option the factory does not take is a ``TypeError`` too, a missing
    file a ``FileNotFoundError`` too) naming the controller and, for a user's factory, its
    file: a name that does not resolve, a model that does not load, a factory that raises
    or returns something else than a controller (an object with ``reset()`` and
    ``act()``). A missing optional dependency stays a
    :class:`~agents.installation.MissingExtraError`.

    The design runs with one BLAS thread (:mod:`hyperloop_env.threads`): the same
    controller, bit for bit, whatever the machine's thread count or the number of
    workers."""
    factory = resolve(name)
    try:
        with one_blas_thread():
            ctrl = factory(env_or_params, **kwargs)
    except (ControllerError, MissingExtraError, MemoryError):
        raise
    except Exception as exc:
        raise controller_error(name, exc, factory_origin(name, factory)) from exc
    problem = controller_shape_problem(ctrl)
    if problem:
        where = factory_origin(name, factory)
        raise ControllerError(
            f"controller {name!r}: its factory{f' ({where})' if where else ''} {problem}"
        )
    return ctrl


BUILTIN_FACTORIES = "agents.controllers.factories"
"""The module of the built-in controllers' factories (named by no error: it is not the
user's code)."""


def factory_origin(name: str, factory: Factory) -> str:
    """Where the factory of ``name`` lives, for an error message: ``"mod:make in
    /path/mod.py"`` (an entry point of a registry entry), ``"/path/mod.py"`` (the name is
    the entry point), or "" (a built-in, or a saved model: the name is its file)."""
    inner = shielded_target(name)
    if inner is not None:
        return factory_origin(inner, resolve(inner))
    spec = controller_spec(name)
    if spec is None and not _ENTRY_POINT.match(name):
        return ""
    ep = spec.entry_point if spec is not None else name
    if isinstance(ep, str) and ep.partition(":")[0] == BUILTIN_FACTORIES:
        return ""
    try:
        file = inspect.getsourcefile(factory) or ""
    except TypeError:  # a builtin or a callable object without source
        file = ""
    label = ep if isinstance(ep, str) else getattr(factory, "__qualname__", "")
    if label == name or not label:
        return file
    return f"{label} in {file}" if file else label
