"""DMC benchmark: env steps per second of every task vs the MuJoCo C library stepping the same model.

    refpo bench dmc [num_envs=N] [device=auto] [tasks=[dmc_cartpole_balance,dmc_walker_walk]] [timed_seconds=3]

Ours: the task's Warp env (Newton + MuJoCo Warp), uniform random actions in [-1, 1], timed after warm-up steps (the
step is replayed as a captured graph: a CUDA graph on GPU, a Warp CPU graph on CPU); one env step = the task's
physics substeps plus rewards, resets and observations. Default: 256 envs on CPU, 4096 on CUDA.
MuJoCo C: the same MJCF file loaded with ``mujoco.MjModel.from_xml_path``, the same number of worlds started from
the env's reset states, each control held for the same substeps. ``C rollout`` is ``mujoco.rollout`` with one
thread (Warp's CPU backend also runs one thread), ``C loop`` a Python loop of ``mj_step(model, data, substeps)`` over
one ``MjData`` per world. Physics only: no observation or reward work on the C side. Every suite task is measured
by default, dmc_point_mass_wall included (its C side loads ``point_mass_wall.xml``: the default wall, as the env's).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import DEVICE_DOC, DEVICE_RULE, Flag, Int, ListOf, Real, Text
from refpo_warp.utils.options import option
from refpo_warp.utils.timing import env_steps_per_second, print_table

if TYPE_CHECKING:
    from refpo_warp.tasks.dmc.env import DmcEnv


def _timed_steps(seconds: float, steps_per_second_guess: float, minimum: int = 10) -> int:
    return max(minimum, int(seconds * steps_per_second_guess))


def ours(task: str, num_envs: int, device: str, seconds: float) -> tuple[float, DmcEnv]:
    env = make_env(f"dmc_{task}", num_envs=num_envs, device=device, seed=0)
    probe = env_steps_per_second(env, steps=5, warmup=3)  # also warms up (compile, graph capture)
    steps = _timed_steps(seconds, probe / num_envs)
    return env_steps_per_second(env, steps=steps, warmup=0), env


def _initial_states(env, model):
    import mujoco

    qpos, qvel = env.qpos.cpu().numpy(), env.joint_qd.cpu().numpy()
    data = mujoco.MjData(model)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    states = np.zeros((env.num_envs, mujoco.mj_stateSize(model, spec)))
    for i in range(env.num_envs):
        data.qpos[:], data.qvel[:] = qpos[i], qvel[i]
        mujoco.mj_getState(model, data, states[i], spec)
    return states


def mujoco_c(env, seconds: float) -> tuple[float, float]:
    """(rollout, Python loop) env steps per second of MuJoCo C for ``env``'s model, worlds and substeps."""
    import mujoco
    from mujoco import rollout

    model = mujoco.MjModel.from_xml_path(str(env.task.model_path()))
    substeps, n = env.task.substeps, env.num_envs
    states = _initial_states(env, model)
    rng = np.random.default_rng(0)

    def run_rollout(control_steps: int) -> float:
        controls = rng.uniform(-1, 1, size=(n, control_steps, model.nu))
        controls = np.repeat(controls, substeps, axis=1)  # hold each control for the task's substeps
        start = time.perf_counter()
        rollout.rollout(model, mujoco.MjData(model), states, controls, nstep=control_steps * substeps)
        return control_steps * n / (time.perf_counter() - start)

    datas = [mujoco.MjData(model) for _ in range(n)]
    for data, state in zip(datas, states):
        mujoco.mj_setState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)

    def run_loop(control_steps: int) -> float:
        controls = rng.uniform(-1, 1, size=(control_steps, n, model.nu))
        start = time.perf_counter()
        for k in range(control_steps):
            for data, ctrl in zip(datas, controls[k]):
                data.ctrl[:] = ctrl
                mujoco.mj_step(model, data, substeps)
        return control_steps * n / (time.perf_counter() - start)

    rollout_rate = run_rollout(_timed_steps(seconds, run_rollout(2) / n, minimum=2))
    loop_rate = run_loop(_timed_steps(seconds, run_loop(2) / n, minimum=2))
    return rollout_rate, loop_rate


@dataclass(frozen=True)
class Options:
    device: str = option("auto", DEVICE_RULE, DEVICE_DOC)
    num_envs: int | None = option(None, Int(1, 1 << 22, optional=True), "envs (default: 256 on CPU, 4096 on CUDA)")
    tasks: list[str] | None = option(None, ListOf(Text(), optional=True), "DMC task ids (default: every one)")
    timed_seconds: float = option(3.0, Real(0, 3600, lo_open=True), "approximate timing window per measurement")
    mujoco_c: bool = option(True, Flag(), "also time MuJoCo C on the same model (false: ours only)")


def task_ids() -> list[str]:
    """Every suite task's id (``tasks/dmc/suite/<task>.py``): the default ``tasks``, this project's tasks included."""
    from refpo_warp.tasks.dmc.suite import task_names

    return [f"dmc_{t}" for t in task_names()]


def run(options: Options, _: dict | None = None) -> None:
    ids = task_ids()
    chosen = options.tasks or ids
    unknown = [t for t in chosen if t not in ids]
    if unknown:
        raise ConfigError(f"tasks={unknown} has unknown DMC task ids; choose from {', '.join(ids)}")
    device = resolve_device(options.device)
    num_envs = options.num_envs or (256 if device == "cpu" else 4096)
    with_c = options.mujoco_c
    torch.manual_seed(0)
    print(
        f"DMC env steps/s on {device}: {num_envs} envs, random actions, graph-captured step"
        + ("; MuJoCo C on the same model and number of worlds (1 thread)" if with_c else ""),
        flush=True,
    )
    rows = []
    for task_id in chosen:
        task = task_id.removeprefix("dmc_")
        rate, env = ours(task, num_envs, device, options.timed_seconds)
        row = {"task": task, "substeps": env.task.substeps, "ours (env steps/s)": f"{rate:,.0f}"}
        if with_c:
            c_rollout, c_loop = mujoco_c(env, options.timed_seconds)
            row.update(
                {
                    "C rollout": f"{c_rollout:,.0f}",
                    "ours / C rollout": f"{rate / c_rollout:.2f}",
                    "C loop": f"{c_loop:,.0f}",
                    "ours / C loop": f"{rate / c_loop:.2f}",
                }
            )
        rows.append(row)
        print(f"  {task}: {row}", flush=True)
        del env
    columns = ["task", "substeps", "ours (env steps/s)"]
    if with_c:
        columns += ["C rollout", "ours / C rollout", "C loop", "ours / C loop"]
    print_table(rows, columns, title=f"DMC env steps per second on {device}, {num_envs} envs")
