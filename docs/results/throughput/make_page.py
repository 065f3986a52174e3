#!/usr/bin/env python
"""Training throughput at the CPU profile: ``README.md`` in this folder, written whole from ``README.template.md`` and
the JSON files ``refpo bench train ... out=<task>.json`` wrote here (one per task, PPO and ReFPO in each):

    python docs/results/throughput/make_page.py [--add-runs runs/sweeps/bf16_amx] [--check]
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import bf16_runs  # bf16_runs.py beside this script

from refpo_warp.studies.reports.results_page import page_main

HERE = Path(__file__).resolve().parent
TASKS = ("dmc_point_mass", "dmc_cartpole_swingup")
NAMES = {"ppo": "PPO", "refpo": "ReFPO"}


@dataclass(frozen=True)
class Change:
    """A change tried: its folder of before and after files (<task>_<before>.json, <task>_<after>.json), the option
    and its default, what it changes, and what else its sentence says (from the after file's machine record)."""

    folder: str
    option: str
    default: str
    what: str
    names: tuple[str, str]
    note: Callable[[dict, dict], str]


def bf16_note(before: dict, after: dict) -> str:
    cpu = after["machine"]
    if cpu.get("native_bfloat16"):
        return (
            f"Its CPU (torch's capability: {cpu.get('cpu_capability', 'not recorded')}) multiplies bfloat16 "
            f"matrices in hardware (AVX512-BF16 or AMX): {phase_changes(before, after, ('update', 'collection'))}."
        )
    return (
        f"Its CPU (torch's capability: {cpu.get('cpu_capability', 'not recorded')}) has no native bfloat16 "
        "(AVX512-BF16 or AMX): torch emulates the bfloat16 matrix products, and training warns when the option is set "
        "on such a CPU."
    )


def phase_changes(before: dict, after: dict, phases: tuple[str, ...]) -> str:
    """Each algo's seconds an iteration in ``phases`` (update, collection), before → after."""
    parts = []
    for b in before["results"]:
        a = next(r for r in after["results"] if r["algo"] == b["algo"])
        moved = " and its ".join(
            f"{phase} {b['iteration'][phase]:.2f} → {a['iteration'][phase]:.2f} s" for phase in phases
        )
        parts.append(f"{NAMES.get(b['algo'], b['algo'])}'s {moved} an iteration")
    return "; ".join(parts)


def threads_note(before: dict, after: dict) -> str:
    return (
        f"The machine has {after['machine']['cpu_count']} cores; "
        + phase_changes(before, after, ("update", "collection"))
        + ". The update's matrix products share the threads; the env kernels (Warp on the CPU) run on one thread "
        "either way."
    )


def compile_note(before: dict, after: dict) -> str:
    warmup = after["results"][0]["warmup"]
    return (
        f"The update: {phase_changes(before, after, ('update',))}. Compilation falls in the {warmup} warm-up "
        "iterations, not timed."
    )


CHANGES = (
    Change(
        "bf16",
        "algorithm.use_mixed_precision=true",
        "false",
        "bfloat16 autocast of the update's forward passes and losses",
        ("float32", "bfloat16"),
        bf16_note,
    ),
    Change(
        "bf16_native",
        "algorithm.use_mixed_precision=true",
        "false",
        "bfloat16 autocast of the update's forward passes and losses",
        ("float32", "bfloat16"),
        bf16_note,
    ),
    Change(
        "threads",
        "torch_threads=2",
        "null: one thread on a machine without CUDA",
        "two torch threads for the networks of one run",
        ("1thread", "2thread"),
        threads_note,
    ),
    Change(
        "compile",
        "runner.torch_compile_mode=default",
        "null: not compiled",
        "torch.compile of the actor and the critic, as rsl_rl applies it",
        ("eager", "compiled"),
        compile_note,
    ),
)


def load(task: str) -> dict:
    return json.loads((HERE / f"{task}.json").read_text())


def share(seconds: float, whole: float) -> str:
    return f"{seconds:.2f} ({100 * seconds / whole:.0f} %)"


def table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def iteration_table(runs: dict[str, dict]) -> str:
    rows = []
    for task, data in runs.items():
        for r in data["results"]:
            it, whole = r["iteration"], r["seconds_per_iteration"]
            evaluation = r["evaluation"]
            rows.append(
                [
                    f"`{task}`",
                    NAMES.get(r["algo"], r["algo"]),
                    f"{r['env_steps_per_s']:,.0f}",
                    f"{r['ratio_to_ppo']:.2f}",
                    f"{whole:.2f}",
                    share(it["collection"], whole),
                    share(it["update"], whole),
                    share(it["logging"] + it["checkpoint"], whole),
                    share(it["returns"] + it["other"], whole),
                    "off"
                    if evaluation is None
                    else f"{evaluation['per_iteration']:.2f} (every {evaluation['interval']})",
                ]
            )
    header = ["task", "algo", "env steps/s", "ratio to PPO", "s / iteration", "collection", "update"]
    return table(header + ["logging and checkpoint", "returns and other", "evaluation (s, amortised)"], rows)


def update_table(runs: dict[str, dict]) -> str:
    rows = []
    for task, data in runs.items():
        for r in data["results"]:
            parts, whole = r["update"], r["iteration"]["update"]
            rows.append(
                [f"`{task}`", NAMES.get(r["algo"], r["algo"]), f"{whole:.2f}"]
                + [share(parts[k], whole) for k in ("actor", "critic", "backward", "optimizer", "before", "other")]
            )
    header = ["task", "algo", "update (s)", "actor", "critic", "backward", "optimizer", "before", "other"]
    return table(header, rows)


def machine(runs: dict[str, dict]) -> str:
    first = next(iter(runs.values()))["machine"]
    loads = "; ".join(
        f"`{t}`: {', '.join(str(x) for x in d['machine'].get('load_average', []))}" for t, d in runs.items()
    )
    return (
        f"Machine: {first['cpu']}, {first['cpu_count']} cores, torch {first['torch']} with "
        f"{first['torch_threads']} thread, shared with running studies while it measured (load average over the "
        f"last 1, 5 and 15 minutes when each command ended: {loads}). The figures are of one measurement on a busy "
        f"machine: other work's load moves them between commands and between the two algorithms of one command, so "
        f"read them as sizes and shares, not as a ranking."
    )


def reading(runs: dict[str, dict]) -> str:
    lines = []
    for task, data in runs.items():
        ppo, refpo = (next(r for r in data["results"] if r["algo"] == a) for a in ("ppo", "refpo"))
        update = {a: r["iteration"]["update"] / r["seconds_per_iteration"] for a, r in (("ppo", ppo), ("refpo", refpo))}
        critic = ppo["update"]["critic"] + ppo["update"]["backward"]
        lines.append(
            f"- `{task}`: the update takes {100 * update['ppo']:.0f} % of PPO's iteration and "
            f"{100 * update['refpo']:.0f} % of ReFPO's; in PPO's update the critic's loss and the backward pass "
            f"(the critic's and the actor's) together take {100 * critic / ppo['iteration']['update']:.0f} %: the "
            f"critic is the larger network at this profile. ReFPO's env steps per second are "
            f"{refpo['ratio_to_ppo']:.2f} times PPO's."
        )
    return "What the tables say:\n\n" + "\n".join(lines)


def commands(runs: dict[str, dict]) -> str:
    return "```\n" + "\n".join(d["command"] for d in runs.values()) + "\n```"


def change_rows() -> tuple[list[list[str]], list[str], list[str]]:
    """One row per (change, task, algo); the commands; a sentence per change, from its before and after files."""
    rows, lines, said = [], [], []
    for change in CHANGES:
        folder, option, default, (before_name, after_name) = change.folder, change.option, change.default, change.names
        for before_file in sorted((HERE / folder).glob(f"*_{before_name}.json")):
            task = before_file.name[: -len(f"_{before_name}.json")]
            before = json.loads(before_file.read_text())
            after = json.loads((HERE / folder / f"{task}_{after_name}.json").read_text())
            lines += [before["command"], after["command"]]
            ratios = []
            for b in before["results"]:
                a = next(r for r in after["results"] if r["algo"] == b["algo"])
                ratio = a["env_steps_per_s"] / b["env_steps_per_s"]
                ratios.append(ratio)
                rows.append(
                    [
                        f"`{option}` (default {default})",
                        f"{after['machine']['cpu']} ({after['machine'].get('cpu_capability', 'not recorded')})",
                        f"`{task}`",
                        NAMES.get(b["algo"], b["algo"]),
                        f"{b['env_steps_per_s']:,.0f}",
                        f"{a['env_steps_per_s']:,.0f}",
                        f"{ratio:.2f}",
                        f"{b['seconds_per_iteration']:.2f} → {a['seconds_per_iteration']:.2f}",
                    ]
                )
            said.append(
                f"- `{option}` ({change.what}) {'pays' if min(ratios) > 1 else 'does not pay'} on `{task}` "
                f"({after['machine']['cpu']}): "
                f"{min(ratios):.2f} to {max(ratios):.2f} times the env steps per second of its default (load average "
                f"{before['machine'].get('load_average', ['?'])[0]} and "
                f"{after['machine'].get('load_average', ['?'])[0]} when the two commands ended). "
                + change.note(before, after)
            )
    return rows, lines, said


def changes() -> str:
    rows, lines, said = change_rows()
    header = [
        *("change", "CPU (torch's capability)", "task", "algo"),
        *("env steps/s before", "after", "ratio", "s / iteration"),
    ]
    return table(header, rows) + "\n\n" + "\n".join(said) + "\n\nMeasured by:\n\n```\n" + "\n".join(lines) + "\n```"


def ceiling() -> str:
    """The update's matrix-product rate against a plain float32 product's, from ceiling/<task>.json, and what that
    bounds: the iteration with the update's matrix products at the plain product's rate, every other part as it is."""
    rows, said, lines, speedups = [], [], [], []
    for task in TASKS:
        data = json.loads((HERE / "ceiling" / f"{task}.json").read_text())
        lines.append(data["command"])
        for r in data["results"]:
            found, whole, update = r["arithmetic"], r["seconds_per_iteration"], r["iteration"]["update"]
            floor = whole - update + found["update_matmul_flops"] / (found["matmul_gflops_per_s"] * 1e9)
            speedups.append(whole / floor)
            rows.append(
                [
                    f"`{task}`",
                    NAMES.get(r["algo"], r["algo"]),
                    f"{found['update_matmul_flops'] / 1e9:,.0f}",
                    f"{update:.2f}",
                    f"{found['update_gflops_per_s']:.1f}",
                    f"{found['matmul_gflops_per_s']:.1f}",
                    f"{100 * found['share_of_matmul_rate']:.0f} %",
                    f"{whole:.2f} → {floor:.2f} ({whole / floor:.2f}x)",
                ]
            )
        shape = data["results"][0]["arithmetic"]["matmul_shape"]
        cpu = data["machine"]
        said.append(
            f"`{task}`: the plain product is {shape[0]:,} x {shape[1]} @ {shape[1]} x {shape[2]} (a minibatch through "
            f"the critic's hidden layer) on {cpu['torch_threads']} thread (torch's capability "
            f"{cpu.get('cpu_capability', 'not recorded')}; load average {cpu.get('load_average', ['?'])[0]} when the "
            "command ended)."
        )
    header = ["task", "algo", "update: matrix-product GFLOP / iteration", "update (s)", "update GFLOP/s"]
    header += ["float32 product GFLOP/s", "share", "s / iteration → bound (speed-up)"]
    verdict = (
        f"A run at this profile {'cannot' if max(speedups) < 2 else 'could'} be made twice as fast on the same "
        f"threads by a change that keeps the float32 arithmetic: the bound is {min(speedups):.2f}x to "
        f"{max(speedups):.2f}x."
    )
    return (
        table(header, rows)
        + "\n\n"
        + " ".join(said)
        + " "
        + verdict
        + "\n\nMeasured by:\n\n```\n"
        + "\n".join(lines)
        + "\n```"
    )


def values() -> dict[str, object]:
    runs = {task: load(task) for task in TASKS}
    first = next(iter(runs.values()))["results"][0]
    return {
        "sizes": f"{first['num_envs']} envs x {first['num_steps_per_env']} steps = "
        f"{first['env_steps_per_iteration']:,} env steps per iteration",
        "warmup": f"{first['warmup']} warm-up iteration{'s' if first['warmup'] != 1 else ''} (not timed)",
        "iterations": f"{first['iterations']} iterations",
        "machine": machine(runs),
        "iteration_table": iteration_table(runs),
        "update_table": update_table(runs),
        "reading": reading(runs),
        "commands": commands(runs),
        "changes": changes(),
        "ceiling": ceiling(),
        "bf16_learning": bf16_runs.section(),
    }


def main() -> None:
    page_main(__doc__.splitlines()[1], HERE / "README.template.md", values, bf16_runs.add_runs)


if __name__ == "__main__":
    main()
