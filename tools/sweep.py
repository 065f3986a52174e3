#!/usr/bin/env python
"""`refpo sweep` from a checkout: python tools/sweep.py [arguments of refpo sweep] (refpo sweep --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["sweep", *sys.argv[1:]]))
