"""The clip ablation's gradient norms: each network's norm before clipping, read from the committed runs'
``progress_train.jsonl`` (``Loss/grad_norm_actor``, ``Loss/grad_norm_critic``: the mean over an update's minibatches),
and the factor a joint clip would scale the actor's gradient by at those norms."""

from __future__ import annotations

import statistics
from pathlib import Path

from refpo_warp.studies.reports.committed_runs import read_jsonl
from refpo_warp.studies.reports.phrases import value_range as span

ACTOR, CRITIC = "Loss/grad_norm_actor", "Loss/grad_norm_critic"


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
