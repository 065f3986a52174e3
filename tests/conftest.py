"""Shared test set-up: CPU by default, one torch thread, a ``gpu`` marker that skips without CUDA, and the order of a
run: the slow tests first, longest first, by the minutes their ``slow`` marker declares.

Markers (pyproject.toml): ``slow(minutes=M)`` a bounded learning check or a long subprocess case, with its measured
wall time in CI; ``on_demand`` a learning check CI leaves out (run with ``--all-checks``); ``gpu`` needs CUDA;
``rsl_rl`` touches rsl_rl's API (CI runs these again on the lowest supported rsl-rl-lib).
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # headless rendering; MuJoCo reads it once, when first imported

import pytest
import torch

torch.set_num_threads(1)  # tiny ops: intra-op threads only add overhead (and CI has 2 cores)


def cuda_available() -> bool:
    """A CUDA device for torch and for Warp (the envs run their kernels through Warp)."""
    if not torch.cuda.is_available():
        return False
    from refpo_warp.utils.warp_setup import init_warp

    return init_warp().get_cuda_device_count() > 0


def pytest_addoption(parser):
    parser.addoption(
        "--null-control",
        action="store_true",
        help="run each learning check with learning switched off (tests/learning/checks.py NULL_CONTROL) "
        "and assert that its bound is NOT met",
    )
    parser.addoption(
        "--all-checks",
        action="store_true",
        help="also run the learning checks that CI leaves to be run on demand (in_ci=False in "
        "tests/learning/checks.py)",
    )


@pytest.fixture
def null_control(request) -> bool:
    return bool(request.config.getoption("--null-control"))


def pytest_configure(config):
    # xdist hands each worker 2 tests at first and then 1 at a time (instead of long runs of consecutive tests), so
    # the order below decides which long tests each worker starts with.
    if config.pluginmanager.hasplugin("xdist") and getattr(config.option, "maxschedchunk", 0) is None:
        config.option.maxschedchunk = 1


def minutes(item) -> float:
    """The wall time a slow test declares (``@pytest.mark.slow(minutes=M)``; 0 for a quick test)."""
    marker = item.get_closest_marker("slow")
    return float(marker.kwargs.get("minutes", 0.5)) if marker is not None else 0.0


def slow_first(items: list) -> list:
    """Slow tests longest first, then the quick ones. Two workers start with two tests each (items 0-1 and 2-3):
    the longest and the third longest go to the first worker, the second and the fourth to the second."""
    slow = sorted((i for i in items if minutes(i) > 0), key=minutes, reverse=True)
    quick = [i for i in items if minutes(i) == 0]
    if len(slow) >= 3:
        slow[1], slow[2] = slow[2], slow[1]
    return slow + quick


def pytest_collection_modifyitems(config, items):
    if not config.getoption("--all-checks"):
        skip = pytest.mark.skip(reason="a learning check CI leaves to be run on demand: --all-checks")
        for item in items:
            if "on_demand" in item.keywords:
                item.add_marker(skip)
                item.own_markers[:] = [m for m in item.own_markers if m.name != "slow"]  # ordered as a quick test
    items[:] = slow_first(items)
    if any("gpu" in item.keywords for item in items) and not cuda_available():
        skip = pytest.mark.skip(reason="needs a CUDA device (torch and Warp)")
        for item in items:
            if "gpu" in item.keywords:
                item.add_marker(skip)


@pytest.fixture
def tmp_run_dir(tmp_path):
    return tmp_path / "run"


# A 3-iteration GridWorld ReFPO run of a few seconds with checkpoints at iterations 0 and 2 (the last): for the tests of
# what training and evaluation print and write.
QUICK_RUN = [
    "task=gridworld",
    "algo=refpo",
    "num_envs=8",
    "runner.num_steps_per_env=16",
    "max_iterations=3",
    "algorithm.num_mc_samples=4",
    "algorithm.num_learning_epochs=1",
    "runner.save_interval=2",
    "eval.num_envs=8",
    "eval.flow_steps=[1, 2]",
    "eval.interval=0",
    "device=cpu",
]


@pytest.fixture
def quick_run() -> list[str]:
    return list(QUICK_RUN)
