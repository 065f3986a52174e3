"""What differs between the rsl-rl-lib versions the project supports (``>=5.0.1,<6``), kept in one place.

Found by diffing the installed 5.0.1 (Isaac Lab's pin) and 5.5.1 packages:

- ``PPO.__init__`` gained ``use_mixed_precision`` and ``grad_reduce_bucket_mb`` in 5.5; older versions reject
  unknown keys with a TypeError. ``split_newer_ppo_args`` takes them out of the kwargs there (refpo_warp's shared
  update loop applies ``use_mixed_precision`` itself on every version).
- Before 5.5, ``PPO.process_env_step`` updates the observation normalisers at every env step; from 5.5 on
  ``PPO.update`` updates them once after the gradient steps, and ``EmpiricalNormalization`` all-reduces its
  statistics across ranks. refpo_warp's update loop updates them only where the installed version does not
  (``NORMALIZERS_UPDATE_PER_STEP``), so a normaliser never sees a batch twice.
- ``torch_compile_mode`` (``PPO.compile``) arrived in 5.1; 5.0.x ignores the key.
- ``GaussianDistribution`` takes ``learn_std`` (a fixed std) from 5.2 on; ``split_learn_std`` lets a model freeze the
  std itself on older versions.
- Before 5.5, rsl_rl pops ``class_name`` out of the config dicts it is given (actor, critic, algorithm,
  ``distribution_cfg``); callers hand it copies.
- The logger takes a ``{"class_name": ...}`` writer dict from 5.4 on; 5.0.x knows only the strings
  ``"tensorboard"``, ``"wandb"`` and ``"neptune"``.
- From 5.5 on, PPO keeps the uncompiled actor and critic as ``_raw_actor`` / ``_raw_critic`` beside the (possibly
  ``torch.compile``d) ``actor`` / ``critic``; older versions have only those (``uncompiled``).

The runner (``_configure_multi_gpu``, ``learn``, ``save``/``load``), the rollout storage and the model protocol
that refpo_warp relies on are the same across the range.
"""

from __future__ import annotations

import inspect
import re
import warnings
from importlib import metadata

from rsl_rl.algorithms import PPO as RslPPO
from rsl_rl.modules.distribution import GaussianDistribution


def _version(dist: str) -> tuple[int, int]:
    major, minor = (int(part) for part in re.findall(r"\d+", metadata.version(dist))[:2])
    return major, minor


RSL_RL_VERSION = _version("rsl-rl-lib")
NORMALIZERS_UPDATE_PER_STEP = RSL_RL_VERSION < (5, 5)
HAS_COMPILE = hasattr(RslPPO, "compile")

# Constructor arguments of newer PPOs, with the value that means "off" (what older versions effectively do).
NEWER_PPO_ARGS = {"use_mixed_precision": False, "grad_reduce_bucket_mb": 25}
_PPO_PARAMETERS = frozenset(inspect.signature(RslPPO.__init__).parameters)
PPO_ARGUMENTS = _PPO_PARAMETERS | frozenset(NEWER_PPO_ARGS)  # rsl_rl's PPO arguments on some supported version
GAUSSIAN_HAS_LEARN_STD = "learn_std" in inspect.signature(GaussianDistribution.__init__).parameters


def split_newer_ppo_args(kwargs: dict, honoured: tuple[str, ...] = ()) -> dict:
    """Pop (and return) the arguments in ``kwargs`` that the installed rsl_rl ``PPO`` does not accept.

    A popped argument set to anything but its "off" value gets a warning, unless the caller handles it itself
    (``honoured``, e.g. refpo_warp's update loop applies ``use_mixed_precision`` on every version).
    """
    newer = {key: kwargs.pop(key) for key in NEWER_PPO_ARGS if key in kwargs and key not in _PPO_PARAMETERS}
    for key, value in newer.items():
        if key not in honoured and value != NEWER_PPO_ARGS[key]:
            warnings.warn(
                f"rsl-rl-lib {metadata.version('rsl-rl-lib')} has no PPO argument '{key}' (added in 5.5); "
                f"'{key}={value}' is ignored.",
                stacklevel=3,
            )
    return newer


def split_learn_std(distribution_cfg: dict | None) -> tuple[dict | None, bool]:
    """``(distribution_cfg for the installed rsl_rl, learn_std)``: where its distributions lack ``learn_std``
    (rsl-rl-lib < 5.2), the key is taken out of a copy and the caller freezes the std when it is False."""
    if not distribution_cfg or "learn_std" not in distribution_cfg or GAUSSIAN_HAS_LEARN_STD:
        return distribution_cfg, True
    cfg = dict(distribution_cfg)
    return cfg, bool(cfg.pop("learn_std"))


def uncompiled(alg, name: str):
    """The algorithm's model ``name`` (``actor`` or ``critic``) without ``torch.compile``'s wrapper (see above)."""
    raw = getattr(alg, f"_raw_{name}", None)
    return raw if raw is not None else getattr(alg, name)
