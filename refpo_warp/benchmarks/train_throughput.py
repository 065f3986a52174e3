"""Training throughput: env steps per second of training each algo, with the split of an iteration and of the update,
as ratios to PPO measured in the same command (refpo bench train task=T algo=[ppo,refpo] device=D).

Each algo's run is built as ``refpo train`` builds it (``resolve_run``, ``build_runner``; a run option of ``refpo
train`` given here, ``task``, ``device``, ``num_envs``, ``algorithm.*`` ..., passes on to it), in a temporary run
dir, so that logging and checkpoints cost what they cost in a run. It learns ``warmup`` iterations (kernel
compilation, graph capture; not measured), then ``iterations`` iterations in one ``Runner.learn_chunk`` call timed
whole (the device synchronised at both ends), then one periodic evaluation, timed, and charged to each iteration as
the run would (one every ``eval.interval`` iterations).

How the parts are measured: the run's own methods are wrapped by functions that read the clock around the call and
change nothing it computes (the device is synchronised at each read on CUDA; ``detail=false`` keeps only the
iteration's phases, for the throughput with the fewest added synchronisations). Iteration: collection (the rollout:
from an iteration's first ``alg.act`` to ``alg.compute_returns``), returns, update (``alg.update``), logging
(``logger.log``: statistics, progress row, TensorBoard), checkpoint (``Runner.save``) and other (the whole less these:
the loop, ``learn``'s set-up). Collection: policy (``alg.act``), env (``env.step``), rest (storage, bookkeeping).
Update (every algorithm's ``OnPolicyAlgorithm.update``): before (the whole-rollout pass, e.g. ReFPO's old CFM
losses), actor (``policy_loss``: the actor's forward and its loss), critic (``value_loss``), backward (one autograd
pass over the summed loss, so the actor's and the critic's backward are one figure), optimizer (``optimizer.step``,
by its step hooks) and other (minibatch indexing, gradient clipping, the statistics' one host read, normalisers).
Host syncs: on CUDA every clock read waits for the device, so a part holds the device work it queued; the waits the
run makes itself (the update's one read of its statistics, the logger's) fall in update/other and logging.

The update against the device's arithmetic rate (``detail=true`` with a warm-up; networks not compiled): the last
warm-up iteration's update is run under torch's ``FlopCounterMode``, which counts the floating-point operations of its
matrix products (forward and backward, as executed); divided by the timed update's seconds, that is the rate the
update reaches. Beside it, the same command times a plain float32 matrix product at the update's widest shape (a
minibatch of rows through the critic's widest hidden layer, square), on the run's device and threads: the rate the
hardware gives such a product. Their ratio bounds what a change that keeps the arithmetic can gain on this machine.

The anchor is PPO at the same task, profile and device (added when not asked for): each algo's env steps/s is printed
as a ratio to PPO's, measured in the same command.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from refpo_warp.config.run_options import run_defaults
from refpo_warp.utils.machine import machine
from refpo_warp.utils.option_rules import Check, Flag, Int, Text
from refpo_warp.utils.option_tables import shown_value
from refpo_warp.utils.options import option

ANCHOR = "ppo"


def _algo_list(key: str, value: Any) -> list[str]:
    from refpo_warp.utils.errors import ConfigError

    names = [value] if isinstance(value, str) else value
    if not isinstance(names, list) or not names or not all(isinstance(n, str) and n for n in names):
        raise ConfigError(f"{key}={value!r} is invalid; expected an algo (ppo) or a list of algos ([ppo,refpo])")
    return list(dict.fromkeys(names))


@dataclass(frozen=True)
class Options:
    algo: list = option(
        ["ppo", "refpo"], Check(_algo_list, "an algo or a list of algos"), "the algos timed (PPO, the anchor, added)"
    )
    iterations: int = option(3, Int(1, 1000), "iterations timed, after the warm-up")
    warmup: int = option(1, Int(0, 1000), "iterations learned first and not timed (compilation, graph capture)")
    detail: bool = option(True, Flag(), "time the parts of the rollout and the update (false: the phases only)")
    out: str | None = option(None, Text(optional=True), "a JSON file the results are written to")


# The options passed on to each algo's run: every run option of refpo train but those the benchmark sets itself (its
# algos, a temporary run dir, a new run).
_RUN = run_defaults()
REST_KEYS = tuple(k for k, v in _RUN.items() if not isinstance(v, dict) and k not in ("algo", "run_dir", "resume"))
REST_PREFIXES = tuple(f"{k}." for k, v in _RUN.items() if isinstance(v, dict))
REST_SYNOPSIS = " [run option=VALUE ...]"
REST_DOC = (
    "run option=VALUE: a run option of refpo train, passed on to each algo's run: task=, device=, num_envs=, seed=,\n"
    "runner.<option>=, algorithm.<option>=, env.<option>=, ... (refpo train --help)"
)


class Clock:
    """Seconds spent inside wrapped calls, per name, and their counts; the device is synchronised at each read."""

    def __init__(self, device: str) -> None:
        self.cuda = str(device).startswith("cuda")
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}

    def now(self) -> float:
        if self.cuda:
            torch.cuda.synchronize()
        return time.perf_counter()

    def add(self, name: str, seconds: float) -> None:
        self.seconds[name] = self.seconds.get(name, 0.0) + seconds
        self.calls[name] = self.calls.get(name, 0) + 1

    def wrap(self, name: str, fn):
        def timed(*args, **kwargs):
            start = self.now()
            try:
                return fn(*args, **kwargs)
            finally:
                self.add(name, self.now() - start)

        return timed


@contextlib.contextmanager
def timing_hooks(runner, clock: Clock, detail: bool):
    """Wrap the run's methods with clock reads (see the module docstring); all are removed on exit."""
    alg, env, logger = runner.alg, runner.env, runner.logger
    rollout = {"start": None}

    def act(*args, **kwargs):
        if rollout["start"] is None:
            rollout["start"] = clock.now()
        return plain_act(*args, **kwargs)

    def compute_returns(*args, **kwargs):
        start = clock.now()
        clock.add("collection", start - rollout["start"])
        rollout["start"] = None
        try:
            return alg_compute_returns(*args, **kwargs)
        finally:
            clock.add("returns", clock.now() - start)

    alg_compute_returns = alg.compute_returns
    plain_act = clock.wrap("collection/policy", alg.act) if detail else alg.act
    patched: list[tuple[Any, str]] = []

    def patch(owner, name: str, fn) -> None:
        patched.append((owner, name))
        setattr(owner, name, fn)

    patch(alg, "act", act)
    patch(alg, "compute_returns", compute_returns)
    patch(alg, "update", clock.wrap("update", alg.update))
    patch(logger, "log", clock.wrap("logging", logger.log))
    patch(runner, "save", clock.wrap("checkpoint", runner.save))
    handles = []
    plain_backward = torch.Tensor.backward
    if detail:
        patch(env, "step", clock.wrap("collection/env", env.step))
        for name in ("before_update", "policy_loss", "value_loss"):
            if hasattr(alg, name):
                patch(alg, name, clock.wrap(f"update/{name}", getattr(alg, name)))
        step_start: list[float] = []
        handles.append(alg.optimizer.register_step_pre_hook(lambda *_: step_start.append(clock.now())))
        handles.append(
            alg.optimizer.register_step_post_hook(
                lambda *_: clock.add("update/optimizer", clock.now() - step_start.pop())
            )
        )
        torch.Tensor.backward = clock.wrap("update/backward", plain_backward)  # type: ignore[method-assign]
    try:
        yield
    finally:
        torch.Tensor.backward = plain_backward  # type: ignore[method-assign]
        for handle in handles:
            handle.remove()
        for owner, name in patched:
            delattr(owner, name)  # the class's method again


