"""Convert AMASS motion files (one npz, or a folder searched recursively) into a motion library file.

    python tools/convert_amass.py ~/data/AMASS/CMU runs/cmu.motionlib.npz --fps 30

Every file is validated; the first bad one stops the conversion with a message naming it (nothing is written).
The result loads with ``motion_file=runs/cmu.motionlib.npz`` (or ``MotionLibrary.load``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from refpo_warp.errors import MotionDataError
from refpo_warp.motion.library_file import LIBRARY_SUFFIX
from refpo_warp.motion.motion_library import MotionLibrary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("source", type=Path, help="an AMASS .npz file or a folder of them")
    parser.add_argument("output", type=Path, help=f"library file to write (name ends in {LIBRARY_SUFFIX})")
    parser.add_argument("--fps", type=float, default=30.0, help="library frame rate (default 30, the control rate)")
    args = parser.parse_args(argv)
    if not args.output.name.endswith(LIBRARY_SUFFIX):
        parser.error(f"output file name must end in {LIBRARY_SUFFIX}, got {args.output.name}")

    start = time.perf_counter()
    try:
        library = MotionLibrary.load(args.source, device="cpu", fps=args.fps)
    except MotionDataError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    library.save(args.output)
    print(f"{library} -> {args.output} ({args.output.stat().st_size / 2**20:.1f} MiB, "
          f"{time.perf_counter() - start:.1f} s)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
