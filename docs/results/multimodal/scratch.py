#!/usr/bin/env python
"""The two-way task from scratch: ``scratch.md`` in this folder, written whole from ``scratch.template.md`` and the
committed runs (nothing typed in by hand):

    python docs/results/multimodal/scratch.py [--add-runs runs/sweeps/scratch_point_mass_wall] [--check]

Rows: ``scratch/runs.csv`` (``refpo sweep scratch_point_mass_wall``, then ``refpo report`` of it); each run's
``eval.json``, ``progress_eval.jsonl`` and ``progress_train.jsonl`` under ``scratch/runs/``. ``--add-runs`` appends
the finished runs of a sweep dir not yet in the table and copies their small files; the page shows every run
committed so far and names the grid's runs still to come.
"""

from __future__ import annotations

import sys

from two_way_runs import (
    HERE,
    MACHINE,
    MINORITY_FLOOR,
    ROOT,
    SUCCESS_FLOOR,
    TwoWayRuns,
    comparison_table,
    curves_figure,
    method_table,
    page_arguments,
    per_run_table,
    percent,
    summary,
)

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.intervals import mean_estimate
from refpo_warp.studies.reports.phrases import and_list
from refpo_warp.studies.reports.results_page import write_page

RUNS = TwoWayRuns(ROOT / "configs" / "sweep" / "scratch_point_mass_wall.yaml", HERE / "scratch" / "runs.csv")
FINETUNED = TwoWayRuns(ROOT / "configs" / "sweep" / "finetune_point_mass_wall.yaml", HERE / "finetune" / "runs.csv")
FIGURE = HERE / "scratch_curves.png"


def progress() -> str:
    """How much of the sweep's grid is committed, and what is still to run."""
    sweep = load_yaml(RUNS.sweep)
    grid = len(sweep["methods"]) * len(sweep["seeds"])
    done = {(r["label"], int(r["seed"])) for r in RUNS.rows if r["status"] in ("ok", "failed")}
    missing = [
        f"{m['label']} ({seeds_text([s for s in sweep['seeds'] if (m['label'], s) not in done])})"
        for m in sweep["methods"]
        if any((m["label"], s) not in done for s in sweep["seeds"])
    ]
    if not missing:
        return f"All {grid} runs of the grid are committed."
    return (
        f"{len(done)} of the grid's {grid} runs are committed; still to run: {and_list(missing)}. "
        "`refpo sweep scratch_point_mass_wall --jobs 2` runs them (it skips finished runs and continues paused ones), "
        "then this page's command adds them."
    )


def against_finetuning() -> str:
    """Each method's success at N = 10 (PPO: its mean action) from scratch beside fine-tuned from its clone."""
    lines = []
    for method in RUNS.methods():
        label = method["label"]
        scratch, tuned = RUNS.run_results(label), FINETUNED.run_results(label)
        if not scratch or not tuned:
            continue
        success = [
            percent(mean_estimate([p["success"] for p in runs.numbers_at(label, 10).values()]))
            for runs in (RUNS, FINETUNED)
        ]
        lines.append(
            f"- **{method['name']}**: success {success[0]} from scratch (seeds {seeds_text(scratch)}, "
            f"{RUNS.first_config()['total_env_steps']:,} env steps) against {success[1]} fine-tuned from its clone "
            f"(seeds {seeds_text(tuned)}, {FINETUNED.first_config()['total_env_steps']:,} env steps after cloning)."
        )
    return "\n".join(lines) if lines else "No method has runs on both pages yet."


def values() -> dict[str, object]:
    sweep = load_yaml(RUNS.sweep)
    seeds = RUNS.seeds()
    return {
        "sweep_seeds": seeds_text(sweep["seeds"]),
        "seeds": seeds_text(seeds) if seeds else "none yet",
        "eval_episodes": sweep["overrides"]["eval"]["num_envs"],
        "methods": "; ".join(m["name"] for m in sweep["methods"]),
        "progress": progress(),
        "success_floor": f"{100 * SUCCESS_FLOOR:.0f} %",
        "minority_floor": f"{100 * MINORITY_FLOOR:.0f} %",
        "table_10": method_table(RUNS, 10),
        "table_1": method_table(RUNS, 1),
        "per_run": per_run_table(RUNS),
        "comparisons": comparison_table(RUNS),
        "summary": summary(RUNS) or "No run is committed yet.",
        "against_finetuning": against_finetuning(),
        "figure": (
            "![Success and the left share of the passes through training, per method](scratch_curves.png)"
            if FIGURE.exists()
            else "(drawn once runs are committed)"
        ),
        "machine": MACHINE,
    }


def main() -> None:
    args = page_arguments(__doc__ or "", RUNS)
    if not args.check and RUNS.rows:
        curves_figure(
            RUNS,
            FIGURE,
            "dmc_point_mass_wall from scratch: mean over seeds, band from the lowest to the highest",
            "env steps",
        )
    same = write_page(HERE / "scratch.template.md", values(), check=args.check)
    sys.exit(0 if same or not args.check else 1)


if __name__ == "__main__":
    main()
