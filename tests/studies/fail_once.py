"""A launcher prefix (``--launcher "python fail_once.py <marker>"``) whose first run fails: the first time it is started
(no ``<marker>`` file yet) it writes the marker, prints an error line and exits 1 (a crash) without training; every
later start runs the real training command that follows it (``<python> -m refpo_warp train <run args>
device=<device>``)."""

import os
import sys
from pathlib import Path

marker, command = Path(sys.argv[1]), sys.argv[2:]
if not marker.exists():
    marker.write_text("failed once\n")
    print("error: fail_once.py fails the first run it starts", flush=True)
    sys.exit(1)
os.execv(command[0], command)
