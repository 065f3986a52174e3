"""Run configuration: the YAML layers and ``key=value`` overrides resolved into one validated config
(``resolve.py``), the rules of the run options (``run_options.py``) and a run's saved config on resume and
evaluation (``saved.py``)."""
