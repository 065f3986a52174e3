#!/usr/bin/env python
"""`refpo report` from a checkout: python tools/report.py [arguments of refpo report] (refpo report --help)."""

import sys

from refpo_warp.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["report", *sys.argv[1:]]))
