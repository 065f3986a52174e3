"""Behaviour cloning of the actor an algorithm uses, on (observation, action) pairs of a demonstration dataset.

- A flow actor (``FlowActor``) by the conditional flow-matching loss its update already uses: ``actor.cfm_loss`` on K
  (tau, eps) pairs per action, tau drawn as the algorithm draws it (``tau_sampling``), in the actor's own
  ``output_mode`` and ``loss_scale``. The update's Reflow term is this same loss on the rollout's pairs.
- A Gaussian actor (rsl_rl's ``MLPModel`` with a ``GaussianDistribution``) by maximum likelihood: the negative log
  density of the action under the actor's distribution, summed over action dimensions (its mean and its std learn).

The observation normaliser is set from the data (``set_normalizer``) before training and stays fixed. A held-out
share of the episodes gives the validation loss (fixed (tau, eps) draws, so epochs compare); training stops when it
has not improved for ``patience`` epochs, and the actor keeps its best epoch's weights.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch
from tensordict import TensorDict

from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.rng import own_random_streams, stream_seed

VALIDATION_STREAM = 4  # the validation loss's (tau, eps) draws: a random stream of its own (refpo_warp.utils.rng)


def is_flow_actor(actor) -> bool:
    return hasattr(actor, "cfm_loss")


def is_gaussian_actor(actor) -> bool:
    return type(getattr(actor, "distribution", None)).__name__.endswith("GaussianDistribution")


def check_clonable(actor, algo: str) -> None:
    if not (is_flow_actor(actor) or is_gaussian_actor(actor)):
        raise ConfigError(
            f"algo={algo}: its actor {type(actor).__name__} cannot be cloned; refpo pretrain clones a "
            f"flow actor (FlowActor: refpo, fpo, refpo_onestep, fpo_pp, ...) or a Gaussian actor "
            f"(ppo)"
        )


def as_obs(flat: torch.Tensor, groups: dict[str, int]) -> TensorDict:
    """The actor's TensorDict from flat observation rows (its groups side by side, ``{group: dim}`` in order)."""
    parts, start = {}, 0
    for group, dim in groups.items():
        parts[group] = flat[:, start : start + dim]
        start += dim
    return TensorDict(parts, batch_size=[flat.shape[0]])


def flow_bc_loss(actor, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor) -> torch.Tensor:
    """Mean CFM loss of ``actions`` on the pairs tau (B, K), eps (B, K, A): the flow actor's own loss."""
    return actor.cfm_loss(obs, actions, tau, eps).mean()


def gaussian_nll(actor, obs: TensorDict, actions: torch.Tensor) -> torch.Tensor:
    """Mean negative log-likelihood of ``actions`` under the Gaussian actor's distribution at ``obs``."""
    actor(obs, stochastic_output=True)  # sets the distribution's mean and std for these observations
    return -actor.get_output_log_prob(actions).mean()


def set_normalizer(model, obs: np.ndarray) -> bool:
    """Set ``model``'s empirical observation normaliser (rsl_rl's ``EmpiricalNormalization``, clamped or not) to the
    mean and variance of ``obs``; False when the model normalises nothing."""
    from rsl_rl.modules import EmpiricalNormalization

    found = [m for m in model.modules() if isinstance(m, EmpiricalNormalization)]
    if not found:
        return False
    data = torch.as_tensor(obs, dtype=torch.float32)
    for norm in found:
        mean, var = data.mean(0, keepdim=True), data.var(0, unbiased=False, keepdim=True)
        norm._mean.copy_(mean.to(norm._mean.device))
        norm._var.copy_(var.to(norm._var.device))
        norm._std.copy_(var.sqrt().to(norm._std.device))
        norm.count.fill_(len(data))
    return True


@dataclass
class CloneOptions:
    epochs: int
    batch_size: int
    learning_rate: float
    patience: int
    num_pairs: int  # K (tau, eps) pairs per action for a flow actor
    seed: int


