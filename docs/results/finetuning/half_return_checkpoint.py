"""The weaker demonstrator's checkpoint: once a periodic evaluation of the run has reached ``TARGET`` (half the
from-scratch PPO's final return), the evaluated checkpoint whose return is nearest the target, up to that first
crossing (the run saves at its evaluations: runner.save_interval equal to eval.interval). A return can jump past the
target between two evaluations (point_mass: 361 at iteration 31, 814 at 35); the nearer one is the weaker policy the
study asks for.

    python docs/results/finetuning/half_return_checkpoint.py RUN_DIR TARGET   # prints the checkpoint's path; exit 1
                                                                              # while no evaluation has reached TARGET
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def half_return_checkpoint(run_dir: Path, target: float) -> tuple[Path, float] | None:
    rows = [json.loads(line) for line in (run_dir / "progress.jsonl").read_text().splitlines() if line.strip()]
    evaluated = [(r["eval/return"], run_dir / f"model_{r['iteration']}.pt") for r in rows if "eval/return" in r]
    evaluated = [(value, path) for value, path in evaluated if path.exists()]
    crossing = next((i for i, (value, _) in enumerate(evaluated) if value >= target), None)
    if crossing is None:
        return None
    value, path = min(evaluated[: crossing + 1], key=lambda e: abs(e[0] - target))
    return path, value


if __name__ == "__main__":
    found = half_return_checkpoint(Path(sys.argv[1]), float(sys.argv[2]))
    if found is None:
        print(f"{sys.argv[1]}: no evaluation has reached {sys.argv[2]} yet", file=sys.stderr)
        sys.exit(1)
    print(f"{found[0].stem}: return {found[1]:.1f} (target {sys.argv[2]})", file=sys.stderr)
    print(found[0])
