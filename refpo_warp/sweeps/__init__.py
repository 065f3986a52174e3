"""Grids of runs: the sweep spec and its expansion, running every run (one ``tools/train.py`` process each), the
paper's tables and figures from the finished runs."""
