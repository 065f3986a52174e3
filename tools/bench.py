#!/usr/bin/env python
"""`refpo bench` from a checkout: python tools/bench.py [arguments of refpo bench] (refpo bench --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["bench", *sys.argv[1:]]))
