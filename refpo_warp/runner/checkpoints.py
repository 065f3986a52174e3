"""Checkpoints: the one way refpo_warp reads them, for resume, evaluation, export and a user-given ``checkpoint=``.

A checkpoint is read with ``torch.load(weights_only=True)``: only tensors and plain containers are rebuilt, so a
crafted file cannot run code (rsl_rl's own ``OnPolicyRunner.load`` unpickles arbitrary objects; ``Runner.load``
replaces it with ``load_checkpoint``). Every problem raises ``CheckpointError`` naming the file: missing, empty,
truncated, not a checkpoint, holding objects other than plain data, NaN weights, written by another task or
algorithm, or of another network shape. ``load_latest`` resumes from the newest checkpoint that passes all of
this and says which newer ones it skipped and why.
"""

from __future__ import annotations

import math
import re
import sys
import zipfile
from pathlib import Path
from typing import Any

import torch

from refpo_warp.utils.errors import CheckpointError
from refpo_warp.utils.rsl_rl_versions import uncompiled

CHECKPOINT_PATTERN = re.compile(r"^model_(\d+)\.pt$")
REQUIRED_KEYS = ("actor_state_dict", "critic_state_dict", "optimizer_state_dict", "iter")
META_KEY = "refpo_warp"  # {"task", "algo", "env_steps", "time_s"}, written by refpo_warp.runner.Runner.save


def _meta(data: dict) -> dict:
    """The refpo_warp entry of a checkpoint (``META_KEY``); empty when another writer's checkpoint has none."""
    meta = data.get(META_KEY)
    return meta if isinstance(meta, dict) else {}


def list_checkpoints(run_dir: str | Path) -> list[Path]:
    """``model_<it>.pt`` files in ``run_dir``, newest (highest iteration) first; temp files are not listed."""
    found = [(int(m.group(1)), p) for p in Path(run_dir).glob("model_*.pt") if (m := CHECKPOINT_PATTERN.match(p.name))]
    return [p for _, p in sorted(found, reverse=True)]


def latest_checkpoint(run_dir: str | Path) -> Path | None:
    """The checkpoint with the highest iteration in ``run_dir`` (None if there is none)."""
    found = list_checkpoints(run_dir)
    return found[0] if found else None


def read_checkpoint(path: str | Path, map_location: str | None = "cpu") -> dict[str, Any]:
    """Read and check a checkpoint file without unpickling anything but tensors and plain data."""
    path = Path(path)
    if not path.exists():
        raise CheckpointError(f"{path}: no such checkpoint file")
    if not path.is_file():
        raise CheckpointError(f"{path}: not a file (a checkpoint is a model_<iteration>.pt file)")
    if path.stat().st_size == 0:
        raise CheckpointError(f"{path}: empty file (0 bytes); it is not a usable checkpoint")
    with open(path, "rb") as f:
        zipped = f.read(4) == b"PK\x03\x04"
    if zipped and not zipfile.is_zipfile(path):
        raise CheckpointError(f"{path}: truncated: its zip archive ends early (was the write interrupted?)")
    try:
        data = torch.load(path, map_location=map_location, weights_only=True)
    except Exception as err:  # (torch raises many types for a bad file; each becomes one message)
        text = " ".join(str(err).split())
        if "Weights only load failed" in text and "GLOBAL" in text:
            found = re.search(r"GLOBAL ([\w.]+)", text)
            what = f" (it asks for {found.group(1)})" if found else ""
            raise CheckpointError(
                f"{path}: refused: the file holds Python objects other than tensors and plain data{what}. Nothing "
                f"in it was run. A checkpoint never holds such objects: the file is corrupt or was crafted"
            ) from None
        raise CheckpointError(
            f"{path}: cannot be read as a checkpoint; it is truncated or not a torch checkpoint "
            f"({type(err).__name__}: {text[:200]})"
        ) from None
    _check_contents(path, data)
    return data


def _check_contents(path: Path, data: Any) -> None:
    if not isinstance(data, dict):
        raise CheckpointError(f"{path}: not a checkpoint: it holds a {type(data).__name__}, not a dict of states")
    missing = [k for k in REQUIRED_KEYS if k not in data]
    if missing:
        raise CheckpointError(
            f"{path}: not an rsl_rl/refpo_warp checkpoint: missing {', '.join(missing)} "
            f"(found: {', '.join(map(str, list(data)[:8])) or 'nothing'})"
        )
    if not isinstance(data["iter"], int) or isinstance(data["iter"], bool) or data["iter"] < 0:
        raise CheckpointError(f"{path}: 'iter' must be a non-negative integer, got {data['iter']!r}")
    for key in ("actor_state_dict", "critic_state_dict"):
        state = data[key]
        if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
            raise CheckpointError(f"{path}: '{key}' is not a state dict of tensors")
        for name, tensor in state.items():
            if tensor.is_floating_point() and not bool(torch.isfinite(tensor).all()):
                raise CheckpointError(
                    f"{path}: '{key}' holds NaN or infinite values in '{name}'; the weights are unusable"
                )


