"""Measure the learning checks over seeds and torch threads, with and without learning, and write their table.

    python tests/learning/measure.py run CHECK [CHECK ...] [--seeds 1-5] [--threads 1] [--null] [--jobs 2]
    python tests/learning/measure.py table      # docs/results/learning_checks.md's table from the records

``run`` trains each (check, seed) in a process of its own (``--jobs`` at a time) with the given number of torch
threads, and writes its record (``checks.run_check``: initial and final evaluation, the training curve, wall time,
CPU) to ``docs/results/learning_checks/records/<check>.jsonl``; a (check, seed, threads, null) already recorded is
skipped. Thread count changes the order of floating-point sums, so two threads stand in for another CPU.
``table`` reads the records back and writes the statistics, the bounds and their margins.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from refpo_warp.utils.machine import cpu_model

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from checks import CHECKS, run_check  # noqa: E402  (tests/learning/checks.py)

RESULTS = HERE.parents[1] / "docs" / "results" / "learning_checks"
RECORDS = RESULTS / "records"


def record_key(record: dict) -> tuple:
    return record["check"], record["seed"], record["threads"], record["null"]


def current(record: dict) -> bool:
    """A record of the check's profile as it is now (a changed profile makes the older records stale)."""
    check = CHECKS.get(record["check"])
    return check is not None and record["overrides"] == list(check.overrides)


def read_records(check: str | None = None) -> list[dict]:
    files = [RECORDS / f"{check}.jsonl"] if check else sorted(RECORDS.glob("*.jsonl"))
    out = []
    for path in files:
        if path.exists():
            out += [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return [r for r in out if current(r)]


def run_one(check: str, seed: int, threads: int, null: bool) -> None:
    """One run in this process; its record is appended to the check's records file as one line."""
    import torch

    torch.set_num_threads(threads)
    with tempfile.TemporaryDirectory(prefix=f"{check}_") as tmp:
        start = time.monotonic()
        record = run_check(CHECKS[check], seed, Path(tmp) / "run", null=null)
    record.update(threads=threads, wall_s=round(time.monotonic() - start, 1), cpu=cpu_model())
    RECORDS.mkdir(parents=True, exist_ok=True)
    with open(RECORDS / f"{check}.jsonl", "a", encoding="utf-8") as f:  # one write of a line: appends stay whole
        f.write(json.dumps(record) + "\n")


def seeds_of(text: str) -> list[int]:
    if "-" in text:
        lo, hi = text.split("-")
        return list(range(int(lo), int(hi) + 1))
    return [int(s) for s in text.split(",")]


def run_many(checks: list[str], seeds: list[int], threads: int, null: bool, jobs: int) -> None:
    done = {record_key(r) for r in read_records()}
    todo = [(c, s) for c in checks for s in seeds if (c, s, threads, null) not in done]
    print(f"{len(todo)} runs to make ({len(checks) * len(seeds) - len(todo)} already recorded)", flush=True)

    def launch(job):
        check, seed = job
        cmd = [sys.executable, __file__, "one", check, str(seed), str(threads)] + (["--null"] if null else [])
        log = Path(tempfile.gettempdir()) / f"measure_{check}_s{seed}_t{threads}{'_null' if null else ''}.log"
        with open(log, "w") as f:
            env = {**os.environ, "OMP_NUM_THREADS": str(threads)}
            rc = subprocess.call(cmd, stdout=f, stderr=subprocess.STDOUT, env=env)
        print(f"{check} seed {seed} threads {threads}{' null' if null else ''}: exit {rc} (log {log})", flush=True)

    with ThreadPoolExecutor(jobs) as pool:
        list(pool.map(launch, todo))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run")
    run.add_argument("checks", nargs="+", choices=sorted(CHECKS))
    run.add_argument("--seeds", default="1-5")
    run.add_argument("--threads", type=int, default=1)
    run.add_argument("--null", action="store_true")
    run.add_argument("--jobs", type=int, default=2)
    one = sub.add_parser("one")
    one.add_argument("check", choices=sorted(CHECKS))
    one.add_argument("seed", type=int)
    one.add_argument("threads", type=int)
    one.add_argument("--null", action="store_true")
    sub.add_parser("table")
    args = parser.parse_args()
    if args.command == "run":
        run_many(args.checks, seeds_of(args.seeds), args.threads, args.null, args.jobs)
    elif args.command == "one":
        run_one(args.check, args.seed, args.threads, args.null)
    else:
        from table import write_table  # tests/learning/table.py

        write_table(read_records(), RESULTS.parent / "learning_checks.md")


if __name__ == "__main__":
    main()
