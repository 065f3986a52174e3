"""Shared test set-up: CPU by default, small thread counts, a `gpu` marker that skips without CUDA."""

import pytest
import torch

torch.set_num_threads(1)  # tiny ops: intra-op threads only add overhead (and CI has 2 cores)


def pytest_collection_modifyitems(config, items):
    if torch.cuda.is_available():
        return
    skip = pytest.mark.skip(reason="needs a CUDA device")
    for item in items:
        if "gpu" in item.keywords:
            item.add_marker(skip)


@pytest.fixture
def tmp_run_dir(tmp_path):
    return tmp_path / "run"
