"""A reader that stops early (`refpo train --help | head -1`) ends the command quietly: no traceback, exit 0."""

import subprocess
import sys


def test_help_into_a_closed_pipe_prints_no_traceback():
    proc = subprocess.Popen(
        [sys.executable, "-m", "refpo_warp", "train", "--help"], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    proc.stdout.close()  # closed before the command writes: its first write meets a broken pipe
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 0 and "Traceback" not in err and "BrokenPipe" not in err, err
