#!/usr/bin/env python
"""Run a sweep: python tools/sweep.py <sweep name or file> [key=value ...] [--jobs N] [--dry-run] [--launcher CMD]
                                      [--backend local|ray] [--ray-address ADDR] [--gpus-per-run G] [--cpus-per-run C]

A grid of tasks x methods x seeds (x list-valued overrides), each run a separate tools/train.py process in
<sweep dir>/<task>/<label>/seed<k> (default sweep dir: runs/sweeps/<name>). Every run's config is resolved before
anything starts. Finished runs are skipped; a failed run is reported with its log and retried once from scratch.

Named sweeps (configs/sweep/): cpu_dmc (the CPU-scale DMC reproduction), paper_dmc (the paper's DMC grid, CUDA).

Examples:
    python tools/sweep.py cpu_dmc                                  # then: python tools/report.py runs/sweeps/cpu_dmc
    python tools/sweep.py cpu_dmc tasks=dmc_point_mass seeds=[1]   # a subset of the grid
    python tools/sweep.py cpu_dmc methods=refpo algorithm.reflow_coef=[0.02,0.08] out=runs/sweeps/lambda
    python tools/sweep.py paper_dmc --dry-run                      # list the runs and their states, train nothing
    cpuslot 2 python tools/sweep.py cpu_dmc --launcher "cpuslot 1" # on a machine that shares its cores
    python tools/sweep.py paper_dmc --backend ray --ray-address auto  # on the head of a Ray cluster: a GPU per run

Sweep-level keys: tasks=, seeds=, methods= (labels to keep), device=, out= (the sweep dir); any other key=value is
a run option for every run (tools/train.py's keys); a list expands the grid unless the option itself takes a list.
Options: --jobs N runs at a time (default: the CPU cores; on CUDA one per GPU; more share the GPUs round-robin),
--retries N (default 1), --launcher "CMD" prefixes each training command, --dry-run.

--backend ray: every run is one Ray task, on the node and GPU Ray picks (pip install -e ".[ray]"; the cluster's
nodes must share the sweep dir and the repository: docs/results/README.md, "On a cluster"). --ray-address auto or
HOST:PORT (default: RAY_ADDRESS, else a new local Ray); --gpus-per-run G (default 1 on CUDA, 0 on CPU; 0.5 packs two
runs on a GPU); --cpus-per-run C (default 1: a CPU run's torch threads); --jobs then defaults to the runs the
cluster fits at once. A lost worker or node is re-run by Ray, not counted as one of the run's --retries.
"""

import argparse
import signal
import sys


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="tools/sweep.py", add_help=False)
    parser.add_argument("sweep", nargs="?")
    parser.add_argument("--jobs", type=int, default=None)
    parser.add_argument("--retries", type=int, default=1)
    parser.add_argument("--launcher", default="")
    parser.add_argument("--dry-run", action="store_true")
    parser.add_argument("--backend", default="local")
    parser.add_argument("--ray-address", default=None)
    parser.add_argument("--gpus-per-run", type=float, default=None)
    parser.add_argument("--cpus-per-run", type=float, default=None)
    parser.add_argument("-h", "--help", action="store_true")
    args, rest = parser.parse_known_args(argv)
    if args.help or args.sweep is None:
        print(__doc__)
        return 0 if args.help else 2
    unknown = [a for a in rest if "=" not in a]
    if unknown:
        print(f"error: unknown option(s) {unknown}; see python tools/sweep.py --help", file=sys.stderr)
        return 2
    from refpo_warp.sweeps.ray_backend import RayOptions
    from refpo_warp.sweeps.run import run_sweep
    from refpo_warp.sweeps.spec import load_sweep
    from refpo_warp.utils.errors import ConfigError

    ray_flags = (args.ray_address, args.gpus_per_run, args.cpus_per_run)
    ray = None
    if any(v is not None for v in ray_flags):  # run_sweep refuses them without --backend ray
        ray = RayOptions(args.ray_address, args.gpus_per_run, 1.0 if args.cpus_per_run is None else args.cpus_per_run)
    signal.signal(signal.SIGTERM, signal.default_int_handler)  # stop the runs cleanly on SIGTERM too
    try:
        summary = run_sweep(load_sweep(args.sweep, rest), jobs=args.jobs, retries=args.retries,
                            launcher=args.launcher, dry_run=args.dry_run, backend=args.backend, ray=ray)  # fmt: skip
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    if summary.interrupted:
        return 130
    return 0 if summary.ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
