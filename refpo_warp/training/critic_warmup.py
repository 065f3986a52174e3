"""The critic's warm-up of a fine-tuning run (``init_from``): for the first ``critic_warmup_iterations`` iterations
the actor does not move, so the critic learns the cloned policy's values from its own rollouts before the policy
gradient uses them (DPPO and ReinFlow warm their critics up the same way).

While frozen, the actor's parameters take no gradient (the optimizer skips them: no step, no moment updates) and its
observation normaliser keeps the data's statistics; the rollouts, the critic's loss and its normaliser run as in any
iteration, and the iterations count in the run's budget, progress log and checkpoints.
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
    actor.update_normalization = _keep_statistics  # an instance attribute: the class's method again after `del`
    try:
        yield
    finally:
        del actor.update_normalization
        for p in params:
            p.requires_grad_(True)


def _keep_statistics(obs) -> None:
    """Stands in for the actor's ``update_normalization`` during the warm-up."""
