"""Option rules for rsl_rl's PPO arguments, which every algorithm here inherits (``OnPolicyAlgorithm`` subclasses
rsl_rl's PPO).

rsl_rl's constructor accepts anything and fails later (a zero ``num_mini_batches`` divides by zero in the middle of
training); these rules let the config resolver refuse such values up front. Written against the parameters of
rsl-rl-lib 5.0.1 to 5.5.1; a parameter one version lacks is simply never checked there.
"""

from __future__ import annotations

from rsl_rl.algorithms import PPO as RslPPO

from refpo_warp.utils.option_rules import Check, Flag, Int, OneOf, Real, mapping_or_none, register_rules

OPTIMIZERS = ("adam", "adamw", "sgd", "rmsprop")  # rsl_rl.utils.resolve_optimizer

register_rules(
    RslPPO,
    {
        "num_learning_epochs": Int(1, 10_000),
        "num_mini_batches": Int(1, 1_000_000),
        "clip_param": Real(0, 10, lo_open=True),
        "gamma": Real(0, 1),
        "lam": Real(0, 1),
        "value_loss_coef": Real(0, 1e6),
        "entropy_coef": Real(0, 1e6),
        "learning_rate": Real(0, 1, lo_open=True),
        "max_grad_norm": Real(0, None, lo_open=True),
        "optimizer": OneOf(OPTIMIZERS, fixed=True),  # the saved optimizer state only loads into the same optimizer
        "use_clipped_value_loss": Flag(),
        "schedule": OneOf("fixed", "adaptive"),
        "desired_kl": Real(0, None, lo_open=True, optional=True),
        "normalize_advantage_per_mini_batch": Flag(),
        "use_mixed_precision": Flag(),
        "rnd_cfg": Check(mapping_or_none, "null or a mapping of RND options", optional=True),
        "symmetry_cfg": Check(mapping_or_none, "null or a mapping of symmetry options", optional=True),
        "grad_reduce_bucket_mb": Real(0, None, lo_open=True),
        "share_cnn_encoders": Flag(optional=True),  # consumed by construct_algorithm
    },
)
