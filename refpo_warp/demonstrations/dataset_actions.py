"""What a demonstration dataset's actions are, and the actions a clone trains on (``pretrain.dataset_actions``).

On a task whose env squashes the policy's action with tanh (``env.action_transform=tanh``: the DMC tasks) the policy,
and every learner, works with the action before the squash; the env applies tanh of it, in [-1, 1]. A dataset holds
one of the two:

- ``pre_squash``: the policy's own actions (what ``refpo collect`` writes, and records in its metadata): the clone
  trains on them as they are;
- ``env_units``: the actions the env applied, in [-1, 1] (most public datasets: a ``Box(-1, 1)`` action space): the
  clone trains on ``atanh(clip(a, -b, b))``, ``b = 1 - pretrain.squash_margin`` (1e-6: ``b = 0.999999``, so an action
  at the bound becomes ``±atanh(0.999999) = ±7.2543``, whose tanh, the action the env applies, is 1e-6 inside the
  bound). A value beyond ``1 + ENV_UNITS_TOLERANCE`` is no env action: refused, naming the episode;
- ``auto`` (the default) decides from the file: the units ``refpo collect`` records (``action_units`` in its ``refpo``
  entry; a ``refpo`` entry without them, written before they were recorded: ``pre_squash``; refused where the env it
  records squashed and this run's does not, or the other way round); else an action space unbounded in every dimension
  (no tanh output) is ``pre_squash``; a bounded one is ``env_units`` where the env does not squash, and refused on a
  tanh task (exit 4, naming both settings): a bounded space does not say which the values are (a collector may store the
  sampled pre-tanh action under the env's declared ``Box(-1, 1)``), and a wrong guess either way changes every action
  the clone learns without a sign, while the user knows the dataset's source.

On a task that does not squash (``clip``) the policy's action is the env's: both settings take the actions as they
are. The run's ``config.yaml`` holds the setting used (``auto`` replaced by what it decided).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refpo_warp.config.run_options import DatasetActions
from refpo_warp.demonstrations.dataset_file import Dataset
from refpo_warp.utils.errors import DataFileError

AUTO, PRE_SQUASH, ENV_UNITS = (m.value for m in DatasetActions)
ACTION_UNITS_KEY = "action_units"  # refpo collect's record of its actions' units in the dataset's refpo entry
ACTION_TRANSFORM_KEY = "action_transform"  # and of its env's action_transform (tanh: the actions are pre-squash)
ENV_UNITS_TOLERANCE = 1e-6  # env_units: |a| up to 1 + this is rounding at the bound (then clipped), beyond is refused
OPTION = "pretrain.dataset_actions"


def squashes(env) -> bool:
    """Whether ``env`` applies tanh to the policy's actions (``env.action_transform=tanh``)."""
    return getattr(getattr(env, "cfg", None), "action_transform", "clip") == "tanh"


@dataclass(frozen=True)
class ActionUnits:
    """What a dataset's actions are (``units``: pre_squash or env_units) and how they become the clone's."""

    units: str
    squash: bool  # the run's env squashes with tanh
    atanh: bool  # env_units on a tanh task: atanh(clip(a, -bound, bound))
    bound: float  # 1 - squash_margin
    clipped: int  # the dataset's action values beyond the bound (at it, as a bang-bang controller's), clipped

    def apply(self, actions: np.ndarray) -> np.ndarray:
        """The actions the clone trains on (float32), from the dataset's."""
        if not self.atanh:
            return actions
        return np.arctanh(np.clip(actions.astype(np.float64), -self.bound, self.bound)).astype(np.float32)

    def describe(self) -> str:
        if not self.atanh:
            return f"{OPTION}={self.units}: taken as they are" + ("" if self.squash else " (the env does not squash)")
        return (
            f"{OPTION}={self.units}: atanh(clip(a, ±{self.bound:.12g})), {self.clipped:,} value(s) clipped to the "
            f"bound (±{np.arctanh(self.bound):.4f} before tanh)"
        )

    def summary(self) -> dict:
        return {"dataset_actions": self.units, "actions_atanh": self.atanh, "actions_clipped": self.clipped}


