"""The OpenGL platform of MuJoCo's offscreen renderer, chosen before MuJoCo is imported (it reads ``MUJOCO_GL`` once).

Headless by default: ``egl`` (Mesa's or a GPU driver's libEGL), else ``osmesa`` (software, ``apt-get install
libosmesa6``); ``MUJOCO_GL=glfw`` needs a display. A platform is probed in a short subprocess (rendering an 8 x 8
frame), since a failed choice cannot be undone inside a process that imported MuJoCo. When none works, one message
names the choices and what to install.
"""

from __future__ import annotations

import os
import subprocess
import sys

from refpo_warp.utils.errors import SystemRefusedError

HEADLESS = ("egl", "osmesa")
CHOICES = ("egl", "osmesa", "glfw")
INSTALL = {
    "egl": "Mesa's libEGL (apt-get install libegl1 libgl1) or a GPU driver",
    "osmesa": "apt-get install libosmesa6",
    "glfw": "a display (DISPLAY set) and the glfw library",
}
_PROBE = (
    "import mujoco; m = mujoco.MjModel.from_xml_string('<mujoco/>'); r = mujoco.Renderer(m, 8, 8); "
    "r.update_scene(mujoco.MjData(m)); r.render(); r.close()"
)


def probe(platform: str) -> str | None:
    """None if MuJoCo can make an offscreen context with ``platform``, else the reason (its last error line)."""
    env = {**os.environ, "MUJOCO_GL": platform, "PYOPENGL_PLATFORM": "osmesa" if platform == "osmesa" else platform}
    try:
        proc = subprocess.run(
            [sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=60, check=False
        )
    except subprocess.TimeoutExpired:
        return "timed out"
    if proc.returncode == 0:
        return None
    lines = [line for line in proc.stderr.strip().splitlines() if line.strip()]
    return lines[-1] if lines else f"exit code {proc.returncode}"


def no_backend(failures: dict[str, str]) -> SystemRefusedError:
    tried = "; ".join(f"MUJOCO_GL={p}: {why}" for p, why in failures.items())
    options = "; ".join(f"MUJOCO_GL={p} needs {INSTALL[p]}" for p in CHOICES)
    return SystemRefusedError(
        f"no OpenGL platform for MuJoCo's offscreen renderer works here ({tried}). Set "
        f"MUJOCO_GL to one that does: {options}"
    )


def select_gl_platform() -> str:
    """Set ``MUJOCO_GL`` for this process (and the processes it starts) to a platform that works, before MuJoCo is
    imported; the user's own ``MUJOCO_GL`` is kept and checked. Returns it."""
    chosen = os.environ.get("MUJOCO_GL", "").strip().lower()
    if "mujoco" in sys.modules:  # too late to choose: the platform MuJoCo took stands
        return chosen or "glfw"
    failures = {}
    for platform in [chosen] if chosen else HEADLESS:
        why = probe(platform)
        if why is None:
            os.environ["MUJOCO_GL"] = platform
            if platform == "osmesa":
                os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")
            return platform
        failures[platform] = why
    raise no_backend(failures)
