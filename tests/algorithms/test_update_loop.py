"""The shared update loop (refpo_warp/algorithms/on_policy.py) reads the device once per update, however many
minibatches it has, and a non-finite loss in any minibatch still stops the update with NonFiniteLossError, leaving
the parameters, the optimizer state and the learning rate as they were before it."""

import copy
import math
import sys
from contextlib import contextmanager

import pytest
import torch
from test_refpo import fill_storage, make_refpo  # tests/algorithms is on sys.path under pytest

from refpo_warp.utils.errors import NonFiniteLossError
from refpo_warp.utils.paths import PACKAGE_DIR

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

# A tensor's value reaches Python only through these; on CUDA each one waits for the device.
READS = ("__bool__", "__float__", "__int__", "item", "tolist", "cpu", "numpy")


@contextmanager
def counting_host_reads():
    """Count the reads the project's own code makes (torch's internals, e.g. Adam's step count kept on the host, are
    not the update loop's)."""
    counts = {"reads": 0}
    originals = {name: getattr(torch.Tensor, name) for name in READS}

    def counted(name):
        def read(self, *args, **kwargs):
            if sys._getframe(1).f_code.co_filename.startswith(str(PACKAGE_DIR)):
                counts["reads"] += 1
            return originals[name](self, *args, **kwargs)

        return read

    for name in READS:
        setattr(torch.Tensor, name, counted(name))
    try:
        yield counts
    finally:
        for name, method in originals.items():
            setattr(torch.Tensor, name, method)


@pytest.mark.parametrize("minibatches,epochs", [(1, 1), (3, 4)])
def test_an_update_reads_the_device_once_whatever_its_minibatch_count(minibatches, epochs):
    # one_step_states=0: ReFPO's once-an-update one-step diagnostic (two numbers, before the loop) is off
    alg, _ = make_refpo(num_mini_batches=minibatches, num_learning_epochs=epochs, one_step_states=0)
    fill_storage(alg, advantages=None)
    with counting_host_reads() as counts:
        stats = alg.update()
    assert counts["reads"] == 1  # before: one per minibatch (1 and 12 here), plus 3 for the statistics after them
    assert set(stats) >= {"surrogate", "reflow", "Flow/ratio_max"}


@pytest.mark.parametrize("reflow_coef,method", [(0.04, "ReFPO"), (0.0, "FPO")])  # FPO: ReFPO with no Reflow term
def test_a_non_finite_loss_in_a_later_minibatch_stops_the_update_and_undoes_it(reflow_coef, method):
    alg, _ = make_refpo(num_mini_batches=3, num_learning_epochs=2, reflow_coef=reflow_coef)
    fill_storage(alg, advantages=None)
    alg.update()  # the optimizer has state (Adam's moments) to keep
    fill_storage(alg, advantages=None)
    before = (
        copy.deepcopy(alg.actor.state_dict()),
        copy.deepcopy(alg.critic.state_dict()),
        copy.deepcopy(alg.optimizer.state_dict()),
        alg.learning_rate,
    )
    policy_loss, calls = alg.policy_loss, [0]

    def nan_in_the_fourth(batch):
        loss, stats = policy_loss(batch)
        calls[0] += 1
        if calls[0] == 4:  # the first minibatch of the second pass: three steps were taken before it
            stats["surrogate"] = stats["surrogate"] * float("nan")
            loss = loss + stats["surrogate"]
        return loss, stats

    alg.policy_loss = nan_in_the_fourth
    with pytest.raises(
        NonFiniteLossError,
        match=rf"Non-finite {method} loss \(surrogate=nan, .*the update was stopped "
        r"before applying it",
    ):
        alg.update()
    assert calls[0] == 6  # every minibatch ran: the loss is read once, after them
    after = (alg.actor.state_dict(), alg.critic.state_dict(), alg.optimizer.state_dict(), alg.learning_rate)
    for old, new in zip(before[:2], after[:2]):
        assert all(torch.equal(old[k], new[k]) for k in old)
    old_state, new_state = before[2]["state"], after[2]["state"]
    assert old_state.keys() == new_state.keys() and all(
        torch.equal(old_state[i][k], new_state[i][k]) for i in old_state for k in old_state[i]
    )
    assert after[3] == before[3] and alg.num_updates == 1


def test_an_algorithm_on_the_cpu_computes_float32_denormals_as_zero():
    if not torch.set_flush_denormal(False):
        pytest.skip("this CPU has no flush-to-zero mode")
    x = torch.tensor([-88.0], requires_grad=True)
    torch.nn.functional.silu(x).backward()
    # SiLU'(x) = s (1 + x (1 - s)), s = sigmoid(-88) = 6.1e-39, a float32 denormal: -87 e^-88 = -5.3e-37
    assert x.grad.item() == pytest.approx(-87 * math.exp(-88), rel=1e-3, abs=0)
    make_refpo()  # on the CPU
    x.grad = None
    torch.nn.functional.silu(x).backward()
    assert x.grad.item() == 0.0  # s read as 0
