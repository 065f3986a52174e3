#!/usr/bin/env python
"""`refpo eval` from a checkout: python tools/eval.py [arguments of refpo eval] (refpo eval --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["eval", *sys.argv[1:]]))
