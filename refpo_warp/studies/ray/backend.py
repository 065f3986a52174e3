"""The Ray backend of a sweep (``refpo sweep <sweep> --backend ray``): every run is one Ray task that runs the same
``python -m refpo_warp train`` process as the local backend, on a node and GPU Ray picks (``node.py``); every
node needs the package installed (not a checkout); the queue, retries,
records and report stay the executor's (``studies/grid/executor.py``). Ray Tune is not used: it would duplicate them.

- Where: ``address`` (``auto``, ``HOST:PORT``), else ``RAY_ADDRESS``, else a new local Ray on this machine (which
  sends no usage statistics unless ``RAY_USAGE_STATS_ENABLED`` says otherwise).
- What a run asks for: ``gpus_per_run`` GPUs (default 1 on a CUDA sweep, 0 on a CPU one; a fraction packs several
  runs on a GPU) and ``cpus_per_run`` CPUs (default 1; a CPU run trains with that many torch threads). ``jobs``
  defaults to the runs the alive nodes fit at once.
- Before the first run every node that can take one must see the sweep dir (it reads a token this machine wrote
  there) and the working directory, at the paths this machine sees: a cluster needs a shared filesystem for them.
- A lost worker or node is Ray's to retry (``SYSTEM_RETRIES`` times), on any node, without counting as one of the
  run's own ``--retries``; ``status.json`` counts those re-runs (``ray_reruns``) and names the node (``node``,
  ``ray_node_id``).
- Ctrl-C (or SIGTERM) cancels every task: a queued one never starts, a running one stops its training process
  (SIGINT, then SIGKILL after ``STOP_GRACE_S``); tasks still running then are force-cancelled, and a training
  process dies with its worker.

Ray is an optional extra, imported here only when a Ray launcher is made.
"""

from __future__ import annotations

import math
import os
import secrets
import shlex
import signal
import socket
import threading
import time
from dataclasses import dataclass

from refpo_warp.studies.grid.executor import Job, Launcher, Outcome
from refpo_warp.studies.grid.launch import STOP_GRACE_S
from refpo_warp.studies.grid.spec import Run, Sweep, device_type
from refpo_warp.studies.ray.node import TrainTask, see_paths, train_run
from refpo_warp.utils.atomic_files import write_text
from refpo_warp.utils.errors import ConfigError

INSTALL = 'pip install "refpo-warp[ray]" (from a checkout: pip install -e ".[ray]")'
SYSTEM_RETRIES = 3  # Ray's re-runs of a task whose worker or node was lost (Ray's own default, stated)
NODE_CHECK_TIMEOUT_S = 120.0  # a node's first task may have to start a worker
NODE_CHECK_FILE = ".ray_node_check"
CONNECT_TIMEOUT_S = 10.0
NODE_WATCH_S = 2.0  # how often the sweep looks for nodes lost or joined, to say so when it happens


def shared_paths() -> list[str]:
    """What every node must see at the head's paths besides the sweep dir: the working directory (relative run dirs
    and config folders are read from there)."""
    return [os.getcwd()]


@dataclass(frozen=True)
class RayOptions:
    address: str | None = None  # None: RAY_ADDRESS, else a new local Ray
    gpus_per_run: float | None = None  # None: 1 on a CUDA sweep, 0 on a CPU sweep
    cpus_per_run: float = 1.0


def _check_amount(value: float, flag: str) -> None:
    # Ray schedules fractions of one unit and whole numbers of units, nothing in between (1.5 GPUs is an error there)
    if not math.isfinite(value) or value < 0 or (value > 1 and value != int(value)):
        raise ConfigError(f"{flag} must be a fraction of one (e.g. 0.5) or a whole number, got {value:g}")


def run_resources(sweep: Sweep, options: RayOptions) -> tuple[float, float]:
    """(GPUs, CPUs) per run, checked against the sweep's device: a CUDA sweep needs a GPU, a CPU sweep takes none."""
    cuda = device_type(sweep.device) == "cuda"
    gpus = options.gpus_per_run if options.gpus_per_run is not None else (1.0 if cuda else 0.0)
    _check_amount(gpus, "--gpus-per-run")
    _check_amount(options.cpus_per_run, "--cpus-per-run")
    if options.cpus_per_run == 0:
        raise ConfigError("--cpus-per-run must be above 0: a run's process needs a CPU")
    if cuda and gpus == 0:
        raise ConfigError(
            f"Sweep '{sweep.name}' trains on CUDA (device: {sweep.device}): --gpus-per-run must be above "
            "0 (1, or e.g. 0.5 for two runs per GPU)"
        )
    if not cuda and gpus > 0:
        raise ConfigError(
            f"Sweep '{sweep.name}' trains on the CPU (device: {sweep.device}): --gpus-per-run must be 0 "
            "(or train on CUDA: device=cuda)"
        )
    return gpus, options.cpus_per_run


def import_ray():
    try:
        import ray
    except ImportError as err:
        raise ConfigError(f"--backend ray needs Ray, an optional extra of this project: {INSTALL}") from err
    return ray


