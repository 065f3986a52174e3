#!/usr/bin/env python
"""`refpo train` from a checkout: python tools/train.py [arguments of refpo train] (refpo train --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["train", *sys.argv[1:]]))
