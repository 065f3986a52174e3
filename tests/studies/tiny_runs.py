"""The tiny run the sweep and tuning tests train: GridWorld-sized, two iterations, an evaluation each."""

TINY = {
    "max_iterations": 2,
    "num_envs": 4,
    "runner.num_steps_per_env": 8,
    "eval.num_envs": 4,
    "eval.flow_steps": [10, 1],
    "eval.interval": 1,
    "eval.interval_num_envs": 4,
}
