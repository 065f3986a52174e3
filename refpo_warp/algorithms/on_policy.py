"""The update loop every refpo_warp algorithm shares, on top of rsl_rl's PPO (models, storage, GAE, multi-GPU, I/O).

A subclass says how it acts (``act``, storing what it needs in ``self.store``) and what its policy loss is
(``policy_loss(batch)``); this class runs the passes over the rollout: minibatches (rsl_rl's single permutation, or
a fresh one per pass as Brax does), per-minibatch advantage normalisation, the value loss, gradient reduction across
ranks, clipping, the optimizer step, the learning-rate schedule and the statistics, which are kept on the device and
read once per update.

Non-finite losses: every minibatch's loss is checked on the device and the flags are read with the statistics, once
per update (a check per minibatch would wait for the device 512 times an update at the CUDA DMC sizes). A non-finite
loss is therefore applied like any other, and undone: the parameters, the optimizer state and the learning rate are
copied (on the device) before the update and put back when any loss of the update was non-finite; then
``NonFiniteLossError`` names the first such minibatch's statistics. A failed update leaves the model as it was before
the update. (rsl_rl's adaptive schedule, ``schedule=adaptive``, still reads each minibatch's KL: its learning rate is
a number on the host.)

Options: each algorithm declares its own once, as ``option`` fields in its class body (default, rule, doc;
``refpo_warp/utils/options.py``: ``reflow_coef: float = option(...)``), and inherits its bases' (those below every
algorithm shares) and rsl_rl's PPO arguments (``refpo_warp/utils/rsl_rl_options.py``); a field may give one of those
another default. The constructor checks every argument against its rule (the error names ``<Class>.<option>``), assigns
every declared option to the attribute its field declares (typed, so ``self.reflow_coef`` is a ``float`` to an editor
and a type checker) and passes rsl_rl's arguments to rsl_rl's PPO; a subclass's constructor only adds what it derives
from them.

The EMA actor (``ema_decay``, ``ema_warmup``; FPO++): an exponential moving average of the actor's weights that starts
from the live weights after ``ema_warmup`` updates and is updated once per update from then on
(``refpo_warp.models.ema``). Until then evaluation and export (``get_policy``) use the live actor, afterwards the
average; rollouts always use the live actor. Checkpoints hold the live weights, and the average once it has started;
a resume trains on from the live weights.

Logged statistics: keys with a ``/`` (e.g. ``Flow/ratio_max``) are logged under that name, others as ``Loss/<key>``;
a key ending in ``_max`` is the maximum over the update's minibatches, every other key the mean. Every algorithm logs
each network's gradient norm before the clip (``grad_norm_actor``, ``grad_norm_critic``; ``clip_gradients``), as
FPO++ does (``algorithms/fpo.py:511-533``, which logs the joint norm), and one whose learning rate moves (the adaptive
schedule, ``lr_decay_rate``) the rate after the update (``learning_rate``).
"""

from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass

import torch
from rsl_rl.algorithms import PPO as RslPPO
from tensordict import TensorDict
from torch import nn

from refpo_warp.algorithms.transition_store import TransitionStore, minibatch_indices
from refpo_warp.models.ema import ActorEMA
from refpo_warp.utils.device import cpu_has_native_bfloat16, flush_denormals_on_cpu
from refpo_warp.utils.errors import NonFiniteLossError
from refpo_warp.utils.option_rules import Flag, Int, Real
from refpo_warp.utils.options import option, option_values
from refpo_warp.utils.rsl_rl_versions import (
    NORMALIZERS_UPDATE_PER_STEP,
    PPO_ARGUMENTS,
    split_newer_ppo_args,
    uncompiled,
)

ADAPTIVE_LR_RANGE = (1e-5, 1e-2)  # rsl_rl's adaptive schedule keeps the learning rate within these


@dataclass
class Minibatch:
    """One minibatch of the rollout: rsl_rl's fields plus the algorithm's own (``field(name)``)."""

    observations: TensorDict
    actions: torch.Tensor
    values: torch.Tensor  # (B, 1)
    returns: torch.Tensor  # (B, 1)
    advantages: torch.Tensor  # (B,)
    indices: torch.Tensor
    store: TransitionStore

    def field(self, name: str) -> torch.Tensor:
        return self.store.flat(name)[self.indices]