def check_fits(path: str | Path, data: dict, alg, task: str | None = None, algo: str | None = None) -> None:
    """Refuse a checkpoint written by another task or algorithm, or whose tensors do not fit ``alg``'s models."""
    meta = _meta(data)
    for name, expected in (("task", task), ("algo", algo)):
        if expected is not None and meta.get(name) is not None and meta[name] != expected:
            raise CheckpointError(f"{path}: written by a run with {name}={meta[name]}; this run has {name}={expected}")
    for key, model in (
        ("actor_state_dict", uncompiled(alg, "actor")),
        ("critic_state_dict", uncompiled(alg, "critic")),
    ):
        have = {k: tuple(v.shape) for k, v in model.state_dict().items()}
        got = {k: tuple(v.shape) for k, v in data[key].items()}
        problems = [f"'{k}' missing" for k in have if k not in got]
        problems += [f"'{k}' unexpected" for k in got if k not in have]
        problems += [
            f"'{k}' is {got[k]} in the file, {have[k]} in the model" for k in have if k in got and got[k] != have[k]
        ]
        if problems:
            more = f" (and {len(problems) - 3} more)" if len(problems) > 3 else ""
            raise CheckpointError(
                f"{path}: does not fit this run's {key.split('_')[0]} network: {'; '.join(problems[:3])}{more}. "
                f"Was it written by another task or network size?"
            )


def apply_checkpoint(runner, path: str | Path, data: dict, load_cfg: dict | None = None, strict: bool = True) -> None:
    """Load a checked checkpoint into ``runner`` (models, optimizer, iteration, and the env steps and training time
    it recorded)."""
    alg = runner.alg
    try:
        load_iteration = alg.load(data, load_cfg, strict)
    except (RuntimeError, ValueError, KeyError, TypeError) as err:
        raise CheckpointError(f"{path}: cannot be loaded into this run ({' '.join(str(err).split())[:300]})") from None
    if load_cfg is None or load_cfg.get("optimizer"):
        # rsl_rl >= 5.5 does this itself; 5.0 keeps the constructor's rate while the optimizer has the restored one
        alg.learning_rate = alg.optimizer.param_groups[0]["lr"]
    if load_iteration:
        runner.current_learning_iteration = data["iter"]
    env_steps, time_s = checkpoint_progress(data)
    if env_steps is not None:
        runner.logger.tot_timesteps, runner.logger.tot_time = env_steps, time_s or 0.0


def load_latest(runner, run_dir: str | Path, task: str | None = None, algo: str | None = None) -> tuple[Path, dict]:
    """Load the newest usable checkpoint of ``run_dir`` into ``runner``; newer unusable ones are skipped with a
    warning that names each file and its problem. Raises ``CheckpointError`` when none is usable."""
    problems = []
    for path in list_checkpoints(run_dir):
        try:
            data = read_checkpoint(path, map_location=runner.device)
            check_fits(path, data, runner.alg, task, algo)
            apply_checkpoint(runner, path, data)
        except CheckpointError as err:
            problems.append(str(err))
            print(f"warning: skipping checkpoint {err}", file=sys.stderr, flush=True)
            continue
        if problems:
            print(
                f"warning: continuing from {path.name} (iteration {data['iter']}), the newest usable checkpoint; "
                f"{len(problems)} newer one(s) skipped (see above)",
                file=sys.stderr,
                flush=True,
            )
        return path, data
    if not problems:
        raise CheckpointError(f"{run_dir}: no checkpoint (model_<iteration>.pt) found")
    listing = "\n  ".join(problems)
    raise CheckpointError(f"{run_dir}: none of its {len(problems)} checkpoint(s) can be used:\n  {listing}")


def checkpoint_progress(data: dict) -> tuple[int | None, float | None]:
    """(env steps, training seconds) recorded in a checkpoint by refpo_warp, or (None, None) for other writers."""
    meta = _meta(data)
    steps, seconds = meta.get("env_steps"), meta.get("time_s")
    valid_steps = steps if isinstance(steps, int) and steps >= 0 else None
    valid_time = (
        float(seconds) if isinstance(seconds, (int, float)) and math.isfinite(seconds) and seconds >= 0 else None
    )
    return valid_steps, valid_time