def measure(overrides: dict[str, Any], algo: str, iterations: int, warmup: int, detail: bool) -> dict[str, Any]:
    """Build one algo's run as ``refpo train`` does and time it (see the module docstring); one result row."""
    from refpo_warp.config.saved import resolve_run
    from refpo_warp.evaluation.evaluate_policy import periodic_evaluator
    from refpo_warp.runner.build import build_runner, env_steps_per_iteration, num_iterations, seed_everything
    from refpo_warp.training.train_run import evaluation_interval

    with tempfile.TemporaryDirectory(prefix="refpo_bench_train_") as tmp:
        run = resolve_run({**overrides, "algo": algo, "run_dir": tmp})
        cfg = run.cfg
        profile_iterations = num_iterations(cfg)  # the run this profile describes: its evaluation interval
        interval = evaluation_interval(cfg, profile_iterations)
        total = warmup + iterations
        seed_everything(cfg["seed"])
        with contextlib.redirect_stdout(io.StringIO()):  # the progress lines of the iterations
            env, runner = build_runner(run, Path(tmp))
            random_start = bool(cfg["runner"]["init_at_random_ep_len"])
            counted_flops = None
            if warmup:
                if warmup > 1:
                    runner.learn_chunk(warmup - 1, total, init_at_random_ep_len=random_start)
                    runner.end_chunk({})
                # torch.compile'd networks are not counted: the counter's module hooks would change what they trace
                counting = detail and not cfg["runner"].get("torch_compile_mode")
                with count_update_flops(runner.alg, counting) as counted_flops:
                    runner.learn_chunk(1, total, init_at_random_ep_len=random_start and warmup == 1)
                runner.end_chunk({})
            clock = Clock(runner.device)
            steps_before = int(runner.logger.tot_timesteps)
            with timing_hooks(runner, clock, detail):
                start = clock.now()
                runner.learn_chunk(iterations, total, init_at_random_ep_len=random_start and not warmup)
                whole = clock.now() - start
                runner.end_chunk({})
            counted = int(runner.logger.tot_timesteps) - steps_before
            evaluation = None
            if interval > 0:
                cfg["eval"]["interval"] = 1  # due at the iteration it is called for
                evaluate = periodic_evaluator(run, runner)
                start = clock.now()
                evaluate(total - 1, False)
                evaluation = clock.now() - start
        per_iteration = env_steps_per_iteration(cfg)
    row = result_row(cfg, algo, clock, whole, iterations, counted, per_iteration, evaluation, interval, str(env.device))
    if counted_flops and "update" in row:
        rows, width = minibatch_rows(cfg), max(cfg["critic"]["hidden_dims"])
        rate = matmul_rate(rows, width, str(env.device))
        achieved = counted_flops["flops"] / row["iteration"]["update"]
        row["arithmetic"] = {
            "update_matmul_flops": counted_flops["flops"],
            "update_gflops_per_s": achieved / 1e9,
            "matmul_shape": [rows, width, width],
            "matmul_gflops_per_s": rate / 1e9,
            "share_of_matmul_rate": achieved / rate,
        }
    return {**row, "warmup": warmup}