def value_regression_loss(
    values: torch.Tensor, old_values: torch.Tensor, returns: torch.Tensor, clip: float | None
) -> torch.Tensor:
    """Mean squared error to the returns; with ``clip``, PPO's pessimistic clipped form around the old values."""
    if clip is None:
        return (returns - values).pow(2).mean()
    clipped = old_values + (values - old_values).clamp(-clip, clip)
    return torch.max((values - returns).pow(2), (clipped - returns).pow(2)).mean()


def gradient_norm(parameters) -> torch.Tensor:
    """The 2-norm of the gradients of ``parameters`` taken together (those without a gradient left out): the norm
    ``nn.utils.clip_grad_norm_`` computes and returns, without clipping anything."""
    grads = [p.grad for p in parameters if p.grad is not None]
    if hasattr(nn.utils, "get_total_norm"):  # torch >= 2.6: the function clip_grad_norm_ itself calls
        return nn.utils.get_total_norm(grads)
    if not grads:
        return torch.tensor(0.0)
    return torch.linalg.vector_norm(torch.stack([torch.linalg.vector_norm(g.detach()) for g in grads]))


def soft_bound_loss(actions: torch.Tensor, bound: float) -> torch.Tensor:
    """mean(relu(|a| - bound)^2): zero inside [-bound, bound], quadratic outside (Puffer-PHC's bound loss)."""
    return (actions.abs() - bound).clamp(min=0.0).square().mean()


