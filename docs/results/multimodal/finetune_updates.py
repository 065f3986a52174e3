"""What the fine-tuning runs' own training statistics say about where the clones are lost: each run's
``progress_train.jsonl`` (every iteration's training return, the flow's update statistics, the training episodes'
success), read at the end of the critic's warm-up and after it."""

from __future__ import annotations

import functools
import statistics
from pathlib import Path

from refpo_warp.studies.reports.committed_runs import read_jsonl
from refpo_warp.studies.reports.phrases import value_range

span = functools.partial(value_range, sep=" to ")  # this page writes a range as "a to b"

AFTER = 3  # the updates right after the warm-up that the clipping figures cover


def read_train_rows(run: Path) -> list[dict] | None:
    path = run / "progress_train.jsonl"
    if not path.exists():
        return None
    return read_jsonl(path)


def update_text(runs: dict[str, tuple[str, list[Path]]], warmup: int) -> str:
    """One line per method (``runs``: label -> (name, run folders)): its training return at the warm-up's last
    iteration and at the run's end, how many runs ended lower, and for a flow the median share of clipped ratios and
    approximate KL of the ``AFTER`` updates that follow the warm-up, with the clone's sampled spread there."""
    lines = []
    for name, folders in runs.values():
        logged = [r for r in (read_train_rows(f) for f in folders) if r and len(r) > warmup]
        if not logged:
            continue
        start = [r[warmup - 1]["reward_mean"] for r in logged]
        end = [r[-1]["reward_mean"] for r in logged]
        lower = sum(e < s for s, e in zip(start, end))
        line = (
            f"- **{name}**: training return {span(start, '.0f')} when the warm-up ends, {span(end, '.0f')} at the "
            f"end; {lower} of {len(logged)} runs end lower"
        )
        if all("Flow/clip_fraction" in r[warmup] for r in logged):
            after = [r[warmup : warmup + AFTER] for r in logged]
            clipped = [statistics.median(x["Flow/clip_fraction"] for x in a) for a in after]
            kl = [statistics.median(x["Flow/approx_kl"] for x in a) for a in after]
            spread = [r[warmup - 1]["Flow/policy_spread"] for r in logged]
            line += (
                f". In the {AFTER} updates after the warm-up it clips {span([100 * c for c in clipped], '.0f')} % of "
                f"its ratios (the median of a run) at an approximate KL of {span(kl, '.3g')}; the variance of the "
                f"clone's actions over its initial noise is {span(spread, '.1g')} there"
            )
        lines.append(line + ".")
    return "\n".join(lines)