def check_reachable(address: str) -> None:
    """A ``HOST:PORT`` address must accept a connection: ray.init would wait forever for a head that is not there."""
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit() or "://" in address:
        return  # auto, or ray://: Ray's own message
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as err:
        hint = "`ray start --head` prints the head's address (port 6379 by default); auto finds one here"
        raise ConfigError(f"No Ray cluster at '{address}' ({err}): {hint}") from err


def _first_line(err: BaseException) -> str:
    return (str(err).strip().splitlines() or [""])[0][:200]


class RayLauncher(Launcher):
    names_nodes = True

    def __init__(
        self, sweep: Sweep, options: RayOptions, jobs: int | None = None, launcher: str = "", echo=print
    ) -> None:
        self.gpus, self.cpus = run_resources(sweep, options)
        self.ray = ray = import_ray()
        self.sweep, self.prefix, self.echo = sweep, tuple(shlex.split(launcher)), echo
        self.interrupted, self._sigint = False, None
        self.cuda = self.gpus > 0
        self.owned = not ray.is_initialized()  # an already connected driver (a test, a notebook) stays connected
        if self.owned:
            self._connect(options.address or os.environ.get("RAY_ADDRESS"))
        try:
            self.nodes = {n["NodeID"]: n for n in ray.nodes() if n.get("Alive")}
            self.room = {node: self._fits(n.get("Resources", {})) for node, n in self.nodes.items()}
            total = sum(self.room.values())
            if not total:
                have = "; ".join(
                    f"{self._name(node)}: {n['Resources'].get('CPU', 0):g} CPU, {n['Resources'].get('GPU', 0):g} GPU"
                    for node, n in self.nodes.items()
                )
                raise ConfigError(
                    f"No node of the Ray cluster has {self.gpus:g} GPU(s) and {self.cpus:g} CPU(s) for a "
                    f"run (--gpus-per-run, --cpus-per-run); its nodes: {have}"
                )
        except BaseException:
            self.close()
            raise
        self.jobs = jobs or total
        self.watched = time.monotonic()
        self.where = (
            f"on Ray ({len(self.nodes)} node(s), room for {total} run(s) at {self.gpus:g} GPU and "
            f"{self.cpus:g} CPU each)"
        )
        self.train = ray.remote(train_run)
        if threading.current_thread() is threading.main_thread():
            # Ctrl-C is taken in wait(), between Ray calls: a KeyboardInterrupt raised inside one of Ray's own calls
            # could leave the driver stuck there instead of stopping the runs.
            self._sigint = signal.signal(signal.SIGINT, self._on_sigint)

    def _on_sigint(self, signum, frame) -> None:
        self.interrupted = True

    # ------------------------------------------------------------------------------------------------ the cluster
    def _connect(self, address: str | None) -> None:
        ray = self.ray
        if address:
            check_reachable(address)
        sigterm = signal.getsignal(signal.SIGTERM)  # ray.init replaces it with an exit: keep ours (stop the runs)
        try:
            if address:
                ray.init(address=address)
            else:
                os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
                ray.init(address="local", include_dashboard=False)
        except ConnectionError as err:
            raise ConfigError(
                f"No Ray cluster at '{address}' ({_first_line(err)}): start one with `ray start --head`"
                ", or leave out --ray-address and RAY_ADDRESS for a local Ray"
            ) from err
        finally:
            if threading.current_thread() is threading.main_thread() and sigterm is not None:
                signal.signal(signal.SIGTERM, sigterm)
        self.echo(f"[sweep] Ray {ray.__version__}: " + ("connected to " + address if address else "started locally"))

    def _fits(self, resources: dict) -> int:
        counts = [math.floor(resources.get("CPU", 0) / self.cpus + 1e-9)]
        if self.gpus:
            counts.append(math.floor(resources.get("GPU", 0) / self.gpus + 1e-9))
        return max(0, min(counts))

    def _name(self, node_id: str) -> str:
        node = self.nodes.get(node_id, {})
        return f"{node.get('NodeManagerHostname', '?')} ({node.get('NodeManagerAddress', '?')}, node {node_id[:8]})"

    def prepare(self, sweep: Sweep) -> None:
        """Every node that can take a run sees the sweep dir and the working directory and imports the package."""
        ray = self.ray
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

        out = sweep.out_dir.resolve()
        token_file, token = out / NODE_CHECK_FILE, secrets.token_hex(16)
        write_text(token_file, token)
        paths = shared_paths()
        check = ray.remote(see_paths)
        refs = {}
        for node in (node for node, room in self.room.items() if room):  # a zero-CPU task runs beside busy runs
            where = NodeAffinitySchedulingStrategy(node, soft=False)
            refs[node] = check.options(num_cpus=0, max_retries=0, scheduling_strategy=where).remote(
                paths, str(token_file), token
            )
        problems = []
        try:
            ready, _ = ray.wait(list(refs.values()), num_returns=len(refs), timeout=NODE_CHECK_TIMEOUT_S)
            for node, ref in refs.items():
                if ref not in ready:
                    problems.append(f"node {self._name(node)} did not answer within {NODE_CHECK_TIMEOUT_S:g} s")
                    continue
                try:
                    seen = ray.get(ref)
                except ray.exceptions.RayError as err:
                    problems.append(
                        f"node {self._name(node)} cannot run the sweep's tasks ({type(err).__name__}: "
                        f"{_first_line(err)}; is the project installed in its Python?)"
                    )
                    continue
                missing = seen["missing"] + ([] if seen["token"] else [f"the sweep dir {out}"])
                if missing:
                    problems.append(f"node {self._name(node)} does not see {', '.join(missing)}")
        finally:
            token_file.unlink(missing_ok=True)
        if problems:
            raise ConfigError(
                "Ray: " + "; ".join(problems) + ". A Ray sweep needs the package installed on every "
                "node, and the sweep dir and the working directory on a filesystem that every node "
                "shares, at the same paths (docs/results/README.md, 'On a cluster')"
            )
        self.echo(
            f"[sweep] Ray: {len(refs)} node(s) see the sweep dir and the working directory: "
            + ", ".join(self._name(node) for node in refs)
        )

    # ------------------------------------------------------------------------------------------------ the runs
    def start(self, run: Run, attempt: int, slot: int, origin: str):
        cwd = os.getcwd()
        task = TrainTask(
            origin,
            run.key,
            attempt,
            tuple(run.args),
            os.path.join(cwd, run.run_dir),
            self.cuda,
            max(1, int(self.cpus)),
            self.prefix,
            cwd,
            run.resume,
        )
        return self.train.options(
            num_gpus=self.gpus,
            num_cpus=self.cpus,
            max_retries=SYSTEM_RETRIES,
            retry_exceptions=False,
            name=f"train {run.key}",
        ).remote(task)

    def _watch_nodes(self) -> None:
        """Say when a node is lost (Ray re-runs its runs elsewhere) or joins (its runs check their paths there)."""
        if time.monotonic() - self.watched < NODE_WATCH_S:
            return
        self.watched = time.monotonic()
        alive = {n["NodeID"]: n for n in self.ray.nodes() if n.get("Alive")}
        lost, joined = [n for n in self.nodes if n not in alive], [n for n in alive if n not in self.nodes]
        for node in lost:
            self.echo(
                f"[sweep] Ray: lost node {self._name(node)}; Ray re-runs its runs on the other nodes (up to "
                f"{SYSTEM_RETRIES} times each)"
            )
        self.nodes = alive
        for node in joined:
            self.echo(f"[sweep] Ray: node {self._name(node)} joined (still {self.jobs} run(s) at a time: --jobs)")

    def wait(self, jobs: list[Job], timeout: float) -> list[tuple[Job, Outcome]]:
        ray = self.ray
        if self.interrupted:
            raise KeyboardInterrupt
        self._watch_nodes()
        by_ref = {job.handle: job for job in jobs}
        ready, _ = ray.wait(list(by_ref), num_returns=len(by_ref), timeout=timeout)
        if self.interrupted:
            raise KeyboardInterrupt
        ended = []
        for ref in ready:
            job = by_ref[ref]
            try:
                done = ray.get(ref)
            except ray.exceptions.RayTaskError as err:  # the task itself raised (e.g. the project fails to import)
                why = f"its Ray task failed: {_first_line(err)}"
                ended.append((job, Outcome(None, time.monotonic() - job.started, "?", why)))
                continue
            except ray.exceptions.RayError as err:  # lost more often than Ray retries (a worker, a node, its object)
                why = f"lost its Ray worker or node ({type(err).__name__}; Ray re-ran it {SYSTEM_RETRIES} times)"
                ended.append((job, Outcome(None, time.monotonic() - job.started, "?", why)))
                continue
            status = {"ray_node_id": done["node_id"], "ray_reruns": done["reruns"]}
            ended.append((job, Outcome(done["exit_code"], done["seconds"], done["host"], done["error"], status)))
            if done["reruns"]:
                self.echo(
                    f"[sweep] {job.run.key} was re-run by Ray {done['reruns']} time(s) after a lost worker or "
                    "node (not one of its --retries)"
                )
        return ended

    def stop(self, jobs: list[Job]) -> None:
        ray = self.ray
        refs = [job.handle for job in jobs]
        if not refs:
            return
        left, deadline = refs, time.monotonic() + STOP_GRACE_S + 10
        while left and time.monotonic() < deadline:
            for ref in left:  # queued: never starts; running: KeyboardInterrupt in the task (node.py)
                ray.cancel(ref, force=False)  # again every few seconds: a busy worker may miss the first
            _, left = ray.wait(left, num_returns=len(left), timeout=3)
        for ref in left:  # a task that did not end: kill its worker, and the training process with it
            ray.cancel(ref, force=True)
        if left:
            ray.wait(left, num_returns=len(left), timeout=10)

    def close(self) -> None:
        if self._sigint is not None:
            signal.signal(signal.SIGINT, self._sigint)
            self._sigint = None
        if self.owned and self.ray.is_initialized():
            self.ray.shutdown()
