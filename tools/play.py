#!/usr/bin/env python
"""A video of a policy: python tools/play.py run_dir=PATH [checkpoint=PATH] [flow_steps=[1,10]] [num_envs=4] [...]
                   or: python tools/play.py task=<task id> agent=zero|random [env options] [out=DIR] [...]

Writes <run dir>/videos/<name>.mp4 (format=gif or both for a GIF) and prints its path. flow_steps=[1,10] shows the
1-step and the 10-step policy side by side from the same initial states. Options: refpo_warp/cli/play.py and
docs/videos.md.
"""

import sys

from refpo_warp.cli.commands import main

if __name__ == "__main__":
    sys.exit(main("play", sys.argv[1:], __doc__))
