#!/usr/bin/env python
"""`refpo pretrain` from a checkout: python tools/pretrain.py [arguments of refpo pretrain] (refpo pretrain --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["pretrain", *sys.argv[1:]]))