class OnPolicyAlgorithm(RslPPO):
    """Shared update loop; subclasses implement ``act`` and ``policy_loss`` (see the module docstring)."""

    uses_critic: bool = True

    # Options every algorithm shares (refpo_warp/utils/options.py), besides rsl_rl's PPO arguments.
    reward_scale: float = option(
        1.0,
        Real(0, 1e6, lo_open=True),
        "rewards x scale for learning; logged returns unscaled (Brax); set per task in configs/task/*.yaml",
    )
    value_clip_param: float | None = option(
        None,
        Real(0, None, lo_open=True, optional=True),
        "clip range of the clipped value loss; null: clip_param, as rsl_rl "
        "(Puffer-PHC clips the ratio at 0.01, values at 0.2)",
    )
    reshuffle_each_epoch: bool = option(
        False,
        Flag(),
        "a new minibatch permutation on every pass (Brax / Playground) instead of one for all (rsl_rl); per task",
    )
    joint_grad_clip: bool = option(
        False, Flag(), "one gradient-norm clip over actor and critic (Puffer-PHC) instead of one each (rsl_rl)"
    )
    lr_decay_rate: float = option(
        0.0,
        Real(0, 10),
        "after update k the learning rate is lr * max(exp(-rate k), lr_decay_floor); 0 keeps it (Puffer-PHC: 1.5e-4)",
    )
    lr_decay_floor: float = option(0.2, Real(0, 1), "the floor of that decay (Puffer-PHC: 0.2)")
    bound_coef: float = option(
        0.0,
        Real(0, 1e6),
        "soft bound loss bound_coef * mean(relu(|a_hat| - bound)^2) on "
        "the predicted action; 0 turns it off (Puffer-PHC: 10)",
    )
    bound: float = option(0.9, Real(0, None), "the bound of that loss, in the action range (Puffer-PHC: 0.9)")
    weight_decay: float | None = option(
        None,
        Real(0, 1, optional=True),
        "the optimizer's weight decay; null: its own default (adam 0, adamw 0.01) (FPO++: adamw, 1e-4)",
    )
    ema_decay: float | None = option(
        None,
        Real(0, 1, lo_open=True, hi_open=True, optional=True),
        "an EMA of the actor's weights, which evaluation and export use after its warm-up (FPO++: 0.95); null: off",
    )
    ema_warmup: int = option(
        500,
        Int(0, 10**9),
        "updates before the EMA starts from the live weights; until then the live actor is the policy (FPO++: 500)",
    )

    def __init__(self, actor: nn.Module, critic: nn.Module, storage, **kwargs) -> None:
        # Every argument checked against its option's rule before anything is built.
        options, ppo_kwargs = option_values(type(self), kwargs)
        for name in ("rnd_cfg", "symmetry_cfg"):
            if kwargs.get(name):
                raise ValueError(
                    f"{type(self).__name__} does not support {name}; remove '{name}' from the algorithm config "
                    "(or set it to None)."
                )
        if getattr(critic, "is_recurrent", False) or getattr(actor, "is_recurrent", False):
            raise ValueError(f"{type(self).__name__} supports feed-forward actors and critics only.")
        self.check_actor(actor)
        ppo_kwargs.update({name: options.pop(name) for name in list(options) if name in PPO_ARGUMENTS})
        newer = split_newer_ppo_args(ppo_kwargs, honoured=("use_mixed_precision",))  # rsl-rl-lib < 5.5
        super().__init__(actor, critic, storage, **ppo_kwargs)
        if not hasattr(self, "use_mixed_precision"):  # this update loop applies it on every rsl_rl version
            self.use_mixed_precision = bool(newer.get("use_mixed_precision", False))
        if self.use_mixed_precision and torch.device(self.device).type == "cpu" and not cpu_has_native_bfloat16():
            warnings.warn(
                f"algorithm.use_mixed_precision=true on a CPU without native bfloat16 (torch sees "
                f"{torch.backends.cpu.get_cpu_capability()}, no AVX512-BF16 or AMX): its bfloat16 matrix products "
                "are emulated and the update runs many times slower than in float32 (12 to 21 times on an AVX2 CPU, "
                "docs/results/throughput/); set it to false on this machine",
                stacklevel=2,
            )
        for name, value in options.items():  # the options this class and its bases declare (typed attributes)
            setattr(self, name, value)
        if self.value_clip_param is None:
            self.value_clip_param = self.clip_param
        if self.weight_decay is not None:  # rsl_rl builds its optimizer with the optimizer's default
            for group in self.optimizer.param_groups:
                group["weight_decay"] = self.weight_decay
        self.base_learning_rate = float(self.learning_rate)
        self.num_updates = 0
        self.store = TransitionStore(storage.num_transitions_per_env, storage.num_envs, self.device)
        self.ema = ActorEMA(uncompiled(self, "actor"), self.ema_decay, self.ema_warmup) if self.ema_decay else None
        flush_denormals_on_cpu(self.device)  # speed only: the same results (refpo_warp.utils.device)

    # ------------------------------------------------------------------------------------------------ rollout
    def process_env_step(
        self, obs: TensorDict, rewards: torch.Tensor, dones: torch.Tensor, extras: dict[str, torch.Tensor]
    ) -> None:
        # The runner hands the same reward tensor to its logger afterwards: scale a copy, never in place.
        super().process_env_step(obs, rewards * self.reward_scale, dones, extras)

    # ------------------------------------------------------------------------------------------------ subclass API
    @property
    def method_name(self) -> str:
        """The method as a user configured it, for messages (a subclass names its special cases)."""
        return type(self).__name__

    def check_actor(self, actor: nn.Module) -> None:
        """Refuse an actor this algorithm cannot train (a ``TypeError`` naming the actor class to set); called by the
        constructor after the options are checked, before anything is built."""

    def before_update(self) -> None:
        """Work on the whole rollout before the first gradient step (e.g. ReFPO's old CFM losses)."""

    def policy_loss(self, batch: Minibatch) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        """The policy's loss on ``batch`` and its statistics (scalar tensors; see the module docstring for names)."""
        raise NotImplementedError

    def kl_estimate(self, stats: dict[str, torch.Tensor]) -> torch.Tensor | None:
        """The minibatch's KL estimate that drives the adaptive learning-rate schedule (None: no adaptation)."""
        return stats.get("approx_kl")

    # ------------------------------------------------------------------------------------------------ update
    def value_loss(self, batch: Minibatch) -> torch.Tensor:
        clip = self.value_clip_param if self.use_clipped_value_loss else None
        return value_regression_loss(self.critic(batch.observations), batch.values, batch.returns, clip)

    def minibatches(self):
        st = self.storage
        observations = st.observations.flatten(0, 1)
        actions, values = st.actions.flatten(0, 1), st.values.flatten(0, 1)
        returns, advantages = st.returns.flatten(0, 1), st.advantages.flatten(0, 1).squeeze(-1)
        for idx in minibatch_indices(
            actions.shape[0], self.num_mini_batches, self.num_learning_epochs, self.device, self.reshuffle_each_epoch
        ):
            adv = advantages[idx]
            if self.normalize_advantage_per_mini_batch:
                adv = (adv - adv.mean()) / (adv.std() + 1e-8)
            yield Minibatch(observations[idx], actions[idx], values[idx], returns[idx], adv, idx, self.store)

    def update(self) -> dict[str, float]:
        self.before_update()
        device_type = torch.device(self.device).type
        restore_point = self._restore_point()
        means: dict[str, list[torch.Tensor]] = {}
        maxima: dict[str, torch.Tensor] = {}
        finite: list[torch.Tensor] = []  # per minibatch, on the device: read with the statistics (module docstring)
        minibatch_stats: list[dict[str, torch.Tensor]] = []  # for the message naming the first non-finite one
        for batch in self.minibatches():
            with torch.autocast(device_type=device_type, enabled=self.use_mixed_precision, dtype=torch.bfloat16):
                loss, stats = self.policy_loss(batch)
                if self.uses_critic:
                    stats["value"] = self.value_loss(batch)
                    loss = loss + self.value_loss_coef * stats["value"]
            finite.append(torch.isfinite(loss.detach()))
            minibatch_stats.append({k: v.detach() for k, v in stats.items()})
            self.optimizer.zero_grad()
            loss.backward()
            if self.is_multi_gpu:
                self.reduce_parameters()
            grad_norms = self.clip_gradients()
            self._adapt_learning_rate(self.kl_estimate(stats))
            self.optimizer.step()
            for key, raw in {**stats, **grad_norms}.items():
                value = raw.detach().float()
                if key.endswith("_max"):
                    maxima[key] = torch.maximum(maxima[key], value) if key in maxima else value
                else:
                    means.setdefault(key, []).append(value)

        keys, max_keys = list(means), list(maxima)
        flags = torch.stack(finite).float()
        if self.is_multi_gpu:  # every rank stops, or none: a non-finite loss on one rank is one on all
            torch.distributed.all_reduce(flags, op=torch.distributed.ReduceOp.MIN)
        parts = [flags]
        if keys:
            parts.append(torch.stack([torch.stack(means[k]).mean() for k in keys]))
        if max_keys:
            parts.append(torch.stack([maxima[k] for k in max_keys]))
        values = torch.cat(parts).tolist()  # the update's one host read
        if min(values[: len(finite)]) < 1.0:
            self._restore(restore_point)
            first = minibatch_stats[values.index(0.0)]
            raise NonFiniteLossError(
                f"Non-finite {self.method_name} loss ("
                + ", ".join(f"{k}={float(v):.4g}" for k, v in first.items())
                + "); the update was stopped before applying it."
            )
        out = dict(zip(keys + max_keys, values[len(finite) :]))

        # Normalisers follow the data after the update, as in rsl_rl's PPO (before 5.5 it did so at every env step).
        if not NORMALIZERS_UPDATE_PER_STEP:
            obs = self.storage.observations.flatten(0, 1)
            self.actor.update_normalization(obs)
            self.critic.update_normalization(obs)
        self.storage.clear()
        self.num_updates += 1
        if self.ema is not None:
            self.ema.update(uncompiled(self, "actor"), self.num_updates)
        if self.lr_decay_rate > 0:
            decay = max(math.exp(-self.lr_decay_rate * self.num_updates), self.lr_decay_floor)
            self._set_learning_rate(self.base_learning_rate * decay)
        if self.schedule == "adaptive" or self.lr_decay_rate > 0:  # a rate that moves: logged (Loss/learning_rate)
            out["learning_rate"] = float(self.learning_rate)
        return out

    def _restore_point(self) -> tuple[list[torch.Tensor], dict, float]:
        """Copies (on the device, no host read) of what an update changes: parameters, optimizer state, rate."""
        params = [p.detach().clone() for group in self.optimizer.param_groups for p in group["params"]]
        return params, copy.deepcopy(self.optimizer.state_dict()), self.learning_rate

    @torch.no_grad()
    def _restore(self, point: tuple[list[torch.Tensor], dict, float]) -> None:
        params, optimizer_state, learning_rate = point
        for p, saved in zip((p for group in self.optimizer.param_groups for p in group["params"]), params):
            p.copy_(saved)
        self.optimizer.load_state_dict(optimizer_state)
        self._set_learning_rate(learning_rate)

    def clip_gradients(self) -> dict[str, torch.Tensor]:
        """Clip the gradients by ``max_grad_norm``, jointly over actor and critic (``joint_grad_clip``) or each network
        on its own (rsl_rl), and return each network's gradient norm before clipping (``grad_norm_actor``, and
        ``grad_norm_critic`` for an algorithm with a critic): logged as ``Loss/grad_norm_*``, the mean over the update's
        minibatches. The clip is the one it always was; the norms are read with the other statistics."""
        if self.joint_grad_clip:
            actor, critic = list(self.actor.parameters()), list(self.critic.parameters())
            norms = {"grad_norm_actor": gradient_norm(actor)}
            if self.uses_critic:
                norms["grad_norm_critic"] = gradient_norm(critic)
            nn.utils.clip_grad_norm_(actor + critic, self.max_grad_norm)
        else:  # clip_grad_norm_ returns the norm it clipped from
            norms = {"grad_norm_actor": nn.utils.clip_grad_norm_(self.actor.parameters(), self.max_grad_norm)}
            if self.uses_critic:
                norms["grad_norm_critic"] = nn.utils.clip_grad_norm_(self.critic.parameters(), self.max_grad_norm)
        return norms

    # ------------------------------------------------------------------------------------------------ learning rate
    def _set_learning_rate(self, lr: float) -> None:
        self.learning_rate = lr
        for group in self.optimizer.param_groups:
            group["lr"] = lr

    def _adapt_learning_rate(self, kl: torch.Tensor | None) -> None:
        """rsl_rl's adaptive schedule (lr / 1.5 above 2 x desired_kl, x 1.5 below half of it), decided on rank 0."""
        if kl is None or self.desired_kl is None or self.schedule != "adaptive":
            return
        kl = kl.detach().clone()
        if self.is_multi_gpu:
            torch.distributed.all_reduce(kl, op=torch.distributed.ReduceOp.SUM)
            kl /= self.gpu_world_size
        lr = self.learning_rate
        if self.gpu_global_rank == 0:
            if kl > self.desired_kl * 2.0:
                lr = max(ADAPTIVE_LR_RANGE[0], lr / 1.5)
            elif 0.0 < kl < self.desired_kl / 2.0:
                lr = min(ADAPTIVE_LR_RANGE[1], lr * 1.5)
        if self.is_multi_gpu:
            lr_tensor = torch.tensor(lr, device=self.device)
            torch.distributed.broadcast(lr_tensor, src=0)
            lr = lr_tensor.item()
        self._set_learning_rate(lr)

    # ---------------------------------------------------------------------------------------------- policy, checkpoints
    def started_ema(self) -> ActorEMA | None:
        """The EMA actor once it has started (after ``ema_warmup`` updates), else None."""
        return self.ema if self.ema is not None and self.ema.started(self.num_updates) else None

    def ema_started(self) -> bool:
        return self.started_ema() is not None

    def get_policy(self) -> nn.Module:
        """The policy evaluation, inference and export use: the EMA actor once it has started, else the live one."""
        ema = self.started_ema()
        return ema.model if ema is not None else uncompiled(self, "actor")

    def save(self) -> dict:
        saved = super().save()  # actor_state_dict: the live weights, which a resume trains on from
        saved["num_updates"] = self.num_updates
        ema = self.started_ema()
        if ema is not None:
            saved["ema_actor_state_dict"] = ema.state_dict()
        return saved

    def load(self, loaded_dict: dict, load_cfg: dict | None, strict: bool) -> bool:
        out = super().load(loaded_dict, load_cfg, strict)
        self.num_updates = int(loaded_dict.get("num_updates", 0))
        ema = self.started_ema()
        if ema is not None:
            if "ema_actor_state_dict" in loaded_dict:
                ema.load_state_dict(loaded_dict["ema_actor_state_dict"])
            else:  # a checkpoint past the warm-up without an average (a run without the EMA): start it here
                ema.reset(uncompiled(self, "actor"))
        return out
