"""Whole runs under bfloat16 autocast on a CPU that multiplies bfloat16 in hardware: does learning hold, and how fast
is a whole run? cpu_dmc's PPO and ReFPO on point_mass at the CPU profile (seeds 1-5), at float32 (the default) and
under autocast, the two alternating run by run on one core (``COMMAND``). The committed files:
``bf16_native/runs.csv`` and each run's small files under ``bf16_native/runs/``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import append_runs, read_rows, seeds_text
from refpo_warp.studies.reports.intervals import improvement_of, mean_estimate

HERE = Path(__file__).resolve().parent / "bf16_native"
ROOT = HERE.parents[3]
RUNS_CSV, RUNS_DIR = HERE / "runs.csv", HERE / "runs"
COMMAND = (
    "refpo sweep cpu_dmc tasks=[dmc_point_mass] methods=[ppo,refpo] seeds=[1,2,3,4,5] "
    "algorithm.use_mixed_precision=[false,true] out=runs/sweeps/bf16_amx --jobs 1"
)
NAMES = {"ppo": "PPO", "refpo": "ReFPO"}
PRECISIONS = {False: "float32", True: "bfloat16"}


def add_runs(sweep_dir: Path) -> None:
    added = append_runs(sweep_dir, RUNS_CSV, RUNS_DIR, ROOT)
    print(f"added {added} run(s) to {RUNS_CSV.relative_to(ROOT)}")


def committed() -> list[dict]:
    """The finished runs: algo, precision, seed, final returns, env steps and training seconds, machine."""
    if not RUNS_CSV.exists():
        return []
    out = []
    for row in read_rows(RUNS_CSV):
        if row["status"] != "ok":
            continue
        run = ROOT / row["run_dir"]
        report = json.loads((run / "eval.json").read_text())
        config = load_yaml(run / "config.yaml")
        out.append(
            {
                "algo": report["algo"],
                "bf16": bool(config["algorithm"]["use_mixed_precision"]),
                "seed": int(row["seed"]),
                "return": float(row["return_multi"]),
                "return_1": float(row["return_1"]) if row["return_1"] else None,
                "steps_per_s": report["env_steps"] / report["train_time_s"],
                "minutes": report["train_time_s"] / 60,
                "machine": report.get("machine"),
            }
        )
    return out


def section() -> str:
    runs = committed()
    if not runs:
        return f"No run of this comparison is committed yet (`{COMMAND}`)."
    cpus = sorted({f"{r['machine']['cpu']} ({r['machine']['cpu_capability']})" for r in runs if r["machine"]})
    header = "| algo | precision | seeds | return, N = 10 (PPO: mean action) | return, N = 1 | env steps/s | minutes |"
    lines = [header, "|---|---|---|---|---|---|---|"]
    said = []
    for algo, name in NAMES.items():
        group = {bf16: [r for r in runs if r["algo"] == algo and r["bf16"] == bf16] for bf16 in PRECISIONS}
        for bf16, precision in PRECISIONS.items():
            g = group[bf16]
            if not g:
                continue
            n1 = [r["return_1"] for r in g if r["return_1"] is not None]
            lines.append(
                f"| {name} | {precision} | {seeds_text(r['seed'] for r in g)} | "
                f"{mean_estimate(r['return'] for r in g).text()} | {mean_estimate(n1).text() if n1 else '--'} | "
                f"{np.mean([r['steps_per_s'] for r in g]):,.0f} | "
                f"{min(r['minutes'] for r in g):.1f}-{max(r['minutes'] for r in g):.1f} |"
            )
        if group[False] and group[True]:
            p = improvement_of([r["return"] for r in group[True]], [r["return"] for r in group[False]])
            verdict = {1: "bfloat16's runs end higher", -1: "float32's runs end higher", 0: "not separated"}[p.side]
            speed = np.mean([r["steps_per_s"] for r in group[True]]) / np.mean([r["steps_per_s"] for r in group[False]])
            said.append(
                f"- {name}: P(a bfloat16 run ends above a float32 run, N = 10) {p.text(2)}: {verdict}. A whole "
                f"bfloat16 run trains at {speed:.2f} times float32's env steps per second."
            )
    machine = f"On {' and '.join(cpus)}, one torch thread a run" if cpus else "The runs record no machine"
    return (
        f"{machine}, the precisions alternating run by run (`{COMMAND}`; a whole run's env steps per second: its env "
        "steps over the seconds its runner counts for collection and update). Means over seeds with 95 % bootstrap "
        "intervals:\n\n" + "\n".join(lines) + "\n\n" + "\n".join(said)
    )
