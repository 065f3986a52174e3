#!/usr/bin/env python
"""Train a policy: python tools/train.py task=<task id> [algo=<configs/algo/*.yaml: refpo, fpo, ...>] [key=value ...]

Examples:
    python tools/train.py task=gridworld algo=refpo seed=1 run_dir=runs/grid
    python tools/train.py task=dmc_cheetah_run algo=fpo num_envs=2048 device=cuda:0
    python tools/train.py task=humanoid_root
    python tools/train.py run_dir=runs/grid resume=true          # continue from the last checkpoint
Any config key can be overridden (see configs/default.yaml); list tasks with `python tools/train.py --tasks`.
"""

import sys

from refpo_warp.cli.commands import main

if __name__ == "__main__":
    sys.exit(main("train", sys.argv[1:], __doc__))
