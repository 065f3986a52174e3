#!/usr/bin/env python
"""`refpo tune` from a checkout: python tools/tune.py [arguments of refpo tune] (refpo tune --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["tune", *sys.argv[1:]]))
