#!/usr/bin/env python
"""What ReFPO's one-step sampler does (the investigation behind this folder's README):

    python docs/results/one_step/one_step_analysis.py SWEEP_DIR [out=DIR] [task=ID] [seed=K] [states=256] [noises=16]
        [every=1] [intervene=ITERATION] [intervene_iterations=5] [device=cpu] [curves_only=false]

Reads a refpo sweep dir whose runs logged the one-step diagnostic and kept checkpoints (configs/sweep/
cpu_reflow_pairs.yaml) and writes into out= (default SWEEP_DIR/one_step):

- <task>_one_step.png for every task: per method (mean over seeds, their range as a band) the periodic N = 10 and
  N = 1 evaluation returns, the one-step error |a_1(eps) - a_N(eps)|^2, the one-step ratio (error / spread) and the
  Reflow coefficient, over env steps;
- for task= (default dmc_point_mass) and seed=: the sampler probe of every checkpoint (every=k: each k-th) of every
  method on the states its own N-step policy visits (one_step_probes.py beside this script: one-step error, spread,
  distance of a_1 to the policy's mean action, a_1's own spread, saturation), <task>_probe_seed<k>.png; the
  velocity error by flow time of the last checkpoints along the sampler's paths and on independent pairs,
  <task>_velocity_by_tau_seed<k>.png; and, for dmc_point_mass, the paths the 1-step and 10-step policies drive from
  the same 8 initial states, <task>_paths_seed<k>.png;
- with intervene=<iteration>: from that checkpoint of the sweep's "refpo" run (independent pairs), a few training
  iterations under each of a few single changes (lambda 0 / 0.2, only positive or only negative advantages, coupled
  pairs), the same first rollout for all; the one-step error on fixed states, the velocity error by tau on the
  sampler's paths and the returns after them, <task>_intervention_seed<k>.png;
- one_step.json with every number behind the figures.

screen=<sweep> (with intervene=<iteration>) screens the sweep's candidates instead (configs/sweep/cpu_onestep.yaml):
from that checkpoint of the "refpo" run of every seed, intervene_iterations iterations under each candidate's
overrides and under ReFPO's own rule, the same first rollout for all, then the one-step error on the checkpoint's
N-step states and the N = 10 and N = 1 returns; <task>_screen.md and screen.json.

curves_only=true redraws the training figures alone (seconds, as more runs of the sweep finish) and updates their
numbers in an existing one_step.json, keeping its probes and intervention.

    python docs/results/one_step/one_step_analysis.py --page [--check]

writes this folder's README.md whole from README.template.md and the committed files (one_step.json, report/runs.csv,
../cpu_dmc/runs.csv, configs/sweep/cpu_reflow_pairs.yaml, configs/task/_dmc.yaml and criteria.yaml), or with --check
compares it with the page on disk; it trains and loads nothing.

The parts live beside this script: training_curves.py (the training figures), checkpoint_probes.py (the probes, on
one_step_probes.py's measures), intervention.py (intervene= and screen=), numbers_file.py (one_step.json); the page's
readme_data.py (its inputs), readme_summary.py and readme_details.py (its sections), and run_rows.py (the runs.csv
helpers it shares with search.md's script).
"""

import json
import sys
from pathlib import Path
from typing import Any

from checkpoint_probes import probe_figures, probe_run
from intervention import intervene, intervention_figure, screen
from numbers_file import write_numbers
from training_curves import method_runs, training_figures

from refpo_warp.cli.guard import EXIT_USAGE, run_guarded
from refpo_warp.config.dotted import parse_overrides
from refpo_warp.utils.errors import ConfigError, unknown

OPTIONS: dict[str, Any] = {  # key=value options of the command line, their types checked in main
    "out": None,
    "task": "dmc_point_mass",
    "seed": 1,
    "states": 256,
    "noises": 16,
    "every": 1,
    "device": "cpu",
    "intervene": None,
    "intervene_iterations": 5,
    "curves_only": False,
    "screen": None,
}
HERE = Path(__file__).resolve().parent