@contextlib.contextmanager
def count_update_flops(alg, counting: bool):
    """Count the matrix products' floating-point operations of every ``alg.update`` inside (forward and backward, as
    executed: torch's ``FlopCounterMode``); yields a dict whose ``flops`` holds the count, empty unless ``counting``."""
    from torch.utils.flop_counter import FlopCounterMode

    found: dict[str, int] = {}
    if not counting:
        yield found
        return
    plain = alg.update

    def counted(*args, **kwargs):
        with FlopCounterMode(display=False) as counter:
            out = plain(*args, **kwargs)
        found["flops"] = found.get("flops", 0) + counter.get_total_flops()
        return out

    alg.update = counted
    try:
        yield found
    finally:
        del alg.update  # the class's method again


def minibatch_rows(cfg: dict[str, Any]) -> int:
    """The transitions of one minibatch: an iteration's (envs x policy steps) over the algorithm's minibatches."""
    return cfg["num_envs"] * cfg["runner"]["num_steps_per_env"] // int(cfg["algorithm"].get("num_mini_batches", 1))


def matmul_rate(rows: int, width: int, device: str, seconds: float = 0.5) -> float:
    """Floating-point operations per second of a float32 (rows x width) @ (width x width) product on ``device`` at
    torch's current threads: the best of five timings of as many products as fill ``seconds``."""
    gen = torch.Generator(device=device).manual_seed(0)
    a = torch.randn(rows, width, device=device, generator=gen)
    b = torch.randn(width, width, device=device, generator=gen)
    clock = Clock(device)
    start = clock.now()
    repeats = 0
    while clock.now() - start < 0.05 or repeats < 3:  # warm-up, and a first estimate of one product's time
        a @ b
        repeats += 1
    per_product = (clock.now() - start) / repeats
    count = max(1, int(seconds / 5 / per_product))
    best = math.inf
    for _ in range(5):
        start = clock.now()
        for _ in range(count):
            a @ b
        best = min(best, (clock.now() - start) / count)
    return 2 * rows * width * width / best


