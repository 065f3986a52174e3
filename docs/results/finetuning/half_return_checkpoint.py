"""The weaker demonstrator's checkpoint: once a periodic evaluation of the run has reached ``TARGET`` (half the
from-scratch PPO's final return), the evaluated checkpoint whose return is nearest the target, up to that first
crossing (the run saves at its evaluations: runner.save_interval equal to eval.interval). A return can jump past the
target between two evaluations (point_mass: 361 at iteration 31, 814 at 35); the nearer one is the weaker policy the
study asks for.

    python docs/results/finetuning/half_return_checkpoint.py RUN_DIR TARGET   # prints the checkpoint's path; exit 1
                                                                              # while no evaluation has reached TARGET
"""

from __future__ import annotations

import sys
from pathlib import Path

from refpo_warp.runner.progress import read_rows


def nearest_up_to_crossing(evaluated: list[tuple[int, float]], target: float) -> tuple[int, float] | None:
    """Of (iteration, return) pairs in order, the one whose return is nearest ``target`` up to the first that reaches
    it; None while none has."""
    crossing = next((i for i, (_, value) in enumerate(evaluated) if value >= target), None)
    if crossing is None:
        return None
    return min(evaluated[: crossing + 1], key=lambda e: abs(e[1] - target))


def half_return_checkpoint(run_dir: Path, target: float) -> tuple[Path, float] | None:
    rows = read_rows(run_dir)  # the live log of a training run: a torn last line is skipped
    saved = [(r["iteration"], r["eval/return"]) for r in rows if "eval/return" in r]
    found = nearest_up_to_crossing([e for e in saved if (run_dir / f"model_{e[0]}.pt").exists()], target)
    return None if found is None else (run_dir / f"model_{found[0]}.pt", found[1])


if __name__ == "__main__":
    found = half_return_checkpoint(Path(sys.argv[1]), float(sys.argv[2]))
    if found is None:
        print(f"{sys.argv[1]}: no evaluation has reached {sys.argv[2]} yet", file=sys.stderr)
        sys.exit(1)
    print(f"{found[0].stem}: return {found[1]:.1f} (target {sys.argv[2]})", file=sys.stderr)
    print(found[0])
