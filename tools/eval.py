#!/usr/bin/env python
"""Evaluate a trained run: python tools/eval.py run_dir=PATH [checkpoint=PATH] [eval.flow_steps=[1,10]] [...]

Writes eval.json (returns and task metrics at each flow-step count, Straightness Error, Explosion Rate) and the
task's figures into the run dir. Overrides apply on top of the run's saved config.yaml.
"""

import sys

from refpo_warp.cli.commands import main

if __name__ == "__main__":
    sys.exit(main("eval", sys.argv[1:], __doc__))
