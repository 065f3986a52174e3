"""``refpo convert-amass``: AMASS motion files into one motion library file."""

from __future__ import annotations

import time
from pathlib import Path

from refpo_warp.utils.command_line import Arguments, Flag
from refpo_warp.utils.errors import ConfigError

SUMMARY = "convert AMASS motion files (a file or a folder) into a motion library file"
USAGE = """Convert AMASS motion files (one npz, or a folder searched recursively) into a motion library file:

    refpo convert-amass ~/data/AMASS/CMU runs/cmu.motionlib.npz [--fps 30]

Every file is validated; the first bad one stops the conversion with a message naming it (nothing is written).
The output is written atomically: an interrupted conversion keeps the previous output file. The result loads with
``motion_file=runs/cmu.motionlib.npz`` (or ``MotionLibrary.load``). --fps: the library frame rate (default 30, the
control rate).
"""
FLAGS = (Flag("--fps", float, "the library frame rate"),)
SUBJECTS = 2


def run(args: Arguments) -> None:
    from refpo_warp.motion.library_file import LIBRARY_SUFFIX

    if len(args.subjects) != 2 or args.options:
        raise ConfigError(
            f"refpo convert-amass takes SOURCE (an AMASS .npz file or a folder of them) and OUTPUT "
            f"(a file name ending in {LIBRARY_SUFFIX}), and --fps; see refpo convert-amass --help"
        )
    source, output = map(Path, args.subjects)
    if not output.name.endswith(LIBRARY_SUFFIX):
        raise ConfigError(f"output file name must end in {LIBRARY_SUFFIX}, got {output.name}")
    convert(source, output, args.flag("--fps", 30.0))


def convert(source: Path, output: Path, fps: float) -> None:
    from refpo_warp.motion.library_file import LIBRARY_SUFFIX
    from refpo_warp.motion.limits import check_fps_argument
    from refpo_warp.motion.motion_library import MotionLibrary

    check_fps_argument(fps, "--fps")
    if output.is_dir():
        raise ConfigError(f"output {output} is a directory; give a file name ending in {LIBRARY_SUFFIX}")
    start = time.perf_counter()
    library = MotionLibrary.load(source, device="cpu", fps=fps)
    library.save(output)
    print(f"{library} -> {output} ({output.stat().st_size / 2**20:.1f} MiB, {time.perf_counter() - start:.1f} s)")
