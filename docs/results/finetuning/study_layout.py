"""Where the fine-tuning study's committed files are, the methods its DMC sweeps ran (labels, names, the sweeps they
come from) and the thresholds its page judges by; JSON and YAML readers."""

from __future__ import annotations

import json
from pathlib import Path

import yaml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
TEMPLATE = HERE / "README.template.md"
KEPT = HERE / "gridworld"
DMC_KEPT = HERE / "dmc"  # the demonstrator, data and clones, and the fine-tuning runs (clone_normalizer=keep)
UPDATED_KEPT = HERE / "normalizers_updated"  # fine-tuning runs whose normalisers followed the rollouts, remedies tried
SCRATCH_KEPT = HERE / "scratch"  # from scratch at the fine-tuning runs' env steps
DMC_TASKS = ("dmc_point_mass", "dmc_reacher_easy")
DMC_METHODS = (  # (sweep label, the method it varies, name); the variants are the remedies tried for ReFPO's collapse
    ("refpo", "refpo", "ReFPO"),
    ("refpo_action_noise_std0.02", "refpo", "ReFPO, action noise 0.02"),
    ("refpo_action_noise_std0.05", "refpo", "ReFPO, action noise 0.05"),
    ("refpo_lr1e-4", "refpo", "ReFPO, learning rate 1e-4"),
    ("refpo_adaptive", "refpo", "ReFPO, adaptive λ"),
    ("refpo_aspo", "refpo", "ReFPO, ASPO trust region"),
    ("refpo_onestep", "refpo_onestep", "refpo_onestep"),
    ("refpo_onestep_action_noise_std0.02", "refpo_onestep", "refpo_onestep, action noise 0.02"),
    ("refpo_onestep_action_noise_std0.05", "refpo_onestep", "refpo_onestep, action noise 0.05"),
    ("ppo", "ppo", "PPO"),
    ("ppo_lr1e-4", "ppo", "PPO, learning rate 1e-4"),
)
NAMES = {label: name for label, _, name in DMC_METHODS}


def prose(label: str) -> str:
    """A run's name inside a sentence: 'ReFPO with adaptive λ', '`refpo_onestep`'."""
    head, _, tail = NAMES[label].partition(", ")
    return (f"{head} with {tail}" if tail else head).replace("refpo_onestep", "`refpo_onestep`")


# (where the runs are kept, the sweeps they come from by task name, how they started)
DMC_SOURCES = (
    (DMC_KEPT, ("finetune_{}", "finetune_remedies_keep_{}"), "the {clone}"),
    (
        UPDATED_KEPT,
        ("finetune_normupdate_{}", "finetune_floor_{}", "finetune_remedies_{}"),
        "the {clone}, normalisers updated",
    ),
    (SCRATCH_KEPT, ("finetune_scratch",), "scratch"),
)
DMC_FIGURE, REMEDIES_FIGURE = HERE / "dmc_curves.png", HERE / "dmc_remedies.png"
FROM_SCRATCH = HERE.parent / "cpu_dmc" / "per_task.csv"  # PPO's final return at the full CPU profile
CHECK_RECORDS = HERE.parent / "learning_checks" / "records" / "gridworld_finetune_refpo.jsonl"
CHECKS_SOURCE = ROOT / "tests" / "learning" / "checks.py"
ROWS = [  # (run folder, what it is)
    ("clone_flow", "flow clone (refpo pretrain algo=refpo)"),
    ("clone_gauss", "Gaussian clone (refpo pretrain algo=ppo)"),
    ("refpo_from_flow", "ReFPO fine-tuned from the flow clone"),
    ("fpo_from_flow", "FPO fine-tuned from the flow clone"),
    ("ppo_from_gauss", "PPO fine-tuned from the Gaussian clone"),
]
FILES = ("config.yaml", "eval.json", "progress.jsonl")
TIMEOUTS = KEPT / "clone_gauss" / "timeout_rows.json"
BOTH_BANDS = 0.2  # each goal band's least share of the successes (tests/learning/checks.py: both_bands_kept)
MOVE = 0.5  # GridWorld moves an axis only where |action| > MOVE (tasks/gridworld/env.py: rounded to {-1, 0, 1})
FALL = 0.5  # a run "falls" when its last periodic N = 10 return is below this share of its peak
FLOWS_HELD = ("refpo", "refpo_adaptive", "refpo_aspo", "refpo_onestep")  # fine-tuned flows, normalisers held


def read_json(path: Path) -> dict:
    return json.loads(path.read_text())


def read_yaml(path: Path) -> dict:
    return yaml.safe_load(path.read_text())
