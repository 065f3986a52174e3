"""``refpo tune``: the tuning file (``spec.py``) and the Optuna studies of its methods (``study.py``)."""
