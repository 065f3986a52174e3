"""The GridWorld modes table of docs/results/finetuning/README.md, from the study's files (gridworld.sh).

    python docs/results/finetuning/tables.py [--runs runs/finetuning/gridworld] [--keep]

Reads each run's eval.json (the dataset's own numbers from the clone's eval.json), writes the table between the
README's markers, and with ``--keep`` copies each run's small files (config.yaml, eval.json, progress.jsonl) and the
dataset's metadata.json into docs/results/finetuning/gridworld/, so the numbers outlive the machine; the table is then
read from there. For the Gaussian clone it also rolls the clone out again and counts where its unfinished episodes
stand when the 200-step time-out ends them (the row, relative to the middle row).
"""

from __future__ import annotations

import argparse
import json
import shutil
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
KEPT = HERE / "gridworld"
BEGIN, END = (
    "<!-- gridworld table: begin (python docs/results/finetuning/tables.py) -->",
    "<!-- gridworld table: end -->",
)
DMC_BEGIN, DMC_END = (
    "<!-- dmc table: begin (python docs/results/finetuning/tables.py --dmc) -->",
    "<!-- dmc table: end -->",
)
DMC_KEPT = HERE / "dmc"
DMC_TASKS = ("dmc_point_mass", "dmc_reacher_easy")
DMC_METHODS = (
    ("refpo", "ReFPO from the flow clone"),
    ("refpo_onestep", "refpo_onestep from the flow clone"),
    ("ppo", "PPO from the Gaussian clone"),
)
FROM_SCRATCH = HERE.parent / "cpu_dmc" / "per_task.csv"  # the committed from-scratch runs (1M env steps)
ROWS = [  # (run folder, what it is)
    ("clone_flow", "flow clone (refpo pretrain algo=refpo)"),
    ("clone_gauss", "Gaussian clone (refpo pretrain algo=ppo)"),
    ("refpo_from_flow", "ReFPO fine-tuned from the flow clone"),
    ("fpo_from_flow", "FPO fine-tuned from the flow clone"),
    ("ppo_from_gauss", "PPO fine-tuned from the Gaussian clone"),
]
FILES = ("config.yaml", "eval.json", "progress.jsonl")


def keep(runs: Path) -> None:
    for name, _ in ROWS:
        for file in FILES:
            if (runs / name / file).exists():
                (KEPT / name).mkdir(parents=True, exist_ok=True)
                shutil.copyfile(runs / name / file, KEPT / name / file)
    if (runs / "data" / "metadata.json").exists():
        (KEPT / "data").mkdir(parents=True, exist_ok=True)
        shutil.copyfile(runs / "data" / "metadata.json", KEPT / "data" / "metadata.json")


def timeout_rows(run: Path, episodes: int = 200) -> Counter:
    """Where the Gaussian clone's time-outs stand: the row (y) of each episode the 200-step time-out ended."""
    import torch

    from refpo_warp.config.saved import load_run
    from refpo_warp.envs.registry import make_env
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest

    resolved = load_run(run, {"device": "cpu"})
    cfg = resolved.cfg
    env = make_env(resolved.task, num_envs=episodes, device="cpu", seed=cfg["seed"] + 10_000, **cfg["env"])
    _, runner = build_runner(resolved, None, env=env)
    load_latest(runner, run, cfg["task"], cfg["algo"])
    actor = runner.get_inference_policy(device="cpu")
    obs, ended, rows = env.reset(), torch.zeros(episodes, dtype=torch.bool), Counter()
    with torch.inference_mode():
        for _ in range(int(env.max_episode_length)):
            before = env.positions.clone()
            obs, _, dones, extras = env.step(actor(obs))
            timed_out = extras["time_outs"] & ~ended
            for i in timed_out.nonzero().flatten().tolist():
                rows[int(before[i, 1])] += 1
            ended |= dones
            if bool(ended.all()):
                break
    return rows


def table(source: Path, runs: Path) -> str:
    lines = ["| policy | N | success | top share | bottom share | episode length |", "|---|---|---|---|---|---|"]
    clone = json.loads((source / "clone_flow" / "eval.json").read_text())
    d = clone["dataset"]
    lines.append(
        f"| demonstrations (scripted, {d['episodes']} episodes) | - | {d['success_rate']:.3f} | "
        f"{d['top_share']:.3f} | {d['bottom_share']:.3f} | {d['length_mean']:.2f} |"
    )
    notes = []
    for name, what in ROWS:
        path = source / name / "eval.json"
        if not path.exists():
            lines.append(f"| {what} | - | not run | | | |")
            continue
        results = json.loads(path.read_text())["results"]
        for setting in ("N=1", "N=10", "mean_action"):
            if setting in results:
                r = results[setting]
                n = setting[2:] if setting.startswith("N=") else "mean action"
                lines.append(
                    f"| {what} | {n} | {r['success_rate']:.3f} | {r['top_share']:.3f} | "
                    f"{r['bottom_share']:.3f} | {r['length_mean']:.1f} |"
                )
    if (runs / "clone_gauss" / "model_0.pt").exists():
        rows = timeout_rows(runs / "clone_gauss")
        shown = ", ".join(f"row {y}: {k}" for y, k in sorted(rows.items()))
        notes.append(
            f"\nThe Gaussian clone's time-outs (200 episodes from fresh starts, mean action), by the row they "
            f"end in (12 is the middle; the demonstrator's two-mode band is rows 9-15): {shown or 'none'}."
        )
    return "\n".join(lines) + "\n" + "\n".join(notes)


