#!/usr/bin/env python
"""Benchmarks: python tools/bench.py <gridworld|dmc|humanoid|all> [options of that benchmark]

Each family's benchmark lives in tasks/<family>/bench.py; `python tools/bench.py dmc --help` shows its options.
"""

import importlib
import sys

FAMILIES = ("gridworld", "dmc", "humanoid")


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    family, rest = argv[0], argv[1:]
    if family not in FAMILIES + ("all",):
        from refpo_warp.errors import unknown

        print(f"error: {unknown('benchmark', family, FAMILIES + ('all',))}", file=sys.stderr)
        return 2
    from refpo_warp.device import set_torch_threads

    set_torch_threads()
    for name in FAMILIES if family == "all" else (family,):
        print(f"\n=== {name} ===", flush=True)
        importlib.import_module(f"tasks.{name}.bench").main(rest)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