def page_values() -> dict:
    """Every field of README.template.md: the sections in the page's order, each adding what later ones read."""
    from readme_data import load_page_data
    from readme_details import (
        by_tau_text,
        diagnostics_and_leads,
        intervention_texts,
        mechanism,
        other_tasks,
        over_training,
        paths_text,
        probe_texts,
    )
    from readme_summary import cpu_dmc_standing, directions, how_measured, in_short, main_table

    c = load_page_data()
    out: dict = {"seed": c.seed, "collapse": f"{c.below:g}"}
    for section in (
        cpu_dmc_standing,
        in_short,
        how_measured,
        main_table,
        directions,
        over_training,
        paths_text,
        probe_texts,
        by_tau_text,
        intervention_texts,
        mechanism,
        other_tasks,
        diagnostics_and_leads,
    ):
        out.update(section(c))
    return out


def write_readme(argv: list[str]) -> int:
    from refpo_warp.studies.reports.results_page import main_args, write_page

    parser = main_args("README.md of docs/results/one_step from its template and the committed data files")
    parser.add_argument("--page", action="store_true", help="write the page (the default when --check is not given)")
    args = parser.parse_args(argv)
    same = write_page(HERE / "README.template.md", page_values(), check=args.check)
    if args.check:
        return 0 if same else 1
    print(f"{HERE / 'README.md'}: {'unchanged' if same else 'written'}")
    return 0


def main(argv: list[str]) -> int:
    if argv and argv[0] in ("--page", "--check"):
        return write_readme(argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else EXIT_USAGE

    def analyse() -> None:
        sweep = Path(argv[0])
        if not sweep.is_dir():
            raise ConfigError(f"{sweep}: no such sweep directory (a refpo sweep output dir)")
        options: dict[str, Any] = dict(OPTIONS)
        for key, value in parse_overrides(argv[1:]).items():
            if key not in OPTIONS:
                raise unknown("option", key, list(OPTIONS))
            options[key] = value
        for key in ("seed", "states", "noises", "every", "intervene_iterations"):
            if not isinstance(options[key], int) or options[key] < (0 if key == "seed" else 1):
                raise ConfigError(f"{key}={options[key]!r} is invalid; expected a positive integer")
        if not isinstance(options["curves_only"], bool):
            raise ConfigError(f"curves_only={options['curves_only']!r} is invalid; expected true or false")
        out = Path(options["out"] or sweep / "one_step")
        out.mkdir(parents=True, exist_ok=True)
        runs = method_runs(sweep)
        if options["task"] not in runs:
            raise unknown("task", options["task"], list(runs))
        numbers = {"training": {} if options["screen"] else training_figures(runs, out), "probes": {}}
        if options["curves_only"]:
            previous = out / "one_step.json"
            kept = json.loads(previous.read_text()) if previous.is_file() else {}
            write_numbers({**kept, "training": numbers["training"]}, previous)
            print(previous)
            return
        task, seed = options["task"], options["seed"]
        if options["screen"] is not None:
            if options["intervene"] is None:
                raise ConfigError("screen= needs intervene=<checkpoint iteration> (the iteration to screen from)")
            print(screen(runs[task], task, options, out))
            return
        for label, seeds in sorted(runs[task].items()):
            if seed in seeds:
                print(f"[one_step] probing {task}/{label}/seed{seed}", flush=True)
                numbers["probes"][label] = probe_run(seeds[seed], options)
        for path in probe_figures(task, seed, numbers["probes"], out):
            print(path)
        if options["intervene"] is not None:
            base = runs[task].get("refpo", {}).get(seed)
            if base is None:
                raise ConfigError(f"intervene= needs the sweep's 'refpo' run of {task} seed {seed}")
            results = intervene(base, int(options["intervene"]), int(options["intervene_iterations"]), options)
            numbers["intervention"] = {"iteration": int(options["intervene"]), **results}
            print(intervention_figure(task, seed, int(options["intervene"]), results, out))
        write_numbers(numbers, out / "one_step.json")
        print(out / "one_step.json")

    return run_guarded(analyse)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
