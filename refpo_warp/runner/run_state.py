"""The state a checkpoint needs beyond the models for a resumed run to go on bit for bit as if it had not stopped:
the random generators (torch's CPU and CUDA ones, numpy's, Python's), the env's state and the logger's episode
bookkeeping (its running episode sums and last finished episodes, so that the progress rows go on as they would).

The env's state is every torch tensor and Warp array the env object reaches through its attributes (its buffers:
observations, episode counters, the per-env random streams; the simulator's state, control and solver data), read
as bytes and written back in place, so that arrays a captured CUDA graph or a kernel aliases stay the same arrays.
Objects named ``Model`` (Newton's and MuJoCo Warp's models: constants built from the task's files), the observation
copies handed out (rewritten at each hand-out) and Python numbers (a graph-capture counter, which copy is handed out
next) are not read: none of them feeds what the env computes. A saved state that does not fit the env (another env
count or task) is not restored: the run then goes on from fresh envs, and says so.
"""

from __future__ import annotations

import random
from typing import Any

import numpy as np
import torch

from refpo_warp.utils.warp_setup import wp

RUN_STATE_KEY = "run_state"  # in a checkpoint: written by Runner.save, read on resume
ENV_STATE_VERSION = 1
WALKED_PACKAGES = ("refpo_warp", "tasks", "newton", "mujoco_warp", "tensordict", "warp")
CONSTANT_CLASSES = ("Model", "ModelBuilder")  # built from the task's files once; never written by a step
HANDED_OUT = ("_obs_out",)  # the copies of the observations handed to the caller, rewritten at every hand-out
MAX_DEPTH = 8


def _walked(obj: Any) -> bool:
    module = type(obj).__module__.split(".")[0]
    return module in WALKED_PACKAGES and type(obj).__name__ not in CONSTANT_CLASSES and hasattr(obj, "__dict__")


def env_arrays(env: Any) -> dict[str, Any]:
    """Every tensor and (contiguous, non-empty) Warp array reachable from ``env``, by attribute path."""
    found: dict[str, Any] = {}
    seen: set[int] = set()

    def visit(obj: Any, path: str, depth: int) -> None:
        if id(obj) in seen or depth > MAX_DEPTH:
            return
        seen.add(id(obj))
        if isinstance(obj, torch.Tensor):
            if obj.numel():
                found[path] = obj
        elif isinstance(obj, wp.array):
            if obj.size and obj.is_contiguous and obj.ptr is not None:
                found[path] = obj
        elif isinstance(obj, dict):
            for key, value in obj.items():
                if isinstance(key, (str, int)):
                    visit(value, f"{path}[{key!r}]", depth + 1)
        elif isinstance(obj, (list, tuple)):
            for i, value in enumerate(obj):
                visit(value, f"{path}[{i}]", depth + 1)
        elif _walked(obj):
            for key, value in vars(obj).items():
                if key not in HANDED_OUT:
                    visit(value, f"{path}.{key}", depth + 1)

    visit(env, "env", 0)
    return found


def capture_env(env: Any) -> dict[str, torch.Tensor]:
    """The env's state: each array's bytes (CPU uint8 tensors), by attribute path."""
    out = {}
    for path, array in env_arrays(env).items():
        if isinstance(array, torch.Tensor):
            out[path] = array.detach().to("cpu", copy=True)
        else:
            raw = np.ascontiguousarray(array.numpy()).view(np.uint8).reshape(-1)
            out[path] = torch.from_numpy(raw.copy())
    return out


def restore_env(env: Any, saved: dict[str, torch.Tensor]) -> str | None:
    """Write ``saved`` (``capture_env``) back into ``env``'s arrays in place; returns why it does not fit (and writes
    nothing then), or None."""
    arrays = env_arrays(env)
    if set(arrays) != set(saved):
        differ = sorted(set(arrays) ^ set(saved))
        return f"the env's arrays differ from the saved ones ({len(differ)}: {', '.join(differ[:3])} ...)"
    for path, array in arrays.items():
        value = saved[path]
        size = array.numel() * array.element_size() if isinstance(array, torch.Tensor) else array.capacity
        if isinstance(array, torch.Tensor):
            fits = tuple(value.shape) == tuple(array.shape) and value.dtype == array.dtype
        else:
            fits = value.dtype == torch.uint8 and value.numel() == size
        if not fits:
            return f"{path} has another shape than the saved one (another env count or task?)"
    for path, array in arrays.items():
        value = saved[path]
        if isinstance(array, torch.Tensor):
            array.copy_(value)
        else:
            like = array.numpy()
            array.assign(np.frombuffer(value.numpy().tobytes(), dtype=like.dtype).reshape(like.shape))
    return None


