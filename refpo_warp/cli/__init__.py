"""Command-line front ends shared by ``tools/*.py``: one clear message and a documented exit code for every failure."""
