"""Where the humanoid env step's time goes (docs/humanoid.md, "Where the time goes"):
``python docs/results/humanoid/profile_humanoid_step.py [--num-envs 64] [--solver K=V]``.

Two measurements on one env (uniform random actions in [-1, 1], as ``refpo bench humanoid``):

1. env steps per second of the captured step, in process CPU time (less sensitive to other jobs than wall time);
2. a per-kernel profile of eager steps: every Warp launch is recorded (``record_cmd``) and then timed on its own, so
   Python's launch overhead is left out. Prints the kernels by time, with launches and threads per step.

``--solver KEY=VALUE`` passes extra ``SolverMuJoCo`` options (e.g. ``tolerance=1e-6``, ``cone=elliptic``,
``solver=cg``) by wrapping its constructor in this process only; ``--env KEY=VALUE`` sets env cfg fields. Tooling
only: it patches ``warp``'s launch function for the profile.
"""

from __future__ import annotations

import argparse
import ast
import collections
import time

import numpy as np
import torch


def key_value_option(item: str) -> tuple[str, object]:
    """``KEY=VALUE`` with VALUE read as a Python literal where it is one."""
    key, sep, value = item.partition("=")
    if not sep:
        raise SystemExit(f"expected KEY=VALUE, got {item!r}")
    try:
        return key, ast.literal_eval(value)
    except (ValueError, SyntaxError):
        return key, value


def _patch_solver(extra: dict) -> None:
    import newton

    original = newton.solvers.SolverMuJoCo.__init__

    def init(self, model, **kwargs):
        original(self, model, **{**kwargs, **extra})

    # a deliberate patch of the solver's constructor, which mypy refuses on any method
    newton.solvers.SolverMuJoCo.__init__ = init  # type: ignore[method-assign]


def cpu_rate(env, steps: int, seed: int = 0) -> float:
    generator = torch.Generator().manual_seed(seed)
    actions = torch.rand(8, env.num_envs, env.num_actions, generator=generator) * 2 - 1
    start = time.process_time()
    for i in range(steps):
        env.step(actions[i % 8])
    return steps * env.num_envs / (time.process_time() - start)


def kernel_profile(env, steps: int) -> dict[str, list]:
    """{kernel: [launches, seconds, threads]} over ``steps`` eager steps (graph replay turned off)."""
    from warp._src import context

    from refpo_warp.utils.warp_setup import wp

    stats: collections.defaultdict[str, list[float]] = collections.defaultdict(lambda: [0, 0.0, 0])
    original = context.launch

    def timed(kernel, *args, **kwargs):
        kwargs["record_cmd"] = True
        start = time.perf_counter()
        command = original(kernel, *args, **kwargs)
        if command is not None:  # a recorded launch: time only the kernel
            start = time.perf_counter()
            command.launch()
        entry = stats[getattr(kernel, "key", str(kernel))]
        dim = kwargs.get("dim", args[0] if args else 1)
        entry[0] += 1
        entry[1] += time.perf_counter() - start
        entry[2] += int(np.prod(dim))

    graph, env._graph = env._graph, None
    context.launch, wp.launch = timed, timed
    try:
        generator = torch.Generator().manual_seed(1)
        for _ in range(steps):
            env.step(torch.rand(env.num_envs, env.num_actions, generator=generator) * 2 - 1)
    finally:
        context.launch, wp.launch = original, original
        env._graph = graph
    return stats


def main() -> None:
    parser = argparse.ArgumentParser(
        prog="python docs/results/humanoid/profile_humanoid_step.py", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--steps", type=int, default=30, help="timed graph steps")
    parser.add_argument("--profile-steps", type=int, default=8, help="profiled eager steps")
    parser.add_argument("--solver", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--env", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--top", type=int, default=30)
    args = parser.parse_args()
    torch.set_num_threads(1)
    if args.solver:
        _patch_solver(dict(key_value_option(item) for item in args.solver))
    from refpo_warp.envs.registry import make_env

    env = make_env(
        "humanoid_all",
        num_envs=args.num_envs,
        device="cpu",
        seed=0,
        **dict(key_value_option(item) for item in args.env),
    )
    cpu_rate(env, 3)  # compile and capture
    rate = cpu_rate(env, args.steps)
    niter = env.sim.solver.mjw_data.solver_niter.numpy()
    print(
        f"{args.num_envs} envs, solver options {args.solver or 'default'}, env options {args.env or 'default'}: "
        f"{rate:,.0f} env steps/s (process CPU time, graph replay); solver iterations at the last substep: "
        f"mean {niter.mean():.2f}, max {niter.max()}"
    )
    stats = kernel_profile(env, args.profile_steps)
    total = sum(v[1] for v in stats.values())
    n = args.profile_steps
    print(
        f"kernel time {1e3 * total / n:.1f} ms per step, {sum(v[0] for v in stats.values()) / n:.0f} launches, "
        f"{sum(v[2] for v in stats.values()) / n:,.0f} threads"
    )
    for name, (launches, seconds, threads) in sorted(stats.items(), key=lambda kv: -kv[1][1])[: args.top]:
        print(
            f"{1e3 * seconds / n:8.2f} ms {100 * seconds / total:5.1f} %  {launches / n:6.1f} launches "
            f"{threads / n:10,.0f} threads  {name}"
        )


if __name__ == "__main__":
    main()