def capture_generators() -> dict[str, Any]:
    """torch's CPU and CUDA generators, numpy's and Python's global ones (plain data and tensors)."""
    numpy_state = np.random.get_state()
    version, keys, pos, has_gauss, cached = numpy_state
    out: dict[str, Any] = {
        "torch": torch.get_rng_state(),
        "numpy": [version, torch.from_numpy(np.asarray(keys, dtype=np.int64)), int(pos), int(has_gauss), cached],
        "python": _plain(random.getstate()),
    }
    if torch.cuda.is_available() and torch.cuda.is_initialized():
        out["cuda"] = torch.cuda.get_rng_state_all()
    return out


def restore_generators(saved: dict[str, Any]) -> None:
    torch.set_rng_state(saved["torch"])
    version, keys, pos, has_gauss, cached = saved["numpy"]
    np.random.set_state((version, keys.numpy().astype(np.uint32), pos, has_gauss, cached))
    random.setstate(_tuples(saved["python"]))
    if "cuda" in saved and torch.cuda.is_available():
        states = saved["cuda"]
        if len(states) == torch.cuda.device_count():
            torch.cuda.set_rng_state_all(states)


def _plain(value: Any) -> Any:
    return [_plain(v) for v in value] if isinstance(value, (tuple, list)) else value


def _tuples(value: Any) -> Any:
    return tuple(_tuples(v) for v in value) if isinstance(value, list) else value


EPISODE_SUMS = ("cur_reward_sum", "cur_episode_length")  # the logger's running episodes, per env
EPISODE_WINDOWS = ("rewbuffer", "lenbuffer")  # the logger's last finished episodes (the progress line's means)


def capture_logger(logger: Any) -> dict[str, Any]:
    """The logger's episode bookkeeping: what the progress rows' episode means are computed from."""
    out: dict[str, Any] = {k: getattr(logger, k).detach().to("cpu", copy=True) for k in EPISODE_SUMS}
    out.update({k: [float(x) for x in getattr(logger, k)] for k in EPISODE_WINDOWS})
    return out


def restore_logger(logger: Any, saved: dict[str, Any]) -> None:
    for key in EPISODE_SUMS:
        if tuple(saved[key].shape) == tuple(getattr(logger, key).shape):
            getattr(logger, key).copy_(saved[key])
    for key in EPISODE_WINDOWS:
        window = getattr(logger, key)
        window.clear()
        window.extend(saved[key])


def capture_run_state(env: Any, logger: Any, eval_envs: dict[str, Any]) -> dict[str, Any]:
    """What ``Runner.save`` writes under ``RUN_STATE_KEY``: the generators, the env's state, the periodic
    evaluation's envs' states (their streams go on from one evaluation to the next) and the logger's episode
    bookkeeping."""
    return {
        "version": ENV_STATE_VERSION,
        "generators": capture_generators(),
        "env": capture_env(env),
        "eval_envs": {name: capture_env(e) for name, e in eval_envs.items()},
        "logger": capture_logger(logger),
    }


def restore_run_state(env: Any, logger: Any, eval_envs: dict[str, Any], saved: Any) -> str | None:
    """Restore ``capture_run_state``'s dict; returns why the training env could not be restored (its generators
    still are), or None when all of it was. An evaluation env the checkpoint holds no fitting state of stays
    fresh (its later periodic evaluations then differ from an unbroken run's)."""
    if not isinstance(saved, dict) or saved.get("version") != ENV_STATE_VERSION:
        return "the checkpoint holds no run state (written by an older refpo_warp or another writer)"
    why = restore_env(env, saved["env"])
    restore_generators(saved["generators"])
    if why is None:
        restore_logger(logger, saved["logger"])
    for name, eval_env in eval_envs.items():
        if name in saved["eval_envs"]:
            restore_env(eval_env, saved["eval_envs"][name])
    return why
