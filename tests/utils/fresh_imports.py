"""Import each of some modules alone: one child process per module, forked from a parent that loaded only the given
third-party packages, so a module that works only after another first-party module was imported fails."""

import json
import subprocess
import sys

from refpo_warp.utils.layering import ROOT


def import_each_alone(modules: list[str], preload: str, check: str = "") -> dict[str, str]:
    """module -> what went wrong (a traceback, or the message ``check`` left in ``msg``) for each that failed;
    ``preload`` is the parent's import line, ``check`` code run in the child after the import (``name`` is the
    module's name; it sets ``msg`` to a non-empty text to fail it)."""
    body = "\n".join("            " + line for line in check.strip().splitlines()) or "            pass"
    script = f"""
import json, os, traceback
{preload}
failed = {{}}
for name in {modules!r}:
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        msg = ""
        try:
            __import__(name)
{body}
        except BaseException:
            msg = traceback.format_exc()[-2000:]
        os.write(w, msg.encode())
        os._exit(0)
    os.close(w)
    msg = os.read(r, 4000).decode()
    os.close(r)
    os.waitpid(pid, 0)
    if msg:
        failed[name] = msg
print(json.dumps(failed))
"""
    out = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=600, check=False
    )
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])
