"""Benchmarks behind ``refpo bench`` that are not one task family's: action latency (N = 1 vs N = 10) and the
update time of every algorithm. Each family's env benchmark is ``refpo_warp/tasks/<family>/bench.py``."""
