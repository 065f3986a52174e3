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
BEGIN, END = "<!-- gridworld table: begin (python docs/results/finetuning/tables.py) -->", "<!-- gridworld table: end -->"
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

    from refpo_warp.config.saved import load_run_config
    from refpo_warp.envs.registry import make_env
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest

    cfg = load_run_config(run, {"device": "cpu"})
    env = make_env(cfg["task"], num_envs=episodes, device="cpu", seed=cfg["seed"] + 10_000, **cfg["env"])
    _, runner = build_runner(cfg, None, env=env)
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
    lines.append(f"| demonstrations (scripted, {d['episodes']} episodes) | - | {d['success_rate']:.3f} | "
                 f"{d['top_share']:.3f} | {d['bottom_share']:.3f} | {d['length_mean']:.2f} |")  # fmt: skip
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
                lines.append(f"| {what} | {n} | {r['success_rate']:.3f} | {r['top_share']:.3f} | "
                             f"{r['bottom_share']:.3f} | {r['length_mean']:.1f} |")  # fmt: skip
    if (runs / "clone_gauss" / "model_0.pt").exists():
        rows = timeout_rows(runs / "clone_gauss")
        shown = ", ".join(f"row {y}: {k}" for y, k in sorted(rows.items()))
        notes.append(f"\nThe Gaussian clone's time-outs (200 episodes from fresh starts, mean action), by the row they "
                     f"end in (12 is the middle; the demonstrator's two-mode band is rows 9-15): {shown or 'none'}.")
    return "\n".join(lines) + "\n" + "\n".join(notes)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=Path, default=Path("runs/finetuning/gridworld"))
    parser.add_argument("--keep", action="store_true")
    args = parser.parse_args()
    if args.keep:
        keep(args.runs)
    source = KEPT if (KEPT / "clone_flow" / "eval.json").exists() else args.runs
    text = table(source, args.runs)
    readme = HERE / "README.md"
    page = readme.read_text()
    head, rest = page.split(BEGIN)
    _, tail = rest.split(END)
    readme.write_text(f"{head}{BEGIN}\n\n{text}\n{END}{tail}")
    print(text)


if __name__ == "__main__":
    main()
