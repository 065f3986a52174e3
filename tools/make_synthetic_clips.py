#!/usr/bin/env python
"""`refpo make-clips` from a checkout: python tools/make_synthetic_clips.py [arguments of refpo make-clips]
(refpo make-clips --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["make-clips", *sys.argv[1:]]))
