"""``refpo eval``: evaluate a trained run."""

from __future__ import annotations

import contextlib
from pathlib import Path

from refpo_warp.cli.explain import EXPLAIN, explain_or_run
from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError

SUMMARY = "evaluate a trained run: eval.json with the returns at each flow-step count and the flow diagnostics"
USAGE = """Evaluate a trained run: refpo eval run_dir=PATH [checkpoint=PATH] [eval.flow_steps=[1,10]] [key=value ...]

Writes eval.json (returns and task metrics at each flow-step count, Straightness Error, Explosion Rate) and the
task's figures into the run dir (a replaced eval.json is kept as eval.prev.json). Overrides apply on top of the
run's saved config.yaml. Flags: --explain [KEY,KEY,...] (the saved config with the overrides; nothing is evaluated).
"""
FLAGS = (EXPLAIN,)
SUBJECTS = 0


def run(args: Arguments) -> None:
    explain_or_run("eval", args, evaluate)


def evaluate(options: list[str]) -> None:
    from refpo_warp.config.dotted import parse_overrides
    from refpo_warp.evaluation.evaluate_run import evaluate_run
    from refpo_warp.utils.console import headline_numbers, run_outputs, summary_block
    from refpo_warp.utils.device import set_torch_threads
    from refpo_warp.utils.errors import tag_run_dir

    set_torch_threads(cuda_cap=4)
    overrides = parse_overrides(options)
    run_dir = overrides.pop("run_dir", None)
    if run_dir is None:
        raise ConfigError("refpo eval needs run_dir=PATH (a directory written by refpo train)")
    checkpoint = overrides.pop("checkpoint", None)
    if checkpoint is not None and not isinstance(checkpoint, str):
        raise ConfigError(f"checkpoint={checkpoint!r} is invalid; expected a path to a model_<iteration>.pt file")
    run_dir = Path(str(run_dir))
    with tag_run_dir(run_dir) if run_dir.is_dir() else contextlib.nullcontext():
        results = evaluate_run(run_dir, checkpoint=checkpoint, overrides=overrides)
    evaluated = checkpoint or run_dir / f"model_{results['checkpoint_iteration']}.pt"
    title = f"Evaluated {results['task']} / {results['algo']} at iteration {results['checkpoint_iteration']}"
    print(summary_block(title, run_outputs(run_dir, evaluated, results), headline_numbers(results)), flush=True)
