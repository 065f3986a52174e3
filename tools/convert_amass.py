"""Convert AMASS motion files (one npz, or a folder searched recursively) into a motion library file.

    python tools/convert_amass.py ~/data/AMASS/CMU runs/cmu.motionlib.npz --fps 30

Every file is validated; the first bad one stops the conversion with a message naming it (nothing is written).
The output is written atomically: an interrupted conversion keeps the previous output file. The result loads with
``motion_file=runs/cmu.motionlib.npz`` (or ``MotionLibrary.load``). Exit codes as tools/train.py (docs/cli.md).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from refpo_warp.cli.guard import EXIT_USAGE, run_guarded
from refpo_warp.motion.library_file import LIBRARY_SUFFIX
from refpo_warp.motion.limits import LIBRARY_FPS
from refpo_warp.utils.errors import ConfigError


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("source", type=Path, help="an AMASS .npz file or a folder of them")
    parser.add_argument("output", type=Path, help=f"library file to write (name ends in {LIBRARY_SUFFIX})")
    parser.add_argument("--fps", type=float, default=30.0,
                        help=f"library frame rate, {LIBRARY_FPS[0]:g} to {LIBRARY_FPS[1]:g} (default 30, the control "
                             f"rate)")  # fmt: skip
    args = parser.parse_args(argv)
    if not args.output.name.endswith(LIBRARY_SUFFIX):
        print(f"error: output file name must end in {LIBRARY_SUFFIX}, got {args.output.name}", file=sys.stderr)
        return EXIT_USAGE
    return run_guarded(lambda: convert(args.source, args.output, args.fps))


def convert(source: Path, output: Path, fps: float) -> None:
    from refpo_warp.motion.limits import check_fps_argument
    from refpo_warp.motion.motion_library import MotionLibrary

    check_fps_argument(fps, "--fps")
    if output.is_dir():
        raise ConfigError(f"output {output} is a directory; give a file name ending in {LIBRARY_SUFFIX}")
    start = time.perf_counter()
    library = MotionLibrary.load(source, device="cpu", fps=fps)
    library.save(output)
    print(f"{library} -> {output} ({output.stat().st_size / 2**20:.1f} MiB, "
          f"{time.perf_counter() - start:.1f} s)")  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
