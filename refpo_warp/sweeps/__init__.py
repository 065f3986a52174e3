"""Grids of runs: the sweep spec and its expansion, running every run (one ``refpo train`` process each), the
paper's tables and figures from the finished runs."""
