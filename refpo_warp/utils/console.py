"""Console output of the tools: third-party chatter kept out of sight unless asked for, and the closing summary block.

rsl_rl prints the model structure, the resolved observation sets and its git-state messages ("Storing git diff",
"Could not find git repository ... Skipping.") with plain ``print``. Rather than patching its internals (which differ
between rsl-rl-lib versions), the calls that print are run with stdout captured; with ``verbose=true`` they print.
"""

from __future__ import annotations

import contextlib
import io
import sys
from collections.abc import Iterator
from pathlib import Path


@contextlib.contextmanager
def quiet_stdout(quiet: bool = True) -> Iterator[None]:
    """Capture ``sys.stdout`` while ``quiet``; if the block raises, what it printed goes to stderr (it may explain
    the failure), then the exception propagates."""
    if not quiet:
        yield
        return
    captured = io.StringIO()
    try:
        with contextlib.redirect_stdout(captured):
            yield
    except BaseException:
        if captured.getvalue():
            sys.stderr.write(captured.getvalue())
            sys.stderr.flush()
        raise


GENERIC = ("episodes", "unfinished", "return_mean", "return_std", "length_mean")
HEADLINE_DIAGNOSTICS = ("straightness_error", "explosion_rate", "ratio_max", "clip_fraction")


def headline_numbers(results: dict) -> list[tuple[str, str]]:
    """One row per evaluation setting (``N=10``, ``N=1``, ``mean_action``): return (mean ± std over episodes), episode
    length and the task's metrics."""
    rows = []
    for setting, summary in results.get("results", {}).items():
        parts = []
        if "return_mean" in summary:
            parts.append(f"return {summary['return_mean']:.2f} ± {summary.get('return_std', 0.0):.2f}")
        if "length_mean" in summary:
            parts.append(f"length {summary['length_mean']:.1f}")
        parts += [f"{k} {v:.4g}" for k, v in summary.items() if k not in GENERIC and isinstance(v, float)]
        parts.append(f"({summary.get('episodes', 0)} episodes)")
        rows.append((f"eval {setting}", "  ".join(parts)))
    if results.get("health"):
        rows.append(("run health", health_line(results["health"])))
    diagnostics = results.get("diagnostics", {})
    shown = [f"{k} {diagnostics[k]:.4g}" for k in HEADLINE_DIAGNOSTICS if isinstance(diagnostics.get(k), float)]
    if shown:
        rows.append(("diagnostics", "  ".join(shown) + "  (all of them in eval.json)"))
    return rows


def health_line(health: dict) -> str:
    """A run's health (``refpo_warp.evaluation.run_health``) on one line: ``cliff: healthy (no cliff after ...);
    N=10 peak 950 (it 39), final 940 (-1 %)``."""
    cliff = health.get("cliff") or {}
    parts = [f"cliff: {cliff['status'].replace('_', ' ')} ({cliff['message']})"] if cliff else []
    parts += [
        f"{setting} peak {h['peak']:.4g} (it {h['peak_iteration']}), final {h['final']:.4g} ({-100 * h['drop']:+.0f} %)"
        for setting, h in (health.get("curves") or {}).items()
    ]
    return ";  ".join(parts)


def run_outputs(run_dir: Path, checkpoint, results: dict | None) -> list[tuple[str, object]]:
    """Where a run's files are: run dir, checkpoint, config, progress log, TensorBoard, eval.json, figures."""
    run_dir = Path(run_dir)

    def present(name: str):
        return run_dir / name if (run_dir / name).is_file() else None

    tensorboard = f"{run_dir} (tensorboard --logdir {run_dir})" if any(run_dir.glob("events.out.tfevents*")) else None
    return [
        ("run dir", run_dir),
        ("checkpoint", checkpoint),
        ("config", present("config.yaml")),
        ("progress log", present("progress.jsonl")),
        ("TensorBoard", tensorboard),
        ("eval.json", present("eval.json") if results else None),
        ("previous eval", present("eval.prev.json") if results else None),
        ("figures", figure_list((results or {}).get("figures", []))),
        ("videos", figure_list((results or {}).get("videos", []))),
    ]


def summary_block(title: str, outputs: list[tuple[str, object]], numbers: list[tuple[str, str]]) -> str:
    """A framed block: where each output went (``name: path``; missing entries skipped) and the headline numbers."""
    rows = [(name, str(where)) for name, where in outputs if where not in (None, "", [])]
    rows += list(numbers)
    width = max((len(name) for name, _ in rows), default=0)
    rule = "=" * 100
    lines = [rule, title]
    lines += [f"  {name:<{width}}  {value}" for name, value in rows]
    lines.append(rule)
    return "\n".join(lines)


def figure_list(paths: list) -> str | None:
    """Figure paths as one line: their common directory once, then the file names."""
    if not paths:
        return None
    paths = [Path(p) for p in paths]
    parents = {p.parent for p in paths}
    if len(parents) == 1:
        return f"{paths[0].parent}/{{{', '.join(p.name for p in paths)}}}"
    return ", ".join(str(p) for p in paths)