def result_row(cfg, algo, clock: Clock, whole, iterations, counted, per_iteration, evaluation, interval, device):
    """The numbers of one algo: per iteration, in seconds, and each part's share."""
    s = {k: v / iterations for k, v in clock.seconds.items()}
    phases = ("collection", "returns", "update", "logging", "checkpoint")
    iteration = {k: s.get(k, 0.0) for k in phases}
    iteration["other"] = whole / iterations - sum(iteration.values())
    row: dict[str, Any] = {
        "task": cfg["task"],
        "algo": algo,
        "device": device,
        "num_envs": cfg["num_envs"],
        "num_steps_per_env": cfg["runner"]["num_steps_per_env"],
        "env_steps_per_iteration": per_iteration,
        "iterations": iterations,
        "env_steps_counted": counted,
        "seconds": whole,
        "seconds_per_iteration": whole / iterations,
        "env_steps_per_s": counted / whole,
        "iteration": iteration,
        "calls": dict(clock.calls),
        "evaluation": None,
    }
    if evaluation is not None:
        row["evaluation"] = {"seconds": evaluation, "interval": interval, "per_iteration": evaluation / interval}
    if "collection/env" in s:
        policy, env = s.get("collection/policy", 0.0), s["collection/env"]
        row["collection"] = {"policy": policy, "env": env, "other": iteration["collection"] - policy - env}
    if "update/backward" in s:
        parts = {
            "before": s.get("update/before_update", 0.0),
            "actor": s.get("update/policy_loss", 0.0),
            "critic": s.get("update/value_loss", 0.0),
            "backward": s["update/backward"],
            "optimizer": s.get("update/optimizer", 0.0),
        }
        parts["other"] = iteration["update"] - sum(parts.values())
        row["update"] = parts
    return row


