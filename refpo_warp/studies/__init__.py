"""Studies of many training runs, one package per job, imports one way (a lower line never imports a higher one):

- ``reports/``: the paper's tables, figures, confidence intervals, a sweep's report and the results pages;
- ``tuning/``: an equal tuning budget per method (``refpo tune``), its trials run by the grid's executor;
- ``sweep.py`` (``refpo sweep``) and ``backends.py`` (which backend runs the runs);
- ``ray/``: the Ray backend (one Ray task per run);
- ``grid/``: the sweep spec and its runs, the state of a sweep dir, one run's training process, the executor (queue,
  retries, progress, ``status.json``) and its local backend.
"""
