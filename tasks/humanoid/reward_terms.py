"""The tracking reward as named terms (reference ``compute_imitation_reward``), with weights and scales from the cfg.

``r = w_pos exp(-k_pos mean dp^2) + w_rot exp(-k_rot mean angle^2) + w_vel exp(-k_vel mean dv^2)
+ w_angvel exp(-k_angvel mean dw^2) - power_coef sum_dof |tau * qdot|``; means over the 24 bodies and, for vectors,
over x/y/z. Defaults (the reference's): weights 0.5 / 0.3 / 0.1 / 0.1, scales 100 / 10 / 0.1 / 0.1, power 0.0005.
The terms are computed in one kernel with the termination checks (``tracking_kernels.reward_and_termination_kernel``);
each step's weighted terms add up to the reward; the base env sums them over each episode, logged as
``Episode_Reward/<term>``.
"""

from __future__ import annotations

from refpo_warp.utils.warp_setup import wp

TERMS = ("pos", "rot", "vel", "angvel", "power")
NUM_TERMS = wp.constant(len(TERMS))
term_vector = wp.types.vector(length=len(TERMS), dtype=wp.float32)


@wp.struct
class RewardParams:
    weights: wp.vec4  # pos, rot, vel, angvel
    scales: wp.vec4  # the exp coefficients, same order
    power_coef: float


def reward_params(cfg) -> RewardParams:
    """The kernel parameters from a ``HumanoidTrackingCfg``'s ``reward_*`` fields and ``power_coef``."""
    params = RewardParams()
    params.weights = wp.vec4(*(getattr(cfg, f"reward_{t}_weight") for t in TERMS[:4]))
    params.scales = wp.vec4(*(getattr(cfg, f"reward_{t}_scale") for t in TERMS[:4]))
    params.power_coef = cfg.power_coef
    return params


@wp.func
def imitation_term(weight: float, scale: float, sq_error_sum: float, count: float):
    """``weight * exp(-scale * sq_error_sum / count)``: a mean squared error through an exponential kernel."""
    return weight * wp.exp(-scale * sq_error_sum / count)


@wp.func
def write_terms(i: int, terms: term_vector, reward_terms: wp.array2d(dtype=float)):
    """This step's terms of env ``i`` (the base env sums them over the episode)."""
    for k in range(NUM_TERMS):
        reward_terms[i, k] = terms[k]
