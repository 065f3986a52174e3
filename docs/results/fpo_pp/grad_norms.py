"""Gradient norms of the clip ablation and of the small-task recipe: each network's norm before clipping, read from the
committed runs' ``progress_train.jsonl`` (``Loss/grad_norm_actor``, ``Loss/grad_norm_critic``: the mean over an update's
minibatches), the factor a joint clip scales the actor's gradient by at those norms, and where the recipe's adaptive
learning rate sat."""

from __future__ import annotations

import statistics
from pathlib import Path

from refpo_warp.algorithms.on_policy import ADAPTIVE_LR_RANGE
from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import read_jsonl
from refpo_warp.studies.reports.phrases import value_range as span

ACTOR, CRITIC = "Loss/grad_norm_actor", "Loss/grad_norm_critic"
LR, KL = "Loss/learning_rate", "Flow/noise_prediction_kl"


def norms(run: Path) -> list[tuple[float, float]] | None:
    """(actor, critic) per iteration, or None where the run's files hold no gradient norms."""
    path = run / "progress_train.jsonl"
    if not path.exists():
        return None
    rows = read_jsonl(path)
    pairs = [(r[ACTOR], r[CRITIC]) for r in rows if ACTOR in r and CRITIC in r]
    return pairs or None


def joint_factor(actor: float, critic: float, max_norm: float) -> float:
    """What a clip of ``max_norm`` over both networks at once multiplies every gradient by (torch's
    ``clip_grad_norm_``: the total norm is the 2-norm of the networks' norms)."""
    return min(1.0, max_norm / (actor * actor + critic * critic) ** 0.5)


def grad_norm_text(runs: dict[str, list[Path]], joint_runs: list[Path], max_norm: float) -> str:
    """A paragraph on the ablated runs' norms (``runs``: label -> run folders) and the joint clip's factor at them;
    ``joint_runs`` are the joint-clip runs, named as having norms or not."""
    parts = []
    for label, folders in runs.items():
        logged = [n for n in (norms(f) for f in folders) if n]
        if not logged:
            continue
        actor = [statistics.median(a for a, _ in n) for n in logged]
        critic = [statistics.median(c for _, c in n) for n in logged]
        last = [n[-1][1] for n in logged]
        factor = [statistics.median(joint_factor(a, c, max_norm) for a, c in n) for n in logged]
        lowest = [min(joint_factor(a, c, max_norm) for a, c in n) for n in logged]
        parts.append(
            f"in the {len(logged)} `{label}` runs the actor's median norm over iterations is "
            f"{span(actor, '.2f')} and the critic's {span(critic, '.0f')}, reaching {span(last, '.0f')} at the last "
            "iteration; "
            f"a joint clip of {max_norm:g} at these norms would multiply the actor's gradient by a median "
            f"{span(factor, '.2f')} a run (lowest {span(lowest, '.3f')})"
        )
    if not parts:
        return ""
    joint_logged = sum(norms(f) is not None for f in joint_runs)
    joint = (
        f"{joint_logged} of the {len(joint_runs)} joint-clip runs hold their own norms"
        if joint_logged
        else f"the {len(joint_runs)} joint-clip runs were trained before the norms were logged, so their own are not "
        "in their files"
    )
    return (
        "**Gradient norms.** Each network's norm before clipping (`Loss/grad_norm_actor`, `Loss/grad_norm_critic`, "
        "the mean over an update's minibatches; each run's `progress_train.jsonl`): "
        + "; ".join(parts)
        + f". The critic's norm sets a joint clip, and the actor's step shrinks with it; {joint}."
    )


def small_recipe_text(runs: dict[str, list[Path]]) -> str:
    """What the small-task recipe's runs (by task) logged: the share of iterations its adaptive learning rate spent at
    the schedule's upper bound, the KL estimate it steers by against the band that raises the rate, and, per task, the
    joint clip's factor on the actor's gradient (the recipe clips actor and critic together)."""
    logged = {
        task: [rows for rows in (read_jsonl(f / "progress_train.jsonl") for f in folders if has_progress(f)) if rows]
        for task, folders in runs.items()
    }
    logged = {t: [r for r in rs if all(k in r[0] for k in (LR, KL, ACTOR, CRITIC))] for t, rs in logged.items()}
    logged = {t: rs for t, rs in logged.items() if rs}
    if not logged:
        return ""
    first = next(f for folders in runs.values() for f in folders if has_progress(f))
    cfg = load_yaml(first / "config.yaml")["algorithm"]
    desired, max_norm, top = float(cfg["desired_kl"]), float(cfg["max_grad_norm"]), ADAPTIVE_LR_RANGE[1]
    every = [rows for rs in logged.values() for rows in rs]
    at_top = [sum(r[LR] >= top for r in rows) / len(rows) for rows in every]
    below = [sum(r[KL] < desired / 2 for r in rows) / len(rows) for rows in every]
    kl = [statistics.median(r[KL] for r in rows) for rows in every]
    shares = [span([100 * a for a in at_top], ".0f"), span([100 * b for b in below], ".0f")]

    def clip(task: str, rs: list[list[dict]]) -> str:
        factor = [statistics.median(joint_factor(r[ACTOR], r[CRITIC], max_norm) for r in rows) for rows in rs]
        critic = [statistics.median(r[CRITIC] for r in rows) for rows in rs]
        actor = [statistics.median(r[ACTOR] for r in rows) for rows in rs]
        return (
            f"{span(factor, '.2g', ' to ')} on {task} ({len(rs)} run{'s' if len(rs) != 1 else ''}; the critic's "
            f"median norm {span(critic, '.0f')}, the actor's {span(actor, '.2f')})"
        )

    return (
        f"**What the small-task recipe's runs logged** ({len(every)} runs, each run's `progress_train.jsonl`): its "
        f"adaptive learning rate sat at the schedule's upper bound, {top:g}, in {shares[0]} % of iterations; the KL "
        "estimate it steers by (the change of the noise-end prediction, `Flow/noise_prediction_kl`) had a median of "
        f"{span(kl, '.1e', ' to ')} a run and was below half the desired {desired:g}, which raises the rate, in "
        f"{shares[1]} % of iterations. Its joint clip of {max_norm:g} multiplied the actor's gradient by a median "
        + "; ".join(clip(task, rs) for task, rs in logged.items())
        + "."
    )


def has_progress(folder: Path) -> bool:
    return (folder / "progress_train.jsonl").exists()
