"""What a ``class_name`` selects and what its constructor accepts: the class (only a model or an algorithm), its
options with their defaults and the class that declares each default.

The options of a class are its ``option`` fields and its bases' that have a default of their own
(``refpo_warp/utils/options.py``), its constructor's keyword parameters, and those of the bases it forwards
``**kwargs`` to (ReFPO -> OnPolicyAlgorithm -> rsl_rl's PPO, whose rules are in
``refpo_warp/utils/rsl_rl_options.py``), minus what rsl_rl passes itself (``POSITIONAL``).
"""

from __future__ import annotations

import inspect
from typing import Any

from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.options import declared_options, option_fields

CLASS_SECTIONS = ("actor", "critic", "algorithm")
# Constructor arguments that rsl_rl itself passes positionally; a config must not set them.
POSITIONAL = {
    "actor": ("obs", "obs_groups", "obs_set", "output_dim"),
    "critic": ("obs", "obs_groups", "obs_set", "output_dim"),
    "algorithm": ("actor", "critic", "storage", "device", "multi_gpu_cfg"),
}
CONSTRUCT_ALGORITHM_KEYS = {"share_cnn_encoders": None}  # consumed by rsl_rl's construct_algorithm


def resolve_class(class_name: str) -> type:
    """The class a ``class_name`` string selects (``"pkg.mod:Class"``, or a bare rsl_rl name)."""
    from rsl_rl.utils import resolve_callable

    try:
        return resolve_callable(class_name)
    except (ImportError, AttributeError, ValueError, TypeError) as err:
        raise ConfigError(f"Cannot resolve class_name '{class_name}': {err}") from err


def class_defaults(class_name: str) -> dict[str, tuple[Any, type]]:
    """Every option of the class: name -> (default, the class that declares it), a subclass's first; the fields of
    the ``option`` fields, then the keyword parameters of the constructor chain (a parameter without a default
    has None)."""
    cls = resolve_class(class_name)
    params: dict[str, tuple[Any, type]] = {}
    declared = declared_options(cls) if inspect.isclass(cls) else {}
    for klass in inspect.getmro(cls) if inspect.isclass(cls) else [cls]:
        for name in option_fields(klass) if inspect.isclass(klass) else ():
            if name in declared:
                params.setdefault(name, (declared[name].default, declared[name].owner))
        init = klass.__init__ if inspect.isclass(klass) else klass
        if init is object.__init__:
            continue
        has_var_kw = False
        for name, p in inspect.signature(init).parameters.items():
            if p.kind is p.VAR_KEYWORD:
                has_var_kw = True
            elif p.kind is not p.VAR_POSITIONAL and name != "self":
                params.setdefault(name, (None if p.default is p.empty else p.default, klass))
        if not has_var_kw:  # a class that does not forward **kwargs ends the chain
            break
    return params


def class_parameters(class_name: str) -> dict[str, Any]:
    """Constructor keyword parameters (with defaults) of ``class_name`` and of the bases it forwards to."""
    return {name: default for name, (default, _) in class_defaults(class_name).items()}


def section_options(section: str, class_name: str) -> dict[str, Any]:
    """The options a config section may set for ``class_name`` (without rsl_rl's positional arguments)."""
    params = class_parameters(class_name)
    for name in POSITIONAL[section]:
        params.pop(name, None)
    if section == "algorithm":
        params.update(CONSTRUCT_ALGORITHM_KEYS)
    return params


def check_class_kind(section: str, class_name: str) -> type:
    """The class of a section's class_name: a model (actor, critic: a torch Module) or an algorithm (a class with
    rsl_rl's ``construct_algorithm``), never an arbitrary callable such as ``os:system`` named in an edited file."""
    import torch

    cls = resolve_class(class_name)
    if section in ("actor", "critic"):
        valid = inspect.isclass(cls) and issubclass(cls, torch.nn.Module)
        kind = "a model class (a torch.nn.Module, e.g. refpo_warp.models:FlowActor or rsl_rl.models:MLPModel)"
    else:
        valid = inspect.isclass(cls) and callable(getattr(cls, "construct_algorithm", None))
        kind = "an algorithm class with rsl_rl's construct_algorithm (e.g. refpo_warp.algorithms:ReFPO)"
    if not valid:
        raise ConfigError(f"{section}.class_name={class_name!r} is invalid; expected {kind}")
    return cls
