"""DMC-style control suite on Newton (ReFPO paper §4.2): ten MuJoCo Playground DM Control tasks as Warp envs.

Registering is cheap: the env module (and Newton) is imported only when an env is built.
"""

from refpo_warp.registry import register_task

_ENTRY = "tasks.dmc.env:DmcEnv"
_DESCRIPTIONS = {
    "cartpole_balance": "keep a pole upright on a cart (obs 5, act 1, 0.01 s control)",
    "cartpole_swingup": "swing a hanging pole up and balance it (obs 5, act 1, 0.01 s control)",
    "pendulum_swingup": "swing a torque-limited pendulum upright (obs 3, act 1, 0.02 s control)",
    "point_mass": "drive a planar point mass to the origin (obs 4, act 2, 0.02 s control)",
    "ball_in_cup": "swing a ball on a string into a cup (obs 8, act 2, 0.02 s control)",
    "finger_spin": "flick a hinged body into fast rotation (obs 9, act 2, 0.02 s control)",
    "reacher_easy": "touch a random target with a two-link arm (obs 6, act 2, 0.02 s control)",
    "acrobot_swingup": "swing a two-link underactuated pendulum up (obs 6, act 1, 0.01 s control)",
    "cheetah_run": "run a planar half-cheetah forward (obs 17, act 6, 0.01 s control)",
    "walker_walk": "walk a planar biped forward at 1 m/s (obs 24, act 6, 0.025 s control)",
}

for _name, _description in _DESCRIPTIONS.items():
    register_task(f"dmc_{_name}", _ENTRY, description=f"DMC {_description}; 1000-step episodes", task=_name)
