#!/usr/bin/env python
"""Fine-tuning on the two-way task from its clones: ``finetuning.md`` in this folder, written whole from
``finetuning.template.md`` and the committed runs (nothing typed in by hand):

    python docs/results/multimodal/finetuning.py [--add-runs runs/sweeps/finetune_point_mass_wall] [--check]

Rows: ``finetune/runs.csv`` (``refpo sweep finetune_point_mass_wall``, then ``refpo report`` of it); each run's
``eval.json`` (success and each way's share at N = 10 and N = 1, PPO: its mean action), ``progress_eval.jsonl``
(the periodic evaluation's curves) and ``progress_train.jsonl`` (its training statistics) under ``finetune/runs/``;
the clones' ``eval.json`` beside this script. ``--add-runs`` appends the finished runs of a sweep dir not yet in the
table and copies their small files.
"""

from __future__ import annotations

import json
import sys

import numpy as np
from finetune_updates import update_text
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
    numbers,
    outcome,
    page_arguments,
    per_run_table,
    summary,
)

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import seeds_text
from refpo_warp.studies.reports.results_page import write_page

RUNS = TwoWayRuns(ROOT / "configs" / "sweep" / "finetune_point_mass_wall.yaml", HERE / "finetune" / "runs.csv")
FIGURE = HERE / "finetune_curves.png"
CLONE_OF = {  # method label -> the clone folder (beside this script) its runs start from
    "refpo": "clone_flow",
    "refpo_adaptive": "clone_flow",
    "fpo": "clone_fpo",
    "fpo_pp": "clone_fpo_pp",
    "ppo": "clone_gauss",
}
MEASURED_CLONES = {  # clone, setting -> its setting in clones.json (the clones page's 500 episodes)
    ("clone_flow", "N=10"): "flow_N10",
    ("clone_flow", "N=1"): "flow_N1",
    ("clone_gauss", "mean_action"): "gauss_mean",
}


def clone_numbers(clone: str, setting: str) -> dict[str, float]:
    """A clone's numbers at ``setting``: the clones page's rollouts (clones.json) where it made them, else the
    clone's own evaluation (its eval.json, the pretrain run's)."""
    if (clone, setting) in MEASURED_CLONES:
        m = json.loads((HERE / "clones.json").read_text())["settings"][MEASURED_CLONES[clone, setting]]
        k = m["episodes"]
        return numbers(
            {
                "success_mean": m["success"] / k,
                "went_left_mean": m["left"] / k,
                "went_right_mean": m["right"] / k,
                "return_mean": float(np.mean(m["returns"])),
                "episodes": k,
            }
        )
    return numbers(json.loads((HERE / clone / "eval.json").read_text())["results"][setting])


def clone_row(label: str, setting: str) -> str:
    c = clone_numbers(CLONE_OF[label], setting)
    return (
        f"| its clone (`{CLONE_OF[label]}`) | {c['episodes']} episodes | {100 * c['success']:.0f} % | "
        f"{100 * c['left']:.0f} % | {100 * c['right']:.0f} % | {100 * c['rarer']:.0f} % | {c['return']:.0f} | "
        f"{outcome(c)} |"
    )


def warmup_iterations() -> int:
    """The critic's warm-up (``critic_warmup_iterations``, the actor held fixed), from a run's config."""
    return int(RUNS.first_config()["critic_warmup_iterations"])


def warmup_env_steps() -> int:
    """Env steps of the critic's warm-up, from a run's config."""
    cfg = RUNS.first_config()
    return warmup_iterations() * int(cfg["num_envs"]) * int(cfg["runner"]["num_steps_per_env"])


def figure() -> None:
    curves_figure(
        RUNS,
        FIGURE,
        "dmc_point_mass_wall, fine-tuned from clones: mean over seeds, band from the lowest to the highest",
        "env steps of fine-tuning",
        (warmup_env_steps(), "critic warm-up ends"),
    )


def values() -> dict[str, object]:
    sweep = load_yaml(RUNS.sweep)
    seeds = RUNS.seeds()
    data = json.loads((HERE / "data" / "metadata.json").read_text())
    return {
        "env_steps": f"{sweep['overrides']['total_env_steps']:,}",
        "eval_episodes": sweep["overrides"]["eval"]["num_envs"],
        "seeds": seeds_text(seeds),
        "n_seeds": len(seeds),
        "data_episodes": data["total_episodes"],
        "left_share": data["refpo"]["policy"]["left_share"],
        "summary": summary(RUNS),
        "updates": update_text(
            {m["label"]: (m["name"], RUNS.folders(m["label"])) for m in RUNS.methods()}, warmup_iterations()
        ),
        "warmup": f"{warmup_env_steps():,}",
        "machine": MACHINE,
        "success_floor": f"{100 * SUCCESS_FLOOR:.0f} %",
        "minority_floor": f"{100 * MINORITY_FLOOR:.0f} %",
        "table_10": method_table(RUNS, 10, clone_row),
        "table_1": method_table(RUNS, 1, clone_row),
        "per_run": per_run_table(RUNS),
        "comparisons": comparison_table(RUNS),
    }


def main() -> None:
    args = page_arguments(__doc__ or "", RUNS)
    if not args.check:
        figure()
    same = write_page(HERE / "finetuning.template.md", values(), check=args.check)
    sys.exit(0 if same or not args.check else 1)


if __name__ == "__main__":
    main()
