"""The weaker demonstrator's checkpoint: the first periodic evaluation of a run whose return reaches half the run's
final one, among the iterations that have a checkpoint (the run saves at its evaluations: runner.save_interval equal
to eval.interval).

    python docs/results/finetuning/half_return_checkpoint.py RUN_DIR     # prints the checkpoint's path
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def half_return_checkpoint(run_dir: Path) -> tuple[Path, float, float]:
    rows = [json.loads(line) for line in (run_dir / "progress.jsonl").read_text().splitlines() if line.strip()]
    evaluated = [(r["iteration"], r["eval/return"]) for r in rows if "eval/return" in r]
    final = evaluated[-1][1]
    for iteration, value in evaluated:
        path = run_dir / f"model_{iteration}.pt"
        if value >= 0.5 * final and path.exists():
            return path, value, final
    raise SystemExit(f"{run_dir}: no checkpoint at an evaluation with half the final return {final:.1f}")


if __name__ == "__main__":
    path, value, final = half_return_checkpoint(Path(sys.argv[1]))
    print(f"{path.stem}: return {value:.1f} of the final {final:.1f}", file=sys.stderr)
    print(path)