def _returns(path: Path) -> str:
    results = json.loads(path.read_text())["results"]
    if "mean_action" in results:
        return f"{results['mean_action']['return_mean']:.0f} (mean action)"
    return f"{results['N=10']['return_mean']:.0f} / {results['N=1']['return_mean']:.0f}"


def first_reaching(run: Path, value: float) -> str:
    """Env steps at the first periodic evaluation (N = 10, or the mean action) whose return reaches ``value``."""
    for line in (run / "progress.jsonl").read_text().splitlines():
        row = json.loads(line)
        got = row.get("eval/return_N10", row.get("eval/return"))
        if got is not None and got >= value:
            return f"{row['env_steps']:,}"
    return "not reached"


def keep_dmc(runs: Path, sweeps: Path) -> None:
    """The DMC study's small files: each stage's and each finished fine-tuning run's config, eval.json, progress."""
    for task in DMC_TASKS:
        stages = [(runs / task / name, DMC_KEPT / task / name) for name in ("demonstrator", "clone_refpo", "clone_ppo")]
        stages += [
            (run, DMC_KEPT / task / run.parent.name / run.name)
            for run in sorted((sweeps / f"finetune_{task[4:]}" / task).glob("*/seed*"))
        ]
        for src, dst in stages:
            if (src / "eval.json").exists():
                dst.mkdir(parents=True, exist_ok=True)
                for file in FILES:
                    if (src / file).exists():
                        shutil.copyfile(src / file, dst / file)
        if (runs / task / "data" / "metadata.json").exists():
            (DMC_KEPT / task / "data").mkdir(parents=True, exist_ok=True)
            shutil.copyfile(runs / task / "data" / "metadata.json", DMC_KEPT / task / "data" / "metadata.json")


def dmc_table() -> str:
    import csv

    scratch = {(r["task"], r["label"]): r for r in csv.DictReader(FROM_SCRATCH.open())}
    header = "| task | policy | env steps | return N = 10 / N = 1 | env steps to the data's return / to PPO's final |"
    lines = [header, "|---|---|---|---|---|"]
    for task in DMC_TASKS:
        root = DMC_KEPT / task
        if not (root / "data" / "metadata.json").exists():
            lines.append(f"| {task} | not run yet | | | |")
            continue
        meta = json.loads((root / "data" / "metadata.json").read_text())["refpo"]
        data = (
            json.loads((root / "clone_refpo" / "eval.json").read_text())["dataset"]
            if (root / "clone_refpo" / "eval.json").exists()
            else None
        )
        demo = Path(meta["policy"]["checkpoint"]).stem
        shown = f"{data['return_mean']:.0f} over {data['episodes']} episodes" if data else "-"
        lines.append(
            f"| {task} | demonstrations: PPO's {demo} (mean action + noise {meta['policy']['action_noise_std']:g}) "
            f"| - | {shown} | |"
        )
        ppo_final = float(scratch[(task, "ppo")]["return_multi_mean"]) if (task, "ppo") in scratch else float("inf")
        for name, what in (("clone_refpo", "flow clone"), ("clone_ppo", "Gaussian clone")):
            if (root / name / "eval.json").exists():
                lines.append(f"| {task} | {what} | 0 | {_returns(root / name / 'eval.json')} | |")
        for label, what in DMC_METHODS:
            for run in sorted((root / label).glob("seed*")):
                out = json.loads((run / "eval.json").read_text())
                reach = (
                    f"{first_reaching(run, data['return_mean']) if data else '-'} / {first_reaching(run, ppo_final)}"
                )
                lines.append(
                    f"| {task} | {what}, {run.name} | {out['env_steps']:,} | {_returns(run / 'eval.json')} | {reach} |"
                )
            ref = scratch.get((task, label))
            if ref is not None:
                one = f" / {float(ref['return_1_mean']):.0f}" if ref["return_1_mean"] else ""
                lines.append(
                    f"| {task} | {label} from scratch (cpu_dmc, mean of 3 seeds) | 1,013,760 | "
                    f"{float(ref['return_multi_mean']):.0f}{one} | |"
                )
    return "\n".join(lines) + "\n"


def write_between(begin: str, end: str, text: str) -> None:
    readme = HERE / "README.md"
    page = readme.read_text()
    head, rest = page.split(begin)
    _, tail = rest.split(end)
    readme.write_text(f"{head}{begin}\n\n{text}\n{end}{tail}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=Path, default=Path("runs/finetuning/gridworld"))
    parser.add_argument("--keep", action="store_true")
    parser.add_argument("--dmc", action="store_true", help="the DMC study's table (its files kept first)")
    args = parser.parse_args()
    if args.dmc:
        keep_dmc(Path("runs/finetuning/dmc"), Path("runs/sweeps"))
        text = dmc_table()
        write_between(DMC_BEGIN, DMC_END, text)
        print(text)
        return
    if args.keep:
        keep(args.runs)
    source = KEPT if (KEPT / "clone_flow" / "eval.json").exists() else args.runs
    text = table(source, args.runs)
    write_between(BEGIN, END, text)
    print(text)


if __name__ == "__main__":
    main()
