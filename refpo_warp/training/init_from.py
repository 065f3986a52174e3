"""``init_from=<pretrain run dir>``: a new training run starts from a cloned actor (``refpo pretrain``) and its
observation normaliser, after checking that the clone fits this run.

Refused, naming what differs (exit 4, before anything is written): a folder that is not a run or holds no checkpoint,
a clone of another task, of an actor of another class or options (hidden sizes, activation, output scale, ...; the
flow-step count and the action noise may differ, as on resume), of other observation groups or env options that
change the spaces, and a checkpoint whose actor tensors do not fit this run's actor. The critic keeps its
initialisation, except its observation normaliser, which the clone set from the data.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from refpo_warp.config.saved import fixed_changes, read_saved_config
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.runner.checkpoints import latest_checkpoint, read_checkpoint
from refpo_warp.utils.errors import CheckpointError, ConfigError, DataFileError
from refpo_warp.utils.rsl_rl_versions import uncompiled

COMPARED = ("task", "actor.", "env.", "runner.obs_groups")  # what a clone must share with the run it starts


def init_differences(saved: dict, cfg: dict, task: TaskSpec) -> list[str]:
    """``key: clone's -> run's`` for every option the clone and the run must share and do not (``task``: the spec of
    the run's task)."""
    changes = [c for c in fixed_changes(saved, cfg, task) if c.startswith(COMPARED)]
    if saved.get("task") != cfg["task"]:
        changes.insert(0, f"task: {saved.get('task')!r} -> {cfg['task']!r}")
    return list(dict.fromkeys(changes))


def load_init_from(runner: Any, cfg: dict, task: TaskSpec) -> Path:
    """Load the cloned actor of ``cfg['init_from']`` into ``runner`` (and the critic's normaliser); returns the
    checkpoint read. Raises ``DataFileError``/``CheckpointError`` naming what does not fit."""
    source = Path(cfg["init_from"])
    try:
        saved = read_saved_config(source)
    except ConfigError as err:
        raise DataFileError(f"init_from={source}: {err}") from None
    differences = init_differences(saved, cfg, task)
    if differences:
        raise DataFileError(
            f"init_from={source}: the cloned actor does not fit this run; these differ (clone -> "
            f"run): {'; '.join(differences)}"
        )
    path = latest_checkpoint(source)
    if path is None:
        raise DataFileError(f"init_from={source}: no checkpoint (model_<iteration>.pt) in it; run refpo pretrain first")
    data = read_checkpoint(path, map_location=runner.device)
    actor = uncompiled(runner.alg, "actor")
    _check_shapes(path, "actor", actor.state_dict(), data["actor_state_dict"])
    actor.load_state_dict(data["actor_state_dict"])
    critic = uncompiled(runner.alg, "critic")
    normaliser = {k: v for k, v in data["critic_state_dict"].items() if "obs_normalizer" in k}
    if normaliser and all(
        k in critic.state_dict() and critic.state_dict()[k].shape == v.shape for k, v in normaliser.items()
    ):
        critic.load_state_dict(normaliser, strict=False)
    ema = getattr(runner.alg, "ema", None)
    if ema is not None and hasattr(ema, "reset"):
        ema.reset(actor)
    return path


def _check_shapes(path: Path, name: str, have: dict, got: dict) -> None:
    problems = [f"'{k}' missing" for k in have if k not in got]
    problems += [f"'{k}' unexpected" for k in got if k not in have]
    problems += [
        f"'{k}' is {tuple(got[k].shape)} in the file, {tuple(have[k].shape)} in the model"
        for k in have
        if k in got and got[k].shape != have[k].shape
    ]
    if problems:
        more = f" (and {len(problems) - 3} more)" if len(problems) > 3 else ""
        raise CheckpointError(f"{path}: does not fit this run's {name} network: {'; '.join(problems[:3])}{more}")