def action_units(dataset: Dataset, setting: str, squash: bool, squash_margin: float, task: str) -> ActionUnits:
    """``setting`` (``auto`` decided from ``dataset``) and its conversion on a task that squashes (``squash``) or not;
    ``DataFileError`` (exit 4) where ``auto`` cannot tell on a tanh task or the actions cannot be env units."""
    units = setting if setting != AUTO else _decide(dataset, squash, task)
    atanh = squash and units == ENV_UNITS
    bound = 1.0 - squash_margin
    clipped = 0
    if atanh:
        for i, e in enumerate(dataset.episodes):
            largest = float(np.abs(e.actions).max())
            if largest > 1.0 + ENV_UNITS_TOLERANCE:
                raise DataFileError(
                    f"{dataset.path}: episode {i}: an action of magnitude {largest:.6g} is no action of task {task}'s "
                    f"env, which squashes with tanh into [-1, 1] ({OPTION}={units}); are they the policy's own "
                    f"actions? then {OPTION}={PRE_SQUASH}"
                )
            clipped += int((np.abs(e.actions) > bound).sum())
    return ActionUnits(units, squash, atanh, bound, clipped)


def _decide(dataset: Dataset, squash: bool, task: str) -> str:
    refpo = dataset.refpo
    if refpo:  # written by refpo collect: the policy's own actions (recorded since action_units exists)
        recorded = refpo.get(ACTION_UNITS_KEY, PRE_SQUASH)
        if recorded not in (PRE_SQUASH, ENV_UNITS):
            raise DataFileError(
                f"{dataset.path}: its metadata records {ACTION_UNITS_KEY}={recorded!r}; expected "
                f"'{PRE_SQUASH}' or '{ENV_UNITS}' (or set {OPTION}=...)"
            )
        env = refpo.get("env")
        transform = refpo.get(ACTION_TRANSFORM_KEY, env.get("action_transform") if isinstance(env, dict) else None)
        if transform is not None and (transform == "tanh") != squash:
            raise DataFileError(
                f"{dataset.path}: collected with env.action_transform={transform}, and task {task}'s env "
                f"{'squashes' if squash else 'does not squash'} the policy's actions with tanh: its actions are not "
                f"this run's policy's. Set {OPTION}={ENV_UNITS} (the env's, in [-1, 1]) or {OPTION}={PRE_SQUASH} "
                f"(taken as they are), or clone with env.action_transform={transform}"
            )
        return recorded
    low, high = dataset.action_low, dataset.action_high
    if low is None or high is None or (np.isinf(low).all() and np.isinf(high).all()):
        return PRE_SQUASH  # unbounded: no tanh output
    if not squash:
        return ENV_UNITS  # the env's actions are the policy's: taken as they are either way
    space = f"Box({_bounds(low)}, {_bounds(high)})"
    largest = max(float(np.abs(e.actions).max()) for e in dataset.episodes)
    raise DataFileError(
        f"{dataset.path}: its actions lie in a bounded space, {space} (largest magnitude {largest:.6g}), and task "
        f"{task}'s env squashes the policy's actions with tanh (env.action_transform=tanh): they may be the actions "
        f"the env applied or the policy's before the squash, and the file does not say which. Set "
        f"{OPTION}={ENV_UNITS} (the env's, in [-1, 1]: the clone trains on atanh(a), |a| clipped to "
        f"1 - pretrain.squash_margin) or {OPTION}={PRE_SQUASH} (the policy's: taken as they are)"
    )


def _bounds(values: np.ndarray) -> str:
    return f"{values[0]:g}" if (values == values[0]).all() else "[" + ", ".join(f"{v:g}" for v in values) + "]"
