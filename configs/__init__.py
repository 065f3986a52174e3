"""The shipped config files, installed as ``refpo_warp.configs`` (package data; no code): ``default.yaml``, ``algo/``,
``task/`` and ``sweep/``. ``refpo_warp.utils.paths`` finds this folder through the installed package."""
