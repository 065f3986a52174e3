"""The run machinery: rsl_rl's ``OnPolicyRunner`` extended (``runner.py``, its logger ``logger.py``), built from a
resolved config (``build.py``), its run directory, checkpoints, progress log and torchrun ranks."""
