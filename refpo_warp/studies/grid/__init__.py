"""Grids of runs: the sweep spec expanded into runs, the state of a sweep dir, one run's ``refpo train`` process, a
finished run's numbers, and the executor with its local backend (the Ray backend: ``studies/ray/``)."""
