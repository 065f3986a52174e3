"""What a fine-tuning run (``init_from``) holds fixed.

The critic's warm-up: for the first ``critic_warmup_iterations`` iterations the actor does not move, so the critic
learns the cloned policy's values from its own rollouts before the policy gradient uses them (DPPO and ReinFlow warm
their critics up the same way). While frozen, the actor's parameters take no gradient (the optimizer skips them: no
step, no moment updates) and its observation normaliser keeps its statistics; the rollouts, the critic's loss and
its normaliser run as in any iteration, and the iterations count in the run's budget, progress log and checkpoints.

The data's normalisers (``clone_normalizer=keep``, the default): the actor's and the critic's observation normalisers
keep the statistics the clone took from the demonstrations for the whole run, as DPPO and ReinFlow normalise
observations by the pre-training data's fixed bounds while they fine-tune. Updated from the rollouts instead
(``update``), the inputs of a narrow cloned flow policy drift as its visited states change, and ReFPO's 10-step
policy collapsed after its clone on point_mass (docs/results/finetuning/README.md).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from refpo_warp.utils.rsl_rl_versions import uncompiled


@contextlib.contextmanager
def actor_frozen(alg) -> Iterator[None]:
    """The algorithm's actor without gradients or normaliser updates inside the block; as before after it."""
    actor = uncompiled(alg, "actor")
    params = [p for p in actor.parameters() if p.requires_grad]
    for p in params:
        p.requires_grad_(False)
        p.grad = None
    try:
        with statistics_kept(actor):
            yield
    finally:
        for p in params:
            p.requires_grad_(True)


@contextlib.contextmanager
def clone_statistics_kept(alg) -> Iterator[None]:
    """The actor's and the critic's observation normalisers unchanged inside the block."""
    with statistics_kept(uncompiled(alg, "actor")), statistics_kept(uncompiled(alg, "critic")):
        yield


@contextlib.contextmanager
def statistics_kept(model) -> Iterator[None]:
    """``model.update_normalization`` does nothing inside the block (an instance attribute over the class's method);
    what was there before is there again after it, so the blocks nest."""
    before = vars(model).get("update_normalization")
    model.update_normalization = _keep_statistics
    try:
        yield
    finally:
        if before is None:
            del model.update_normalization
        else:
            model.update_normalization = before


def _keep_statistics(obs) -> None:
    """Stands in for a model's ``update_normalization``."""
