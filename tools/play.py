#!/usr/bin/env python
"""`refpo play` from a checkout: python tools/play.py [arguments of refpo play] (refpo play --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["play", *sys.argv[1:]]))