def make_loss(actor, tau_sampler: Callable, num_pairs: int):
    """loss(obs, actions) for this actor: the flow's CFM loss (fresh pairs every call) or the Gaussian's NLL."""
    if is_flow_actor(actor):

        def loss(obs, actions):
            b, a = actions.shape
            tau = tau_sampler((b, num_pairs)).to(actions.device)
            eps = torch.randn(b, num_pairs, a, device=actions.device)
            return flow_bc_loss(actor, obs, actions, tau, eps)

        return loss
    return lambda obs, actions: gaussian_nll(actor, obs, actions)


def clone(
    actor,
    loss,
    groups: dict[str, int],
    train: tuple[np.ndarray, np.ndarray],
    validation: tuple[np.ndarray, np.ndarray],
    options: CloneOptions,
    report: Callable[[dict], None],
) -> dict:
    """Train ``actor`` on ``train`` by ``loss`` with Adam, early-stopped on ``validation``; ``report`` receives one row
    per epoch. Returns the best epoch, its validation loss and the epochs run; the actor keeps the best weights."""
    device = next(actor.parameters()).device
    obs_t, act_t = (torch.as_tensor(x, device=device) for x in train)
    obs_v, act_v = (torch.as_tensor(x, device=device) for x in validation)
    params = [p for p in actor.parameters() if p.requires_grad]
    optimizer = torch.optim.Adam(params, lr=options.learning_rate)
    generator = torch.Generator().manual_seed(options.seed)
    best, best_epoch, best_state, waited = math.inf, -1, None, 0
    started = time.monotonic()
    n = len(obs_t)
    epoch = -1
    for epoch in range(options.epochs):
        actor.train()
        order = torch.randperm(n, generator=generator).to(device)
        total, batches = 0.0, 0
        for start in range(0, n, options.batch_size):
            idx = order[start : start + options.batch_size]
            value = loss(as_obs(obs_t[idx], groups), act_t[idx])
            if not bool(torch.isfinite(value.detach())):
                from refpo_warp.utils.errors import NonFiniteLossError

                raise NonFiniteLossError(f"behaviour-cloning loss {float(value)} at epoch {epoch}")
            optimizer.zero_grad()
            value.backward()
            optimizer.step()
            total, batches = total + float(value.detach()), batches + 1
        val = validation_loss(actor, loss, groups, obs_v, act_v, options)
        improved = val < best
        if improved:
            best, best_epoch, best_state, waited = val, epoch, copy.deepcopy(actor.state_dict()), 0
        else:
            waited += 1
        report(
            {
                "epoch": epoch,
                "train_loss": total / max(batches, 1),
                "val_loss": val,
                "best_val_loss": best,
                "time_s": time.monotonic() - started,
            }
        )
        if waited >= options.patience:
            break
    if best_state is not None:
        actor.load_state_dict(best_state)
    actor.eval()
    return {
        "best_epoch": best_epoch,
        "best_val_loss": best,
        "epochs_run": epoch + 1,
        "stopped_early": epoch + 1 < options.epochs,
        "time_s": time.monotonic() - started,
    }


@torch.no_grad()
def validation_loss(actor, loss, groups, obs_v, act_v, options: CloneOptions, batch: int = 8192) -> float:
    """Mean loss over the held-out transitions, with the same (tau, eps) draws at every epoch."""
    actor.eval()
    with own_random_streams(stream_seed(options.seed, VALIDATION_STREAM), obs_v.device):
        total = sum(
            float(loss(as_obs(obs_v[s : s + batch], groups), act_v[s : s + batch])) * len(obs_v[s : s + batch])
            for s in range(0, len(obs_v), batch)
        )
    return total / len(obs_v)


def split_episodes(num_episodes: int, fraction: float, seed: int) -> tuple[list[int], list[int]]:
    """(training, validation) episode indices: ``fraction`` of the episodes held out, at least one each side."""
    if num_episodes < 2:
        raise ConfigError(f"the dataset holds {num_episodes} episode; a validation split needs at least 2")
    order = np.random.default_rng(seed).permutation(num_episodes)
    held = min(num_episodes - 1, max(1, round(fraction * num_episodes)))
    return sorted(order[held:].tolist()), sorted(order[:held].tolist())
