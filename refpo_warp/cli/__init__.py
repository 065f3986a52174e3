"""The ``refpo`` command and its subcommands (``main.py``), one argument convention (``arguments.py``), and one clear
message and a documented exit code for every failure (``guard.py``). The checkout's ``tools/*.py`` call ``main``."""
