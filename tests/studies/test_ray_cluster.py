"""The Ray backend on a cluster of several nodes (``ray.cluster_utils.Cluster``: a head and GPU worker nodes on this
machine, each its own raylet): a node removed while its run trains is lost to the sweep, Ray runs that run again on
a replacement node, and the sweep finishes it there without counting one of its own retries."""

import json
import sys
import threading
import time
from pathlib import Path

import pytest
import ray
import yaml
from ray.cluster_utils import Cluster

from refpo_warp.studies.grid.spec import load_sweep
from refpo_warp.studies.sweep import run_sweep

STAND_IN = f"{sys.executable} {Path(__file__).with_name('stand_in_train.py')}"


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


@pytest.mark.slow(minutes=0.4)
def test_a_run_on_a_lost_node_finishes_on_another(tmp_path, monkeypatch):
    monkeypatch.setenv("RAY_AUTH_MODE", "disabled")
    monkeypatch.setenv("RAY_USAGE_STATS_ENABLED", "0")
    monkeypatch.setenv("STAND_IN_SECONDS", "4")  # the nodes' workers inherit it: long enough to lose a node mid-run
    spec = tmp_path / "grid.yaml"
    spec.write_text(
        yaml.safe_dump(
            {"device": "cuda", "tasks": ["gridworld"], "seeds": [1], "methods": [{"label": "ppo", "algo": "ppo"}]}
        )
    )
    out = tmp_path / "out"
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "num_gpus": 0})  # the head trains nothing
    try:
        first = cluster.add_node(num_cpus=1, num_gpus=1)
        cluster.connect()
        lines: list[str] = []
        result = {}
        sweep = threading.Thread(
            target=lambda: result.update(
                summary=run_sweep(
                    load_sweep(str(spec), [f"out={out}"]), launcher=STAND_IN, backend="ray", echo=lines.append
                )
            )
        )
        sweep.start()
        log = out / "stand_in.jsonl"
        deadline = time.monotonic() + 90
        while not (log.exists() and log.read_text().strip()) and time.monotonic() < deadline and sweep.is_alive():
            time.sleep(0.2)
        started = json.loads(log.read_text().splitlines()[0])
        assert started["event"] == "start" and alive(started["pid"]), "\n".join(lines)
        cluster.remove_node(first)  # its raylet and workers are killed, as when a machine is lost
        replacement = cluster.add_node(num_cpus=1, num_gpus=1)
        sweep.join(timeout=120)
        assert not sweep.is_alive(), "\n".join(lines)
    finally:
        ray.shutdown()
        cluster.shutdown()
    text = "\n".join(lines)
    assert result["summary"].ok and result["summary"].finished == ["gridworld/ppo/seed1"], text
    checked = next(line for line in lines if "see the sweep dir and the working directory" in line)
    assert "Ray: 1 node(s)" in checked and f"node {first.node_id[:8]})" in checked  # the nodes with room: GPU nodes
    status = json.loads((out / "status.json").read_text())["gridworld/ppo/seed1"]
    assert (status["attempts"], status["exit_codes"], status["ray_reruns"]) == (1, [0], 1)
    assert status["ray_node_id"] == replacement.node_id != first.node_id
    runs = [json.loads(line) for line in (out / "stand_in.jsonl").read_text().splitlines()]
    assert [r["event"] for r in runs] == ["start", "start", "end"] and runs[1]["ppid"] != started["ppid"]
    assert not alive(started["pid"])  # the training process on the lost node died with it
    assert f"Ray: lost node {started['host']} (" in text and f"node {first.node_id[:8]}); Ray re-runs its runs" in text
    assert f"node {replacement.node_id[:8]}) joined" in text
    assert "gridworld/ppo/seed1 was re-run by Ray 1 time(s) after a lost worker or node" in text