def print_results(rows: list[dict[str, Any]]) -> None:
    from refpo_warp.utils.timing import print_table

    anchor = next((r for r in rows if r["algo"] == ANCHOR), rows[0])
    first = rows[0]
    title = (
        f"Training throughput on {first['task']}, {first['device']}: {first['num_envs']} envs x "
        f"{first['num_steps_per_env']} steps = {first['env_steps_per_iteration']:,} env steps per iteration, "
        f"{first['iterations']} iterations timed"
    )
    table = [
        {
            "algo": r["algo"],
            "env steps/s": f"{r['env_steps_per_s']:,.0f}",
            f"ratio to {anchor['algo']}": f"{r['env_steps_per_s'] / anchor['env_steps_per_s']:.2f}",
            "s/iteration": f"{r['seconds_per_iteration']:.2f}",
            **{k: _share(v, r["seconds_per_iteration"]) for k, v in r["iteration"].items()},
            "evaluation (amortised)": _evaluation(r),
        }
        for r in rows
    ]
    columns = list(table[0])
    print_table(table, columns, title=title)
    detail = [r for r in rows if "update" in r]
    if detail:
        parts = [
            {
                "algo": r["algo"],
                "update (s)": f"{r['iteration']['update']:.2f}",
                **{f"update: {k}": _share(v, r["iteration"]["update"]) for k, v in r["update"].items()},
                "collection (s)": f"{r['iteration']['collection']:.2f}",
                **{f"collection: {k}": _share(v, r["iteration"]["collection"]) for k, v in r["collection"].items()},
            }
            for r in detail
        ]
        print_table(parts, list(parts[0]), title="The update's and the rollout's parts (seconds per iteration, share)")
    counted = [r for r in rows if "arithmetic" in r]
    if counted:
        rates = [
            {
                "algo": r["algo"],
                "update: matrix-product GFLOP / iteration": f"{r['arithmetic']['update_matmul_flops'] / 1e9:,.1f}",
                "update GFLOP/s": f"{r['arithmetic']['update_gflops_per_s']:.1f}",
                "float32 product GFLOP/s": f"{r['arithmetic']['matmul_gflops_per_s']:.1f}",
                "product shape": " x ".join(str(n) for n in r["arithmetic"]["matmul_shape"][:2])
                + f" @ {r['arithmetic']['matmul_shape'][1]} x {r['arithmetic']['matmul_shape'][2]}",
                "share": f"{100 * r['arithmetic']['share_of_matmul_rate']:.0f}%",
            }
            for r in counted
        ]
        print_table(rates, list(rates[0]), title="The update against this device's float32 matrix-product rate")


def _share(seconds: float, whole: float) -> str:
    return f"{seconds:.3f} ({100 * seconds / whole:.0f}%)" if whole > 0 else f"{seconds:.3f}"


def _evaluation(row: dict[str, Any]) -> str:
    found = row["evaluation"]
    if found is None:
        return "off"
    return f"{found['per_iteration']:.3f} ({found['seconds']:.2f} s every {found['interval']})"


def command_line(options: Options, run_options: dict[str, Any]) -> str:
    """The command that repeats this measurement: the run options given, then every option of the benchmark."""
    given = {**run_options, **{k: getattr(options, k) for k in Options.__dataclass_fields__}}
    return "refpo bench train " + " ".join(f"{k}={_written(v)}" for k, v in given.items())


def _written(value: Any) -> str:
    """A value as the command line takes it (a list as [a,b])."""
    text = shown_value(value).replace("`", "")
    return text.replace(", ", ",") if isinstance(value, (list, tuple)) else text


def run(options: Options, run_options: dict[str, Any]) -> list[dict[str, Any]]:
    """Time each algo (PPO added) on the run that ``run_options`` describe (see the module docstring)."""
    from refpo_warp.config.saved import resolve_run
    from refpo_warp.utils.atomic_files import write_text
    from refpo_warp.utils.device import set_torch_threads
    from refpo_warp.utils.errors import ConfigError

    set_torch_threads(cuda_cap=4)  # as refpo train sets them
    algos = options.algo if ANCHOR in options.algo else [ANCHOR, *options.algo]
    out = Path(options.out) if options.out is not None else None
    if out is not None and (out.is_dir() or not out.parent.is_dir()):
        raise ConfigError(f"out={out}: give the path of a JSON file in an existing folder")
    for algo in algos:  # every run's options refused before the first is timed
        resolve_run({**run_options, "algo": algo, "run_dir": tempfile.gettempdir()})
    rows = [measure(run_options, a, options.iterations, options.warmup, options.detail) for a in algos]
    print_results(rows)
    if out is not None:
        anchor = next(r for r in rows if r["algo"] == ANCHOR)
        for r in rows:
            r[f"ratio_to_{ANCHOR}"] = r["env_steps_per_s"] / anchor["env_steps_per_s"]
        command = command_line(options, run_options)
        text = json.dumps({"command": command, "machine": machine(), "results": rows}, indent=2)
        write_text(out, text + "\n")
        print(f"\nwritten: {out}")
    return rows


__all__ = ["Options", "measure", "run"]
