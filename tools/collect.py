#!/usr/bin/env python
"""`refpo collect` from a checkout: python tools/collect.py [arguments of refpo collect] (refpo collect --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["collect", *sys.argv[1:]]))
