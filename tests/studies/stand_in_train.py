"""A stand-in for ``refpo train`` in the sweep backend tests, a few seconds instead of a training run.

The tests pass it as the sweep's ``--launcher``, so each run executes ``python stand_in_train.py <python> -m
refpo_warp train <run args> device=<device>``: the real command line, with this script in front. It appends what it saw
(pid, parent, start and end times, host, ``CUDA_VISIBLE_DEVICES``, ``OMP_NUM_THREADS``, the device argument) as one
JSON line to ``<sweep dir>/stand_in.jsonl``, sleeps ``STAND_IN_SECONDS`` (default 1), and then writes what a finished
run leaves: ``config.yaml`` (the config ``refpo train`` would resolve from these arguments) and ``eval.json``.

The run's method label picks a behaviour, for the first execution only (no ``train.attempt1.log`` beside it yet):
``crash`` exits 1 with an error line; ``lost`` kills its parent, the Ray worker (SIGKILL), as a lost node would;
``sleepy`` sleeps 600 s whatever the attempt (for Ctrl-C).
"""

import json
import os
import signal
import socket
import sys
import time
from pathlib import Path

started = time.time()
args = sys.argv[sys.argv.index("train") + 1 :]  # after <python> -m refpo_warp train
options = dict(a.split("=", 1) for a in args)
run_dir = Path(options["run_dir"])
label = run_dir.parent.name
first = not (run_dir / "train.attempt1.log").exists()


def record(event: str) -> None:
    line = {
        "event": event,
        "key": f"{run_dir.parents[1].name}/{label}/{run_dir.name}",
        "pid": os.getpid(),
        "ppid": os.getppid(),
        "start": started,
        "time": time.time(),
        "host": socket.gethostname(),
        "cuda_visible_devices": os.environ.get("CUDA_VISIBLE_DEVICES"),
        "omp_num_threads": os.environ.get("OMP_NUM_THREADS"),
        "device": options["device"],
    }
    with open(run_dir.parents[2] / "stand_in.jsonl", "a") as f:
        f.write(json.dumps(line) + "\n")


def finish() -> None:
    """Write what a finished ``refpo train`` run leaves (imports here: the timing before them is the run's)."""
    from refpo_warp.config.dotted import parse_overrides
    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.config.yaml_files import dump_config

    # As refpo train on a machine with that device (a CUDA run resolves its CUDA profile here, with no GPU).
    cfg = resolve_config(parse_overrides(args), device_type=options["device"].split(":")[0])
    dump_config(cfg, run_dir / "config.yaml")
    results = {"N=1": {"return_mean": float(cfg["seed"])}}
    (run_dir / "eval.json").write_text(json.dumps({"task": cfg["task"], "algo": cfg["algo"], "results": results}))


record("start")
if label == "lost" and first:
    os.kill(os.getppid(), signal.SIGKILL)  # the Ray worker; PR_SET_PDEATHSIG then kills this process too
    time.sleep(60)
    sys.exit("error: the stand-in outlived its killed worker")
if label == "crash" and first:
    print("error: stand-in crash on its first attempt", flush=True)
    sys.exit(1)
time.sleep(600 if label == "sleepy" else float(os.environ.get("STAND_IN_SECONDS", "1")))
finish()
record("end")
print("stand-in run finished", flush=True)
