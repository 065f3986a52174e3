"""Shared test set-up: CPU by default, small thread counts, a `gpu` marker that skips without CUDA."""

import pytest
import torch

torch.set_num_threads(1)  # tiny ops: intra-op threads only add overhead (and CI has 2 cores)


def cuda_available() -> bool:
    """A CUDA device for torch and for Warp (the envs run their kernels through Warp)."""
    if not torch.cuda.is_available():
        return False
    from refpo_warp.utils.device import init_warp

    return init_warp().get_cuda_device_count() > 0


# The longest tests (minutes each on a 2-core CPU, as CI's `--durations` measured them): under xdist they start first,
# one per worker, and everything else fills in around them. The first two compile different Warp kernels (the
# humanoid's and Newton's, GridWorld's): started together, two humanoid checks would both compile Newton's kernels
# (about a minute each on a cold cache); the second one starts once the first has filled the cache.
LONGEST = ("test_humanoid_episodes_get_longer[refpo]", "test_refpo_solves_gridworld_with_one_and_ten_flow_steps",
           "test_method_raises_its_cartpole_return[flow_grpo-10]", "test_method_raises_its_cartpole_return[reinflow-4]",
           "test_humanoid_episodes_get_longer[ppo]",
           "test_refpo_balances_the_cartpole_with_ten_and_one_flow_steps",
           "test_method_raises_its_cartpole_return[refpo_aw-10]", "test_ppo_balances_the_cartpole",
           "test_train_and_evaluate_humanoid_root")


def pytest_configure(config):
    # xdist hands each worker 2 tests at first and then 1 at a time (instead of long runs of consecutive tests), so
    # the order below decides which long test each worker starts with.
    if config.pluginmanager.hasplugin("xdist") and getattr(config.option, "maxschedchunk", 0) is None:
        config.option.maxschedchunk = 1


def slow_first(items: list) -> list:
    """Slow tests before quick ones; the LONGEST at even positions (0, 2, ...), each followed by another slow test,
    so that with 2 tests per worker at the start, worker k begins with the k-th longest."""
    longest = sorted((i for i in items if i.name in LONGEST), key=lambda i: LONGEST.index(i.name))
    slow = [i for i in items if "slow" in i.keywords and i not in longest]
    quick = [i for i in items if "slow" not in i.keywords and i not in longest]
    ordered = []
    for item in longest:
        ordered.append(item)
        if slow:
            ordered.append(slow.pop(0))
    return ordered + slow + quick


def pytest_collection_modifyitems(config, items):
    items[:] = slow_first(items)
    if any("gpu" in item.keywords for item in items) and not cuda_available():
        skip = pytest.mark.skip(reason="needs a CUDA device (torch and Warp)")
        for item in items:
            if "gpu" in item.keywords:
                item.add_marker(skip)


@pytest.fixture
def tmp_run_dir(tmp_path):
    return tmp_path / "run"
