#!/usr/bin/env python
"""`refpo plot` from a checkout: python tools/plot.py [arguments of refpo plot] (refpo plot --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["plot", *sys.argv[1:]]))
