"""Action-latency benchmark (the paper's Figure 5b): time to compute one batch of actions with N = 10 and N = 1
Euler steps for flow policies, and with the mean action for a Gaussian policy.

    refpo bench latency [tasks=[dmc_cheetah_run]] [algos=[ppo,fpo,refpo]] [batch_sizes=[1,128]]
                        [flow_steps=[10,1]] [device=auto] [repeats=50] [out=PATH]

Each policy is the task's actor at its resolved config (the device's profile) with freshly initialised weights:
latency depends on the architecture and N, not on the weights. The observation batch comes from the task's env
after reset; each timing is the median of ``repeats`` calls after warm-up, synchronising the device every call.
``out=PATH`` also writes the rows (read by ``refpo report`` for the latency figure).
"""

from __future__ import annotations

import contextlib
import datetime
import functools
import io
from dataclasses import dataclass
from pathlib import Path

import torch

from refpo_warp.config.run_options import FLOW_STEPS
from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.machine import cpu_model
from refpo_warp.utils.option_rules import DEVICE_DOC, DEVICE_RULE, Int, ListOf, Rule, Text
from refpo_warp.utils.options import option
from refpo_warp.utils.timing import print_table, time_call


def device_name(device: str) -> str:
    if device.startswith("cuda"):
        return torch.cuda.get_device_name(torch.device(device))
    return cpu_model()


def policy_latency(
    task: str, algo: str, device: str, batches: list[int], flow_steps: list[int], repeats: int = 50
) -> list[dict]:
    """Latency rows (``latency_ms`` per call) of ``algo``'s actor on ``task`` for every batch size and N."""
    from refpo_warp.config.resolve import resolve
    from refpo_warp.evaluation.evaluate_policy import is_flow, make_policy
    from refpo_warp.runner.build import build_runner

    run = resolve([f"task={task}", f"algo={algo}", f"device={device}", f"num_envs={max(batches)}"])
    with contextlib.redirect_stdout(io.StringIO()):  # rsl_rl prints the model structure
        env, runner = build_runner(run, None)
    actor = runner.get_inference_policy(device=device)
    obs = env.get_observations().to(device)
    rows = []
    for n in flow_steps if is_flow(actor) else [None]:
        policy = make_policy(actor, n)  # random initial noise, no perturbation: the evaluation protocol
        for batch in batches:
            part = obs[:batch]
            with torch.inference_mode():
                seconds = time_call(functools.partial(policy, part), device=device, repeats=repeats, warmup=5)
            rows.append({"task": task, "algo": algo, "flow_steps": n, "batch": batch, "latency_ms": seconds * 1e3})
    return rows


class _BatchSize(Rule):
    """A positive batch size or ``num_envs`` (the task's profile's)."""

    def _check(self, key, value):
        return value if value == "num_envs" else Int(1, 1 << 22).check(key, value)

    def describe(self) -> str:
        return "a positive integer or num_envs"


@dataclass(frozen=True)
class Options:
    tasks: list[str] = option(["dmc_cheetah_run"], ListOf(Text()), "task ids")
    algos: list[str] = option(["ppo", "fpo", "refpo"], ListOf(Text()), "algorithms (refpo train's algo= names)")
    batch_sizes: list = option([1, "num_envs"], ListOf(_BatchSize()), "observations per call; num_envs: the profile's")
    flow_steps: list[int] = option([10, 1], FLOW_STEPS, "Euler steps N of a flow policy, each timed")
    device: str = option("auto", DEVICE_RULE, DEVICE_DOC)
    repeats: int = option(50, Int(1), "timed calls per case")
    out: str | None = option(
        None, Text(optional=True), "also write the rows to this JSON file (refpo report's latency=)"
    )


def run(args: Options, _: dict | None = None) -> None:
    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.utils.atomic_files import write_json

    device = resolve_device(args.device)
    rows = []
    for task in args.tasks:
        profile_envs = resolve_config([f"task={task}", f"device={device}"])["num_envs"]
        batches = sorted({profile_envs if b == "num_envs" else b for b in args.batch_sizes})
        for algo in args.algos:
            rows += policy_latency(task, algo, device, batches, args.flow_steps, args.repeats)
    ratios = []
    for task, algo, batch in sorted({(r["task"], r["algo"], r["batch"]) for r in rows if r["flow_steps"]}):
        by_n = {
            r["flow_steps"]: r["latency_ms"] for r in rows if (r["task"], r["algo"], r["batch"]) == (task, algo, batch)
        }
        if 1 in by_n and 10 in by_n:
            ratios.append(f"{task} {algo} batch {batch}: N=10 / N=1 latency ratio {by_n[10] / by_n[1]:.1f}x")
    print_table(
        [{**r, "flow_steps": r["flow_steps"] or "mean action", "latency_ms": f"{r['latency_ms']:.3f}"} for r in rows],
        ["task", "algo", "flow_steps", "batch", "latency_ms"],
        title=f"Action latency on {device} ({device_name(device)}), torch threads {torch.get_num_threads()}, "
        f"median of {args.repeats} calls",
        notes=tuple(ratios),
    )
    if args.out:
        path = Path(args.out)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_json(
            {
                "benchmark": "action_latency",
                "device": device,
                "device_name": device_name(device),
                "torch_threads": torch.get_num_threads(),
                "torch_version": torch.__version__,
                "repeats": args.repeats,
                "created": datetime.datetime.now().isoformat(timespec="seconds"),
                "rows": rows,
            },
            path,
        )
        print(f"wrote {path}")
