"""``refpo tune``: the tuning file (``spec.py``) and the Optuna studies whose trials the grid's executor trains
(``study.py``), with their records (``records.py``)."""
