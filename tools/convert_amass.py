#!/usr/bin/env python
"""`refpo convert-amass` from a checkout: python tools/convert_amass.py [arguments of refpo convert-amass]
(refpo convert-amass --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["convert-amass", *sys.argv[1:]]))
