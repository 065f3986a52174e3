"""``python -m refpo_warp <command> ...``: the ``refpo`` command (``refpo_warp/cli/main.py``) of this Python; sweeps
start their runs this way, so a node needs the installed package, not a checkout."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main())
